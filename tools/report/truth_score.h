// A run's estimated path scored against the ground truth (`--truth` of `footslam run` and
// `fastslam run`): the errors for summary.json, error.csv and error.png, and the headline line.
#ifndef GROVE_TOOLS_REPORT_TRUTH_SCORE_H_
#define GROVE_TOOLS_REPORT_TRUTH_SCORE_H_

#include <string>
#include <vector>

#include "grove/status.h"
#include "grove/types.h"
#include "tools/io/output_set.h"
#include "tools/io/truth_trajectory.h"
#include "tools/report/trajectory_metrics.h"

namespace grove::tools {

struct TruthScore {
  // CompareTrajectories of the truth and the estimate; not ok when fewer than 2 truth poses fall
  // within the estimate's time span.
  StatusOr<TrajectoryError> error = InvalidArgumentError("not scored");
  std::vector<AlignedPointError> points;  // each matched truth pose with its aligned error
};

// Scores `estimate` (times non-decreasing; at a repeated time the last pose counts, as a scan's
// update follows the prediction to its time) against `truth`.
TruthScore ScoreAgainstTruth(const TruthTrajectory& truth,
                             const std::vector<StampedPose>& estimate);

// The names AddTruthScoreFiles writes.
inline constexpr const char* kTruthScoreFiles[] = {"error.csv", "error.png"};
// Adds error.csv (`t,error`: each matched truth time and the aligned position error, metres) and
// error.png (that error against time, the y axis from zero; `title` on top) to `out`. Without
// gnuplot error.png is left out with a note on stderr: a run's other outputs are worth more.
Status AddTruthScoreFiles(OutputSet* out, const TruthScore& score, const std::string& title);

// The terminal's last line after a run with a truth: "error against truth: RMSE 1.23 m (aligned
// 0.98 m), max 3.40 m over 812 points", or why there is none.
std::string TruthHeadline(const TruthScore& score);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_REPORT_TRUTH_SCORE_H_

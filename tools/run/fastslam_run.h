// The `grove fastslam` commands: run (on the generic run loop) and evaluate.
#ifndef GROVE_TOOLS_RUN_FASTSLAM_RUN_H_
#define GROVE_TOOLS_RUN_FASTSLAM_RUN_H_

#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "grove/fastslam.h"
#include "tools/run/run_loop.h"

namespace grove::tools {

struct FastSlamRunOptions {
  RunOptions run;
  std::string controls_path;
  std::string observations_path;
  // optional: the true path (tools/io/truth_trajectory.h: truth.csv or TUM), scored and drawn
  std::string truth_path;
  std::string landmarks_truth_path;  // optional: landmarks_truth.csv (id,x,y), drawn and scored
  // Victoria Park instead of the CSV files (tools/io/victoria_park.h): its directory, and the
  // records up to until_s only. Adds gps_error.csv and the GPS errors to summary.json.
  std::string victoria_park_dir;
  double until_s = INFINITY;
};

// Runs FastSLAM and writes every output; returns an exit code after printing any error.
int RunFastSlamCommand(const FastSlamConfig& config, const FastSlamRunOptions& options);

// `grove fastslam evaluate`: prints the JSON report to stdout.
int FastSlamEvaluateCommand(const std::string& truth_path, const std::string& trajectory_path,
                            const std::string& landmarks_path,
                            const std::string& landmarks_truth_path);

// Errors of estimated poses against the truth at the truth's times (an estimate at the same
// time; truth times without one are counted, not matched).
struct PoseErrors {
  int64_t matched = 0;
  int64_t unmatched = 0;  // truth times without an estimate
  double position_rmse_m = 0;
  double heading_rmse_rad = 0;
  double max_position_m = 0;
  double position_mse_mean_m2 = 0;      // mean over time of the squared position error
  double position_mse_variance_m4 = 0;  // its variance over time
};
PoseErrors ComparePoses(const std::map<double, Pose2>& truth,
                        const std::map<double, Pose2>& estimate);

// `id,x,y,sxx,sxy,syy,source_id`, one landmark a row (source_id: -1 under known association).
std::string LandmarksCsv(const std::vector<LandmarkEstimate>& landmarks);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_RUN_FASTSLAM_RUN_H_

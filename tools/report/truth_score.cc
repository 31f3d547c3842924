#include "tools/report/truth_score.h"

#include <fmt/format.h>

#include <cstdio>
#include <iterator>

#include "tools/report/chart.h"

namespace grove::tools {

TruthScore ScoreAgainstTruth(const TruthTrajectory& truth,
                             const std::vector<StampedPose>& estimate) {
  std::vector<TimedPoint> points;
  points.reserve(estimate.size());
  for (const StampedPose& p : estimate) {
    if (!points.empty() && points.back().t_s == p.t_s) points.pop_back();
    points.push_back({p.t_s, p.pose.x_m, p.pose.y_m});
  }
  TruthScore score;
  score.error = CompareTrajectories(TimedPointsOf(truth.poses), points, &score.points);
  return score;
}

Status AddTruthScoreFiles(OutputSet* out, const TruthScore& score, const std::string& title) {
  std::string csv = "t,error\n";
  ChartSeries series{.label = {}, .style = ChartStyle::kLine};
  for (const AlignedPointError& p : score.points) {
    fmt::format_to(std::back_inserter(csv), "{:.6f},{:.6f}\n", p.t_s, p.error_m);
    series.x.push_back(p.t_s);
    series.y.push_back(p.error_m);
  }
  GROVE_RETURN_IF_ERROR(out->Add(kTruthScoreFiles[0], csv));
  const Chart chart{.title = title,
                    .x_label = "time, s",
                    .y_label = "position error after a rigid alignment, m",
                    .series = {series},
                    .y_from_zero = true};
  Status drawn = WriteChart(chart, out->StagingPath(kTruthScoreFiles[1]), "");
  if (drawn.code() == StatusCode::kNotFound) {  // gnuplot is not installed: not worth the run
    std::fprintf(stderr, "grove: %s is not drawn: %s\n", kTruthScoreFiles[1],
                 drawn.message().c_str());
    return Status::Ok();
  }
  GROVE_RETURN_IF_ERROR(drawn);
  return out->Adopt(kTruthScoreFiles[1]);
}

std::string TruthHeadline(const TruthScore& score) {
  if (!score.error.ok()) {
    return "error against truth: not computed: " + score.error.status().message();
  }
  const TrajectoryError& e = *score.error;
  return fmt::format(
      "error against truth: RMSE {:.2f} m (aligned {:.2f} m), max {:.2f} m over {} points",
      e.rmse_m, e.aligned_rmse_m, e.max_m, e.matched);
}

}  // namespace grove::tools

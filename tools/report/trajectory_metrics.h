// Accuracy of an estimated trajectory against the truth.
#ifndef GROVE_TOOLS_REPORT_TRAJECTORY_METRICS_H_
#define GROVE_TOOLS_REPORT_TRAJECTORY_METRICS_H_

#include <cstddef>
#include <string>
#include <vector>

#include "grove/status.h"

namespace grove::tools {

struct TimedPoint {
  double t_s = 0;
  double x_m = 0;
  double y_m = 0;
};

// Reads a CSV file whose header starts with the fields t,x,y; further columns (such as a heading)
// are allowed and ignored, but every row must have as many fields as the header. The file syntax
// and the "FILE:LINE:COLUMN: what" errors are those of step files (tools/io/step_reader.h); times
// must be strictly increasing and the file must hold at least one point. Lines are limited to
// 64 KiB.
StatusOr<std::vector<TimedPoint>> ReadTimedPoints(const std::string& path);

struct TrajectoryError {
  size_t matched = 0;  // truth points inside the estimate's time span
  // Distances between matched truth points and the estimate, as given.
  double rmse_m = 0;
  double max_m = 0;
  // The same after moving the estimate by the rigid transform (rotation, then translation; no
  // scale) that minimises the squared distances: truth ~ R(rotation_rad) * estimate + translation.
  double aligned_rmse_m = 0;
  double aligned_max_m = 0;
  double rotation_rad = 0;  // in (-pi, pi]
  double translation_x_m = 0;
  double translation_y_m = 0;
};

// Matches every truth point to the estimate at the same time, linearly interpolated between the
// two estimate points around it; truth points outside the estimate's time span are skipped.
// Both inputs need finite values and strictly increasing times. Returns InvalidArgument when
// fewer than 2 points match. If the matched estimate points all coincide the rotation is 0.
// Alignment: closed-form 2D Kabsch/Umeyama (Umeyama 1991, without the scale).
// `points` (may be null) gets each matched truth point with its aligned error.
struct AlignedPointError {
  double t_s = 0;
  double truth_x_m = 0, truth_y_m = 0;
  double estimate_x_m = 0, estimate_y_m = 0;  // interpolated and aligned
  double error_m = 0;
};
StatusOr<TrajectoryError> CompareTrajectories(const std::vector<TimedPoint>& truth,
                                              const std::vector<TimedPoint>& estimate,
                                              std::vector<AlignedPointError>* points = nullptr);

// The fields of `error` as a pretty-printed JSON object, named as in the struct.
std::string TrajectoryErrorJson(const TrajectoryError& error);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_REPORT_TRAJECTORY_METRICS_H_

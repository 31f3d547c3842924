// Accuracy of an estimated trajectory against the truth.
#ifndef GROVE_TOOLS_REPORT_TRAJECTORY_METRICS_H_
#define GROVE_TOOLS_REPORT_TRAJECTORY_METRICS_H_

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "grove/status.h"
#include "grove/types.h"

namespace grove::tools {

struct TimedPoint {
  double t_s = 0;
  double x_m = 0;
  double y_m = 0;
};

// Reads the points of a trajectory file: a CSV file whose header starts with the fields t,x,y
// or a TUM file, as ReadTruthTrajectory (tools/io/truth_trajectory.h) reads them.
StatusOr<std::vector<TimedPoint>> ReadTimedPoints(const std::string& path);
// The positions of `poses`.
std::vector<TimedPoint> TimedPointsOf(const std::vector<StampedPose>& poses);

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

// The fields of `error` as a JSON object, named as in the struct (keys sorted).
nlohmann::json TrajectoryErrorObject(const TrajectoryError& error);
// The same, pretty-printed, the keys in the struct's order.
std::string TrajectoryErrorJson(const TrajectoryError& error);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_REPORT_TRAJECTORY_METRICS_H_

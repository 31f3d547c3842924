#include "tools/report/trajectory_metrics.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string_view>

#include "tools/io/truth_trajectory.h"

namespace grove::tools {
namespace {

Status CheckPoints(const std::vector<TimedPoint>& points, std::string_view name) {
  for (size_t i = 0; i < points.size(); ++i) {
    const TimedPoint& p = points[i];
    for (const auto& [field, value] :
         {std::pair{"t_s", p.t_s}, std::pair{"x_m", p.x_m}, std::pair{"y_m", p.y_m}}) {
      if (!std::isfinite(value)) {
        return InvalidArgumentError(
            fmt::format("{}[{}].{} = {}: must be finite", name, i, field, value));
      }
    }
    if (i > 0 && !(p.t_s > points[i - 1].t_s)) {
      return InvalidArgumentError(fmt::format(
          "{}[{}].t_s = {} is not after {}[{}].t_s = {}: times must be strictly increasing", name,
          i, p.t_s, name, i - 1, points[i - 1].t_s));
    }
  }
  return Status::Ok();
}

// The fields of `error`, named as in the struct, into a JSON object of type Json.
template <typename Json>
Json ErrorFields(const TrajectoryError& error) {
  Json json;
  json["matched"] = error.matched;
  json["rmse_m"] = error.rmse_m;
  json["max_m"] = error.max_m;
  json["aligned_rmse_m"] = error.aligned_rmse_m;
  json["aligned_max_m"] = error.aligned_max_m;
  json["rotation_rad"] = error.rotation_rad;
  json["translation_x_m"] = error.translation_x_m;
  json["translation_y_m"] = error.translation_y_m;
  return json;
}

}  // namespace

StatusOr<std::vector<TimedPoint>> ReadTimedPoints(const std::string& path) {
  StatusOr<TruthTrajectory> truth = ReadTruthTrajectory(path);
  if (!truth.ok()) return truth.status();
  return TimedPointsOf(truth->poses);
}

std::vector<TimedPoint> TimedPointsOf(const std::vector<StampedPose>& poses) {
  std::vector<TimedPoint> points;
  points.reserve(poses.size());
  for (const StampedPose& p : poses) points.push_back({p.t_s, p.pose.x_m, p.pose.y_m});
  return points;
}

StatusOr<TrajectoryError> CompareTrajectories(const std::vector<TimedPoint>& truth,
                                              const std::vector<TimedPoint>& estimate,
                                              std::vector<AlignedPointError>* points) {
  GROVE_RETURN_IF_ERROR(CheckPoints(truth, "truth"));
  GROVE_RETURN_IF_ERROR(CheckPoints(estimate, "estimate"));

  // Pairs (truth, estimate at the truth's time); both lists are sorted, so one forward pass.
  struct Pair {
    double tx, ty, ex, ey, t;
  };
  std::vector<Pair> pairs;
  size_t j = 0;
  for (const TimedPoint& p : truth) {
    if (estimate.empty() || p.t_s < estimate.front().t_s || p.t_s > estimate.back().t_s) continue;
    while (j + 1 < estimate.size() && estimate[j + 1].t_s <= p.t_s) ++j;
    const TimedPoint& a = estimate[j];
    if (p.t_s == a.t_s) {
      pairs.push_back({p.x_m, p.y_m, a.x_m, a.y_m, p.t_s});
      continue;
    }
    const TimedPoint& b = estimate[j + 1];  // exists: a.t_s < p.t_s <= back().t_s
    const double f = (p.t_s - a.t_s) / (b.t_s - a.t_s);
    pairs.push_back(
        {p.x_m, p.y_m, a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m), p.t_s});
  }
  if (pairs.size() < 2) {
    return InvalidArgumentError(fmt::format(
        "{} truth point(s) fall within the estimate's time span{}: need at least 2", pairs.size(),
        estimate.empty() ? std::string(" (the estimate is empty)")
                         : fmt::format(" [{}, {}] s", estimate.front().t_s, estimate.back().t_s)));
  }

  TrajectoryError error;
  error.matched = pairs.size();
  const double n = static_cast<double>(pairs.size());
  double sum_squared = 0;
  double truth_cx = 0, truth_cy = 0, estimate_cx = 0, estimate_cy = 0;
  for (const Pair& q : pairs) {
    const double d2 = (q.tx - q.ex) * (q.tx - q.ex) + (q.ty - q.ey) * (q.ty - q.ey);
    sum_squared += d2;
    error.max_m = std::max(error.max_m, std::sqrt(d2));
    truth_cx += q.tx;
    truth_cy += q.ty;
    estimate_cx += q.ex;
    estimate_cy += q.ey;
  }
  error.rmse_m = std::sqrt(sum_squared / n);
  truth_cx /= n;
  truth_cy /= n;
  estimate_cx /= n;
  estimate_cy /= n;

  // In 2D the optimal rotation angle is atan2 of the summed cross and dot products of the centred
  // estimate and truth points.
  double dot = 0;
  double cross = 0;
  for (const Pair& q : pairs) {
    const double ax = q.ex - estimate_cx, ay = q.ey - estimate_cy;
    const double bx = q.tx - truth_cx, by = q.ty - truth_cy;
    dot += ax * bx + ay * by;
    cross += ax * by - ay * bx;
  }
  double angle = std::atan2(cross, dot);
  if (angle <= -std::numbers::pi) angle += 2 * std::numbers::pi;  // atan2(-0.0, x < 0) is -pi
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  error.rotation_rad = angle;
  error.translation_x_m = truth_cx - (c * estimate_cx - s * estimate_cy);
  error.translation_y_m = truth_cy - (s * estimate_cx + c * estimate_cy);
  double aligned_squared = 0;
  if (points != nullptr) points->clear();
  for (const Pair& q : pairs) {
    const double ex = c * q.ex - s * q.ey + error.translation_x_m;
    const double ey = s * q.ex + c * q.ey + error.translation_y_m;
    const double d2 = (q.tx - ex) * (q.tx - ex) + (q.ty - ey) * (q.ty - ey);
    aligned_squared += d2;
    error.aligned_max_m = std::max(error.aligned_max_m, std::sqrt(d2));
    if (points != nullptr) points->push_back({q.t, q.tx, q.ty, ex, ey, std::sqrt(d2)});
  }
  error.aligned_rmse_m = std::sqrt(aligned_squared / n);
  return error;
}

nlohmann::json TrajectoryErrorObject(const TrajectoryError& error) {
  return ErrorFields<nlohmann::json>(error);
}

std::string TrajectoryErrorJson(const TrajectoryError& error) {
  return ErrorFields<nlohmann::ordered_json>(error).dump(2);
}

}  // namespace grove::tools

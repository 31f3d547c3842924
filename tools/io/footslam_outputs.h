// FootSLAM's output files: map.csv, map_best.csv, trajectory.csv, mean_trajectory.csv,
// smoothed_trajectory.csv, the map images and summary.json's FootSLAM fields, and the odometry
// path drawn beside the estimate.
#ifndef GROVE_TOOLS_IO_FOOTSLAM_OUTPUTS_H_
#define GROVE_TOOLS_IO_FOOTSLAM_OUTPUTS_H_

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "grove/footslam.h"
#include "tools/io/filter_outputs.h"
#include "tools/report/map_render.h"

namespace grove::tools {

// `q,r,x,y,c0..c5`, one hexagon a row; counts with 9 significant digits, or as integers.
std::string MapCsv(const std::vector<HexCounts>& hexes, bool integer_counts);

// The raw odometry in the map frame: the steps rotated by the start heading and summed from
// the start position. The one integration of a step file, for `run` and `render` alike.
class OdometryPath {
 public:
  explicit OdometryPath(const Pose2& start)
      : cos_(std::cos(start.heading_rad)), sin_(std::sin(start.heading_rad)) {
    points_.push_back({start.x_m, start.y_m});
  }
  void Add(double dx_m, double dy_m) {
    points_.push_back({points_.back().x_m + cos_ * dx_m - sin_ * dy_m,
                       points_.back().y_m + sin_ * dx_m + cos_ * dy_m});
  }
  const std::vector<RenderPoint>& points() const { return points_; }

 private:
  double cos_, sin_;
  std::vector<RenderPoint> points_;
};

// The image of a run: the map's hexagons shaded by use, a path and the odometry.
MapImage FootSlamImage(double hex_radius_m, const std::vector<HexCounts>& map,
                       const std::vector<StampedPose>& path, std::vector<RenderPoint> odometry,
                       std::string title);

// summary.json's FootSLAM fields: FilterSummaryJson's and its own: memory, resamplings, ESS, scale
// and heading error.
nlohmann::json FootSlamSummaryJson(const FootSlamSummary& s);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_FOOTSLAM_OUTPUTS_H_

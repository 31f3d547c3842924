#include "tools/io/footslam_outputs.h"

#include <fmt/format.h>

#include <iterator>

namespace grove::tools {
std::string MapCsv(const std::vector<HexCounts>& hexes, bool integer_counts) {
  std::string out = "q,r,x,y,c0,c1,c2,c3,c4,c5\n";
  out.reserve(hexes.size() * 64 + out.size());
  for (const HexCounts& h : hexes) {
    fmt::format_to(std::back_inserter(out), "{},{},{:.4f},{:.4f}", h.q, h.r, h.x_m, h.y_m);
    for (double c : h.counts) {
      if (integer_counts) {
        fmt::format_to(std::back_inserter(out), ",{}", static_cast<int64_t>(c));
      } else {
        fmt::format_to(std::back_inserter(out), ",{:.9g}", c);
      }
    }
    out += '\n';
  }
  return out;
}

MapImage FootSlamImage(double hex_radius_m, const std::vector<HexCounts>& map,
                       const std::vector<StampedPose>& path, std::vector<RenderPoint> odometry,
                       std::string title) {
  MapImage image;
  image.hex_radius_m = hex_radius_m;
  for (const HexCounts& h : map) {
    double use = 0;
    for (double c : h.counts) use += c;
    image.hexes.push_back({h.q, h.r, use});
  }
  for (const StampedPose& p : path) image.path.push_back({p.pose.x_m, p.pose.y_m});
  image.odometry = std::move(odometry);
  image.title = std::move(title);
  return image;
}

nlohmann::json FootSlamSummaryJson(const FootSlamSummary& s) {
  nlohmann::json j = FilterSummaryJson(s);
  j["map_memory"] = MemoryUseJson(s.map_memory);
  j["trajectory_memory"] = MemoryUseJson(s.trajectory_memory);
  j["mean_scale"] = s.mean_scale;
  j["mean_heading_error_rad"] = s.mean_heading_error_rad;
  j["grid_size"] = s.grid_size;
  j["prior_hexagons"] = s.prior_hexagons;
  if (s.stored_blocks > 0 || s.stored_hexagons > 0) {
    j["storage_of_diversity"] = {{"stored_blocks", s.stored_blocks},
                                 {"stored_blocks_exact", s.stored_blocks_exact},
                                 {"stored_hexagons", s.stored_hexagons},
                                 {"seconds", s.store_s}};
  }
  return j;
}

}  // namespace grove::tools

#include "tools/footslam_outputs.h"

#include <fmt/format.h>

#include <iterator>

namespace grove::tools {
namespace {

nlohmann::json MemoryJson(const MemoryUse& m) {
  return {{"live_nodes", m.live_nodes},
          {"live_bytes", m.live_bytes},
          {"peak_live_nodes", m.peak_live_nodes},
          {"peak_live_bytes", m.peak_live_bytes},
          {"reserved_bytes", m.reserved_bytes}};
}

}  // namespace

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

std::string TrajectoryCsv(const std::vector<StampedPose>& poses) {
  std::string out = "t,x,y,heading\n";
  out.reserve(poses.size() * 48 + out.size());
  for (const StampedPose& p : poses) {
    fmt::format_to(std::back_inserter(out), "{:.6f},{:.6f},{:.6f},{:.6f}\n", p.t_s, p.pose.x_m,
                   p.pose.y_m, p.pose.heading_rad);
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

nlohmann::json FilterSummaryJson(const FilterSummary& s) {
  const double filter_s = s.filter_s();
  const double particle_steps = static_cast<double>(s.particles) * static_cast<double>(s.steps);
  return {{"particles", s.particles},
          {"steps", s.steps},
          {"threads_requested", s.threads_requested},
          {"threads_used", s.threads_used},
          {"filter_time_s", filter_s},
          {"particle_steps_per_s", filter_s > 0 ? particle_steps / filter_s : 0.0},
          {"ns_per_particle_step", particle_steps > 0 ? filter_s * 1e9 / particle_steps : 0.0},
          {"phases_s",
           {{"advance", s.advance_s},
            {"normalize", s.normalize_s},
            {"resample", s.resample_s},
            {"release", s.release_s},
            {"bookkeeping", s.bookkeeping_s}}},
          {"resamplings", s.resamplings},
          {"mean_ess", s.mean_ess}};
}

nlohmann::json FootSlamSummaryJson(const FootSlamSummary& s) {
  nlohmann::json j = FilterSummaryJson(s);
  j["map_memory"] = MemoryJson(s.map_memory);
  j["trajectory_memory"] = MemoryJson(s.trajectory_memory);
  j["mean_scale"] = s.mean_scale;
  j["mean_heading_error_rad"] = s.mean_heading_error_rad;
  return j;
}

}  // namespace grove::tools

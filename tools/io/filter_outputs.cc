#include "tools/io/filter_outputs.h"

#include <fmt/format.h>

#include <cmath>
#include <iterator>

namespace grove::tools {

nlohmann::json MemoryUseJson(const MemoryUse& m) {
  return {{"live_nodes", m.live_nodes},
          {"live_bytes", m.live_bytes},
          {"peak_live_nodes", m.peak_live_nodes},
          {"peak_live_bytes", m.peak_live_bytes},
          {"reserved_bytes", m.reserved_bytes}};
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

std::string TrajectoryTum(const std::vector<StampedPose>& poses) {
  std::string out = "# t x y z qx qy qz qw\n";
  out.reserve(poses.size() * 96 + out.size());
  for (const StampedPose& p : poses) {
    const double half = 0.5 * p.pose.heading_rad;
    fmt::format_to(std::back_inserter(out), "{:.9f} {:.9f} {:.9f} 0 0 0 {:.9f} {:.9f}\n", p.t_s,
                   p.pose.x_m, p.pose.y_m, std::sin(half), std::cos(half));
  }
  return out;
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
          {"mean_ess", s.mean_ess},
          {"sent_particles", s.sent_particles},
          {"sent_bytes", s.sent_bytes},
          {"migrate_s", s.migrate_s},
          {"loops", {{"count", s.loops}, {"wall_s", s.loop_s}, {"busy_s", s.loop_busy_s}}}};
}

}  // namespace grove::tools

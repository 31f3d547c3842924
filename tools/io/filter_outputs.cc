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

std::string TrajectoryKitti(const std::vector<StampedPose>& poses) {
  std::string out;
  out.reserve(poses.size() * 160);
  for (const StampedPose& p : poses) {
    const double c = std::cos(p.pose.heading_rad), s = std::sin(p.pose.heading_rad);
    // + 0.0 turns -0 into 0.
    fmt::format_to(std::back_inserter(out), "{} {} 0 {} {} {} 0 {} 0 0 1 0\n", c, -s + 0.0,
                   p.pose.x_m, s, c, p.pose.y_m);
  }
  return out;
}

namespace {

// The formats of a trajectory file, in the order the files are written.
struct TrajectoryFormat {
  const char* extension;
  std::string (*write)(const std::vector<StampedPose>&);
};
constexpr TrajectoryFormat kTrajectoryFormats[] = {
    {".csv", TrajectoryCsv}, {".tum", TrajectoryTum}, {".kitti", TrajectoryKitti}};

}  // namespace

std::vector<std::string> TrajectoryFileNames(std::span<const char* const> stems) {
  std::vector<std::string> names;
  for (const TrajectoryFormat& format : kTrajectoryFormats) {
    for (const char* stem : stems) names.push_back(std::string(stem) + format.extension);
  }
  return names;
}

Status AddTrajectoryFiles(OutputSet* out, std::span<const char* const> stems,
                          std::span<const std::vector<StampedPose>* const> trajectories) {
  if (stems.size() != trajectories.size()) {
    return InternalError(
        fmt::format("{} trajectory names for {} trajectories", stems.size(), trajectories.size()));
  }
  for (const TrajectoryFormat& format : kTrajectoryFormats) {
    for (size_t k = 0; k < stems.size(); ++k) {
      GROVE_RETURN_IF_ERROR(
          out->Add(std::string(stems[k]) + format.extension, format.write(*trajectories[k])));
    }
  }
  return Status::Ok();
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

#include "tools/montecarlo/monte_carlo_plan.h"

#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <utility>

#include "grove/config_fields.h"
#include "grove/config_json.h"
#include "tools/montecarlo/fnv1a.h"

namespace grove::tools {
namespace {

constexpr PaperRow kPaperRows[] = {
    {"sim1", FastSlamFilter::kFastSlam2, 0, 5.2617, 17.2117, 0.1784, "Table 1"},
    {"sim1", FastSlamFilter::kSrcdAided, 0, 4.5262, 6.9328, 0.2338, "Table 1"},
    {"sim1", FastSlamFilter::kSrcdParticle, 0, 2.8735, 1.7646, 0.1453, "Table 1"},
    {"sim1", FastSlamFilter::kSrcd, 0, 2.8211, 1.5997, 0.1211, "Table 1"},
    {"sim2", FastSlamFilter::kUnscented, 30, 18.4513, 120.0046, 0.5669, "Table 2"},
    {"sim2", FastSlamFilter::kSrcd, 30, 16.5021, 95.3682, 0.5156, "Table 2"},
    {"sim2", FastSlamFilter::kDeSrcd, 3, 11.2039, 42.8834, 0.4157, "Table 2"},
};

const PaperRow* FindPaperRow(const std::string& scenario, FastSlamFilter filter,
                             int64_t particles) {
  for (const PaperRow& row : kPaperRows) {
    if (row.scenario == scenario && row.filter == filter &&
        (row.particles == 0 || row.particles == particles)) {
      return &row;
    }
  }
  return nullptr;
}

// The result-changing fields of the job's configuration, hashed.
std::string ConfigDigest(const FastSlamConfig& config) {
  return Hex16(Fnv1a(ResultConfigToJson(FastSlamConfigFields(), config)));
}

}  // namespace

int64_t PaperParticles(std::string_view preset, FastSlamFilter filter) {
  const bool de = filter == FastSlamFilter::kDeSrcd;
  if (preset == "sim2") return de ? 3 : 30;
  if (preset == "sim3") return de ? 10 : 100;
  return 100;
}

FastSlamConfig MonteCarloJobConfig(const MonteCarloScenario& scenario, FastSlamFilter filter,
                                   int64_t particles, uint64_t seed) {
  const BaileySimOptions& o = scenario.spec.sim;
  FastSlamConfig c;
  c.filter = filter;
  c.particles = particles;
  c.seed = seed;
  c.threads = 1;
  c.wheelbase_m = o.wheelbase_m;
  c.sigma_speed_mps = o.sigma_speed_mps;
  c.sigma_steer_rad = o.sigma_steer_rad;
  c.sigma_range_m = o.sigma_range_m;
  c.sigma_bearing_rad = o.sigma_bearing_rad;
  c.start_x_m = o.start_x_m;
  c.start_y_m = o.start_y_m;
  c.start_heading_rad = o.start_heading_rad;
  c.association = scenario.spec.association;
  c.sensor_range_m = o.max_range_m;
  c.sensor_fov_rad = o.field_of_view_rad;
  // The seed's Eq. 27: resample when the effective sample size falls below half the particles.
  c.resample_threshold = 0.5;
  return c;
}

StatusOr<MonteCarloPlan> MakeMonteCarloPlan(const MonteCarloScenario& scenario,
                                            const std::vector<FastSlamFilter>& filters,
                                            const std::vector<int64_t>& particles, int64_t runs,
                                            uint64_t seed) {
  MonteCarloPlan plan;
  for (FastSlamFilter filter : filters) {
    std::vector<int64_t> counts = particles;
    if (counts.empty()) counts = {PaperParticles(scenario.spec.preset, filter)};
    for (int64_t n : counts) {
      MonteCarloGroup g{filter, n, fmt::format("{}_p{}", FastSlamFilterName(filter), n), "",
                        FindPaperRow(scenario.spec.name, filter, n)};
      const FastSlamConfig config = MonteCarloJobConfig(scenario, filter, n, seed);
      if (Status s = config.Validate(); !s.ok()) {
        return InvalidArgumentError(
            fmt::format("{} with {} particles: {}", FastSlamFilterName(filter), n, s.message()));
      }
      FastSlamConfig digest_config = config;
      digest_config.seed = 0;  // per run, recorded apart
      g.config_digest = ConfigDigest(digest_config);
      plan.groups.push_back(std::move(g));
    }
  }
  for (size_t g = 0; g < plan.groups.size(); ++g) {
    for (int64_t r = 0; r < runs; ++r) {
      plan.jobs.push_back({g, r, seed + static_cast<uint64_t>(r)});
    }
  }
  return plan;
}

std::string RunsText(int64_t runs) { return fmt::format("{} run{}", runs, runs == 1 ? "" : "s"); }

}  // namespace grove::tools

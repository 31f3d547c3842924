// The jobs of `grove fastslam montecarlo`: one group per filter and particle count, one job per
// group and run; and what each job's filter is configured with.
#ifndef GROVE_TOOLS_MONTECARLO_MONTE_CARLO_PLAN_H_
#define GROVE_TOOLS_MONTECARLO_MONTE_CARLO_PLAN_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "grove/fastslam.h"
#include "grove/status.h"
#include "tools/montecarlo/monte_carlo_scenario.h"

namespace grove::tools {

// One row of the seed's numbers (Ankışhan et al., 2016): Table 1 (Simulation I, no particle count
// given) and Table 2 (Simulation II, 30 particles, 3 for DE-SRCD).
struct PaperRow {
  std::string_view scenario;
  FastSlamFilter filter;
  int64_t particles;  // 0: any count
  double position_mse_mean;
  double position_mse_variance;
  double heading_mse;
  const char* table;
};

// The particles the seed ran `filter` with in the scenario of `preset`: sim2 30 (de_srcd 3),
// sim3 100 (de_srcd 10); sim1 and webmap 100 (the seed gives no count for Simulation I).
int64_t PaperParticles(std::string_view preset, FastSlamFilter filter);

// The filter's configuration for one job: FastSlamConfig's defaults, with the filter, particles,
// seed and one thread; the simulator's noise as the assumed noise (sigma_speed_mps,
// sigma_steer_rad, sigma_range_m, sigma_bearing_rad), its wheelbase and start pose; the
// scenario's association; and for the existence evidence of unknown association the simulator's
// sensor range and field of view (sensor_range_m, sensor_fov_rad); resampling when
// ESS < 0.5 N (the seed's Eq. 27).
FastSlamConfig MonteCarloJobConfig(const MonteCarloScenario& scenario, FastSlamFilter filter,
                                   int64_t particles, uint64_t seed);

// A filter at one particle count.
struct MonteCarloGroup {
  FastSlamFilter filter;
  int64_t particles;
  std::string name;           // <filter>_p<particles>
  std::string config_digest;  // of the result-changing fields, the seed aside
  const PaperRow* paper;      // the seed's row for it, or null
};

// Run `run` of group `group`: simulator and filter seeded with `seed`.
struct MonteCarloJob {
  size_t group;
  int64_t run;
  uint64_t seed;
};

struct MonteCarloPlan {
  std::vector<MonteCarloGroup> groups;
  std::vector<MonteCarloJob> jobs;  // group by group, runs in order
};

// Every filter at every count of `particles` (empty: PaperParticles), `runs` runs each, run r
// seeded with seed + r. InvalidArgument "filter with N particles: ..." when a job's
// configuration is invalid.
StatusOr<MonteCarloPlan> MakeMonteCarloPlan(const MonteCarloScenario& scenario,
                                            const std::vector<FastSlamFilter>& filters,
                                            const std::vector<int64_t>& particles, int64_t runs,
                                            uint64_t seed);

// "1 run", "30 runs".
std::string RunsText(int64_t runs);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_MONTE_CARLO_PLAN_H_

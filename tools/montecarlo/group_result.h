// The figures of one filter and particle count over its Monte Carlo runs, gathered from the
// runs' records (tools/montecarlo/job_record.h): the same numbers whether a job ran now or in
// an earlier invocation.
#ifndef GROVE_TOOLS_MONTECARLO_GROUP_RESULT_H_
#define GROVE_TOOLS_MONTECARLO_GROUP_RESULT_H_

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "grove/status.h"
#include "tools/montecarlo/job_record.h"
#include "tools/montecarlo/monte_carlo_plan.h"
#include "tools/montecarlo/monte_carlo_scenario.h"

namespace grove::tools {

// The confidence level of the intervals over runs and of the NEES acceptance interval.
inline constexpr double kMonteCarloLevel = 0.95;
// The pose NEES's degrees of freedom: x, y, heading.
inline constexpr int kPoseDof = 3;

struct GroupResult {
  int64_t runs_ok = 0;
  int64_t runs_failed = 0;
  int64_t out_of_memory = 0;          // of runs_failed
  std::vector<std::string> failures;  // "run r: message"
  std::vector<double> mse_mean, mse_variance, heading_mse, nees_mean, cpu_s, ns_per_particle_step,
      final_error;
  int64_t nees_scans = 0, nees_undefined = 0;
  // Per truth row, over the successful runs.
  std::vector<double> t, e2_sum, h2_sum, nees_sum;
  std::vector<int64_t> e_count, nees_count;
  std::vector<uint8_t> scan;
  nlohmann::json runs = nlohmann::json::array();
  // Of the averaged NEES at scans with a finite value: how many lie inside the interval for the
  // runs averaged there (CountNeesInside).
  int64_t nees_points = 0, nees_inside = 0;

  // Adds one run: its JSON record and the series of its CSV.
  void Add(const nlohmann::json& record, const RunSeries& series);
  // Sets nees_points and nees_inside, once every run is added.
  void CountNeesInside();
};

// Every group's result, read from the records in `dir` (failed runs included), in plan.groups's
// order. An error when a record is missing or damaged.
StatusOr<std::vector<GroupResult>> ReadGroupResults(const std::string& dir,
                                                    const MonteCarloScenario& scenario,
                                                    const MonteCarloPlan& plan);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_GROUP_RESULT_H_

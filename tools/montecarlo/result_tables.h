// The tables of `grove fastslam montecarlo`: table.csv, table.md (in the shape of the seed's
// Tables 1 and 2, with 95 % intervals and the seed's figures beside), and the per-group part of
// summary.json.
#ifndef GROVE_TOOLS_MONTECARLO_RESULT_TABLES_H_
#define GROVE_TOOLS_MONTECARLO_RESULT_TABLES_H_

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tools/montecarlo/group_result.h"
#include "tools/montecarlo/mc_statistics.h"
#include "tools/montecarlo/monte_carlo_plan.h"
#include "tools/montecarlo/monte_carlo_scenario.h"

namespace grove::tools {

struct MonteCarloTables {
  std::string csv;        // table.csv
  std::string md;         // table.md: a title, what the columns mean, the table
  nlohmann::json groups;  // summary.json's "groups"
};

// `results` in plan.groups's order; `runs` runs per group, run r seeded with seed + r;
// `interval` the NEES acceptance interval for `runs` runs.
MonteCarloTables MakeMonteCarloTables(const MonteCarloScenario& scenario,
                                      const MonteCarloPlan& plan,
                                      const std::vector<GroupResult>& results, int64_t runs,
                                      uint64_t seed, const NeesInterval& interval);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_RESULT_TABLES_H_

// A scenario file of `grove fastslam montecarlo --scenario FILE.json` (the format:
// ParseMonteCarloScenario, tools/montecarlo/monte_carlo_scenario.h).
#ifndef GROVE_TOOLS_MONTECARLO_SCENARIO_FILE_H_
#define GROVE_TOOLS_MONTECARLO_SCENARIO_FILE_H_

#include <string>

#include "grove/status.h"
#include "tools/montecarlo/monte_carlo_scenario.h"

namespace grove::tools {

// The scenario `path` describes, with the preset's options and the file's overrides; the map
// is not read. Errors name the file, line and column.
StatusOr<MonteCarloScenarioSpec> ParseScenarioFile(const std::string& path);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_SCENARIO_FILE_H_

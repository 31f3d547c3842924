// The charts of `grove fastslam montecarlo` (PNG and SVG, drawn by gnuplot): mse_position and
// mse_heading (the seed's Figs. 3 and 6), boxplot_position (Fig. 4), nees (Fig. 8) and, with
// more than one particle count, accuracy_vs_cpu.
#ifndef GROVE_TOOLS_MONTECARLO_RESULT_CHARTS_H_
#define GROVE_TOOLS_MONTECARLO_RESULT_CHARTS_H_

#include <cstdint>
#include <string>
#include <vector>

#include "grove/fastslam.h"
#include "grove/status.h"
#include "tools/montecarlo/group_result.h"
#include "tools/montecarlo/mc_statistics.h"
#include "tools/montecarlo/monte_carlo_plan.h"
#include "tools/montecarlo/monte_carlo_scenario.h"

namespace grove::tools {

// What the charts are drawn from: `results` in plan.groups's order, the filters and particle
// counts as given (`particles` empty: the seed's), `runs` runs per group and the NEES
// acceptance interval for them.
struct MonteCarloChartData {
  const MonteCarloScenario& scenario;
  const MonteCarloPlan& plan;
  const std::vector<GroupResult>& results;
  const std::vector<FastSlamFilter>& filters;
  const std::vector<int64_t>& particles;
  int64_t runs;
  NeesInterval interval;
};

// Writes DIR/<name>.png and .svg for each chart; *names gets the names written, in order.
Status WriteMonteCarloCharts(const MonteCarloChartData& data, const std::string& dir,
                             std::vector<std::string>* names);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_RESULT_CHARTS_H_

#include "tools/montecarlo/result_charts.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "tools/report/chart.h"

namespace grove::tools {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// The time-series charts draw at most about this many points per series.
constexpr size_t kMaxChartPoints = 4000;

// Every `stride`-th row of a per-row average, and the last, where it is defined.
ChartSeries RowSeries(const std::string& label, const GroupResult& g,
                      const std::vector<double>& sum) {
  ChartSeries s{.label = label, .style = ChartStyle::kLine};
  const size_t rows = g.t.size();
  const size_t stride = std::max<size_t>(1, (rows + kMaxChartPoints - 1) / kMaxChartPoints);
  for (size_t r = 0; r < rows; ++r) {
    if (r % stride != 0 && r + 1 != rows) continue;
    if (g.e_count[r] == 0) continue;
    s.x.push_back(g.t[r]);
    s.y.push_back(sum[r] / static_cast<double>(g.e_count[r]));
  }
  return s;
}

// The average NEES at each scan. The line breaks (a NaN) at a scan without a finite NEES and
// where scans stop for a while (no landmark in view). *t_first and *t_last widen to the scans
// with a finite NEES.
ChartSeries NeesSeries(const std::string& label, const GroupResult& r, double dt_observe_s,
                       double* t_first, double* t_last) {
  ChartSeries ns{.label = label, .style = ChartStyle::kLine};
  double last_scan_t = -INFINITY;
  for (size_t row = 0; row < r.t.size(); ++row) {
    if (!r.scan[row]) continue;
    if (r.t[row] - last_scan_t > 1.5 * dt_observe_s && !ns.x.empty()) {
      ns.x.push_back(r.t[row]);
      ns.y.push_back(kNaN);
    }
    last_scan_t = r.t[row];
    ns.x.push_back(r.t[row]);
    ns.y.push_back(
        r.nees_count[row] == 0 ? kNaN : r.nees_sum[row] / static_cast<double>(r.nees_count[row]));
    if (r.nees_count[row] == 0) continue;
    *t_first = std::min(*t_first, r.t[row]);
    *t_last = std::max(*t_last, r.t[row]);
  }
  return ns;
}

// The four charts every invocation draws, in order: mse_position, mse_heading,
// boxplot_position, nees.
std::vector<Chart> GroupCharts(const MonteCarloChartData& d) {
  const std::string& name = d.scenario.spec.name;
  const std::string runs_text = RunsText(d.runs);
  Chart mse_position{
      .title = fmt::format("{}: position MSE over {} (seed Fig. 3a / 6a)", name, runs_text),
      .x_label = "time (s)",
      .y_label = "mean squared position error (m²)"};
  Chart mse_heading{
      .title = fmt::format("{}: heading MSE over {} (seed Fig. 3b / 6b)", name, runs_text),
      .x_label = "time (s)",
      .y_label = "mean squared heading error (rad²)"};
  Chart boxes{.title = fmt::format(
                  "{}: position MSE of each run, by filter and particles (seed Fig. 4)", name),
              .y_label = "run's mean squared position error (m²)"};
  Chart nees{.title = fmt::format("{}: pose NEES averaged over {} (seed Fig. 8)", name, runs_text),
             .x_label = "time (s)",
             .y_label = "average NEES (log scale)",
             .log_y = true};
  double t_first = INFINITY, t_last = -INFINITY;
  for (size_t gi = 0; gi < d.plan.groups.size(); ++gi) {
    const MonteCarloGroup& g = d.plan.groups[gi];
    const GroupResult& r = d.results[gi];
    const std::string label = fmt::format("{}, {} particle{}", FastSlamFilterName(g.filter),
                                          g.particles, g.particles == 1 ? "" : "s");
    mse_position.series.push_back(RowSeries(label, r, r.e2_sum));
    mse_heading.series.push_back(RowSeries(label, r, r.h2_sum));
    boxes.boxes.push_back(
        {.label = fmt::format("{}, {}", FastSlamFilterName(g.filter), g.particles),
         .values = r.mse_mean});
    nees.series.push_back(
        NeesSeries(label, r, d.scenario.spec.sim.dt_observe_s, &t_first, &t_last));
  }
  if (t_first <= t_last) {
    nees.series.push_back(
        {.label = fmt::format("95 % interval, {}: upper {:.2f}", runs_text, d.interval.high),
         .x = {t_first, t_last},
         .y = {d.interval.high, d.interval.high},
         .style = ChartStyle::kDashed});
    nees.series.push_back(
        {.label = fmt::format("95 % interval, {}: lower {:.2f}", runs_text, d.interval.low),
         .x = {t_first, t_last},
         .y = {d.interval.low, d.interval.low},
         .style = ChartStyle::kDashed});
  }
  return {std::move(mse_position), std::move(mse_heading), std::move(boxes), std::move(nees)};
}

// Position MSE against CPU time, one line per filter through its particle counts.
Chart AccuracyChart(const MonteCarloChartData& d) {
  const std::string& name = d.scenario.spec.name;
  std::string all_counts;
  for (int64_t n : d.particles) {
    all_counts += (all_counts.empty() ? "" : ", ") + std::to_string(n);
  }
  // The counts go into the title, not the legend, so that the plot keeps its width.
  Chart accuracy{.title = fmt::format("{}: accuracy against CPU time ({})\neach line: {} particles",
                                      name, RunsText(d.runs), all_counts),
                 .x_label = "CPU seconds per run (log scale)",
                 .y_label = "position MSE mean (m², log scale)",
                 .log_x = true,
                 .log_y = true};
  for (FastSlamFilter filter : d.filters) {
    std::vector<std::pair<int64_t, size_t>> points;
    for (size_t gi = 0; gi < d.plan.groups.size(); ++gi) {
      if (d.plan.groups[gi].filter == filter) points.push_back({d.plan.groups[gi].particles, gi});
    }
    std::sort(points.begin(), points.end());
    ChartSeries series{.label = FastSlamFilterName(filter), .style = ChartStyle::kLinePoints};
    for (const auto& [n, gi] : points) {
      series.x.push_back(Mean(d.results[gi].cpu_s));
      series.y.push_back(Mean(d.results[gi].mse_mean));
    }
    accuracy.series.push_back(std::move(series));
  }
  return accuracy;
}

}  // namespace

Status WriteMonteCarloCharts(const MonteCarloChartData& data, const std::string& dir,
                             std::vector<std::string>* names) {
  std::vector<std::pair<std::string, Chart>> charts;
  std::vector<Chart> group_charts = GroupCharts(data);
  const char* group_names[] = {"mse_position", "mse_heading", "boxplot_position", "nees"};
  for (size_t i = 0; i < group_charts.size(); ++i) {
    charts.emplace_back(group_names[i], std::move(group_charts[i]));
  }
  if (data.particles.size() > 1) charts.emplace_back("accuracy_vs_cpu", AccuracyChart(data));
  for (const auto& [name, chart] : charts) {
    GROVE_RETURN_IF_ERROR(WriteChart(chart, dir + "/" + name + ".png", dir + "/" + name + ".svg"));
    names->push_back(name);
  }
  return Status::Ok();
}

}  // namespace grove::tools

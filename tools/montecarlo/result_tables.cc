#include "tools/montecarlo/result_tables.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "tools/report/report_tables.h"

namespace grove::tools {
namespace {

using nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

const std::vector<std::string>& CsvHeader() {
  static const auto* header = new std::vector<std::string>{"filter",
                                                           "particles",
                                                           "runs",
                                                           "runs_failed",
                                                           "position_mse_mean",
                                                           "position_mse_mean_ci_low",
                                                           "position_mse_mean_ci_high",
                                                           "position_mse_variance",
                                                           "position_mse_variance_ci_low",
                                                           "position_mse_variance_ci_high",
                                                           "heading_mse_mean",
                                                           "heading_mse_mean_ci_low",
                                                           "heading_mse_mean_ci_high",
                                                           "nees_mean",
                                                           "nees_undefined",
                                                           "nees_scans",
                                                           "nees_in_interval_fraction",
                                                           "cpu_s_mean",
                                                           "ns_per_particle_step",
                                                           "paper_position_mse_mean",
                                                           "paper_position_mse_variance",
                                                           "paper_heading_mse"};
  return *header;
}

// The columns of a group's row, over its successful runs.
struct GroupFigures {
  ConfidenceInterval mse, var, heading;
  double nees, inside, cpu, ns;
};

GroupFigures FiguresOf(const GroupResult& r) {
  return {StudentTInterval(r.mse_mean, kMonteCarloLevel),
          StudentTInterval(r.mse_variance, kMonteCarloLevel),
          StudentTInterval(r.heading_mse, kMonteCarloLevel),
          Mean(r.nees_mean),
          r.nees_points > 0
              ? static_cast<double>(r.nees_inside) / static_cast<double>(r.nees_points)
              : kNaN,
          Mean(r.cpu_s),
          Mean(r.ns_per_particle_step)};
}

json IntervalJson(const ConfidenceInterval& ci) {
  return {{"mean", ci.mean}, {"ci_low", ci.low}, {"ci_high", ci.high}, {"count", ci.count}};
}

// A number for table.csv: empty when not a number.
std::string CsvNumber(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : ""; }
// "4.526 (4.1 .. 4.95)", or "n/a".
std::string MdInterval(const ConfidenceInterval& ci) {
  if (!std::isfinite(ci.mean)) return "n/a";
  if (!std::isfinite(ci.half_width)) return fmt::format("{:.4g}", ci.mean);
  return fmt::format("{:.4g} ({:.3g} .. {:.3g})", ci.mean, ci.low, ci.high);
}
std::string MdNumber(double v, const char* format = "{:.3g}") {
  return std::isfinite(v) ? fmt::format(fmt::runtime(format), v) : "n/a";
}

std::vector<std::string> CsvRow(const MonteCarloGroup& g, const GroupResult& r,
                                const GroupFigures& f) {
  const PaperRow* paper = g.paper;
  return {FastSlamFilterName(g.filter),
          std::to_string(g.particles),
          std::to_string(r.runs_ok),
          std::to_string(r.runs_failed),
          CsvNumber(f.mse.mean),
          CsvNumber(f.mse.low),
          CsvNumber(f.mse.high),
          CsvNumber(f.var.mean),
          CsvNumber(f.var.low),
          CsvNumber(f.var.high),
          CsvNumber(f.heading.mean),
          CsvNumber(f.heading.low),
          CsvNumber(f.heading.high),
          CsvNumber(f.nees),
          std::to_string(r.nees_undefined),
          std::to_string(r.nees_scans),
          CsvNumber(f.inside),
          CsvNumber(f.cpu),
          CsvNumber(f.ns),
          paper ? CsvNumber(paper->position_mse_mean) : "",
          paper ? CsvNumber(paper->position_mse_variance) : "",
          paper ? CsvNumber(paper->heading_mse) : ""};
}

// The last column is the seed's figures ("" without).
std::vector<std::string> MdRow(const MonteCarloGroup& g, const GroupResult& r,
                               const GroupFigures& f) {
  const PaperRow* paper = g.paper;
  return {FastSlamFilterName(g.filter),
          std::to_string(g.particles),
          r.runs_failed == 0 ? std::to_string(r.runs_ok)
                             : fmt::format("{} ({} failed)", r.runs_ok, r.runs_failed),
          MdInterval(f.mse),
          MdInterval(f.var),
          MdInterval(f.heading),
          r.nees_undefined == 0 ? MdNumber(f.nees)
                                : fmt::format("{} ({} of {} scans undefined)", MdNumber(f.nees),
                                              r.nees_undefined, r.nees_scans),
          r.nees_points > 0 ? fmt::format("{:.0f} %", 100 * f.inside) : "n/a",
          MdNumber(f.cpu, "{:.3g}"),
          MdNumber(f.ns, "{:.0f}"),
          paper ? fmt::format("{} / {} / {} ({})", paper->position_mse_mean,
                              paper->position_mse_variance, paper->heading_mse, paper->table)
                : ""};
}

json GroupJson(const MonteCarloGroup& g, const GroupResult& r, const GroupFigures& f) {
  const PaperRow* paper = g.paper;
  json gj = {{"filter", FastSlamFilterName(g.filter)},
             {"particles", g.particles},
             {"directory", "runs/" + g.name},
             {"config_digest", g.config_digest},
             {"runs_ok", r.runs_ok},
             {"runs_failed", r.runs_failed},
             {"failures", r.failures},
             {"position_mse_mean", IntervalJson(f.mse)},
             {"position_mse_variance", IntervalJson(f.var)},
             {"heading_mse_mean", IntervalJson(f.heading)},
             {"final_position_error_m_mean", Mean(r.final_error)},
             {"nees_mean", f.nees},
             {"nees_scans", r.nees_scans},
             {"nees_undefined", r.nees_undefined},
             {"nees_in_interval_fraction", f.inside},
             {"cpu_s_mean", f.cpu},
             {"ns_per_particle_step", f.ns},
             {"runs", r.runs}};
  gj["paper"] = paper ? json{{"table", paper->table},
                             {"position_mse_mean", paper->position_mse_mean},
                             {"position_mse_variance", paper->position_mse_variance},
                             {"heading_mse", paper->heading_mse}}
                      : json(nullptr);
  return gj;
}

// table.md: the title, what the columns mean, then `table`.
std::string MdText(const MonteCarloScenario& scenario, int64_t runs, uint64_t seed,
                   const NeesInterval& interval, const std::string& table) {
  return fmt::format(
      "# grove fastslam montecarlo: {}\n\n"
      "Scenario {} (preset {}, map {}, {} association, {} loops; digest {}), {} per filter "
      "and particle count, run r with seed {} + r for the simulator and the filter, one thread "
      "per run.\n\n"
      "Per run, at every truth time (each control step; after the scan at a scan time), the "
      "weighted-mean pose against the truth: position MSE mean and variance are the mean and the "
      "variance over time of the squared position error, heading MSE the mean squared heading "
      "error (the seed's Tables 1 and 2); each column is their mean over the successful runs, "
      "with a 95 % Student-t interval over runs. Mean NEES: the pose NEES (3 degrees of freedom, "
      "the particles' weighted pose covariance after each scan) averaged over scans and runs, "
      "scans where the covariance is not positive definite left out and counted; NEES in "
      "interval: the share of scans whose NEES averaged over runs lies in the two-sided 95 % "
      "interval for that many runs ({:.2f} .. {:.2f} for {}). CPU: the thread CPU time of "
      "the filter's run (simulation excluded); ns per particle-step: that over particles x "
      "filter steps.\n\n{}",
      scenario.spec.name, scenario.spec.name, scenario.spec.preset, scenario.map_name,
      AssociationName(scenario.spec.association), scenario.spec.sim.loops, scenario.digest,
      RunsText(runs), seed, interval.low, interval.high, RunsText(runs), table);
}

}  // namespace

MonteCarloTables MakeMonteCarloTables(const MonteCarloScenario& scenario,
                                      const MonteCarloPlan& plan,
                                      const std::vector<GroupResult>& results, int64_t runs,
                                      uint64_t seed, const NeesInterval& interval) {
  std::vector<std::vector<std::string>> csv_rows, md_rows;
  json groups = json::array();
  for (size_t gi = 0; gi < plan.groups.size(); ++gi) {
    const GroupFigures f = FiguresOf(results[gi]);
    csv_rows.push_back(CsvRow(plan.groups[gi], results[gi], f));
    md_rows.push_back(MdRow(plan.groups[gi], results[gi], f));
    groups.push_back(GroupJson(plan.groups[gi], results[gi], f));
  }
  std::vector<std::string> md_header = {"filter",
                                        "particles",
                                        "runs",
                                        "position MSE mean, m² (95 % CI)",
                                        "position MSE variance, m⁴ (95 % CI)",
                                        "heading MSE, rad² (95 % CI)",
                                        "mean NEES",
                                        "NEES in interval",
                                        "CPU s per run",
                                        "ns per particle-step"};
  if (std::any_of(plan.groups.begin(), plan.groups.end(),
                  [](const MonteCarloGroup& g) { return g.paper != nullptr; })) {
    md_header.push_back("seed paper: MSE mean / variance / heading");
  } else {
    for (auto& row : md_rows) row.pop_back();
  }
  return {CsvTable(CsvHeader(), csv_rows),
          MdText(scenario, runs, seed, interval, MarkdownTable(md_header, md_rows)),
          std::move(groups)};
}

}  // namespace grove::tools

#include "tools/montecarlo/group_result.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "tools/montecarlo/mc_statistics.h"

namespace grove::tools {
namespace {

using nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// The code of an out-of-memory failure.
constexpr StatusCode kOutOfMemory = StatusCode::kResourceExhausted;

}  // namespace

void GroupResult::Add(const json& record, const RunSeries& series) {
  runs.push_back(record);
  if (record["status"] != "ok") {
    ++runs_failed;
    failures.push_back(fmt::format("run {}: {}", record["run"].get<int64_t>(),
                                   record["status"].get<std::string>()));
    out_of_memory += record.value("status_code", "") == StatusCodeName(kOutOfMemory);
    return;
  }
  ++runs_ok;
  mse_mean.push_back(JsonNumber(record, "position_mse_mean"));
  mse_variance.push_back(JsonNumber(record, "position_mse_variance"));
  heading_mse.push_back(JsonNumber(record, "heading_mse_mean"));
  final_error.push_back(JsonNumber(record, "final_position_error_m"));
  if (double n = JsonNumber(record, "nees_mean"); std::isfinite(n)) nees_mean.push_back(n);
  const double cpu = JsonNumber(record, "cpu_s");
  const double steps = JsonNumber(record, "filter_steps");
  const double particles = JsonNumber(record, "particles");
  cpu_s.push_back(cpu);
  ns_per_particle_step.push_back(steps > 0 ? cpu * 1e9 / (particles * steps) : kNaN);
  nees_scans += record.value("nees_scans", int64_t{0});
  nees_undefined += record.value("nees_undefined", int64_t{0});
  const size_t rows = series.t.size();
  if (t.size() < rows) {
    for (size_t r = t.size(); r < rows; ++r) t.push_back(series.t[r]);
    e2_sum.resize(rows, 0);
    h2_sum.resize(rows, 0);
    nees_sum.resize(rows, 0);
    e_count.resize(rows, 0);
    nees_count.resize(rows, 0);
    scan.resize(rows, 0);
  }
  for (size_t r = 0; r < rows; ++r) {
    if (std::isfinite(series.e2[r]) && std::isfinite(series.h2[r])) {
      e2_sum[r] += series.e2[r];
      h2_sum[r] += series.h2[r];
      ++e_count[r];
    }
    if (series.scan[r]) {
      scan[r] = 1;
      if (std::isfinite(series.nees[r])) {
        nees_sum[r] += series.nees[r];
        ++nees_count[r];
      }
    }
  }
}

void GroupResult::CountNeesInside() {
  std::map<int64_t, NeesInterval> intervals;
  for (size_t r = 0; r < t.size(); ++r) {
    if (!scan[r] || nees_count[r] == 0) continue;
    auto it = intervals.find(nees_count[r]);
    if (it == intervals.end()) {
      it = intervals
               .emplace(nees_count[r],
                        AverageNeesInterval(kPoseDof, nees_count[r], kMonteCarloLevel))
               .first;
    }
    const double mean = nees_sum[r] / static_cast<double>(nees_count[r]);
    ++nees_points;
    nees_inside += mean >= it->second.low && mean <= it->second.high;
  }
}

StatusOr<std::vector<GroupResult>> ReadGroupResults(const std::string& dir,
                                                    const MonteCarloScenario& scenario,
                                                    const MonteCarloPlan& plan) {
  std::vector<GroupResult> results(plan.groups.size());
  for (const MonteCarloJob& job : plan.jobs) {
    const MonteCarloGroup& g = plan.groups[job.group];
    std::string csv;
    StatusOr<json> record = ReadJobRecord(dir, scenario, g, job, &csv);
    if (!record.ok()) return record.status();
    StatusOr<RunSeries> series = ParseRunSeries(RunPath(dir, g, job.run, "csv"), csv);
    if (!series.ok()) return series.status();
    results[job.group].Add(*record, *series);
  }
  for (GroupResult& r : results) r.CountNeesInside();
  return results;
}

}  // namespace grove::tools

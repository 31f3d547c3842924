#include "tools/montecarlo/job_record.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <system_error>
#include <utility>

#include "tools/io/atomic_file.h"
#include "tools/io/csv_reader.h"
#include "tools/montecarlo/fnv1a.h"
#include "tools/montecarlo/mc_statistics.h"

namespace grove::tools {
namespace {

using nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

constexpr const char* kRunCsvHeader =
    "t,x,y,heading,truth_x,truth_y,truth_heading,position_error2,heading_error2,nees";

// Per truth row: the last mean pose at its time (when there is one), and at a scan's row the
// pose NEES.
struct TruthRows {
  std::vector<Pose2> estimate;
  std::vector<uint8_t> has;
  std::vector<double> nees;
  std::vector<uint8_t> is_scan;
};

TruthRows MatchToTruth(const JobOutcome& outcome, int64_t particles) {
  const std::vector<BaileyPose>& truth = outcome.truth;
  const size_t rows = truth.size();
  TruthRows m{std::vector<Pose2>(rows), std::vector<uint8_t>(rows, 0),
              std::vector<double>(rows, kNaN), std::vector<uint8_t>(rows, 0)};
  size_t k = 0;
  for (const StampedPose& p : outcome.trajectory) {
    while (k < rows && truth[k].t_s < p.t_s) ++k;
    if (k == rows) break;
    if (truth[k].t_s == p.t_s) {
      m.estimate[k] = p.pose;
      m.has[k] = 1;
    }
  }
  k = 0;
  for (const ScanSample& s : outcome.scans) {
    while (k < rows && truth[k].t_s < s.t_s) ++k;
    if (k == rows) break;
    if (truth[k].t_s != s.t_s) continue;
    const BaileyPose& t = truth[k];
    m.is_scan[k] = 1;
    // The weighted covariance of fewer than 4 poses about their mean has rank < 3. The engine's
    // is taken about the circular mean heading, which differs from the weighted mean of the
    // heading differences by round-off and more, so it is only nearly singular then: undefined.
    if (particles < 4) continue;
    m.nees[k] = PoseNees(t.x_m - s.mean.x_m, t.y_m - s.mean.y_m,
                         WrapAngle(t.heading_rad - s.mean.heading_rad), s.covariance);
  }
  return m;
}

// The figures a job's JSON records, over the rows of its CSV.
struct RunFigures {
  std::vector<double> e2, h2, finite_nees;
  int64_t nees_scans = 0, nees_undefined = 0;
  double final_error = kNaN;
};

std::string RunCsv(const std::vector<BaileyPose>& truth, const TruthRows& m, RunFigures* f) {
  const size_t rows = truth.size();
  std::string csv;
  csv.reserve(rows * 120 + 128);
  csv += kRunCsvHeader;
  csv += '\n';
  for (size_t r = 0; r < rows; ++r) {
    const BaileyPose& t = truth[r];
    auto out = std::back_inserter(csv);
    fmt::format_to(out, "{}", t.t_s);
    if (m.has[r]) {
      const Pose2& p = m.estimate[r];
      const double d2 = (p.x_m - t.x_m) * (p.x_m - t.x_m) + (p.y_m - t.y_m) * (p.y_m - t.y_m);
      const double dh = WrapAngle(p.heading_rad - t.heading_rad);
      f->e2.push_back(d2);
      f->h2.push_back(dh * dh);
      f->final_error = std::sqrt(d2);
      fmt::format_to(out, ",{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.9g},{:.9g},", p.x_m, p.y_m,
                     p.heading_rad, t.x_m, t.y_m, t.heading_rad, d2, dh * dh);
    } else {
      fmt::format_to(out, ",,,,{:.6f},{:.6f},{:.6f},,,", t.x_m, t.y_m, t.heading_rad);
    }
    if (m.is_scan[r]) {
      ++f->nees_scans;
      if (std::isfinite(m.nees[r])) {
        f->finite_nees.push_back(m.nees[r]);
        fmt::format_to(out, "{:.9g}", m.nees[r]);
      } else {
        ++f->nees_undefined;
        csv += "nan";
      }
    }
    csv += '\n';
  }
  return csv;
}

json JobJson(const MonteCarloScenario& scenario, const MonteCarloGroup& group,
             const MonteCarloJob& job, const JobOutcome& outcome, const RunFigures& f,
             const std::string& csv) {
  const bool ok = outcome.status.ok();
  json j = {{"filter", FastSlamFilterName(group.filter)},
            {"particles", group.particles},
            {"run", job.run},
            {"seed", job.seed},
            {"scenario", scenario.spec.name},
            {"scenario_digest", scenario.digest},
            {"config_digest", group.config_digest},
            {"status", ok ? std::string("ok") : outcome.status.message()},
            {"position_mse_mean", ok ? Mean(f.e2) : kNaN},
            {"position_mse_variance", ok ? PopulationVariance(f.e2) : kNaN},
            {"heading_mse_mean", ok ? Mean(f.h2) : kNaN},
            {"final_position_error_m", ok ? f.final_error : kNaN},
            {"nees_mean", ok ? Mean(f.finite_nees) : kNaN},
            {"nees_scans", f.nees_scans},
            {"nees_undefined", f.nees_undefined},
            {"cpu_s", outcome.cpu_s},
            {"filter_steps", outcome.steps},
            {"rows", outcome.truth.size()},
            {"rows_evaluated", f.e2.size()},
            {"csv_bytes", csv.size()},
            {"csv_fnv1a", Hex16(Fnv1a(csv))}};
  // A failure's kind: out of memory ("resource exhausted") sets the command's exit code.
  if (!ok) j["status_code"] = StatusCodeName(outcome.status.code());
  return j;
}

double ParseField(std::string_view field) {
  if (field.empty()) return kNaN;
  double v = kNaN;
  auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), v);
  return ec == std::errc() && end == field.data() + field.size() ? v : kNaN;
}

}  // namespace

std::string RunPath(const std::string& dir, const MonteCarloGroup& g, int64_t run,
                    const char* ext) {
  return fmt::format("{}/runs/{}/run_{}.{}", dir, g.name, run, ext);
}

Status WriteJobRecord(const std::string& dir, const MonteCarloScenario& scenario,
                      const MonteCarloGroup& group, const MonteCarloJob& job,
                      const JobOutcome& outcome) {
  RunFigures figures;
  const std::string csv = RunCsv(outcome.truth, MatchToTruth(outcome, group.particles), &figures);
  const json j = JobJson(scenario, group, job, outcome, figures, csv);
  // The CSV first: the JSON says the job is complete.
  GROVE_RETURN_IF_ERROR(WriteFileAtomically(RunPath(dir, group, job.run, "csv"), csv));
  return WriteFileAtomically(RunPath(dir, group, job.run, "json"), j.dump() + "\n");
}

StatusOr<json> ReadFinishedJob(const std::string& dir, const MonteCarloScenario& scenario,
                               const MonteCarloGroup& group, const MonteCarloJob& job) {
  StatusOr<json> j = ReadJobRecord(dir, scenario, group, job);
  if (!j.ok()) return j.status();
  if ((*j)["status"] != "ok") {
    return FailedPreconditionError(fmt::format("{}: the job failed ({}): it runs again",
                                               RunPath(dir, group, job.run, "json"),
                                               (*j)["status"].get<std::string>()));
  }
  return j;
}

StatusOr<json> ReadJobRecord(const std::string& dir, const MonteCarloScenario& scenario,
                             const MonteCarloGroup& group, const MonteCarloJob& job,
                             std::string* csv_text) {
  const std::string path = RunPath(dir, group, job.run, "json");
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return NotFoundError(path + ": not written yet");
  StatusOr<std::string> text = ReadWholeFile(path);
  if (!text.ok()) return text.status();
  json j = json::parse(*text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return DataLossError(path + ": not a job record");
  auto is = [&](const char* key, const json& want) {
    auto it = j.find(key);
    return it != j.end() && *it == want;
  };
  if (!is("filter", FastSlamFilterName(group.filter)) || !is("particles", group.particles) ||
      !is("run", job.run) || !is("seed", job.seed) || !is("scenario_digest", scenario.digest) ||
      !is("config_digest", group.config_digest) || !j.contains("status") ||
      !j["status"].is_string() || !j.contains("csv_bytes") || !j.contains("csv_fnv1a")) {
    return FailedPreconditionError(path + ": made under another configuration");
  }
  StatusOr<std::string> csv = ReadWholeFile(RunPath(dir, group, job.run, "csv"));
  if (!csv.ok()) return csv.status();
  if (!is("csv_bytes", csv->size()) || !is("csv_fnv1a", Hex16(Fnv1a(*csv)))) {
    return DataLossError(path + ": its CSV differs from the one it records");
  }
  if (csv_text != nullptr) *csv_text = std::move(*csv);
  return j;
}

StatusOr<RunSeries> ParseRunSeries(const std::string& path, std::string_view text) {
  RunSeries s;
  std::string_view rest = text;
  std::vector<CsvField> fields;
  bool header = true;
  while (!rest.empty()) {
    const size_t nl = rest.find('\n');
    const std::string_view line = rest.substr(0, nl);
    rest = nl == std::string_view::npos ? std::string_view() : rest.substr(nl + 1);
    if (header) {
      if (line != kRunCsvHeader) return DataLossError(path + ": not a run CSV");
      header = false;
      continue;
    }
    SplitCsvLine(line, &fields);
    if (fields.size() != 10) return DataLossError(path + ": a row without 10 fields");
    s.t.push_back(ParseField(fields[0].text));
    s.e2.push_back(ParseField(fields[7].text));
    s.h2.push_back(ParseField(fields[8].text));
    s.scan.push_back(!fields[9].text.empty());
    s.nees.push_back(ParseField(fields[9].text));
  }
  return s;
}

double JsonNumber(const json& j, const char* key) {
  auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : kNaN;
}

}  // namespace grove::tools

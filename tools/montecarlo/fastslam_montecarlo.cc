#include "tools/montecarlo/fastslam_montecarlo.h"

#include <fmt/format.h>
#include <oneapi/tbb/task_arena.h>
#include <oneapi/tbb/task_group.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <mutex>
#include <new>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <thread>
#include <utility>
#include <variant>

#include "engine/io/config_json.h"
#include "tools/io/atomic_file.h"
#include "tools/io/csv_reader.h"
#include "tools/io/output_set.h"
#include "tools/montecarlo/mc_statistics.h"
#include "tools/report/chart.h"
#include "tools/report/report_tables.h"
#include "tools/run/progress_reporter.h"
#include "tools/run/run_loop.h"

namespace grove::tools {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr int64_t kMaxRuns = 100000;
constexpr int64_t kMaxParticles = int64_t{1} << 31;
constexpr int64_t kMaxThreads = 256;
constexpr int64_t kMaxLoops = 1000;
constexpr double kLevel = 0.95;  // confidence intervals and the NEES acceptance interval
constexpr int kPoseDof = 3;      // x, y, heading
// The time-series charts draw at most about this many points per series.
constexpr size_t kMaxChartPoints = 4000;

constexpr const char* kRunCsvHeader =
    "t,x,y,heading,truth_x,truth_y,truth_heading,position_error2,heading_error2,nees";

// The seed's numbers (paper 003): Table 1 (Simulation I, no particle count given) and Table 2
// (Simulation II, 30 particles, 3 for DE-SRCD).
struct PaperRow {
  std::string_view scenario;
  FastSlamFilter filter;
  int64_t particles;  // 0: any count
  double position_mse_mean;
  double position_mse_variance;
  double heading_mse;
  const char* table;
};
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

uint64_t Fnv1a(std::string_view text, uint64_t hash = 0xcbf29ce484222325ULL) {
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

std::string Hex16(uint64_t v) { return fmt::format("{:016x}", v); }

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// `text` split at commas, blanks around each item removed.
std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> items;
  size_t begin = 0;
  for (;;) {
    const size_t end = text.find(',', begin);
    std::string item = text.substr(begin, end == std::string::npos ? end : end - begin);
    const size_t first = item.find_first_not_of(" \t");
    const size_t last = item.find_last_not_of(" \t");
    items.push_back(first == std::string::npos ? "" : item.substr(first, last - first + 1));
    if (end == std::string::npos) return items;
    begin = end + 1;
  }
}

std::vector<std::string> FilterNames() {
  const ConfigField<FastSlamConfig>* f = FindField(FastSlamConfigFields(), "filter");
  return f->info.choices;
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

StatusOr<std::vector<FastSlamFilter>> ParseFilters(const std::string& text) {
  const std::vector<std::string> names = FilterNames();
  if (text.empty()) {
    return InvalidArgumentError(
        fmt::format("--filters: the list is empty: give one or more of {}", JoinNames(names)));
  }
  std::vector<FastSlamFilter> filters;
  for (const std::string& item : SplitList(text)) {
    FastSlamFilter filter;
    if (!FastSlamFilterFromName(item, &filter)) {
      return InvalidArgumentError(
          fmt::format("--filters = {}: unknown filter {}: must be a comma list of {}",
                      QuoteForMessage(text), QuoteForMessage(item), JoinNames(names)));
    }
    if (std::find(filters.begin(), filters.end(), filter) != filters.end()) {
      return InvalidArgumentError(fmt::format("--filters = {}: {} is given twice",
                                              QuoteForMessage(text), QuoteForMessage(item)));
    }
    filters.push_back(filter);
  }
  return filters;
}

StatusOr<std::vector<int64_t>> ParseParticles(const std::string& text) {
  std::vector<int64_t> counts;
  for (const std::string& item : SplitList(text)) {
    int64_t n = 0;
    auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), n);
    if (item.empty() || ec != std::errc() || end != item.data() + item.size() || n < 1 ||
        n > kMaxParticles) {
      return InvalidArgumentError(fmt::format("--particles = {}: {} must be an integer in 1..{}",
                                              QuoteForMessage(text), QuoteForMessage(item),
                                              kMaxParticles));
    }
    if (std::find(counts.begin(), counts.end(), n) != counts.end()) {
      return InvalidArgumentError(
          fmt::format("--particles = {}: {} is given twice", QuoteForMessage(text), n));
    }
    counts.push_back(n);
  }
  return counts;
}

json SimOptionsJson(const BaileySimOptions& o) {
  return {{"speed_mps", o.speed_mps},
          {"wheelbase_m", o.wheelbase_m},
          {"max_steer_rad", o.max_steer_rad},
          {"max_steer_rate_radps", o.max_steer_rate_radps},
          {"at_waypoint_m", o.at_waypoint_m},
          {"loops", o.loops},
          {"dt_control_s", o.dt_control_s},
          {"dt_observe_s", o.dt_observe_s},
          {"max_range_m", o.max_range_m},
          {"field_of_view_rad", o.field_of_view_rad},
          {"sigma_speed_mps", o.sigma_speed_mps},
          {"sigma_steer_rad", o.sigma_steer_rad},
          {"sigma_range_m", o.sigma_range_m},
          {"sigma_bearing_rad", o.sigma_bearing_rad},
          {"start_x_m", o.start_x_m},
          {"start_y_m", o.start_y_m},
          {"start_heading_rad", o.start_heading_rad},
          {"max_steps", o.max_steps}};
}

const char* AssociationName(FastSlamAssociation a) {
  return a == FastSlamAssociation::kKnown ? "known" : "ml";
}

// The scenario file's keys besides "map", typed and bounded as FastSlamConfig's fields are.
const std::vector<FieldInfo>& ScenarioKeys() {
  auto real = [](const char* name, Interval interval) {
    return FieldInfo{name, "", FieldType::kReal, kChangesResults, 0, 0, interval, {}};
  };
  auto choice = [](const char* name, std::vector<std::string> names) {
    const auto last = static_cast<int64_t>(names.size()) - 1;
    return FieldInfo{name, "", FieldType::kChoice, kChangesResults, 0, last, {}, std::move(names)};
  };
  static const auto* keys = new std::vector<FieldInfo>{
      choice("preset", {"webmap", "sim1", "sim2", "sim3"}),
      choice("association", {"known", "ml"}),
      {"loops", "", FieldType::kInteger, kChangesResults, 1, kMaxLoops, {}, {}},
      real("sigma_speed_mps", Interval::Closed(0, 100)),
      real("sigma_steer_rad", Interval::Closed(0, std::numbers::pi)),
      real("sigma_range_m", Interval::Closed(0, 1e4)),
      real("sigma_bearing_rad", Interval::Closed(0, std::numbers::pi)),
      real("max_range_m", Interval::LeftOpen(0, 1e6)),
  };
  return *keys;
}

StatusOr<MonteCarloScenarioSpec> ParseScenarioFile(const std::string& path) {
  StatusOr<std::string> text = ReadConfigFile(path);
  if (!text.ok()) return text.status();
  StatusOr<std::vector<ConfigEntry>> entries = ParseConfigObject(path, *text);
  if (!entries.ok()) return entries.status();
  std::map<std::string, FieldValue> values;
  const ConfigEntry* map_entry = nullptr;
  for (const ConfigEntry& e : *entries) {
    if (e.key == "map") {
      if (!e.value.is_string() || e.value.get<std::string>().empty()) {
        return InvalidArgumentError(fmt::format(
            "{}:{}:{}: map = {}: must be the path of a map file (a non-empty string), found {}",
            path, e.line, e.column,
            e.value.is_string() ? QuoteForMessage(e.value.get<std::string>())
                                : QuoteForMessage(e.value.dump()),
            e.value.type_name()));
      }
      map_entry = &e;
      continue;
    }
    const FieldInfo* info = nullptr;
    for (const FieldInfo& k : ScenarioKeys()) {
      if (e.key == k.name) info = &k;
    }
    if (info == nullptr) {
      std::vector<std::string> known = {"map"};
      for (const FieldInfo& k : ScenarioKeys()) known.push_back(k.name);
      return UnknownKeyError(path, e, known);
    }
    StatusOr<FieldValue> v = FieldValueFromJson(path, *info, e);
    if (!v.ok()) return v.status();
    values[e.key] = *v;
  }
  for (const char* required : {"preset", "association"}) {
    if (values.count(required) == 0) {
      return InvalidArgumentError(
          fmt::format("{}:1:1: missing key \"{}\" (a scenario needs \"preset\": webmap, sim1, "
                      "sim2 or sim3, and \"association\": known or ml)",
                      path, required));
    }
  }
  MonteCarloScenarioSpec spec;
  spec.name = path;
  spec.preset = ScenarioKeys()[0].choices[std::get<int64_t>(values["preset"])];
  StatusOr<BaileySimOptions> preset = BaileyPreset(spec.preset);
  if (!preset.ok()) return preset.status();
  spec.sim = *preset;
  spec.association = std::get<int64_t>(values["association"]) == 0
                         ? FastSlamAssociation::kKnown
                         : FastSlamAssociation::kMaximumLikelihood;
  if (map_entry != nullptr) {
    std::filesystem::path map = map_entry->value.get<std::string>();
    if (map.is_relative()) map = std::filesystem::path(path).parent_path() / map;
    spec.map_path = map.string();
  } else {
    spec.map_bundle = "webmap";
  }
  auto real = [&](const char* key, double* field) {
    if (auto it = values.find(key); it != values.end()) *field = std::get<double>(it->second);
  };
  real("sigma_speed_mps", &spec.sim.sigma_speed_mps);
  real("sigma_steer_rad", &spec.sim.sigma_steer_rad);
  real("sigma_range_m", &spec.sim.sigma_range_m);
  real("sigma_bearing_rad", &spec.sim.sigma_bearing_rad);
  real("max_range_m", &spec.sim.max_range_m);
  if (auto it = values.find("loops"); it != values.end()) {
    spec.sim.loops = static_cast<int32_t>(std::get<int64_t>(it->second));
  }
  return spec;
}

// ---- One job ----

struct Group {
  FastSlamFilter filter;
  int64_t particles;
  std::string name;  // <filter>_p<particles>
  std::string config_digest;
  const PaperRow* paper;
};

struct Job {
  size_t group;
  int64_t run;
  uint64_t seed;
};

// The result-changing fields of the job's configuration, hashed.
std::string ConfigDigest(const FastSlamConfig& config) {
  json j = json::object();
  for (const ConfigField<FastSlamConfig>& f : FastSlamConfigFields()) {
    if (f.info.effect == kChangesResults) j[f.info.name] = FieldValueToJson(f.info, f.get(config));
  }
  return Hex16(Fnv1a(j.dump()));
}

std::string RunPath(const std::string& dir, const Group& g, int64_t run, const char* ext) {
  return fmt::format("{}/runs/{}/run_{}.{}", dir, g.name, run, ext);
}

struct ScanSample {
  double t_s;
  Pose2 mean;
  Pose2Covariance covariance;
};

// Runs one job and writes its CSV and JSON. Returns the status of the writes; the filter's own
// failure is recorded in the JSON.
Status RunMonteCarloJob(const MonteCarloScenario& scenario, const Group& group, const Job& job,
                        const std::string& dir) {
  BaileySimOptions sim_options = scenario.spec.sim;
  sim_options.seed = job.seed;
  Status status;
  std::vector<BaileyPose> truth;
  std::vector<StampedPose> trajectory;
  std::vector<ScanSample> scans;
  double cpu_s = kNaN;
  int64_t steps = 0;
  try {
    StatusOr<BaileySimulation> sim = SimulateBailey(scenario.map, sim_options);
    if (!sim.ok()) {
      status = sim.status();
    } else {
      truth = sim->truth;
      const FastSlamConfig config =
          MonteCarloJobConfig(scenario, group.filter, group.particles, job.seed);
      const double cpu0 = ThreadCpuSeconds();
      StatusOr<std::unique_ptr<FastSlam>> slam = FastSlam::Create(config);
      if (!slam.ok()) {
        status = slam.status();
      } else {
        FastSlam& f = **slam;
        status = FeedSimulation(*sim, &f, SIZE_MAX, nullptr, [&](double t) {
          scans.push_back({t, f.MeanPose(), f.PoseCovariance()});
        });
        cpu_s = ThreadCpuSeconds() - cpu0;
        steps = (*slam)->steps();
        trajectory = (*slam)->MeanTrajectory();
      }
    }
  } catch (const std::bad_alloc&) {
    status = ResourceExhaustedError("out of memory");
  } catch (const std::exception& e) {
    status = InternalError(fmt::format("internal error: {}", e.what()));
  }

  // The last mean pose at each truth time, and the NEES at each scan's truth row.
  const size_t rows = truth.size();
  std::vector<Pose2> estimate(rows);
  std::vector<uint8_t> has(rows, 0);
  size_t k = 0;
  for (const StampedPose& p : trajectory) {
    while (k < rows && truth[k].t_s < p.t_s) ++k;
    if (k == rows) break;
    if (truth[k].t_s == p.t_s) {
      estimate[k] = p.pose;
      has[k] = 1;
    }
  }
  std::vector<double> nees(rows, kNaN);
  std::vector<uint8_t> is_scan(rows, 0);
  k = 0;
  for (const ScanSample& s : scans) {
    while (k < rows && truth[k].t_s < s.t_s) ++k;
    if (k == rows) break;
    if (truth[k].t_s != s.t_s) continue;
    const BaileyPose& t = truth[k];
    is_scan[k] = 1;
    // The weighted covariance of fewer than 4 poses about their mean has rank < 3. The engine's
    // is taken about the circular mean heading, which differs from the weighted mean of the
    // heading differences by round-off and more, so it is only nearly singular then: undefined.
    if (group.particles < 4) continue;
    nees[k] = PoseNees(t.x_m - s.mean.x_m, t.y_m - s.mean.y_m,
                       WrapAngle(t.heading_rad - s.mean.heading_rad), s.covariance);
  }

  std::string csv;
  csv.reserve(rows * 120 + 128);
  csv += kRunCsvHeader;
  csv += '\n';
  std::vector<double> e2, h2, finite_nees;
  int64_t nees_scans = 0, nees_undefined = 0;
  double final_error = kNaN;
  for (size_t r = 0; r < rows; ++r) {
    const BaileyPose& t = truth[r];
    auto out = std::back_inserter(csv);
    fmt::format_to(out, "{}", t.t_s);
    if (has[r]) {
      const Pose2& p = estimate[r];
      const double d2 = (p.x_m - t.x_m) * (p.x_m - t.x_m) + (p.y_m - t.y_m) * (p.y_m - t.y_m);
      const double dh = WrapAngle(p.heading_rad - t.heading_rad);
      e2.push_back(d2);
      h2.push_back(dh * dh);
      final_error = std::sqrt(d2);
      fmt::format_to(out, ",{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.9g},{:.9g},", p.x_m, p.y_m,
                     p.heading_rad, t.x_m, t.y_m, t.heading_rad, d2, dh * dh);
    } else {
      fmt::format_to(out, ",,,,{:.6f},{:.6f},{:.6f},,,", t.x_m, t.y_m, t.heading_rad);
    }
    if (is_scan[r]) {
      ++nees_scans;
      if (std::isfinite(nees[r])) {
        finite_nees.push_back(nees[r]);
        fmt::format_to(out, "{:.9g}", nees[r]);
      } else {
        ++nees_undefined;
        csv += "nan";
      }
    }
    csv += '\n';
  }

  const bool ok = status.ok();
  json j = {{"filter", FastSlamFilterName(group.filter)},
            {"particles", group.particles},
            {"run", job.run},
            {"seed", job.seed},
            {"scenario", scenario.spec.name},
            {"scenario_digest", scenario.digest},
            {"config_digest", group.config_digest},
            {"status", ok ? std::string("ok") : status.message()},
            {"position_mse_mean", ok ? Mean(e2) : kNaN},
            {"position_mse_variance", ok ? PopulationVariance(e2) : kNaN},
            {"heading_mse_mean", ok ? Mean(h2) : kNaN},
            {"final_position_error_m", ok ? final_error : kNaN},
            {"nees_mean", ok ? Mean(finite_nees) : kNaN},
            {"nees_scans", nees_scans},
            {"nees_undefined", nees_undefined},
            {"cpu_s", cpu_s},
            {"filter_steps", steps},
            {"rows", rows},
            {"rows_evaluated", e2.size()},
            {"csv_bytes", csv.size()},
            {"csv_fnv1a", Hex16(Fnv1a(csv))}};
  // The CSV first: the JSON says the job is complete.
  GROVE_RETURN_IF_ERROR(WriteFileAtomically(RunPath(dir, group, job.run, "csv"), csv));
  return WriteFileAtomically(RunPath(dir, group, job.run, "json"), j.dump() + "\n");
}

// ---- Reading finished jobs ----

double JsonNumber(const json& j, const char* key) {
  auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : kNaN;
}

// The job's JSON, when it exists, parses and belongs to this job under this scenario and
// configuration, and its CSV has the recorded size and hash; otherwise an error saying why.
// `csv_text` (may be null) gets the CSV.
StatusOr<json> ReadFinishedJob(const std::string& dir, const MonteCarloScenario& scenario,
                               const Group& group, const Job& job,
                               std::string* csv_text = nullptr) {
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

struct RunSeries {
  std::vector<double> t, e2, h2, nees;  // NaN: no estimate at that row / no NEES
  std::vector<uint8_t> scan;
};

double ParseField(std::string_view field) {
  if (field.empty()) return kNaN;
  double v = kNaN;
  auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), v);
  return ec == std::errc() && end == field.data() + field.size() ? v : kNaN;
}

// The columns of a run's CSV (written by RunMonteCarloJob) that the aggregates need.
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

// ---- Aggregates ----

struct GroupResult {
  int64_t runs_ok = 0;
  int64_t runs_failed = 0;
  std::vector<std::string> failures;  // "run r: message"
  std::vector<double> mse_mean, mse_variance, heading_mse, nees_mean, cpu_s, ns_per_particle_step,
      final_error;
  int64_t nees_scans = 0, nees_undefined = 0;
  // Per truth row, over the successful runs.
  std::vector<double> t, e2_sum, h2_sum, nees_sum;
  std::vector<int64_t> e_count, nees_count;
  std::vector<uint8_t> scan;
  json runs = json::array();
  // Of the averaged NEES at scans with a finite value: how many lie inside the interval for the
  // runs averaged there.
  int64_t nees_points = 0, nees_inside = 0;

  void Add(const json& record, const RunSeries& series) {
    runs.push_back(record);
    if (record["status"] != "ok") {
      ++runs_failed;
      failures.push_back(fmt::format("run {}: {}", record["run"].get<int64_t>(),
                                     record["status"].get<std::string>()));
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

  void CountNeesInside() {
    std::map<int64_t, NeesInterval> intervals;
    for (size_t r = 0; r < t.size(); ++r) {
      if (!scan[r] || nees_count[r] == 0) continue;
      auto it = intervals.find(nees_count[r]);
      if (it == intervals.end()) {
        it = intervals.emplace(nees_count[r], AverageNeesInterval(kPoseDof, nees_count[r], kLevel))
                 .first;
      }
      const double mean = nees_sum[r] / static_cast<double>(nees_count[r]);
      ++nees_points;
      nees_inside += mean >= it->second.low && mean <= it->second.high;
    }
  }
};

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

// "1 run", "30 runs".
std::string RunsText(int64_t runs) { return fmt::format("{} run{}", runs, runs == 1 ? "" : "s"); }

// ---- Progress ----

// Jobs done out of the total, with an ETA from the jobs this invocation ran: one redrawn line on
// a terminal, otherwise a line at each new tenth. Thread safety: JobDone() may be called from
// any thread.
class JobProgress {
 public:
  JobProgress(int64_t total, int64_t reused, bool enabled)
      : total_(total),
        done_(reused),
        reused_(reused),
        enabled_(enabled && total > reused),
        terminal_(::isatty(::fileno(stderr)) == 1),
        start_(Clock::now()) {
    if (total_ > 0) next_tenth_ = done_ * 10 / total_ + 1;
  }

  void JobDone() {
    std::lock_guard<std::mutex> lock(mu_);
    ++done_;
    if (!enabled_) return;
    const double elapsed = Seconds();
    const int64_t ran = done_ - reused_;
    const double eta = static_cast<double>(total_ - done_) * elapsed / static_cast<double>(ran);
    const int64_t percent = done_ * 100 / total_;
    if (terminal_) {
      if (drawn_ && elapsed - last_s_ < 0.1 && done_ < total_) return;
      last_s_ = elapsed;
      drawn_ = true;
      std::string line = fmt::format("montecarlo: jobs {}/{} ({}%)  elapsed {}  ETA {}", done_,
                                     total_, percent, FormatClock(elapsed), FormatClock(eta));
      if (line.size() < width_) line.append(width_ - line.size(), ' ');
      width_ = line.size();
      std::fprintf(stderr, "\r%s", line.c_str());
      std::fflush(stderr);
      return;
    }
    const int64_t tenth = done_ * 10 / total_;
    if (tenth >= next_tenth_) {
      next_tenth_ = tenth + 1;
      std::fprintf(stderr, "montecarlo: jobs %lld/%lld (%lld%%), ETA %s\n",
                   static_cast<long long>(done_), static_cast<long long>(total_),
                   static_cast<long long>(percent), FormatDuration(eta).c_str());
    }
  }

  void Finish() {
    std::lock_guard<std::mutex> lock(mu_);
    if (drawn_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

  double Seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

 private:
  std::mutex mu_;
  const int64_t total_;
  int64_t done_;
  const int64_t reused_;
  const bool enabled_;
  const bool terminal_;
  const Clock::time_point start_;
  int64_t next_tenth_ = 1;
  double last_s_ = 0;
  size_t width_ = 0;
  bool drawn_ = false;
};

}  // namespace

// ---- Public ----

StatusOr<MonteCarloScenarioSpec> ParseMonteCarloScenario(const std::string& name, int64_t loops) {
  if (loops != 0 && (loops < 1 || loops > kMaxLoops)) {
    return InvalidArgumentError(fmt::format("--loops = {}: must be in 1..{}", loops, kMaxLoops));
  }
  MonteCarloScenarioSpec spec;
  if (name == "sim1" || name == "sim2" || name == "sim3") {
    spec.name = name;
    spec.preset = name;
    StatusOr<BaileySimOptions> preset = BaileyPreset(name);
    if (!preset.ok()) return preset.status();
    spec.sim = *preset;
    spec.map_bundle = name == "sim1" ? "webmap" : name;
    spec.association =
        name == "sim2" ? FastSlamAssociation::kMaximumLikelihood : FastSlamAssociation::kKnown;
  } else {
    std::error_code ec;
    const bool json_name = name.size() > 5 && name.compare(name.size() - 5, 5, ".json") == 0;
    if (name.empty() || (!json_name && !std::filesystem::exists(name, ec))) {
      return InvalidArgumentError(
          fmt::format("--scenario = {}: must be sim1, sim2, sim3 or a scenario file FILE.json",
                      QuoteForMessage(name)));
    }
    StatusOr<MonteCarloScenarioSpec> file = ParseScenarioFile(name);
    if (!file.ok()) return file.status();
    spec = std::move(*file);
  }
  if (loops != 0) spec.sim.loops = static_cast<int32_t>(loops);
  if (Status s = spec.sim.Validate(); !s.ok()) {
    return InvalidArgumentError(fmt::format("{}: {}", spec.name, s.message()));
  }
  return spec;
}

StatusOr<MonteCarloScenario> LoadMonteCarloScenario(const MonteCarloScenarioSpec& spec) {
  MonteCarloScenario scenario;
  scenario.spec = spec;
  StatusOr<BaileyMap> map = InternalError("no map");
  if (!spec.map_path.empty()) {
    scenario.map_name = spec.map_path;
    map = ReadBaileyMap(spec.map_path);
  } else if (spec.map_bundle == "sim2") {
    scenario.map_name = EmbeddedSim2MapName();
    map = ParseBaileyMap(scenario.map_name, EmbeddedSim2Map());
  } else if (spec.map_bundle == "sim3") {
    scenario.map_name = EmbeddedSim3MapName();
    map = ParseBaileyMap(scenario.map_name, EmbeddedSim3Map());
  } else {
    scenario.map_name = EmbeddedBaileyWebmapName();
    map = ParseBaileyMap(scenario.map_name, EmbeddedBaileyWebmap());
  }
  if (!map.ok()) return map.status();
  scenario.map = std::move(*map);
  BaileySimOptions o = spec.sim;
  o.seed = 0;  // per run
  std::string canonical = fmt::format("grove fastslam montecarlo scenario 1\nassociation {}\n{}\n",
                                      AssociationName(spec.association), SimOptionsJson(o).dump());
  for (const BaileyPoint& p : scenario.map.landmarks) {
    canonical += fmt::format("lm {} {}\n", p.x_m, p.y_m);
  }
  for (const BaileyPoint& p : scenario.map.waypoints) {
    canonical += fmt::format("wp {} {}\n", p.x_m, p.y_m);
  }
  scenario.digest = Hex16(Fnv1a(canonical));
  return scenario;
}

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

int FastSlamMonteCarloCommand(const MonteCarloOptions& options) {
  const auto wall_start = Clock::now();
  // ---- Options ----
  if (options.runs < 1 || options.runs > kMaxRuns) {
    return Fail(kExitUsage, fmt::format("--runs = {}: must be in 1..{}", options.runs, kMaxRuns));
  }
  if (options.threads < 0 || options.threads > kMaxThreads) {
    return Fail(kExitUsage,
                fmt::format("--threads = {}: must be in 0..{} (0: every hardware thread)",
                            options.threads, kMaxThreads));
  }
  if (options.out_dir.empty()) return Fail(kExitUsage, "--out: the path is empty");
  const FieldInfo seed_info{"--seed", "", FieldType::kUnsigned, kChangesResults, 0, 0, {}, {}};
  StatusOr<FieldValue> seed_value = ParseFieldValue(seed_info, options.seed);
  if (!seed_value.ok()) return Fail(kExitUsage, seed_value.status().message());
  const uint64_t seed = std::get<uint64_t>(*seed_value);
  StatusOr<std::vector<FastSlamFilter>> filters = ParseFilters(options.filters);
  if (!filters.ok()) return Fail(kExitUsage, filters.status().message());
  std::vector<int64_t> particle_list;
  if (!options.particles.empty()) {
    StatusOr<std::vector<int64_t>> p = ParseParticles(options.particles);
    if (!p.ok()) return Fail(kExitUsage, p.status().message());
    particle_list = std::move(*p);
  }
  StatusOr<MonteCarloScenarioSpec> spec = ParseMonteCarloScenario(options.scenario, options.loops);
  if (!spec.ok()) {
    const StatusCode c = spec.status().code();
    return Fail(c == StatusCode::kNotFound || c == StatusCode::kIoError ? kExitInput : kExitUsage,
                spec.status().message());
  }
  StatusOr<MonteCarloScenario> loaded = LoadMonteCarloScenario(*spec);
  if (!loaded.ok()) return Fail(kExitInput, loaded.status().message());
  const MonteCarloScenario& scenario = *loaded;
  // The truth does not depend on the seed; run 0's simulation checks that the vehicle reaches
  // its waypoints and gives the sizes for the report.
  int64_t control_steps = 0;
  size_t scans = 0;
  {
    BaileySimOptions first = scenario.spec.sim;
    first.seed = seed;
    StatusOr<BaileySimulation> probe = SimulateBailey(scenario.map, first);
    if (!probe.ok()) {
      return Fail(kExitInput, fmt::format("{}: {}: {}", scenario.spec.name, scenario.map_name,
                                          probe.status().message()));
    }
    control_steps = probe->control_steps();
    scans = probe->scan_times_s.size();
  }

  // ---- Groups and jobs ----
  std::vector<Group> groups;
  for (FastSlamFilter filter : *filters) {
    std::vector<int64_t> counts = particle_list;
    if (counts.empty()) counts = {PaperParticles(scenario.spec.preset, filter)};
    for (int64_t n : counts) {
      Group g{filter, n, fmt::format("{}_p{}", FastSlamFilterName(filter), n), "",
              FindPaperRow(scenario.spec.name, filter, n)};
      const FastSlamConfig config = MonteCarloJobConfig(scenario, filter, n, seed);
      if (Status s = config.Validate(); !s.ok()) {
        return Fail(kExitUsage, fmt::format("{} with {} particles: {}", FastSlamFilterName(filter),
                                            n, s.message()));
      }
      FastSlamConfig digest_config = config;
      digest_config.seed = 0;  // per run, recorded apart
      g.config_digest = ConfigDigest(digest_config);
      groups.push_back(std::move(g));
    }
  }
  std::vector<Job> jobs;
  for (size_t g = 0; g < groups.size(); ++g) {
    for (int64_t r = 0; r < options.runs; ++r) {
      jobs.push_back({g, r, seed + static_cast<uint64_t>(r)});
    }
  }

  // ---- Output directory: rank 0 makes and locks it while the others wait ----
  const int ranks = options.all_gather ? std::max(1, options.ranks) : 1;
  const size_t rank = static_cast<size_t>(ranks > 1 ? options.rank : 0);
  // Every rank's exit code (0: ok) after a step that may fail on some rank: the largest, so
  // that every rank stops when one does and none waits for it.
  auto agree = [&](int code) {
    if (ranks == 1) return code;
    int worst = 0;
    for (const std::string& c : options.all_gather(std::to_string(code))) {
      worst = std::max(worst, std::stoi(c));
    }
    return worst;
  };
  std::optional<OutputDirectory> out;
  const std::string& dir = options.out_dir;
  int code = kExitOk;
  if (rank == 0) {
    StatusOr<OutputDirectory> opened = OutputDirectory::Open(options.out_dir);
    if (!opened.ok()) {
      code = Fail(opened.status().code() == StatusCode::kInvalidArgument ? kExitUsage : kExitOutput,
                  opened.status().message());
    } else {
      out.emplace(std::move(opened).value());
      for (const Group& g : groups) {
        if (Status s = EnsureDirectory(dir + "/runs/" + g.name); !s.ok() && code == kExitOk) {
          code = Fail(kExitOutput, s.message());
        }
      }
      if (code == kExitOk) out->Keep();
    }
  }
  if (const int agreed = agree(code); agreed != kExitOk) return agreed;

  // ---- Jobs ----
  // This rank's jobs: every ranks-th from its own.
  std::vector<size_t> todo;
  int64_t own_jobs = 0;
  for (size_t i = rank; i < jobs.size(); i += static_cast<size_t>(ranks)) {
    ++own_jobs;
    if (!ReadFinishedJob(dir, scenario, groups[jobs[i].group], jobs[i]).ok()) todo.push_back(i);
  }
  const int64_t reused = own_jobs - static_cast<int64_t>(todo.size());
  // The costliest first (most particles), so that the last jobs to start are short; ties in job
  // order (std::sort with the index as tie-break: libstdc++ 12's stable_sort trips clang's
  // deprecation warning).
  std::sort(todo.begin(), todo.end(), [&](size_t a, size_t b) {
    const int64_t pa = groups[jobs[a].group].particles, pb = groups[jobs[b].group].particles;
    return pa != pb ? pa > pb : a < b;
  });
  const int hardware = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int threads = options.threads == 0 ? hardware : static_cast<int>(options.threads);
  const int threads_used =
      static_cast<int>(std::max<size_t>(1, std::min<size_t>(threads, todo.size())));
  std::fprintf(
      stderr,
      "montecarlo: %s (%s, %s association, %d loops: %lld control steps, %zu scans), "
      "%zu filter/particle groups x %s = %zu jobs; %lld reused from an earlier "
      "invocation, %zu to run%s\n",
      scenario.spec.name.c_str(), scenario.map_name.c_str(),
      AssociationName(scenario.spec.association), scenario.spec.sim.loops,
      static_cast<long long>(control_steps), scans, groups.size(), RunsText(options.runs).c_str(),
      jobs.size(), static_cast<long long>(reused), todo.size(),
      todo.empty()
          ? ""
          : fmt::format(" on {} thread{}", threads_used, threads_used == 1 ? "" : "s").c_str());

  if (ranks > 1) {
    std::fprintf(stderr, "montecarlo: rank %zu of %d runs %lld of the %zu jobs\n", rank, ranks,
                 static_cast<long long>(own_jobs), jobs.size());
  }
  JobProgress progress(own_jobs, reused, options.progress);
  std::atomic<size_t> next{0};
  std::atomic<bool> stop{false};
  std::mutex error_mu;
  Status write_error;
  auto worker = [&] {
    for (;;) {
      // Relaxed: the counter only hands out distinct indices; the task group's wait publishes
      // the results.
      const size_t i = next.fetch_add(1, std::memory_order_relaxed);
      if (i >= todo.size() || stop.load(std::memory_order_relaxed)) return;
      const Job& job = jobs[todo[i]];
      Status s = RunMonteCarloJob(scenario, groups[job.group], job, dir);
      if (!s.ok()) {
        std::lock_guard<std::mutex> lock(error_mu);
        if (write_error.ok()) write_error = s;
        stop.store(true, std::memory_order_relaxed);
        return;
      }
      progress.JobDone();
    }
  };
  if (!todo.empty()) {
    tbb::task_arena arena(threads_used);
    arena.execute([&] {
      tbb::task_group tasks;
      for (int t = 0; t < threads_used; ++t) tasks.run(worker);
      tasks.wait();
    });
  }
  progress.Finish();
  if (!write_error.ok()) code = Fail(kExitOutput, write_error.message());
  // Every rank's jobs are on disk once all have come here; rank 0 writes the aggregates.
  if (const int agreed = agree(code); agreed != kExitOk || rank != 0) return agreed;

  // ---- Aggregates, from the files (the same numbers whether a job ran now or before) ----
  std::vector<GroupResult> results(groups.size());
  for (const Job& job : jobs) {
    const Group& g = groups[job.group];
    std::string csv;
    StatusOr<json> record = ReadFinishedJob(dir, scenario, g, job, &csv);
    if (!record.ok()) return Fail(kExitOutput, record.status().message());
    StatusOr<RunSeries> series = ParseRunSeries(RunPath(dir, g, job.run, "csv"), csv);
    if (!series.ok()) return Fail(kExitOutput, series.status().message());
    results[job.group].Add(*record, *series);
  }
  const NeesInterval interval = AverageNeesInterval(kPoseDof, options.runs, kLevel);

  const std::vector<std::string> csv_header = {"filter",
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
  std::vector<std::vector<std::string>> csv_rows, md_rows;
  json group_json = json::array();
  for (size_t gi = 0; gi < groups.size(); ++gi) {
    const Group& g = groups[gi];
    GroupResult& r = results[gi];
    r.CountNeesInside();
    const ConfidenceInterval mse = StudentTInterval(r.mse_mean, kLevel);
    const ConfidenceInterval var = StudentTInterval(r.mse_variance, kLevel);
    const ConfidenceInterval heading = StudentTInterval(r.heading_mse, kLevel);
    const double nees = Mean(r.nees_mean);
    const double inside =
        r.nees_points > 0 ? static_cast<double>(r.nees_inside) / static_cast<double>(r.nees_points)
                          : kNaN;
    const double cpu = Mean(r.cpu_s);
    const double ns = Mean(r.ns_per_particle_step);
    const PaperRow* paper = g.paper;
    csv_rows.push_back({FastSlamFilterName(g.filter),
                        std::to_string(g.particles),
                        std::to_string(r.runs_ok),
                        std::to_string(r.runs_failed),
                        CsvNumber(mse.mean),
                        CsvNumber(mse.low),
                        CsvNumber(mse.high),
                        CsvNumber(var.mean),
                        CsvNumber(var.low),
                        CsvNumber(var.high),
                        CsvNumber(heading.mean),
                        CsvNumber(heading.low),
                        CsvNumber(heading.high),
                        CsvNumber(nees),
                        std::to_string(r.nees_undefined),
                        std::to_string(r.nees_scans),
                        CsvNumber(inside),
                        CsvNumber(cpu),
                        CsvNumber(ns),
                        paper ? CsvNumber(paper->position_mse_mean) : "",
                        paper ? CsvNumber(paper->position_mse_variance) : "",
                        paper ? CsvNumber(paper->heading_mse) : ""});
    md_rows.push_back(
        {FastSlamFilterName(g.filter), std::to_string(g.particles),
         r.runs_failed == 0 ? std::to_string(r.runs_ok)
                            : fmt::format("{} ({} failed)", r.runs_ok, r.runs_failed),
         MdInterval(mse), MdInterval(var), MdInterval(heading),
         r.nees_undefined == 0 ? MdNumber(nees)
                               : fmt::format("{} ({} of {} scans undefined)", MdNumber(nees),
                                             r.nees_undefined, r.nees_scans),
         r.nees_points > 0 ? fmt::format("{:.0f} %", 100 * inside) : "n/a", MdNumber(cpu, "{:.3g}"),
         MdNumber(ns, "{:.0f}"),
         paper ? fmt::format("{} / {} / {} ({})", paper->position_mse_mean,
                             paper->position_mse_variance, paper->heading_mse, paper->table)
               : ""});
    json gj = {{"filter", FastSlamFilterName(g.filter)},
               {"particles", g.particles},
               {"directory", "runs/" + g.name},
               {"config_digest", g.config_digest},
               {"runs_ok", r.runs_ok},
               {"runs_failed", r.runs_failed},
               {"failures", r.failures},
               {"position_mse_mean", IntervalJson(mse)},
               {"position_mse_variance", IntervalJson(var)},
               {"heading_mse_mean", IntervalJson(heading)},
               {"final_position_error_m_mean", Mean(r.final_error)},
               {"nees_mean", nees},
               {"nees_scans", r.nees_scans},
               {"nees_undefined", r.nees_undefined},
               {"nees_in_interval_fraction", inside},
               {"cpu_s_mean", cpu},
               {"ns_per_particle_step", ns},
               {"runs", r.runs}};
    gj["paper"] = paper ? json{{"table", paper->table},
                               {"position_mse_mean", paper->position_mse_mean},
                               {"position_mse_variance", paper->position_mse_variance},
                               {"heading_mse", paper->heading_mse}}
                        : json(nullptr);
    group_json.push_back(std::move(gj));
  }
  const bool any_paper =
      std::any_of(groups.begin(), groups.end(), [](const Group& g) { return g.paper != nullptr; });
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
  if (any_paper) {
    md_header.push_back("seed paper: MSE mean / variance / heading");
  } else {
    for (auto& row : md_rows) row.pop_back();
  }
  const std::string md = fmt::format(
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
      RunsText(options.runs), seed, interval.low, interval.high, RunsText(options.runs),
      MarkdownTable(md_header, md_rows));

  Status s = WriteFileAtomically(dir + "/table.csv", CsvTable(csv_header, csv_rows));
  if (s.ok()) s = WriteFileAtomically(dir + "/table.md", md);
  if (!s.ok()) return Fail(kExitOutput, s.message());

  // ---- Charts ----
  std::vector<std::string> charts;
  if (options.charts) {
    const std::string runs_text = RunsText(options.runs);
    Chart mse_position{.title = fmt::format("{}: position MSE over {} (seed Fig. 3a / 6a)",
                                            scenario.spec.name, runs_text),
                       .x_label = "time (s)",
                       .y_label = "mean squared position error (m²)"};
    Chart mse_heading{.title = fmt::format("{}: heading MSE over {} (seed Fig. 3b / 6b)",
                                           scenario.spec.name, runs_text),
                      .x_label = "time (s)",
                      .y_label = "mean squared heading error (rad²)"};
    Chart boxes{
        .title = fmt::format("{}: position MSE of each run, by filter and particles (seed Fig. 4)",
                             scenario.spec.name),
        .y_label = "run's mean squared position error (m²)"};
    Chart nees_chart{.title = fmt::format("{}: pose NEES averaged over {} (seed Fig. 8)",
                                          scenario.spec.name, runs_text),
                     .x_label = "time (s)",
                     .y_label = "average NEES (log scale)",
                     .log_y = true};
    double t_first = INFINITY, t_last = -INFINITY;
    for (size_t gi = 0; gi < groups.size(); ++gi) {
      const GroupResult& r = results[gi];
      const std::string label =
          fmt::format("{}, {} particle{}", FastSlamFilterName(groups[gi].filter),
                      groups[gi].particles, groups[gi].particles == 1 ? "" : "s");
      mse_position.series.push_back(RowSeries(label, r, r.e2_sum));
      mse_heading.series.push_back(RowSeries(label, r, r.h2_sum));
      boxes.boxes.push_back({.label = fmt::format("{}, {}", FastSlamFilterName(groups[gi].filter),
                                                  groups[gi].particles),
                             .values = r.mse_mean});
      // The line breaks (a NaN) at a scan without a finite NEES and where scans stop for a
      // while (no landmark in view).
      ChartSeries ns{.label = label, .style = ChartStyle::kLine};
      double last_scan_t = -INFINITY;
      for (size_t row = 0; row < r.t.size(); ++row) {
        if (!r.scan[row]) continue;
        if (r.t[row] - last_scan_t > 1.5 * scenario.spec.sim.dt_observe_s && !ns.x.empty()) {
          ns.x.push_back(r.t[row]);
          ns.y.push_back(kNaN);
        }
        last_scan_t = r.t[row];
        ns.x.push_back(r.t[row]);
        ns.y.push_back(r.nees_count[row] == 0
                           ? kNaN
                           : r.nees_sum[row] / static_cast<double>(r.nees_count[row]));
        if (r.nees_count[row] == 0) continue;
        t_first = std::min(t_first, r.t[row]);
        t_last = std::max(t_last, r.t[row]);
      }
      nees_chart.series.push_back(std::move(ns));
    }
    if (t_first <= t_last) {
      nees_chart.series.push_back(
          {.label = fmt::format("95 % interval, {}: upper {:.2f}", runs_text, interval.high),
           .x = {t_first, t_last},
           .y = {interval.high, interval.high},
           .style = ChartStyle::kDashed});
      nees_chart.series.push_back(
          {.label = fmt::format("95 % interval, {}: lower {:.2f}", runs_text, interval.low),
           .x = {t_first, t_last},
           .y = {interval.low, interval.low},
           .style = ChartStyle::kDashed});
    }
    std::vector<std::pair<std::string, const Chart*>> to_draw = {{"mse_position", &mse_position},
                                                                 {"mse_heading", &mse_heading},
                                                                 {"boxplot_position", &boxes},
                                                                 {"nees", &nees_chart}};
    Chart accuracy{
        .title = fmt::format("{}: accuracy against CPU time ({})", scenario.spec.name, runs_text),
        .x_label = "CPU seconds per run (log scale)",
        .y_label = "position MSE mean (m², log scale)",
        .log_x = true,
        .log_y = true};
    if (particle_list.size() > 1) {
      std::string all_counts;
      for (int64_t n : particle_list) {
        all_counts += (all_counts.empty() ? "" : ", ") + std::to_string(n);
      }
      // The counts go into the title, not the legend, so that the plot keeps its width.
      accuracy.title = fmt::format("{}: accuracy against CPU time ({})\neach line: {} particles",
                                   scenario.spec.name, runs_text, all_counts);
      for (FastSlamFilter filter : *filters) {
        std::vector<std::pair<int64_t, size_t>> points;
        for (size_t gi = 0; gi < groups.size(); ++gi) {
          if (groups[gi].filter == filter) points.push_back({groups[gi].particles, gi});
        }
        std::sort(points.begin(), points.end());
        ChartSeries series{.label = FastSlamFilterName(filter), .style = ChartStyle::kLinePoints};
        for (const auto& [n, gi] : points) {
          series.x.push_back(Mean(results[gi].cpu_s));
          series.y.push_back(Mean(results[gi].mse_mean));
        }
        accuracy.series.push_back(std::move(series));
      }
      to_draw.push_back({"accuracy_vs_cpu", &accuracy});
    }
    for (const auto& [name, chart] : to_draw) {
      s = WriteChart(*chart, dir + "/" + name + ".png", dir + "/" + name + ".svg");
      if (!s.ok()) return Fail(kExitOutput, s.message());
      charts.push_back(name);
    }
  }

  const double wall_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
  json summary = {{"command", "grove fastslam montecarlo"},
                  {"scenario",
                   {{"name", scenario.spec.name},
                    {"preset", scenario.spec.preset},
                    {"map", scenario.map_name},
                    {"association", AssociationName(scenario.spec.association)},
                    {"digest", scenario.digest},
                    {"simulator", SimOptionsJson(scenario.spec.sim)}}},
                  {"runs", options.runs},
                  {"seed", seed},
                  {"threads_requested", options.threads},
                  {"threads_used", threads_used},
                  {"jobs", jobs.size()},
                  {"jobs_reused", reused},
                  {"jobs_run", todo.size()},
                  {"wall_s", wall_s},
                  {"nees_interval",
                   {{"dof", kPoseDof},
                    {"runs", options.runs},
                    {"level", kLevel},
                    {"low", interval.low},
                    {"high", interval.high}}},
                  {"groups", group_json},
                  {"tables", {"table.md", "table.csv"}},
                  {"charts", charts},
                  {"grove", VersionJson()}};
  s = WriteFileAtomically(dir + "/summary.json", summary.dump(2) + "\n");
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::printf("%s", md.c_str());
  std::fprintf(stderr, "montecarlo: %zu jobs (%zu run, %lld reused) in %s; wrote %s/table.md\n",
               jobs.size(), todo.size(), static_cast<long long>(reused),
               FormatDuration(wall_s).c_str(), dir.c_str());
  return kExitOk;
}

}  // namespace grove::tools

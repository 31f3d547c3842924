#include "tools/montecarlo/fastslam_montecarlo.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>
#include <utility>
#include <variant>

#include "grove/config_fields.h"
#include "grove/version.h"
#include "tools/io/atomic_file.h"
#include "tools/io/output_set.h"
#include "tools/montecarlo/group_result.h"
#include "tools/montecarlo/job_progress.h"
#include "tools/montecarlo/job_runner.h"
#include "tools/montecarlo/mc_statistics.h"
#include "tools/montecarlo/result_charts.h"
#include "tools/montecarlo/result_tables.h"
#include "tools/run/memory_budget.h"
#include "tools/run/progress_reporter.h"
#include "tools/run/run_loop.h"
#include "tools/run/signal_policy.h"

namespace grove::tools {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

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
        n > kMonteCarloMaxParticles) {
      return InvalidArgumentError(fmt::format("--particles = {}: {} must be an integer in 1..{}",
                                              QuoteForMessage(text), QuoteForMessage(item),
                                              kMonteCarloMaxParticles));
    }
    if (std::find(counts.begin(), counts.end(), n) != counts.end()) {
      return InvalidArgumentError(
          fmt::format("--particles = {}: {} is given twice", QuoteForMessage(text), n));
    }
    counts.push_back(n);
  }
  return counts;
}

// The options checked and parsed.
struct MonteCarloRequest {
  uint64_t seed = 0;
  std::vector<FastSlamFilter> filters;
  std::vector<int64_t> particles;  // empty: the seed's per scenario and filter
};

// Checks every option but the scenario. Returns -1 to go on, or the exit code after printing
// the error.
int ReadRequest(const MonteCarloOptions& options, MonteCarloRequest* request) {
  if (options.runs < 1 || options.runs > kMonteCarloMaxRuns) {
    return Fail(kExitUsage,
                fmt::format("--runs = {}: must be in 1..{}", options.runs, kMonteCarloMaxRuns));
  }
  if (options.threads < 0 || options.threads > kMonteCarloMaxThreads) {
    return Fail(kExitUsage,
                fmt::format("--threads = {}: must be in 0..{} (0: every hardware thread)",
                            options.threads, kMonteCarloMaxThreads));
  }
  if (options.out_dir.empty()) return Fail(kExitUsage, "--out: the path is empty");
  const FieldInfo seed_info{"--seed", "", FieldType::kUnsigned, kChangesResults, 0, 0, {}, {}};
  StatusOr<FieldValue> seed_value = ParseFieldValue(seed_info, options.seed);
  if (!seed_value.ok()) return Fail(kExitUsage, seed_value.status().message());
  request->seed = std::get<uint64_t>(*seed_value);
  const uint64_t last_run = static_cast<uint64_t>(options.runs - 1);
  if (request->seed > std::numeric_limits<uint64_t>::max() - last_run) {
    return Fail(kExitUsage,
                fmt::format("--seed = {} with --runs = {}: run r uses seed + r, so seed + runs - 1 "
                            "must be at most {}",
                            request->seed, options.runs, std::numeric_limits<uint64_t>::max()));
  }
  StatusOr<std::vector<FastSlamFilter>> filters = ParseFilters(options.filters);
  if (!filters.ok()) return Fail(kExitUsage, filters.status().message());
  request->filters = std::move(*filters);
  if (!options.particles.empty()) {
    StatusOr<std::vector<int64_t>> p = ParseParticles(options.particles);
    if (!p.ok()) return Fail(kExitUsage, p.status().message());
    request->particles = std::move(*p);
  }
  return -1;
}

// The scenario, and the sizes of its runs for the report.
struct LoadedScenario {
  MonteCarloScenario scenario;
  int64_t control_steps = 0;
  size_t scans = 0;
  size_t observations = 0;
};

// Reads the scenario and simulates run 0. The truth does not depend on the seed; run 0's
// simulation checks that the vehicle reaches its waypoints and gives the sizes. Returns -1 to
// go on, or the exit code after printing the error.
int LoadScenario(const MonteCarloOptions& options, uint64_t seed, LoadedScenario* out) {
  StatusOr<MonteCarloScenarioSpec> spec = ParseMonteCarloScenario(options.scenario, options.loops);
  if (!spec.ok()) {
    const StatusCode c = spec.status().code();
    return Fail(c == StatusCode::kNotFound || c == StatusCode::kIoError ? kExitInput : kExitUsage,
                spec.status().message());
  }
  StatusOr<MonteCarloScenario> loaded = LoadMonteCarloScenario(*spec);
  if (!loaded.ok()) return Fail(kExitInput, loaded.status().message());
  out->scenario = std::move(*loaded);
  const MonteCarloScenario& scenario = out->scenario;
  BaileySimOptions first = scenario.spec.sim;
  first.seed = seed;
  StatusOr<BaileySimulation> probe = SimulateBailey(scenario.map, first);
  if (!probe.ok()) {
    return Fail(kExitInput, fmt::format("{}: {}: {}", scenario.spec.name, scenario.map_name,
                                        probe.status().message()));
  }
  out->control_steps = probe->control_steps();
  out->scans = probe->scan_times_s.size();
  out->observations = probe->observations.size();
  return -1;
}

// Per job beyond its engine, a bound per control row: the simulation (true and noisy controls,
// truth, observations), the outcome's trajectory, truth and scan samples, and the CSV text.
constexpr int64_t kJobBytesPerControl = 640;

// The peak memory of the jobs `todo` when `threads` run side by side, the costliest first (as
// RunMonteCarloJobs starts them): the process's fixed part once, and the rest of the `threads`
// largest predictions.
int64_t PredictJobsBytes(const LoadedScenario& loaded, const MonteCarloPlan& plan,
                         const std::vector<size_t>& todo, int threads) {
  FastSlamWorkload work;
  work.controls = loaded.control_steps + 1;
  work.scans = static_cast<int64_t>(loaded.scans);
  work.observations = static_cast<int64_t>(loaded.observations);
  std::vector<int64_t> jobs;
  for (size_t i : todo) {
    const MonteCarloJob& job = plan.jobs[i];
    const MonteCarloGroup& g = plan.groups[job.group];
    const FastSlamConfig config =
        MonteCarloJobConfig(loaded.scenario, g.filter, g.particles, job.seed);
    jobs.push_back(FastSlam::EstimatePeakBytes(config, work) - kProcessBaselineBytes +
                   kJobBytesPerControl * work.controls);
  }
  std::sort(jobs.begin(), jobs.end(), std::greater<>());
  int64_t total = kProcessBaselineBytes;
  for (size_t k = 0; k < jobs.size() && k < static_cast<size_t>(threads); ++k) {
    total = total > INT64_MAX - jobs[k] ? INT64_MAX : total + jobs[k];
  }
  return total;
}

// The MPI ranks the jobs are shared among (one without all_gather).
class RankGroup {
 public:
  explicit RankGroup(const MonteCarloOptions& options)
      : options_(options),
        ranks_(options.all_gather ? std::max(1, options.ranks) : 1),
        rank_(static_cast<size_t>(ranks_ > 1 ? options.rank : 0)) {}

  int ranks() const { return ranks_; }
  size_t rank() const { return rank_; }

  // Every rank's exit code (0: ok) after a step that may fail on some rank: the largest, so
  // that every rank stops when one does and none waits for it. Collective.
  int Agree(int code) const {
    if (ranks_ == 1) return code;
    int worst = 0;
    for (const std::string& c : options_.all_gather(std::to_string(code))) {
      worst = std::max(worst, std::stoi(c));
    }
    return worst;
  }

 private:
  const MonteCarloOptions& options_;
  const int ranks_;
  const size_t rank_;
};

// Opens (and locks) the output directory with a runs/<group> directory per group. Returns 0 or
// the exit code after printing the error.
int OpenOutput(const std::string& dir, const MonteCarloPlan& plan,
               std::optional<OutputDirectory>* out) {
  StatusOr<OutputDirectory> opened = OutputDirectory::Open(dir);
  if (!opened.ok()) {
    return Fail(opened.status().code() == StatusCode::kInvalidArgument ? kExitUsage : kExitOutput,
                opened.status().message());
  }
  out->emplace(std::move(opened).value());
  int code = kExitOk;
  for (const MonteCarloGroup& g : plan.groups) {
    if (Status s = EnsureDirectory(dir + "/runs/" + g.name); !s.ok() && code == kExitOk) {
      code = Fail(kExitOutput, s.message());
    }
  }
  if (code == kExitOk) (*out)->Keep();
  return code;
}

// What this invocation did with the jobs.
struct JobCounts {
  int64_t reused = 0;  // of this rank's jobs, finished by an earlier invocation
  size_t ran = 0;
  int threads_used = 1;
};

void PrintPlan(const LoadedScenario& loaded, const MonteCarloPlan& plan, int64_t runs,
               const JobCounts& counts) {
  const MonteCarloScenario& scenario = loaded.scenario;
  std::fprintf(
      stderr,
      "montecarlo: %s (%s, %s association, %d loops: %lld control steps, %zu scans), "
      "%zu filter/particle groups x %s = %zu jobs; %lld reused from an earlier "
      "invocation, %zu to run%s\n",
      scenario.spec.name.c_str(), scenario.map_name.c_str(),
      AssociationName(scenario.spec.association), scenario.spec.sim.loops,
      static_cast<long long>(loaded.control_steps), loaded.scans, plan.groups.size(),
      RunsText(runs).c_str(), plan.jobs.size(), static_cast<long long>(counts.reused), counts.ran,
      counts.ran == 0
          ? ""
          : fmt::format(" on {} thread{}", counts.threads_used, counts.threads_used == 1 ? "" : "s")
                .c_str());
}

json SummaryJson(const MonteCarloOptions& options, const MonteCarloScenario& scenario,
                 const MonteCarloPlan& plan, uint64_t seed, const JobCounts& counts,
                 const NeesInterval& interval, json groups, const std::vector<std::string>& charts,
                 double wall_s) {
  return {{"command", "grove fastslam montecarlo"},
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
          {"threads_used", counts.threads_used},
          {"jobs", plan.jobs.size()},
          {"jobs_reused", counts.reused},
          {"jobs_run", counts.ran},
          {"wall_s", wall_s},
          {"nees_interval",
           {{"dof", kPoseDof},
            {"runs", options.runs},
            {"level", kMonteCarloLevel},
            {"low", interval.low},
            {"high", interval.high}}},
          {"groups", std::move(groups)},
          {"tables", {"table.md", "table.csv"}},
          {"charts", charts},
          {"grove", VersionJson()}};
}

// kExitOk when every job succeeded; otherwise prints how many failed, with the first failure,
// and returns kExitMemory when one ran out of memory, else kExitRun.
int FailedJobsExit(const MonteCarloPlan& plan, const std::vector<GroupResult>& results) {
  int64_t failed = 0, out_of_memory = 0;
  std::string first;
  for (size_t g = 0; g < results.size(); ++g) {
    failed += results[g].runs_failed;
    out_of_memory += results[g].out_of_memory;
    if (first.empty() && !results[g].failures.empty()) {
      first = plan.groups[g].name + " " + results[g].failures.front();
    }
  }
  if (failed == 0) return kExitOk;
  return Fail(out_of_memory > 0 ? kExitMemory : kExitRun,
              fmt::format("{} of {} jobs failed (first: {}); the tables count them as failed "
                          "runs; run the same command again to run them again",
                          failed, plan.jobs.size(), first));
}

// Once every job is done: the aggregates from the files, the tables, the charts and
// summary.json; table.md also to stdout. Returns the exit code.
int WriteResults(const MonteCarloOptions& options, const MonteCarloRequest& request,
                 const MonteCarloScenario& scenario, const MonteCarloPlan& plan,
                 const JobCounts& counts, Clock::time_point wall_start) {
  const std::string& dir = options.out_dir;
  StatusOr<std::vector<GroupResult>> results = ReadGroupResults(dir, scenario, plan);
  if (!results.ok()) return Fail(kExitOutput, results.status().message());
  const NeesInterval interval = AverageNeesInterval(kPoseDof, options.runs, kMonteCarloLevel);
  MonteCarloTables tables =
      MakeMonteCarloTables(scenario, plan, *results, options.runs, request.seed, interval);
  Status s = WriteFileAtomically(dir + "/table.csv", tables.csv);
  if (s.ok()) s = WriteFileAtomically(dir + "/table.md", tables.md);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::vector<std::string> charts;
  if (options.charts) {
    s = WriteMonteCarloCharts(
        {scenario, plan, *results, request.filters, request.particles, options.runs, interval}, dir,
        &charts);
    if (!s.ok()) return Fail(kExitOutput, s.message());
  }
  const double wall_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
  const json summary = SummaryJson(options, scenario, plan, request.seed, counts, interval,
                                   std::move(tables.groups), charts, wall_s);
  s = WriteFileAtomically(dir + "/summary.json", summary.dump(2) + "\n");
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::printf("%s", tables.md.c_str());
  std::fflush(stdout);  // while SIGPIPE is ignored: a closed stdout must not kill the command
  std::fprintf(stderr, "montecarlo: %zu jobs (%zu run, %lld reused) in %s; wrote %s/table.md\n",
               plan.jobs.size(), counts.ran, static_cast<long long>(counts.reused),
               FormatDuration(wall_s).c_str(), dir.c_str());
  return FailedJobsExit(plan, *results);
}

}  // namespace

int FastSlamMonteCarloCommand(const MonteCarloOptions& options) {
  const auto wall_start = Clock::now();
  const SignalHandlers signals;
  MonteCarloRequest request;
  if (const int code = ReadRequest(options, &request); code >= 0) return code;
  LoadedScenario loaded;
  if (const int code = LoadScenario(options, request.seed, &loaded); code >= 0) return code;
  const MonteCarloScenario& scenario = loaded.scenario;
  StatusOr<MonteCarloPlan> plan =
      MakeMonteCarloPlan(scenario, request.filters, request.particles, options.runs, request.seed);
  if (!plan.ok()) return Fail(kExitUsage, plan.status().message());

  const RankGroup ranks(options);
  JobCounts counts;
  int64_t own_jobs = 0;
  const std::vector<size_t> todo =
      JobsToRun(options.out_dir, scenario, *plan, ranks.rank(), ranks.ranks(), &own_jobs);
  counts.reused = own_jobs - static_cast<int64_t>(todo.size());
  counts.ran = todo.size();
  const int hardware = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int threads = options.threads == 0 ? hardware : static_cast<int>(options.threads);
  counts.threads_used =
      static_cast<int>(std::max<size_t>(1, std::min<size_t>(threads, todo.size())));
  // The jobs that run side by side must fit, before any directory is made or job started.
  const MemoryBudget budget = MemoryBudget::Of(options.memory_budget_bytes);
  const int64_t predicted = PredictJobsBytes(loaded, *plan, todo, counts.threads_used);
  Status fits = budget.Check(
      predicted,
      fmt::format("{} job{} side by side, the largest with {} particles", counts.threads_used,
                  counts.threads_used == 1 ? "" : "s",
                  todo.empty() ? 0 : plan->groups[plan->jobs[todo.front()].group].particles),
      "use fewer particles or --threads, or raise --memory-budget");
  const int fit = fits.ok() ? kExitOk : Fail(kExitMemory, fits.message());
  if (const int agreed = ranks.Agree(fit); agreed != kExitOk) return agreed;

  // Rank 0 makes and locks the output directory while the others wait.
  std::optional<OutputDirectory> out;
  const int opened = ranks.rank() == 0 ? OpenOutput(options.out_dir, *plan, &out) : kExitOk;
  if (const int agreed = ranks.Agree(opened); agreed != kExitOk) return agreed;
  PrintPlan(loaded, *plan, options.runs, counts);
  if (ranks.ranks() > 1) {
    std::fprintf(stderr, "montecarlo: rank %zu of %d runs %lld of the %zu jobs\n", ranks.rank(),
                 ranks.ranks(), static_cast<long long>(own_jobs), plan->jobs.size());
  }
  JobProgress progress(own_jobs, counts.reused, options.progress);
  Status ran =
      RunMonteCarloJobs(scenario, *plan, todo, counts.threads_used, options.out_dir, &progress);
  progress.Finish();
  int code = ran.ok() ? kExitOk : Fail(kExitOutput, ran.message());
  if (const int signal = StopSignal(); signal != 0 && code == kExitOk) {
    std::fprintf(stderr,
                 "montecarlo: stopped by %s; the jobs finished so far are kept in %s: run the same "
                 "command again to run the rest\n",
                 strsignal(signal), options.out_dir.c_str());
    code = kExitSignalBase + signal;
  }
  // Every rank's jobs are on disk once all have come here; rank 0 writes the aggregates.
  if (const int agreed = ranks.Agree(code); agreed != kExitOk || ranks.rank() != 0) return agreed;
  return WriteResults(options, request, scenario, *plan, counts, wall_start);
}

}  // namespace grove::tools

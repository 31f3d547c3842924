#include "tools/bench/sweep_bench.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <utility>

#include "tools/bench/bench_process.h"
#include "tools/io/output_set.h"
#include "tools/report/chart.h"
#include "tools/report/report_tables.h"
#include "tools/run/memory_budget.h"
#include "tools/run/run_loop.h"

namespace grove::tools {
namespace {

// One run of one pair.
struct SweepRun {
  int64_t particles = 0;
  int threads = 0;
  int repetition = 0;  // from 1
  int64_t steps = 0;
  int threads_used = 0;
  double filter_s = 0;
  double wall_s = 0;  // the child's: the engine made and fed the input
  double cpu_s = 0;   // the child's, user + system, every thread
  int64_t peak_rss_bytes = 0;
};

// The runs of one pair and what the report says of them.
struct SweepPair {
  int64_t particles = 0;
  int threads = 0;
  std::vector<const SweepRun*> runs = {};
  double median_s = 0, min_s = 0, max_s = 0;
  double particle_steps_per_s = 0;  // at the median time
  double ns_per_particle_step = 0;
  double step_ms = 0;          // median time per filter step
  double speedup = 0;          // the same particles' median at the smallest thread count / this one
  double ideal_speedup = 0;    // threads / the smallest thread count
  int64_t peak_rss_bytes = 0;  // the largest of the runs'
};

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

bool WriteAll(int fd, const std::string& text) {
  for (size_t done = 0; done < text.size();) {
    const ssize_t n = write(fd, text.data() + done, text.size() - done);
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

std::string ReadAll(int fd) {
  std::string text;
  char buffer[4096];
  for (ssize_t n; (n = read(fd, buffer, sizeof(buffer))) > 0;) {
    text.append(buffer, static_cast<size_t>(n));
  }
  return text;
}

// One run in a child process, which sends its summary (or its error) back through a pipe as
// JSON: a few hundred bytes, well within a pipe's buffer, so the child never waits for the
// parent to read.
StatusOr<SweepRun> RunInChild(const SweepBenchModel& model, int64_t particles, int threads) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) return InternalError("bench: no pipe to a child process");
  SweepRun r{.particles = particles, .threads = threads};
  const int code = InChild(
      [&] {
        close(fds[0]);
        const auto start = std::chrono::steady_clock::now();
        StatusOr<FilterSummary> summary = model.run(particles, threads);
        const double wall_s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        nlohmann::json j;
        if (summary.ok()) {
          j = {{"filter_s", summary->filter_s()},
               {"steps", summary->steps},
               {"threads_used", summary->threads_used},
               {"wall_s", wall_s}};
        } else {
          j = {{"code", static_cast<int>(summary.status().code())},
               {"message", summary.status().message()}};
        }
        return WriteAll(fds[1], j.dump()) ? 0 : 1;
      },
      &r.cpu_s, &r.peak_rss_bytes);
  close(fds[1]);
  const std::string text = ReadAll(fds[0]);
  close(fds[0]);
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (code != 0 || !j.is_object()) {
    return FailedPreconditionError(fmt::format(
        "bench: the run with {} particles on {} threads ended without a result ({})", particles,
        threads, code < 0 ? "killed by a signal" : fmt::format("exit status {}", code)));
  }
  if (j.contains("code")) {
    return Status(static_cast<StatusCode>(j["code"].get<int>()), j["message"].get<std::string>());
  }
  r.filter_s = j["filter_s"].get<double>();
  r.steps = j["steps"].get<int64_t>();
  r.threads_used = j["threads_used"].get<int>();
  r.wall_s = j["wall_s"].get<double>();
  return r;
}

// The pairs in the order of the command line's lists, particles outer.
std::vector<SweepPair> Summarise(const std::vector<int64_t>& particles,
                                 const std::vector<int64_t>& threads,
                                 const std::vector<SweepRun>& runs) {
  const int64_t fewest_threads = *std::min_element(threads.begin(), threads.end());
  std::vector<SweepPair> pairs;
  for (int64_t n : particles) {
    std::optional<double> base_s;  // the median at the fewest threads
    const size_t first = pairs.size();
    for (int64_t t : threads) {
      SweepPair p{.particles = n, .threads = static_cast<int>(t)};
      std::vector<double> times;
      for (const SweepRun& r : runs) {
        if (r.particles != n || r.threads != t) continue;
        p.runs.push_back(&r);
        times.push_back(r.filter_s);
        p.peak_rss_bytes = std::max(p.peak_rss_bytes, r.peak_rss_bytes);
      }
      p.median_s = Median(times);
      p.min_s = *std::min_element(times.begin(), times.end());
      p.max_s = *std::max_element(times.begin(), times.end());
      const double steps = static_cast<double>(p.runs.front()->steps);
      const double particle_steps = static_cast<double>(n) * steps;
      p.particle_steps_per_s = p.median_s > 0 ? particle_steps / p.median_s : 0;
      p.ns_per_particle_step = particle_steps > 0 ? p.median_s * 1e9 / particle_steps : 0;
      p.step_ms = steps > 0 ? p.median_s * 1e3 / steps : 0;
      p.ideal_speedup = static_cast<double>(t) / static_cast<double>(fewest_threads);
      if (t == fewest_threads) base_s = p.median_s;
      pairs.push_back(std::move(p));
    }
    for (size_t k = first; k < pairs.size(); ++k) {
      pairs[k].speedup = pairs[k].median_s > 0 ? *base_s / pairs[k].median_s : 0;
    }
  }
  return pairs;
}

std::string RunsCsv(const std::vector<SweepRun>& runs) {
  std::vector<std::vector<std::string>> rows;
  for (const SweepRun& r : runs) {
    rows.push_back({std::to_string(r.particles), std::to_string(r.threads),
                    std::to_string(r.repetition), std::to_string(r.steps),
                    std::to_string(r.threads_used), fmt::format("{}", r.filter_s),
                    fmt::format("{}", r.wall_s), fmt::format("{}", r.cpu_s),
                    std::to_string(r.peak_rss_bytes)});
  }
  return CsvTable({"particles", "threads", "repetition", "steps", "threads_used", "filter_s",
                   "wall_s", "cpu_s", "peak_rss_bytes"},
                  rows);
}

std::string PairsCsv(const std::vector<SweepPair>& pairs) {
  std::vector<std::vector<std::string>> rows;
  for (const SweepPair& p : pairs) {
    rows.push_back({std::to_string(p.particles), std::to_string(p.threads),
                    std::to_string(p.runs.size()), std::to_string(p.runs.front()->steps),
                    fmt::format("{}", p.median_s), fmt::format("{}", p.min_s),
                    fmt::format("{}", p.max_s), fmt::format("{}", p.particle_steps_per_s),
                    fmt::format("{}", p.ns_per_particle_step), fmt::format("{}", p.speedup),
                    fmt::format("{}", p.ideal_speedup), std::to_string(p.peak_rss_bytes)});
  }
  return CsvTable({"particles", "threads", "runs", "steps", "median_filter_s", "min_filter_s",
                   "max_filter_s", "particle_steps_per_s", "ns_per_particle_step", "speedup",
                   "ideal_speedup", "max_peak_rss_bytes"},
                  rows);
}

// "the defaults" or "the defaults but map = naive, seed = 7" (particles and threads aside).
std::string ConfigDifferences(const SweepBenchModel& model) {
  const nlohmann::json config = nlohmann::json::parse(model.config_json);
  const nlohmann::json defaults = nlohmann::json::parse(model.defaults_json);
  std::string differences;
  for (const auto& [key, value] : config.items()) {
    if (key == "particles" || key == "threads" || value == defaults.value(key, nlohmann::json())) {
      continue;
    }
    differences += fmt::format("{}{} = {}", differences.empty() ? "" : ", ", key, value.dump());
  }
  return differences.empty() ? "the defaults" : "the defaults but " + differences;
}

std::string Report(const SweepBenchModel& model, const SweepBenchOptions& options,
                   const std::vector<SweepPair>& pairs) {
  std::vector<std::vector<std::string>> rows;
  for (const SweepPair& p : pairs) {
    rows.push_back({std::to_string(p.particles), std::to_string(p.threads),
                    fmt::format("{:.4f}", p.median_s), fmt::format("{:.4f}", p.min_s),
                    fmt::format("{:.4f}", p.max_s), fmt::format("{:.3g}", p.particle_steps_per_s),
                    fmt::format("{:.1f}", p.ns_per_particle_step), fmt::format("{:.2f}", p.speedup),
                    fmt::format("{:.2f}", p.ideal_speedup),
                    fmt::format("{:.0f}", static_cast<double>(p.peak_rss_bytes) / 1048576.0)});
  }
  return fmt::format(
      "# grove bench {}\n\nMachine: {}\n\nCommand: `{}`\n\nInput: {}\n\nConfiguration: {}.\n\n"
      "Each pair ran {} times, each run in a fresh process. Filter time: the sum of the "
      "filter's phases (the filter_time_s of a run's summary.json), reading and writing "
      "excluded; speed-up: the median at the fewest threads over this median, for the same "
      "particles; ideal: linear in the threads.\n\n{}",
      model.command, MachineDescription(), CommandLine(), model.input, ConfigDifferences(model),
      options.repeat,
      MarkdownTable({"particles", "threads", "median s", "min s", "max s", "particle-steps/s",
                     "ns per particle-step", "speed-up", "ideal", "peak RSS MiB"},
                    rows));
}

nlohmann::json SummaryJson(const SweepBenchModel& model, const SweepBenchOptions& options,
                           const std::vector<SweepPair>& pairs) {
  nlohmann::json j = {{"bench", model.command},
                      {"machine", MachineDescription()},
                      {"command_line", CommandLine()},
                      {"grove", VersionJson()},
                      {"config", nlohmann::json::parse(model.config_json)},
                      {"repeat", options.repeat},
                      {"pairs", nlohmann::json::array()}};
  for (const SweepPair& p : pairs) {
    j["pairs"].push_back({{"particles", p.particles},
                          {"threads", p.threads},
                          {"steps", p.runs.front()->steps},
                          {"median_filter_s", p.median_s},
                          {"min_filter_s", p.min_s},
                          {"max_filter_s", p.max_s},
                          {"particle_steps_per_s", p.particle_steps_per_s},
                          {"speedup", p.speedup},
                          {"ideal_speedup", p.ideal_speedup}});
  }
  return j;
}

using Points = std::vector<std::pair<double, double>>;

// A series through `xy` sorted by x: the command line's lists may come in any order.
ChartSeries SortedSeries(std::string label, Points xy, ChartStyle style = ChartStyle::kLinePoints) {
  std::sort(xy.begin(), xy.end());
  ChartSeries s{.label = std::move(label), .style = style};
  for (const auto& [x, y] : xy) {
    s.x.push_back(x);
    s.y.push_back(y);
  }
  return s;
}

// threads.png, and particles.png when more than one particle count ran.
std::vector<std::pair<std::string, Chart>> Charts(const std::vector<int64_t>& particles,
                                                  const std::vector<SweepPair>& pairs) {
  std::map<int64_t, Points> speedups;  // per particle count
  std::map<int, Points> step_ms;       // per thread count
  std::map<double, double> ideal;
  for (const SweepPair& p : pairs) {
    speedups[p.particles].emplace_back(p.threads, p.speedup);
    step_ms[p.threads].emplace_back(static_cast<double>(p.particles), p.step_ms);
    ideal[p.threads] = p.ideal_speedup;
  }
  Chart threads{.title = "Speed-up against threads (median filter time)",
                .x_label = "threads",
                .y_label = "speed-up over the fewest threads",
                .integer_x = true,
                .y_from_zero = true};
  for (int64_t n : particles) {
    threads.series.push_back(SortedSeries(fmt::format("{} particles", n), speedups[n]));
  }
  threads.series.push_back(
      SortedSeries("ideal (linear)", Points(ideal.begin(), ideal.end()), ChartStyle::kDashed));
  std::vector<std::pair<std::string, Chart>> charts = {{"threads.png", std::move(threads)}};
  if (particles.size() < 2) return charts;
  Chart by_particles{.title = "Time per step against particles (median filter time)",
                     .x_label = "particles",
                     .y_label = "ms per filter step",
                     .log_x = true,
                     .log_y = true};
  for (const auto& [t, xy] : step_ms) {
    by_particles.series.push_back(
        SortedSeries(fmt::format("{} thread{}", t, t == 1 ? "" : "s"), xy));
  }
  charts.emplace_back("particles.png", std::move(by_particles));
  return charts;
}

// Writes the outputs as one set; a chart that cannot be drawn (gnuplot missing) is left out
// with a warning rather than losing the measurements.
Status WriteOutputs(const SweepBenchModel& model, const SweepBenchOptions& options,
                    const std::vector<int64_t>& particles, const std::vector<SweepRun>& runs,
                    const std::vector<SweepPair>& pairs, const std::string& md) {
  StatusOr<OutputSet> out = OutputSet::Begin(options.out_dir);
  if (!out.ok()) return out.status();
  GROVE_RETURN_IF_ERROR(out->Add("bench.md", md));
  GROVE_RETURN_IF_ERROR(out->Add("bench.csv", RunsCsv(runs)));
  GROVE_RETURN_IF_ERROR(out->Add("bench_summary.csv", PairsCsv(pairs)));
  for (const auto& [name, chart] : Charts(particles, pairs)) {
    Status s = WriteChart(chart, out->StagingPath(name), "");
    if (s.ok()) {
      GROVE_RETURN_IF_ERROR(out->Adopt(name));
    } else {
      std::fprintf(stderr, "grove: warning: %s not drawn: %s\n", name.c_str(), s.message().c_str());
    }
  }
  return out->Commit(SummaryJson(model, options, pairs));
}

}  // namespace

std::vector<int64_t> DefaultThreadCounts() {
  const int cpus = UsableCpus();
  std::vector<int64_t> counts;
  for (int t = 1; t < cpus; t *= 2) counts.push_back(t);
  counts.push_back(cpus);
  return counts;
}

int RunSweepBench(const SweepBenchModel& model, const SweepBenchOptions& options) {
  const std::vector<int64_t>& particles = options.particles;
  const std::vector<int64_t> threads =
      options.threads.empty() ? DefaultThreadCounts() : options.threads;
  for (int64_t n : particles) {
    for (int64_t t : threads) {
      if (Status s = model.check(n, static_cast<int>(t)); !s.ok()) {
        return Fail(kExitUsage, s.message());
      }
    }
  }
  const int64_t most = *std::max_element(particles.begin(), particles.end());
  const auto most_threads = static_cast<int>(*std::max_element(threads.begin(), threads.end()));
  const MemoryBudget budget = MemoryBudget::Of(options.memory_budget_bytes);
  Status fits = budget.Check(model.predict_peak_bytes(most, most_threads),
                             fmt::format("{} particles, {} threads", most, most_threads),
                             "use fewer particles or raise --memory-budget");
  if (!fits.ok()) return Fail(kExitMemory, fits.message());
  StatusOr<OutputDirectory> dir = OutputDirectory::Open(options.out_dir);
  if (!dir.ok()) return Fail(kExitOutput, dir.status().message());
  // Repetition outermost: a change in the machine's load while the bench runs spreads over
  // every pair instead of falling on one.
  std::vector<SweepRun> runs;
  for (int rep = 1; rep <= options.repeat; ++rep) {
    for (int64_t n : particles) {
      for (int64_t t : threads) {
        StatusOr<SweepRun> r = RunInChild(model, n, static_cast<int>(t));
        if (!r.ok()) {
          const Status& s = r.status();
          return Fail(s.code() == StatusCode::kResourceExhausted ? kExitMemory : ExitCodeOf(s),
                      s.message());
        }
        r->repetition = rep;
        std::fprintf(stderr, "%s: %lld particles x %lld thread%s, run %d of %d: %.4f s\n",
                     model.command.c_str(), static_cast<long long>(n), static_cast<long long>(t),
                     t == 1 ? "" : "s", rep, options.repeat, r->filter_s);
        runs.push_back(*r);
      }
    }
  }
  const std::vector<SweepPair> pairs = Summarise(particles, threads, runs);
  const std::string md = Report(model, options, pairs);
  if (Status s = WriteOutputs(model, options, particles, runs, pairs, md); !s.ok()) {
    return Fail(kExitOutput, s.message());
  }
  dir->Keep();
  std::printf("%s", md.c_str());
  return kExitOk;
}

}  // namespace grove::tools

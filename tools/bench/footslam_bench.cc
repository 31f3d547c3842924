// `grove bench paper`, `scaling` and `footslam` (tools/bench/bench_commands.h).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "grove/config_json.h"
#include "grove/footslam.h"
#include "tools/bench/bench_commands.h"
#include "tools/bench/bench_process.h"
#include "tools/io/atomic_file.h"
#include "tools/io/csv_reader.h"
#include "tools/io/output_set.h"
#include "tools/io/step_reader.h"
#include "tools/report/chart.h"
#include "tools/report/report_tables.h"
#include "tools/run/footslam_run.h"
#include "tools/sim/walk_simulator.h"

namespace grove::tools {
namespace {

using Clock = std::chrono::steady_clock;

struct PaperConfig {
  const char* name;
  FootSlamMapKind map;
  int degree;
  int grid;
  int alphabet;
};

const PaperConfig kPaperConfigs[] = {
    {"naive", FootSlamMapKind::kNaive, 16, 256, 0},
    {"htree s=4 T=5", FootSlamMapKind::kHTree, 4, 256, 5},
    {"htree s=16 T=0", FootSlamMapKind::kHTree, 16, 256, 0},
    {"htree s=16 T=5", FootSlamMapKind::kHTree, 16, 256, 5},
    {"htree s=64 T=5", FootSlamMapKind::kHTree, 64, 512, 5},
};

struct Sample {
  double walk_s, run_s, rss_mib, map_mib;
};

// Parses the child's series: one "walk_s run_s rss_mib map_mib" line per sample.
std::vector<Sample> ParseSamples(const std::string& text) {
  std::vector<Sample> out;
  std::istringstream in(text);
  Sample s;
  while (in >> s.walk_s >> s.run_s >> s.rss_mib >> s.map_mib) out.push_back(s);
  return out;
}

// One configuration's run of the walk (the median of its repetitions).
struct PaperResult {
  const PaperConfig* config = nullptr;
  std::vector<Sample> samples;
  int64_t steps = 0;
  double run_s = 0;
  double cpu_s = 0;
  double peak_rss_mib = 0;
  bool stopped = false;
  std::vector<double> all_run_s;  // every repetition's, in order
};

// The body of the child process that runs `pc` on `walk`: writes a sample every 5 s of walk
// to `series_path`, then "# steps N peak_rss_mib M". Returns the child's exit code.
int RunPaperSeries(const PaperBenchOptions& options, const PaperConfig& pc,
                   const std::vector<StepRecord>& walk, const std::string& series_path) {
  const double walk_start = 0;
  FootSlamConfig config;
  config.particles = options.particles;
  config.threads = options.threads;
  config.map = pc.map;
  config.degree = pc.degree;
  config.grid_size = pc.grid;
  config.grid = options.grid == "growing" ? FootSlamGrid::kGrowing : FootSlamGrid::kFixed;
  config.alphabet = pc.alphabet;
  auto slam = FootSlam::Create(config);
  if (!slam.ok()) return 10;
  std::string out;
  auto start = Clock::now();
  double next_sample = 0;
  int64_t done = 0;
  for (const StepRecord& step : walk) {
    if (!(*slam)->Step(step.t_s, step.dx_m, step.dy_m).ok()) return 11;
    ++done;
    double run_s = std::chrono::duration<double>(Clock::now() - start).count();
    if (step.t_s >= next_sample || done == static_cast<int64_t>(walk.size())) {
      next_sample = step.t_s + 5;
      out +=
          fmt::format("{} {} {} {}\n", step.t_s - walk_start, run_s, CurrentRssBytes() / 1048576.0,
                      (*slam)->Summary().map_memory.live_bytes / 1048576.0);
    }
    if (pc.map == FootSlamMapKind::kNaive && run_s > options.naive_limit_s) break;
  }
  out += fmt::format("# steps {} peak_rss_mib {}\n", done, PeakRssBytes() / 1048576.0);
  return WriteFileAtomically(series_path, out).ok() ? 0 : 12;
}

// One repetition of `pc`, in a child process so that its peak RSS is its own.
StatusOr<PaperResult> RunPaperRepetition(const PaperBenchOptions& options, const PaperConfig& pc,
                                         const std::vector<StepRecord>& walk) {
  double cpu_s = 0;
  std::string series_path = fmt::format("{}/.series-{}", options.out_dir, getpid());
  int code = InChild([&] { return RunPaperSeries(options, pc, walk, series_path); }, &cpu_s);
  if (code != 0) {
    return FailedPreconditionError(fmt::format("{}: the run failed (code {})", pc.name, code));
  }
  StatusOr<std::string> series = ReadWholeFile(series_path);
  if (!series.ok()) return series.status();
  const std::string& text = *series;
  std::remove(series_path.c_str());
  PaperResult r;
  r.config = &pc;
  r.samples = ParseSamples(text.substr(0, text.find('#')));
  size_t tail = text.find("# steps");
  if (tail != std::string::npos) {
    std::sscanf(text.c_str() + tail, "# steps %ld peak_rss_mib %lf", &r.steps, &r.peak_rss_mib);
  }
  r.run_s = r.samples.empty() ? 0 : r.samples.back().run_s;
  r.cpu_s = cpu_s;
  r.stopped = r.steps < static_cast<int64_t>(walk.size());
  std::fprintf(stderr, "%-16s %5ld steps in %7.2f s (CPU %.2f s), peak RSS %7.1f MiB%s\n", pc.name,
               r.steps, r.run_s, r.cpu_s, r.peak_rss_mib,
               r.stopped ? " (stopped: time limit)" : "");
  return r;
}

// The repetitions run one after another; the median run (by run time) is reported.
StatusOr<PaperResult> RunPaperConfig(const PaperBenchOptions& options, const PaperConfig& pc,
                                     const std::vector<StepRecord>& walk) {
  std::vector<PaperResult> runs;
  for (int rep = 0; rep < options.repeat; ++rep) {
    StatusOr<PaperResult> r = RunPaperRepetition(options, pc, walk);
    if (!r.ok()) return r.status();
    runs.push_back(std::move(*r));
  }
  std::vector<double> all;
  for (const PaperResult& r : runs) all.push_back(r.run_s);
  const auto middle = runs.begin() + static_cast<std::ptrdiff_t>(runs.size() / 2);
  std::nth_element(runs.begin(), middle, runs.end(),
                   [](const PaperResult& a, const PaperResult& b) { return a.run_s < b.run_s; });
  PaperResult median = std::move(*middle);
  median.all_run_s = std::move(all);
  return median;
}

// The row of paper.md for one configuration.
std::vector<std::string> PaperTableRow(const PaperBenchOptions& options, const PaperResult& r) {
  // Time per step in the first and the last minute of what was run: flat means linear time.
  double first_minute = 0, last_minute = 0;
  int64_t first_n = 0, last_n = 0;
  for (size_t k = 1; k < r.samples.size(); ++k) {
    double dt = r.samples[k].run_s - r.samples[k - 1].run_s;
    double dw = r.samples[k].walk_s - r.samples[k - 1].walk_s;
    if (r.samples[k].walk_s <= 60) {
      first_minute += dt;
      first_n += static_cast<int64_t>(dw);
    }
    if (r.samples[k].walk_s > r.samples.back().walk_s - 60) {
      last_minute += dt;
      last_n += static_cast<int64_t>(dw);
    }
  }
  double ratio = first_n > 0 && last_n > 0 && first_minute > 0
                     ? (last_minute / last_n) / (first_minute / first_n)
                     : 0;
  double ns = r.steps > 0 ? r.run_s * 1e9 / (static_cast<double>(r.steps) * options.particles) : 0;
  double walked = r.samples.empty() ? 0 : r.samples.back().walk_s;
  double peak_map = 0;
  for (const Sample& s : r.samples) peak_map = std::max(peak_map, s.map_mib);
  const auto [lo, hi] = std::minmax_element(r.all_run_s.begin(), r.all_run_s.end());
  return {r.config->name,
          fmt::format("{}{}", r.steps, r.stopped ? " (stopped)" : ""),
          fmt::format("{:.0f}", walked),
          fmt::format("{:.2f}", r.run_s),
          fmt::format("{:.2f}-{:.2f}", *lo, *hi),
          fmt::format("{:.2f}", r.cpu_s),
          fmt::format("{:.3f}", walked > 0 ? r.run_s / walked : 0),
          fmt::format("{:.0f}", ns),
          fmt::format("{:.2f}", ratio),
          fmt::format("{:.0f}", r.peak_rss_mib),
          fmt::format("{:.1f}", peak_map)};
}

// The charts of `bench paper` and the rows of paper.csv.
struct PaperCharts {
  // Log scale: grove runs orders of magnitude below the real-time line.
  Chart runtime{.title = "Run time against walk time (Fig. 9)",
                .x_label = "walk time (s)",
                .y_label = "cumulative run time (s, log scale)",
                .log_y = true};
  Chart memory{.title = "Resident memory against walk time (Fig. 10)",
               .x_label = "walk time (s)",
               .y_label = "RSS (MiB)"};
  Chart map_memory{.title = "Live map memory against walk time",
                   .x_label = "walk time (s)",
                   .y_label = "live map nodes (MiB)"};
  std::vector<std::vector<std::string>> csv_rows;

  PaperCharts(const std::vector<PaperResult>& results, double walk_end) {
    ChartSeries real_time{.label = "real time", .style = ChartStyle::kDashed};
    for (double t = 1; t < walk_end + 5; t += 5) {
      real_time.x.push_back(std::min(t, walk_end));
      real_time.y.push_back(std::min(t, walk_end));
    }
    runtime.series.push_back(real_time);
    for (const PaperResult& r : results) {
      // A sample every 5 s of walk: too dense for markers.
      ChartSeries time_series{.label = r.config->name, .style = ChartStyle::kLine};
      ChartSeries rss_series = time_series;
      ChartSeries map_series = time_series;
      for (const Sample& s : r.samples) {
        csv_rows.push_back({r.config->name, fmt::format("{:.2f}", s.walk_s),
                            fmt::format("{:.3f}", s.run_s), fmt::format("{:.1f}", s.rss_mib),
                            fmt::format("{:.2f}", s.map_mib)});
        time_series.x.push_back(s.walk_s);
        time_series.y.push_back(s.run_s);
        rss_series.x.push_back(s.walk_s);
        rss_series.y.push_back(s.rss_mib);
        map_series.x.push_back(s.walk_s);
        map_series.y.push_back(s.map_mib);
      }
      runtime.series.push_back(time_series);
      memory.series.push_back(rss_series);
      map_memory.series.push_back(map_series);
    }
  }
};

// paper.csv, paper.md (also to stdout) and the charts.
int WritePaperReport(const PaperBenchOptions& options, const std::vector<StepRecord>& walk,
                     const std::vector<PaperResult>& results) {
  const PaperCharts charts(results, walk.back().t_s);
  std::vector<std::vector<std::string>> table;
  for (const PaperResult& r : results) table.push_back(PaperTableRow(options, r));
  std::string md = fmt::format(
      "# grove bench paper\n\nMachine: {}\n\nWalk: simulated open area, {} minutes ({} steps), "
      "{} particles, {} threads; each configuration run {} times, the median run (by run time) "
      "reported, its CPU time (user + system, all threads) beside it.\n\n",
      MachineDescription(), options.minutes, walk.size(), options.particles,
      options.threads == 0 ? std::thread::hardware_concurrency() : options.threads, options.repeat);
  md += MarkdownTable({"configuration", "steps run", "walk s", "run s", "run s, all runs", "CPU s",
                       "run / walk time", "ns per particle-step", "last/first minute time per step",
                       "peak RSS MiB", "peak live map MiB"},
                      table);
  const std::string& dir = options.out_dir;
  Status s = WriteFileAtomically(
      dir + "/paper.csv",
      CsvTable({"configuration", "walk_s", "run_s", "rss_mib", "live_map_mib"}, charts.csv_rows));
  // The tables before the charts: without gnuplot the numbers are still kept.
  if (s.ok()) s = WriteFileAtomically(dir + "/paper.md", md);
  if (s.ok()) {
    s = WriteChart(charts.runtime, dir + "/paper_runtime.png", dir + "/paper_runtime.svg");
  }
  if (s.ok()) s = WriteChart(charts.memory, dir + "/paper_memory.png", dir + "/paper_memory.svg");
  if (s.ok()) {
    s = WriteChart(charts.map_memory, dir + "/paper_map_memory.png", dir + "/paper_map_memory.svg");
  }
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::printf("%s", md.c_str());
  return kExitOk;
}

}  // namespace

std::vector<std::string> PaperBenchConfigurations() {
  std::vector<std::string> names;
  for (const PaperConfig& pc : kPaperConfigs) names.push_back(pc.name);
  return names;
}

int PaperBenchCommand(const PaperBenchOptions& options) {
  if (!options.only.empty()) {
    std::string known;
    bool found = false;
    for (const PaperConfig& pc : kPaperConfigs) {
      found = found || options.only == pc.name;
      known += fmt::format("{}\"{}\"", known.empty() ? "" : ", ", pc.name);
    }
    if (!found) {
      return Fail(kExitUsage, fmt::format("--only = {}: must be one of {}",
                                          QuoteForMessage(options.only), known));
    }
  }
  StatusOr<std::vector<StepRecord>> walk = PaperWalk(options.minutes);
  if (!walk.ok()) return Fail(kExitUsage, walk.status().message());
  Status s = EnsureDirectory(options.out_dir);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::vector<PaperResult> results;
  for (const PaperConfig& pc : kPaperConfigs) {
    if (!options.only.empty() && options.only != pc.name) continue;
    StatusOr<PaperResult> median = RunPaperConfig(options, pc, *walk);
    if (!median.ok()) return Fail(kExitRun, median.status().message());
    results.push_back(std::move(*median));
  }
  return WritePaperReport(options, *walk, results);
}

int ScalingBenchCommand(const ScalingBenchOptions& options) {
  StatusOr<std::vector<StepRecord>> walk = PaperWalk(13);
  if (!walk.ok()) return Fail(kExitUsage, walk.status().message());
  Status s = EnsureDirectory(options.out_dir);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  const int64_t steps = std::min<int64_t>(options.steps, static_cast<int64_t>(walk->size()));
  struct Point {
    int64_t particles;
    int threads;
    FootSlamSummary summary;
    double cpu_s;  // the process's, over the run
  };
  auto process_cpu_s = [] {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return CpuSeconds(usage);
  };
  auto run = [&](int64_t particles, int threads) -> StatusOr<FootSlamSummary> {
    FootSlamConfig config;
    config.particles = particles;
    config.threads = threads;
    config.grid = options.grid == "fixed" ? FootSlamGrid::kFixed : FootSlamGrid::kGrowing;
    auto slam = FootSlam::Create(config);
    if (!slam.ok()) return slam.status();
    for (int64_t k = 0; k < steps; ++k) {
      const StepRecord& st = (*walk)[k];
      GROVE_RETURN_IF_ERROR((*slam)->Step(st.t_s, st.dx_m, st.dy_m));
    }
    return (*slam)->Summary();
  };
  std::vector<Point> points;
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  // --max-particles limits the thread sweep too.
  const int64_t sweep_particles = std::min(options.thread_sweep_particles, options.max_particles);
  for (int t = 1; t <= cores; ++t) {
    const double cpu0 = process_cpu_s();
    auto r = run(sweep_particles, t);
    if (!r.ok()) return Fail(kExitRun, r.status().message());
    points.push_back({sweep_particles, t, *r, process_cpu_s() - cpu0});
  }
  for (int64_t n : {1000, 3000, 10000, 30000, 100000, 300000, 1000000}) {
    if (n > options.max_particles) break;
    const double cpu0 = process_cpu_s();
    auto r = run(n, cores);
    if (!r.ok()) return Fail(kExitRun, r.status().message());
    points.push_back({n, cores, *r, process_cpu_s() - cpu0});
  }
  std::vector<std::vector<std::string>> rows;
  Chart threads_chart{.title = "Throughput against threads",
                      .x_label = "threads",
                      .y_label = "M particle-steps / s",
                      .integer_x = true,
                      .y_from_zero = true};
  Chart particles_chart{.title = "Cost against particles",
                        .x_label = "particles",
                        .y_label = "ns per particle-step",
                        .log_x = true};
  ChartSeries tp{.label = fmt::format("{} particles", sweep_particles)};
  ChartSeries pp{.label = fmt::format("{} threads", cores)};
  std::vector<ChartSeries> phase_series;
  for (const char* phase : {"advance", "resample", "release", "normalise"}) {
    phase_series.push_back({.label = phase, .style = ChartStyle::kDashed});
  }
  for (size_t i = 0; i < points.size(); ++i) {
    const Point& p = points[i];
    const FootSlamSummary& m = p.summary;
    double total = m.advance_s + m.normalize_s + m.resample_s + m.release_s + m.bookkeeping_s;
    double ps = static_cast<double>(p.particles) * steps;
    double ns = total * 1e9 / ps;
    bool thread_sweep = i < static_cast<size_t>(cores);
    rows.push_back({thread_sweep ? "threads" : "particles", std::to_string(p.particles),
                    std::to_string(p.threads), std::to_string(steps), fmt::format("{:.3f}", total),
                    fmt::format("{:.3f}", ps / total / 1e6), fmt::format("{:.1f}", ns),
                    fmt::format("{:.1f}", m.advance_s * 1e9 / ps),
                    fmt::format("{:.1f}", m.normalize_s * 1e9 / ps),
                    fmt::format("{:.1f}", m.resample_s * 1e9 / ps),
                    fmt::format("{:.1f}", m.release_s * 1e9 / ps),
                    fmt::format("{:.1f}", m.bookkeeping_s * 1e9 / ps),
                    fmt::format("{:.1f}", p.cpu_s * 1e9 / ps),
                    fmt::format("{:.1f}", m.loop_busy_s * 1e9 / ps),
                    fmt::format("{:.1f}", (m.threads_used * m.loop_s - m.loop_busy_s) * 1e9 / ps),
                    fmt::format("{:.1f}", (total - m.loop_s) * 1e9 / ps),
                    fmt::format("{:.1f}", m.map_memory.peak_live_bytes / 1048576.0)});
    if (thread_sweep) {
      tp.x.push_back(p.threads);
      tp.y.push_back(ps / total / 1e6);
    } else {
      pp.x.push_back(static_cast<double>(p.particles));
      pp.y.push_back(ns);
      double parts[] = {m.advance_s, m.resample_s, m.release_s, m.normalize_s};
      for (int j = 0; j < 4; ++j) {
        phase_series[j].x.push_back(static_cast<double>(p.particles));
        phase_series[j].y.push_back(parts[j] * 1e9 / ps);
      }
    }
  }
  threads_chart.series.push_back(tp);
  particles_chart.series.push_back(pp);
  for (auto& ps : phase_series) particles_chart.series.push_back(ps);
  std::vector<std::string> header = {"sweep",
                                     "particles",
                                     "threads",
                                     "steps",
                                     "run s",
                                     "M particle-steps/s",
                                     "ns per particle-step",
                                     "advance ns",
                                     "normalise ns",
                                     "resample ns",
                                     "release ns",
                                     "bookkeeping ns",
                                     "process CPU ns",
                                     "loop bodies ns",
                                     "waiting in loops ns",
                                     "outside loops ns",
                                     "peak live map MiB"};
  std::string md = fmt::format(
      "# grove bench scaling\n\nMachine: {}\n\nThe first {} steps of the paper walk (simulated "
      "open area), H-tree s = 16, T = 5, {} grid; per-phase costs in ns per particle-step. Process "
      "CPU: user + system time of every thread over the run (including setting up); loop bodies: "
      "the threads' time running the parallel loops' work; waiting in loops: the threads' time "
      "inside a loop without work (arriving late or done early); outside loops: the driving "
      "thread's wall time between the loops (the other threads spin or sleep then).\n\n",
      MachineDescription(), steps, options.grid);
  md += MarkdownTable(header, rows);
  const std::string& dir = options.out_dir;
  s = WriteFileAtomically(dir + "/scaling.csv", CsvTable(header, rows));
  if (s.ok()) s = WriteFileAtomically(dir + "/scaling.md", md);
  if (s.ok()) {
    s = WriteChart(threads_chart, dir + "/scaling_threads.png", dir + "/scaling_threads.svg");
  }
  if (s.ok()) {
    s = WriteChart(particles_chart, dir + "/scaling_particles.png", dir + "/scaling_particles.svg");
  }
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::printf("%s", md.c_str());
  return kExitOk;
}

int FootSlamBenchCommand(const FootSlamConfig& config, const FootSlamBenchOptions& options) {
  StepReaderOptions reader_options;
  reader_options.max_step_m = options.max_step_m;
  double start_s = 0;
  StatusOr<std::vector<StepRecord>> steps =
      ReadAllSteps(options.steps_path, reader_options, &start_s);
  if (!steps.ok()) return Fail(kExitInput, steps.status().message());
  if (steps->empty()) return Fail(kExitInput, options.steps_path + ": no steps");
  const auto with = [&config](int64_t particles, int threads) {
    FootSlamConfig c = config;
    c.particles = particles;
    c.threads = threads;
    return c;
  };
  const auto records = static_cast<int64_t>(steps->size());
  SweepBenchModel model{
      .command = "footslam",
      .input = fmt::format("`{}`, {} steps", options.steps_path, records),
      .config_json = ConfigToJson(FootSlamConfigFields(), config),
      .defaults_json = ConfigToJson(FootSlamConfigFields(), FootSlamConfig()),
      .check = [&](int64_t particles, int threads) { return with(particles, threads).Validate(); },
      .predict_peak_bytes =
          [&](int64_t particles, int threads) {
            return FootSlam::EstimatePeakBytes(with(particles, threads), records) +
                   records * kCommandBytesPerStep;
          },
      .run = [&](int64_t particles, int threads) -> StatusOr<FilterSummary> {
        auto slam = FootSlam::Create(with(particles, threads));
        if (!slam.ok()) return slam.status();
        for (const StepRecord& step : *steps) {
          GROVE_RETURN_IF_ERROR(FeedStep(step, options.steps_path, start_s, slam->get()));
        }
        return (*slam)->Summary();
      }};
  return RunSweepBench(model, options.sweep);
}

}  // namespace grove::tools

#include "tools/bench/bench_commands.h"

#include <fmt/format.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "grove/footslam.h"
#include "grove/version.h"
#include "tools/io/atomic_file.h"
#include "tools/io/csv_reader.h"
#include "tools/io/output_set.h"
#include "tools/io/victoria_park.h"
#include "tools/report/chart.h"
#include "tools/report/report_tables.h"
#include "tools/run/fastslam_run.h"
#include "tools/run/footslam_run.h"
#include "tools/sim/fastslam_simulator.h"
#include "tools/sim/walk_simulator.h"

namespace grove::tools {
namespace {

using Clock = std::chrono::steady_clock;

// Resident set size now, from /proc/self/statm (pages).
int64_t CurrentRssBytes() {
  std::ifstream statm("/proc/self/statm");
  int64_t size = 0, resident = 0;
  statm >> size >> resident;
  return resident * sysconf(_SC_PAGESIZE);
}

std::string MachineDescription() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  }
  long pages = sysconf(_SC_PHYS_PAGES);
  double gib = static_cast<double>(pages) * sysconf(_SC_PAGESIZE) / (1024.0 * 1024 * 1024);
  return fmt::format("{}, {} hardware threads, {:.0f} GiB memory; {}", model,
                     std::thread::hardware_concurrency(), gib, VersionString());
}

// User plus system CPU time, in seconds.
double CpuSeconds(const rusage& usage) {
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// Runs `body` in a child process so that its memory (peak RSS) is its own; the child writes its
// result to `result_path`. Returns the child's exit status; *cpu_s (when given) receives the
// child's CPU time, user and system, summed over its threads.
template <typename F>
int InChild(F&& body, double* cpu_s = nullptr) {
  std::fflush(nullptr);
  pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) _exit(body());
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  if (cpu_s != nullptr) *cpu_s = CpuSeconds(usage);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

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
  for (int t = 1; t <= cores; ++t) {
    const double cpu0 = process_cpu_s();
    auto r = run(options.thread_sweep_particles, t);
    if (!r.ok()) return Fail(kExitRun, r.status().message());
    points.push_back({options.thread_sweep_particles, t, *r, process_cpu_s() - cpu0});
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
                      .y_label = "M particle-steps / s"};
  Chart particles_chart{.title = "Cost against particles",
                        .x_label = "particles",
                        .y_label = "ns per particle-step",
                        .log_x = true};
  ChartSeries tp{.label = fmt::format("{} particles", options.thread_sweep_particles)};
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

namespace {

// The webmap simulation of `seed` (Bailey's options).
StatusOr<BaileySimulation> WebmapSimulation(uint64_t seed) {
  StatusOr<BaileyMap> map = ParseBaileyMap(EmbeddedBaileyWebmapName(), EmbeddedBaileyWebmap());
  if (!map.ok()) return map.status();
  BaileySimOptions options = WebmapPreset();
  options.seed = seed;
  return SimulateBailey(*map, options);
}

// The mean pose after the last step at each truth time against the truth.
PoseErrors ScoreAgainstTruth(const FastSlam& slam, const BaileySimulation& sim) {
  std::map<double, Pose2> truth, estimate;
  for (const BaileyPose& t : sim.truth) truth[t.t_s] = Pose2{t.x_m, t.y_m, t.heading_rad};
  for (const StampedPose& p : slam.MeanTrajectory()) estimate[p.t_s] = p.pose;
  return ComparePoses(truth, estimate);
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty()      ? 0
         : v.size() % 2 ? v[v.size() / 2]
                        : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

}  // namespace

int FastSlamAccuracyBenchCommand(const FastSlamAccuracyOptions& options) {
  Status s = EnsureDirectory(options.out_dir);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  const FastSlamFilter filters[] = {FastSlamFilter::kFastSlam1, FastSlamFilter::kFastSlam2};
  FastSlamAssociation association = FastSlamAssociation::kKnown;
  if (options.association == "ml") {
    association = FastSlamAssociation::kMaximumLikelihood;
  } else if (options.association == "ml_exclusive") {
    association = FastSlamAssociation::kExclusive;
  } else if (options.association != "known") {
    return Fail(kExitUsage, fmt::format("--association = {}: must be known, ml or ml_exclusive",
                                        QuoteForMessage(options.association)));
  }
  const bool unknown = association != FastSlamAssociation::kKnown;
  std::vector<std::vector<std::string>> rows;
  nlohmann::json runs = nlohmann::json::array();
  // rmse[filter][particles] over seeds; under unknown association also the wrong associations
  // and the landmarks created, summed over seeds.
  std::map<std::pair<int, int64_t>, std::vector<double>> rmse;
  std::map<std::pair<int, int64_t>, AssociationCounts> counts;
  for (int seed = 1; seed <= options.seeds; ++seed) {
    StatusOr<BaileySimulation> sim = WebmapSimulation(static_cast<uint64_t>(seed));
    if (!sim.ok()) return Fail(kExitRun, sim.status().message());
    for (FastSlamFilter filter : filters) {
      for (int64_t n : options.particles) {
        FastSlamConfig config;
        config.filter = filter;
        config.particles = n;
        config.seed = static_cast<uint64_t>(seed);
        config.threads = options.threads;
        config.association = association;
        auto slam = FastSlam::Create(config);
        if (!slam.ok()) return Fail(kExitUsage, slam.status().message());
        s = FeedSimulation(*sim, slam->get());
        if (!s.ok()) return Fail(kExitRun, s.message());
        const PoseErrors a = ScoreAgainstTruth(**slam, *sim);
        const FastSlamSummary summary = (*slam)->Summary();
        rmse[{static_cast<int>(filter), n}].push_back(a.position_rmse_m);
        AssociationCounts& c = counts[{static_cast<int>(filter), n}];
        c.tagged += summary.association.tagged;
        c.wrong += summary.association.wrong;
        c.created += summary.association.created;
        runs.push_back({{"seed", seed},
                        {"filter", FastSlamFilterName(filter)},
                        {"particles", n},
                        {"position_rmse_m", a.position_rmse_m},
                        {"heading_rmse_rad", a.heading_rmse_rad},
                        {"position_mse_mean_m2", a.position_mse_mean_m2},
                        {"position_mse_variance_m4", a.position_mse_variance_m4},
                        {"resamplings", summary.resamplings},
                        {"filter_time_s", summary.filter_s()},
                        {"association", options.association},
                        {"associations_tagged", summary.association.tagged},
                        {"associations_wrong", summary.association.wrong},
                        {"landmarks_created", summary.association.created},
                        {"landmarks", summary.landmarks}});
        std::fprintf(stderr, "seed %d %s %lld particles: position RMSE %.2f m\n", seed,
                     FastSlamFilterName(filter), static_cast<long long>(n), a.position_rmse_m);
      }
    }
  }
  std::vector<std::string> header = {"filter",  "particles", "mean RMSE (m)", "median (m)",
                                     "min (m)", "max (m)",   "per seed (m)"};
  if (unknown) {
    header.insert(header.end() - 1, {"wrong / tagged associations", "landmarks created per run"});
  }
  for (FastSlamFilter filter : filters) {
    for (int64_t n : options.particles) {
      const std::vector<double>& v = rmse[{static_cast<int>(filter), n}];
      double sum = 0;
      std::string each;
      for (double x : v) {
        sum += x;
        each += fmt::format("{}{:.2f}", each.empty() ? "" : " ", x);
      }
      rows.push_back({FastSlamFilterName(filter), std::to_string(n),
                      fmt::format("{:.2f}", sum / v.size()), fmt::format("{:.2f}", Median(v)),
                      fmt::format("{:.2f}", *std::min_element(v.begin(), v.end())),
                      fmt::format("{:.2f}", *std::max_element(v.begin(), v.end())), each});
      if (unknown) {
        const AssociationCounts& c = counts[{static_cast<int>(filter), n}];
        rows.back().insert(rows.back().end() - 1,
                           {fmt::format("{} / {}", c.wrong, c.tagged),
                            fmt::format("{:.1f}", static_cast<double>(c.created) / v.size())});
      }
    }
  }
  const std::string md = fmt::format(
      "# FastSLAM accuracy on Bailey's webmap\n\nMachine: {}\n\n{}, Bailey's "
      "webmap options (2 loops, scans every 0.2 s), position RMSE of the weighted-mean pose "
      "against the truth at every control time (after the scan at a scan time), seeds 1..{} "
      "(simulator and filter).\n\n{}",
      MachineDescription(),
      unknown ? fmt::format("Unknown association ({}; the simulator's ids only tag, and the wrong "
                            "associations are counted along the heaviest particle's ancestry)",
                            options.association)
              : std::string("Known association"),
      options.seeds, MarkdownTable(header, rows));
  s = WriteFileAtomically(
      options.out_dir + "/fastslam_accuracy.json",
      nlohmann::json{{"machine", MachineDescription()}, {"grove", VersionJson()}, {"runs", runs}}
          .dump(2));
  if (s.ok()) s = WriteFileAtomically(options.out_dir + "/fastslam_accuracy.md", md);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::printf("%s", md.c_str());
  return kExitOk;
}

int FastSlamSpeedBenchCommand(const FastSlamSpeedOptions& options) {
  Status s = EnsureDirectory(options.out_dir);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  StatusOr<BaileySimulation> sim = WebmapSimulation(1);
  if (!sim.ok()) return Fail(kExitRun, sim.status().message());
  // The whole webmap, FastSLAM 2.0, 100 particles, one thread.
  std::vector<double> whole, filter_times;
  for (int r = 0; r < options.repeats; ++r) {
    FastSlamConfig config;
    config.threads = 1;
    auto slam = FastSlam::Create(config);
    if (!slam.ok()) return Fail(kExitUsage, slam.status().message());
    auto t0 = Clock::now();
    s = FeedSimulation(*sim, slam->get());
    whole.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    if (!s.ok()) return Fail(kExitRun, s.message());
    filter_times.push_back((*slam)->Summary().filter_s());
  }
  std::vector<std::vector<std::string>> rows;
  nlohmann::json points = nlohmann::json::array();
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::map<int64_t, double> one_thread_rate;
  for (int64_t n = 100; n <= options.max_particles; n *= 10) {
    for (int threads = 1; threads <= cores; ++threads) {
      FastSlamConfig config;
      config.particles = n;
      config.threads = threads;
      config.batch = 64;
      auto slam = FastSlam::Create(config);
      if (!slam.ok()) return Fail(kExitUsage, slam.status().message());
      FeedTimes times;
      s = FeedSimulation(*sim, slam->get(), static_cast<size_t>(options.controls), &times);
      if (!s.ok()) return Fail(kExitRun, s.message());
      const FastSlamSummary summary = (*slam)->Summary();
      const double control_rate = summary.controls * static_cast<double>(n) / times.control_s;
      const double scan_rate = summary.scans * static_cast<double>(n) / times.scan_s;
      const double total = (times.control_s + times.scan_s);
      const double rate = static_cast<double>(summary.steps) * n / total;
      if (threads == 1) one_thread_rate[n] = rate;
      const double speedup = rate / one_thread_rate[n];
      rows.push_back({std::to_string(n), std::to_string(threads),
                      fmt::format("{:.3g}", control_rate), fmt::format("{:.3g}", scan_rate),
                      fmt::format("{:.3g}", rate), fmt::format("{:.2f}", speedup),
                      fmt::format("{:.2f}", total)});
      points.push_back({{"particles", n},
                        {"threads", threads},
                        {"controls", summary.controls},
                        {"scans", summary.scans},
                        {"control_s", times.control_s},
                        {"scan_s", times.scan_s},
                        {"control_particle_steps_per_s", control_rate},
                        {"scan_particle_steps_per_s", scan_rate},
                        {"speedup_over_one_thread", speedup}});
      std::fprintf(stderr, "%lld particles x %d threads: %.3g particle-steps/s\n",
                   static_cast<long long>(n), threads, rate);
    }
  }
  const std::string md = fmt::format(
      "# FastSLAM speed\n\nMachine: {}\n\n## The whole webmap\n\nFastSLAM 2.0, 100 particles, one "
      "thread, seed 1: {} control steps, {} scans. Wall time of the run (simulation excluded), "
      "median of {}: **{:.3f} s** (filter phases: {:.3f} s).\n\n## Throughput\n\nFastSLAM 2.0 on "
      "the first {} control rows of the webmap (seed 1). Particle-steps per second, control steps "
      "(predictions) and scan steps (weighting, resampling, drawing and map updates) counted "
      "apart; all: every filter step over the time of both.\n\n{}",
      MachineDescription(), sim->controls.size(), sim->scan_times_s.size(), options.repeats,
      Median(whole), Median(filter_times), options.controls,
      MarkdownTable({"particles", "threads", "control steps/s", "scan steps/s", "all steps/s",
                     "speed-up", "time (s)"},
                    rows));
  s = WriteFileAtomically(options.out_dir + "/fastslam_speed.json",
                          nlohmann::json{{"machine", MachineDescription()},
                                         {"grove", VersionJson()},
                                         {"whole_webmap_s", whole},
                                         {"whole_webmap_filter_s", filter_times},
                                         {"throughput", points}}
                              .dump(2));
  if (s.ok()) s = WriteFileAtomically(options.out_dir + "/fastslam_speed.md", md);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::printf("%s", md.c_str());
  return kExitOk;
}

int VictoriaParkBenchCommand(const VictoriaParkBenchOptions& options) {
  Status s = EnsureDirectory(options.out_dir);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  StatusOr<VictoriaParkData> data = ReadVictoriaPark(BundledVictoriaParkDir(), options.until_s);
  if (!data.ok()) return Fail(kExitInput, data.status().message());
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<std::vector<std::string>> rows;
  nlohmann::json points = nlohmann::json::array();
  for (const std::string& filter : options.filters) {
    FastSlamFilter kind;
    if (!FastSlamFilterFromName(filter, &kind)) {
      return Fail(kExitUsage,
                  fmt::format("--filters: {}: not a filter (fastslam1, fastslam2, ufastslam, "
                              "srcd, srcd_aided, srcd_pf, de_srcd)",
                              QuoteForMessage(filter)));
    }
    for (int64_t n : options.particles) {
      for (int threads : {1, cores}) {
        if (threads == 1 && cores > 1 && n > options.max_one_thread_particles) continue;
        if (threads == cores && cores == 1 && !rows.empty() && rows.back()[1] == "1") continue;
        const std::string result_path = fmt::format("{}/.park-{}", options.out_dir, getpid());
        std::fflush(nullptr);
        const pid_t pid = fork();
        if (pid < 0) return Fail(kExitRun, "fork failed");
        if (pid == 0) {
          FastSlamConfig config = VictoriaParkConfig();
          config.filter = kind;
          config.particles = n;
          config.threads = threads;
          auto slam = FastSlam::Create(config);
          if (!slam.ok()) _exit(10);
          VictoriaParkEvents events(&*data);
          FastSlamEvent e;
          const auto t0 = Clock::now();
          for (;;) {
            StatusOr<bool> more = events.Next(&e);
            if (!more.ok()) _exit(11);
            if (!*more) break;
            Status step =
                e.is_scan ? (*slam)->Scan(e.scan_t_s, e.scan)
                          : (*slam)->Control(e.control.t_s, e.control.v_mps, e.control.steer_rad);
            if (!step.ok()) {
              std::fprintf(stderr, "%s\n", step.message().c_str());
              _exit(12);
            }
          }
          const double run_s = std::chrono::duration<double>(Clock::now() - t0).count();
          StatusOr<GpsErrors> gps = CompareWithGps((*slam)->MeanTrajectory(), data->gps);
          if (!gps.ok()) _exit(13);
          const FastSlamSummary summary = (*slam)->Summary();
          const nlohmann::json j = {{"run_s", run_s},
                                    {"filter_s", summary.filter_s()},
                                    {"landmarks", summary.landmarks},
                                    {"gps_mean_m", gps->mean_m},
                                    {"gps_median_m", gps->median_m},
                                    {"gps_rmse_m", gps->rmse_m},
                                    {"gps_max_m", gps->max_m},
                                    {"gps_fixes", gps->fixes.size()}};
          _exit(WriteFileAtomically(result_path, j.dump()).ok() ? 0 : 14);
        }
        int status = 0;
        rusage usage{};
        wait4(pid, &status, 0, &usage);
        if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
          return Fail(kExitRun, fmt::format("{} with {} particles on {} threads failed (status {})",
                                            filter, n, threads, status));
        }
        std::ifstream in(result_path);
        const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
        std::remove(result_path.c_str());
        if (j.is_discarded()) return Fail(kExitRun, "a run's result could not be read");
        const double rss_mib = static_cast<double>(usage.ru_maxrss) / 1024.0;
        rows.push_back({filter, std::to_string(threads), std::to_string(n),
                        fmt::format("{:.2f}", j["gps_mean_m"].get<double>()),
                        fmt::format("{:.2f}", j["gps_median_m"].get<double>()),
                        fmt::format("{:.2f}", j["gps_rmse_m"].get<double>()),
                        std::to_string(j["landmarks"].get<int64_t>()),
                        fmt::format("{:.2f}", j["run_s"].get<double>()),
                        fmt::format("{:.0f}", rss_mib)});
        nlohmann::json point = j;
        point["filter"] = filter;
        point["particles"] = n;
        point["threads"] = threads;
        point["peak_rss_mib"] = rss_mib;
        points.push_back(point);
        std::fprintf(stderr, "%s, %lld particles, %d threads: %.2f s, GPS mean %.2f m\n",
                     filter.c_str(), static_cast<long long>(n), threads, j["run_s"].get<double>(),
                     j["gps_mean_m"].get<double>());
      }
    }
  }
  const std::string md = fmt::format(
      "# Victoria Park\n\nMachine: {}\n\n`grove fastslam victoria-park` defaults (guivant_nebot, "
      "the seed's noise, unknown association, evidence on), seed 1, {} controls and {} "
      "detections{}. Error of the weighted-mean path against GPS after a rigid alignment (every "
      "fix, GPS jumps included); landmarks in the heaviest map; run time of the filter (reading "
      "excluded); peak RSS of the process.\n\n{}",
      MachineDescription(), data->controls.size(), data->observations.size(),
      options.until_s < 1e9 ? fmt::format(" (up to {} s)", options.until_s) : std::string(),
      MarkdownTable({"filter", "threads", "particles", "GPS mean (m)", "median (m)", "RMSE (m)",
                     "landmarks", "time (s)", "peak RSS (MiB)"},
                    rows));
  s = WriteFileAtomically(
      options.out_dir + "/victoria_park.json",
      nlohmann::json{{"machine", MachineDescription()}, {"grove", VersionJson()}, {"runs", points}}
          .dump(2));
  if (s.ok()) s = WriteFileAtomically(options.out_dir + "/victoria_park.md", md);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::printf("%s", md.c_str());
  return kExitOk;
}

}  // namespace grove::tools

// `grove bench fastslam-accuracy`, `fastslam-speed`, `victoria-park` and `fastslam`
// (tools/bench/bench_commands.h).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "grove/config_json.h"
#include "grove/fastslam.h"
#include "tools/bench/bench_commands.h"
#include "tools/bench/bench_process.h"
#include "tools/io/atomic_file.h"
#include "tools/io/csv_reader.h"
#include "tools/io/fastslam_inputs.h"
#include "tools/io/output_set.h"
#include "tools/io/victoria_park.h"
#include "tools/report/chart.h"
#include "tools/report/report_tables.h"
#include "tools/run/fastslam_run.h"
#include "tools/sim/fastslam_simulator.h"

namespace grove::tools {

namespace {

using Clock = std::chrono::steady_clock;

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
  } else if (options.association == "sampled") {
    association = FastSlamAssociation::kSampled;
  } else if (options.association == "jcbb") {
    association = FastSlamAssociation::kJointCompatibility;
  } else if (options.association != "known") {
    return Fail(kExitUsage,
                fmt::format("--association = {}: must be known, ml, ml_exclusive, sampled or jcbb",
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
      // Control() records its step and the next Scan() runs the predictions: only the two
      // together are timed apart from the simulation.
      const double total = times.control_s + times.scan_s;
      const double particle_steps = static_cast<double>(summary.steps) * static_cast<double>(n);
      const double rate = particle_steps / total;
      if (threads == 1) one_thread_rate[n] = rate;
      const double speedup = rate / one_thread_rate[n];
      rows.push_back({std::to_string(n), std::to_string(threads), fmt::format("{:.3g}", rate),
                      fmt::format("{:.1f}", total * 1e9 / particle_steps),
                      fmt::format("{:.2f}", speedup), fmt::format("{:.3f}", total)});
      points.push_back({{"particles", n},
                        {"threads", threads},
                        {"controls", summary.controls},
                        {"scans", summary.scans},
                        {"time_s", total},
                        {"particle_steps_per_s", rate},
                        {"speedup_over_one_thread", speedup}});
      std::fprintf(stderr, "%lld particles x %d threads: %.3g particle-steps/s\n",
                   static_cast<long long>(n), threads, rate);
    }
  }
  const std::string md = fmt::format(
      "# FastSLAM speed\n\nMachine: {}\n\n## The whole webmap\n\nFastSLAM 2.0, 100 particles, one "
      "thread, seed 1: {} control steps, {} scans. Wall time of the run (simulation excluded), "
      "median of {}: **{:.3f} s** (filter phases: {:.3f} s).\n\n## Throughput\n\nFastSLAM 2.0 on "
      "the first {} control rows of the webmap (seed 1): particle-steps (controls and scans) per "
      "second of the filter's calls, simulation excluded.\n\n{}",
      MachineDescription(), sim->controls.size(), sim->scan_times_s.size(), options.repeats,
      Median(whole), Median(filter_times), options.controls,
      MarkdownTable({"particles", "threads", "particle-steps/s", "ns per particle-step", "speed-up",
                     "time (s)"},
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

int FastSlamBenchCommand(const FastSlamConfig& config, const FastSlamBenchOptions& options) {
  StatusOr<FastSlamInputReader> reader =
      FastSlamInputReader::Open(options.controls_path, options.observations_path, config);
  if (!reader.ok()) return Fail(kExitInput, reader.status().message());
  FastSlamConfig adapted = config;
  if (const std::string note = AdaptAssociationToIds(*reader, &adapted); !note.empty()) {
    std::fprintf(stderr, "%s\n", note.c_str());
  }
  std::vector<FastSlamEvent> events;
  FastSlamWorkload work;
  for (FastSlamEvent e;;) {
    StatusOr<bool> more = reader->Next(&e);
    if (!more.ok()) return Fail(kExitInput, more.status().message());
    if (!*more) break;
    if (e.is_scan) {
      ++work.scans;
      work.observations += static_cast<int64_t>(e.scan.size());
    } else {
      ++work.controls;
    }
    events.push_back(e);
  }
  if (events.empty()) {
    return Fail(kExitInput, fmt::format("{} and {}: no input", options.controls_path,
                                        options.observations_path));
  }
  const auto with = [&adapted](int64_t particles, int threads) {
    FastSlamConfig c = adapted;
    c.particles = particles;
    c.threads = threads;
    return c;
  };
  SweepBenchModel model{
      .command = "fastslam",
      .input =
          fmt::format("`{}` and `{}`: {} controls, {} scans, {} detections", options.controls_path,
                      options.observations_path, work.controls, work.scans, work.observations),
      .config_json = ConfigToJson(FastSlamConfigFields(), adapted),
      .defaults_json = ConfigToJson(FastSlamConfigFields(), FastSlamConfig()),
      .check = [&](int64_t particles, int threads) { return with(particles, threads).Validate(); },
      .predict_peak_bytes =
          [&](int64_t particles, int threads) {
            return FastSlam::EstimatePeakBytes(with(particles, threads), work);
          },
      .run = [&](int64_t particles, int threads) -> StatusOr<FilterSummary> {
        auto slam = FastSlam::Create(with(particles, threads));
        if (!slam.ok()) return slam.status();
        for (const FastSlamEvent& e : events) {
          GROVE_RETURN_IF_ERROR(FeedEvent(e, *reader, slam->get()));
        }
        return (*slam)->Summary();
      }};
  return RunSweepBench(model, options.sweep);
}

}  // namespace grove::tools

#include "tools/footslam_run.h"

#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string_view>
#include <vector>

#include "tools/atomic_file.h"
#include "tools/config_json.h"
#include "tools/csv_reader.h"
#include "tools/map_render.h"
#include "tools/output_readers.h"
#include "tools/progress_reporter.h"
#include "tools/step_reader.h"
#include "tools/trajectory_metrics.h"
#include "tools/walk_simulator.h"

namespace grove::tools {
namespace {

int Fail(int code, const std::string& message) {
  std::fprintf(stderr, "grove: error: %s\n", message.c_str());
  return code;
}

// The exit code of a run's or an output's error. An error reading an input file (steps,
// checkpoint, truth, CSV) is kExitInput whatever its code.
int ExitCodeOf(const Status& s) {
  switch (s.code()) {
    case StatusCode::kInvalidArgument:
    case StatusCode::kNotFound:
    case StatusCode::kDataLoss:
      return kExitInput;
    case StatusCode::kIoError:
    case StatusCode::kResourceExhausted:
      return kExitOutput;
    case StatusCode::kOutOfRange:
    case StatusCode::kFailedPrecondition:
      return kExitRun;
    default:
      return kExitInternal;
  }
}

std::string MapCsv(const std::vector<HexCounts>& hexes, bool integer_counts) {
  std::string out = "q,r,x,y,c0,c1,c2,c3,c4,c5\n";
  out.reserve(hexes.size() * 64 + out.size());
  for (const HexCounts& h : hexes) {
    fmt::format_to(std::back_inserter(out), "{},{},{:.4f},{:.4f}", h.q, h.r, h.x_m, h.y_m);
    for (double c : h.counts) {
      if (integer_counts) {
        fmt::format_to(std::back_inserter(out), ",{}", static_cast<int64_t>(c));
      } else {
        fmt::format_to(std::back_inserter(out), ",{:.9g}", c);
      }
    }
    out += '\n';
  }
  return out;
}

std::string TrajectoryCsv(const std::vector<StampedPose>& poses) {
  std::string out = "t,x,y,heading\n";
  for (const StampedPose& p : poses) {
    fmt::format_to(std::back_inserter(out), "{:.6f},{:.6f},{:.6f},{:.6f}\n", p.t_s, p.pose.x_m,
                   p.pose.y_m, p.pose.heading_rad);
  }
  return out;
}

int64_t CountLines(std::string_view text) {
  return static_cast<int64_t>(std::count(text.begin(), text.end(), '\n'));
}

int64_t CountFileLines(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> buffer(1 << 20);
  int64_t lines = 0;
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    lines += CountLines(std::string_view(buffer.data(), static_cast<size_t>(in.gcount())));
  }
  return lines;
}

int64_t PeakRssBytes() {
  struct rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<int64_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

nlohmann::json MemoryJson(const MemoryUse& m) {
  return {{"live_nodes", m.live_nodes},
          {"live_bytes", m.live_bytes},
          {"peak_live_nodes", m.peak_live_nodes},
          {"peak_live_bytes", m.peak_live_bytes},
          {"reserved_bytes", m.reserved_bytes}};
}

MapImage MakeImage(const FootSlamConfig& config, const std::vector<HexCounts>& map,
                   const std::vector<StampedPose>& path, const std::vector<RenderPoint>& odometry,
                   const std::string& title) {
  MapImage image;
  image.hex_radius_m = config.hex_radius_m;
  for (const HexCounts& h : map) {
    double use = 0;
    for (double c : h.counts) use += c;
    image.hexes.push_back({h.q, h.r, use});
  }
  for (const StampedPose& p : path) image.path.push_back({p.pose.x_m, p.pose.y_m});
  image.odometry = odometry;
  image.title = title;
  return image;
}

// The signal that asked the run to stop (0: none). A signal handler may only store to a
// lock-free atomic; the step loop reads it between steps.
std::atomic<int> g_stop_signal{0};
static_assert(std::atomic<int>::is_always_lock_free);

extern "C" void OnStopSignal(int signal) { g_stop_signal.store(signal, std::memory_order_relaxed); }

// Installs the stop handler for SIGINT and SIGTERM while alive; the first signal asks for a
// stop at the next step boundary, a second one kills as usual (SA_RESETHAND).
class StopSignals {
 public:
  StopSignals() {
    g_stop_signal.store(0);
    struct sigaction action = {};
    action.sa_handler = OnStopSignal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND | SA_RESTART;  // interrupted reads and writes resume
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
  }
  ~StopSignals() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  int received() const { return g_stop_signal.load(std::memory_order_relaxed); }

 private:
  struct sigaction old_int_ = {};
  struct sigaction old_term_ = {};
};

// A string from a file, quoted and escaped (JSON style) so an error stays on one line.
std::string QuotedForError(const std::string& text) {
  return nlohmann::json(text.substr(0, 200))
      .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

// Where the run stands in its step file: kept in each checkpoint so a resumed run can check
// that it reads the same steps.
struct InputPosition {
  std::string steps_name;
  int64_t steps = 0;
  uint32_t digest = 0;  // CRC-32 of the (t, dx, dy) of every step so far

  void Add(const StepRecord& step) {
    const double v[3] = {step.t_s, step.dx_m, step.dy_m};
    digest = static_cast<uint32_t>(crc32(digest, reinterpret_cast<const Bytef*>(v), sizeof(v)));
    ++steps;
  }
  std::string ToJson() const {
    return nlohmann::json{{"steps_file", steps_name}, {"steps", steps}, {"digest", digest}}.dump();
  }
  static StatusOr<InputPosition> FromJson(const std::string& text, const std::string& name) {
    InputPosition p;
    try {
      nlohmann::json j = nlohmann::json::parse(text);
      p.steps_name = j.at("steps_file").get<std::string>();
      p.steps = j.at("steps").get<int64_t>();
      p.digest = j.at("digest").get<uint32_t>();
    } catch (const nlohmann::json::exception& e) {
      return DataLossError(
          fmt::format("{}: the input position is unreadable: {}", name, QuotedForError(e.what())));
    }
    return p;
  }
};

}  // namespace

StatusOr<int64_t> ParseMemorySize(const std::string& text) {
  double value = 0;
  const char* begin = text.data();
  const char* end = begin + text.size();
  auto [ptr, ec] = std::from_chars(begin, end, value);
  double scale = 1;
  if (ec == std::errc() && ptr + 1 == end) {
    switch (*ptr) {
      case 'K':
      case 'k':
        scale = 1024.0;
        break;
      case 'M':
      case 'm':
        scale = 1024.0 * 1024;
        break;
      case 'G':
      case 'g':
        scale = 1024.0 * 1024 * 1024;
        break;
      case 'T':
      case 't':
        scale = 1024.0 * 1024 * 1024 * 1024;
        break;
      default:
        ec = std::errc::invalid_argument;
    }
  } else if (ptr != end) {
    ec = std::errc::invalid_argument;
  }
  double bytes = value * scale;
  if (ec != std::errc() || !std::isfinite(bytes) || bytes < 1 || bytes > 9.0e18) {
    return InvalidArgumentError(fmt::format(
        "--memory-budget = \"{}\": must be a size such as 512M, 8G or 1073741824", text));
  }
  return static_cast<int64_t>(bytes);
}

int64_t AvailableMemoryBytes() {
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  int64_t kib = 0;
  std::string unit;
  while (meminfo >> key >> kib >> unit) {
    if (key == "MemAvailable:") return kib * 1024;
  }
  return 0;
}

int RunFootSlamCommand(const FootSlamConfig& config, const RunOptions& options) {
  auto wall_start = std::chrono::steady_clock::now();
  if (Status s = config.Validate(); !s.ok()) return Fail(kExitUsage, s.message());
  if (options.out_dir.empty()) return Fail(kExitUsage, "--out: an output directory is required");

  StepReaderOptions reader_options;
  reader_options.max_step_m = options.max_step_m;
  std::string steps_name = options.steps_path.empty() ? EmbeddedWalkName() : options.steps_path;
  StatusOr<StepReader> reader =
      options.steps_path.empty()
          ? StepReader::OpenText(EmbeddedWalkName(), EmbeddedWalkSteps(), reader_options)
          : StepReader::Open(options.steps_path, reader_options);
  if (!reader.ok()) return Fail(kExitInput, reader.status().message());

  // Refuse a run that would not fit before building anything.
  const int64_t lines = options.steps_path.empty() ? CountLines(EmbeddedWalkSteps())
                                                   : CountFileLines(options.steps_path);
  const int64_t budget =
      options.memory_budget_bytes > 0 ? options.memory_budget_bytes : AvailableMemoryBytes();
  const int64_t predicted = FootSlam::EstimatePeakBytes(config, std::max<int64_t>(lines - 1, 0));
  if (budget > 0 && predicted > budget) {
    return Fail(
        kExitMemory,
        fmt::format("the run is predicted to need {:.1f} MiB ({} particles, {} map, {} "
                    "steps), more than the {} of {:.1f} MiB; use fewer particles or raise "
                    "--memory-budget",
                    predicted / 1048576.0, config.particles, FootSlamMapKindName(config.map),
                    std::max<int64_t>(lines - 1, 0),
                    options.memory_budget_bytes > 0 ? "--memory-budget" : "memory available",
                    budget / 1048576.0));
  }

  // A new engine, or one continuing from a checkpoint.
  InputPosition resumed_at;
  StatusOr<std::unique_ptr<FootSlam>> created =
      options.resume_path.empty() ? FootSlam::Create(config)
                                  : StatusOr<std::unique_ptr<FootSlam>>(InternalError("unset"));
  if (!options.resume_path.empty()) {
    StatusOr<std::string> bytes = ReadWholeFile(options.resume_path);
    if (!bytes.ok()) return Fail(kExitInput, bytes.status().message());
    std::string user;
    created = FootSlam::Resume(config, *bytes, options.resume_path, &user);
    if (!created.ok()) {
      return Fail(created.status().code() == StatusCode::kFailedPrecondition
                      ? kExitUsage
                      : ExitCodeOf(created.status()),
                  created.status().message());
    }
    StatusOr<InputPosition> at = InputPosition::FromJson(user, options.resume_path);
    if (!at.ok()) return Fail(kExitInput, at.status().message());
    resumed_at = *at;
  }
  if (!created.ok()) return Fail(kExitUsage, created.status().message());
  FootSlam& slam = **created;
  const std::string checkpoint_path = options.checkpoint_path.empty()
                                          ? options.out_dir + "/checkpoint.grove"
                                          : options.checkpoint_path;
  InputPosition position;
  position.steps_name = steps_name;
  int64_t checkpoints_written = 0, checkpoint_bytes = 0;
  double checkpoint_s = 0;
  auto write_checkpoint = [&]() -> Status {
    auto t0 = std::chrono::steady_clock::now();
    StatusOr<std::string> bytes = slam.Checkpoint(position.ToJson());
    if (!bytes.ok()) return bytes.status();
    if (options.checkpoint_path.empty()) GROVE_RETURN_IF_ERROR(EnsureDirectory(options.out_dir));
    GROVE_RETURN_IF_ERROR(WriteFileAtomically(checkpoint_path, *bytes));
    ++checkpoints_written;
    checkpoint_bytes = static_cast<int64_t>(bytes->size());
    checkpoint_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return Status::Ok();
  };
  StopSignals signals;

  // The progress total: lines after the header (comments and blank lines make it an estimate).
  const bool terminal = isatty(fileno(stderr)) != 0;
  int64_t total_steps = lines - 1;
  if (reader->positions_form()) --total_steps;
  ProgressReporter progress(std::max<int64_t>(total_steps, 0), config.particles, stderr, terminal);
  // The raw odometry drawn in the map frame: rotated by the configured start heading.
  std::vector<RenderPoint> odometry{{config.start_x_m, config.start_y_m}};
  auto add_odometry = [&](const StepRecord& step) {
    double c = std::cos(config.start_heading_rad), sn = std::sin(config.start_heading_rad);
    odometry.push_back({odometry.back().x_m + c * step.dx_m - sn * step.dy_m,
                        odometry.back().y_m + sn * step.dx_m + c * step.dy_m});
  };
  bool start_set = slam.steps() > 0;
  StepRecord step;
  while (true) {
    if (int signal = signals.received(); signal != 0) {
      if (position.steps < resumed_at.steps) {  // still re-reading: nothing new to save
        std::fprintf(stderr, "\ngrove: stopped by %s before any new step; %s is unchanged\n",
                     strsignal(signal), options.resume_path.c_str());
        return kExitSignalBase + signal;
      }
      Status s = write_checkpoint();
      if (!s.ok()) return Fail(kExitOutput, s.message());
      std::fprintf(stderr,
                   "\ngrove: stopped by %s after step %lld: wrote %s; continue with the same "
                   "command and --resume %s\n",
                   strsignal(signal), static_cast<long long>(slam.steps()), checkpoint_path.c_str(),
                   checkpoint_path.c_str());
      return kExitSignalBase + signal;
    }
    StatusOr<bool> more = reader->Next(&step);
    if (!more.ok()) return Fail(kExitInput, more.status().message());
    if (!*more) break;
    // The steps a resumed run has taken already: re-read to check them and to redraw the
    // odometry, not stepped again.
    const bool replay = position.steps < resumed_at.steps;
    position.Add(step);
    if (replay && position.steps == resumed_at.steps && position.digest != resumed_at.digest) {
      return Fail(kExitInput,
                  fmt::format("{}: the first {} steps differ from those of {} (made from {}): "
                              "resume with the same step file",
                              steps_name, resumed_at.steps, options.resume_path,
                              QuotedForError(resumed_at.steps_name)));
    }
    if (replay) {
      add_odometry(step);
      continue;
    }
    if (!start_set) {
      Status st = slam.SetStartTime(reader->start_time_s());
      if (!st.ok()) return Fail(kExitInput, fmt::format("{}: {}", steps_name, st.message()));
      start_set = true;
    }
    Status s = slam.Step(step.t_s, step.dx_m, step.dy_m);
    if (!s.ok()) {
      return Fail(ExitCodeOf(s), fmt::format("{}:{}: {}", steps_name, step.line, s.message()));
    }
    add_odometry(step);
    if (options.progress) progress.Update(slam.steps());
    if (options.checkpoint_every > 0 && slam.steps() % options.checkpoint_every == 0) {
      Status cs = write_checkpoint();
      if (!cs.ok()) return Fail(ExitCodeOf(cs), cs.message());
    }
  }
  if (position.steps < resumed_at.steps) {
    return Fail(kExitInput,
                fmt::format("{}: has {} steps, but {} was made after step {}: resume "
                            "with the same step file",
                            steps_name, position.steps, options.resume_path, resumed_at.steps));
  }
  if (slam.steps() == 0) return Fail(kExitInput, fmt::format("{}: no steps", steps_name));
  if (options.progress) progress.Finish();

  // Every output is built in memory and written under a temporary name, then renamed.
  StatusOr<std::vector<HexCounts>> cumulative_or = slam.CumulativeMap();
  StatusOr<std::vector<HexCounts>> best_map_or = slam.HeaviestMap();
  StatusOr<std::vector<StampedPose>> trajectory_or = slam.HeaviestTrajectory();
  for (const Status* st :
       {&cumulative_or.status(), &best_map_or.status(), &trajectory_or.status()}) {
    if (!st->ok()) return Fail(ExitCodeOf(*st), st->message());
  }
  const std::vector<HexCounts>& cumulative = *cumulative_or;
  const std::vector<HexCounts>& best_map = *best_map_or;
  const std::vector<StampedPose>& trajectory = *trajectory_or;
  FootSlamSummary summary = slam.Summary();
  double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  double filter_s = summary.advance_s + summary.normalize_s + summary.resample_s +
                    summary.release_s + summary.bookkeeping_s;
  nlohmann::json report = {
      {"inputs", {{"steps", steps_name}, {"steps_read", slam.steps()}}},
      {"config", ConfigToJson(FootSlamConfigFields(), config)},
      {"particles", config.particles},
      {"steps", slam.steps()},
      {"threads_requested", summary.threads_requested},
      {"threads_used", summary.threads_used},
      {"wall_time_s", wall_s},
      {"filter_time_s", filter_s},
      {"particle_steps_per_s", filter_s > 0 ? config.particles * slam.steps() / filter_s : 0.0},
      {"ns_per_particle_step",
       slam.steps() > 0 ? filter_s * 1e9 / (config.particles * slam.steps()) : 0.0},
      {"phases_s",
       {{"advance", summary.advance_s},
        {"normalize", summary.normalize_s},
        {"resample", summary.resample_s},
        {"release", summary.release_s},
        {"bookkeeping", summary.bookkeeping_s}}},
      {"peak_rss_bytes", PeakRssBytes()},
      {"predicted_peak_bytes", predicted},
      {"map_memory", MemoryJson(summary.map_memory)},
      {"trajectory_memory", MemoryJson(summary.trajectory_memory)},
      {"resamplings", summary.resamplings},
      {"mean_ess", summary.mean_ess},
      {"mean_scale", summary.mean_scale},
      {"mean_heading_error_rad", summary.mean_heading_error_rad},
      {"hexagons", {{"cumulative", cumulative.size()}, {"heaviest", best_map.size()}}},
      {"checkpoints",
       {{"written", checkpoints_written},
        {"seconds", checkpoint_s},
        {"last_bytes", checkpoint_bytes},
        {"resumed_from", options.resume_path},
        {"resumed_at_step", resumed_at.steps}}},
  };
  const std::string& dir = options.out_dir;
  Status s = EnsureDirectory(dir);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  MapImage image = MakeImage(config, cumulative, trajectory, odometry,
                             fmt::format("FootSLAM, {} particles, {} steps: cumulative map, "
                                         "heaviest particle's path, raw odometry",
                                         config.particles, slam.steps()));
  for (auto [name, text] :
       {std::pair<const char*, std::string>{"map.csv", MapCsv(cumulative, false)},
        {"map_best.csv", MapCsv(best_map, true)},
        {"trajectory.csv", TrajectoryCsv(trajectory)},
        {"mean_trajectory.csv", TrajectoryCsv(slam.MeanTrajectory())}}) {
    s = WriteFileAtomically(dir + "/" + name, text);
    if (!s.ok()) return Fail(kExitOutput, s.message());
  }
  s = WriteMapImages(dir + "/map.png", dir + "/map.svg", image);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  s = WriteFileAtomically(dir + "/summary.json", report.dump(2) + "\n");
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::fprintf(stderr,
               "%s\nwrote %s/{map.csv, map_best.csv, trajectory.csv, "
               "mean_trajectory.csv, map.png, map.svg, summary.json}\n",
               summary.BriefReport().c_str(), dir.c_str());
  return kExitOk;
}

int SimulateCommand(const std::string& out_dir, double minutes, uint64_t seed,
                    const std::string& scenario, double heading_drift, double scale_error) {
  SimulatorOptions options;
  options.minutes = minutes;
  options.seed = seed;
  if (heading_drift >= 0) options.heading_drift_rad_per_sqrt_step = heading_drift;
  if (scale_error > -1) options.scale_error = scale_error;
  if (scenario == "building") {
    options.scenario = Scenario::kBuilding;
  } else if (scenario == "open") {
    options.scenario = Scenario::kOpen;
  } else {
    return Fail(kExitUsage, fmt::format("--scenario = {}: must be building or open", scenario));
  }
  StatusOr<SimulatedWalk> walk = SimulateWalk(options);
  if (!walk.ok()) return Fail(kExitUsage, walk.status().message());
  Status s = EnsureDirectory(out_dir);
  if (s.ok()) s = WriteFileAtomically(out_dir + "/steps.csv", StepsCsv(*walk));
  if (s.ok()) s = WriteFileAtomically(out_dir + "/truth.csv", TruthCsv(*walk));
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::fprintf(stderr, "wrote %s/steps.csv and %s/truth.csv: %zu steps\n", out_dir.c_str(),
               out_dir.c_str(), walk->steps.size());
  return kExitOk;
}

int EvaluateCommand(const std::string& truth_path, const std::string& trajectory_path) {
  auto truth = ReadTimedPoints(truth_path);
  if (!truth.ok()) return Fail(kExitInput, truth.status().message());
  auto estimate = ReadTimedPoints(trajectory_path);
  if (!estimate.ok()) return Fail(kExitInput, estimate.status().message());
  auto error = CompareTrajectories(*truth, *estimate);
  if (!error.ok()) return Fail(kExitInput, error.status().message());
  std::printf("%s\n", TrajectoryErrorJson(*error).c_str());
  return kExitOk;
}

int RenderCommand(const std::string& dir, double hex_radius_m, const std::string& odometry_path) {
  auto hexes = ReadMapCsv(dir + "/map.csv");
  if (!hexes.ok()) return Fail(kExitInput, hexes.status().message());
  auto path = ReadPathCsv(dir + "/trajectory.csv");
  if (!path.ok()) return Fail(kExitInput, path.status().message());
  MapImage image;
  image.hex_radius_m = hex_radius_m;
  image.hexes = std::move(*hexes);
  image.path = std::move(*path);
  if (!odometry_path.empty()) {
    auto steps = ReadAllSteps(odometry_path);
    if (!steps.ok()) return Fail(kExitInput, steps.status().message());
    image.odometry.push_back({0, 0});
    for (const StepRecord& s : *steps) {
      image.odometry.push_back(
          {image.odometry.back().x_m + s.dx_m, image.odometry.back().y_m + s.dy_m});
    }
  }
  image.title = "FootSLAM map (redrawn from " + dir + ")";
  Status s = WriteMapImages(dir + "/map.png", dir + "/map.svg", image);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  return kExitOk;
}

}  // namespace grove::tools

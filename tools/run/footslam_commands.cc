// `grove footslam simulate`, `evaluate` and `render`.
#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "tools/io/atomic_file.h"
#include "tools/io/csv_reader.h"
#include "tools/io/footslam_outputs.h"
#include "tools/io/output_readers.h"
#include "tools/io/step_reader.h"
#include "tools/report/map_render.h"
#include "tools/report/trajectory_metrics.h"
#include "tools/run/footslam_run.h"
#include "tools/sim/walk_simulator.h"

namespace grove::tools {

int SimulateCommand(const SimulateOptions& o) {
  if (o.out_dir.empty()) return Fail(kExitUsage, "--out: the path is empty");
  SimulatorOptions options;
  options.minutes = o.minutes;
  options.seed = o.seed;
  if (o.heading_drift_given) options.heading_drift_rad_per_sqrt_step = o.heading_drift;
  if (o.scale_error_given) options.scale_error = o.scale_error;
  if (o.scenario == "building") {
    options.scenario = Scenario::kBuilding;
  } else if (o.scenario == "open") {
    options.scenario = Scenario::kOpen;
  } else if (o.scenario == "campus") {
    options.scenario = Scenario::kCampus;
  } else {
    return Fail(kExitUsage, fmt::format("--scenario = {}: must be building, open or campus",
                                        QuoteForMessage(o.scenario)));
  }
  StatusOr<SimulatedWalk> walk = SimulateWalk(options);
  if (!walk.ok()) return Fail(kExitUsage, walk.status().message());
  if (walk->steps.empty()) {
    return Fail(kExitUsage,
                fmt::format("--minutes = {}: the walk is shorter than one step", o.minutes));
  }
  Status s = EnsureDirectory(o.out_dir);
  if (s.ok()) s = WriteFileAtomically(o.out_dir + "/steps.csv", StepsCsv(*walk));
  if (s.ok()) s = WriteFileAtomically(o.out_dir + "/truth.csv", TruthCsv(*walk));
  if (!s.ok()) return Fail(kExitOutput, s.message());
  std::fprintf(stderr, "wrote %s/steps.csv and %s/truth.csv: %zu steps\n", o.out_dir.c_str(),
               o.out_dir.c_str(), walk->steps.size());
  if (o.imu) {
    StatusOr<int64_t> samples = WriteSimulatedImu(*walk, o.imu_options, o.out_dir);
    if (!samples.ok()) {
      return Fail(
          samples.status().code() == StatusCode::kInvalidArgument ? kExitUsage : kExitOutput,
          samples.status().message());
    }
    std::fprintf(stderr, "wrote %s/imu.csv and %s/stances.csv: %lld samples at %g Hz\n",
                 o.out_dir.c_str(), o.out_dir.c_str(), static_cast<long long>(*samples),
                 o.imu_options.rate_hz);
  }
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
  // The run's own radius and start pose, from its summary.json when there is one.
  double radius = 0.5;
  Pose2 start;
  if (StatusOr<std::string> text = ReadWholeFile(dir + "/summary.json"); text.ok()) {
    try {
      const nlohmann::json config = nlohmann::json::parse(*text).at("config");
      radius = config.at("hex_radius_m").get<double>();
      start = {config.at("start_x_m").get<double>(), config.at("start_y_m").get<double>(),
               config.at("start_heading_rad").get<double>()};
    } catch (const nlohmann::json::exception& e) {
      return Fail(kExitInput, fmt::format("{}/summary.json: not a run summary: {}", dir,
                                          QuoteForMessage(e.what(), 200)));
    }
  }
  if (hex_radius_m > 0) radius = hex_radius_m;
  if (!(radius > 0) || !std::isfinite(radius)) {
    return Fail(kExitUsage, fmt::format("--hex-radius = {}: must be > 0", radius));
  }
  auto hexes = ReadMapCsv(dir + "/map.csv");
  if (!hexes.ok()) return Fail(kExitInput, hexes.status().message());
  // The smoothed path, as the run drew it (runs before it existed: the heaviest particle's).
  std::string path_file = dir + "/smoothed_trajectory.csv";
  if (std::error_code ec; !std::filesystem::exists(path_file, ec))
    path_file = dir + "/trajectory.csv";
  auto path = ReadPathCsv(path_file);
  if (!path.ok()) return Fail(kExitInput, path.status().message());
  MapImage image;
  image.hex_radius_m = radius;
  image.hexes = std::move(*hexes);
  image.path = std::move(*path);
  if (path_file.ends_with("smoothed_trajectory.csv")) image.path_label = "smoothed path";
  if (!odometry_path.empty()) {
    auto steps = ReadAllSteps(odometry_path);
    if (!steps.ok()) return Fail(kExitInput, steps.status().message());
    OdometryPath odometry(start);
    for (const StepRecord& s : *steps) odometry.Add(s.dx_m, s.dy_m);
    image.odometry = odometry.points();
  }
  image.title = "FootSLAM map (redrawn from " + dir + ")";
  Status s = WriteMapImages(dir + "/map.png", dir + "/map.svg", image);
  if (!s.ok()) return Fail(kExitOutput, s.message());
  return kExitOk;
}

}  // namespace grove::tools

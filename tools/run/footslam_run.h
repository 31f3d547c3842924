// The `grove footslam` commands: run (on the generic run loop), simulate, evaluate and render.
#ifndef GROVE_TOOLS_RUN_FOOTSLAM_RUN_H_
#define GROVE_TOOLS_RUN_FOOTSLAM_RUN_H_

#include <cstdint>
#include <string>

#include "grove/foot_imu.h"
#include "grove/footslam.h"
#include "grove/status.h"
#include "tools/io/imu_reader.h"
#include "tools/io/step_reader.h"
#include "tools/run/foot_imu_commands.h"
#include "tools/run/run_loop.h"

namespace grove::tools {

// Options of `grove footslam run` beyond the configuration.
struct FootSlamRunOptions {
  RunOptions run;
  std::string steps_path;      // empty: the walk bundled in the binary
  double max_step_m = 5.0;     // longer steps in the input are rejected
  std::string prior_map_path;  // a map.csv of an earlier walk (FootSlam::SetPriorMap); empty: none
  // The true path (tools/io/truth_trajectory.h): the smoothed path is scored against it; empty:
  // none.
  std::string truth_path;
  // An IMU recording instead of a step file: its steps come from the foot IMU front end.
  std::string imu_path;
  FootImuConfig imu_config;
  ImuReaderOptions imu_reader;
};

// Runs FootSLAM and writes every output; returns an exit code after printing any error to
// stderr as one line.
int RunFootSlamCommand(const FootSlamConfig& config, const FootSlamRunOptions& options);

// Feeds `step`, read from `input_name`, to `slam`, after setting the walk's start time
// `start_time_s` when it is the first step; an error names the file and line (`grove footslam
// run`'s messages).
Status FeedStep(const StepRecord& step, const std::string& input_name, double start_time_s,
                FootSlam* slam);

// Bytes the grove command itself keeps per step of a run (odometry, outputs built in memory),
// on top of FootSlam::EstimatePeakBytes.
inline constexpr int64_t kCommandBytesPerStep = 400;

struct SimulateOptions {
  std::string out_dir;
  double minutes = 8;
  uint64_t seed = 1;
  std::string scenario = "building";
  bool heading_drift_given = false;  // else the simulator's default
  double heading_drift = 0;
  bool scale_error_given = false;
  double scale_error = 0;
  bool imu = false;  // also imu.csv and stances.csv
  SimulateImuOptions imu_options;
};
// `grove footslam simulate`.
int SimulateCommand(const SimulateOptions& options);
// `grove footslam evaluate`: prints the JSON report to stdout.
int EvaluateCommand(const std::string& truth_path, const std::string& trajectory_path);
// `grove footslam render`: map.png and map.svg from the CSV outputs in `dir`; the hexagon
// radius and start pose come from dir/summary.json when it is there, `hex_radius_m` > 0
// overrides it.
int RenderCommand(const std::string& dir, double hex_radius_m, const std::string& odometry_path);

// The walk bundled in the binary (tools/data/building_walk_steps.csv) and its name.
const char* EmbeddedWalkName();
std::string EmbeddedWalkSteps();

}  // namespace grove::tools

#endif  // GROVE_TOOLS_RUN_FOOTSLAM_RUN_H_

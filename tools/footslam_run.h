// The `grove footslam` commands: run, simulate, evaluate and render.
#ifndef GROVE_TOOLS_FOOTSLAM_RUN_H_
#define GROVE_TOOLS_FOOTSLAM_RUN_H_

#include <cstdint>
#include <optional>
#include <string>

#include "grove/footslam.h"
#include "grove/status.h"

namespace grove::tools {

// Exit codes of the grove command (documented in the README).
enum ExitCode : int {
  kExitOk = 0,
  kExitInternal = 1,  // a bug: please report
  kExitUsage = 2,     // bad command line or configuration
  kExitInput = 3,     // bad input file (steps, truth, CSV)
  kExitRun = 4,       // the run itself failed: left the grid, filter degenerated
  kExitOutput = 5,    // outputs could not be written (earlier outputs are left intact)
  kExitMemory = 6,    // the predicted memory exceeds --memory-budget; nothing was run
  // 128 + the signal (130 for SIGINT, 143 for SIGTERM): stopped at a step boundary by the
  // signal after writing a checkpoint.
  kExitSignalBase = 128,
};

// Parses a memory size: a number of bytes with an optional binary suffix K, M, G or T
// ("512M", "1.5G", "1073741824"). InvalidArgument naming the text otherwise.
StatusOr<int64_t> ParseMemorySize(const std::string& text);
// MemAvailable from /proc/meminfo, or 0 when it cannot be read.
int64_t AvailableMemoryBytes();

// Options of `grove footslam run` that are not part of FootSlamConfig.
struct RunOptions {
  std::string steps_path;  // empty: the walk bundled in the binary
  std::string out_dir;
  bool progress = true;             // progress on stderr
  double max_step_m = 5.0;          // longer steps in the input are rejected
  int64_t memory_budget_bytes = 0;  // refuse runs predicted to need more; 0: the memory available
  int64_t checkpoint_every = 0;     // steps between checkpoints; 0: only when stopped by a signal
  std::string checkpoint_path;      // empty: out_dir + "/checkpoint.grove"
  std::string resume_path;          // continue from this checkpoint
};

// Runs FootSLAM and writes every output; returns an exit code after printing any error to
// stderr as one line.
int RunFootSlamCommand(const FootSlamConfig& config, const RunOptions& options);

// `grove footslam simulate`: `heading_drift` and `scale_error` < 0 keep the simulator defaults.
int SimulateCommand(const std::string& out_dir, double minutes, uint64_t seed,
                    const std::string& scenario, double heading_drift, double scale_error);
// `grove footslam evaluate`: prints the JSON report to stdout.
int EvaluateCommand(const std::string& truth_path, const std::string& trajectory_path);
// `grove footslam render`: map.png and map.svg from the CSV outputs in `dir`.
int RenderCommand(const std::string& dir, double hex_radius_m, const std::string& odometry_path);

// The walk bundled in the binary (tools/data/building_walk_steps.csv) and its name.
const char* EmbeddedWalkName();
std::string EmbeddedWalkSteps();

}  // namespace grove::tools

#endif  // GROVE_TOOLS_FOOTSLAM_RUN_H_

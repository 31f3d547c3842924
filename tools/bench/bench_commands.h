// The `grove bench` commands: the paper's run-time and memory figures (Garcia Puyol et al.,
// Figs. 9 and 10), throughput across cores and particle counts, FastSLAM's accuracy and speed on
// Bailey's webmap and Victoria Park, and either filter's speed on the user's own input.
#ifndef GROVE_TOOLS_BENCH_BENCH_COMMANDS_H_
#define GROVE_TOOLS_BENCH_BENCH_COMMANDS_H_

#include <cstdint>
#include <string>
#include <vector>

#include "grove/fastslam.h"
#include "grove/footslam.h"
#include "tools/bench/sweep_bench.h"

namespace grove::tools {

struct PaperBenchOptions {
  std::string out_dir;
  int64_t particles = 30000;
  double minutes = 13;         // length of the simulated open-area walk
  int threads = 0;             // 0: all cores
  double naive_limit_s = 180;  // the naive run stops after this much run time
  std::string only;            // run only the configuration with this name (empty: all)
  int repeat = 1;              // runs per configuration; the median run is reported
  std::string grid = "fixed";  // "fixed" (the paper's) or "growing": what growth costs
};
int PaperBenchCommand(const PaperBenchOptions& options);
// The names of the configurations `bench paper` runs (what --only takes).
std::vector<std::string> PaperBenchConfigurations();

struct ScalingBenchOptions {
  std::string out_dir;
  int64_t steps = 300;  // first steps of the paper walk used for every point
  int64_t max_particles = 1000000;
  int64_t thread_sweep_particles = 30000;
  // "growing" (the default configuration's grid, as every committed scaling run used) or
  // "fixed" (the paper's 256 x 256 grid, as `bench paper` runs it).
  std::string grid = "growing";
};
int ScalingBenchCommand(const ScalingBenchOptions& options);

// `grove bench fastslam-accuracy`: position RMSE of the weighted-mean pose against the truth on
// Bailey's webmap (known or unknown association), for FastSLAM 1.0 and 2.0, `seeds` simulator seeds
// (the filter's seed equals the simulator's) and each particle count.
struct FastSlamAccuracyOptions {
  std::string out_dir;
  int seeds = 10;
  std::vector<int64_t> particles = {10, 100, 1000, 10000};
  int threads = 0;
  // "known", or "ml" / "ml_exclusive" / "sampled" / "jcbb": unknown association, the ids only
  // tags (the table then also gives the detections associated wrongly and the landmarks
  // created).
  std::string association = "known";
};
int FastSlamAccuracyBenchCommand(const FastSlamAccuracyOptions& options);

// `grove bench fastslam-speed`: the whole webmap with FastSLAM 2.0 and 100 particles on one
// thread (the median of `repeats` runs), then throughput (particle-steps/s, control and scan
// steps apart) for 100 ... max_particles particles x 1 .. cores threads on the first
// `controls` control rows.
struct FastSlamSpeedOptions {
  std::string out_dir;
  int repeats = 5;
  int64_t max_particles = 100000;
  int64_t controls = 2000;
};
int FastSlamSpeedBenchCommand(const FastSlamSpeedOptions& options);

// `grove bench victoria-park`: the bundled Victoria Park run (its defaults,
// VictoriaParkConfig()) for each filter and particle count, at 1 thread (up to
// max_one_thread_particles) and at every hardware thread: the error against GPS, the landmarks
// of the heaviest map, the filter's run time and the peak RSS of a child process per run.
struct VictoriaParkBenchOptions {
  std::string out_dir;
  std::vector<int64_t> particles = {3, 10, 100, 1000, 10000};
  std::vector<std::string> filters = {"fastslam1", "fastslam2"};
  int64_t max_one_thread_particles = 1000;
  double until_s = 1e9;
};
int VictoriaParkBenchCommand(const VictoriaParkBenchOptions& options);

// `grove bench footslam`: FootSLAM on the user's step file (read as `grove footslam run
// --steps` reads it, --max-step included) for every pair of `sweep` (tools/bench/sweep_bench.h).
struct FootSlamBenchOptions {
  SweepBenchOptions sweep;
  std::string steps_path;
  double max_step_m = 5.0;
};
int FootSlamBenchCommand(const FootSlamConfig& config, const FootSlamBenchOptions& options);

// `grove bench fastslam`: FastSLAM on the user's controls and observations (read as `grove
// fastslam run` reads them; observations without ids make the association unknown) for every
// pair of `sweep`.
struct FastSlamBenchOptions {
  SweepBenchOptions sweep;
  std::string controls_path;
  std::string observations_path;
};
int FastSlamBenchCommand(const FastSlamConfig& config, const FastSlamBenchOptions& options);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_BENCH_BENCH_COMMANDS_H_

// Synthetic pedestrian walks with ground truth, for testing and benchmarking FootSLAM.
//
// The walker follows a graph of waypoints (corridor junctions, doors, room interiors; or junctions
// of outdoor paths), so it revisits places as a real pedestrian does. Each true step is then
// corrupted the way foot-mounted odometry is (FootSLAM paper, Section II: a step measurement with
// correlated errors and white noise): a heading error that drifts as a random walk, a constant
// step-length scale error, and white noise on each step's length and direction.
#ifndef GROVE_TOOLS_SIM_WALK_SIMULATOR_H_
#define GROVE_TOOLS_SIM_WALK_SIMULATOR_H_

#include <cstdint>
#include <string>
#include <vector>

#include "grove/config_fields.h"
#include "grove/status.h"
#include "tools/io/step_reader.h"

namespace grove::tools {

enum class Scenario {
  // One floor of about 38 m x 27 m: a corridor loop split by a middle corridor, with 18 rooms off
  // it through doors. The walker mostly walks on straight ahead (loops around the corridors in
  // a consistent direction), sometimes turns at random, and keeps room visits short.
  kBuilding,
  // About 100 m x 100 m of outdoor paths (a distorted grid with a few diagonals) centred on the
  // start. The walker prefers paths it has not walked yet: mostly exploration, some revisits.
  kOpen,
  // Three such buildings 100 m apart in a row (corners at x = 0, 100, 200), each one's east
  // corridor joined to the next one's west corridor by a 64 m outdoor path: a walk of an hour
  // moves between buildings and returns to them, for storage of diversity.
  kCampus,
};

// An axis-aligned box in the truth frame.
struct Area {
  double min_x_m = 0;
  double min_y_m = 0;
  double max_x_m = 0;
  double max_y_m = 0;
};

// The box the true walk of a scenario stays in (the walls of the building, the paths' extent plus
// a margin), in the truth frame, where the walk starts at (0, 0).
Area ScenarioArea(Scenario scenario);

struct SimulatorOptions {
  // The true walk. It depends on these fields only, not on the odometry errors below.
  Scenario scenario = Scenario::kBuilding;
  // Length of the walk. Range: (0, 1440]. Default: 8.
  double minutes = 8;
  // Seeds both the walk and the odometry errors. Default: 1.
  uint64_t seed = 1;
  // Mean true step length; each step varies by about 5% around it, and steps shorten when a
  // waypoint is closer. Range: [0.1, 2]. Default: 0.7.
  double step_length_m = 0.7;
  // Time between steps (constant). Range: [0.1, 5]. Default: 0.55.
  double step_period_s = 0.55;
  // Probability that at a waypoint the walker takes the way closest to straight ahead instead
  // of a random one: loops around corridors in a consistent direction. Range: [0, 1].
  // Default: 0.6.
  double straight_probability = 0.6;

  // Odometry errors. All zero gives odometry steps equal to the true steps, bit for bit.
  // Standard deviation of the per-step increment of the heading error, which is a random walk:
  // after n steps its spread is this times sqrt(n). Range: [0, 0.5]. Default: 0.006 (about 10
  // degrees after 8 minutes).
  double heading_drift_rad_per_sqrt_step = 0.006;
  // Fixed, not drawn: every odometry step length is the true one times (1 + scale_error).
  // Range: (-0.5, 0.5). Default: 0.02.
  double scale_error = 0.02;
  // Standard deviation of white noise added to each step's length. Range: [0, 0.5]. Default: 0.03.
  double step_length_noise_m = 0.03;
  // Standard deviation of white noise added to each step's direction (does not accumulate).
  // Range: [0, 1]. Default: 0.02.
  double heading_noise_rad = 0.02;
  // The heading error before the first step: the odometry frame is rotated by this much against
  // the truth frame (both start at (0, 0)). Range: [-pi, pi]. Default: 0 (aligned).
  double initial_heading_rad = 0;
};

// A true position at the end of a step.
struct TruthPoint {
  double t_s = 0;
  double x_m = 0;
  double y_m = 0;
};

struct SimulatedWalk {
  // truth[0] is the start, (0, 0) at t = 0; truth[k] is the position after steps[k - 1].
  std::vector<TruthPoint> truth;
  // Odometry steps in the deltas form and the odometry frame; steps[k].t_s == truth[k + 1].t_s.
  std::vector<StepRecord> steps;
};

// The ranges SimulateWalk checks of the options the command line sets: minutes, the heading
// drift and the scale error.
Interval WalkMinutesRange();
Interval HeadingDriftRange();
Interval ScaleErrorRange();

// Simulates a walk of floor(minutes * 60 / step_period_s) steps. The same options give the same
// walk: draws come from std::mt19937_64 through our own uniform and Box-Muller transforms, never
// from an implementation-defined std:: distribution (libm may still differ in the last bits).
// Returns InvalidArgument naming the field when an option is out of range.
StatusOr<SimulatedWalk> SimulateWalk(const SimulatorOptions& options);

// The walk of the paper's experiment (Garcia Puyol et al. §VII: an open area, 30,000
// particles), as `grove bench` and the benchmarks use it: the open scenario, seed 1.
StatusOr<std::vector<StepRecord>> PaperWalk(double minutes);

// The steps as a step file in the deltas form ("t,dx,dy" then one row per step). Numbers are
// written in the shortest form that reads back to the same double.
std::string StepsCsv(const SimulatedWalk& walk);
// The truth as "t,x,y" then one row per point, the first the start at (0, 0).
std::string TruthCsv(const SimulatedWalk& walk);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_SIM_WALK_SIMULATOR_H_

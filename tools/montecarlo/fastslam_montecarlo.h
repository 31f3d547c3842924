// `grove fastslam montecarlo`: Monte Carlo runs of the landmark FastSLAM filters on the seed
// paper's simulations (Ankışhan et al., paper 003, Section 4.1-4.3: Simulations I-III), written
// in the shape of its Tables 1 and 2 and Figures 3, 4, 6 and 8.
//
// Each (filter, particle count, run) is one job: run r simulates Bailey's vehicle with seed S + r
// and runs the filter (seed S + r, one thread) on it; after every control and scan it scores the
// weighted-mean pose against the truth, and after every scan it takes the pose NEES from
// FastSlam::PoseCovariance(). Jobs run in parallel (a tbb::task_arena of --threads); every
// result but the CPU time is the same at any thread count. A job writes
// DIR/runs/<filter>_p<particles>/run_<r>.csv and then run_<r>.json (each atomically); a later
// invocation into the same DIR reuses every job whose JSON matches its filter, particle count,
// seed, scenario digest and filter configuration digest and whose CSV has the size and hash the
// JSON records, so a killed command finishes on rerun. When all jobs are done it writes
// DIR/table.md, DIR/table.csv, DIR/summary.json and the charts (PNG and SVG): mse_position,
// mse_heading, boxplot_position, nees and, with more than one particle count, accuracy_vs_cpu.
#ifndef GROVE_TOOLS_MONTECARLO_FASTSLAM_MONTECARLO_H_
#define GROVE_TOOLS_MONTECARLO_FASTSLAM_MONTECARLO_H_

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "grove/fastslam.h"
#include "grove/status.h"
#include "tools/sim/fastslam_simulator.h"

namespace grove::tools {

// The maps of the seed's Simulations II and III (tools/data/scenarios/sim2_map.txt and
// sim3_map.txt, embedded at build time), and the names that stand for them in messages.
const char* EmbeddedSim2MapName();
std::string EmbeddedSim2Map();
const char* EmbeddedSim3MapName();
std::string EmbeddedSim3Map();

// What a scenario says, before its map is read.
struct MonteCarloScenarioSpec {
  std::string name;        // "sim1", "sim2", "sim3" or the JSON file's path
  std::string preset;      // BaileyPreset's name the simulator options start from
  std::string map_path;    // empty: the bundled map (webmap; sim2 and sim3 their own)
  std::string map_bundle;  // with map_path empty: "webmap", "sim2" or "sim3"
  BaileySimOptions sim;    // the preset with the file's overrides and the loops; seed per run
  FastSlamAssociation association = FastSlamAssociation::kKnown;
};

// A scenario ready to run.
struct MonteCarloScenario {
  MonteCarloScenarioSpec spec;
  std::string map_name;  // the map's name in messages (a path or "bundled:...")
  BaileyMap map;
  // 16 hex digits: FNV-1a (64-bit) of the simulator's options (seed aside), the association and
  // the map's points, so a comment edited in a map file does not invalidate finished runs.
  std::string digest;
};

// `spec` is "sim1" (Simulation I: the sim1 preset on the bundled webmap, known association),
// "sim2" (the sim2 preset on the bundled sim2 map, unknown association: maximum likelihood, the
// simulator's ids only tag), "sim3" (the sim3 preset on the bundled sim3 map, known association)
// or a JSON file:
//   {"map": "map.txt", "preset": "sim1", "association": "ml", "loops": 1,
//    "sigma_speed_mps": 1.0, "sigma_steer_rad": 0.17, "sigma_range_m": 1.2,
//    "sigma_bearing_rad": 0.2, "max_range_m": 30}
// where preset ("webmap", "sim1", "sim2", "sim3") and association ("known", "ml") are required,
// map (Bailey's text format; relative to the JSON file's directory; default: the bundled webmap)
// and the rest optional; the sigmas and max_range_m override the preset's. `loops` > 0 overrides
// the scenario's loops (--loops); 0 keeps them.
// Errors: NotFound or IoError when the JSON file cannot be read (exit 3); InvalidArgument for an
// unknown name, or "FILE:LINE:COLUMN: ..." for invalid JSON, an unknown, repeated or missing key,
// a value of the wrong type or out of range (exit 2).
StatusOr<MonteCarloScenarioSpec> ParseMonteCarloScenario(const std::string& spec, int64_t loops);
// Reads the map and computes the digest. Any error is the map's (exit 3).
StatusOr<MonteCarloScenario> LoadMonteCarloScenario(const MonteCarloScenarioSpec& spec);

// The particles the seed ran `filter` with in the scenario of `preset`: sim2 30 (de_srcd 3),
// sim3 100 (de_srcd 10); sim1 and webmap 100 (the seed gives no count for Simulation I).
int64_t PaperParticles(std::string_view preset, FastSlamFilter filter);

// The filter's configuration for one job: FastSlamConfig's defaults, with the filter, particles,
// seed and one thread; the simulator's noise as the assumed noise (sigma_speed_mps,
// sigma_steer_rad, sigma_range_m, sigma_bearing_rad), its wheelbase and start pose; the
// scenario's association; and for the existence evidence of unknown association the simulator's
// sensor range and field of view (sensor_range_m, sensor_fov_rad); resampling when
// ESS < 0.5 N (the seed's Eq. 27).
FastSlamConfig MonteCarloJobConfig(const MonteCarloScenario& scenario, FastSlamFilter filter,
                                   int64_t particles, uint64_t seed);

struct MonteCarloOptions {
  std::string scenario;   // sim1, sim2, sim3 or FILE.json (ParseMonteCarloScenario)
  std::string filters;    // comma list of FastSlamFilterName names, each once
  std::string particles;  // comma list of counts in 1..2^31, each once; empty: PaperParticles
  int64_t runs = 0;       // Monte Carlo runs, 1..100000
  std::string out_dir;
  std::string seed = "1";  // S, a non-negative integer: run r uses S + r
  int64_t threads = 0;     // jobs in parallel, 0..256; 0: every hardware thread
  int64_t loops = 0;       // 0: the scenario's; else 1..1000
  bool progress = true;    // progress on stderr
  bool charts = true;      // not a flag: lets tests skip gnuplot
  // MPI ranks (tools/cli/mpi_world.h): job i runs on rank i % ranks, then rank 0 writes the
  // tables from the files every rank wrote (DIR on a file system they share). all_gather(mine)
  // returns every rank's string in rank order on every rank (collective). Unset: one rank.
  int rank = 0;
  int ranks = 1;
  std::function<std::vector<std::string>(const std::string&)> all_gather;
};

// Runs the command. Returns 0, or prints "grove: error: ..." and returns 2 (a bad option: it is
// named with its value; a bad scenario file's content), 3 (a scenario file or map that cannot be
// read or simulated) or 5 (the output directory or a file in it cannot be written, or another
// grove run holds DIR). A filter that fails in a job is that run's status, not an error.
int FastSlamMonteCarloCommand(const MonteCarloOptions& options);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_FASTSLAM_MONTECARLO_H_

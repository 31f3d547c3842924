// The scenarios of `grove fastslam montecarlo`: the seed paper's Simulations I-III (Ankışhan et
// al., 2016, Section 4.1-4.3) built in, or a scenario file; each read into the simulator's
// options, its map and a digest that keys the finished jobs made under it.
#ifndef GROVE_TOOLS_MONTECARLO_MONTE_CARLO_SCENARIO_H_
#define GROVE_TOOLS_MONTECARLO_MONTE_CARLO_SCENARIO_H_

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "grove/fastslam.h"
#include "grove/status.h"
#include "tools/sim/fastslam_simulator.h"

namespace grove::tools {

// Loops through the waypoints a scenario may ask for (its file's "loops", --loops).
inline constexpr int64_t kMonteCarloMaxLoops = 1000;

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

// "known" or "ml".
const char* AssociationName(FastSlamAssociation a);
// The simulator's options as summary.json records them.
nlohmann::json SimOptionsJson(const BaileySimOptions& o);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_MONTE_CARLO_SCENARIO_H_

// The simulator of `grove tracking simulate`: a target flying a figure of eight through four
// beacons at the corners of a 100 m square centred on the origin,
//   x(t) = 30 sin(w t),  y(t) = 20 sin(2 w t),  w = 2 pi / 120 s,
// and its range to every beacon every 1 / rate_hz seconds (t = 1 / rate_hz, 2 / rate_hz, ...),
// plus N(0, range_sigma_m^2) noise (NormalSource, purpose 1). The files it writes are the inputs
// of `grove tracking run` (tools/io/tracking_inputs.h) and the truth (`t,x,y,heading`, the
// heading the direction of motion; t = 0 first).
//
// Thread safety: the functions are thread-safe (no shared state).
#ifndef GROVE_TOOLS_SIM_TRACKING_SIMULATOR_H_
#define GROVE_TOOLS_SIM_TRACKING_SIMULATOR_H_

#include <cstdint>
#include <string>
#include <vector>

#include "grove/config_fields.h"
#include "grove/status.h"
#include "grove/types.h"

namespace grove::tools {

struct TrackingSimOptions {
  double seconds = 120;  // duration, s
  double rate_hz = 1;    // updates per second
  double range_sigma_m = 0.5;
  uint64_t seed = 1;
};
// The options' ranges, for the command's flags.
Interval TrackingSecondsRange();     // (0, 86400]
Interval TrackingRateRange();        // (0, 100]
Interval TrackingRangeSigmaRange();  // [0, 100]

// The three files' text.
struct TrackingSimulation {
  std::string beacons_csv;
  std::string measurements_csv;
  std::vector<StampedPose> truth;
};
TrackingSimulation SimulateTracking(const TrackingSimOptions& options);

// `grove tracking simulate`: beacons.csv, measurements.csv and truth.csv into out_dir.
int TrackingSimulateCommand(const TrackingSimOptions& options, const std::string& out_dir);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_SIM_TRACKING_SIMULATOR_H_

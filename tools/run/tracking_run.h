// `grove tracking run`: the beacon tracker on the generic run loop (tools/run/run_loop.h).
#ifndef GROVE_TOOLS_RUN_TRACKING_RUN_H_
#define GROVE_TOOLS_RUN_TRACKING_RUN_H_

#include <string>

#include "grove/tracking.h"
#include "tools/run/run_loop.h"

namespace grove::tools {

struct TrackingRunOptions {
  RunOptions run;
  std::string beacons_path;       // beacons.csv (tools/io/tracking_inputs.h)
  std::string measurements_path;  // measurements.csv
};

// Runs the tracker and writes trajectory.csv and summary.json; returns an exit code after
// printing any error.
int RunTrackingCommand(const TrackerConfig& config, const TrackingRunOptions& options);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_RUN_TRACKING_RUN_H_

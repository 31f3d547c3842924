// The outputs every model's run writes the same way: trajectories as CSV and TUM, and
// summary.json's generic fields.
#ifndef GROVE_TOOLS_IO_FILTER_OUTPUTS_H_
#define GROVE_TOOLS_IO_FILTER_OUTPUTS_H_

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "grove/types.h"

namespace grove::tools {

// `t,x,y,heading`, one pose a row (6 decimals).
std::string TrajectoryCsv(const std::vector<StampedPose>& poses);
// The TUM trajectory format evaluation tools read (evo, the TUM RGB-D benchmark's scripts):
// `t x y z qx qy qz qw` separated by spaces, z = 0, the heading as a rotation about z
// (qz = sin(heading / 2), qw = cos(heading / 2)); 9 decimals.
std::string TrajectoryTum(const std::vector<StampedPose>& poses);
// summary.json's fields of every filter: particles, steps, threads, timings, rates, phases.
nlohmann::json FilterSummaryJson(const FilterSummary& s);
// A MemoryUse as {live_nodes, live_bytes, peak_live_nodes, peak_live_bytes, reserved_bytes}.
nlohmann::json MemoryUseJson(const MemoryUse& m);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_FILTER_OUTPUTS_H_

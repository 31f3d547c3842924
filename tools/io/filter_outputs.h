// The outputs every model's run writes the same way: trajectories as CSV, TUM and KITTI, and
// summary.json's generic fields.
#ifndef GROVE_TOOLS_IO_FILTER_OUTPUTS_H_
#define GROVE_TOOLS_IO_FILTER_OUTPUTS_H_

#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "grove/types.h"
#include "tools/io/output_set.h"

namespace grove::tools {

// `t,x,y,heading`, one pose a row (6 decimals).
std::string TrajectoryCsv(const std::vector<StampedPose>& poses);
// The TUM trajectory format evaluation tools read (evo, the TUM RGB-D benchmark's scripts):
// `t x y z qx qy qz qw` separated by spaces, z = 0, the heading as a rotation about z
// (qz = sin(heading / 2), qw = cos(heading / 2)); 9 decimals.
std::string TrajectoryTum(const std::vector<StampedPose>& poses);
// The KITTI odometry pose format (evo's `kitti` mode): per pose one line of the 12 numbers of
// the row-major 3x4 matrix [R | t], R the rotation about z by the heading, t = (x, y, 0),
// separated by spaces, each the shortest text that reads back as the same double. No times:
// line k is the pose of line k of the TUM file.
std::string TrajectoryKitti(const std::vector<StampedPose>& poses);

// The files of the trajectories named `stems` ("smoothed_trajectory"): every STEM.csv, then every
// STEM.tum, then every STEM.kitti.
std::vector<std::string> TrajectoryFileNames(std::span<const char* const> stems);
// Adds trajectory k, named stems[k], to `out` in each format, in TrajectoryFileNames' order.
// Internal error unless there are as many trajectories as stems.
Status AddTrajectoryFiles(OutputSet* out, std::span<const char* const> stems,
                          std::span<const std::vector<StampedPose>* const> trajectories);
// summary.json's fields of every filter: particles, steps, threads, timings, rates, phases.
nlohmann::json FilterSummaryJson(const FilterSummary& s);
// A MemoryUse as {live_nodes, live_bytes, peak_live_nodes, peak_live_bytes, reserved_bytes}.
nlohmann::json MemoryUseJson(const MemoryUse& m);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_FILTER_OUTPUTS_H_

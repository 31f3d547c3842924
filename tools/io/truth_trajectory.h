// The ground truth a run is scored against (`--truth` of `footslam run` and `fastslam run`) and
// the points `footslam evaluate` compares: grove's CSV or a TUM trajectory.
//
// CSV: a header starting with the fields t,x,y (a fourth field named `heading` is read as the
// heading, radians; further columns are ignored), then rows of as many fields as the header, in
// the syntax of step files (tools/io/csv_reader.h).
// TUM: `t x y z qx qy qz qw` separated by spaces or tabs, `#` comment and blank lines skipped;
// the heading is the quaternion's yaw; z and the tilt are ignored. A file is read as TUM when its
// name ends in `.tum` or `.txt`, or when its first line that is not skipped has no comma.
//
// Both: every number finite, times strictly increasing, at least one pose; lines up to 64 KiB.
// Errors are InvalidArgument "FILE:LINE:COLUMN: field, value, rule" (NotFound, IoError for a file
// that cannot be read).
#ifndef GROVE_TOOLS_IO_TRUTH_TRAJECTORY_H_
#define GROVE_TOOLS_IO_TRUTH_TRAJECTORY_H_

#include <string>
#include <vector>

#include "grove/status.h"
#include "grove/types.h"

namespace grove::tools {

struct TruthTrajectory {
  std::vector<StampedPose> poses;  // times strictly increasing
  bool has_heading = false;        // a TUM file, or a CSV file with a heading column
};

StatusOr<TruthTrajectory> ReadTruthTrajectory(const std::string& path);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_TRUTH_TRAJECTORY_H_

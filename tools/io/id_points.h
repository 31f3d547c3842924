// `id,x,y` files: points named by an integer id, one a row (landmarks_truth.csv of `grove
// fastslam run`, beacons.csv of `grove tracking run`). The id is an integer in [0, 2^31), each
// once; x and y are finite numbers (metres). The CSV syntax and the "FILE:LINE:COLUMN: what"
// errors are those of tools/io/csv_reader.h.
#ifndef GROVE_TOOLS_IO_ID_POINTS_H_
#define GROVE_TOOLS_IO_ID_POINTS_H_

#include <cstdint>
#include <map>
#include <string>

#include "grove/status.h"

namespace grove::tools {

struct IdPoint {
  double x_m = 0, y_m = 0;
};

// Every point of the file at `path`, by id.
StatusOr<std::map<int64_t, IdPoint>> ReadIdPoints(const std::string& path);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_ID_POINTS_H_

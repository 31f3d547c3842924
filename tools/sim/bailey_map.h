// The map of Tim Bailey's FastSLAM simulator (tools/sim/fastslam_simulator.h): landmarks and
// waypoints, read from his text format.
//
// Thread safety: all functions are thread-safe (no shared state).
#ifndef GROVE_TOOLS_SIM_BAILEY_MAP_H_
#define GROVE_TOOLS_SIM_BAILEY_MAP_H_

#include <string>
#include <vector>

#include "grove/status.h"

namespace grove::tools {

// The largest |x| or |y| of a map's point or a start pose, metres.
inline constexpr double kBaileyMaxCoordinateM = 1e9;

struct BaileyPoint {
  double x_m = 0;
  double y_m = 0;
};

// The landmarks and waypoints of Bailey's simulator. A landmark's id is its index.
struct BaileyMap {
  std::vector<BaileyPoint> landmarks;
  std::vector<BaileyPoint> waypoints;
};

// Reads Bailey's text form of a map (example_webmap.txt; the format of the C++ port's
// read_input_file, which example_webmap.mat was converted to):
//   #type columns rows
//   lm 2 35
//   2.9922  -25.7009
//   ...
//   wp 2 17
//   12.6495  -41.5888
//   ...
// Each block is a header `name columns rows` and then `rows` lines of `columns` numbers: one
// point a line, x then y in metres (the C++ loader fills column r of Bailey's 2 x N MATLAB
// matrix from line r, so the file is one point per line, not column-major). Blocks `lm`
// (landmarks, rows >= 0) and `wp` (waypoints, rows >= 1) must both appear, once each, in either
// order, with columns = 2. Numbers are separated by spaces or tabs and read as std::from_chars
// does (finite, |value| <= 1e9 m). Blank lines and lines starting with '#' are skipped anywhere.
//
// Errors: NotFound for a missing file; IoError when it cannot be read; InvalidArgument as one
// line "FILE:LINE:COLUMN: what" (1-based line and byte column) for a bad header, an unknown or
// repeated block, a row with the wrong count of numbers, a block with fewer or more rows than its
// header declares, a field that is not a number or not finite, a missing lm or wp block.
StatusOr<BaileyMap> ReadBaileyMap(const std::string& path);
// The same for text already in memory; `name` stands for FILE in messages.
StatusOr<BaileyMap> ParseBaileyMap(const std::string& name, const std::string& text);

// The bundled copy of Bailey's example_webmap.txt (tools/data/bailey_webmap/, embedded at build
// time), used when no map is given, and the name that stands for it in messages.
const char* EmbeddedBaileyWebmapName();
std::string EmbeddedBaileyWebmap();

}  // namespace grove::tools

#endif  // GROVE_TOOLS_SIM_BAILEY_MAP_H_

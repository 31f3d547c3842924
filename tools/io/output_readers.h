// Readers for grove's own CSV outputs, used by `grove footslam render`.
//
// Errors: NotFound for a missing file, IoError when it cannot be read (a directory included),
// InvalidArgument for a bad record as one line "FILE:LINE:COLUMN: what (detail)" (1-based; COLUMN
// counts bytes), a line longer than 64 KiB included.
// Both readers are built on tools/io/csv_reader.h and accept "\r\n" line ends, a UTF-8 byte order
// mark, blank lines, spaces around fields and extra columns after the required ones; quoted fields
// are not supported (grove never writes them). Thread-safe (no shared state).
#ifndef GROVE_TOOLS_IO_OUTPUT_READERS_H_
#define GROVE_TOOLS_IO_OUTPUT_READERS_H_

#include <string>
#include <vector>

#include "grove/footslam.h"
#include "grove/status.h"
#include "tools/report/map_render.h"

namespace grove::tools {

// map.csv: header q,r,x,y,c0,c1,c2,c3,c4,c5; use = c0 + ... + c5. q and r are int32, the others
// finite numbers, the counts >= 0; each (q, r) appears once.
StatusOr<std::vector<RenderHex>> ReadMapCsv(const std::string& path);

// map.csv as a FootSLAM prior map (FootSlam::SetPriorMap), with the rules above; when
// hex_radius_m > 0, x and y must also be the centre of hexagon (q, r) at that radius (to the file's
// four decimals), so a map made with another radius is refused.
StatusOr<std::vector<HexCounts>> ReadPriorMapCsv(const std::string& path, double hex_radius_m);

// trajectory.csv (t,x,y,heading) or any CSV whose header starts t,x,y: the (x, y) points in order.
StatusOr<std::vector<RenderPoint>> ReadPathCsv(const std::string& path);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_OUTPUT_READERS_H_

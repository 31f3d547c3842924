// The input files of `grove tracking run`:
//   beacons.csv       `id,x,y` (tools/io/id_points.h): each beacon's id and position (m).
//   measurements.csv  `t,beacon,range`: time (s, finite, non-decreasing), the id of a beacon of
//                     beacons.csv and the range measured to it (m, finite, >= 0); the rows of
//                     one time are one update.
// The CSV syntax and the "FILE:LINE:COLUMN: what" errors are those of tools/io/csv_reader.h.
#ifndef GROVE_TOOLS_IO_TRACKING_INPUTS_H_
#define GROVE_TOOLS_IO_TRACKING_INPUTS_H_

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "grove/status.h"
#include "grove/tracking.h"
#include "tools/io/csv_reader.h"
#include "tools/io/id_points.h"

namespace grove::tools {

// One update: its time, its ranges (the beacons' positions filled in) and its first row's line.
struct TrackingUpdate {
  double t_s = 0;
  std::vector<RangeMeasurement> ranges;
  int64_t line = 0;
};

// Reads measurements.csv an update at a time. Movable.
class MeasurementReader {
 public:
  static StatusOr<MeasurementReader> Open(const std::string& path,
                                          std::map<int64_t, IdPoint> beacons);
  // The next update: false at the end of the file.
  StatusOr<bool> Next(TrackingUpdate* out);
  const std::string& path() const { return table_.path(); }

 private:
  struct Row {
    double t_s = 0;
    RangeMeasurement z;
    int64_t line = 0;
  };
  MeasurementReader(CsvTableReader table, std::map<int64_t, IdPoint> beacons)
      : table_(std::move(table)), beacons_(std::move(beacons)) {}
  // The next row, checked, into pending_; false at the end.
  StatusOr<bool> ReadRow();

  CsvTableReader table_;
  std::map<int64_t, IdPoint> beacons_;
  bool has_pending_ = false;  // pending_ is the first row of the next update
  Row pending_;
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_TRACKING_INPUTS_H_

#include "tools/io/tracking_inputs.h"

#include <fmt/format.h>

#include <utility>

namespace grove::tools {

StatusOr<MeasurementReader> MeasurementReader::Open(const std::string& path,
                                                    std::map<int64_t, IdPoint> beacons) {
  StatusOr<CsvTableReader> table = CsvTableReader::Open(path, {{"t", "beacon", "range"}});
  if (!table.ok()) return table.status();
  MeasurementReader reader(std::move(table).value(), std::move(beacons));
  StatusOr<bool> first = reader.ReadRow();
  if (!first.ok()) return first.status();
  return reader;
}

StatusOr<bool> MeasurementReader::ReadRow() {
  const std::vector<CsvField>* f = nullptr;
  StatusOr<bool> more = table_.Next(&f);
  if (!more.ok() || !*more) {
    has_pending_ = false;
    return more;
  }
  const std::string& path = table_.path();
  const int64_t line = table_.line_number();
  Row row;
  row.line = line;
  int32_t beacon = 0;
  GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, (*f)[0], "t", &row.t_s));
  GROVE_RETURN_IF_ERROR(ParseCsvId(path, line, (*f)[1], "beacon", &beacon));
  GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, (*f)[2], "range", &row.z.range_m));
  if (has_pending_ && row.t_s < pending_.t_s) {
    return LineError(path, line, (*f)[0].column,
                     fmt::format("t = {} is before the previous row's {}", row.t_s, pending_.t_s));
  }
  const auto b = beacons_.find(beacon);
  if (b == beacons_.end()) {
    return LineError(path, line, (*f)[1].column,
                     fmt::format("beacon {} is not one of the beacons file's", beacon));
  }
  if (row.z.range_m < 0) {
    return LineError(path, line, (*f)[2].column,
                     fmt::format("range = {}: must be >= 0", row.z.range_m));
  }
  row.z.beacon_x_m = b->second.x_m;
  row.z.beacon_y_m = b->second.y_m;
  pending_ = row;
  has_pending_ = true;
  return true;
}

StatusOr<bool> MeasurementReader::Next(TrackingUpdate* out) {
  if (!has_pending_) return false;
  out->t_s = pending_.t_s;
  out->line = pending_.line;
  out->ranges.assign(1, pending_.z);
  for (;;) {
    StatusOr<bool> more = ReadRow();
    if (!more.ok()) return more.status();
    if (!*more || pending_.t_s != out->t_s) return true;
    out->ranges.push_back(pending_.z);
  }
}

}  // namespace grove::tools

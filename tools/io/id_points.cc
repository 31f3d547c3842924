#include "tools/io/id_points.h"

#include <fmt/format.h>

#include <vector>

#include "tools/io/csv_reader.h"

namespace grove::tools {

StatusOr<std::map<int64_t, IdPoint>> ReadIdPoints(const std::string& path) {
  StatusOr<CsvTableReader> table = CsvTableReader::Open(path, {{"id", "x", "y"}});
  if (!table.ok()) return table.status();
  std::map<int64_t, IdPoint> out;
  GROVE_RETURN_IF_ERROR(
      table->ForEachRow([&](const std::vector<CsvField>& f, int64_t line) -> Status {
        int32_t id = 0;
        GROVE_RETURN_IF_ERROR(ParseCsvId(path, line, f[0], "id", &id));
        IdPoint p;
        GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, f[1], "x", &p.x_m));
        GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, line, f[2], "y", &p.y_m));
        if (!out.emplace(id, p).second) {
          return LineError(path, line, f[0].column, fmt::format("id {} appears twice", id));
        }
        return Status::Ok();
      }));
  return out;
}

}  // namespace grove::tools

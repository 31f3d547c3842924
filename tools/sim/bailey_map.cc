#include "tools/sim/bailey_map.h"

#include <fmt/format.h>

#include <charconv>
#include <cstdint>
#include <memory>
#include <sstream>
#include <string_view>
#include <utility>

#include "tools/io/csv_reader.h"

namespace grove::tools {
namespace {

constexpr int32_t kMaxBlockRows = 10'000'000;
constexpr size_t kMaxLineBytes = 64 * 1024;

bool IsBlockName(std::string_view text) { return text == "lm" || text == "wp"; }

bool LooksLikeNumber(std::string_view text) {
  double value = 0;
  const NumberParse parse = ParseCsvDouble(text, &value);
  return parse == NumberParse::kOk || parse == NumberParse::kNotFinite ||
         parse == NumberParse::kOutOfRange;
}

StatusOr<BaileyMap> ParseMapLines(LineReader lines) {
  const std::string path = lines.path();
  BaileyMap map;
  int64_t lm_line = 0;  // line of each block's header; 0 while not seen
  int64_t wp_line = 0;
  // The block whose rows are being read.
  std::vector<BaileyPoint>* rows = nullptr;
  std::string_view block;
  int32_t declared = 0;
  int64_t header_line = 0;
  int64_t rows_column = 0;

  std::vector<CsvField> fields;
  std::string_view line;
  int64_t last_line = 0;
  for (;;) {
    StatusOr<bool> more = lines.Next(&line);
    if (!more.ok()) return more.status();
    if (!*more) break;
    const int64_t number = lines.line_number();
    last_line = number;
    if (IsSkippedLine(line)) continue;
    SplitAtBlanks(line, &fields);

    if (rows != nullptr && static_cast<int32_t>(rows->size()) < declared) {
      const size_t row = rows->size() + 1;
      if (IsBlockName(fields[0].text)) {
        return LineError(path, number, fields[0].column,
                         fmt::format("block {} (line {}) declares {} rows but has {}: a new "
                                     "block starts here",
                                     block, header_line, declared, rows->size()));
      }
      if (fields.size() != 2) {
        const int64_t column =
            fields.size() > 2 ? fields[2].column : static_cast<int64_t>(line.size()) + 1;
        return LineError(path, number, column,
                         fmt::format("{} row {}: expected 2 numbers (x y), found {}", block, row,
                                     fields.size()));
      }
      double xy[2];
      for (int c = 0; c < 2; ++c) {
        const std::string name = fmt::format("{} row {} {}", block, row, c == 0 ? "x" : "y");
        GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, number, fields[c], name, &xy[c]));
        if (!(std::fabs(xy[c]) <= kBaileyMaxCoordinateM)) {
          return LineError(
              path, number, fields[c].column,
              fmt::format("{} = {}: must be within +-{:g} m", name, xy[c], kBaileyMaxCoordinateM));
        }
      }
      rows->push_back({xy[0], xy[1]});
      continue;
    }

    // A block header is expected here.
    if (!IsBlockName(fields[0].text)) {
      if (LooksLikeNumber(fields[0].text)) {
        if (rows != nullptr) {
          return LineError(path, number, fields[0].column,
                           fmt::format("block {} (line {}) declares {} rows but has more: "
                                       "expected a block header \"lm 2 N\" or \"wp 2 M\"",
                                       block, header_line, declared));
        }
        return LineError(path, number, fields[0].column,
                         "a row of numbers before any block header: expected \"lm 2 N\" or "
                         "\"wp 2 M\" (name columns rows)");
      }
      return LineError(
          path, number, fields[0].column,
          fmt::format("unknown block {}: expected lm or wp", QuotedField(fields[0].text)));
    }
    const std::string_view name = fields[0].text;
    if (fields.size() != 3) {
      const int64_t column =
          fields.size() > 3 ? fields[3].column : static_cast<int64_t>(line.size()) + 1;
      return LineError(path, number, column,
                       fmt::format("block header {}: expected 3 fields \"name columns rows\", "
                                   "found {}",
                                   name, fields.size()));
    }
    int64_t& seen_line = name == "lm" ? lm_line : wp_line;
    if (seen_line != 0) {
      return LineError(path, number, fields[0].column,
                       fmt::format("a second {} block (the first is on line {})", name, seen_line));
    }
    int32_t columns = 0;
    if (ParseCsvInt32(fields[1].text, &columns) != NumberParse::kOk) {
      return LineError(
          path, number, fields[1].column,
          fmt::format("{} columns: {} is not an integer", name, QuotedField(fields[1].text)));
    }
    if (columns != 2) {
      return LineError(path, number, fields[1].column,
                       fmt::format("{} columns = {}: must be 2 (x y on each line)", name, columns));
    }
    int32_t count = 0;
    if (ParseCsvInt32(fields[2].text, &count) != NumberParse::kOk) {
      return LineError(
          path, number, fields[2].column,
          fmt::format("{} rows: {} is not an integer", name, QuotedField(fields[2].text)));
    }
    const int32_t min_rows = name == "wp" ? 1 : 0;
    if (count < min_rows || count > kMaxBlockRows) {
      return LineError(
          path, number, fields[2].column,
          fmt::format("{} rows = {}: must be in [{}, {}]{}", name, count, min_rows, kMaxBlockRows,
                      name == "wp" ? " (the path needs a waypoint)" : ""));
    }
    seen_line = number;
    rows = name == "lm" ? &map.landmarks : &map.waypoints;
    rows->reserve(static_cast<size_t>(std::min(count, 4096)));
    block = name == "lm" ? "lm" : "wp";  // not a view into the line buffer
    declared = count;
    header_line = number;
    rows_column = fields[2].column;
  }
  if (rows != nullptr && static_cast<int32_t>(rows->size()) < declared) {
    return LineError(path, header_line, rows_column,
                     fmt::format("block {} declares {} rows but the file ends after {}", block,
                                 declared, rows->size()));
  }
  const int64_t end_line = std::max<int64_t>(1, last_line);
  if (lm_line == 0) {
    return LineError(path, end_line, 1,
                     "no lm block: expected \"lm 2 N\" and then N lines \"x y\" (landmarks)");
  }
  if (wp_line == 0) {
    return LineError(path, end_line, 1,
                     "no wp block: expected \"wp 2 M\" and then M lines \"x y\" (waypoints)");
  }
  return map;
}

}  // namespace

StatusOr<BaileyMap> ReadBaileyMap(const std::string& path) {
  StatusOr<LineReader> lines = LineReader::Open(path, kMaxLineBytes);
  if (!lines.ok()) return lines.status();
  return ParseMapLines(std::move(lines).value());
}

StatusOr<BaileyMap> ParseBaileyMap(const std::string& name, const std::string& text) {
  StatusOr<LineReader> lines =
      LineReader::FromStream(name, std::make_unique<std::istringstream>(text), kMaxLineBytes);
  if (!lines.ok()) return lines.status();
  return ParseMapLines(std::move(lines).value());
}

}  // namespace grove::tools

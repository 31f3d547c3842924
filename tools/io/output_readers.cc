#include "tools/io/output_readers.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string_view>
#include <unordered_map>
#include <utility>

#include "tools/io/csv_reader.h"

namespace grove::tools {
namespace {

// Far beyond any line grove writes; it bounds the memory one line can take.
constexpr size_t kMaxLineBytes = size_t{64} << 10;

// The non-blank lines of one CSV file, split into fields, with errors at the current line.
class CsvRows {
 public:
  explicit CsvRows(LineReader lines) : lines_(std::move(lines)) {}

  // Advances to the next non-blank line and splits it; false at the end of the file.
  StatusOr<bool> Next() {
    for (;;) {
      StatusOr<bool> more = lines_.Next(&line_);
      if (!more.ok() || !*more) return more;
      if (!IsBlankLine(line_)) break;
    }
    SplitCsvLine(line_, &fields_);
    return true;
  }

  std::string_view line() const { return line_; }
  const std::vector<CsvField>& fields() const { return fields_; }
  int64_t line_number() const { return lines_.line_number(); }

  Status Error(int64_t column, std::string_view what) const {
    return LineError(lines_.path(), std::max<int64_t>(line_number(), 1), column, what);
  }

  // Checks that the current line has exactly `count` fields.
  Status CheckFieldCount(size_t count) const {
    if (fields_.size() < count) {
      return Error(static_cast<int64_t>(line_.size()) + 1,
                   fmt::format("expected {} fields, found {}", count, fields_.size()));
    }
    if (fields_.size() > count) {
      return Error(fields_[count].column,
                   fmt::format("expected {} fields, found {}", count, fields_.size()));
    }
    return Status::Ok();
  }

  // Reads field i as a finite double or as an int32, named `name` in messages.
  Status Double(size_t i, std::string_view name, double* value) const {
    return FieldError(i, name, ParseCsvDouble(fields_[i].text, value), "a number", "out of range");
  }
  Status Int32(size_t i, std::string_view name, int32_t* value) const {
    return FieldError(i, name, ParseCsvInt32(fields_[i].text, value), "an integer",
                      "outside the int32 range");
  }

 private:
  Status FieldError(size_t i, std::string_view name, NumberParse result, std::string_view kind,
                    std::string_view range) const {
    const CsvField& field = fields_[i];
    const std::string quoted = QuotedField(field.text);
    switch (result) {
      case NumberParse::kOk:
        return Status::Ok();
      case NumberParse::kEmpty:
        return Error(field.column, fmt::format("{}: missing value", name));
      case NumberParse::kNotANumber:
        return Error(field.column, fmt::format("{}: {} is not {}", name, quoted, kind));
      case NumberParse::kOutOfRange:
        return Error(field.column, fmt::format("{}: {} is {}", name, quoted, range));
      case NumberParse::kNotFinite:
        return Error(field.column, fmt::format("{}: {} is not finite", name, quoted));
    }
    return Error(field.column, fmt::format("{}: {} is not {}", name, quoted, kind));
  }

  LineReader lines_;
  std::string_view line_;
  std::vector<CsvField> fields_;
};

// Opens `path` and checks that its header starts with `names`; returns the rows after it and
// sets *columns to the header's field count.
StatusOr<CsvRows> OpenWithHeader(const std::string& path,
                                 const std::vector<std::string_view>& names, size_t* columns) {
  StatusOr<LineReader> lines = LineReader::Open(path, kMaxLineBytes);
  if (!lines.ok()) return lines.status();
  CsvRows rows(std::move(lines).value());
  const std::string expected = fmt::format("{}", fmt::join(names, ","));
  StatusOr<bool> more = rows.Next();
  if (!more.ok()) return more.status();
  if (!*more) return rows.Error(1, fmt::format("missing header (expected \"{}\")", expected));
  const std::vector<CsvField>& fields = rows.fields();
  for (size_t i = 0; i < names.size(); ++i) {
    if (i >= fields.size()) {
      return rows.Error(
          static_cast<int64_t>(rows.line().size()) + 1,
          fmt::format("header: missing column \"{}\" (expected \"{}\")", names[i], expected));
    }
    if (fields[i].text != names[i]) {
      return rows.Error(fields[i].column,
                        fmt::format("header: expected \"{}\", found {} (the header \"{}\" is "
                                    "required)",
                                    names[i], QuotedField(fields[i].text), expected));
    }
  }
  *columns = fields.size();
  return rows;
}

struct PairHash {
  size_t operator()(const std::pair<int32_t, int32_t>& p) const {
    uint64_t key = (static_cast<uint64_t>(static_cast<uint32_t>(p.first)) << 32) |
                   static_cast<uint32_t>(p.second);
    return std::hash<uint64_t>()(key * 0x9E3779B97F4A7C15ULL);
  }
};

}  // namespace

StatusOr<std::vector<HexCounts>> ReadPriorMapCsv(const std::string& path, double hex_radius_m) {
  static const std::vector<std::string_view> kNames = {"q",  "r",  "x",  "y",  "c0",
                                                       "c1", "c2", "c3", "c4", "c5"};
  size_t columns = 0;
  StatusOr<CsvRows> opened = OpenWithHeader(path, kNames, &columns);
  if (!opened.ok()) return opened.status();
  CsvRows& rows = *opened;
  std::vector<HexCounts> hexes;
  std::unordered_map<std::pair<int32_t, int32_t>, int64_t, PairHash> first_line;
  for (;;) {
    StatusOr<bool> more = rows.Next();
    if (!more.ok()) return more.status();
    if (!*more) break;
    GROVE_RETURN_IF_ERROR(rows.CheckFieldCount(columns));
    const std::vector<CsvField>& f = rows.fields();
    HexCounts hex;
    GROVE_RETURN_IF_ERROR(rows.Int32(0, kNames[0], &hex.q));
    GROVE_RETURN_IF_ERROR(rows.Int32(1, kNames[1], &hex.r));
    GROVE_RETURN_IF_ERROR(rows.Double(2, kNames[2], &hex.x_m));
    GROVE_RETURN_IF_ERROR(rows.Double(3, kNames[3], &hex.y_m));
    double use = 0;
    for (size_t i = 4; i < 10; ++i) {
      double& count = hex.counts[i - 4];
      GROVE_RETURN_IF_ERROR(rows.Double(i, kNames[i], &count));
      if (count < 0.0) {
        return rows.Error(f[i].column, fmt::format("{}: {} is negative (counts are >= 0)",
                                                   kNames[i], QuotedField(f[i].text)));
      }
      use += count;
    }
    if (!std::isfinite(use)) {
      return rows.Error(f[4].column, "c0..c5: the sum of the counts is not finite");
    }
    if (hex_radius_m > 0) {
      // The centre of (q, r) (engine/footslam/hex_grid.h), written with four decimals.
      const double centre[2] = {hex_radius_m * std::sqrt(3.0) * (hex.q + 0.5 * hex.r),
                                1.5 * hex_radius_m * hex.r};
      const double given[2] = {hex.x_m, hex.y_m};
      for (int axis = 0; axis < 2; ++axis) {
        if (std::abs(given[axis] - centre[axis]) > 1e-3 + 1e-9 * std::abs(centre[axis])) {
          return rows.Error(
              f[2 + axis].column,
              fmt::format("{}: {} is not the centre of hexagon (q={}, r={}) at hex_radius_m = {} "
                          "(expected {:.4f}): the map was made with another hexagon radius",
                          kNames[2 + axis], QuotedField(f[2 + axis].text), hex.q, hex.r,
                          hex_radius_m, centre[axis]));
        }
      }
    }
    auto [it, inserted] = first_line.emplace(std::make_pair(hex.q, hex.r), rows.line_number());
    if (!inserted) {
      return rows.Error(f[0].column,
                        fmt::format("duplicate hexagon (q={}, r={}) (first on line {})", hex.q,
                                    hex.r, it->second));
    }
    hexes.push_back(hex);
  }
  return hexes;
}

StatusOr<std::vector<RenderHex>> ReadMapCsv(const std::string& path) {
  StatusOr<std::vector<HexCounts>> hexes = ReadPriorMapCsv(path, 0);
  if (!hexes.ok()) return hexes.status();
  std::vector<RenderHex> out;
  out.reserve(hexes->size());
  for (const HexCounts& h : *hexes) {
    RenderHex r{h.q, h.r, 0.0};
    for (double c : h.counts) r.use += c;
    out.push_back(r);
  }
  return out;
}

StatusOr<std::vector<RenderPoint>> ReadPathCsv(const std::string& path) {
  static const std::vector<std::string_view> kNames = {"t", "x", "y"};
  size_t columns = 0;
  StatusOr<CsvRows> opened = OpenWithHeader(path, kNames, &columns);
  if (!opened.ok()) return opened.status();
  CsvRows& rows = *opened;
  std::vector<RenderPoint> points;
  for (;;) {
    StatusOr<bool> more = rows.Next();
    if (!more.ok()) return more.status();
    if (!*more) break;
    GROVE_RETURN_IF_ERROR(rows.CheckFieldCount(columns));
    double t;
    RenderPoint p;
    GROVE_RETURN_IF_ERROR(rows.Double(0, kNames[0], &t));
    GROVE_RETURN_IF_ERROR(rows.Double(1, kNames[1], &p.x_m));
    GROVE_RETURN_IF_ERROR(rows.Double(2, kNames[2], &p.y_m));
    points.push_back(p);
  }
  return points;
}

}  // namespace grove::tools

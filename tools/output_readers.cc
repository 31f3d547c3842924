#include "tools/output_readers.h"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <utility>

namespace grove::tools {
namespace {

StatusOr<std::string> ReadWholeFile(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                       &std::fclose);
  if (file == nullptr) {
    int err = errno;
    std::string message =
        fmt::format("cannot open {}: {}", path, std::generic_category().message(err));
    if (err == ENOENT) return NotFoundError(std::move(message));
    return IoError(std::move(message));
  }
  std::string contents;
  char chunk[1 << 16];
  size_t n;
  while ((n = std::fread(chunk, 1, sizeof(chunk), file.get())) > 0) contents.append(chunk, n);
  if (std::ferror(file.get())) {
    return IoError(fmt::format("cannot read {}: {}", path, std::generic_category().message(errno)));
  }
  return contents;
}

struct Field {
  std::string_view text;  // without surrounding blanks
  size_t column;          // 1-based byte column of `text` in its line
};

std::vector<Field> SplitFields(std::string_view line) {
  std::vector<Field> fields;
  size_t start = 0;
  while (true) {
    size_t end = line.find(',', start);
    size_t stop = end == std::string_view::npos ? line.size() : end;
    size_t b = start;
    while (b < stop && (line[b] == ' ' || line[b] == '\t')) ++b;
    size_t e = stop;
    while (e > b && (line[e - 1] == ' ' || line[e - 1] == '\t')) --e;
    fields.push_back({line.substr(b, e - b), b + 1});
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  return fields;
}

// Quotes a field for a message, shortened so one bad line cannot flood the terminal.
std::string Quoted(std::string_view text) {
  constexpr size_t kMaxChars = 40;
  if (text.size() <= kMaxChars) return fmt::format("\"{}\"", text);
  return fmt::format("\"{}...\"", text.substr(0, kMaxChars));
}

// Walks the non-blank lines of a CSV file and formats errors at a position.
class CsvCursor {
 public:
  CsvCursor(const std::string& path, std::string_view contents) : path_(path), rest_(contents) {}

  // Advances to the next non-blank line; false at the end of the file.
  bool Next() {
    while (!rest_.empty()) {
      size_t end = rest_.find('\n');
      line_ = rest_.substr(0, end);
      rest_ = end == std::string_view::npos ? std::string_view() : rest_.substr(end + 1);
      ++line_number_;
      if (!line_.empty() && line_.back() == '\r') line_.remove_suffix(1);
      if (line_.find_first_not_of(" \t") != std::string_view::npos) return true;
    }
    line_ = {};
    return false;
  }

  std::string_view line() const { return line_; }
  int64_t line_number() const { return line_number_; }

  Status Error(size_t column, std::string_view what) const {
    return InvalidArgumentError(
        fmt::format("{}:{}:{}: {}", path_, std::max<int64_t>(line_number_, 1), column, what));
  }

 private:
  const std::string& path_;
  std::string_view rest_;
  std::string_view line_;
  int64_t line_number_ = 0;
};

// Checks that the header starts with `names`; returns its field count.
StatusOr<size_t> ReadHeader(CsvCursor& cursor, const std::vector<std::string_view>& names) {
  std::string expected = fmt::format("{}", fmt::join(names, ","));
  if (!cursor.Next()) {
    return cursor.Error(1, fmt::format("missing header (expected \"{}\")", expected));
  }
  std::vector<Field> fields = SplitFields(cursor.line());
  for (size_t i = 0; i < names.size(); ++i) {
    if (i >= fields.size()) {
      return cursor.Error(
          cursor.line().size() + 1,
          fmt::format("header: missing column \"{}\" (expected \"{}\")", names[i], expected));
    }
    if (fields[i].text != names[i]) {
      return cursor.Error(fields[i].column,
                          fmt::format("header: expected \"{}\", found {} (the header \"{}\" is "
                                      "required)",
                                      names[i], Quoted(fields[i].text), expected));
    }
  }
  return fields.size();
}

// Splits the current line into exactly `count` fields.
StatusOr<std::vector<Field>> RowFields(const CsvCursor& cursor, size_t count) {
  std::vector<Field> fields = SplitFields(cursor.line());
  if (fields.size() < count) {
    return cursor.Error(cursor.line().size() + 1,
                        fmt::format("expected {} fields, found {}", count, fields.size()));
  }
  if (fields.size() > count) {
    return cursor.Error(fields[count].column,
                        fmt::format("expected {} fields, found {}", count, fields.size()));
  }
  return fields;
}

Status ParseDouble(const CsvCursor& cursor, const Field& field, std::string_view name,
                   double* value) {
  std::string_view text = field.text;
  if (text.empty()) return cursor.Error(field.column, fmt::format("{}: missing value", name));
  // from_chars rejects a leading '+', which other tools write.
  if (text.size() > 1 && text[0] == '+' && text[1] != '-') text.remove_prefix(1);
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), *value);
  if (ec == std::errc::result_out_of_range) {
    return cursor.Error(field.column,
                        fmt::format("{}: {} is out of range", name, Quoted(field.text)));
  }
  if (ec != std::errc() || ptr != text.data() + text.size()) {
    return cursor.Error(field.column,
                        fmt::format("{}: {} is not a number", name, Quoted(field.text)));
  }
  if (!std::isfinite(*value)) {
    return cursor.Error(field.column,
                        fmt::format("{}: {} is not finite", name, Quoted(field.text)));
  }
  return Status::Ok();
}

Status ParseInt32(const CsvCursor& cursor, const Field& field, std::string_view name,
                  int32_t* value) {
  std::string_view text = field.text;
  if (text.empty()) return cursor.Error(field.column, fmt::format("{}: missing value", name));
  if (text.size() > 1 && text[0] == '+' && text[1] != '-') text.remove_prefix(1);
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), *value);
  if (ec == std::errc::result_out_of_range) {
    return cursor.Error(field.column,
                        fmt::format("{}: {} is outside the int32 range", name, Quoted(field.text)));
  }
  if (ec != std::errc() || ptr != text.data() + text.size()) {
    return cursor.Error(field.column,
                        fmt::format("{}: {} is not an integer", name, Quoted(field.text)));
  }
  return Status::Ok();
}

struct PairHash {
  size_t operator()(const std::pair<int32_t, int32_t>& p) const {
    uint64_t key = (static_cast<uint64_t>(static_cast<uint32_t>(p.first)) << 32) |
                   static_cast<uint32_t>(p.second);
    return std::hash<uint64_t>()(key * 0x9E3779B97F4A7C15ULL);
  }
};

}  // namespace

StatusOr<std::vector<RenderHex>> ReadMapCsv(const std::string& path) {
  StatusOr<std::string> contents = ReadWholeFile(path);
  if (!contents.ok()) return contents.status();
  static const std::vector<std::string_view> kNames = {"q",  "r",  "x",  "y",  "c0",
                                                       "c1", "c2", "c3", "c4", "c5"};
  CsvCursor cursor(path, *contents);
  StatusOr<size_t> columns = ReadHeader(cursor, kNames);
  if (!columns.ok()) return columns.status();
  std::vector<RenderHex> hexes;
  std::unordered_map<std::pair<int32_t, int32_t>, int64_t, PairHash> first_line;
  while (cursor.Next()) {
    StatusOr<std::vector<Field>> fields = RowFields(cursor, *columns);
    if (!fields.ok()) return fields.status();
    const std::vector<Field>& f = *fields;
    RenderHex hex;
    GROVE_RETURN_IF_ERROR(ParseInt32(cursor, f[0], kNames[0], &hex.q));
    GROVE_RETURN_IF_ERROR(ParseInt32(cursor, f[1], kNames[1], &hex.r));
    double unused;
    GROVE_RETURN_IF_ERROR(ParseDouble(cursor, f[2], kNames[2], &unused));
    GROVE_RETURN_IF_ERROR(ParseDouble(cursor, f[3], kNames[3], &unused));
    for (size_t i = 4; i < 10; ++i) {
      double count;
      GROVE_RETURN_IF_ERROR(ParseDouble(cursor, f[i], kNames[i], &count));
      if (count < 0.0) {
        return cursor.Error(f[i].column, fmt::format("{}: {} is negative (counts are >= 0)",
                                                     kNames[i], Quoted(f[i].text)));
      }
      hex.use += count;
    }
    if (!std::isfinite(hex.use)) {
      return cursor.Error(f[4].column, "c0..c5: the sum of the counts is not finite");
    }
    auto [it, inserted] = first_line.emplace(std::make_pair(hex.q, hex.r), cursor.line_number());
    if (!inserted) {
      return cursor.Error(f[0].column,
                          fmt::format("duplicate hexagon (q={}, r={}) (first on line {})", hex.q,
                                      hex.r, it->second));
    }
    hexes.push_back(hex);
  }
  return hexes;
}

StatusOr<std::vector<RenderPoint>> ReadPathCsv(const std::string& path) {
  StatusOr<std::string> contents = ReadWholeFile(path);
  if (!contents.ok()) return contents.status();
  static const std::vector<std::string_view> kNames = {"t", "x", "y"};
  CsvCursor cursor(path, *contents);
  StatusOr<size_t> columns = ReadHeader(cursor, kNames);
  if (!columns.ok()) return columns.status();
  std::vector<RenderPoint> points;
  while (cursor.Next()) {
    StatusOr<std::vector<Field>> fields = RowFields(cursor, *columns);
    if (!fields.ok()) return fields.status();
    const std::vector<Field>& f = *fields;
    double t;
    RenderPoint p;
    GROVE_RETURN_IF_ERROR(ParseDouble(cursor, f[0], kNames[0], &t));
    GROVE_RETURN_IF_ERROR(ParseDouble(cursor, f[1], kNames[1], &p.x_m));
    GROVE_RETURN_IF_ERROR(ParseDouble(cursor, f[2], kNames[2], &p.y_m));
    points.push_back(p);
  }
  return points;
}

}  // namespace grove::tools

#include "tools/step_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <system_error>
#include <utility>

namespace grove::tools {
namespace internal {
namespace {

constexpr size_t kMinBufferBytes = size_t{64} << 10;
constexpr size_t kMinLineBytes = 16;
constexpr size_t kMaxLineBytes = size_t{64} << 20;
constexpr std::string_view kByteOrderMark = "\xEF\xBB\xBF";

bool IsBlank(char c) { return c == ' ' || c == '\t'; }

}  // namespace

StatusOr<LineReader> LineReader::Open(const std::string& path, size_t max_line_bytes) {
  if (max_line_bytes < kMinLineBytes || max_line_bytes > kMaxLineBytes) {
    return InvalidArgumentError(fmt::format("max_line_bytes = {}: must be in [{}, {}]",
                                            max_line_bytes, kMinLineBytes, kMaxLineBytes));
  }
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found) {
    return NotFoundError(fmt::format("{}: no such file", path));
  }
  if (ec) return IoError(fmt::format("{}: {}", path, ec.message()));
  if (std::filesystem::is_directory(status)) {
    return InvalidArgumentError(fmt::format("{}: is a directory, not a file", path));
  }
  auto in = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!in->is_open()) return IoError(fmt::format("{}: cannot open for reading", path));
  return FromStream(path, std::move(in), max_line_bytes);
}

StatusOr<LineReader> LineReader::FromStream(const std::string& path,
                                            std::unique_ptr<std::istream> in,
                                            size_t max_line_bytes) {
  if (max_line_bytes < kMinLineBytes || max_line_bytes > kMaxLineBytes) {
    return InvalidArgumentError(fmt::format("max_line_bytes = {}: must be in [{}, {}]",
                                            max_line_bytes, kMinLineBytes, kMaxLineBytes));
  }
  LineReader reader;
  reader.path_ = path;
  reader.max_line_bytes_ = max_line_bytes;
  reader.in_ = std::move(in);
  reader.buffer_.resize(std::max(kMinBufferBytes, max_line_bytes + 2));
  return reader;
}

StatusOr<bool> LineReader::Next(std::string_view* line) {
  if (!error_.ok()) return error_;
  for (;;) {
    const size_t pending = end_ - begin_;
    const void* newline =
        pending == 0 ? nullptr : std::memchr(buffer_.data() + begin_, '\n', pending);
    if (newline != nullptr) {
      const size_t stop = static_cast<const char*>(newline) - buffer_.data();
      const size_t first = begin_;
      begin_ = stop + 1;
      return Finish(first, stop, line);
    }
    if (eof_) {
      if (pending == 0) return false;
      const size_t first = begin_;
      begin_ = end_;
      return Finish(first, end_, line);
    }
    // No newline yet. More than max + 1 bytes (a '\r' may precede the '\n') is too long already.
    if (pending > max_line_bytes_ + 1) {
      ++line_number_;
      error_ = LineError(path_, line_number_, 1,
                         fmt::format("line longer than {} bytes", max_line_bytes_));
      return error_;
    }
    if (begin_ > 0) {
      std::memmove(buffer_.data(), buffer_.data() + begin_, pending);
      begin_ = 0;
      end_ = pending;
    }
    // The buffer holds at least max + 2 bytes, so there is room for one more byte at least.
    in_->read(buffer_.data() + end_, static_cast<std::streamsize>(buffer_.size() - end_));
    end_ += static_cast<size_t>(in_->gcount());
    if (in_->bad() || (in_->fail() && !in_->eof())) {
      error_ = IoError(fmt::format("{}: read failed after line {}", path_, line_number_));
      return error_;
    }
    if (in_->eof()) eof_ = true;
  }
}

StatusOr<bool> LineReader::Finish(size_t first, size_t stop, std::string_view* line) {
  ++line_number_;
  std::string_view text(buffer_.data() + first, stop - first);
  if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
  if (line_number_ == 1 && text.starts_with(kByteOrderMark)) text.remove_prefix(3);
  if (text.size() > max_line_bytes_) {
    error_ = LineError(path_, line_number_, 1,
                       fmt::format("line longer than {} bytes", max_line_bytes_));
    return error_;
  }
  *line = text;
  return true;
}

void SplitCsvLine(std::string_view line, std::vector<CsvField>* fields) {
  fields->clear();
  size_t start = 0;
  for (;;) {
    size_t stop = line.find(',', start);
    if (stop == std::string_view::npos) stop = line.size();
    size_t first = start;
    while (first < stop && IsBlank(line[first])) ++first;
    size_t last = stop;
    while (last > first && IsBlank(line[last - 1])) --last;
    const size_t column = first < stop ? first : start;
    fields->push_back({line.substr(first, last - first), static_cast<int64_t>(column) + 1});
    if (stop == line.size()) break;
    start = stop + 1;
  }
}

bool IsSkippedLine(std::string_view line) {
  for (char c : line) {
    if (!IsBlank(c)) return c == '#';
  }
  return true;
}

Status LineError(std::string_view path, int64_t line, int64_t column, std::string_view what) {
  return InvalidArgumentError(fmt::format("{}:{}:{}: {}", path, line, column, what));
}

Status ParseFiniteNumber(std::string_view path, int64_t line, const CsvField& field,
                         std::string_view name, double* value) {
  std::string_view text = field.text;
  // from_chars takes no '+'; accept exactly one in front of a digit or '.'.
  if (text.size() > 1 && text[0] == '+' && text[1] != '+' && text[1] != '-') text.remove_prefix(1);
  double parsed = 0;
  const auto [end, ec] =
      std::from_chars(text.data(), text.data() + text.size(), parsed, std::chars_format::general);
  if (ec == std::errc::result_out_of_range && end == text.data() + text.size()) {
    return LineError(path, line, field.column,
                     fmt::format("{}: \"{}\" is out of the range of a double", name, field.text));
  }
  if (ec != std::errc() || end != text.data() + text.size() || text.empty()) {
    return LineError(path, line, field.column,
                     fmt::format("{}: \"{}\" is not a number", name, field.text));
  }
  if (!std::isfinite(parsed)) {
    return LineError(path, line, field.column,
                     fmt::format("{} = {}: must be finite", name, field.text));
  }
  *value = parsed;
  return Status::Ok();
}

}  // namespace internal

namespace {

constexpr double kMaxAbsTime = 1e12;
constexpr std::string_view kExpectedHeader = "expected a header \"t,dx,dy\" or \"t,x,y\"";

}  // namespace

StatusOr<StepReader> StepReader::Open(const std::string& path, const StepReaderOptions& options) {
  if (!(options.max_step_m > 0) || !std::isfinite(options.max_step_m)) {
    return InvalidArgumentError(
        fmt::format("max_step_m = {}: must be > 0 and finite", options.max_step_m));
  }
  StatusOr<internal::LineReader> lines = internal::LineReader::Open(path, options.max_line_bytes);
  if (!lines.ok()) return lines.status();
  return Start(std::move(lines).value(), options);
}

StatusOr<StepReader> StepReader::OpenText(const std::string& name, std::string text,
                                          const StepReaderOptions& options) {
  if (!(options.max_step_m > 0) || !std::isfinite(options.max_step_m)) {
    return InvalidArgumentError(
        fmt::format("max_step_m = {}: must be > 0 and finite", options.max_step_m));
  }
  StatusOr<internal::LineReader> lines = internal::LineReader::FromStream(
      name, std::make_unique<std::istringstream>(std::move(text)), options.max_line_bytes);
  if (!lines.ok()) return lines.status();
  return Start(std::move(lines).value(), options);
}

StatusOr<StepReader> StepReader::Start(internal::LineReader lines,
                                       const StepReaderOptions& options) {
  const std::string path = lines.path();
  StepReader reader(std::move(lines), options);

  std::string_view line;
  for (;;) {
    StatusOr<bool> more = reader.lines_.Next(&line);
    if (!more.ok()) return more.status();
    if (!*more) {
      return InvalidArgumentError(fmt::format("{}: empty file: {}", path, kExpectedHeader));
    }
    if (!internal::IsSkippedLine(line)) break;
  }
  internal::SplitCsvLine(line, &reader.fields_);
  const auto header_is = [&](std::string_view a, std::string_view b, std::string_view c) {
    const auto& f = reader.fields_;
    return f.size() == 3 && f[0].text == a && f[1].text == b && f[2].text == c;
  };
  if (header_is("t", "dx", "dy")) {
    reader.positions_form_ = false;
  } else if (header_is("t", "x", "y")) {
    reader.positions_form_ = true;
  } else {
    return internal::LineError(
        path, reader.lines_.line_number(), 1,
        fmt::format("unknown header \"{}\": expected \"t,dx,dy\" or \"t,x,y\"", line));
  }

  while (reader.lookahead_end_ < 2) {
    StatusOr<bool> more = reader.ReadRow(&reader.lookahead_[reader.lookahead_end_]);
    if (!more.ok()) return more.status();
    if (!*more) break;
    ++reader.lookahead_end_;
  }
  const Row* rows = reader.lookahead_;
  if (reader.positions_form_) {
    if (reader.lookahead_end_ >= 1) {
      reader.start_time_s_ = rows[0].t_s;
      reader.start_x_m_ = reader.previous_x_m_ = rows[0].a_m;
      reader.start_y_m_ = reader.previous_y_m_ = rows[0].b_m;
      reader.lookahead_begin_ = 1;  // the first position is the start, not a step
    }
  } else if (reader.lookahead_end_ == 2) {
    reader.start_time_s_ = rows[0].t_s - (rows[1].t_s - rows[0].t_s);
  } else if (reader.lookahead_end_ == 1) {
    reader.start_time_s_ = rows[0].t_s - 1;
  }
  return reader;
}

StatusOr<bool> StepReader::ReadRow(Row* row) {
  std::string_view line;
  for (;;) {
    StatusOr<bool> more = lines_.Next(&line);
    if (!more.ok()) return more.status();
    if (!*more) return false;
    if (!internal::IsSkippedLine(line)) break;
  }
  const std::string& path = lines_.path();
  const int64_t number = lines_.line_number();
  internal::SplitCsvLine(line, &fields_);
  if (fields_.size() != 3) {
    return internal::LineError(path, number, 1,
                               fmt::format("expected 3 fields, found {}", fields_.size()));
  }
  Row parsed{0, 0, 0, number};
  GROVE_RETURN_IF_ERROR(internal::ParseFiniteNumber(path, number, fields_[0], "t", &parsed.t_s));
  // Bounded so that time differences and the start time before the first step stay exact enough
  // to be strictly ordered (a second is still resolved at 1e12 s, about 31,700 years).
  if (std::fabs(parsed.t_s) > kMaxAbsTime) {
    return internal::LineError(path, number, fields_[0].column,
                               fmt::format("t = {}: must be within +-{:g} s", parsed.t_s,
                                           kMaxAbsTime));
  }
  GROVE_RETURN_IF_ERROR(internal::ParseFiniteNumber(path, number, fields_[1],
                                                    positions_form_ ? "x" : "dx", &parsed.a_m));
  GROVE_RETURN_IF_ERROR(internal::ParseFiniteNumber(path, number, fields_[2],
                                                    positions_form_ ? "y" : "dy", &parsed.b_m));
  if (has_previous_time_ && !(parsed.t_s > previous_time_s_)) {
    return internal::LineError(
        path, number, fields_[0].column,
        fmt::format("t = {} is not after the previous time {}: times must be strictly increasing",
                    parsed.t_s, previous_time_s_));
  }
  has_previous_time_ = true;
  previous_time_s_ = parsed.t_s;
  *row = parsed;
  return true;
}

StatusOr<bool> StepReader::Next(StepRecord* step) {
  if (!error_.ok()) return error_;
  Row row;
  if (lookahead_begin_ < lookahead_end_) {
    row = lookahead_[lookahead_begin_++];
  } else {
    StatusOr<bool> more = ReadRow(&row);
    if (!more.ok()) {
      error_ = more.status();
      return error_;
    }
    if (!*more) {
      if (steps_read_ > 0) return false;
      const bool one_position = positions_form_ && has_previous_time_;
      error_ = InvalidArgumentError(
          fmt::format("{}: no steps after the header{}", path(),
                      one_position ? " (a t,x,y file needs two rows for one step)" : ""));
      return error_;
    }
  }
  double dx = row.a_m;
  double dy = row.b_m;
  if (positions_form_) {
    dx = row.a_m - previous_x_m_;
    dy = row.b_m - previous_y_m_;
  }
  const double length = std::hypot(dx, dy);
  if (!(length <= options_.max_step_m)) {
    error_ = internal::LineError(path(), row.line, 1,
                                 fmt::format("step of {:.6g} m is longer than max_step_m = {}",
                                             length, options_.max_step_m));
    return error_;
  }
  if (positions_form_) {
    previous_x_m_ = row.a_m;
    previous_y_m_ = row.b_m;
  }
  *step = StepRecord{row.t_s, dx, dy, row.line};
  ++steps_read_;
  return true;
}

StatusOr<std::vector<StepRecord>> ReadAllSteps(const std::string& path,
                                               const StepReaderOptions& options) {
  StatusOr<StepReader> reader = StepReader::Open(path, options);
  if (!reader.ok()) return reader.status();
  std::vector<StepRecord> steps;
  StepRecord step;
  for (;;) {
    StatusOr<bool> more = reader->Next(&step);
    if (!more.ok()) return more.status();
    if (!*more) break;
    steps.push_back(step);
  }
  return steps;
}

}  // namespace grove::tools

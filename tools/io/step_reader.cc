#include "tools/io/step_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <memory>
#include <sstream>
#include <string_view>
#include <utility>

#include "grove/input_rules.h"

namespace grove::tools {
namespace {

constexpr std::string_view kExpectedHeader = "expected a header \"t,dx,dy\" or \"t,x,y\"";
// The columns a deltas-form file may add after t,dx,dy (the foot IMU front end writes them);
// checked, not used.
constexpr std::string_view kOptionalColumns[] = {
    "dz",     "dheading",        "var_dx",          "cov_dx_dy",
    "var_dy", "cov_dx_dheading", "cov_dy_dheading", "var_dheading"};

}  // namespace

Status StepReader::CheckLineEnd(std::string_view line) const {
  if (lines_.line_terminated() || options_.allow_unterminated_last_line) return Status::Ok();
  return LineError(lines_.path(), lines_.line_number(), static_cast<int64_t>(line.size()) + 1,
                   "the last line has no line end: the file may still be being written; a "
                   "complete step file ends in a newline");
}

StatusOr<StepReader> StepReader::Open(const std::string& path, const StepReaderOptions& options) {
  if (!(options.max_step_m > 0) || !std::isfinite(options.max_step_m)) {
    return InvalidArgumentError(
        fmt::format("max_step_m = {}: must be > 0 and finite", options.max_step_m));
  }
  StatusOr<LineReader> lines = LineReader::Open(path, options.max_line_bytes);
  if (!lines.ok()) return lines.status();
  return Start(std::move(lines).value(), options);
}

StatusOr<StepReader> StepReader::OpenText(const std::string& name, std::string text,
                                          const StepReaderOptions& options) {
  if (!(options.max_step_m > 0) || !std::isfinite(options.max_step_m)) {
    return InvalidArgumentError(
        fmt::format("max_step_m = {}: must be > 0 and finite", options.max_step_m));
  }
  StatusOr<LineReader> lines = LineReader::FromStream(
      name, std::make_unique<std::istringstream>(std::move(text)), options.max_line_bytes);
  if (!lines.ok()) return lines.status();
  return Start(std::move(lines).value(), options);
}

StatusOr<StepReader> StepReader::Start(LineReader lines, const StepReaderOptions& options) {
  const std::string path = lines.path();
  StepReader reader(std::move(lines), options);

  std::string_view line;
  for (;;) {
    StatusOr<bool> more = reader.lines_.Next(&line);
    if (!more.ok()) return more.status();
    if (!*more) {
      return InvalidArgumentError(fmt::format("{}: empty file: {}", path, kExpectedHeader));
    }
    GROVE_RETURN_IF_ERROR(reader.CheckLineEnd(line));
    if (!IsSkippedLine(line)) break;
  }
  SplitCsvLine(line, &reader.fields_);
  const auto header_is = [&](std::string_view a, std::string_view b, std::string_view c) {
    const auto& f = reader.fields_;
    return f.size() == 3 && f[0].text == a && f[1].text == b && f[2].text == c;
  };
  const auto& f = reader.fields_;
  const bool deltas_with_extras =
      f.size() > 3 && f[0].text == "t" && f[1].text == "dx" && f[2].text == "dy";
  if (header_is("t", "dx", "dy")) {
    reader.positions_form_ = false;
  } else if (deltas_with_extras) {
    reader.positions_form_ = false;
    for (size_t c = 3; c < f.size(); ++c) {
      const bool known = std::find(std::begin(kOptionalColumns), std::end(kOptionalColumns),
                                   f[c].text) != std::end(kOptionalColumns);
      const bool repeated = std::find(reader.extra_columns_.begin(), reader.extra_columns_.end(),
                                      f[c].text) != reader.extra_columns_.end();
      if (!known || repeated) {
        return LineError(path, reader.lines_.line_number(), f[c].column,
                         fmt::format("{} column {}: after t,dx,dy a step file may have dz, "
                                     "dheading, var_dx, cov_dx_dy, var_dy, cov_dx_dheading, "
                                     "cov_dy_dheading and var_dheading, each once",
                                     repeated ? "repeated" : "unknown", QuotedField(f[c].text)));
      }
      reader.extra_columns_.emplace_back(f[c].text);
    }
  } else if (header_is("t", "x", "y")) {
    reader.positions_form_ = true;
  } else {
    return LineError(
        path, reader.lines_.line_number(), 1,
        fmt::format("unknown header {}: expected \"t,dx,dy\" or \"t,x,y\"", QuotedField(line)));
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
    GROVE_RETURN_IF_ERROR(CheckLineEnd(line));
    if (!IsSkippedLine(line)) break;
  }
  const std::string& path = lines_.path();
  const int64_t number = lines_.line_number();
  SplitCsvLine(line, &fields_);
  const size_t columns = 3 + extra_columns_.size();
  if (fields_.size() != columns) {
    return LineError(path, number, 1,
                     fmt::format("expected {} fields, found {}", columns, fields_.size()));
  }
  for (size_t c = 3; c < columns; ++c) {
    double value = 0;
    const std::string& name = extra_columns_[c - 3];
    GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, number, fields_[c], name, &value));
    if (name.starts_with("var_") && value < 0) {
      return LineError(path, number, fields_[c].column,
                       fmt::format("{} = {}: a variance must be >= 0", name, value));
    }
  }
  Row parsed{0, 0, 0, number};
  GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path, number, fields_[0], "t", &parsed.t_s));
  // The engine's bound (grove/input_rules.h): time differences and the start time before the
  // first step stay exact enough to be strictly ordered.
  GROVE_RETURN_IF_ERROR(
      AtField(path, number, fields_[0], CheckInput(InputField::kTime, parsed.t_s)));
  GROVE_RETURN_IF_ERROR(
      ParseFiniteNumber(path, number, fields_[1], positions_form_ ? "x" : "dx", &parsed.a_m));
  GROVE_RETURN_IF_ERROR(
      ParseFiniteNumber(path, number, fields_[2], positions_form_ ? "y" : "dy", &parsed.b_m));
  if (!positions_form_) {
    GROVE_RETURN_IF_ERROR(
        AtField(path, number, fields_[1], CheckInput(InputField::kStepDx, parsed.a_m)));
    GROVE_RETURN_IF_ERROR(
        AtField(path, number, fields_[2], CheckInput(InputField::kStepDy, parsed.b_m)));
  }
  if (has_previous_time_ && !(parsed.t_s > previous_time_s_)) {
    return LineError(
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
    error_ = LineError(path(), row.line, 1,
                       fmt::format("step of {:.6g} m is longer than max_step_m = {}", length,
                                   options_.max_step_m));
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
                                               const StepReaderOptions& options,
                                               double* start_time_s) {
  StatusOr<StepReader> reader = StepReader::Open(path, options);
  if (!reader.ok()) return reader.status();
  if (start_time_s != nullptr) *start_time_s = reader->start_time_s();
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

#include "tools/io/imu_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "tools/io/csv_reader.h"
#include "tools/io/gzip_line_reader.h"
#include "tools/io/mat_file.h"

namespace grove::tools {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kStandardGravity = 9.80665;
constexpr const char* kNames[6] = {"ax", "ay", "az", "gx", "gy", "gz"};
constexpr int kRateIntervals = 64;  // intervals whose median the rate is checked against
constexpr double kRateTolerance = 0.05;
constexpr size_t kMaxLineBytes = 4096;

// Lower case, without blanks, underscores and hyphens.
std::string Normalise(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == ' ' || c == '\t' || c == '_' || c == '-') continue;
    out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return out;
}

// The unit of a unit name, in SI per unit, or nullopt.
std::optional<double> AccelUnit(const std::string& u) {
  if (u == "m/s^2" || u == "m/s2" || u == "mps2" || u == "m/s\xc2\xb2") return 1.0;
  if (u == "g") return kStandardGravity;
  return std::nullopt;
}
std::optional<double> GyroUnit(const std::string& u) {
  if (u == "rad/s" || u == "rads") return 1.0;
  if (u == "deg/s" || u == "dps" || u == "\xc2\xb0/s") return kPi / 180;
  return std::nullopt;
}
std::optional<double> TimeUnit(const std::string& u) {
  if (u == "s") return 1.0;
  if (u == "ms") return 1e-3;
  if (u == "us") return 1e-6;
  return std::nullopt;
}

// What a header field names: -1 time, 0..5 ax..gz, -2 nothing of ours.
int ColumnRole(const std::string& base) {
  static const std::pair<const char*, int> kKnown[] = {
      {"t", -1},
      {"time", -1},
      {"ts", -1},
      {"timestamp", -1},
      {"ax", 0},
      {"ay", 1},
      {"az", 2},
      {"accx", 0},
      {"accy", 1},
      {"accz", 2},
      {"accelx", 0},
      {"accely", 1},
      {"accelz", 2},
      {"accelerometerx", 0},
      {"accelerometery", 1},
      {"accelerometerz", 2},
      {"gx", 3},
      {"gy", 4},
      {"gz", 5},
      {"gyrx", 3},
      {"gyry", 4},
      {"gyrz", 5},
      {"gyrox", 3},
      {"gyroy", 4},
      {"gyroz", 5},
      {"gyroscopex", 3},
      {"gyroscopey", 4},
      {"gyroscopez", 5},
  };
  for (const auto& [name, role] : kKnown) {
    if (base == name) return role;
  }
  return -2;
}

}  // namespace

Status ParseImuUnits(const std::string& text, ImuReaderOptions* options) {
  const size_t comma = text.find(',');
  const std::string accel = comma == std::string::npos ? text : text.substr(0, comma);
  const std::string gyro = comma == std::string::npos ? "" : text.substr(comma + 1);
  const std::optional<double> a = AccelUnit(Normalise(accel));
  const std::optional<double> g = GyroUnit(Normalise(gyro));
  if (!a || !g) {
    return InvalidArgumentError(fmt::format(
        "--units = {}: must be ACCEL,GYRO with ACCEL m/s^2 or g and GYRO rad/s or deg/s "
        "(e.g. g,deg/s)",
        QuoteForMessage(text)));
  }
  options->accel_unit_mps2 = *a;
  options->gyro_unit_radps = *g;
  return Status::Ok();
}

// The checks every format shares; a format supplies rows and says where they are.
class ImuReader::Source {
 public:
  virtual ~Source() = default;

  StatusOr<bool> Next(ImuRecord* record) {
    if (!error_.ok()) return error_;
    StatusOr<bool> more = NextChecked(record);
    if (!more.ok()) error_ = more.status();
    return more;
  }

  virtual std::string Where(int64_t line) const = 0;
  virtual const char* format() const = 0;
  int64_t duplicates() const { return duplicates_; }
  const std::string& path() const { return path_; }

 protected:
  // One row as read: the time (when the file has one) and the six values in SI units.
  struct Row {
    bool has_time = false;
    double t_s = 0;
    std::array<double, 6> values = {};
    std::array<double, 6> raw = {};  // as written, for messages
    int64_t line = 0;
  };
  static constexpr int kTimeField = -1;
  static constexpr int kWholeRow = -2;

  Source(std::string path, const ImuReaderOptions& options)
      : path_(std::move(path)), options_(options) {}
  // The next row, its numbers parsed; false at the end.
  virtual StatusOr<bool> ReadRow(Row* row) = 0;
  // An InvalidArgument at `field` (kTimeField, 0..5, kWholeRow) of `row`.
  virtual Status FieldError(const Row& row, int field, const std::string& what) const = 0;
  // The unit of value `field` as written ("g", "deg/s", ...).
  virtual std::string UnitName(int field) const = 0;

  std::string path_;
  ImuReaderOptions options_;

 private:
  StatusOr<bool> NextChecked(ImuRecord* record) {
    Row row;
    for (;;) {
      StatusOr<bool> more = ReadRow(&row);
      if (!more.ok()) return more.status();
      if (!*more) {
        if (samples_ == 0) {
          return InvalidArgumentError(fmt::format("{}: no samples after the header", path_));
        }
        GROVE_RETURN_IF_ERROR(CheckRate(last_, true));
        return false;
      }
      if (!row.has_time) {
        if (!(options_.rate_hz > 0)) {
          return FieldError(row, kWholeRow, "no time column: give the rate (--rate)");
        }
        row.t_s = static_cast<double>(samples_) / options_.rate_hz;
      }
      if (samples_ > 0 && row.has_time && row.t_s == last_.t_s && row.raw == last_.raw) {
        ++duplicates_;
        continue;
      }
      break;
    }
    for (int i = 0; i < 6; ++i) {
      const double range = i < 3 ? options_.accel_range_mps2 : options_.gyro_range_radps;
      if (std::fabs(row.values[i]) >= range) {
        return FieldError(
            row, i,
            fmt::format("{} = {} {}: saturated: |{:.6g}| {} reaches the {} range "
                        "{:.6g} {}",
                        kNames[i], row.raw[i], UnitName(i), row.values[i],
                        i < 3 ? "m/s^2" : "rad/s", i < 3 ? "accelerometer's" : "gyroscope's", range,
                        i < 3 ? "m/s^2" : "rad/s"));
      }
    }
    if (samples_ > 0) {
      if (!(row.t_s > last_.t_s)) {
        return FieldError(row, kTimeField,
                          fmt::format("t = {} is not after the previous sample's {} (line {}): "
                                      "times must increase",
                                      row.t_s, last_.t_s, last_.line));
      }
      const double interval = row.t_s - last_.t_s;
      if (interval > options_.max_interval_s) {
        return FieldError(row, kTimeField,
                          fmt::format("t = {}: a gap of {:.6g} s after the previous sample (line "
                                      "{}), more than max_sample_interval_s = {} s",
                                      row.t_s, interval, last_.line, options_.max_interval_s));
      }
      if (intervals_.size() < kRateIntervals) {
        intervals_.push_back(interval);
        if (intervals_.size() == kRateIntervals) GROVE_RETURN_IF_ERROR(CheckRate(row, false));
      }
    }
    ++samples_;
    last_ = row;
    record->line = row.line;
    record->sample.t_s = row.t_s;
    for (int i = 0; i < 3; ++i) {
      record->sample.accel_mps2[i] = row.values[i];
      record->sample.gyro_radps[i] = row.values[3 + i];
    }
    return true;
  }

  // With a rate and a time column: the median of the intervals so far against the rate, once
  // kRateIntervals are in (or at the end of a shorter file).
  Status CheckRate(const Row& row, bool at_end) {
    if (!(options_.rate_hz > 0) || !row.has_time || intervals_.empty()) return Status::Ok();
    if (at_end && intervals_.size() >= kRateIntervals) return Status::Ok();  // checked already
    std::vector<double> sorted = intervals_;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double median = sorted[sorted.size() / 2];
    if (std::fabs(median * options_.rate_hz - 1) <= kRateTolerance) return Status::Ok();
    return FieldError(row, kTimeField,
                      fmt::format("t: the median interval of the first {} is {:.6g} s ({:.6g} "
                                  "Hz): the rate {} Hz (--rate) does not match the time column "
                                  "(more than 5 % apart)",
                                  intervals_.size(), median, 1 / median, options_.rate_hz));
  }

  Status error_;
  int64_t samples_ = 0;
  int64_t duplicates_ = 0;
  Row last_;
  std::vector<double> intervals_;
};

namespace {

class CsvSource final : public ImuReader::Source {
 public:
  static StatusOr<std::unique_ptr<CsvSource>> Open(const std::string& path,
                                                   const ImuReaderOptions& options) {
    StatusOr<LineReader> lines = OpenMaybeCompressed(path, kMaxLineBytes);
    if (!lines.ok()) return lines.status();
    auto source =
        std::unique_ptr<CsvSource>(new CsvSource(path, options, std::move(lines).value()));
    GROVE_RETURN_IF_ERROR(source->ReadHeader());
    return source;
  }

  std::string Where(int64_t line) const override { return fmt::format("{}:{}", path_, line); }
  const char* format() const override { return "CSV"; }

 protected:
  StatusOr<bool> ReadRow(Row* row) override {
    std::string_view line;
    StatusOr<bool> more = NextLine(&line);
    if (!more.ok() || !*more) return more;
    SplitCsvLine(line, &fields_);
    row->line = lines_.line_number();
    if (fields_.size() != columns_) {
      return LineError(
          path_, row->line, 1,
          fmt::format("expected {} fields as the header, found {}", columns_, fields_.size()));
    }
    row->has_time = time_column_ >= 0;
    if (row->has_time) {
      GROVE_RETURN_IF_ERROR(
          ParseFiniteNumber(path_, row->line, fields_[time_column_], "t", &row->t_s));
      row->t_s *= time_unit_;
    }
    for (int i = 0; i < 6; ++i) {
      GROVE_RETURN_IF_ERROR(
          ParseFiniteNumber(path_, row->line, fields_[value_columns_[i]], kNames[i], &row->raw[i]));
      row->values[i] = row->raw[i] * units_[i];
    }
    return true;
  }

  Status FieldError(const Row& row, int field, const std::string& what) const override {
    int64_t column = 1;
    if (field == kTimeField && time_column_ >= 0) column = field_columns_[time_column_];
    if (field >= 0) column = field_columns_[value_columns_[field]];
    return LineError(path_, row.line, column, what);
  }

  std::string UnitName(int field) const override { return unit_names_[field]; }

 private:
  CsvSource(const std::string& path, const ImuReaderOptions& options, LineReader lines)
      : Source(path, options), lines_(std::move(lines)) {}

  // The next line that is not blank or a comment: false at the end.
  StatusOr<bool> NextLine(std::string_view* line) {
    for (;;) {
      StatusOr<bool> more = lines_.Next(line);
      if (!more.ok() || !*more) return more;
      if (!lines_.line_terminated()) {
        return LineError(path_, lines_.line_number(), static_cast<int64_t>(line->size()) + 1,
                         "the last line has no line end: the file may still be being written; "
                         "a complete recording ends in a newline");
      }
      if (!IsSkippedLine(*line)) return true;
    }
  }

  Status ReadHeader() {
    std::string_view line;
    StatusOr<bool> more = NextLine(&line);
    if (!more.ok()) return more.status();
    if (!*more) {
      return InvalidArgumentError(
          fmt::format("{}: empty file: expected a header such as \"t,ax,ay,az,gx,gy,gz\"", path_));
    }
    SplitCsvLine(line, &fields_);
    columns_ = fields_.size();
    value_columns_.fill(-1);
    for (size_t c = 0; c < fields_.size(); ++c) {
      field_columns_.push_back(fields_[c].column);
      std::string name(fields_[c].text);
      std::string unit;
      // A unit after the name: "Accelerometer X (g)", "gx [deg/s]".
      for (auto [open, close] : {std::pair{'(', ')'}, std::pair{'[', ']'}}) {
        const size_t at = name.find(open);
        if (at != std::string::npos && !name.empty() && name.back() == close) {
          unit = Normalise(name.substr(at + 1, name.size() - at - 2));
          name = name.substr(0, at);
        }
      }
      const int role = ColumnRole(Normalise(name));
      if (role == -2) continue;
      const int64_t line_number = lines_.line_number();
      const auto duplicate = [&] {
        return LineError(
            path_, line_number, fields_[c].column,
            fmt::format("column {} names {} a second time", QuotedField(fields_[c].text),
                        role == -1 ? "the time" : kNames[role]));
      };
      if (role == -1) {
        if (time_column_ >= 0) return duplicate();
        time_column_ = static_cast<int>(c);
        if (!unit.empty()) {
          const std::optional<double> u = TimeUnit(unit);
          if (!u) return UnitError(line_number, c, "s or ms");
          time_unit_ = *u;
        }
        continue;
      }
      if (value_columns_[role] >= 0) return duplicate();
      value_columns_[role] = static_cast<int>(c);
      const bool accel = role < 3;
      units_[role] = accel ? options_.accel_unit_mps2 : options_.gyro_unit_radps;
      unit_names_[role] = UnitNameOf(accel, units_[role]);
      if (!unit.empty()) {
        const std::optional<double> u = accel ? AccelUnit(unit) : GyroUnit(unit);
        if (!u) return UnitError(line_number, c, accel ? "m/s^2 or g" : "rad/s or deg/s");
        units_[role] = *u;
        unit_names_[role] = UnitNameOf(accel, *u);
      }
    }
    std::string missing;
    for (int i = 0; i < 6; ++i) {
      if (value_columns_[i] < 0) missing += (missing.empty() ? "" : ", ") + std::string(kNames[i]);
    }
    if (!missing.empty()) {
      return LineError(path_, lines_.line_number(), 1,
                       fmt::format("header {}: no column for {} (expected t,ax,ay,az,gx,gy,gz "
                                   "or x-io's \"Time (s),Gyroscope X (deg/s),...\")",
                                   QuotedField(line), missing));
    }
    return Status::Ok();
  }

  Status UnitError(int64_t line, size_t c, const char* expected) const {
    return LineError(path_, line, fields_[c].column,
                     fmt::format("column {}: unknown unit (expected {})",
                                 QuotedField(fields_[c].text), expected));
  }

  static std::string UnitNameOf(bool accel, double unit) {
    if (accel) return unit == 1 ? "m/s^2" : "g";
    return unit == 1 ? "rad/s" : "deg/s";
  }

  LineReader lines_;
  std::vector<CsvField> fields_;
  std::vector<int64_t> field_columns_;  // byte column of each header field
  size_t columns_ = 0;
  int time_column_ = -1;
  double time_unit_ = 1;
  std::array<int, 6> value_columns_ = {};
  std::array<double, 6> units_ = {1, 1, 1, 1, 1, 1};
  std::array<std::string, 6> unit_names_;
};

class MatSource final : public ImuReader::Source {
 public:
  static StatusOr<std::unique_ptr<MatSource>> Open(const std::string& path,
                                                   const ImuReaderOptions& options) {
    StatusOr<MatFile> mat = MatFile::Open(path);
    if (!mat.ok()) return mat.status();
    StatusOr<MatMatrix> imu = mat->ReadMatrix("imu");
    if (!imu.ok()) return imu.status();
    if (imu->columns != 6 || imu->rows == 0) {
      return InvalidArgumentError(fmt::format(
          "{}: imu is {} x {}: expected N x 6 (ax, ay, az in m/s^2, gx, gy, gz in rad/s)", path,
          imu->rows, imu->columns));
    }
    auto source = std::unique_ptr<MatSource>(new MatSource(path, options));
    source->imu_ = std::move(imu).value();
    if (mat->Has("ts")) {
      StatusOr<MatMatrix> ts = mat->ReadMatrix("ts");
      if (!ts.ok()) return ts.status();
      if (ts->values.size() != source->imu_.rows || std::min(ts->rows, ts->columns) != 1) {
        return InvalidArgumentError(
            fmt::format("{}: ts is {} x {}: expected {} times, a row or a column as imu's rows",
                        path, ts->rows, ts->columns, source->imu_.rows));
      }
      source->ts_ = std::move(ts->values);
    }
    return source;
  }

  std::string Where(int64_t line) const override {
    return fmt::format("{}: imu row {}", path_, line);
  }
  const char* format() const override { return "MAT (PyShoe)"; }

 protected:
  StatusOr<bool> ReadRow(Row* row) override {
    if (next_ >= imu_.rows) return false;
    row->line = static_cast<int64_t>(next_) + 1;
    row->has_time = !ts_.empty();
    if (row->has_time) {
      row->t_s = ts_[next_];
      if (!std::isfinite(row->t_s)) {
        return FieldError(*row, kTimeField, fmt::format("t = {}: must be finite", row->t_s));
      }
    }
    for (int i = 0; i < 6; ++i) {
      row->raw[i] = row->values[i] = imu_.At(next_, static_cast<size_t>(i));
      if (!std::isfinite(row->values[i])) {
        return FieldError(*row, i, fmt::format("{} = {}: must be finite", kNames[i], row->raw[i]));
      }
    }
    ++next_;
    return true;
  }

  Status FieldError(const Row& row, int field, const std::string& what) const override {
    if (field == kTimeField) {
      return InvalidArgumentError(fmt::format("{}: ts element {}: {}", path_, row.line, what));
    }
    if (field == kWholeRow) {
      return InvalidArgumentError(fmt::format("{}: imu row {}: {}", path_, row.line, what));
    }
    return InvalidArgumentError(
        fmt::format("{}: imu row {}, column {}: {}", path_, row.line, field + 1, what));
  }

  std::string UnitName(int field) const override { return field < 3 ? "m/s^2" : "rad/s"; }

 private:
  MatSource(const std::string& path, const ImuReaderOptions& options) : Source(path, options) {}

  MatMatrix imu_;
  std::vector<double> ts_;
  size_t next_ = 0;
};

}  // namespace

StatusOr<ImuReader> ImuReader::Open(const std::string& path, const ImuReaderOptions& options) {
  if (path.size() >= 4 && Normalise(path.substr(path.size() - 4)) == ".mat") {
    StatusOr<std::unique_ptr<MatSource>> source = MatSource::Open(path, options);
    if (!source.ok()) return source.status();
    return ImuReader(std::move(source).value());
  }
  StatusOr<std::unique_ptr<CsvSource>> source = CsvSource::Open(path, options);
  if (!source.ok()) return source.status();
  return ImuReader(std::move(source).value());
}

ImuReader::ImuReader(std::unique_ptr<Source> source) : source_(std::move(source)) {}
ImuReader::ImuReader(ImuReader&&) noexcept = default;
ImuReader& ImuReader::operator=(ImuReader&&) noexcept = default;
ImuReader::~ImuReader() = default;

StatusOr<bool> ImuReader::Next(ImuRecord* record) { return source_->Next(record); }
std::string ImuReader::Where(const ImuRecord& record) const { return source_->Where(record.line); }
int64_t ImuReader::duplicates() const { return source_->duplicates(); }
const char* ImuReader::format() const { return source_->format(); }
const std::string& ImuReader::path() const { return source_->path(); }

}  // namespace grove::tools

#include "tools/io/truth_trajectory.h"

#include <fmt/format.h>

#include <cmath>
#include <string_view>

#include "tools/io/csv_reader.h"

namespace grove::tools {
namespace {

constexpr size_t kMaxLineBytes = size_t{64} << 10;

// Reads the rows of one format into a TruthTrajectory, line by line.
class TruthParser {
 public:
  explicit TruthParser(const std::string& path) : path_(path) {
    tum_ = path.ends_with(".tum") || path.ends_with(".txt");
  }

  // One line that is not skipped.
  Status Line(std::string_view line, int64_t number) {
    if (!started_) {
      started_ = true;
      if (line.find(',') == std::string_view::npos) tum_ = true;
      if (!tum_) return CsvHeader(line, number);
    }
    return tum_ ? TumRow(line, number) : CsvRow(line, number);
  }

  StatusOr<TruthTrajectory> Finish() {
    if (tum_ && truth_.poses.empty()) {
      return InvalidArgumentError(
          fmt::format("{}: no poses: expected lines \"t x y z qx qy qz qw\"", path_));
    }
    if (!started_) {
      return InvalidArgumentError(
          fmt::format("{}: empty file: expected a header starting with \"t,x,y\"", path_));
    }
    if (truth_.poses.empty()) {
      return InvalidArgumentError(fmt::format("{}: no points after the header", path_));
    }
    truth_.has_heading = tum_ || truth_.has_heading;
    return std::move(truth_);
  }

 private:
  Status CsvHeader(std::string_view line, int64_t number) {
    SplitCsvLine(line, &fields_);
    if (fields_.size() < 3 || fields_[0].text != "t" || fields_[1].text != "x" ||
        fields_[2].text != "y") {
      return LineError(path_, number, 1,
                       fmt::format("unknown header {}: expected one starting with \"t,x,y\"",
                                   QuotedField(line)));
    }
    field_count_ = fields_.size();
    truth_.has_heading = field_count_ > 3 && fields_[3].text == "heading";
    return Status::Ok();
  }

  Status CsvRow(std::string_view line, int64_t number) {
    SplitCsvLine(line, &fields_);
    if (fields_.size() != field_count_) {
      return LineError(path_, number, 1,
                       fmt::format("expected {} fields as in the header, found {}", field_count_,
                                   fields_.size()));
    }
    StampedPose p;
    GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path_, number, fields_[0], "t", &p.t_s));
    GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path_, number, fields_[1], "x", &p.pose.x_m));
    GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path_, number, fields_[2], "y", &p.pose.y_m));
    if (truth_.has_heading) {
      GROVE_RETURN_IF_ERROR(
          ParseFiniteNumber(path_, number, fields_[3], "heading", &p.pose.heading_rad));
    }
    return Append(p, number);
  }

  Status TumRow(std::string_view line, int64_t number) {
    SplitAtBlanks(line, &fields_);
    if (fields_.size() != 8) {
      return LineError(path_, number, 1,
                       fmt::format("expected 8 numbers \"t x y z qx qy qz qw\" separated by "
                                   "spaces, found {} field(s)",
                                   fields_.size()));
    }
    static constexpr const char* kNames[8] = {"t", "x", "y", "z", "qx", "qy", "qz", "qw"};
    double v[8];
    for (int k = 0; k < 8; ++k) {
      GROVE_RETURN_IF_ERROR(ParseFiniteNumber(path_, number, fields_[k], kNames[k], &v[k]));
    }
    const double qx = v[4], qy = v[5], qz = v[6], qw = v[7];
    if (qx == 0 && qy == 0 && qz == 0 && qw == 0) {
      return LineError(path_, number, fields_[4].column,
                       "qx, qy, qz, qw = 0, 0, 0, 0: a rotation needs a non-zero quaternion");
    }
    StampedPose p;
    p.t_s = v[0];
    p.pose.x_m = v[1];
    p.pose.y_m = v[2];
    // The yaw of the (not necessarily unit) quaternion: its rotation about z.
    p.pose.heading_rad = std::atan2(2 * (qw * qz + qx * qy), qw * qw + qx * qx - qy * qy - qz * qz);
    return Append(p, number);
  }

  Status Append(const StampedPose& p, int64_t number) {
    if (!truth_.poses.empty() && !(p.t_s > truth_.poses.back().t_s)) {
      return LineError(
          path_, number, fields_[0].column,
          fmt::format("t = {} is not after the previous time {}: times must be strictly increasing",
                      p.t_s, truth_.poses.back().t_s));
    }
    truth_.poses.push_back(p);
    return Status::Ok();
  }

  const std::string& path_;
  bool tum_ = false;
  bool started_ = false;
  size_t field_count_ = 0;  // CSV: fields in the header
  std::vector<CsvField> fields_;
  TruthTrajectory truth_;
};

}  // namespace

StatusOr<TruthTrajectory> ReadTruthTrajectory(const std::string& path) {
  StatusOr<LineReader> opened = LineReader::Open(path, kMaxLineBytes);
  if (!opened.ok()) return opened.status();
  LineReader& lines = *opened;
  TruthParser parser(path);
  std::string_view line;
  for (;;) {
    StatusOr<bool> more = lines.Next(&line);
    if (!more.ok()) return more.status();
    if (!*more) break;
    if (IsSkippedLine(line)) continue;
    GROVE_RETURN_IF_ERROR(parser.Line(line, lines.line_number()));
  }
  return parser.Finish();
}

}  // namespace grove::tools

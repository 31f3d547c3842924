// Streaming reader of foot-mounted IMU recordings, the input of `grove footslam steps` and of
// `grove footslam run --imu`.
//
// Formats (tools/io/FORMATS.md, "IMU recordings"):
//   CSV, plain or gzip: a header naming the columns, then one sample per row. The columns are
//     found by name in any order: time (t, time, timestamp; seconds, or "(ms)"), specific force
//     (ax, ay, az, acc_x, accel_x, "Accelerometer X", ...) and angular rate (gx, gy, gz, gyr_x,
//     gyro_x, "Gyroscope X", ...); other columns are ignored. A unit in parentheses or brackets
//     after a name ("Accelerometer X (g)", "gx [deg/s]") sets that column's unit; the others
//     take ImuReaderOptions' units. x-io's NGIMU export reads as it is. Without a time column
//     the rate gives the times. The syntax (blank and '#' lines, padding, a complete last line)
//     is that of step files (tools/io/step_reader.h).
//   MAT (a name ending in ".mat"), the PyShoe / University of Toronto layout: a variable imu of
//     N x 6 doubles (ax, ay, az in m/s^2, gx, gy, gz in rad/s) and ts, N times in seconds (a row
//     or a column); other variables (gt, gt_idx) are ignored. Needs grove built with libmatio.
//
// Rules, each an InvalidArgument naming the place (FILE:LINE:COLUMN for CSV, "FILE: imu row R,
// column C" for MAT), the field, its value and the rule: every value a finite number; no axis at
// or beyond the sensor's range (saturated); times strictly increasing, except that a row equal
// to the one before in every field is skipped (x-io's NGIMU logs some twice: duplicates()); no
// interval longer than max_interval_s (a gap); with rate_hz, the median of the first 64
// intervals within 5 % of 1 / rate_hz.
#ifndef GROVE_TOOLS_IO_IMU_READER_H_
#define GROVE_TOOLS_IO_IMU_READER_H_

#include <cstdint>
#include <memory>
#include <string>

#include "grove/foot_imu.h"
#include "grove/status.h"

namespace grove::tools {

struct ImuReaderOptions {
  // Metres per second squared per unit of an accelerometer column without a unit in its
  // header (1: m/s^2; 9.80665: g), and radians per second per unit of a gyroscope column (1:
  // rad/s; pi / 180: deg/s).
  double accel_unit_mps2 = 1;
  double gyro_unit_radps = 1;
  // Samples per second: checked against the time column, or giving the times without one
  // (sample i at i / rate_hz). 0: not given.
  double rate_hz = 0;
  // The sensor's ranges and the longest interval: FootImuConfig's.
  double accel_range_mps2 = FootImuConfig().accel_range_mps2;
  double gyro_range_radps = FootImuConfig().gyro_range_radps;
  double max_interval_s = FootImuConfig().max_sample_interval_s;
};

// Parses a --units value "ACCEL,GYRO", ACCEL one of m/s^2 (m/s2, mps2) or g, GYRO one of rad/s
// (rads) or deg/s (dps), into the options' units; InvalidArgument otherwise.
Status ParseImuUnits(const std::string& text, ImuReaderOptions* options);

struct ImuRecord {
  ImuSample sample;
  int64_t line = 0;  // CSV line, or MAT row (1-based)
};

// Not thread-safe. Movable, not copyable.
class ImuReader {
 public:
  // Opens the file and reads its header (CSV) or its variables (MAT). NotFound for a missing
  // file.
  static StatusOr<ImuReader> Open(const std::string& path, const ImuReaderOptions& options = {});
  ImuReader(ImuReader&&) noexcept;
  ImuReader& operator=(ImuReader&&) noexcept;
  ~ImuReader();

  // Sets *record to the next sample and returns true, or returns false at the end. A file
  // without a sample is an error. After an error every later call returns the same error.
  StatusOr<bool> Next(ImuRecord* record);
  // "FILE:LINE" (CSV) or "FILE: imu row R" (MAT): where a record came from, for messages.
  std::string Where(const ImuRecord& record) const;
  // Rows skipped as duplicates of the row before.
  int64_t duplicates() const;
  // "CSV" or "MAT (PyShoe)".
  const char* format() const;
  const std::string& path() const;

  class Source;

 private:
  explicit ImuReader(std::unique_ptr<Source> source);
  std::unique_ptr<Source> source_;
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_IMU_READER_H_

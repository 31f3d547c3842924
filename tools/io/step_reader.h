// Streaming reader for step files, the odometry input of FootSLAM.
//
// A step file is CSV text whose header names its form:
//   t,dx,dy  each row is one step vector (metres, odometry frame) that ends at time t (seconds);
//   t,x,y    each row is a cumulative odometry position; the first row is the start and every
//            later row gives one step, its difference from the row before.
// The deltas form may add columns after t,dx,dy, as the foot IMU front end writes them: dz,
// dheading, var_dx, cov_dx_dy, var_dy, cov_dx_dheading, cov_dy_dheading, var_dheading (each at
// most once, in any order; finite, variances >= 0). They are checked and not used.
// Fields may be padded with spaces or tabs; lines end in "\n" or "\r\n"; blank lines and lines
// whose first non-blank character is '#' are skipped (before the header too); a UTF-8 byte order
// mark is ignored. Numbers are decimal as std::from_chars reads them (no locale, no hex), with an
// optional leading '+'; NaN and infinities are rejected. Times are finite and strictly increasing.
//
// A complete step file ends its last line with "\n" (or "\r\n"). Nothing else tells a finished
// file from one still being written, or left by a writer that was killed (its size and times do
// not), and the last line of such a file may hold a cut number (0.7 read for 0.7312). So a last
// line without a line end is an error, for a regular file, a pipe and a text alike, unless
// StepReaderOptions::allow_unterminated_last_line is set.
//
// Every error message is one line "FILE:LINE:COLUMN: what (detail)", FILE as given to Open, COLUMN
// the 1-based byte column of the offending field's first non-blank character, 1 when the error
// is about the whole row, or one past the last byte for a missing line end. Errors in records are
// InvalidArgument, a missing file is NotFound.
#ifndef GROVE_TOOLS_IO_STEP_READER_H_
#define GROVE_TOOLS_IO_STEP_READER_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "grove/status.h"
#include "tools/io/csv_reader.h"

namespace grove::tools {

// One step of the pedestrian, in the odometry frame.
struct StepRecord {
  double t_s = 0;  // time at the end of the step
  double dx_m = 0;
  double dy_m = 0;
  int64_t line = 0;  // 1-based line of the row that gave the step; 0 when not read from a file
};

struct StepReaderOptions {
  // A step longer than this is taken for a corrupt record. Range: > 0, finite. Default: 5.
  double max_step_m = 5.0;
  // The longest accepted line in bytes, without its "\n" or "\r\n"; it bounds the reader's memory
  // and applies to comment lines too. Range: [16, 64 MiB]. Default: 4096.
  size_t max_line_bytes = 4096;
  // Accept a last line without "\n" (see the file comment), for text known to be complete that
  // was written without one. Default: false.
  bool allow_unterminated_last_line = false;
};

// Reads a step file one record at a time; memory use does not depend on the file's length.
// Not thread-safe. Movable, not copyable.
class StepReader {
 public:
  // Opens the file, reads the header and looks ahead at up to two data rows (so that
  // start_time_s() is known), reporting any error in them.
  static StatusOr<StepReader> Open(const std::string& path, const StepReaderOptions& options = {});
  // Reads a step file held in memory (the walk bundled in the binary); `name` is used in messages.
  static StatusOr<StepReader> OpenText(const std::string& name, std::string text,
                                       const StepReaderOptions& options = {});

  // Sets *step to the next step and returns true, or returns false at the end of the file.
  // A file without a single step is an error ("FILE: no steps after the header") instead of false.
  // After an error every later call returns the same error.
  StatusOr<bool> Next(StepRecord* step);

  // True when the header was t,x,y.
  bool positions_form() const { return positions_form_; }
  // The time the walk starts, before its first step. Positions form: the first row's t.
  // Deltas form: t1 - (t2 - t1) from the first two rows (one step period before the first step),
  // t1 - 1 if there is one row only, 0 if there is none.
  double start_time_s() const { return start_time_s_; }
  // The odometry start: the first row's position in the positions form, (0, 0) otherwise.
  double start_x_m() const { return start_x_m_; }
  double start_y_m() const { return start_y_m_; }
  // Steps returned by Next so far.
  int64_t steps_read() const { return steps_read_; }
  const std::string& path() const { return lines_.path(); }

 private:
  struct Row {
    double t_s;
    double a_m;  // dx or x
    double b_m;  // dy or y
    int64_t line;
  };

  StepReader(LineReader lines, const StepReaderOptions& options)
      : lines_(std::move(lines)), options_(options) {}
  // Reads the next data row, checking its fields and its time against the row before.
  static StatusOr<StepReader> Start(LineReader lines, const StepReaderOptions& options);
  StatusOr<bool> ReadRow(Row* row);
  // The error for `line`, the line last read, when it lacks its line end and that is refused.
  Status CheckLineEnd(std::string_view line) const;

  LineReader lines_;
  StepReaderOptions options_;
  bool positions_form_ = false;
  double start_time_s_ = 0;
  double start_x_m_ = 0;
  double start_y_m_ = 0;
  Row lookahead_[2] = {};
  int lookahead_begin_ = 0;
  int lookahead_end_ = 0;
  bool has_previous_time_ = false;
  double previous_time_s_ = 0;
  double previous_x_m_ = 0;  // positions form: the row before the next step
  double previous_y_m_ = 0;
  int64_t steps_read_ = 0;
  std::vector<std::string> extra_columns_;  // after t,dx,dy
  Status error_;
  std::vector<CsvField> fields_;  // scratch, reused across rows
};

// Reads every step of a file; for tests and small files. *start_time_s (when given) receives
// the walk's start time (StepReader::start_time_s()).
StatusOr<std::vector<StepRecord>> ReadAllSteps(const std::string& path,
                                               const StepReaderOptions& options = {},
                                               double* start_time_s = nullptr);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_STEP_READER_H_

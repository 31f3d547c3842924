// Streaming reader for step files, the odometry input of FootSLAM.
//
// A step file is CSV text whose header names its form:
//   t,dx,dy  each row is one step vector (metres, odometry frame) that ends at time t (seconds);
//   t,x,y    each row is a cumulative odometry position; the first row is the start and every
//            later row gives one step, its difference from the row before.
// Fields may be padded with spaces or tabs; lines end in "\n" or "\r\n"; blank lines and lines
// whose first non-blank character is '#' are skipped (before the header too); a UTF-8 byte order
// mark is ignored. Numbers are decimal as std::from_chars reads them (no locale, no hex), with an
// optional leading '+'; NaN and infinities are rejected. Times are finite and strictly increasing.
//
// Every error message is one line "FILE:LINE:COLUMN: what (detail)", FILE as given to Open, COLUMN
// the 1-based byte column of the offending field's first non-blank character, or 1 when the error
// is about the whole row. Errors in records are InvalidArgument, a missing file is NotFound.
#ifndef GROVE_TOOLS_STEP_READER_H_
#define GROVE_TOOLS_STEP_READER_H_

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "grove/status.h"

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
};

namespace internal {

// Reads a file line by line through a buffer of max(64 KiB, max_line_bytes + 2) bytes, so a line
// over the limit is reported without ever being held whole. Shared by the CSV readers in tools/.
// After an error every later call returns the same error.
class LineReader {
 public:
  static StatusOr<LineReader> Open(const std::string& path, size_t max_line_bytes);
  // Reads lines from `in`; `path` names it in messages.
  static StatusOr<LineReader> FromStream(const std::string& path, std::unique_ptr<std::istream> in,
                                         size_t max_line_bytes);

  // Sets *line to the next line without its terminator; the view is valid until the next call.
  // Returns false at the end of the file.
  StatusOr<bool> Next(std::string_view* line);
  // The 1-based number of the line last returned (or found too long).
  int64_t line_number() const { return line_number_; }
  const std::string& path() const { return path_; }

 private:
  LineReader() = default;
  StatusOr<bool> Finish(size_t first, size_t stop, std::string_view* line);

  std::string path_;
  size_t max_line_bytes_ = 0;
  std::unique_ptr<std::istream> in_;
  std::vector<char> buffer_;
  size_t begin_ = 0;  // unread bytes are buffer_[begin_, end_)
  size_t end_ = 0;
  bool eof_ = false;
  int64_t line_number_ = 0;
  Status error_;
};

struct CsvField {
  std::string_view text;  // without the blanks around it
  int64_t column = 1;     // 1-based byte column of text (of the field start when text is empty)
};

// Splits a line at every ',' (no quoting) into *fields, which it clears first.
void SplitCsvLine(std::string_view line, std::vector<CsvField>* fields);
// True for a blank line or one whose first non-blank character is '#'.
bool IsSkippedLine(std::string_view line);
// InvalidArgument "path:line:column: what".
Status LineError(std::string_view path, int64_t line, int64_t column, std::string_view what);
// Parses field as a finite double named `name` in error messages.
Status ParseFiniteNumber(std::string_view path, int64_t line, const CsvField& field,
                         std::string_view name, double* value);

}  // namespace internal

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

  StepReader(internal::LineReader lines, const StepReaderOptions& options)
      : lines_(std::move(lines)), options_(options) {}
  // Reads the next data row, checking its fields and its time against the row before.
  static StatusOr<StepReader> Start(internal::LineReader lines, const StepReaderOptions& options);
  StatusOr<bool> ReadRow(Row* row);

  internal::LineReader lines_;
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
  Status error_;
  std::vector<internal::CsvField> fields_;  // scratch, reused across rows
};

// Reads every step of a file; for tests and small files. A file without steps is an error.
StatusOr<std::vector<StepRecord>> ReadAllSteps(const std::string& path,
                                               const StepReaderOptions& options = {});

}  // namespace grove::tools

#endif  // GROVE_TOOLS_STEP_READER_H_

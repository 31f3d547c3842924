// Building blocks of the CSV readers in tools/ (step files, trajectories, map.csv): a line reader
// with a bounded line length, a field splitter, number parsers, and ReadWholeFile.
//
// The CSV is plain: fields are separated by ',' without quoting and may be padded with spaces or
// tabs; lines end in "\n" or "\r\n"; a UTF-8 byte order mark before the first line is ignored.
// Numbers are decimal as std::from_chars reads them (no locale, no hex), with an optional leading
// '+'.
//
// Errors: NotFound for a missing file; IoError for a file that cannot be opened or read (a
// directory included), naming the reason the OS gives; InvalidArgument for a bad line or field,
// as one line "FILE:LINE:COLUMN: what" with a 1-based LINE and a 1-based byte COLUMN. Text from
// the file appears in messages only through QuoteForMessage (grove/status.h): escaped, and cut
// after kMessageTextBytes bytes.
// Thread safety: the functions are thread-safe; a LineReader is not (one thread at a time).
#ifndef GROVE_TOOLS_IO_CSV_READER_H_
#define GROVE_TOOLS_IO_CSV_READER_H_

#include <cstddef>
#include <cstdint>
#include <functional>
#include <istream>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "grove/status.h"

namespace grove::tools {

// The most bytes of a field or line of a file that a reader's message shows.
inline constexpr size_t kMessageTextBytes = 64;

// The whole contents of a file. Messages name the path and the reason given by the OS.
StatusOr<std::string> ReadWholeFile(const std::string& path);

// Reads a file line by line through a buffer of max(64 KiB, max_line_bytes + 2) bytes, so a line
// over the limit is reported ("FILE:LINE:1: line longer than N bytes") without ever being held
// whole. After an error every later call returns the same error. Movable, not copyable.
class LineReader {
 public:
  // max_line_bytes: the longest line accepted, in bytes without its terminator; in [16, 64 MiB].
  static StatusOr<LineReader> Open(const std::string& path, size_t max_line_bytes);
  // Reads lines from `in`; `path` names it in messages.
  static StatusOr<LineReader> FromStream(const std::string& path, std::unique_ptr<std::istream> in,
                                         size_t max_line_bytes);
  // Reads lines from `read`, which fills up to `room` bytes at `data` and returns how many (0 at
  // the end) or an error, which the reader returns as it is; `path` names the input in messages.
  using ReadFunction = std::function<StatusOr<size_t>(char* data, size_t room)>;
  static StatusOr<LineReader> FromFunction(const std::string& path, ReadFunction read,
                                           size_t max_line_bytes);

  // Sets *line to the next line without its terminator; the view is valid until the next call.
  // Returns false at the end of the file.
  StatusOr<bool> Next(std::string_view* line);
  // The 1-based number of the line last returned (or found too long); 0 before the first.
  int64_t line_number() const { return line_number_; }
  // Whether the line last returned ended in "\n": false only for a last line without one.
  bool line_terminated() const { return line_terminated_; }
  const std::string& path() const { return path_; }

 private:
  // Owns a file descriptor, closed on destruction. Movable.
  class FileDescriptor {
   public:
    FileDescriptor() = default;
    explicit FileDescriptor(int fd) : fd_(fd) {}
    FileDescriptor(FileDescriptor&& other) noexcept;
    FileDescriptor& operator=(FileDescriptor&& other) noexcept;
    ~FileDescriptor();
    int get() const { return fd_; }

   private:
    int fd_ = -1;
  };

  LineReader() = default;
  // A reader of no input yet, its buffer sized for max_line_bytes (checked).
  static StatusOr<LineReader> Make(const std::string& path, size_t max_line_bytes);
  StatusOr<bool> Finish(size_t first, size_t stop, std::string_view* line);
  // Appends what the input has, up to the buffer's end; sets eof_ at its end.
  Status Fill();

  std::string path_;
  size_t max_line_bytes_ = 0;
  FileDescriptor fd_;                 // the input, for Open
  std::unique_ptr<std::istream> in_;  // the input, for FromStream
  ReadFunction read_;                 // the input, for FromFunction
  std::vector<char> buffer_;
  size_t begin_ = 0;  // unread bytes are buffer_[begin_, end_)
  size_t end_ = 0;
  bool eof_ = false;
  int64_t line_number_ = 0;
  bool line_terminated_ = true;
  Status error_;
};

struct CsvField {
  std::string_view text;  // without the blanks around it
  int64_t column = 1;     // 1-based byte column of text (of the field start when text is empty)
};

// Splits a line at every ',' (no quoting) into *fields, which it clears first.
void SplitCsvLine(std::string_view line, std::vector<CsvField>* fields);
// Splits a line at runs of spaces and tabs into *fields (none empty), which it clears first.
void SplitAtBlanks(std::string_view line, std::vector<CsvField>* fields);
// True for a line of spaces and tabs only, or an empty one.
bool IsBlankLine(std::string_view line);
// True for a blank line or one whose first non-blank character is '#'.
bool IsSkippedLine(std::string_view line);
// InvalidArgument "path:line:column: what".
Status LineError(std::string_view path, int64_t line, int64_t column, std::string_view what);
// A field's value checked by a rule of grove/input_rules.h, `rule` being the check's status: Ok,
// or "path:line:column: " and the rule's message.
Status AtField(std::string_view path, int64_t line, const CsvField& field, const Status& rule);
// A field's (or line's) text for a message: QuoteForMessage(text, kMessageTextBytes).
std::string QuotedField(std::string_view text);

// Why a field is not a number.
enum class NumberParse {
  kOk,
  kEmpty,
  kNotANumber,  // not (wholly) a number of the type asked for
  kOutOfRange,  // a number, but outside the range of the type
  kNotFinite,   // NaN or an infinity (doubles only)
};
// Parse a whole field; *value is set only on kOk.
NumberParse ParseCsvDouble(std::string_view text, double* value);
NumberParse ParseCsvInt32(std::string_view text, int32_t* value);

// Parses field as a finite double named `name` in error messages, which are
// "path:line:column: name: \"text\" is not a number" (an empty field too),
// "...: name: \"text\" is out of the range of a double" or "...: name = value: must be finite"
// (the value as parsed: nan, inf or -inf).
Status ParseFiniteNumber(std::string_view path, int64_t line, const CsvField& field,
                         std::string_view name, double* value);

// Parses field as an integer in [0, 2^31) named `name` (a landmark id):
// "path:line:column: name: \"text\" is not an integer in [0, 2^31)" otherwise.
Status ParseCsvId(std::string_view path, int64_t line, const CsvField& field, std::string_view name,
                  int32_t* value);

// A CSV table: a header row naming the columns, then rows of as many fields. Comment and blank
// lines are skipped anywhere; a last line without a line end is an error (the file may still be
// being written). The model-specific readers (controls, observations) check the fields.
class CsvTableReader {
 public:
  // Opens `path` and reads its header, which must be one of `headers` (each a list of column
  // names): "FILE:LINE:1: unknown header ...: expected ..." otherwise. Lines are limited to
  // 64 KiB.
  static StatusOr<CsvTableReader> Open(const std::string& path,
                                       const std::vector<std::vector<std::string>>& headers);
  // The index in `headers` of the header found.
  size_t header() const { return header_; }
  // The next row's fields (as many as the header's): false at the end of the file.
  StatusOr<bool> Next(const std::vector<CsvField>** fields);
  // Calls row(fields, line) -> Status for every row to the end; the first error stops it.
  template <typename F>
  Status ForEachRow(F&& row) {
    for (;;) {
      const std::vector<CsvField>* fields = nullptr;
      StatusOr<bool> more = Next(&fields);
      if (!more.ok()) return more.status();
      if (!*more) return Status::Ok();
      GROVE_RETURN_IF_ERROR(row(*fields, line_number()));
    }
  }
  int64_t line_number() const { return lines_.line_number(); }
  const std::string& path() const { return lines_.path(); }

 private:
  explicit CsvTableReader(LineReader lines) : lines_(std::move(lines)) {}
  StatusOr<bool> NextLine(std::string_view* line);
  LineReader lines_;
  size_t header_ = 0;
  size_t columns_ = 0;
  std::vector<CsvField> fields_;
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_CSV_READER_H_

#include "tools/io/csv_reader.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <system_error>
#include <utility>

namespace grove::tools {
namespace {

constexpr size_t kMinBufferBytes = size_t{64} << 10;
constexpr size_t kMinLineBytes = 16;
constexpr size_t kMaxLineBytes = size_t{64} << 20;
constexpr std::string_view kByteOrderMark = "\xEF\xBB\xBF";

bool IsBlank(char c) { return c == ' ' || c == '\t'; }

Status CheckMaxLineBytes(size_t max_line_bytes) {
  if (max_line_bytes < kMinLineBytes || max_line_bytes > kMaxLineBytes) {
    return InvalidArgumentError(fmt::format("max_line_bytes = {}: must be in [{}, {}]",
                                            max_line_bytes, kMinLineBytes, kMaxLineBytes));
  }
  return Status::Ok();
}

// std::generic_category().message() is thread-safe where strerror() is not.
std::string ErrnoText(int err) { return std::generic_category().message(err); }

// from_chars takes no '+'; accept exactly one in front of a digit or '.'.
std::string_view WithoutPlus(std::string_view text) {
  if (text.size() > 1 && text[0] == '+' && text[1] != '+' && text[1] != '-') text.remove_prefix(1);
  return text;
}

template <typename T, typename... Format>
NumberParse ParseWhole(std::string_view field, T* value, Format... format) {
  if (field.empty()) return NumberParse::kEmpty;
  const std::string_view text = WithoutPlus(field);
  T parsed{};
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), parsed, format...);
  if (end != text.data() + text.size()) return NumberParse::kNotANumber;
  if (ec == std::errc::result_out_of_range) return NumberParse::kOutOfRange;
  if (ec != std::errc()) return NumberParse::kNotANumber;
  *value = parsed;
  return NumberParse::kOk;
}

}  // namespace

StatusOr<std::string> ReadWholeFile(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"),
                                                       &std::fclose);
  if (file == nullptr) {
    const int err = errno;
    std::string message = fmt::format("{}: cannot open: {}", path, ErrnoText(err));
    if (err == ENOENT) return NotFoundError(std::move(message));
    return IoError(std::move(message));
  }
  std::string contents;
  char chunk[1 << 16];
  size_t n;
  while ((n = std::fread(chunk, 1, sizeof(chunk), file.get())) > 0) contents.append(chunk, n);
  if (std::ferror(file.get())) {
    return IoError(fmt::format("{}: cannot read: {}", path, ErrnoText(errno)));
  }
  return contents;
}

LineReader::FileDescriptor::FileDescriptor(FileDescriptor&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)) {}

LineReader::FileDescriptor& LineReader::FileDescriptor::operator=(FileDescriptor&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

LineReader::FileDescriptor::~FileDescriptor() {
  if (fd_ >= 0) ::close(fd_);
}

StatusOr<LineReader> LineReader::Open(const std::string& path, size_t max_line_bytes) {
  GROVE_RETURN_IF_ERROR(CheckMaxLineBytes(max_line_bytes));
  FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_NOCTTY | O_CLOEXEC));
  if (fd.get() < 0) {
    const int err = errno;
    std::string message = fmt::format("{}: cannot open for reading: {}", path, ErrnoText(err));
    if (err == ENOENT) return NotFoundError(std::move(message));
    return IoError(std::move(message));
  }
  struct stat st;
  if (::fstat(fd.get(), &st) != 0) {
    return IoError(fmt::format("{}: cannot stat: {}", path, ErrnoText(errno)));
  }
  if (S_ISDIR(st.st_mode)) return IoError(fmt::format("{}: is a directory, not a file", path));
  StatusOr<LineReader> reader = Make(path, max_line_bytes);
  if (reader.ok()) reader->fd_ = std::move(fd);
  return reader;
}

StatusOr<LineReader> LineReader::Make(const std::string& path, size_t max_line_bytes) {
  GROVE_RETURN_IF_ERROR(CheckMaxLineBytes(max_line_bytes));
  LineReader reader;
  reader.path_ = path;
  reader.max_line_bytes_ = max_line_bytes;
  reader.buffer_.resize(std::max(kMinBufferBytes, max_line_bytes + 2));
  return reader;
}

StatusOr<LineReader> LineReader::FromStream(const std::string& path,
                                            std::unique_ptr<std::istream> in,
                                            size_t max_line_bytes) {
  StatusOr<LineReader> reader = Make(path, max_line_bytes);
  if (reader.ok()) reader->in_ = std::move(in);
  return reader;
}

StatusOr<LineReader> LineReader::FromFunction(const std::string& path, ReadFunction read,
                                              size_t max_line_bytes) {
  StatusOr<LineReader> reader = Make(path, max_line_bytes);
  if (reader.ok()) reader->read_ = std::move(read);
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
      line_terminated_ = true;
      return Finish(first, stop, line);
    }
    if (eof_) {
      if (pending == 0) return false;
      const size_t first = begin_;
      begin_ = end_;
      line_terminated_ = false;
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
    error_ = Fill();
    if (!error_.ok()) return error_;
  }
}

Status LineReader::Fill() {
  // The buffer holds at least max + 2 bytes, so there is room for one more byte at least.
  char* data = buffer_.data() + end_;
  const size_t room = buffer_.size() - end_;
  if (read_) {
    StatusOr<size_t> n = read_(data, room);
    if (!n.ok()) return n.status();
    if (*n == 0) eof_ = true;
    end_ += *n;
    return Status::Ok();
  }
  if (in_ == nullptr) {
    for (;;) {
      const ssize_t n = ::read(fd_.get(), data, room);
      if (n > 0) {
        end_ += static_cast<size_t>(n);
        return Status::Ok();
      }
      if (n == 0) {
        eof_ = true;
        return Status::Ok();
      }
      if (errno != EINTR) {
        return IoError(fmt::format("{}: read failed after line {}: {}", path_, line_number_,
                                   ErrnoText(errno)));
      }
    }
  }
  in_->read(data, static_cast<std::streamsize>(room));
  end_ += static_cast<size_t>(in_->gcount());
  if (in_->bad() || (in_->fail() && !in_->eof())) {
    return IoError(fmt::format("{}: read failed after line {}", path_, line_number_));
  }
  if (in_->eof()) eof_ = true;
  return Status::Ok();
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

void SplitAtBlanks(std::string_view line, std::vector<CsvField>* fields) {
  fields->clear();
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && IsBlank(line[i])) ++i;
    if (i == line.size()) break;
    const size_t start = i;
    while (i < line.size() && !IsBlank(line[i])) ++i;
    fields->push_back({line.substr(start, i - start), static_cast<int64_t>(start) + 1});
  }
}

bool IsBlankLine(std::string_view line) { return std::all_of(line.begin(), line.end(), IsBlank); }

bool IsSkippedLine(std::string_view line) {
  for (char c : line) {
    if (!IsBlank(c)) return c == '#';
  }
  return true;
}

Status LineError(std::string_view path, int64_t line, int64_t column, std::string_view what) {
  return InvalidArgumentError(fmt::format("{}:{}:{}: {}", path, line, column, what));
}

Status AtField(std::string_view path, int64_t line, const CsvField& field, const Status& rule) {
  if (rule.ok()) return rule;
  return LineError(path, line, field.column, rule.message());
}

std::string QuotedField(std::string_view text) { return QuoteForMessage(text, kMessageTextBytes); }

NumberParse ParseCsvDouble(std::string_view text, double* value) {
  double parsed = 0;
  const NumberParse result = ParseWhole(text, &parsed, std::chars_format::general);
  if (result != NumberParse::kOk) return result;
  if (!std::isfinite(parsed)) return NumberParse::kNotFinite;
  *value = parsed;
  return NumberParse::kOk;
}

NumberParse ParseCsvInt32(std::string_view text, int32_t* value) { return ParseWhole(text, value); }

Status ParseFiniteNumber(std::string_view path, int64_t line, const CsvField& field,
                         std::string_view name, double* value) {
  double parsed = 0;
  switch (ParseWhole(field.text, &parsed, std::chars_format::general)) {
    case NumberParse::kOk:
      if (std::isfinite(parsed)) {
        *value = parsed;
        return Status::Ok();
      }
      // The value, not the text: "NaN(...)" can be long, and the value says what is wrong.
      return LineError(path, line, field.column,
                       fmt::format("{} = {}: must be finite", name, parsed));
    case NumberParse::kOutOfRange:
      return LineError(
          path, line, field.column,
          fmt::format("{}: {} is out of the range of a double", name, QuotedField(field.text)));
    case NumberParse::kEmpty:
    case NumberParse::kNotANumber:
    case NumberParse::kNotFinite:
      break;
  }
  return LineError(path, line, field.column,
                   fmt::format("{}: {} is not a number", name, QuotedField(field.text)));
}

Status ParseCsvId(std::string_view path, int64_t line, const CsvField& field, std::string_view name,
                  int32_t* value) {
  int32_t v = 0;
  if (ParseCsvInt32(field.text, &v) != NumberParse::kOk || v < 0) {
    return LineError(
        path, line, field.column,
        fmt::format("{}: {} is not an integer in [0, 2^31)", name, QuotedField(field.text)));
  }
  *value = v;
  return Status::Ok();
}

StatusOr<CsvTableReader> CsvTableReader::Open(
    const std::string& path, const std::vector<std::vector<std::string>>& headers) {
  StatusOr<LineReader> lines = LineReader::Open(path, 64 * 1024);
  if (!lines.ok()) return lines.status();
  CsvTableReader reader(std::move(lines).value());
  std::string expected;
  for (size_t k = 0; k < headers.size(); ++k) {
    std::string joined;
    for (const std::string& h : headers[k]) joined += (joined.empty() ? "" : ",") + h;
    expected += fmt::format("{}\"{}\"",
                            k == 0                    ? ""
                            : k + 1 == headers.size() ? " or "
                                                      : ", ",
                            joined);
  }
  std::string_view line;
  StatusOr<bool> more = reader.NextLine(&line);
  if (!more.ok()) return more.status();
  if (!*more)
    return InvalidArgumentError(
        fmt::format("{}: empty file: expected a header {}", path, expected));
  SplitCsvLine(line, &reader.fields_);
  for (size_t k = 0; k < headers.size(); ++k) {
    const std::vector<std::string>& h = headers[k];
    bool match = h.size() == reader.fields_.size();
    for (size_t i = 0; match && i < h.size(); ++i) match = reader.fields_[i].text == h[i];
    if (match) {
      reader.header_ = k;
      reader.columns_ = h.size();
      return reader;
    }
  }
  return LineError(path, reader.lines_.line_number(), 1,
                   fmt::format("unknown header {}: expected {}", QuotedField(line), expected));
}

StatusOr<bool> CsvTableReader::NextLine(std::string_view* line) {
  for (;;) {
    StatusOr<bool> more = lines_.Next(line);
    if (!more.ok() || !*more) return more;
    if (!lines_.line_terminated()) {
      return LineError(lines_.path(), lines_.line_number(), static_cast<int64_t>(line->size()) + 1,
                       "the last line has no line end: the file may still be being written; a "
                       "complete file ends in a newline");
    }
    if (!IsSkippedLine(*line)) return true;
  }
}

StatusOr<bool> CsvTableReader::Next(const std::vector<CsvField>** fields) {
  std::string_view line;
  StatusOr<bool> more = NextLine(&line);
  if (!more.ok() || !*more) return more;
  SplitCsvLine(line, &fields_);
  if (fields_.size() != columns_) {
    return LineError(lines_.path(), lines_.line_number(), 1,
                     fmt::format("expected {} fields, found {}", columns_, fields_.size()));
  }
  *fields = &fields_;
  return true;
}

}  // namespace grove::tools

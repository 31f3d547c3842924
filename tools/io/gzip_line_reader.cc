#include "tools/io/gzip_line_reader.h"

#include <fmt/format.h>
#include <sys/stat.h>
#include <zlib.h>

#include <algorithm>
#include <memory>
#include <utility>

namespace grove::tools {
namespace {

// Owns a gzFile; closing it reports a truncated stream.
struct GzipFile {
  gzFile file = nullptr;
  ~GzipFile() {
    if (file != nullptr) gzclose(file);
  }
};

// The text of zlib's message for `path`, quoted and cut as in every reader's message.
Status ZlibError(const std::string& path, const std::string& what, int code) {
  if (code == Z_ERRNO) return IoError(fmt::format("{}: cannot read: {}", path, what));
  return InvalidArgumentError(
      fmt::format("{}: the compressed data is corrupt: {}", path, QuotedField(what)));
}

}  // namespace

StatusOr<LineReader> OpenMaybeCompressed(const std::string& path, size_t max_line_bytes) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) return NotFoundError(fmt::format("{}: no such file", path));
  if (!S_ISREG(st.st_mode)) {
    return InvalidArgumentError(fmt::format("{}: not a regular file", path));
  }
  auto gz = std::make_shared<GzipFile>();
  gz->file = gzopen(path.c_str(), "rb");
  if (gz->file == nullptr) return IoError(fmt::format("{}: cannot open", path));
  auto read = [gz, path](char* data, size_t room) -> StatusOr<size_t> {
    if (gz->file == nullptr) return size_t{0};
    const unsigned ask = static_cast<unsigned>(std::min<size_t>(room, 1u << 30));
    const int n = gzread(gz->file, data, ask);
    if (n < 0) {
      int code = 0;
      const std::string what = gzerror(gz->file, &code);
      return ZlibError(path, what, code);
    }
    if (n > 0) return static_cast<size_t>(n);
    // The end: a truncated stream reads as a short file, and closing it says so.
    const int closed = gzclose(gz->file);
    gz->file = nullptr;
    if (closed == Z_ERRNO) return IoError(fmt::format("{}: cannot read", path));
    if (closed != Z_OK) {
      return InvalidArgumentError(
          fmt::format("{}: the compressed data is truncated or corrupt (zlib {})", path, closed));
    }
    return size_t{0};
  };
  return LineReader::FromFunction(path, std::move(read), max_line_bytes);
}

}  // namespace grove::tools

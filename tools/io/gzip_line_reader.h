// Line readers over files that may be gzip-compressed (zlib reads a plain file as it is).
#ifndef GROVE_TOOLS_IO_GZIP_LINE_READER_H_
#define GROVE_TOOLS_IO_GZIP_LINE_READER_H_

#include <cstddef>
#include <string>

#include "grove/status.h"
#include "tools/io/csv_reader.h"

namespace grove::tools {

// Opens `path`, plain or gzip, as a LineReader of lines of at most max_line_bytes, decompressing
// as it reads: memory stays bounded whatever the file holds. NotFound when the file does not
// exist; a directory or a device is refused; corrupt or truncated compressed data is an
// InvalidArgument naming the file and the line after which it was found.
StatusOr<LineReader> OpenMaybeCompressed(const std::string& path, size_t max_line_bytes);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_GZIP_LINE_READER_H_

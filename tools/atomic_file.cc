#include "tools/atomic_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <system_error>
#include <utility>

namespace grove::tools {
namespace {

std::atomic<uint64_t> temp_counter{0};

// std::generic_category().message() is thread-safe where strerror() is not.
std::string ErrnoText(int err) { return std::generic_category().message(err); }

Status ErrnoStatus(int err, std::string_view what, const std::string& path) {
  std::string message = fmt::format("cannot {} {}: {}", what, path, ErrnoText(err));
  if (err == ENOSPC || err == EDQUOT) return ResourceExhaustedError(std::move(message));
  return IoError(std::move(message));
}

std::string DirectoryOf(const std::string& path) {
  size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

Status WriteAll(int fd, std::string_view data, const std::string& path) {
  while (!data.empty()) {
    ssize_t n = ::write(fd, data.data(), data.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      return ErrnoStatus(errno, "write", path);
    }
    // A zero-byte write of a non-empty buffer would loop forever; report it as a full disk.
    if (n == 0) return ErrnoStatus(ENOSPC, "write", path);
    data.remove_prefix(static_cast<size_t>(n));
  }
  return Status::Ok();
}

Status SyncDirectory(const std::string& path) {
  std::string dir = DirectoryOf(path);
  int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return ErrnoStatus(errno, "open directory of", path);
  int rc = ::fsync(fd);
  int err = errno;
  ::close(fd);
  // Some file systems cannot fsync a directory; the rename is then as durable as they allow.
  if (rc != 0 && err != EINVAL) return ErrnoStatus(err, "fsync directory of", path);
  return Status::Ok();
}

}  // namespace

StatusOr<AtomicFileWriter> AtomicFileWriter::Create(const std::string& path) {
  if (path.empty()) return InvalidArgumentError("cannot write a file with an empty path");
  std::string temp_path = fmt::format("{}.tmp-{}-{}", path, static_cast<long>(::getpid()),
                                      temp_counter.fetch_add(1, std::memory_order_relaxed));
  int fd = ::open(temp_path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) return ErrnoStatus(errno, "create", path);
  return AtomicFileWriter(path, std::move(temp_path), fd);
}

AtomicFileWriter::AtomicFileWriter(std::string path, std::string temp_path, int fd)
    : path_(std::move(path)), temp_path_(std::move(temp_path)), fd_(fd) {}

AtomicFileWriter::AtomicFileWriter(AtomicFileWriter&& other) noexcept
    : path_(std::move(other.path_)),
      temp_path_(std::move(other.temp_path_)),
      fd_(std::exchange(other.fd_, -1)),
      buffer_(std::move(other.buffer_)),
      error_(std::move(other.error_)),
      committed_(other.committed_) {
  other.temp_path_.clear();
}

AtomicFileWriter& AtomicFileWriter::operator=(AtomicFileWriter&& other) noexcept {
  if (this != &other) {
    Abandon();
    path_ = std::move(other.path_);
    temp_path_ = std::move(other.temp_path_);
    other.temp_path_.clear();
    fd_ = std::exchange(other.fd_, -1);
    buffer_ = std::move(other.buffer_);
    error_ = std::move(other.error_);
    committed_ = other.committed_;
  }
  return *this;
}

AtomicFileWriter::~AtomicFileWriter() { Abandon(); }

void AtomicFileWriter::Abandon() {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
  if (!committed_ && !temp_path_.empty()) ::unlink(temp_path_.c_str());
  temp_path_.clear();
}

Status AtomicFileWriter::Fail(Status status) {
  Abandon();
  error_ = status;
  return status;
}

Status AtomicFileWriter::FlushBuffer() {
  Status status = WriteAll(fd_, buffer_, path_);
  buffer_.clear();
  return status;
}

Status AtomicFileWriter::Append(std::string_view data) {
  if (!error_.ok()) return error_;
  if (committed_ || fd_ < 0)
    return FailedPreconditionError("append to a closed writer for " + path_);
  if (buffer_.size() + data.size() <= kBufferBytes) {
    if (buffer_.capacity() < kBufferBytes) buffer_.reserve(kBufferBytes);
    buffer_.append(data);
    return Status::Ok();
  }
  Status status = FlushBuffer();
  if (!status.ok()) return Fail(std::move(status));
  if (data.size() >= kBufferBytes) {
    status = WriteAll(fd_, data, path_);
    if (!status.ok()) return Fail(std::move(status));
  } else {
    buffer_.append(data);
  }
  return Status::Ok();
}

Status AtomicFileWriter::Commit() {
  if (!error_.ok()) return error_;
  if (committed_ || fd_ < 0) return FailedPreconditionError("commit a closed writer for " + path_);
  Status status = FlushBuffer();
  if (!status.ok()) return Fail(std::move(status));
  if (::fsync(fd_) != 0) return Fail(ErrnoStatus(errno, "fsync", path_));
  int rc = ::close(fd_);
  fd_ = -1;
  // close() can report a deferred write error (NFS, quotas).
  if (rc != 0) return Fail(ErrnoStatus(errno, "close", path_));
  if (::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    return Fail(ErrnoStatus(errno, "rename temporary over", path_));
  }
  committed_ = true;
  temp_path_.clear();
  status = SyncDirectory(path_);
  if (!status.ok()) error_ = status;
  return status;
}

Status WriteFileAtomically(const std::string& path, std::string_view contents) {
  StatusOr<AtomicFileWriter> writer = AtomicFileWriter::Create(path);
  if (!writer.ok()) return writer.status();
  GROVE_RETURN_IF_ERROR(writer->Append(contents));
  return writer->Commit();
}

Status EnsureDirectory(const std::string& dir) {
  if (dir.empty()) return InvalidArgumentError("cannot create a directory with an empty path");
  size_t pos = 0;
  while (pos != std::string::npos) {
    pos = dir.find('/', pos + 1);
    std::string prefix = dir.substr(0, pos);
    // Skip "" (root), repeated slashes and the trailing slash.
    if (prefix.empty() || prefix.back() == '/') continue;
    if (::mkdir(prefix.c_str(), 0777) == 0) continue;
    int err = errno;
    struct stat st;
    if (err == EEXIST || err == EISDIR) {
      if (::stat(prefix.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) continue;
      return IoError(
          fmt::format("cannot create directory {}: {} exists and is not a directory", dir, prefix));
    }
    // EACCES on an existing directory (e.g. a read-only parent) is not an error.
    if (::stat(prefix.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) continue;
    return IoError(fmt::format("cannot create directory {}: {}", prefix, ErrnoText(err)));
  }
  return Status::Ok();
}

}  // namespace grove::tools

#include "tools/io/atomic_file.h"

#include <dirent.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <system_error>
#include <utility>

namespace grove::tools {
namespace {

constexpr std::string_view kTempInfix = ".tmp-";
constexpr int kTempSuffixChars = 12;
constexpr int kMaxCreateAttempts = 16;

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

std::string BaseNameOf(const std::string& path) {
  size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

bool SameFile(const struct stat& a, const struct stat& b) {
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

// kTempSuffixChars random letters and digits. The names only need to be unlikely to collide
// (O_EXCL catches a collision), so without getrandom() the clock and a counter do.
std::string RandomSuffix() {
  static constexpr char kChars[] = "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz";
  unsigned char bytes[kTempSuffixChars];
  if (::getrandom(bytes, sizeof(bytes), GRND_NONBLOCK) != static_cast<ssize_t>(sizeof(bytes))) {
    static std::atomic<uint64_t> counter{0};
    uint64_t x =
        static_cast<uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count()) ^
        (static_cast<uint64_t>(::getpid()) << 40) ^
        counter.fetch_add(1, std::memory_order_relaxed) * 0x9E3779B97F4A7C15ULL;
    for (unsigned char& b : bytes) {
      x += 0x9E3779B97F4A7C15ULL;  // SplitMix64 (Steele, Lea, Flood 2014)
      uint64_t z = x;
      z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
      z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
      b = static_cast<unsigned char>(z ^ (z >> 31));
    }
  }
  std::string suffix;
  for (unsigned char b : bytes) suffix += kChars[b % (sizeof(kChars) - 1)];
  return suffix;
}

// Removes every regular file named like a temporary of `path` that no writer holds locked: its
// writer died. A file that cannot be opened or locked is left alone; so is everything when the
// directory cannot be read, since a clean-up failure must not stop a write.
void RemoveStaleTemporaries(const std::string& path) {
  const std::string prefix = BaseNameOf(path) + std::string(kTempInfix);
  DIR* dir = ::opendir(DirectoryOf(path).c_str());
  if (dir == nullptr) return;
  const int dir_fd = ::dirfd(dir);
  while (const struct dirent* entry = ::readdir(dir)) {
    const std::string_view name = entry->d_name;
    if (name.size() <= prefix.size() || !name.starts_with(prefix)) continue;
    // O_NONBLOCK: a FIFO of that name must not hang the open (it is skipped as not regular).
    const int fd =
        ::openat(dir_fd, entry->d_name, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
    if (fd < 0) continue;
    struct stat locked;
    if (::fstat(fd, &locked) == 0 && S_ISREG(locked.st_mode) &&
        ::flock(fd, LOCK_EX | LOCK_NB) == 0) {
      // Unlink only if the name still is the file locked, not a new writer's that took it.
      struct stat named;
      if (::fstatat(dir_fd, entry->d_name, &named, AT_SYMLINK_NOFOLLOW) == 0 &&
          SameFile(named, locked)) {
        ::unlinkat(dir_fd, entry->d_name, 0);
      }
    }
    ::close(fd);
  }
  ::closedir(dir);
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

// fsyncs the directory `dir` itself, so that entries created or renamed in it are durable.
Status SyncDirectory(const std::string& dir) {
  int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return ErrnoStatus(errno, "open directory", dir);
  int rc = ::fsync(fd);
  int err = errno;
  ::close(fd);
  // Some file systems cannot fsync a directory; the entry is then as durable as they allow.
  if (rc != 0 && err != EINVAL) return ErrnoStatus(err, "fsync directory", dir);
  return Status::Ok();
}

}  // namespace

StatusOr<AtomicFileWriter> AtomicFileWriter::Create(const std::string& path) {
  if (path.empty()) return InvalidArgumentError("cannot write a file with an empty path");
  RemoveStaleTemporaries(path);
  for (int attempt = 0; attempt < kMaxCreateAttempts; ++attempt) {
    std::string temp_path = path + std::string(kTempInfix) + RandomSuffix();
    // A plain create, so that the umask and a default ACL apply as to any new file.
    int fd = ::open(temp_path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) {
      if (errno == EEXIST) continue;
      return ErrnoStatus(errno, "create temporary", temp_path);
    }
    // Blocks only while another writer's clean-up holds the lock. A file system without flock
    // leaves the temporary unlocked; clean-ups there cannot lock it either and leave it alone.
    while (::flock(fd, LOCK_EX) != 0 && errno == EINTR) {
    }
    // A clean-up may have locked and removed the new file before this writer locked it.
    struct stat opened, named;
    if (::fstat(fd, &opened) != 0) {
      Status status = ErrnoStatus(errno, "stat temporary", temp_path);
      ::unlink(temp_path.c_str());
      ::close(fd);
      return status;
    }
    if (::lstat(temp_path.c_str(), &named) == 0 && SameFile(named, opened)) {
      return AtomicFileWriter(path, std::move(temp_path), fd);
    }
    ::close(fd);
  }
  return IoError(fmt::format("cannot create a temporary {}{}XXXXXXXXXXXX: {} names tried", path,
                             kTempInfix, kMaxCreateAttempts));
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
  // Unlinked before the close releases the lock, so no clean-up sees it unlocked under its name.
  if (!committed_ && !temp_path_.empty()) ::unlink(temp_path_.c_str());
  temp_path_.clear();
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

Status AtomicFileWriter::Fail(Status status) {
  Abandon();
  error_ = status;
  return status;
}

Status AtomicFileWriter::FlushBuffer() {
  Status status = WriteAll(fd_, buffer_, temp_path_);
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
    status = WriteAll(fd_, data, temp_path_);
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
  if (::fsync(fd_) != 0) return Fail(ErrnoStatus(errno, "fsync", temp_path_));
  // close() can report a deferred write error (NFS, quotas), and does so on every descriptor of
  // the file; closing a duplicate keeps the lock on fd_ until the temporary has been renamed.
  const int duplicate = ::fcntl(fd_, F_DUPFD_CLOEXEC, 0);
  if (duplicate < 0) return Fail(ErrnoStatus(errno, "duplicate the descriptor of", temp_path_));
  if (::close(duplicate) != 0) return Fail(ErrnoStatus(errno, "close", temp_path_));
  if (::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    return Fail(ErrnoStatus(errno, "rename " + temp_path_ + " over", path_));
  }
  committed_ = true;
  temp_path_.clear();
  ::close(fd_);
  fd_ = -1;
  status = SyncDirectory(DirectoryOf(path_));
  if (!status.ok()) error_ = status;
  return status;
}

Status WriteFileAtomically(const std::string& path, std::string_view contents) {
  StatusOr<AtomicFileWriter> writer = AtomicFileWriter::Create(path);
  if (!writer.ok()) return writer.status();
  GROVE_RETURN_IF_ERROR(writer->Append(contents));
  return writer->Commit();
}

Status EnsureDirectory(const std::string& dir, std::vector<std::string>* created) {
  if (dir.empty()) return InvalidArgumentError("cannot create a directory with an empty path");
  std::vector<std::string> made;
  auto fail = [&](Status s) {
    RemoveCreatedDirectories(made);
    return s;
  };
  size_t pos = 0;
  while (pos != std::string::npos) {
    pos = dir.find('/', pos + 1);
    std::string prefix = dir.substr(0, pos);
    // Skip "" (root), repeated slashes and the trailing slash.
    if (prefix.empty() || prefix.back() == '/') continue;
    if (::mkdir(prefix.c_str(), 0777) == 0) {
      made.push_back(prefix);
      // The new directory's own entries, then its entry in the parent.
      if (Status s = SyncDirectory(prefix); !s.ok()) return fail(s);
      if (Status s = SyncDirectory(DirectoryOf(prefix)); !s.ok()) return fail(s);
      continue;
    }
    int err = errno;
    struct stat st;
    if (err == EEXIST || err == EISDIR) {
      if (::stat(prefix.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) continue;
      return fail(IoError(fmt::format(
          "cannot create directory {}: {} exists and is not a directory", dir, prefix)));
    }
    // EACCES on an existing directory (e.g. a read-only parent) is not an error.
    if (::stat(prefix.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) continue;
    return fail(IoError(fmt::format("cannot create directory {}: {}", prefix, ErrnoText(err))));
  }
  if (created != nullptr) created->insert(created->end(), made.begin(), made.end());
  return Status::Ok();
}

void RemoveCreatedDirectories(const std::vector<std::string>& created) {
  for (auto it = created.rbegin(); it != created.rend(); ++it) ::rmdir(it->c_str());
}

}  // namespace grove::tools

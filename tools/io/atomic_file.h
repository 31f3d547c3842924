// Durable output files: write to a unique temporary name in the same directory, flush, fsync,
// rename over the target, fsync the directory (LevelDB SetCurrentFile). An earlier good output is
// never truncated by a failed run.
//
// Temporaries are named PATH.tmp-XXXXXXXXXXXX (random) and held under flock(LOCK_EX) by their
// writer until the rename. Creating a writer removes the temporaries of the same target that no
// live writer holds: those a killed writer left behind, whatever their suffix (the older
// PATH.tmp-<pid>-<n> names too). On a file system without flock nothing is removed.
//
// Errors: IoError naming the file concerned (the temporary, for its creation, writes and fsync)
// and the operating system's reason; ResourceExhausted when the disk is full (ENOSPC, EDQUOT).
#ifndef GROVE_TOOLS_IO_ATOMIC_FILE_H_
#define GROVE_TOOLS_IO_ATOMIC_FILE_H_

#include <string>
#include <string_view>
#include <vector>

#include "grove/status.h"

namespace grove::tools {

// Replaces `path` with `contents`. On failure the temporary is removed and `path` keeps its
// previous contents, except when only the final directory fsync fails (the rename has happened).
Status WriteFileAtomically(const std::string& path, std::string_view contents);

// Streaming variant for large outputs. Movable, not copyable.
// Thread safety: none; one thread uses a writer at a time.
class AtomicFileWriter {
 public:
  static constexpr size_t kBufferBytes = 1 << 20;

  // Removes stale temporaries of `path`, then creates a new one, `path` + ".tmp-" + 12 random
  // characters, next to `path` (the directory must exist), mode 0666 less the umask.
  static StatusOr<AtomicFileWriter> Create(const std::string& path);

  AtomicFileWriter(AtomicFileWriter&& other) noexcept;
  AtomicFileWriter& operator=(AtomicFileWriter&& other) noexcept;
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  // Without a successful Commit() the temporary is removed and `path` is untouched.
  ~AtomicFileWriter();

  // Buffers `data`, writing full buffers. After the first failure the temporary is already gone
  // and every later call returns that failure again.
  Status Append(std::string_view data);
  // Flushes, fsyncs, renames over path() and fsyncs the directory. REQUIRES: called once.
  Status Commit();

  const std::string& path() const { return path_; }
  const std::string& temp_path() const { return temp_path_; }

 private:
  friend class AtomicFileWriterTestPeer;

  AtomicFileWriter(std::string path, std::string temp_path, int fd);
  Status FlushBuffer();
  // Closes and removes the temporary and remembers `status` for later calls; returns it.
  Status Fail(Status status);
  void Abandon();

  std::string path_;
  std::string temp_path_;
  int fd_ = -1;  // holds the flock that tells other writers the temporary is in use
  std::string buffer_;
  Status error_;
  bool committed_ = false;
};

// mkdir -p: creates `dir` and its missing parents (mode 0777 minus umask), fsyncing each new
// directory and then its parent, so that a crash cannot lose a directory a later file went into.
// Fails if some component exists and is not a directory; a failed call removes what it made
// (deepest first), so it leaves nothing new. `created`, when given, gets the directories made,
// outermost first, for a caller that must remove them if it fails later.
Status EnsureDirectory(const std::string& dir, std::vector<std::string>* created = nullptr);

// Removes the directories of `created` (as EnsureDirectory lists them) that are empty, deepest
// first; one that is not empty stays.
void RemoveCreatedDirectories(const std::vector<std::string>& created);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_ATOMIC_FILE_H_

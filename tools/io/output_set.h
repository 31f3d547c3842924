// The output directory of a run and the set of files a run writes into it, written as a set.
//
// OutputDirectory: opened before the first step. It creates the directory and its missing
// parents if needed (removed again, those still empty, when the run does not succeed), takes an
// exclusive lock on it (flock(2) on the directory itself: a second run into the same directory is
// refused at once, and the lock dies with its process), and removes the staging directories that
// killed runs left behind.
//
// OutputSet: every file is written complete and fsynced into a fresh staging directory inside
// the output directory (`.grove-staging-XXXXXX`); only when all of them are there are they
// renamed into place, one rename each, and summary.json, the manifest, is written last: it
// names the run (`run_id`) and lists every file with its size and CRC-32. A failure or a signal
// before the renames leaves the earlier outputs untouched; a crash during the renames (a few
// microseconds) leaves files that the manifest does not list, or lists with another CRC-32.
//
// Thread safety: none; one thread runs a command.
#ifndef GROVE_TOOLS_IO_OUTPUT_SET_H_
#define GROVE_TOOLS_IO_OUTPUT_SET_H_

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "grove/status.h"

namespace grove::tools {

// grove::Version() as JSON: every summary.json and benchmark result carries it.
nlohmann::json VersionJson();

class OutputDirectory {
 public:
  // IoError when `path` cannot be a directory (a file is in the way, no permission), or
  // FailedPrecondition "is in use by another grove run" when another process holds the lock.
  static StatusOr<OutputDirectory> Open(const std::string& path);
  OutputDirectory(OutputDirectory&& other) noexcept;
  OutputDirectory& operator=(OutputDirectory&&) = delete;
  OutputDirectory(const OutputDirectory&) = delete;
  // Unlocks; unless Keep() was called, removes the directories Open() created (the directory
  // and its parents) that are empty, deepest first.
  ~OutputDirectory();

  const std::string& path() const { return path_; }
  // The run succeeded (or wrote a checkpoint into it): never remove the directory.
  void Keep() { keep_ = true; }

 private:
  OutputDirectory(std::string path, int fd, std::vector<std::string> created)
      : path_(std::move(path)), fd_(fd), created_(std::move(created)) {}
  std::string path_;
  int fd_ = -1;
  std::vector<std::string> created_;  // by Open(), outermost first
  bool keep_ = false;
};

class OutputSet {
 public:
  // A staging directory inside `dir` (which must exist and be locked by this run).
  static StatusOr<OutputSet> Begin(const std::string& dir);
  OutputSet(OutputSet&& other) noexcept;
  OutputSet& operator=(OutputSet&&) = delete;
  OutputSet(const OutputSet&) = delete;
  // Removes the staging directory and whatever is in it, unless committed.
  ~OutputSet();

  // Writes `name` (a plain file name) into the staging directory, flushed and fsynced.
  Status Add(const std::string& name, std::string_view contents);
  // Where a writer that takes a path should write `name`; then Adopt(name).
  std::string StagingPath(const std::string& name) const;
  // Takes `name`, written at StagingPath(name) by another writer, into the set.
  Status Adopt(const std::string& name);

  // Renames every file into the output directory, then writes `summary` with "run_id" and
  // "outputs" (name -> {bytes, crc32}) added as summary.json, fsyncs the directory and removes
  // the staging directory. REQUIRES: called once.
  Status Commit(nlohmann::json summary);

  // Names of the files added so far (summary.json comes at Commit()).
  const std::vector<std::string>& names() const { return names_; }
  const std::string& run_id() const { return run_id_; }

 private:
  OutputSet(std::string dir, std::string staging, std::string run_id)
      : dir_(std::move(dir)), staging_(std::move(staging)), run_id_(std::move(run_id)) {}
  std::string dir_;
  std::string staging_;
  std::string run_id_;
  std::vector<std::string> names_;
  std::vector<uint32_t> crcs_;
  std::vector<uint64_t> sizes_;
  bool committed_ = false;
};

// The prefix of staging directories inside an output directory.
inline constexpr char kStagingPrefix[] = ".grove-staging-";

}  // namespace grove::tools

#endif  // GROVE_TOOLS_IO_OUTPUT_SET_H_

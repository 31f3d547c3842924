#include "tools/io/output_set.h"

#include <dirent.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <filesystem>
#include <system_error>
#include <utility>

#include "grove/checksum.h"
#include "grove/version.h"
#include "tools/io/atomic_file.h"
#include "tools/io/csv_reader.h"

namespace grove::tools {
namespace {

std::string ErrnoText(int err) { return std::generic_category().message(err); }

// Removes what killed runs left: staging directories. The caller holds the directory's lock.
void RemoveStaleStaging(const std::string& dir) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(kStagingPrefix, 0) == 0) std::filesystem::remove_all(entry.path(), ec);
  }
}

}  // namespace

StatusOr<OutputDirectory> OutputDirectory::Open(const std::string& path) {
  if (path.empty()) return InvalidArgumentError("--out: the path is empty");
  struct stat st;
  std::vector<std::string> created;
  if (::stat(path.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode)) {
      return IoError(fmt::format("--out {}: exists and is not a directory", path));
    }
  } else {
    GROVE_RETURN_IF_ERROR(EnsureDirectory(path, &created));
  }
  int fd = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) {
    RemoveCreatedDirectories(created);
    return IoError(fmt::format("cannot open directory {}: {}", path, ErrnoText(errno)));
  }
  OutputDirectory dir(path, fd, std::move(created));
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    if (errno == EWOULDBLOCK) {
      return FailedPreconditionError(
          fmt::format("{} is in use by another grove run: give each run its own --out", path));
    }
    return IoError(fmt::format("cannot lock directory {}: {}", path, ErrnoText(errno)));
  }
  if (::access(path.c_str(), W_OK) != 0) {
    return IoError(fmt::format("cannot write into directory {}: {}", path, ErrnoText(errno)));
  }
  RemoveStaleStaging(path);
  return dir;
}

OutputDirectory::OutputDirectory(OutputDirectory&& other) noexcept
    : path_(std::move(other.path_)),
      fd_(std::exchange(other.fd_, -1)),
      created_(std::move(other.created_)),
      keep_(other.keep_) {
  other.created_.clear();
}

OutputDirectory::~OutputDirectory() {
  if (fd_ < 0) return;
  ::close(fd_);
  if (!keep_) RemoveCreatedDirectories(created_);  // only the empty ones
}

StatusOr<OutputSet> OutputSet::Begin(const std::string& dir) {
  std::string staging = dir + "/" + kStagingPrefix + "XXXXXX";
  if (::mkdtemp(staging.data()) == nullptr) {
    return IoError(
        fmt::format("cannot create a staging directory in {}: {}", dir, ErrnoText(errno)));
  }
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  std::string id =
      fmt::format("{:x}-{}", std::chrono::duration_cast<std::chrono::microseconds>(now).count(),
                  staging.substr(staging.size() - 6));
  return OutputSet(dir, std::move(staging), std::move(id));
}

OutputSet::OutputSet(OutputSet&& other) noexcept
    : dir_(std::move(other.dir_)),
      staging_(std::exchange(other.staging_, std::string())),
      run_id_(std::move(other.run_id_)),
      names_(std::move(other.names_)),
      crcs_(std::move(other.crcs_)),
      sizes_(std::move(other.sizes_)),
      committed_(other.committed_) {}

OutputSet::~OutputSet() {
  if (staging_.empty() || committed_) return;
  std::error_code ec;
  std::filesystem::remove_all(staging_, ec);
}

std::string OutputSet::StagingPath(const std::string& name) const { return staging_ + "/" + name; }

Status OutputSet::Add(const std::string& name, std::string_view contents) {
  GROVE_RETURN_IF_ERROR(WriteFileAtomically(StagingPath(name), contents));
  names_.push_back(name);
  crcs_.push_back(Crc32(contents));
  sizes_.push_back(contents.size());
  return Status::Ok();
}

Status OutputSet::Adopt(const std::string& name) {
  StatusOr<std::string> contents = ReadWholeFile(StagingPath(name));
  if (!contents.ok()) return contents.status();
  names_.push_back(name);
  crcs_.push_back(Crc32(*contents));
  sizes_.push_back(contents->size());
  return Status::Ok();
}

nlohmann::json VersionJson() {
  const VersionInfo v = Version();
  return {{"version", v.version},         {"commit", v.commit},
          {"compiler", v.compiler},       {"build_type", v.build_type},
          {"simd_target", v.simd_target}, {"simd_targets", v.simd_targets}};
}

Status OutputSet::Commit(nlohmann::json summary) {
  summary["grove"] = VersionJson();
  // Nothing is renamed unless every target can take a file.
  std::vector<std::string> targets = names_;
  targets.push_back("summary.json");
  for (const std::string& name : targets) {
    struct stat st;
    const std::string target = dir_ + "/" + name;
    if (::lstat(target.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
      return IoError(fmt::format("cannot write {}: it is a directory", target));
    }
  }
  nlohmann::json outputs = nlohmann::json::object();
  for (size_t i = 0; i < names_.size(); ++i) {
    const std::string target = dir_ + "/" + names_[i];
    if (::rename(StagingPath(names_[i]).c_str(), target.c_str()) != 0) {
      return IoError(
          fmt::format("cannot rename the new {} into place: {}", target, ErrnoText(errno)));
    }
    outputs[names_[i]] = {{"bytes", sizes_[i]}, {"crc32", crcs_[i]}};
  }
  summary["run_id"] = run_id_;
  summary["outputs"] = outputs;
  // The manifest last: it names the files that belong to this run.
  GROVE_RETURN_IF_ERROR(WriteFileAtomically(dir_ + "/summary.json", summary.dump(2) + "\n"));
  committed_ = true;
  std::error_code ec;
  std::filesystem::remove_all(staging_, ec);
  return Status::Ok();
}

}  // namespace grove::tools

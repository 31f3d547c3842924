#include "tools/io/atomic_file.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

std::mutex fsync_mutex;
std::vector<std::string>* fsync_paths = nullptr;  // guarded by fsync_mutex

}  // namespace

// Every fsync of this test binary, grove_tools' included, comes here: the executable's definition
// interposes the C library's. While a FsyncRecorder lives it records the path of each descriptor
// synced; then it does the real fsync.
extern "C" int fsync(int fd) {
  {
    std::lock_guard<std::mutex> lock(fsync_mutex);
    if (fsync_paths != nullptr) {
      char target[4096];
      const std::string link = "/proc/self/fd/" + std::to_string(fd);
      const ssize_t n = ::readlink(link.c_str(), target, sizeof(target));
      fsync_paths->push_back(n > 0 ? std::string(target, static_cast<size_t>(n)) : "?");
    }
  }
  return static_cast<int>(::syscall(SYS_fsync, fd));
}

namespace grove::tools {

// Swaps a writer's temporary file descriptor for another one (e.g. /dev/full), so the writer's
// own write path meets a real ENOSPC.
class AtomicFileWriterTestPeer {
 public:
  static void ReplaceFd(AtomicFileWriter& writer, int fd) { ASSERT_GE(::dup2(fd, writer.fd_), 0); }
};

namespace {

namespace fs = std::filesystem;

// A directory of its own for each test, removed afterwards.
class ScratchDir {
 public:
  ScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = (fs::path(::testing::TempDir()) /
             (std::string("atomic_file_") + info->name() + "_" + std::to_string(::getpid())))
                .string();
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The paths fsynced while it lives, in order. One at a time.
class FsyncRecorder {
 public:
  FsyncRecorder() {
    std::lock_guard<std::mutex> lock(fsync_mutex);
    fsync_paths = &paths_;
  }
  ~FsyncRecorder() {
    std::lock_guard<std::mutex> lock(fsync_mutex);
    fsync_paths = nullptr;
  }
  std::vector<std::string> Take() {
    std::lock_guard<std::mutex> lock(fsync_mutex);
    return std::exchange(paths_, {});
  }

 private:
  std::vector<std::string> paths_;
};

std::vector<std::string> ListDir(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(WriteFileAtomicallyTest, CreatesFileWithContents) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  std::string path = dir + "/out.csv";
  ASSERT_TRUE(WriteFileAtomically(path, "a,b\n1,2\n").ok());
  EXPECT_EQ(ReadFile(path), "a,b\n1,2\n");
  EXPECT_EQ(ListDir(dir), std::vector<std::string>{"out.csv"});
}

TEST(WriteFileAtomicallyTest, ReplacesExistingFile) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  std::string path = dir + "/out.csv";
  ASSERT_TRUE(WriteFileAtomically(path, "old contents that are longer\n").ok());
  ASSERT_TRUE(WriteFileAtomically(path, "new\n").ok());
  EXPECT_EQ(ReadFile(path), "new\n");
  EXPECT_EQ(ListDir(dir), std::vector<std::string>{"out.csv"});
}

TEST(WriteFileAtomicallyTest, MissingDirectoryFailsWithIoErrorNamingThePath) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  std::string path = dir + "/no/such/dir/out.csv";
  Status status = WriteFileAtomically(path, "x");
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), StatusCode::kIoError);
  // The message names the temporary that could not be created.
  EXPECT_NE(status.message().find("cannot create temporary " + path + ".tmp-"), std::string::npos)
      << status.message();
  EXPECT_NE(status.message().find("No such file or directory"), std::string::npos)
      << status.message();
  EXPECT_TRUE(ListDir(dir).empty());
}

TEST(WriteFileAtomicallyTest, EmptyPathIsInvalidArgument) {
  EXPECT_EQ(WriteFileAtomically("", "x").code(), StatusCode::kInvalidArgument);
}

TEST(AtomicFileWriterTest, TemporaryIsAUniqueNameInTheSameDirectory) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  std::string path = dir + "/out.csv";
  StatusOr<AtomicFileWriter> a = AtomicFileWriter::Create(path);
  StatusOr<AtomicFileWriter> b = AtomicFileWriter::Create(path);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_NE(a->temp_path(), b->temp_path());
  for (const std::string& temp : {a->temp_path(), b->temp_path()}) {
    const std::string prefix = path + ".tmp-";
    ASSERT_EQ(temp.rfind(prefix, 0), 0u) << temp;
    const std::string suffix = temp.substr(prefix.size());
    EXPECT_EQ(suffix.size(), 12u) << temp;
    EXPECT_TRUE(std::all_of(suffix.begin(), suffix.end(), [](unsigned char c) {
      return std::isalnum(c) != 0;
    })) << temp;
    EXPECT_TRUE(fs::is_regular_file(temp));
  }
  // The second Create did not take the first writer's temporary for a stale one.
  EXPECT_EQ(ListDir(dir).size(), 2u);
  EXPECT_FALSE(fs::exists(path));
}

TEST(AtomicFileWriterTest, TemporaryHasTheModeOfANormalCreate) {
  ScratchDir scratch;
  const mode_t old_mask = ::umask(027);
  StatusOr<AtomicFileWriter> writer = AtomicFileWriter::Create(scratch.path() + "/out.csv");
  ::umask(old_mask);
  ASSERT_TRUE(writer.ok()) << writer.status().ToString();
  struct stat st;
  ASSERT_EQ(::stat(writer->temp_path().c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
}

void WriteRawFile(const std::string& path, const std::string& contents) {
  std::ofstream out(path, std::ios::binary);
  out << contents;
  ASSERT_TRUE(out.good()) << path;
}

// Regression: temporaries were named PATH.tmp-<pid>-<n> and created with
// O_EXCL, so one left by a killed process whose pid came back (a PID namespace restarts at 1)
// made every later write of PATH fail with "File exists", naming PATH.
TEST(AtomicFileWriterTest, StaleTemporariesOfDeadWritersDoNotBlockAWriteAndAreRemoved) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  const std::string path = dir + "/checkpoint.grove";
  // What a killed writer with our pid leaves behind, in the old naming (for every counter value
  // this process may have reached) and in the new one.
  for (int n = 0; n < 256; ++n) {
    WriteRawFile(path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(n), "old");
  }
  WriteRawFile(path + ".tmp-AbCdEf012345", "stale");
  // Not temporaries of this target, or not regular files: left alone.
  WriteRawFile(dir + "/other.grove.tmp-AbCdEf012345", "x");
  WriteRawFile(path + ".tmpX", "x");
  WriteRawFile(path + ".tmp-", "x");
  fs::create_directory(path + ".tmp-dir");
  WriteRawFile(dir + "/target", "x");
  fs::create_symlink(dir + "/target", path + ".tmp-link");

  Status status = WriteFileAtomically(path, "new checkpoint");
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(ReadFile(path), "new checkpoint");
  const std::vector<std::string> expected = {"checkpoint.grove",
                                             "checkpoint.grove.tmp-",
                                             "checkpoint.grove.tmp-dir",
                                             "checkpoint.grove.tmp-link",
                                             "checkpoint.grove.tmpX",
                                             "other.grove.tmp-AbCdEf012345",
                                             "target"};
  EXPECT_EQ(ListDir(dir), expected);
  EXPECT_EQ(ReadFile(dir + "/target"), "x");
}

TEST(AtomicFileWriterTest, TemporaryLockedByALiveWriterIsNotRemoved) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  const std::string path = dir + "/map.csv";
  // A writer of this library in this process, and a foreign one that holds its own lock.
  StatusOr<AtomicFileWriter> live = AtomicFileWriter::Create(path);
  ASSERT_TRUE(live.ok()) << live.status().ToString();
  ASSERT_TRUE(live->Append("from the live writer").ok());
  const std::string foreign = path + ".tmp-Foreign00000";
  WriteRawFile(foreign, "in progress");
  const int fd = ::open(foreign.c_str(), O_RDONLY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);

  ASSERT_TRUE(WriteFileAtomically(path, "from the other writer").ok());
  EXPECT_TRUE(fs::exists(live->temp_path()));
  EXPECT_TRUE(fs::exists(foreign));
  EXPECT_EQ(ReadFile(foreign), "in progress");
  ASSERT_TRUE(live->Commit().ok());
  EXPECT_EQ(ReadFile(path), "from the live writer");

  // Once its writer is gone (the lock with it), the foreign temporary is stale.
  ::close(fd);
  ASSERT_TRUE(WriteFileAtomically(path, "last").ok());
  EXPECT_EQ(ListDir(dir), std::vector<std::string>{"map.csv"});
}

TEST(AtomicFileWriterTest, ParallelWritersOfOneTargetAllSucceed) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  const std::string path = dir + "/summary.json";
  const std::string contents[2] = {std::string(100000, 'a'), std::string(7, 'b')};
  constexpr int kWrites = 100;
  std::vector<std::string> failures[2];
  {
    std::vector<std::jthread> writers;
    for (int w = 0; w < 2; ++w) {
      writers.emplace_back([&, w] {
        for (int i = 0; i < kWrites; ++i) {
          Status status = WriteFileAtomically(path, contents[w]);
          if (!status.ok()) failures[w].push_back(status.ToString());
        }
      });
    }
  }
  for (int w = 0; w < 2; ++w) EXPECT_TRUE(failures[w].empty()) << failures[w].front();
  const std::string result = ReadFile(path);
  EXPECT_TRUE(result == contents[0] || result == contents[1]) << result.size() << " bytes";
  EXPECT_EQ(ListDir(dir), std::vector<std::string>{"summary.json"});
}

TEST(AtomicFileWriterTest, StreamsDataLargerThanItsBuffer) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  std::string path = dir + "/big.csv";
  StatusOr<AtomicFileWriter> writer = AtomicFileWriter::Create(path);
  ASSERT_TRUE(writer.ok());
  std::string expected;
  for (int i = 0; i < 200000; ++i) {
    std::string line = std::to_string(i) + "," + std::to_string(i * 7) + "\n";
    expected += line;
    ASSERT_TRUE(writer->Append(line).ok());
  }
  std::string block(3 * AtomicFileWriter::kBufferBytes / 2, 'z');
  expected += block;
  ASSERT_TRUE(writer->Append(block).ok());
  ASSERT_GT(expected.size(), 2 * AtomicFileWriter::kBufferBytes);
  ASSERT_TRUE(writer->Commit().ok());
  EXPECT_EQ(ReadFile(path), expected);
  EXPECT_EQ(ListDir(dir), std::vector<std::string>{"big.csv"});
}

TEST(AtomicFileWriterTest, DestroyedWithoutCommitKeepsOldFileAndRemovesTemporary) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  std::string path = dir + "/map.csv";
  ASSERT_TRUE(WriteFileAtomically(path, "good old output\n").ok());
  {
    StatusOr<AtomicFileWriter> writer = AtomicFileWriter::Create(path);
    ASSERT_TRUE(writer.ok());
    ASSERT_TRUE(writer->Append(std::string(3 * AtomicFileWriter::kBufferBytes, 'x')).ok());
    EXPECT_EQ(ListDir(dir).size(), 2u);  // the temporary exists while writing
  }
  EXPECT_EQ(ReadFile(path), "good old output\n");
  EXPECT_EQ(ListDir(dir), std::vector<std::string>{"map.csv"});
}

TEST(AtomicFileWriterTest, MovedWriterCommitsAndMovedFromWriterRemovesNothing) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  std::string path = dir + "/out.txt";
  StatusOr<AtomicFileWriter> created = AtomicFileWriter::Create(path);
  ASSERT_TRUE(created.ok());
  AtomicFileWriter first = std::move(created).value();
  ASSERT_TRUE(first.Append("hello ").ok());
  AtomicFileWriter second = std::move(first);
  ASSERT_TRUE(second.Append("world").ok());
  EXPECT_EQ(first.Commit().code(), StatusCode::kFailedPrecondition);  // NOLINT: use after move
  ASSERT_TRUE(second.Commit().ok());
  EXPECT_EQ(ReadFile(path), "hello world");
  EXPECT_EQ(ListDir(dir), std::vector<std::string>{"out.txt"});
}

TEST(AtomicFileWriterTest, SecondCommitIsFailedPrecondition) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  StatusOr<AtomicFileWriter> writer = AtomicFileWriter::Create(dir + "/a");
  ASSERT_TRUE(writer.ok());
  ASSERT_TRUE(writer->Commit().ok());
  EXPECT_EQ(writer->Commit().code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(writer->Append("x").code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(ReadFile(dir + "/a"), "");
}

int OpenDevFull() { return ::open("/dev/full", O_WRONLY | O_CLOEXEC); }

TEST(AtomicFileWriterTest, FullDiskDuringAppendIsReportedAndLeavesNothingBehind) {
  int full = OpenDevFull();
  if (full < 0) GTEST_SKIP() << "/dev/full is not available";
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  std::string path = dir + "/trajectory.csv";
  ASSERT_TRUE(WriteFileAtomically(path, "previous run\n").ok());
  StatusOr<AtomicFileWriter> writer = AtomicFileWriter::Create(path);
  ASSERT_TRUE(writer.ok());
  AtomicFileWriterTestPeer::ReplaceFd(*writer, full);
  ::close(full);
  // More than one buffer, so Append itself has to write.
  Status status = writer->Append(std::string(2 * AtomicFileWriter::kBufferBytes, 'x'));
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), StatusCode::kResourceExhausted);
  EXPECT_NE(status.message().find("cannot write " + path + ".tmp-"), std::string::npos)
      << status.message();
  EXPECT_NE(status.message().find("No space left on device"), std::string::npos)
      << status.message();
  // The temporary is gone at once, and the writer keeps reporting the failure.
  EXPECT_EQ(ListDir(dir), std::vector<std::string>{"trajectory.csv"});
  EXPECT_EQ(writer->Append("y").code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(writer->Commit().code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(ReadFile(path), "previous run\n");
}

TEST(AtomicFileWriterTest, FullDiskDuringCommitFlushKeepsThePreviousFile) {
  int full = OpenDevFull();
  if (full < 0) GTEST_SKIP() << "/dev/full is not available";
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  std::string path = dir + "/map.csv";
  ASSERT_TRUE(WriteFileAtomically(path, "previous run\n").ok());
  StatusOr<AtomicFileWriter> writer = AtomicFileWriter::Create(path);
  ASSERT_TRUE(writer.ok());
  AtomicFileWriterTestPeer::ReplaceFd(*writer, full);
  ::close(full);
  ASSERT_TRUE(writer->Append("small, still buffered\n").ok());
  Status status = writer->Commit();
  EXPECT_EQ(status.code(), StatusCode::kResourceExhausted);
  EXPECT_NE(status.message().find(path), std::string::npos) << status.message();
  EXPECT_EQ(ReadFile(path), "previous run\n");
  EXPECT_EQ(ListDir(dir), std::vector<std::string>{"map.csv"});
}

TEST(EnsureDirectoryTest, CreatesMissingParentsAndIsIdempotent) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  std::string nested = dir + "/a/b//c/";
  ASSERT_TRUE(EnsureDirectory(nested).ok());
  EXPECT_TRUE(fs::is_directory(dir + "/a/b/c"));
  EXPECT_TRUE(EnsureDirectory(nested).ok());
  EXPECT_TRUE(EnsureDirectory(dir).ok());
}

TEST(WriteFileAtomicallyTest, SyncsTheTemporaryThenTheDirectory) {
  if (!fs::exists("/proc/self/fd")) GTEST_SKIP() << "no /proc/self/fd to name descriptors";
  ScratchDir scratch;
  const std::string dir = fs::canonical(scratch.path()).string();
  FsyncRecorder recorder;
  ASSERT_TRUE(WriteFileAtomically(dir + "/out.csv", "x").ok());
  const std::vector<std::string> synced = recorder.Take();
  ASSERT_EQ(synced.size(), 2u);
  EXPECT_EQ(synced[0].rfind(dir + "/out.csv.tmp-", 0), 0u) << synced[0];
  EXPECT_EQ(synced[1], dir);
}

// Regression: mkdir was never followed by an fsync of the parent, so after a
// crash the new output directory, and every file in it, could be gone.
TEST(EnsureDirectoryTest, SyncsEachNewDirectoryAndThenItsParent) {
  if (!fs::exists("/proc/self/fd")) GTEST_SKIP() << "no /proc/self/fd to name descriptors";
  ScratchDir scratch;
  const std::string base = fs::canonical(scratch.path()).string();
  ASSERT_TRUE(fs::create_directory(base + "/old"));
  FsyncRecorder recorder;
  ASSERT_TRUE(EnsureDirectory(scratch.path() + "/old/a//b/").ok());
  EXPECT_TRUE(fs::is_directory(base + "/old/a/b"));
  const std::vector<std::string> expected = {base + "/old/a", base + "/old", base + "/old/a/b",
                                             base + "/old/a"};
  EXPECT_EQ(recorder.Take(), expected);
  // Nothing new, nothing to sync.
  ASSERT_TRUE(EnsureDirectory(base + "/old/a/b").ok());
  EXPECT_TRUE(recorder.Take().empty());
}

TEST(EnsureDirectoryTest, RelativePathIsCreatedAndSyncedInTheWorkingDirectory) {
  if (!fs::exists("/proc/self/fd")) GTEST_SKIP() << "no /proc/self/fd to name descriptors";
  ScratchDir scratch;
  const std::string base = fs::canonical(scratch.path()).string();
  const fs::path previous = fs::current_path();
  fs::current_path(base);
  FsyncRecorder recorder;
  const Status status = EnsureDirectory("rel");
  const std::vector<std::string> synced = recorder.Take();
  fs::current_path(previous);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_TRUE(fs::is_directory(base + "/rel"));
  EXPECT_EQ(synced, (std::vector<std::string>{base + "/rel", base}));
}

TEST(EnsureDirectoryTest, FileInTheWayIsAnIoErrorNamingIt) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  ASSERT_TRUE(WriteFileAtomically(dir + "/blocker", "x").ok());
  Status status = EnsureDirectory(dir + "/blocker/sub");
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), StatusCode::kIoError);
  EXPECT_NE(status.message().find(dir + "/blocker exists and is not a directory"),
            std::string::npos)
      << status.message();
  status = EnsureDirectory(dir + "/blocker");
  EXPECT_EQ(status.code(), StatusCode::kIoError);
}

// Regression: a path whose last component was too long (ENAMETOOLONG) left the 20 directories
// made before it.
TEST(EnsureDirectoryTest, AFailedCallLeavesNoNewDirectory) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  std::string path = dir + "/keep";
  ASSERT_TRUE(EnsureDirectory(path).ok());
  for (int k = 0; k < 5; ++k) path += "/" + std::string(200, 'd');
  path += "/" + std::string(300, 'x');  // over NAME_MAX
  Status status = EnsureDirectory(path);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), StatusCode::kIoError);
  EXPECT_EQ(ListDir(dir + "/keep"), std::vector<std::string>{}) << "made directories stayed";
  EXPECT_TRUE(fs::is_directory(dir + "/keep")) << "an existing directory was removed";
}

TEST(EnsureDirectoryTest, CreatedDirectoriesAreListedAndRemovedWhenEmpty) {
  ScratchDir scratch;
  const std::string& dir = scratch.path();
  ASSERT_TRUE(EnsureDirectory(dir + "/a").ok());
  std::vector<std::string> created;
  ASSERT_TRUE(EnsureDirectory(dir + "/a/b/c", &created).ok());
  EXPECT_EQ(created, (std::vector<std::string>{dir + "/a/b", dir + "/a/b/c"}));
  ASSERT_TRUE(WriteFileAtomically(dir + "/a/b/c/file", "x").ok());
  RemoveCreatedDirectories(created);  // c is not empty: both stay
  EXPECT_TRUE(fs::exists(dir + "/a/b/c/file"));
  fs::remove(dir + "/a/b/c/file");
  RemoveCreatedDirectories(created);
  EXPECT_FALSE(fs::exists(dir + "/a/b"));
  EXPECT_TRUE(fs::is_directory(dir + "/a"));
}

TEST(EnsureDirectoryTest, EmptyPathIsInvalidArgument) {
  EXPECT_EQ(EnsureDirectory("").code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace grove::tools

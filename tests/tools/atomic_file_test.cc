#include "tools/atomic_file.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

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
  EXPECT_NE(status.message().find(path), std::string::npos) << status.message();
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
  std::string prefix = path + ".tmp-" + std::to_string(::getpid()) + "-";
  EXPECT_EQ(a->temp_path().rfind(prefix, 0), 0u) << a->temp_path();
  EXPECT_TRUE(fs::exists(a->temp_path()));
  EXPECT_FALSE(fs::exists(path));
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
  EXPECT_NE(status.message().find(path), std::string::npos) << status.message();
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

TEST(EnsureDirectoryTest, EmptyPathIsInvalidArgument) {
  EXPECT_EQ(EnsureDirectory("").code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace grove::tools

#include "tools/io/csv_reader.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

namespace grove::tools {
namespace {

// A path under the test temporary directory that is this process's own.
std::string TempPath(const std::string& name) {
  return (std::filesystem::path(::testing::TempDir()) /
          ("csv_reader_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

TEST(ReadWholeFileTest, ReturnsEveryByte) {
  const std::string bytes("a\0b\r\n\xff", 6);
  const std::string path = TempPath("bytes");
  std::ofstream(path, std::ios::binary) << bytes;
  StatusOr<std::string> read = ReadWholeFile(path);
  std::filesystem::remove(path);
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  EXPECT_EQ(*read, bytes);
}

TEST(ReadWholeFileTest, MissingIsNotFoundNamingPathAndReason) {
  const std::string path = TempPath("absent");
  StatusOr<std::string> read = ReadWholeFile(path);
  EXPECT_EQ(read.status().code(), StatusCode::kNotFound);
  EXPECT_EQ(read.status().message(), path + ": cannot open: No such file or directory");
}

TEST(ReadWholeFileTest, DirectoryIsAnIoError) {
  const std::string dir = ::testing::TempDir();
  StatusOr<std::string> read = ReadWholeFile(dir);
  EXPECT_EQ(read.status().code(), StatusCode::kIoError);
  EXPECT_EQ(read.status().message().rfind(dir + ": ", 0), 0u) << read.status().message();
}

// Regression: a file that exists but cannot be opened gave "cannot open
// for reading" without the reason. A socket cannot be opened even by root (ENXIO).
TEST(LineReaderTest, OpenFailureNamesTheReason) {
  const std::string path = TempPath("socket");
  std::filesystem::remove(path);
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  ASSERT_LT(path.size(), sizeof(address.sun_path)) << path;
  std::memcpy(address.sun_path, path.c_str(), path.size() + 1);
  ASSERT_EQ(::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)), 0);
  StatusOr<LineReader> lines = LineReader::Open(path, 64);
  ::close(fd);
  std::filesystem::remove(path);
  EXPECT_EQ(lines.status().code(), StatusCode::kIoError);
  EXPECT_EQ(lines.status().message(),
            path + ": cannot open for reading: No such device or address");
}

// The status of LineReader::Open(path) as an unprivileged user: run in a child process that drops
// root's rights when the test runs as root (root reads files without read permission).
std::string OpenMessageWithoutPrivileges(const std::string& path) {
  if (::geteuid() != 0) return LineReader::Open(path, 64).status().message();
  int fds[2];
  if (::pipe(fds) != 0) return "pipe failed";
  const pid_t child = ::fork();
  if (child == 0) {
    ::close(fds[0]);
    std::string message = "cannot drop privileges";
    if (::setgid(65534) == 0 && ::setuid(65534) == 0) {
      message = LineReader::Open(path, 64).status().message();
    }
    const ssize_t ignored = ::write(fds[1], message.data(), message.size());
    (void)ignored;
    ::_exit(0);
  }
  ::close(fds[1]);
  std::string message;
  char buffer[512];
  ssize_t n;
  while ((n = ::read(fds[0], buffer, sizeof(buffer))) > 0) message.append(buffer, n);
  ::close(fds[0]);
  ::waitpid(child, nullptr, 0);
  return message;
}

TEST(LineReaderTest, UnreadableFileIsPermissionDenied) {
  const std::string path = TempPath("unreadable");
  std::ofstream(path) << "t,dx,dy\n";
  std::filesystem::permissions(path, std::filesystem::perms::none);
  const std::string message = OpenMessageWithoutPrivileges(path);
  std::filesystem::remove(path);
  EXPECT_EQ(message, path + ": cannot open for reading: Permission denied");
}

TEST(LineReaderTest, ReadsAFileThroughItsDescriptor) {
  const std::string path = TempPath("lines");
  // Longer than the 64 KiB buffer, so that reads continue where they stopped.
  std::string contents;
  for (int i = 0; i < 20000; ++i) contents += std::to_string(i) + "\n";
  std::ofstream(path, std::ios::binary) << contents;
  StatusOr<LineReader> lines = LineReader::Open(path, 64);
  ASSERT_TRUE(lines.ok()) << lines.status().ToString();
  std::string_view line;
  int count = 0;
  for (;;) {
    StatusOr<bool> more = lines->Next(&line);
    ASSERT_TRUE(more.ok()) << more.status().ToString();
    if (!*more) break;
    ASSERT_EQ(line, std::to_string(count)) << "line " << count + 1;
    ++count;
  }
  std::filesystem::remove(path);
  EXPECT_EQ(count, 20000);
}

TEST(LineReaderTest, DirectoryIsAnIoErrorMissingIsNotFoundBadLimitIsInvalid) {
  EXPECT_EQ(LineReader::Open(::testing::TempDir(), 64).status().code(), StatusCode::kIoError);
  EXPECT_EQ(LineReader::Open(TempPath("absent"), 64).status().code(), StatusCode::kNotFound);
  EXPECT_EQ(LineReader::Open(TempPath("absent"), 15).status().code(), StatusCode::kInvalidArgument);
}

TEST(LineReaderTest, StripsTerminatorsAndTheByteOrderMarkAndCountsLines) {
  StatusOr<LineReader> lines = LineReader::FromStream(
      "f", std::make_unique<std::istringstream>("\xEF\xBB\xBFone\r\n\ntwo"), 16);
  ASSERT_TRUE(lines.ok());
  std::string_view line;
  std::vector<std::string> got;
  for (;;) {
    StatusOr<bool> more = lines->Next(&line);
    ASSERT_TRUE(more.ok()) << more.status().ToString();
    if (!*more) break;
    got.emplace_back(line);
  }
  EXPECT_EQ(got, (std::vector<std::string>{"one", "", "two"}));
  EXPECT_EQ(lines->line_number(), 3);
}

TEST(LineReaderTest, LongLineIsAnErrorAtItsLineAndStays) {
  StatusOr<LineReader> lines = LineReader::FromStream(
      "f", std::make_unique<std::istringstream>("ok\n" + std::string(17, 'x') + "\n"), 16);
  ASSERT_TRUE(lines.ok());
  std::string_view line;
  ASSERT_TRUE(*lines->Next(&line));
  StatusOr<bool> more = lines->Next(&line);
  EXPECT_EQ(more.status().message(), "f:2:1: line longer than 16 bytes");
  EXPECT_EQ(lines->Next(&line).status().message(), more.status().message());
}

TEST(CsvFieldsTest, SplitTrimsBlanksAndGivesColumns) {
  std::vector<CsvField> fields;
  SplitCsvLine(" a ,\tb,,  ", &fields);
  ASSERT_EQ(fields.size(), 4u);
  EXPECT_EQ(fields[0].text, "a");
  EXPECT_EQ(fields[0].column, 2);
  EXPECT_EQ(fields[1].text, "b");
  EXPECT_EQ(fields[1].column, 6);
  EXPECT_EQ(fields[2].text, "");
  EXPECT_EQ(fields[2].column, 8);
  EXPECT_EQ(fields[3].text, "");
  EXPECT_EQ(fields[3].column, 9);
}

TEST(CsvFieldsTest, BlankAndSkippedLines) {
  EXPECT_TRUE(IsBlankLine(""));
  EXPECT_TRUE(IsBlankLine(" \t "));
  EXPECT_FALSE(IsBlankLine(" # note"));
  EXPECT_TRUE(IsSkippedLine(" # note"));
  EXPECT_FALSE(IsSkippedLine("1,#"));
}

TEST(CsvFieldsTest, QuotedFieldIsEscapedAndShortened) {
  EXPECT_EQ(QuotedField("abc"), "\"abc\"");
  const std::string full(kMessageTextBytes, 'z');
  EXPECT_EQ(QuotedField(full), fmt::format("\"{}\"", full));
  EXPECT_EQ(QuotedField(full + "z"), fmt::format("\"{}...\"", full));
  EXPECT_EQ(QuotedField(std::string("a\x1b[2J\0\n\"", 8)), "\"a\\x1b[2J\\x00\\x0a\\x22\"");
}

TEST(CsvNumbersTest, DoubleClassifiesEveryFailure) {
  double v = 7;
  EXPECT_EQ(ParseCsvDouble("+1.5e1", &v), NumberParse::kOk);
  EXPECT_EQ(v, 15.0);
  v = 7;
  EXPECT_EQ(ParseCsvDouble("", &v), NumberParse::kEmpty);
  EXPECT_EQ(ParseCsvDouble("+-1", &v), NumberParse::kNotANumber);
  EXPECT_EQ(ParseCsvDouble("++1", &v), NumberParse::kNotANumber);
  EXPECT_EQ(ParseCsvDouble("0x1p3", &v), NumberParse::kNotANumber);
  EXPECT_EQ(ParseCsvDouble("1e999x", &v), NumberParse::kNotANumber);
  EXPECT_EQ(ParseCsvDouble("1e999", &v), NumberParse::kOutOfRange);
  EXPECT_EQ(ParseCsvDouble("nan", &v), NumberParse::kNotFinite);
  EXPECT_EQ(ParseCsvDouble("-inf", &v), NumberParse::kNotFinite);
  EXPECT_EQ(v, 7.0);  // untouched by failures
}

TEST(CsvNumbersTest, Int32ClassifiesEveryFailure) {
  int32_t v = 7;
  EXPECT_EQ(ParseCsvInt32("+12", &v), NumberParse::kOk);
  EXPECT_EQ(v, 12);
  EXPECT_EQ(ParseCsvInt32("-2147483648", &v), NumberParse::kOk);
  EXPECT_EQ(v, std::numeric_limits<int32_t>::min());
  v = 7;
  EXPECT_EQ(ParseCsvInt32("", &v), NumberParse::kEmpty);
  EXPECT_EQ(ParseCsvInt32("1.5", &v), NumberParse::kNotANumber);
  EXPECT_EQ(ParseCsvInt32("2147483648", &v), NumberParse::kOutOfRange);
  EXPECT_EQ(v, 7);
}

TEST(CsvNumbersTest, ParseFiniteNumberMessages) {
  double v = 0;
  EXPECT_TRUE(ParseFiniteNumber("f", 3, {"-2.5", 4}, "x", &v).ok());
  EXPECT_EQ(v, -2.5);
  EXPECT_EQ(ParseFiniteNumber("f", 3, {"", 4}, "x", &v).message(),
            "f:3:4: x: \"\" is not a number");
  EXPECT_EQ(ParseFiniteNumber("f", 3, {"inf", 4}, "x", &v).message(),
            "f:3:4: x = inf: must be finite");
  EXPECT_EQ(ParseFiniteNumber("f", 3, {"1e999", 4}, "x", &v).message(),
            "f:3:4: x: \"1e999\" is out of the range of a double");
  const std::string junk(500, 'z');
  EXPECT_LT(ParseFiniteNumber("f", 3, {junk, 4}, "x", &v).message().size(), 100u);
  EXPECT_EQ(ParseFiniteNumber("f", 3, {"1", 4}, "x", &v).code(), StatusCode::kOk);
}

}  // namespace
}  // namespace grove::tools

#include "tools/io/step_reader.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "tools/run/footslam_run.h"
#include "tools/sim/walk_simulator.h"

namespace grove::tools {
namespace {

// Writes `content` to a file named after the running test, so tests never share a file.
std::string WriteTempFile(std::string_view content, const std::string& name = "walk.csv") {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path path =
      std::filesystem::path(::testing::TempDir()) /
      (std::string("grove_") + info->test_suite_name() + "_" + info->name() + "_" + name);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(content.data(), static_cast<std::streamsize>(content.size()));
  out.close();
  EXPECT_TRUE(out) << "cannot write " << path;
  return path.string();
}

// The error message of reading the whole file, or "" when it reads fine.
std::string ReadError(const std::string& path, const StepReaderOptions& options = {}) {
  StatusOr<std::vector<StepRecord>> steps = ReadAllSteps(path, options);
  EXPECT_FALSE(steps.ok()) << path << " read without error";
  if (steps.ok()) return "";
  EXPECT_EQ(steps.status().code(), StatusCode::kInvalidArgument) << steps.status().ToString();
  return steps.status().message();
}

TEST(StepReaderTest, DeltasFormReadsEachRowAsAStepWithItsLine) {
  const std::string path = WriteTempFile("t,dx,dy\n1.0,0.5,0.25\n1.5,-0.5,0\n2.25,0,-0.7\n");
  StatusOr<std::vector<StepRecord>> steps = ReadAllSteps(path);
  ASSERT_TRUE(steps.ok()) << steps.status().ToString();
  ASSERT_EQ(steps->size(), 3u);
  EXPECT_EQ((*steps)[0].t_s, 1.0);
  EXPECT_EQ((*steps)[0].dx_m, 0.5);
  EXPECT_EQ((*steps)[0].dy_m, 0.25);
  EXPECT_EQ((*steps)[0].line, 2);
  EXPECT_EQ((*steps)[1].dx_m, -0.5);
  EXPECT_EQ((*steps)[2].t_s, 2.25);
  EXPECT_EQ((*steps)[2].dy_m, -0.7);
  EXPECT_EQ((*steps)[2].line, 4);
}

TEST(StepReaderTest, PositionsFormGivesDifferencesOfConsecutiveRows) {
  const std::string path = WriteTempFile("t,x,y\n10,2,3\n10.5,2.5,3\n11,2.5,2\n");
  StatusOr<StepReader> reader = StepReader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_TRUE(reader->positions_form());
  EXPECT_EQ(reader->start_time_s(), 10);
  EXPECT_EQ(reader->start_x_m(), 2);
  EXPECT_EQ(reader->start_y_m(), 3);
  StepRecord step;
  ASSERT_TRUE(*reader->Next(&step));
  EXPECT_EQ(step.t_s, 10.5);
  EXPECT_EQ(step.dx_m, 0.5);
  EXPECT_EQ(step.dy_m, 0);
  EXPECT_EQ(step.line, 3);
  ASSERT_TRUE(*reader->Next(&step));
  EXPECT_EQ(step.dx_m, 0);
  EXPECT_EQ(step.dy_m, -1);
  StatusOr<bool> more = reader->Next(&step);
  ASSERT_TRUE(more.ok()) << more.status().ToString();
  EXPECT_FALSE(*more);
  EXPECT_EQ(reader->steps_read(), 2);
}

TEST(StepReaderTest, DeltasFormStartsOnePeriodBeforeTheFirstStep) {
  StatusOr<StepReader> two =
      StepReader::Open(WriteTempFile("t,dx,dy\n4,1,0\n4.5,1,0\n", "two.csv"));
  ASSERT_TRUE(two.ok()) << two.status().ToString();
  EXPECT_FALSE(two->positions_form());
  EXPECT_EQ(two->start_time_s(), 3.5);
  EXPECT_EQ(two->start_x_m(), 0);
  EXPECT_EQ(two->start_y_m(), 0);

  StatusOr<StepReader> one = StepReader::Open(WriteTempFile("t,dx,dy\n4,1,0\n", "one.csv"));
  ASSERT_TRUE(one.ok()) << one.status().ToString();
  EXPECT_EQ(one->start_time_s(), 3);
}

TEST(StepReaderTest, BothFormsGiveTheSameStepsForTheSameWalk) {
  SimulatorOptions options;
  options.minutes = 2;
  options.seed = 7;
  StatusOr<SimulatedWalk> walk = SimulateWalk(options);
  ASSERT_TRUE(walk.ok()) << walk.status().ToString();
  std::string positions = "t,x,y\n0,0,0\n";
  double x = 0;
  double y = 0;
  for (const StepRecord& s : walk->steps) {
    x += s.dx_m;
    y += s.dy_m;
    positions += fmt::format("{},{},{}\n", s.t_s, x, y);
  }
  StatusOr<std::vector<StepRecord>> from_deltas =
      ReadAllSteps(WriteTempFile(StepsCsv(*walk), "deltas.csv"));
  StatusOr<std::vector<StepRecord>> from_positions =
      ReadAllSteps(WriteTempFile(positions, "positions.csv"));
  ASSERT_TRUE(from_deltas.ok()) << from_deltas.status().ToString();
  ASSERT_TRUE(from_positions.ok()) << from_positions.status().ToString();
  ASSERT_EQ(from_deltas->size(), walk->steps.size());
  ASSERT_EQ(from_positions->size(), walk->steps.size());
  for (size_t i = 0; i < walk->steps.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ((*from_deltas)[i].t_s, (*from_positions)[i].t_s);
    EXPECT_EQ((*from_deltas)[i].line + 1, (*from_positions)[i].line);  // after the start row
    // Differences of cumulative sums lose a few ulps of the sum.
    EXPECT_NEAR((*from_deltas)[i].dx_m, (*from_positions)[i].dx_m, 1e-9);
    EXPECT_NEAR((*from_deltas)[i].dy_m, (*from_positions)[i].dy_m, 1e-9);
  }
}

TEST(StepReaderTest, AcceptsCrlfCommentsBlankLinesPaddingBomAndPlusSign) {
  const std::string path = WriteTempFile(
      "\xEF\xBB\xBF# recorded by hand\r\n\r\n  t , dx ,\tdy \r\n# a comment\r\n"
      "1, +0.5 ,-0.25\r\n   \r\n  # indented comment\r\n2,1e-1,.5\r\n");
  StatusOr<std::vector<StepRecord>> steps = ReadAllSteps(path);
  ASSERT_TRUE(steps.ok()) << steps.status().ToString();
  ASSERT_EQ(steps->size(), 2u);
  EXPECT_EQ((*steps)[0].t_s, 1);
  EXPECT_EQ((*steps)[0].dx_m, 0.5);
  EXPECT_EQ((*steps)[0].dy_m, -0.25);
  EXPECT_EQ((*steps)[0].line, 5);
  EXPECT_EQ((*steps)[1].dx_m, 0.1);
  EXPECT_EQ((*steps)[1].dy_m, 0.5);
  EXPECT_EQ((*steps)[1].line, 8);
}

// Regression: a step file caught while being written ends in a partial line,
// which was read as a step with a cut number (here 0.7 for 0.7312).
TEST(StepReaderTest, LastLineWithoutLineEndIsAnError) {
  const std::string kError =
      "the last line has no line end: the file may still be being written; a complete step file "
      "ends in a newline";
  const std::string path = WriteTempFile("t,dx,dy\n1,0.5,0\n2,0.5,0\n3,0.7");
  EXPECT_EQ(ReadError(path), path + ":4:6: " + kError);
  // The same whether the partial line is a row, the header, a comment or blank; CRLF too.
  const std::string header = WriteTempFile("t,dx,dy", "header.csv");
  EXPECT_EQ(ReadError(header), header + ":1:8: " + kError);
  const std::string comment = WriteTempFile("t,dx,dy\r\n1,0.5,0\r\n# more to co", "comment.csv");
  EXPECT_EQ(ReadError(comment), comment + ":3:13: " + kError);
  const std::string crlf = WriteTempFile("t,dx,dy\r\n1,0.5,0\r\n2,0.5,0\r", "crlf.csv");
  EXPECT_EQ(ReadError(crlf), crlf + ":3:8: " + kError);
  // Text held in memory follows the same rule.
  StatusOr<StepReader> text = StepReader::OpenText("mem.csv", "t,dx,dy\n1,0.5,0\n2,0.5,0\n3,0.7");
  ASSERT_TRUE(text.ok()) << text.status().ToString();
  StepRecord step;
  StatusOr<bool> more = text->Next(&step);
  ASSERT_TRUE(more.ok() && *more);
  more = text->Next(&step);
  ASSERT_TRUE(more.ok() && *more);
  more = text->Next(&step);
  ASSERT_FALSE(more.ok());
  EXPECT_EQ(more.status().message(), "mem.csv:4:6: " + kError);
}

TEST(StepReaderTest, UnterminatedLastLineIsReadWhenAllowed) {
  StepReaderOptions options;
  options.allow_unterminated_last_line = true;
  const std::string path = WriteTempFile("t,dx,dy\n1,0.5,0\n2,0.7,0");
  StatusOr<std::vector<StepRecord>> steps = ReadAllSteps(path, options);
  ASSERT_TRUE(steps.ok()) << steps.status().ToString();
  ASSERT_EQ(steps->size(), 2u);
  EXPECT_EQ((*steps)[1].dx_m, 0.7);
  EXPECT_EQ((*steps)[1].line, 3);
}

TEST(StepReaderTest, PipeWithoutFinalLineEndIsAnErrorToo) {
  const std::string fifo =
      ::testing::TempDir() + "/grove_step_reader_fifo_" + std::to_string(::getpid());
  std::filesystem::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::thread writer([&] {
    std::ofstream out(fifo, std::ios::binary);
    out << "t,dx,dy\n1,0.5,0\n2,0.5,0\n3,0.5,0\n4,0.7";  // a writer killed mid-line
  });
  const std::string message = ReadError(fifo);
  writer.join();
  std::filesystem::remove(fifo);
  EXPECT_EQ(message, fifo +
                         ":5:6: the last line has no line end: the file may still be being "
                         "written; a complete step file ends in a newline");
}

TEST(StepReaderTest, BundledWalkEndsWithALineEndAndReadsWithDefaultOptions) {
  const std::string walk = EmbeddedWalkSteps();
  ASSERT_FALSE(walk.empty());
  EXPECT_EQ(walk.back(), '\n');
  StatusOr<StepReader> reader = StepReader::OpenText(EmbeddedWalkName(), walk);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  StepRecord step;
  for (;;) {
    StatusOr<bool> more = reader->Next(&step);
    ASSERT_TRUE(more.ok()) << more.status().ToString();
    if (!*more) break;
  }
  EXPECT_GT(reader->steps_read(), 100);
}

TEST(StepReaderTest, NonNumberReportsFileLineAndColumnOfTheField) {
  std::string content = "t,dx,dy\n";
  for (int i = 1; i <= 12; ++i) content += fmt::format("{},0.5,0\n", i);
  content += "12.25,abc,0\n";  // line 14, dx starts in column 7
  const std::string path = WriteTempFile(content);
  EXPECT_EQ(ReadError(path), path + ":14:7: dx: \"abc\" is not a number");
}

TEST(StepReaderTest, TrailingGarbageEmptyFieldsAndHexAreNotNumbers) {
  const std::string garbage = WriteTempFile("t,dx,dy\n1,0.5m,0\n", "garbage.csv");
  EXPECT_EQ(ReadError(garbage), garbage + ":2:3: dx: \"0.5m\" is not a number");
  const std::string empty = WriteTempFile("t,dx,dy\n1,0, \n", "empty.csv");
  EXPECT_EQ(ReadError(empty), empty + ":2:5: dy: \"\" is not a number");
  const std::string hex = WriteTempFile("t,dx,dy\n1,0x1p3,0\n", "hex.csv");
  EXPECT_EQ(ReadError(hex), hex + ":2:3: dx: \"0x1p3\" is not a number");
  const std::string signs = WriteTempFile("t,dx,dy\n1,+-1,0\n", "signs.csv");
  EXPECT_EQ(ReadError(signs), signs + ":2:3: dx: \"+-1\" is not a number");
}

TEST(StepReaderTest, TimeNotIncreasingReportsBothTimes) {
  std::string content = "t,dx,dy\n";
  // Lines 2 to 7.
  for (int i = 1; i <= 6; ++i) content += fmt::format("{},0.5,0\n", i * 0.5);
  content += "3.5,0.5,0\n3.2,0.5,0\n";  // lines 8 and 9
  const std::string path = WriteTempFile(content);
  EXPECT_EQ(ReadError(path),
            path +
                ":9:1: t = 3.2 is not after the previous time 3.5: times must be strictly "
                "increasing");
}

TEST(StepReaderTest, EqualTimesAreRejected) {
  const std::string path = WriteTempFile("t,x,y\n1,0,0\n 1,1,0\n");
  EXPECT_EQ(ReadError(path),
            path +
                ":3:2: t = 1 is not after the previous time 1: times must be strictly "
                "increasing");
}

TEST(StepReaderTest, UnknownHeaderIsRejected) {
  const std::string path = WriteTempFile("t,dx,dz\n1,0,0\n");
  EXPECT_EQ(ReadError(path),
            path + ":1:1: unknown header \"t,dx,dz\": expected \"t,dx,dy\" or \"t,x,y\"");
}

TEST(StepReaderTest, HeaderAfterCommentsIsReportedOnItsOwnLine) {
  const std::string path = WriteTempFile("# comment\n\nx,y\n");
  EXPECT_EQ(ReadError(path),
            path + ":3:1: unknown header \"x,y\": expected \"t,dx,dy\" or \"t,x,y\"");
}

TEST(StepReaderTest, NanAndInfinityAreRejected) {
  const std::string nan_path =
      WriteTempFile("t,dx,dy\n1,0,0\n2,0,0\n3,0,0\n4.5,0.7000,nan\n", "nan.csv");
  EXPECT_EQ(ReadError(nan_path), nan_path + ":5:12: dy = nan: must be finite");
  const std::string inf_path = WriteTempFile("t,x,y\n0,0,0\n1,-inf,0\n", "inf.csv");
  EXPECT_EQ(ReadError(inf_path), inf_path + ":3:3: x = -inf: must be finite");
  const std::string time_path = WriteTempFile("t,dx,dy\nInfinity,0,0\n", "time.csv");
  // The value as parsed, not the text.
  EXPECT_EQ(ReadError(time_path), time_path + ":2:1: t = inf: must be finite");
}

TEST(StepReaderTest, NumberOutOfRangeIsRejected) {
  const std::string path = WriteTempFile("t,dx,dy\n1,1e999,0\n");
  EXPECT_EQ(ReadError(path), path + ":2:3: dx: \"1e999\" is out of the range of a double");
}

TEST(StepReaderTest, StepLongerThanMaxStepIsRejected) {
  std::string content = "t,dx,dy\n";
  for (int i = 1; i <= 20; ++i) content += fmt::format("{},0.5,0\n", i);
  content += "21,12.4,0\n";  // line 22
  const std::string path = WriteTempFile(content);
  EXPECT_EQ(ReadError(path), path + ":22:1: step of 12.4 m is longer than max_step_m = 5");

  StepReaderOptions options;
  options.max_step_m = 20;
  EXPECT_TRUE(ReadAllSteps(path, options).ok());
}

TEST(StepReaderTest, PositionsFormChecksTheLengthOfTheDifference) {
  const std::string path = WriteTempFile("t,x,y\n0,100,100\n1,100.5,100\n2,103,104.5\n");
  EXPECT_EQ(ReadError(path), path + ":4:1: step of 5.14782 m is longer than max_step_m = 5");
}

TEST(StepReaderTest, WrongFieldCountIsRejected) {
  const std::string path = WriteTempFile("t,dx,dy\n1,0,0\n2,0,0,0\n");
  EXPECT_EQ(ReadError(path), path + ":3:1: expected 3 fields, found 4");
  const std::string short_path = WriteTempFile("t,dx,dy\n1,0\n", "short.csv");
  EXPECT_EQ(ReadError(short_path), short_path + ":2:1: expected 3 fields, found 2");
}

TEST(StepReaderTest, LineLongerThanTheLimitIsRejected) {
  const std::string path = WriteTempFile("t,dx,dy\n1,0," + std::string(5000, '0') + "\n");
  EXPECT_EQ(ReadError(path), path + ":2:1: line longer than 4096 bytes");
}

TEST(StepReaderTest, HugeLineWithoutNewlineIsRejectedAtTheLimit) {
  // 8 MiB on one line, far more than the reader's 64 KiB buffer: it must stop at the limit.
  const std::string path = WriteTempFile("t,dx,dy\n1,0,0\n" + std::string(size_t{8} << 20, '7'));
  EXPECT_EQ(ReadError(path), path + ":3:1: line longer than 4096 bytes");
  std::filesystem::remove(path);
}

TEST(StepReaderTest, LineExactlyAtTheLimitIsAccepted) {
  StepReaderOptions options;
  options.max_line_bytes = 64;
  std::string row = "1,0,0";
  row += std::string(64 - row.size(), ' ');  // 64 bytes, then "\r\n"
  const std::string path = WriteTempFile("t,dx,dy\r\n" + row + "\r\n", "exact.csv");
  StatusOr<std::vector<StepRecord>> steps = ReadAllSteps(path, options);
  ASSERT_TRUE(steps.ok()) << steps.status().ToString();
  EXPECT_EQ(steps->size(), 1u);

  const std::string longer = WriteTempFile("t,dx,dy\r\n" + row + " \r\n", "longer.csv");
  EXPECT_EQ(ReadError(longer, options), longer + ":2:1: line longer than 64 bytes");
}

TEST(StepReaderTest, EmptyFileIsRejected) {
  const std::string path = WriteTempFile("");
  EXPECT_EQ(ReadError(path), path + ": empty file: expected a header \"t,dx,dy\" or \"t,x,y\"");
  const std::string comments = WriteTempFile("# nothing\n\n", "comments.csv");
  EXPECT_EQ(ReadError(comments),
            comments + ": empty file: expected a header \"t,dx,dy\" or \"t,x,y\"");
}

TEST(StepReaderTest, HeaderOnlyHasNoSteps) {
  const std::string path = WriteTempFile("t,dx,dy\n# no data\n");
  EXPECT_EQ(ReadError(path), path + ": no steps after the header");

  StatusOr<StepReader> reader = StepReader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  StepRecord step;
  StatusOr<bool> more = reader->Next(&step);
  ASSERT_FALSE(more.ok());
  EXPECT_EQ(more.status().message(), path + ": no steps after the header");
  EXPECT_EQ(reader->steps_read(), 0);
}

TEST(StepReaderTest, PositionsFormWithOneRowHasNoSteps) {
  const std::string path = WriteTempFile("t,x,y\n1,2,3\n");
  EXPECT_EQ(ReadError(path),
            path + ": no steps after the header (a t,x,y file needs two rows for one step)");
}

TEST(StepReaderTest, MissingFileIsNotFound) {
  const std::string path = ::testing::TempDir() + "/grove_step_reader_no_such_file.csv";
  StatusOr<std::vector<StepRecord>> steps = ReadAllSteps(path);
  ASSERT_FALSE(steps.ok());
  EXPECT_EQ(steps.status().code(), StatusCode::kNotFound);
  EXPECT_EQ(steps.status().message(),
            path + ": cannot open for reading: No such file or directory");
}

// True when `text` is printable ASCII only: no control byte, escape sequence or NUL that a
// terminal would act on.
bool Printable(std::string_view text) {
  for (char c : text) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) return false;
  }
  return true;
}

// Regression: the unknown-header message echoed the whole header line,
// raw: up to 4 KB, terminal escape sequences and NULs included.
TEST(StepReaderTest, UnknownHeaderIsEscapedAndCut) {
  const std::string header =
      std::string("t,\x1b[2J\x1b]0;owned\x07\0,dz", 20) + std::string(4000, 'y');
  const std::string path = WriteTempFile(header + "\n1,0,0\n");
  const std::string message = ReadError(path);
  EXPECT_TRUE(Printable(message)) << message;
  EXPECT_TRUE(
      message.starts_with(path + ":1:1: unknown header \"t,\\x1b[2J\\x1b]0;owned\\x07\\x00,dz"))
      << message;
  EXPECT_NE(message.find("yyy...\": expected \"t,dx,dy\" or \"t,x,y\""), std::string::npos)
      << message;
  EXPECT_LT(message.size(), path.size() + 200) << message;
}

TEST(StepReaderTest, BadFieldWithControlBytesIsEscaped) {
  const std::string path = WriteTempFile(std::string("t,dx,dy\n1,\x1b[31m\r\0x,0\n", 21));
  EXPECT_EQ(ReadError(path), path + ":2:3: dx: \"\\x1b[31m\\x0d\\x00x\" is not a number");
}

TEST(StepReaderTest, InvalidOptionsAreRejected) {
  const std::string path = WriteTempFile("t,dx,dy\n1,0,0\n");
  StepReaderOptions options;
  options.max_step_m = 0;
  StatusOr<StepReader> reader = StepReader::Open(path, options);
  ASSERT_FALSE(reader.ok());
  EXPECT_EQ(reader.status().message(), "max_step_m = 0: must be > 0 and finite");
  options = {};
  options.max_line_bytes = 3;
  reader = StepReader::Open(path, options);
  ASSERT_FALSE(reader.ok());
  EXPECT_EQ(reader.status().message(), "max_line_bytes = 3: must be in [16, 67108864]");
}

TEST(StepReaderTest, ErrorRepeatsOnEveryLaterCall) {
  const std::string path = WriteTempFile("t,dx,dy\n1,0,0\n2,0,0\n3,x,0\n4,0,0\n");
  StatusOr<StepReader> reader = StepReader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  StepRecord step;
  ASSERT_TRUE(*reader->Next(&step));
  ASSERT_TRUE(*reader->Next(&step));
  StatusOr<bool> first = reader->Next(&step);
  ASSERT_FALSE(first.ok());
  EXPECT_EQ(first.status().message(), path + ":4:3: dx: \"x\" is not a number");
  StatusOr<bool> again = reader->Next(&step);
  ASSERT_FALSE(again.ok());
  EXPECT_EQ(again.status().message(), first.status().message());
  EXPECT_EQ(reader->steps_read(), 2);
}

TEST(StepReaderTest, MovedReaderContinuesWhereItWas) {
  const std::string path = WriteTempFile("t,dx,dy\n1,1,0\n2,2,0\n3,3,0\n");
  StatusOr<StepReader> opened = StepReader::Open(path);
  ASSERT_TRUE(opened.ok()) << opened.status().ToString();
  StepRecord step;
  ASSERT_TRUE(*opened->Next(&step));
  StepReader moved = std::move(*opened);
  ASSERT_TRUE(*moved.Next(&step));
  EXPECT_EQ(step.dx_m, 2);
  ASSERT_TRUE(*moved.Next(&step));
  EXPECT_EQ(step.dx_m, 3);
  EXPECT_FALSE(*moved.Next(&step));
  EXPECT_EQ(moved.steps_read(), 3);
}

TEST(StepReaderTest, StreamsALargeFileRecordByRecord) {
  constexpr int kRows = 200000;
  const std::filesystem::path path = std::filesystem::path(WriteTempFile(""));
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << "t,x,y\n";
    for (int i = 0; i <= kRows; ++i) {
      // A walk along x with a y zigzag; positions are exact in binary.
      out << fmt::format("{},{},{}\n", i * 0.5, i * 0.5, (i % 2) * 0.25);
    }
  }
  StatusOr<StepReader> reader = StepReader::Open(path.string());
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  StepRecord step;
  int64_t count = 0;
  double sum_dx = 0;
  for (;;) {
    StatusOr<bool> more = reader->Next(&step);
    ASSERT_TRUE(more.ok()) << more.status().ToString();
    if (!*more) break;
    ++count;
    ASSERT_EQ(step.t_s, count * 0.5);
    ASSERT_EQ(step.dx_m, 0.5);
    ASSERT_EQ(step.dy_m, count % 2 == 1 ? 0.25 : -0.25);
    ASSERT_EQ(step.line, count + 2);
    sum_dx += step.dx_m;
  }
  EXPECT_EQ(count, kRows);
  EXPECT_EQ(reader->steps_read(), kRows);
  EXPECT_EQ(sum_dx, kRows * 0.5);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace grove::tools

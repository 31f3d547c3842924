#include "tools/run/progress_reporter.h"

#include <gtest/gtest.h>
#include <stdio.h>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

namespace grove::tools {
namespace {

// An in-memory FILE* and a clock the test moves by hand.
class ProgressReporterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    out_ = open_memstream(&buffer_, &size_);
    ASSERT_NE(out_, nullptr);
  }
  void TearDown() override {
    std::fclose(out_);
    std::free(buffer_);
  }
  std::string Output() {
    std::fflush(out_);
    return std::string(buffer_, size_);
  }
  std::vector<std::string> Lines() {
    std::vector<std::string> lines;
    std::string text = Output();
    size_t start = 0;
    for (size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1) {
      lines.push_back(text.substr(start, end - start));
    }
    return lines;
  }
  ProgressReporter Make(int64_t total, int64_t particles, bool terminal) {
    return ProgressReporter(total, particles, out_, terminal, [this] { return now_s_; });
  }

  std::FILE* out_ = nullptr;
  char* buffer_ = nullptr;
  size_t size_ = 0;
  double now_s_ = 0.0;
};

TEST(FormatRateTest, UsesSiSuffixesWithTwoSignificantDigitsBelowTen) {
  EXPECT_EQ(FormatRate(0.0), "0");
  EXPECT_EQ(FormatRate(950.0), "950");
  EXPECT_EQ(FormatRate(999.7), "1.0k");
  EXPECT_EQ(FormatRate(999.7e3), "1.0M");
  EXPECT_EQ(FormatRate(12345.0), "12k");
  EXPECT_EQ(FormatRate(6.8e6), "6.8M");
  EXPECT_EQ(FormatRate(9.96e6), "10M");
  EXPECT_EQ(FormatRate(2.5e8), "250M");
  EXPECT_EQ(FormatRate(1.2e9), "1.2G");
  EXPECT_EQ(FormatRate(-1.0), "?");
}

TEST(FormatClockTest, PrintsMinutesSecondsAndHoursPastAnHour) {
  EXPECT_EQ(FormatClock(3.0), "0:03");
  EXPECT_EQ(FormatClock(754.0), "12:34");
  EXPECT_EQ(FormatClock(3723.0), "1:02:03");
  EXPECT_EQ(FormatClock(-1.0), "--:--");
}

TEST(FormatDurationTest, PrintsSecondsMinutesAndHours) {
  EXPECT_EQ(FormatDuration(12.4), "12 s");
  EXPECT_EQ(FormatDuration(200.0), "3 min 20 s");
  EXPECT_EQ(FormatDuration(3720.0), "1 h 02 min");
}

TEST_F(ProgressReporterTest, PlainOutputPrintsOneLinePerTenthWithCountsRateAndEta) {
  ProgressReporter reporter = Make(1000, 1000, /*terminal=*/false);
  for (int i = 1; i < 1000; ++i) {
    now_s_ = i * 0.001;
    reporter.Update(i);
  }
  std::vector<std::string> lines = Lines();
  ASSERT_EQ(lines.size(), 9u) << Output();
  // 100 steps in 0.1 s of 1000 particles: 1e6 particle-steps/s; 900 steps left at 1000 steps/s.
  EXPECT_EQ(lines[0], "step 100/1000 (10%) 1.0M particle-steps/s, ETA 1 s");
  EXPECT_EQ(lines[8].substr(0, 20), "step 900/1000 (90%) ");
  EXPECT_EQ(Output().find('\r'), std::string::npos);
}

TEST_F(ProgressReporterTest, PlainOutputPrintsAfterFiveSecondsWithoutANewTenth) {
  ProgressReporter reporter = Make(1000, 10, /*terminal=*/false);
  now_s_ = 1.0;
  reporter.Update(1);
  now_s_ = 4.9;
  reporter.Update(2);
  EXPECT_EQ(Output(), "");
  now_s_ = 5.0;
  reporter.Update(3);
  now_s_ = 9.0;
  reporter.Update(4);
  std::vector<std::string> lines = Lines();
  ASSERT_EQ(lines.size(), 1u) << Output();
  EXPECT_EQ(lines[0].substr(0, 18), "step 3/1000 (0%) 6") << lines[0];
  now_s_ = 10.0;
  reporter.Update(5);
  EXPECT_EQ(Lines().size(), 2u);
}

TEST_F(ProgressReporterTest, TerminalRedrawsOneLineWithCarriageReturnAtMostTenTimesPerSecond) {
  ProgressReporter reporter = Make(1000, 100, /*terminal=*/true);
  for (int i = 1; i <= 100; ++i) {
    now_s_ = i * 0.01;
    reporter.Update(i);
  }
  std::string text = Output();
  int redraws = static_cast<int>(std::count(text.begin(), text.end(), '\r'));
  EXPECT_GE(redraws, 9);
  EXPECT_LE(redraws, 11);
  EXPECT_EQ(text.find('\n'), std::string::npos);
  EXPECT_EQ(text[0], '\r');
}

TEST_F(ProgressReporterTest, TerminalLineShowsBarCountsRateElapsedAndEta) {
  ProgressReporter reporter = Make(100, 1000000, /*terminal=*/true);
  now_s_ = 2.0;
  reporter.Update(20);
  // 20% of a 30-character bar; 10 steps/s of 1e6 particles; 80 steps left take 8 s.
  EXPECT_EQ(Output(),
            "\r[######........................]  20% steps 20/100  10M p-steps/s  elapsed 0:02  "
            "ETA 0:08");
}

TEST_F(ProgressReporterTest, TerminalBlanksTheRestOfALongerPreviousLine) {
  ProgressReporter reporter = Make(100, 1000000, /*terminal=*/true);
  now_s_ = 3600.0;
  reporter.Update(1);  // slow start: "ETA 99:00:00"
  std::string first = Output();
  now_s_ = 3601.0;
  reporter.Update(99);  // "ETA 0:36"
  std::string second = Output().substr(first.size());
  ASSERT_EQ(second[0], '\r');
  EXPECT_NE(second.find("ETA 0:36"), std::string::npos) << second;
  EXPECT_EQ(second.size(), first.size());
  EXPECT_EQ(second.substr(second.size() - 3), "   ");
}

TEST_F(ProgressReporterTest, FinishPrintsTotalsAtOneHundredPercent) {
  ProgressReporter reporter = Make(50, 200, /*terminal=*/false);
  now_s_ = 10.0;
  reporter.Update(50);
  reporter.Finish();
  std::vector<std::string> lines = Lines();
  ASSERT_EQ(lines.size(), 1u) << Output();
  EXPECT_EQ(lines[0], "done: step 50/50 (100%), 10k particle-steps in 10 s, 1.0k particle-steps/s");
}

TEST_F(ProgressReporterTest, FinishOnTerminalOverwritesTheBarAndEndsTheLineOnce) {
  ProgressReporter reporter = Make(10, 5, /*terminal=*/true);
  now_s_ = 1.0;
  reporter.Update(5);
  size_t before = Output().size();
  now_s_ = 2.0;
  reporter.Update(10);
  now_s_ = 2.0;
  reporter.Finish();
  std::string text = Output();
  size_t done = text.rfind("\rdone: step 10/10 (100%)");
  ASSERT_NE(done, std::string::npos) << text;
  EXPECT_GE(done, before);
  EXPECT_EQ(text.back(), '\n');
  reporter.Finish();
  reporter.Update(3);
  EXPECT_EQ(Output(), text);
}

TEST_F(ProgressReporterTest, ZeroStepsFinishesAtOneHundredPercent) {
  ProgressReporter reporter = Make(0, 10, /*terminal=*/false);
  reporter.Update(0);
  reporter.Finish();
  std::vector<std::string> lines = Lines();
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].substr(0, 23), "done: step 0/0 (100%), ") << lines[0];
}

TEST_F(ProgressReporterTest, StepsBeyondTheTotalAreClamped) {
  ProgressReporter reporter = Make(10, 1, /*terminal=*/false);
  now_s_ = 1.0;
  reporter.Update(25);
  reporter.Finish();
  EXPECT_EQ(Lines().back().substr(0, 25), "done: step 10/10 (100%), ");
}

}  // namespace
}  // namespace grove::tools

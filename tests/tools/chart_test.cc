#include "tools/report/chart.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <pthread.h>
#include <signal.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tests/tools/decoded_png.h"

namespace grove::tools {
namespace {

namespace fs = std::filesystem;
using test_images::DecodedPng;
using test_images::Distance;
using test_images::kWhite;
using test_images::Rgb8;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
// The first three palette colours (ColorBrewer Dark2).
constexpr Rgb8 kColour0 = {0x1b, 0x9e, 0x77};
constexpr Rgb8 kColour1 = {0xd9, 0x5f, 0x02};
constexpr Rgb8 kColour2 = {0x75, 0x70, 0xb3};

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void WriteFile(const fs::path& path, const std::string& contents) {
  std::ofstream(path, std::ios::binary) << contents;
}

// The text of an SVG with the XML escapes gnuplot uses undone.
std::string SvgText(const fs::path& path) {
  std::string svg = ReadFile(path), out;
  for (size_t i = 0; i < svg.size(); ++i) {
    bool replaced = false;
    for (auto [entity, c] : {std::pair<const char*, char>{"&lt;", '<'},
                             {"&gt;", '>'},
                             {"&quot;", '"'},
                             {"&apos;", '\''},
                             {"&amp;", '&'}}) {
      if (svg.compare(i, std::strlen(entity), entity) == 0) {
        out += c;
        i += std::strlen(entity) - 1;
        replaced = true;
        break;
      }
    }
    if (!replaced) out += svg[i];
  }
  return out;
}

// Pixels within `tolerance` of `colour`.
int CountNear(const DecodedPng& png, const Rgb8& colour, int tolerance) {
  int n = 0;
  for (int y = 0; y < png.height(); ++y) {
    for (int x = 0; x < png.width(); ++x) n += Distance(png.At(x, y), colour) <= tolerance;
  }
  return n;
}

std::vector<std::string> FilesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// Every test gets empty output and TMPDIR directories; TearDown checks that WriteChart left
// nothing in TMPDIR, whatever the outcome.
class ChartTest : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = fs::path(::testing::TempDir()) /
            fmt::format("chart_test_{}_{}", ::getpid(),
                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(base_);
    out_ = base_ / "out";
    tmp_ = base_ / "tmp";
    fs::create_directories(out_);
    fs::create_directories(tmp_);
    if (const char* old = std::getenv("TMPDIR")) old_tmpdir_ = old;
    ::setenv("TMPDIR", tmp_.c_str(), 1);
  }
  void TearDown() override {
    EXPECT_TRUE(FilesIn(tmp_).empty()) << "left in TMPDIR: " << FilesIn(tmp_).front();
    if (old_tmpdir_) {
      ::setenv("TMPDIR", old_tmpdir_->c_str(), 1);
    } else {
      ::unsetenv("TMPDIR");
    }
    fs::remove_all(base_);
  }

  // An executable shell script standing in for gnuplot.
  std::string FakeGnuplot(const std::string& body) {
    fs::path path = base_ / "fake-gnuplot";
    WriteFile(path, "#!/bin/sh\n" + body);
    fs::permissions(path, fs::perms::owner_all);
    return path.string();
  }

  fs::path base_, out_, tmp_;
  std::optional<std::string> old_tmpdir_;
};

Chart EveryKind() {
  Chart chart;
  chart.title = "Every kind of element";
  chart.x_label = "walk time (s)";
  chart.y_label = "error (m)";
  chart.log_x = true;
  chart.log_y = true;
  std::vector<double> x;
  for (int i = 1; i <= 40; ++i) x.push_back(i * 0.1);
  ChartSeries line{.label = "line", .x = x, .style = ChartStyle::kLine};
  ChartSeries dashed{.label = "dashed", .x = x, .style = ChartStyle::kDashed};
  ChartSeries points{.label = "points", .x = x, .style = ChartStyle::kPoints};
  ChartSeries both{.label = "line and points", .x = x, .style = ChartStyle::kLinePoints};
  ChartBand band{.label = "95 % interval", .x = x};
  for (double v : x) {
    line.y.push_back(1 + v);
    dashed.y.push_back(2 + v * v);
    points.y.push_back(0.5 + v / 2);
    both.y.push_back(3);
    band.y_low.push_back(0.8 + v);
    band.y_high.push_back(1.3 + v);
  }
  chart.series = {line, dashed, points, both};
  chart.bands = {band};
  chart.boxes = {{"filter A", {1.0, 1.5, 2.0, 2.2, 3.0, 9.0}}, {"filter B", {2.0, 2.5, 2.6, 4.0}}};
  return chart;
}

TEST_F(ChartTest, EveryKindOfElementGivesPngAndSvg) {
  const fs::path png_path = out_ / "every.png", svg_path = out_ / "every.svg";
  Status s = WriteChart(EveryKind(), png_path, svg_path, {.width_px = 900, .height_px = 600});
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(FilesIn(out_), (std::vector<std::string>{"every.png", "every.svg"}));

  DecodedPng png(ReadFile(png_path));
  ASSERT_TRUE(png.ok());
  EXPECT_EQ(png.width(), 900);
  EXPECT_EQ(png.height(), 600);
  Rgb8 corner = png.At(0, 0);
  EXPECT_LE(Distance(corner, kWhite), 3);
  int drawn = 0;
  for (int y = 0; y < png.height(); ++y) {
    for (int x = 0; x < png.width(); ++x) drawn += Distance(png.At(x, y), corner) > 60;
  }
  EXPECT_GT(drawn, 5000);
  // The first three series in their palette colours (lines, points and legend samples).
  EXPECT_GT(CountNear(png, kColour0, 30), 300);
  EXPECT_GT(CountNear(png, kColour1, 30), 200);
  EXPECT_GT(CountNear(png, kColour2, 30), 200);

  std::string svg = SvgText(svg_path);
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_NE(svg.find("width=\"900\" height=\"600\""), std::string::npos);
  for (const char* text : {"Every kind of element", "walk time (s)", "error (m)", "line", "dashed",
                           "points", "line and points", "95 % interval", "filter A", "filter B"}) {
    EXPECT_NE(svg.find(std::string(">") + text + "<"), std::string::npos) << text;
  }
}

TEST_F(ChartTest, WithoutSvgPathWritesOnlyThePng) {
  Status s = WriteChart(EveryKind(), out_ / "only.png", "");
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(FilesIn(out_), std::vector<std::string>{"only.png"});
  DecodedPng png(ReadFile(out_ / "only.png"));
  ASSERT_TRUE(png.ok());
  EXPECT_EQ(png.width(), 1200);
  EXPECT_EQ(png.height(), 800);
}

TEST_F(ChartTest, SpecialCharactersAreShownLiterally) {
  // A backquoted command would run in a gnuplot double-quoted string if it were not escaped.
  const fs::path injected = out_ / "injected";
  const std::string first_line = fmt::format(
      "say \"hi\" C:\\dir\\ x_1^2 @var {{a}} 100% ; # σ µ `touch {}`", injected.string());
  Chart chart;
  chart.title = first_line + "\nsecond line";
  chart.x_label = "x \\\"";
  chart.y_label = "y_µs";
  chart.series.push_back({.label = "it's \"q\"", .x = {1, 2, 3}, .y = {1, 4, 9}});
  chart.boxes.push_back({.label = "box_σ", .values = {1, 2, 3}});
  Status s = WriteChart(chart, out_ / "text.png", out_ / "text.svg");
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_FALSE(fs::exists(injected));
  std::string svg = SvgText(out_ / "text.svg");
  for (const std::string& text :
       {first_line, std::string("second line"), std::string("x \\\""), std::string("y_µs"),
        std::string("it's \"q\""), std::string("box_σ")}) {
    EXPECT_NE(svg.find(">" + text + "<"), std::string::npos) << text;
  }
}

// The row holding the most pixels of `colour`, and the runs of such pixels along it that are
// longer than `min_run_px` (gaps of up to 2 px, from antialiasing, do not end a run).
std::vector<int> RunsOnBusiestRow(const DecodedPng& png, const Rgb8& colour, int min_run_px) {
  int best_row = 0, best_count = -1;
  for (int y = 0; y < png.height(); ++y) {
    int count = 0;
    for (int x = 0; x < png.width(); ++x) count += Distance(png.At(x, y), colour) <= 40;
    if (count > best_count) best_count = count, best_row = y;
  }
  std::vector<int> runs;
  int start = -1, last = -10;
  for (int x = 0; x <= png.width(); ++x) {
    bool hit = x < png.width() && Distance(png.At(x, best_row), colour) <= 40;
    if (hit && x - last > 3) start = x;  // a new run
    if (!hit && start >= 0 && x - last > 3) {
      if (last - start + 1 > min_run_px) runs.push_back(last - start + 1);
      start = -1;
    }
    if (hit) last = x;
  }
  if (start >= 0 && last - start + 1 > min_run_px) runs.push_back(last - start + 1);
  return runs;
}

TEST_F(ChartTest, UnusablePointsAreSkippedAndBreakTheLine) {
  Chart chart;
  chart.title = "gaps";
  chart.log_y = true;
  // A horizontal line with a hole in the middle: NaN, infinity and, on the log axis, 0 and -1.
  std::vector<double> x, y;
  for (int i = 0; i <= 20; ++i) {
    x.push_back(i);
    y.push_back(i >= 8 && i <= 12 ? std::vector<double>{kNan, kInf, 0, -1, kNan}[i - 8] : 5.0);
  }
  chart.series.push_back({.label = "holes", .x = x, .y = y, .style = ChartStyle::kLine});
  chart.series.push_back({.label = "nothing usable", .x = {1, 2}, .y = {kNan, -3}});
  // Something below the line and not crossing it, so that the y axis spans more than one value.
  chart.series.push_back({.label = "below", .x = {0, 20}, .y = {1, 2}, .style = ChartStyle::kLine});
  Status s = WriteChart(chart, out_ / "gaps.png", out_ / "gaps.svg");
  ASSERT_TRUE(s.ok()) << s.ToString();
  DecodedPng png(ReadFile(out_ / "gaps.png"));
  ASSERT_TRUE(png.ok());
  std::vector<int> runs = RunsOnBusiestRow(png, kColour0, 100);
  EXPECT_EQ(runs.size(), 2u) << "the line should be cut in two";
  // A series with no usable point keeps its legend entry.
  EXPECT_NE(SvgText(out_ / "gaps.svg").find(">nothing usable<"), std::string::npos);
}

// Pixels darker than mid-grey: the axes, tick labels and texts.
int DarkPixels(const DecodedPng& png) {
  int dark = 0;
  for (int y = 0; y < png.height(); ++y) {
    for (int x = 0; x < png.width(); ++x) dark += png.At(x, y).Luma() < 128;
  }
  return dark;
}

// A thread axis shows whole numbers only, and a y axis from zero draws a 20 % gain as 20 %.
TEST_F(ChartTest, IntegerXAndYFromZeroSetTheAxes) {
  Chart chart{.title = "threads", .series = {{.label = "s", .x = {1, 2}, .y = {3.0, 3.6}}}};
  const std::string plain = ChartScript(chart, {}, "a.png", "");
  EXPECT_EQ(plain.find("set xtics 1"), std::string::npos) << plain;
  EXPECT_EQ(plain.find("set yrange"), std::string::npos) << plain;
  chart.integer_x = true;
  chart.y_from_zero = true;
  const std::string script = ChartScript(chart, {}, "a.png", "");
  EXPECT_NE(script.find("set xtics 1\n"), std::string::npos) << script;
  EXPECT_NE(script.find("set xrange [0.5:2.5]\n"), std::string::npos) << script;
  EXPECT_NE(script.find("set yrange [0:*]\n"), std::string::npos) << script;
  // gnuplot takes the settings.
  Status s = WriteChart(chart, out_ / "threads.png", "");
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_TRUE(fs::exists(out_ / "threads.png"));
}

TEST_F(ChartTest, EmptyChartHasAxesAndTitle) {
  Chart linear{.title = "Nothing yet", .x_label = "x", .y_label = "y"};
  // Log axes, and a box whose only value is unusable: its category stays on the axis.
  Chart log = linear;
  log.log_x = log.log_y = true;
  log.boxes.push_back({.label = "no values", .values = {kNan, -1}});
  for (const Chart& chart : {linear, log}) {
    SCOPED_TRACE(chart.log_x ? "log axes" : "linear axes");
    Status s = WriteChart(chart, out_ / "empty.png", out_ / "empty.svg");
    ASSERT_TRUE(s.ok()) << s.ToString();
    DecodedPng png(ReadFile(out_ / "empty.png"));
    ASSERT_TRUE(png.ok());
    EXPECT_GT(DarkPixels(png), png.width() / 2 + png.height() / 2);  // at least the two axes
    std::string svg = SvgText(out_ / "empty.svg");
    EXPECT_NE(svg.find(">Nothing yet<"), std::string::npos);
    if (chart.log_x) {
      EXPECT_NE(svg.find(">no values<"), std::string::npos);
    }
  }
}

TEST_F(ChartTest, MissingOutputDirectoryIsAnIoErrorAndLeavesNothing) {
  const fs::path missing = out_ / "no_such_dir";
  Status s = WriteChart(EveryKind(), missing / "c.png", missing / "c.svg");
  EXPECT_EQ(s.code(), StatusCode::kIoError) << s.ToString();
  EXPECT_NE(s.message().find("no_such_dir"), std::string::npos) << s.message();
  EXPECT_FALSE(fs::exists(missing));
  // A missing SVG directory is found before the PNG is drawn.
  s = WriteChart(EveryKind(), out_ / "c.png", missing / "c.svg");
  EXPECT_EQ(s.code(), StatusCode::kIoError) << s.ToString();
  EXPECT_TRUE(FilesIn(out_).empty());
  // A file where the directory should be.
  WriteFile(out_ / "file", "x");
  s = WriteChart(EveryKind(), out_ / "file" / "c.png", "");
  EXPECT_EQ(s.code(), StatusCode::kIoError) << s.ToString();
  EXPECT_EQ(FilesIn(out_), std::vector<std::string>{"file"});
}

TEST_F(ChartTest, MissingGnuplotSaysWhichPackageToInstall) {
  for (const std::string& gnuplot :
       {(base_ / "no-such-dir" / "gnuplot").string(), std::string("grove-no-such-gnuplot")}) {
    Status s = WriteChart(EveryKind(), out_ / "c.png", out_ / "c.svg", {.gnuplot = gnuplot});
    EXPECT_EQ(s.code(), StatusCode::kNotFound) << s.ToString();
    EXPECT_NE(s.message().find("gnuplot not found"), std::string::npos) << s.message();
    EXPECT_NE(s.message().find("install Debian's gnuplot-nox"), std::string::npos) << s.message();
    EXPECT_TRUE(FilesIn(out_).empty());
  }
}

TEST_F(ChartTest, FailingGnuplotReportsTheStartOfItsErrorsAndKeepsEarlierOutputs) {
  WriteFile(out_ / "c.png", "earlier");
  std::string gnuplot = FakeGnuplot(
      "echo '   plot $series0 ...' >&2\necho '        ^' >&2\n"
      "echo '\"chart.gp\" line 30: boom' >&2\n"
      "i=0; while [ $i -lt 200 ]; do echo "
      "xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx >&2; i=$((i+1)); "
      "done\nexit 3\n");
  Status s = WriteChart(EveryKind(), out_ / "c.png", out_ / "c.svg", {.gnuplot = gnuplot});
  EXPECT_EQ(s.code(), StatusCode::kInternal) << s.ToString();
  EXPECT_NE(s.message().find("exit status 3"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("plot $series0 ... | \\x22chart.gp\\x22 line 30: boom"),
            std::string::npos)
      << s.message();
  EXPECT_LT(s.message().size(), 500u) << s.message();
  EXPECT_EQ(ReadFile(out_ / "c.png"), "earlier");
  EXPECT_EQ(FilesIn(out_), std::vector<std::string>{"c.png"});

  // Exit status 0 without an image is a failure too.
  s = WriteChart(EveryKind(), out_ / "c.png", "", {.gnuplot = FakeGnuplot("exit 0\n")});
  EXPECT_EQ(s.code(), StatusCode::kInternal) << s.ToString();
  EXPECT_EQ(ReadFile(out_ / "c.png"), "earlier");
}

TEST_F(ChartTest, InvalidInputIsRejectedNamingTheField) {
  Chart chart = EveryKind();
  chart.series[1].y.pop_back();
  Status s = WriteChart(chart, out_ / "c.png", "");
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("series[1] \"dashed\": x has 40 values, y has 39"), std::string::npos)
      << s.message();

  chart = EveryKind();
  chart.bands[0].y_high.clear();
  s = WriteChart(chart, out_ / "c.png", "");
  EXPECT_NE(s.message().find("bands[0]"), std::string::npos) << s.message();

  chart = EveryKind();
  chart.title = "bad \xff";
  s = WriteChart(chart, out_ / "c.png", "");
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("title"), std::string::npos) << s.message();

  s = WriteChart(EveryKind(), out_ / "c.png", "", {.width_px = 100});
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("100 x 800"), std::string::npos) << s.message();
  EXPECT_TRUE(FilesIn(out_).empty());
}

void IgnoreSignal(int) {}

TEST_F(ChartTest, InterruptingSignalsDoNotBreakIt) {
  // SIGALRM every millisecond without SA_RESTART: waitpid and writes see EINTR.
  struct sigaction action = {}, old_alarm;
  action.sa_handler = IgnoreSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;
  ASSERT_EQ(sigaction(SIGALRM, &action, &old_alarm), 0);
  itimerval timer = {{0, 1000}, {0, 1000}};
  ASSERT_EQ(setitimer(ITIMER_REAL, &timer, nullptr), 0);
  Status s = WriteChart(EveryKind(), out_ / "c.png", out_ / "c.svg");
  itimerval off = {};
  setitimer(ITIMER_REAL, &off, nullptr);
  sigaction(SIGALRM, &old_alarm, nullptr);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_TRUE(DecodedPng(ReadFile(out_ / "c.png")).ok());
}

TEST_F(ChartTest, GnuplotDoesNotInheritBlockedSignals) {
  sigset_t term, old_mask;
  sigemptyset(&term);
  sigaddset(&term, SIGTERM);
  ASSERT_EQ(pthread_sigmask(SIG_BLOCK, &term, &old_mask), 0);
  // With SIGTERM still blocked this would exit 0 without an image instead.
  Status s = WriteChart(EveryKind(), out_ / "c.png", "",
                        {.gnuplot = FakeGnuplot("kill -TERM $$\nexit 0\n")});
  pthread_sigmask(SIG_SETMASK, &old_mask, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kInternal) << s.ToString();
  EXPECT_NE(s.message().find("killed by signal 15"), std::string::npos) << s.message();
  EXPECT_TRUE(FilesIn(out_).empty());
}

}  // namespace
}  // namespace grove::tools

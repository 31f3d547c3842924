#include "tools/line_plot.h"

// Rooted at /usr/include: cairo is a private dependency of grove_tools.
#include <cairo/cairo.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/tools/decoded_png.h"

namespace grove::tools {
namespace {

using test_images::DecodedPng;
using test_images::Distance;
using test_images::ExpectColourNear;
using test_images::kWhite;
using test_images::Rgb8;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

Rgb8 ToRgb8(const PlotRgb& c) {
  return {static_cast<int>(std::lround(c.r * 255)), static_cast<int>(std::lround(c.g * 255)),
          static_cast<int>(std::lround(c.b * 255))};
}

// A data x midway between two neighbouring x ticks, so away from the vertical grid lines.
double BetweenXTicks(const PlotLayout& layout, size_t i) {
  EXPECT_GT(layout.x_ticks.size(), i + 1);
  return (layout.x_ticks[i] + layout.x_ticks[i + 1]) / 2;
}

LinePlot TwoHorizontalLines() {
  LinePlot plot;
  plot.title = "two lines";
  plot.x_label = "particles";
  plot.y_label = "time [ms]";
  plot.series.push_back({"low", {0.0, 10.0}, {1.0, 1.0}});
  plot.series.push_back({"high", {0.0, 10.0}, {3.0, 3.0}});
  return plot;
}

// Returns true when the step between consecutive ticks is 1, 2 or 5 x 10^k (up to rounding).
bool IsOneTwoFiveStep(double step) {
  double k = std::floor(std::log10(step) + 1e-9);
  double mantissa = step / std::pow(10.0, k);
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (std::abs(mantissa - m) < 1e-6) return true;
  }
  return false;
}

TEST(NiceTicksTest, ExactValuesForTypicalRanges) {
  EXPECT_EQ(NiceTicks(0.0, 1.0, 5), (std::vector<double>{0.0, 0.2, 0.4, 0.6, 0.8, 1.0}));
  EXPECT_EQ(NiceTicks(0.0, 97.0, 5), (std::vector<double>{0, 20, 40, 60, 80}));
  EXPECT_EQ(NiceTicks(-3.0, 7.0, 4), (std::vector<double>{-2, 0, 2, 4, 6}));
  EXPECT_EQ(NiceTicks(1200.0, 4800.0, 4), (std::vector<double>{2000, 3000, 4000}));
  EXPECT_EQ(NiceTicks(0.013, 0.031, 4), (std::vector<double>{0.015, 0.02, 0.025, 0.03}));
}

TEST(NiceTicksTest, DegenerateInputs) {
  EXPECT_EQ(NiceTicks(5.0, 5.0, 5), std::vector<double>{5.0});
  EXPECT_TRUE(NiceTicks(kNan, 1.0, 5).empty());
  EXPECT_TRUE(NiceTicks(0.0, kInf, 5).empty());
  EXPECT_EQ(NiceTicks(1.0, 0.0, 5), NiceTicks(0.0, 1.0, 5));
  EXPECT_EQ(NiceTicks(0.0, 1.0, 0), NiceTicks(0.0, 1.0, 1));
  // Zero is +0, never -0.
  for (double t : NiceTicks(-1.0, 1.0, 4)) {
    if (t == 0.0) {
      EXPECT_FALSE(std::signbit(t));
    }
  }
}

TEST(NiceTicksTest, RandomRangesGetOneTwoFiveStepsInsideTheRange) {
  const uint32_t seed = 20240611;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> exponent(-8.0, 12.0);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> target_dist(2, 12);
  for (int trial = 0; trial < 2000; ++trial) {
    double scale = std::pow(10.0, exponent(rng));
    double lo = unit(rng) * scale;
    double hi = lo + std::abs(unit(rng)) * scale + scale * 1e-3;
    int target = target_dist(rng);
    std::vector<double> ticks = NiceTicks(lo, hi, target);
    SCOPED_TRACE(testing::Message()
                 << "trial " << trial << " lo " << lo << " hi " << hi << " target " << target);
    ASSERT_GE(ticks.size(), 2u);
    // The chosen step is within a factor sqrt(5) or so of (hi - lo) / target.
    EXPECT_LE(static_cast<int>(ticks.size()), 3 * target + 1);
    EXPECT_GE(static_cast<int>(ticks.size()), target / 3);
    const double step = ticks[1] - ticks[0];
    ASSERT_TRUE(IsOneTwoFiveStep(step)) << step;
    for (size_t i = 0; i < ticks.size(); ++i) {
      EXPECT_GE(ticks[i], lo - step * 1e-6);
      EXPECT_LE(ticks[i], hi + step * 1e-6);
      // Multiples of the step.
      double q = ticks[i] / step;
      EXPECT_NEAR(q, std::round(q), 1e-6 * std::max(1.0, std::abs(q)));
      if (i > 0) {
        EXPECT_NEAR(ticks[i] - ticks[i - 1], step, step * 1e-6);
      }
    }
    // No multiple of the step inside the range is missing at either end.
    EXPECT_LT(ticks.front() - step, lo);
    EXPECT_GT(ticks.back() + step, hi);
  }
}

TEST(LogTicksTest, DecadesInsideTheRange) {
  EXPECT_EQ(LogTicks(1.0, 1e4, 8), (std::vector<double>{1, 10, 100, 1000, 10000}));
  EXPECT_EQ(LogTicks(0.5, 2000.0, 8), (std::vector<double>{1, 10, 100, 1000}));
  EXPECT_EQ(LogTicks(0.001, 0.1, 8), (std::vector<double>{0.001, 0.01, 0.1}));
}

TEST(LogTicksTest, ManyDecadesAreThinnedEvenly) {
  std::vector<double> ticks = LogTicks(1.0, 1e30, 6);
  ASSERT_GE(ticks.size(), 3u);
  EXPECT_LE(ticks.size(), 9u);
  const double stride = std::log10(ticks[1]) - std::log10(ticks[0]);
  EXPECT_GT(stride, 1.5);
  for (size_t i = 0; i < ticks.size(); ++i) {
    double k = std::log10(ticks[i]);
    EXPECT_NEAR(k, std::round(k), 1e-9);  // a decade
    if (i > 0) {
      EXPECT_NEAR(k - std::log10(ticks[i - 1]), stride, 1e-9);
    }
  }
}

TEST(LogTicksTest, NarrowRangesFallBackToOneTwoFiveThenNiceTicks) {
  EXPECT_EQ(LogTicks(15.0, 80.0, 5), (std::vector<double>{20, 50}));
  EXPECT_EQ(LogTicks(3.0, 30.0, 5), (std::vector<double>{5, 10, 20}));
  std::vector<double> narrow = LogTicks(61.0, 69.0, 4);
  ASSERT_GE(narrow.size(), 2u);
  for (double t : narrow) {
    EXPECT_GE(t, 61.0);
    EXPECT_LE(t, 69.0);
  }
  EXPECT_TRUE(LogTicks(0.0, 10.0, 5).empty());
  EXPECT_TRUE(LogTicks(-1.0, 10.0, 5).empty());
}

TEST(FormatTickLabelTest, LargeNumbersAreCompact) {
  EXPECT_EQ(FormatTickLabel(1000, 1000), "1k");
  EXPECT_EQ(FormatTickLabel(30000, 10000), "30k");
  EXPECT_EQ(FormatTickLabel(1500, 500), "1.5k");
  EXPECT_EQ(FormatTickLabel(1e6, 2e5), "1M");
  EXPECT_EQ(FormatTickLabel(2.5e6, 5e5), "2.5M");
  EXPECT_EQ(FormatTickLabel(4e9, 1e9), "4G");
  EXPECT_EQ(FormatTickLabel(1e12, 1e12), "1T");
  EXPECT_EQ(FormatTickLabel(-2000, 1000), "-2k");
  EXPECT_EQ(FormatTickLabel(500, 500), "500");
}

TEST(FormatTickLabelTest, OrdinaryNumbersHaveNoExponentAndNoNoise) {
  EXPECT_EQ(FormatTickLabel(0.0, 0.2), "0");
  EXPECT_EQ(FormatTickLabel(0.6000000000000001, 0.2), "0.6");
  EXPECT_EQ(FormatTickLabel(0.25, 0.05), "0.25");
  EXPECT_EQ(FormatTickLabel(7.0, 1.0), "7");
  EXPECT_EQ(FormatTickLabel(2.0, 0.5), "2");
  EXPECT_EQ(FormatTickLabel(0.001, 0.009), "0.001");
  EXPECT_EQ(FormatTickLabel(0.0001, 0.0001), "0.0001");
  EXPECT_EQ(FormatTickLabel(-0.5, 0.5), "-0.5");
  EXPECT_EQ(FormatTickLabel(1e-17, 0.1), "0");  // rounding noise around zero
  EXPECT_EQ(FormatTickLabel(999, 1), "999");
}

TEST(PlotLayoutTest, DataFitsInsideTheFrameWithYUp) {
  LinePlot plot = TwoHorizontalLines();
  PlotLayout layout = ComputePlotLayout(plot, 1200, 800);
  EXPECT_EQ(layout.width_px, 1200);
  EXPECT_EQ(layout.height_px, 800);
  EXPECT_GT(layout.area_left_px, 0.0);
  EXPECT_GT(layout.area_top_px, 0.0);
  EXPECT_LT(layout.area_bottom_px, 800.0);
  // The legend sits right of the frame, inside the image.
  EXPECT_GT(layout.legend_left_px, layout.area_right_px);
  EXPECT_LE(layout.legend_left_px + layout.legend_width_px, 1200.0);
  ASSERT_EQ(layout.legend_labels, (std::vector<std::string>{"low", "high"}));
  for (const PlotSeries& s : plot.series) {
    for (size_t i = 0; i < s.x.size(); ++i) {
      EXPECT_GT(layout.XPx(s.x[i]), layout.area_left_px);
      EXPECT_LT(layout.XPx(s.x[i]), layout.area_right_px);
      EXPECT_GT(layout.YPx(s.y[i]), layout.area_top_px);
      EXPECT_LT(layout.YPx(s.y[i]), layout.area_bottom_px);
    }
  }
  EXPECT_LT(layout.YPx(3.0), layout.YPx(1.0));
  EXPECT_LT(layout.XPx(0.0), layout.XPx(10.0));
  ASSERT_EQ(layout.x_ticks.size(), layout.x_tick_labels.size());
  ASSERT_EQ(layout.y_ticks.size(), layout.y_tick_labels.size());
  EXPECT_GE(layout.x_ticks.size(), 3u);
  EXPECT_GE(layout.y_ticks.size(), 3u);
}

TEST(PlotLayoutTest, LogAxesPutDecadesEquallyApart) {
  LinePlot plot;
  plot.log_x = plot.log_y = true;
  // The non-positive points are skipped and do not disturb the range.
  plot.series.push_back({"a", {0.0, 10.0, 100.0, 1000.0, 1e4}, {5.0, 1.0, -1.0, 100.0, 1e3}});
  PlotLayout layout = ComputePlotLayout(plot, 1200, 800);
  const double decade_x = layout.XPx(100.0) - layout.XPx(10.0);
  EXPECT_GT(decade_x, 50.0);
  EXPECT_NEAR(layout.XPx(1000.0) - layout.XPx(100.0), decade_x, 1e-6);
  const double decade_y = layout.YPx(10.0) - layout.YPx(100.0);
  EXPECT_GT(decade_y, 50.0);
  EXPECT_NEAR(layout.YPx(100.0) - layout.YPx(1000.0), decade_y, 1e-6);
  // x data 10..1e4 and y data 1..1e3 fill the area up to the small padding.
  EXPECT_NEAR(layout.x_min, 1.0, 0.2);
  EXPECT_NEAR(layout.x_max, 4.0, 0.2);
  EXPECT_NEAR(layout.y_min, 0.0, 0.2);
  EXPECT_NEAR(layout.y_max, 3.0, 0.2);
  EXPECT_EQ(layout.x_ticks, (std::vector<double>{10, 100, 1000, 10000}));
  EXPECT_EQ(layout.x_tick_labels, (std::vector<std::string>{"10", "100", "1k", "10k"}));
  EXPECT_EQ(layout.y_ticks, (std::vector<double>{1, 10, 100, 1000}));
}

TEST(PlotLayoutTest, EqualYValuesGetAPaddedRange) {
  LinePlot plot;
  plot.series.push_back({"flat", {1.0, 2.0, 3.0}, {5.0, 5.0, 5.0}});
  PlotLayout layout = ComputePlotLayout(plot, 800, 600);
  EXPECT_LT(layout.y_min, 5.0);
  EXPECT_GT(layout.y_max, 5.0);
  EXPECT_NEAR(layout.YPx(5.0), (layout.area_top_px + layout.area_bottom_px) / 2, 1e-6);
  EXPECT_GE(layout.y_ticks.size(), 2u);

  // One point: both axes padded around it.
  LinePlot one;
  one.series.push_back({"one", {0.0}, {0.0}});
  PlotLayout single = ComputePlotLayout(one, 800, 600);
  EXPECT_LT(single.x_min, 0.0);
  EXPECT_GT(single.x_max, 0.0);
  EXPECT_LT(single.y_min, 0.0);
  EXPECT_GT(single.y_max, 0.0);
}

TEST(PlotLayoutTest, NanAndInfinitePointsDoNotWidenTheRange) {
  LinePlot clean;
  clean.series.push_back({"s", {0.0, 1.0, 3.0}, {2.0, 4.0, 3.0}});
  LinePlot noisy;
  noisy.series.push_back(
      {"s", {0.0, 1.0, kNan, 2.0, 3.0, kInf}, {2.0, 4.0, 100.0, -kInf, 3.0, 0.0}});
  PlotLayout a = ComputePlotLayout(clean, 1000, 700);
  PlotLayout b = ComputePlotLayout(noisy, 1000, 700);
  EXPECT_EQ(a.x_min, b.x_min);
  EXPECT_EQ(a.x_max, b.x_max);
  EXPECT_EQ(a.y_min, b.y_min);
  EXPECT_EQ(a.y_max, b.y_max);
  EXPECT_TRUE(std::isfinite(b.y_max));
}

TEST(PlotLayoutTest, EmptyPlotHasUnitRangesAndNoLegend) {
  LinePlot plot;
  PlotLayout layout = ComputePlotLayout(plot, 800, 600);
  EXPECT_EQ(layout.x_min, 0.0);
  EXPECT_EQ(layout.x_max, 1.0);
  EXPECT_EQ(layout.legend_width_px, 0.0);
  EXPECT_TRUE(layout.legend_labels.empty());
  plot.log_x = true;
  layout = ComputePlotLayout(plot, 800, 600);
  EXPECT_NEAR(layout.XPx(10.0), layout.area_right_px, 1e-9);
  EXPECT_NEAR(layout.XPx(1.0), layout.area_left_px, 1e-9);
}

TEST(PlotLayoutTest, LargeValuesGetCompactLabels) {
  LinePlot plot;
  plot.series.push_back({"s", {0.0, 2e6}, {0.0, 3e4}});
  PlotLayout layout = ComputePlotLayout(plot, 1200, 800);
  bool has_mega = false;
  for (const std::string& label : layout.x_tick_labels) {
    EXPECT_EQ(label.find('e'), std::string::npos) << label;
    if (label.back() == 'M') has_mega = true;
  }
  EXPECT_TRUE(has_mega);
  bool has_kilo = false;
  for (const std::string& label : layout.y_tick_labels) {
    if (label.back() == 'k') has_kilo = true;
  }
  EXPECT_TRUE(has_kilo);
}

TEST(PlotLayoutTest, LongLegendLabelsAreShortenedAtCodePointBoundaries) {
  LinePlot plot;
  std::string label;
  for (int i = 0; i < 300; ++i) label += "\xC3\xA9";  // é, two bytes
  plot.series.push_back({label, {0.0, 1.0}, {0.0, 1.0}});
  PlotLayout layout = ComputePlotLayout(plot, 1200, 800);
  ASSERT_EQ(layout.legend_labels.size(), 1u);
  const std::string& shown = layout.legend_labels[0];
  const std::string ellipsis = "\xE2\x80\xA6";
  ASSERT_GT(shown.size(), ellipsis.size());
  EXPECT_LT(shown.size(), label.size());
  EXPECT_EQ(shown.substr(shown.size() - ellipsis.size()), ellipsis);
  EXPECT_EQ(shown.substr(0, shown.size() - ellipsis.size()),
            label.substr(0, shown.size() - ellipsis.size()));
  EXPECT_EQ((shown.size() - ellipsis.size()) % 2, 0u);
  EXPECT_LE(layout.legend_left_px + layout.legend_width_px, 1200.0);
}

TEST(SeriesColourTest, EightDistinctColoursCycled) {
  for (size_t i = 0; i < 8; ++i) {
    for (size_t j = i + 1; j < 8; ++j) {
      EXPECT_GT(Distance(ToRgb8(SeriesColour(i)), ToRgb8(SeriesColour(j))), 60) << i << " " << j;
    }
    EXPECT_LT(Distance(ToRgb8(SeriesColour(i)), kWhite), 3 * 255 - 10);
    EXPECT_GT(Distance(ToRgb8(SeriesColour(i)), kWhite), 150) << "too light on white: " << i;
  }
  // ColorBrewer Dark2 in its published order.
  EXPECT_EQ(Distance(ToRgb8(SeriesColour(0)), Rgb8{0x1b, 0x9e, 0x77}), 0);
  EXPECT_EQ(Distance(ToRgb8(SeriesColour(1)), Rgb8{0xd9, 0x5f, 0x02}), 0);
  EXPECT_EQ(Distance(ToRgb8(SeriesColour(7)), Rgb8{0x66, 0x66, 0x66}), 0);
  EXPECT_EQ(Distance(ToRgb8(SeriesColour(8)), ToRgb8(SeriesColour(0))), 0);
  EXPECT_EQ(Distance(ToRgb8(SeriesColour(11)), ToRgb8(SeriesColour(3))), 0);
}

TEST(RenderLinePlotPngTest, HasPngSignatureAndRequestedSize) {
  StatusOr<std::string> png = RenderLinePlotPng(TwoHorizontalLines(), 640, 480);
  ASSERT_TRUE(png.ok()) << png.status().ToString();
  ASSERT_GE(png->size(), 8u);
  EXPECT_EQ(png->substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  DecodedPng decoded(*png);
  ASSERT_TRUE(decoded.ok());
  EXPECT_EQ(decoded.width(), 640);
  EXPECT_EQ(decoded.height(), 480);

  StatusOr<std::string> defaults = RenderLinePlotPng(TwoHorizontalLines());
  ASSERT_TRUE(defaults.ok());
  DecodedPng big(*defaults);
  ASSERT_TRUE(big.ok());
  EXPECT_EQ(big.width(), 1200);
  EXPECT_EQ(big.height(), 800);
}

TEST(RenderLinePlotPngTest, SeriesLinesAndLegendSamplesHaveTheSeriesColours) {
  LinePlot plot = TwoHorizontalLines();
  PlotLayout layout = ComputePlotLayout(plot, 1200, 800);
  StatusOr<std::string> png = RenderLinePlotPng(plot, 1200, 800);
  ASSERT_TRUE(png.ok()) << png.status().ToString();
  DecodedPng decoded(*png);
  ASSERT_TRUE(decoded.ok());
  const Rgb8 low = ToRgb8(SeriesColour(0));
  const Rgb8 high = ToRgb8(SeriesColour(1));
  for (double x : {2.5, 5.0, 7.5}) {
    ExpectColourNear(decoded.NearestAlongColumn(layout.XPx(x), layout.YPx(1.0), low), low, 2);
    ExpectColourNear(decoded.NearestAlongColumn(layout.XPx(x), layout.YPx(3.0), high), high, 2);
  }
  // Between the lines and the grid lines, the background is white.
  double gap_y = kNan;
  for (size_t i = 0; i + 1 < layout.y_ticks.size(); ++i) {
    if (layout.y_ticks[i] >= 1.5 && layout.y_ticks[i + 1] <= 2.5) {
      gap_y = (layout.y_ticks[i] + layout.y_ticks[i + 1]) / 2;
      break;
    }
  }
  ASSERT_TRUE(std::isfinite(gap_y));
  ExpectColourNear(decoded.At(layout.XPx(BetweenXTicks(layout, 1)), layout.YPx(gap_y)), kWhite, 0);
  ExpectColourNear(decoded.At(layout.LegendSampleXPx(), layout.LegendSampleYPx(0)), low, 2);
  ExpectColourNear(decoded.At(layout.LegendSampleXPx(), layout.LegendSampleYPx(1)), high, 2);
}

// Counts the pixel columns along the horizontal line y = `y` from x = `x0` to `x1` that show
// `colour` (on) and those that clearly do not (off).
std::pair<int, int> OnOffAlongLine(const DecodedPng& image, const PlotLayout& layout, double x0,
                                   double x1, double y, const Rgb8& colour) {
  int on = 0, off = 0;
  for (double px = layout.XPx(x0); px < layout.XPx(x1); px += 1.0) {
    int d = Distance(image.NearestAlongColumn(px, layout.YPx(y), colour), colour);
    if (d <= 6) ++on;
    if (d >= 60) ++off;
  }
  return {on, off};
}

TEST(RenderLinePlotPngTest, DashedSeriesHasGapsAndSolidSeriesHasNone) {
  LinePlot plot = TwoHorizontalLines();
  plot.series[1].dashed = true;
  PlotLayout layout = ComputePlotLayout(plot, 1200, 800);
  StatusOr<std::string> png = RenderLinePlotPng(plot, 1200, 800);
  ASSERT_TRUE(png.ok());
  DecodedPng decoded(*png);
  ASSERT_TRUE(decoded.ok());
  auto [solid_on, solid_off] =
      OnOffAlongLine(decoded, layout, 1.0, 9.0, 1.0, ToRgb8(SeriesColour(0)));
  EXPECT_GT(solid_on, 500);
  EXPECT_EQ(solid_off, 0);
  auto [dashed_on, dashed_off] =
      OnOffAlongLine(decoded, layout, 1.0, 9.0, 3.0, ToRgb8(SeriesColour(1)));
  EXPECT_GT(dashed_on, 100);
  EXPECT_GT(dashed_off, 100);
}

TEST(RenderLinePlotPngTest, SinglePointSeriesShowsAMarker) {
  LinePlot plot;
  plot.series.push_back({"a", {0.0, 10.0}, {0.0, 10.0}});
  plot.series.push_back({"lonely", {4.0}, {7.0}});
  PlotLayout layout = ComputePlotLayout(plot, 800, 600);
  StatusOr<std::string> png = RenderLinePlotPng(plot, 800, 600);
  ASSERT_TRUE(png.ok());
  DecodedPng decoded(*png);
  ASSERT_TRUE(decoded.ok());
  ExpectColourNear(decoded.At(layout.XPx(4.0), layout.YPx(7.0)), ToRgb8(SeriesColour(1)), 2);
}

TEST(RenderLinePlotPngTest, SparseSeriesHaveMarkersAndDenseSeriesDoNot) {
  LinePlot plot;
  plot.series.push_back({"sparse", {0.0, 5.0, 10.0}, {1.0, 1.0, 1.0}});
  PlotSeries dense{"dense", {}, {}};
  for (int i = 0; i <= 2000; ++i) {
    dense.x.push_back(i / 200.0);
    dense.y.push_back(3.0);
  }
  plot.series.push_back(dense);
  PlotLayout layout = ComputePlotLayout(plot, 1200, 800);
  StatusOr<std::string> png = RenderLinePlotPng(plot, 1200, 800);
  ASSERT_TRUE(png.ok());
  DecodedPng decoded(*png);
  ASSERT_TRUE(decoded.ok());
  // Below the line but inside a marker's radius (1.5 line widths).
  const double below_px = layout.line_px;
  ExpectColourNear(decoded.At(layout.XPx(5.0), layout.YPx(1.0) + below_px), ToRgb8(SeriesColour(0)),
                   2);
  const Rgb8 dense_colour = ToRgb8(SeriesColour(1));
  ExpectColourNear(decoded.NearestAlongColumn(layout.XPx(5.0), layout.YPx(3.0), dense_colour),
                   dense_colour, 2);
  EXPECT_GT(Distance(decoded.At(layout.XPx(5.0), layout.YPx(3.0) + below_px), dense_colour), 100);
}

TEST(RenderLinePlotPngTest, NanPointBreaksTheLine) {
  LinePlot plot;
  plot.series.push_back({"gappy", {0.0, 1.0, 2.0, 3.0, 4.0}, {1.0, 1.0, kNan, 1.0, 1.0}});
  plot.series.push_back({"other", {0.0, 4.0}, {2.0, 2.0}});
  PlotLayout layout = ComputePlotLayout(plot, 1200, 800);
  StatusOr<std::string> png = RenderLinePlotPng(plot, 1200, 800);
  ASSERT_TRUE(png.ok()) << png.status().ToString();
  DecodedPng decoded(*png);
  ASSERT_TRUE(decoded.ok());
  const Rgb8 colour = ToRgb8(SeriesColour(0));
  ExpectColourNear(decoded.NearestAlongColumn(layout.XPx(0.5), layout.YPx(1.0), colour), colour, 2);
  ExpectColourNear(decoded.NearestAlongColumn(layout.XPx(3.5), layout.YPx(1.0), colour), colour, 2);
  // Between x = 1 and x = 3 the point at x = 2 is missing: no line there.
  EXPECT_GT(Distance(decoded.NearestAlongColumn(layout.XPx(2.0), layout.YPx(1.0), colour), colour),
            100);
}

TEST(RenderLinePlotPngTest, EmptyPlotDrawsTheFrameOnly) {
  LinePlot plot;
  plot.title = "nothing yet";
  PlotLayout layout = ComputePlotLayout(plot, 800, 600);
  StatusOr<std::string> png = RenderLinePlotPng(plot, 800, 600);
  ASSERT_TRUE(png.ok()) << png.status().ToString();
  DecodedPng decoded(*png);
  ASSERT_TRUE(decoded.ok());
  const double mid_y = (layout.area_top_px + layout.area_bottom_px) / 2 + 3.0;
  const double mid_x = (layout.area_left_px + layout.area_right_px) / 2 + 3.0;
  const Rgb8 frame = decoded.At(layout.area_left_px - 0.5, mid_y);
  EXPECT_LT(frame.r, 100);
  EXPECT_LT(decoded.At(layout.area_right_px + 0.5, mid_y).g, 100);
  EXPECT_LT(decoded.At(mid_x, layout.area_bottom_px + 0.5).b, 100);
  ExpectColourNear(decoded.At(layout.XPx(BetweenXTicks(layout, 0)),
                              layout.YPx((layout.y_ticks[0] + layout.y_ticks[1]) / 2)),
                   kWhite, 0);
  // Right of the frame, where a legend would be, is blank.
  ExpectColourNear(decoded.At(layout.area_right_px + 8.0, mid_y), kWhite, 0);
}

TEST(RenderLinePlotPngTest, RejectsInvalidInputNamingTheField) {
  LinePlot plot = TwoHorizontalLines();
  EXPECT_EQ(RenderLinePlotPng(plot, 100, 800).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(RenderLinePlotPng(plot, 1200, 9000).status().code(), StatusCode::kInvalidArgument);

  plot.series[1].y.push_back(4.0);
  Status mismatch = RenderLinePlotPng(plot).status();
  EXPECT_EQ(mismatch.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(mismatch.message().find("series[1]"), std::string::npos) << mismatch.ToString();

  plot = TwoHorizontalLines();
  plot.title = "bad \xFF byte";
  Status bad_title = RenderLinePlotPng(plot).status();
  EXPECT_EQ(bad_title.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad_title.message().find("title"), std::string::npos);

  plot = TwoHorizontalLines();
  plot.series[0].label = "cut \xE2\x82";  // truncated 3-byte sequence
  Status bad_label = RenderLinePlotPng(plot).status();
  EXPECT_NE(bad_label.message().find("series[0].label"), std::string::npos);

  plot = TwoHorizontalLines();
  plot.y_label = "\xC0\xAF";  // overlong encoding of '/'
  EXPECT_EQ(RenderLinePlotPng(plot).status().code(), StatusCode::kInvalidArgument);

  plot = TwoHorizontalLines();
  plot.x_label =
      "\xCE\xBC"
      "s per step \xE2\x86\x92";  // valid: µ, →
  EXPECT_TRUE(RenderLinePlotPng(plot).ok());
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

TEST(WriteLinePlotPngTest, WritesTheRenderedBytes) {
  const std::string path = ::testing::TempDir() + "/line_plot_test_write.png";
  std::filesystem::remove(path);
  LinePlot plot = TwoHorizontalLines();
  Status status = WriteLinePlotPng(path, plot, 600, 400);
  ASSERT_TRUE(status.ok()) << status.ToString();
  StatusOr<std::string> png = RenderLinePlotPng(plot, 600, 400);
  ASSERT_TRUE(png.ok());
  EXPECT_EQ(ReadFile(path), *png);
  std::filesystem::remove(path);
}

TEST(WriteLinePlotPngTest, FailedRenderingLeavesTheOldFile) {
  const std::string path = ::testing::TempDir() + "/line_plot_test_keep.png";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << "previous";
  }
  LinePlot plot = TwoHorizontalLines();
  plot.series[0].x.pop_back();
  EXPECT_EQ(WriteLinePlotPng(path, plot).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ReadFile(path), "previous");
  std::filesystem::remove(path);

  const std::string missing_dir = ::testing::TempDir() + "/line_plot_no_such_dir/plot.png";
  EXPECT_FALSE(WriteLinePlotPng(missing_dir, TwoHorizontalLines()).ok());
  EXPECT_FALSE(std::filesystem::exists(missing_dir));
}

TEST(CsvTableTest, QuotesOnlyFieldsThatNeedIt) {
  EXPECT_EQ(
      CsvTable({"name", "particles", "ms"}, {{"a", "1000", "1.5"}, {"b,c", "say \"hi\"", ""}}),
      "name,particles,ms\n"
      "a,1000,1.5\n"
      "\"b,c\",\"say \"\"hi\"\"\",\n");
  EXPECT_EQ(CsvTable({"x"}, {{"two\nlines"}, {"cr\r"}}), "x\n\"two\nlines\"\n\"cr\r\"\n");
  EXPECT_EQ(CsvTable({}, {{"1", "2"}}), "1,2\n");
  EXPECT_EQ(CsvTable({"only"}, {}), "only\n");
  EXPECT_EQ(CsvTable({}, {}), "");
}

TEST(MarkdownTableTest, PipesAndHeaderSeparator) {
  EXPECT_EQ(MarkdownTable({"name", "ms"}, {{"a", "1.5"}, {"b", "20"}}),
            "| name | ms |\n"
            "| --- | --- |\n"
            "| a | 1.5 |\n"
            "| b | 20 |\n");
  // Short rows are padded, pipes escaped, line breaks turned into <br>.
  EXPECT_EQ(MarkdownTable({"k", "v"}, {{"a|b"}, {"x", "1\n2"}, {"y", "3\r\n4"}}),
            "| k | v |\n"
            "| --- | --- |\n"
            "| a\\|b |  |\n"
            "| x | 1<br>2 |\n"
            "| y | 3<br>4 |\n");
  // A row longer than the header widens the table.
  EXPECT_EQ(MarkdownTable({"a"}, {{"1", "2"}}),
            "| a |  |\n"
            "| --- | --- |\n"
            "| 1 | 2 |\n");
  EXPECT_EQ(MarkdownTable({}, {}), "");
}

}  // namespace
}  // namespace grove::tools

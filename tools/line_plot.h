// Line charts as PNG (drawn with cairo) for benchmark reports, and small CSV / Markdown table
// writers for the numbers behind them.
#ifndef GROVE_TOOLS_LINE_PLOT_H_
#define GROVE_TOOLS_LINE_PLOT_H_

#include <cstddef>
#include <string>
#include <vector>

#include "grove/status.h"

namespace grove::tools {

// One polyline with a small marker at each point; a series too dense for markers (more points
// than fit about three marker widths apart across the plot) is drawn as a bare line. x and y
// have the same length; points with a NaN or infinite coordinate, or a coordinate <= 0 on a log
// axis, are skipped and break the line there.
struct PlotSeries {
  std::string label;
  std::vector<double> x, y;
  bool dashed = false;
};

struct LinePlot {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;     // coloured by position, from a cycled 8-colour palette
  bool log_x = false, log_y = false;  // log10 axes
};

struct PlotRgb {
  double r, g, b;  // [0, 1]
};

// The colour of series `index`: ColorBrewer Dark2, cycled.
PlotRgb SeriesColour(size_t index);

// Where everything lands in the image. Device y points down. On a log axis the *_min/*_max
// fields are log10 of the data range.
struct PlotLayout {
  int width_px = 0;
  int height_px = 0;
  double font_px = 0.0;
  double line_px = 0.0;  // series line width

  // The plot area (the frame), in device pixels.
  double area_left_px = 0.0;
  double area_top_px = 0.0;
  double area_right_px = 0.0;
  double area_bottom_px = 0.0;

  bool log_x = false;
  bool log_y = false;
  double x_min = 0.0, x_max = 1.0;  // axis range, log10 on a log axis
  double y_min = 0.0, y_max = 1.0;
  std::vector<double> x_ticks, y_ticks;  // data values, inside the range
  std::vector<std::string> x_tick_labels, y_tick_labels;

  // The legend box; width 0 when there are no series.
  double legend_left_px = 0.0;
  double legend_top_px = 0.0;
  double legend_width_px = 0.0;
  double legend_height_px = 0.0;
  double legend_row_px = 0.0;
  double legend_pad_px = 0.0;
  double legend_sample_px = 0.0;           // length of the line sample in front of each label
  std::vector<std::string> legend_labels;  // one per series, shortened with "…" to fit

  // Device position of a data value. REQUIRES: the value is > 0 on a log axis.
  double XPx(double x) const;
  double YPx(double y) const;
  // Centre of the line sample of legend entry `i`.
  double LegendSampleXPx() const { return legend_left_px + legend_pad_px + legend_sample_px / 2; }
  double LegendSampleYPx(size_t i) const {
    return legend_top_px + legend_pad_px + (static_cast<double>(i) + 0.5) * legend_row_px;
  }
};

// "Nice" tick values covering [lo, hi]: the multiples of a step of 1, 2 or 5 x 10^k that lie in
// [lo, hi], with the step chosen so that there are about `target` of them, and at least two.
// Returns {lo} when lo == hi and nothing when either bound is not finite.
std::vector<double> NiceTicks(double lo, double hi, int target);

// Ticks for a log10 axis over the values [lo, hi] (both > 0): the decades 10^k inside, thinned to
// every 2nd, 5th, 10th... decade when there are many more than `target`; when fewer than two
// decades fall inside, 1, 2 and 5 x 10^k, and failing that NiceTicks.
std::vector<double> LogTicks(double lo, double hi, int target);

// A compact tick label for `value` on an axis whose ticks are `step` apart: thousands and up
// with a suffix (1k, 2.5k, 30k, 1M, 4G, 1T), smaller values in fixed notation with as many
// decimals as the step needs (0.25, 7, 0.001); exponents only below 1e-6 or from 1e15.
std::string FormatTickLabel(double value, double step);

// Lays out the frame, ticks and legend of `plot` in a `width_px` x `height_px` image. Series with
// unequal x and y lengths use their common prefix. Empty or unusable data gives the range
// [0, 1] ([1, 10] on a log axis); equal values get a padded range around them.
PlotLayout ComputePlotLayout(const LinePlot& plot, int width_px, int height_px);

// Returns the encoded PNG. InvalidArgument when a size is outside [200, 8192], a series' x and
// y differ in length, or a text is not valid UTF-8; an empty plot gives the frame only.
StatusOr<std::string> RenderLinePlotPng(const LinePlot& plot, int width_px = 1200,
                                        int height_px = 800);

// Renders the PNG and writes it with WriteFileAtomically; nothing is written if rendering fails.
Status WriteLinePlotPng(const std::string& path, const LinePlot& plot, int width_px = 1200,
                        int height_px = 800);

// RFC 4180 CSV: a field holding a comma, a double quote, CR or LF is quoted with inner quotes
// doubled; every record, the header included, ends with "\n". An empty header writes no header
// line. Rows are written as given, whatever their length.
std::string CsvTable(const std::vector<std::string>& header,
                     const std::vector<std::vector<std::string>>& rows);

// A GitHub-flavoured Markdown table: "| a | b |", then "| --- | --- |", then one line per row.
// Every line gets as many cells as the longest of header and rows (missing cells are empty);
// "|" in a cell is escaped as "\|" and a line break becomes "<br>". Empty input gives "".
std::string MarkdownTable(const std::vector<std::string>& header,
                          const std::vector<std::vector<std::string>>& rows);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_LINE_PLOT_H_

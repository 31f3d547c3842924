// Report charts drawn by gnuplot (Debian's gnuplot-nox), run as a subprocess: series, translucent
// bands and box plots on linear or log10 axes, written as PNG (pngcairo) and SVG.
//
// Colours come from one 8-colour palette (ColorBrewer Dark2, cycled) by position within each list,
// so series i, band i and box i share a colour: a band drawn around series i matches it.
//
// The structs are meant for designated initializers (`Chart{.title = "...", .log_y = true}`);
// every field has a default so that -Wmissing-field-initializers stays quiet about the rest.
#ifndef GROVE_TOOLS_REPORT_CHART_H_
#define GROVE_TOOLS_REPORT_CHART_H_

#include <string>
#include <vector>

#include "grove/status.h"

namespace grove::tools {

enum class ChartStyle { kLine, kLinePoints, kPoints, kDashed };

// x and y have the same length. A point with a NaN or infinite coordinate, or one <= 0 on a log
// axis, is skipped and breaks the line there.
struct ChartSeries {
  std::string label = {};  // legend text; empty: no legend entry
  std::vector<double> x = {}, y = {};
  ChartStyle style = ChartStyle::kLinePoints;
};

// The area between y_low and y_high, filled translucent behind the series (e.g. a 95 % interval).
// x, y_low and y_high have the same length; unusable points are skipped as for a series, and the
// area is cut there.
struct ChartBand {
  std::string label = {};  // legend text; empty: no legend entry
  std::vector<double> x = {}, y_low = {}, y_high = {};
};

// One box plot of `values` (gnuplot's boxplot: quartiles, whiskers to the furthest value within
// 1.5 interquartile ranges, the values beyond as points; fewer than 4 values are drawn as points
// only). NaN, infinite and, on a log y axis, values <= 0 are left out.
struct ChartBox {
  std::string label = {};  // the category, written under the box
  std::vector<double> values = {};
};

// Every text is UTF-8 and shown literally (no markup); "\n" breaks a line. An empty chart still
// has its frame, axes and title.
struct Chart {
  std::string title = {}, x_label = {}, y_label = {};
  bool log_x = false, log_y = false;  // log10 axes
  std::vector<ChartSeries> series = {};
  std::vector<ChartBand> bands = {};
  // Box k (from 0) stands at x = k + 1, and the x axis then shows the box labels instead of
  // numbers; series and bands, if any, are drawn on that same axis.
  std::vector<ChartBox> boxes = {};
  // A linear x axis of whole numbers (thread counts): tics only at integers, half a unit of room
  // either side of the data.
  bool integer_x = false;
  // A linear y axis that starts at zero, so that differences are drawn to scale.
  bool y_from_zero = false;
};

struct ChartOptions {
  int width_px = 1200;  // [200, 8192]; the SVG has the same size
  int height_px = 800;  // [200, 8192]
  // The gnuplot executable: a name looked up in PATH, or a path. Default: "gnuplot".
  std::string gnuplot = "gnuplot";
};

// Draws `chart` into `png_path` and, unless `svg_path` is empty, `svg_path`. Each file is
// replaced atomically (WriteFileAtomically): it appears complete or not at all, and both output
// directories are checked before anything is drawn.
//
// Errors: InvalidArgument for a size out of range, unequal vector lengths or text that is not
// UTF-8; IoError when an output directory does not exist or a write fails (ResourceExhausted when
// the disk is full); NotFound when gnuplot is not installed (the message says to install
// gnuplot-nox); Internal when gnuplot fails (the message holds the start of its error output).
// Thread safety: calls may run concurrently; each has its own temporary directory and gnuplot.
Status WriteChart(const Chart& chart, const std::string& png_path, const std::string& svg_path,
                  const ChartOptions& options = {});

// The gnuplot script WriteChart runs to draw `chart` into the two paths (for tests; it does not
// check the chart: WriteChart does).
std::string ChartScript(const Chart& chart, const ChartOptions& options,
                        const std::string& png_path, const std::string& svg_path);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_REPORT_CHART_H_

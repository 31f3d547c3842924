#include "tools/line_plot.h"

#include <cairo.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <new>
#include <numbers>
#include <string_view>
#include <utility>

#include "tools/atomic_file.h"
#include "tools/cairo_output.h"

namespace grove::tools {
namespace {

constexpr int kMinSizePx = 200;
constexpr int kMaxSizePx = 8192;
// Data beyond this magnitude is clipped, so that hi - lo stays finite.
constexpr double kMaxAbsValue = 1e300;
// Fraction of the data range left empty on each side, so that end markers are not cut.
constexpr double kRangePad = 0.04;
constexpr std::string_view kEllipsis = "\xE2\x80\xA6";  // U+2026

// ColorBrewer Dark2: 8 qualitative colours that stay readable on white.
constexpr std::array<PlotRgb, 8> kDark2 = {{
    {0x1b / 255.0, 0x9e / 255.0, 0x77 / 255.0},
    {0xd9 / 255.0, 0x5f / 255.0, 0x02 / 255.0},
    {0x75 / 255.0, 0x70 / 255.0, 0xb3 / 255.0},
    {0xe7 / 255.0, 0x29 / 255.0, 0x8a / 255.0},
    {0x66 / 255.0, 0xa6 / 255.0, 0x1e / 255.0},
    {0xe6 / 255.0, 0xab / 255.0, 0x02 / 255.0},
    {0xa6 / 255.0, 0x76 / 255.0, 0x1d / 255.0},
    {0x66 / 255.0, 0x66 / 255.0, 0x66 / 255.0},
}};

constexpr PlotRgb kGridColour = {0.88, 0.88, 0.88};
constexpr PlotRgb kFrameColour = {0.25, 0.25, 0.25};
constexpr PlotRgb kLegendBorderColour = {0.7, 0.7, 0.7};

// 10^k, correctly rounded for |k| <= 22 (10^-k is computed as 1 / 10^k).
double Pow10(int k) { return k >= 0 ? std::pow(10.0, k) : 1.0 / std::pow(10.0, -k); }

// floor(log10(v)) for v > 0, corrected where log10 is off by one ulp near powers of ten.
int FloorLog10(double v) {
  int k = static_cast<int>(std::floor(std::log10(v)));
  if (Pow10(k + 1) <= v) ++k;
  if (Pow10(k) > v) --k;
  return k;
}

bool IsValidUtf8(std::string_view s) {
  static constexpr uint32_t kMinCodePoint[] = {0, 0x80, 0x800, 0x10000};
  size_t i = 0;
  while (i < s.size()) {
    unsigned char c = static_cast<unsigned char>(s[i]);
    int n;
    uint32_t cp;
    if (c < 0x80) {
      ++i;
      continue;
    } else if ((c & 0xE0) == 0xC0) {
      n = 1;
      cp = c & 0x1F;
    } else if ((c & 0xF0) == 0xE0) {
      n = 2;
      cp = c & 0x0F;
    } else if ((c & 0xF8) == 0xF0) {
      n = 3;
      cp = c & 0x07;
    } else {
      return false;
    }
    if (s.size() - i <= static_cast<size_t>(n)) return false;
    for (int k = 1; k <= n; ++k) {
      unsigned char b = static_cast<unsigned char>(s[i + k]);
      if ((b & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (b & 0x3F);
    }
    if (cp < kMinCodePoint[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
    i += n + 1;
  }
  return true;
}

void SetColour(cairo_t* cr, const PlotRgb& c) { cairo_set_source_rgb(cr, c.r, c.g, c.b); }

double TextWidth(cairo_t* cr, const std::string& text) {
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  return extents.x_advance;
}

// `text`, or its longest prefix (cut at a UTF-8 code point boundary) plus "…" that is at most
// `max_px` wide.
std::string FitText(cairo_t* cr, const std::string& text, double max_px) {
  if (TextWidth(cr, text) <= max_px) return text;
  std::string prefix = text;
  while (!prefix.empty()) {
    prefix.pop_back();
    while (!prefix.empty() && (static_cast<unsigned char>(prefix.back()) & 0xC0) == 0x80) {
      prefix.pop_back();
    }
    // Drop the lead byte of a sequence whose continuation bytes were just removed.
    if (!prefix.empty() && (static_cast<unsigned char>(prefix.back()) & 0xC0) == 0xC0) {
      prefix.pop_back();
    }
    std::string candidate = prefix + std::string(kEllipsis);
    if (TextWidth(cr, candidate) <= max_px) return candidate;
  }
  return std::string(kEllipsis);
}

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* cr) const { cairo_destroy(cr); }
};
using SurfacePtr = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using ContextPtr = std::unique_ptr<cairo_t, ContextDeleter>;

void SelectFont(cairo_t* cr, double size_px, bool bold) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL,
                         bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size_px);
}

// A point of a series is drawn only when both coordinates are finite and, on a log axis,
// positive. Returns the axis coordinate (log10 on a log axis) in `out`.
bool AxisValue(double v, bool log_axis, double* out) {
  if (!std::isfinite(v) || (log_axis && v <= 0.0)) return false;
  *out = log_axis ? std::log10(v) : std::clamp(v, -kMaxAbsValue, kMaxAbsValue);
  return true;
}

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  bool empty() const { return lo > hi; }
  void Add(double v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
};

// Pads the data range of one axis (in axis coordinates); see ComputePlotLayout.
Range PadRange(Range r, bool log_axis) {
  if (r.empty()) return Range{0.0, 1.0};  // [0, 1], or [1, 10] on a log axis
  double magnitude = std::max(std::abs(r.lo), std::abs(r.hi));
  if (r.hi - r.lo <= 1e-12 * magnitude) {
    double pad = log_axis ? 0.5 : (magnitude > 0.0 ? 0.1 * magnitude : 1.0);
    return Range{r.lo - pad, r.hi + pad};
  }
  double pad = (r.hi - r.lo) * kRangePad;
  return Range{r.lo - pad, r.hi + pad};
}

// The distance from ticks[i] to its nearest neighbour: the precision its label needs.
double TickStep(const std::vector<double>& ticks, size_t i) {
  double step = std::numeric_limits<double>::infinity();
  if (i > 0) step = std::min(step, ticks[i] - ticks[i - 1]);
  if (i + 1 < ticks.size()) step = std::min(step, ticks[i + 1] - ticks[i]);
  if (!std::isfinite(step)) step = std::abs(ticks[i]);
  return step;
}

struct AxisTicks {
  std::vector<double> values;
  std::vector<std::string> labels;
  double max_label_px = 0.0;
};

AxisTicks MakeTicks(cairo_t* cr, Range range, bool log_axis, int target) {
  AxisTicks ticks;
  ticks.values = log_axis ? LogTicks(std::pow(10.0, range.lo), std::pow(10.0, range.hi), target)
                          : NiceTicks(range.lo, range.hi, target);
  for (size_t i = 0; i < ticks.values.size(); ++i) {
    ticks.labels.push_back(FormatTickLabel(ticks.values[i], TickStep(ticks.values, i)));
    ticks.max_label_px = std::max(ticks.max_label_px, TextWidth(cr, ticks.labels.back()));
  }
  return ticks;
}

void DrawText(cairo_t* cr, const std::string& text, double x, double baseline_y) {
  cairo_move_to(cr, x, baseline_y);
  cairo_show_text(cr, text.c_str());
}

void DrawGridAndTicks(cairo_t* cr, const PlotLayout& layout) {
  const double tick_px = layout.font_px * 0.4;
  cairo_set_line_width(cr, 1.0);
  cairo_set_dash(cr, nullptr, 0, 0.0);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
  // Grid lines on pixel centres, so they are crisp.
  SetColour(cr, kGridColour);
  cairo_new_path(cr);
  for (double x : layout.x_ticks) {
    double px = std::floor(layout.XPx(x)) + 0.5;
    cairo_move_to(cr, px, layout.area_top_px);
    cairo_line_to(cr, px, layout.area_bottom_px);
  }
  for (double y : layout.y_ticks) {
    double py = std::floor(layout.YPx(y)) + 0.5;
    cairo_move_to(cr, layout.area_left_px, py);
    cairo_line_to(cr, layout.area_right_px, py);
  }
  cairo_stroke(cr);

  SetColour(cr, kFrameColour);
  cairo_new_path(cr);
  for (double x : layout.x_ticks) {
    double px = std::floor(layout.XPx(x)) + 0.5;
    cairo_move_to(cr, px, layout.area_bottom_px);
    cairo_line_to(cr, px, layout.area_bottom_px + tick_px);
  }
  for (double y : layout.y_ticks) {
    double py = std::floor(layout.YPx(y)) + 0.5;
    cairo_move_to(cr, layout.area_left_px - tick_px, py);
    cairo_line_to(cr, layout.area_left_px, py);
  }
  cairo_stroke(cr);
}

void DrawTickLabels(cairo_t* cr, const PlotLayout& layout) {
  const double tick_px = layout.font_px * 0.4;
  SelectFont(cr, layout.font_px, false);
  cairo_set_source_rgb(cr, 0, 0, 0);
  for (size_t i = 0; i < layout.x_ticks.size(); ++i) {
    const std::string& label = layout.x_tick_labels[i];
    double px = layout.XPx(layout.x_ticks[i]);
    DrawText(cr, label, px - TextWidth(cr, label) / 2,
             layout.area_bottom_px + tick_px + layout.font_px * 1.1);
  }
  for (size_t i = 0; i < layout.y_ticks.size(); ++i) {
    const std::string& label = layout.y_tick_labels[i];
    double py = layout.YPx(layout.y_ticks[i]);
    DrawText(cr, label, layout.area_left_px - tick_px * 1.5 - TextWidth(cr, label),
             py + layout.font_px * 0.35);
  }
}

void DrawTitleAndAxisLabels(cairo_t* cr, const LinePlot& plot, const PlotLayout& layout) {
  const double area_cx = (layout.area_left_px + layout.area_right_px) / 2;
  const double area_cy = (layout.area_top_px + layout.area_bottom_px) / 2;
  cairo_set_source_rgb(cr, 0, 0, 0);
  if (!plot.title.empty()) {
    SelectFont(cr, layout.font_px * 1.25, true);
    DrawText(cr, plot.title, layout.width_px / 2.0 - TextWidth(cr, plot.title) / 2,
             layout.font_px * 2.0);
  }
  SelectFont(cr, layout.font_px * 1.05, false);
  if (!plot.x_label.empty()) {
    DrawText(cr, plot.x_label, area_cx - TextWidth(cr, plot.x_label) / 2,
             layout.height_px - layout.font_px * 0.8);
  }
  if (!plot.y_label.empty()) {
    cairo_save(cr);
    cairo_translate(cr, layout.font_px * 1.7, area_cy);
    cairo_rotate(cr, -std::numbers::pi / 2);
    DrawText(cr, plot.y_label, -TextWidth(cr, plot.y_label) / 2, 0.0);
    cairo_restore(cr);
  }
}

void ApplySeriesStyle(cairo_t* cr, const PlotLayout& layout, size_t index, bool dashed) {
  SetColour(cr, SeriesColour(index));
  cairo_set_line_width(cr, layout.line_px);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  if (dashed) {
    const double dashes[] = {4.0 * layout.line_px, 3.0 * layout.line_px};
    cairo_set_dash(cr, dashes, 2, 0.0);
  } else {
    cairo_set_dash(cr, nullptr, 0, 0.0);
  }
}

double MarkerRadius(const PlotLayout& layout) { return layout.line_px * 1.5; }

// A series with more drawable points than this gets no markers: on average they would be less
// than three marker diameters apart across the plot's width.
double MaxMarkedPoints(const PlotLayout& layout) {
  return (layout.area_right_px - layout.area_left_px) / (6.0 * MarkerRadius(layout));
}

// Strokes the series as polylines broken at skipped points, skipping vertices within half a pixel
// of the last one drawn (a dense series costs no more than the pixels it covers), then fills a
// marker at every point, unless there are so many points that markers would merge into a band.
void DrawSeries(cairo_t* cr, const LinePlot& plot, const PlotLayout& layout, size_t index) {
  const PlotSeries& series = plot.series[index];
  const size_t n = std::min(series.x.size(), series.y.size());
  ApplySeriesStyle(cr, layout, index, series.dashed);
  cairo_new_path(cr);
  bool in_segment = false;
  bool pending = false;  // a skipped vertex that must end the segment
  double last_x = 0, last_y = 0, pending_x = 0, pending_y = 0;
  auto end_segment = [&] {
    if (pending) cairo_line_to(cr, pending_x, pending_y);
    in_segment = pending = false;
  };
  for (size_t i = 0; i < n; ++i) {
    double ax, ay;
    if (!AxisValue(series.x[i], plot.log_x, &ax) || !AxisValue(series.y[i], plot.log_y, &ay)) {
      end_segment();
      continue;
    }
    double x = layout.XPx(series.x[i]);
    double y = layout.YPx(series.y[i]);
    if (!in_segment) {
      cairo_move_to(cr, x, y);
      in_segment = true;
    } else if (std::hypot(x - last_x, y - last_y) < 0.5) {
      pending = true;
      pending_x = x;
      pending_y = y;
      continue;
    } else {
      cairo_line_to(cr, x, y);
    }
    pending = false;
    last_x = x;
    last_y = y;
  }
  end_segment();
  cairo_stroke(cr);

  const double radius = MarkerRadius(layout);
  size_t usable = 0;
  for (size_t i = 0; i < n; ++i) {
    double ax, ay;
    if (AxisValue(series.x[i], plot.log_x, &ax) && AxisValue(series.y[i], plot.log_y, &ay)) {
      ++usable;
    }
  }
  if (static_cast<double>(usable) > MaxMarkedPoints(layout)) return;
  cairo_new_path(cr);
  for (size_t i = 0; i < n; ++i) {
    double ax, ay;
    if (!AxisValue(series.x[i], plot.log_x, &ax) || !AxisValue(series.y[i], plot.log_y, &ay)) {
      continue;
    }
    cairo_new_sub_path(cr);
    cairo_arc(cr, layout.XPx(series.x[i]), layout.YPx(series.y[i]), radius, 0.0,
              2 * std::numbers::pi);
  }
  cairo_fill(cr);
}

void DrawLegend(cairo_t* cr, const LinePlot& plot, const PlotLayout& layout) {
  if (plot.series.empty()) return;
  cairo_set_dash(cr, nullptr, 0, 0.0);
  cairo_rectangle(cr, std::floor(layout.legend_left_px) + 0.5,
                  std::floor(layout.legend_top_px) + 0.5, std::round(layout.legend_width_px),
                  std::round(layout.legend_height_px));
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_fill_preserve(cr);
  SetColour(cr, kLegendBorderColour);
  cairo_set_line_width(cr, 1.0);
  cairo_stroke(cr);

  SelectFont(cr, layout.font_px, false);
  const double x0 = layout.legend_left_px + layout.legend_pad_px;
  for (size_t i = 0; i < plot.series.size(); ++i) {
    const double y = layout.LegendSampleYPx(i);
    ApplySeriesStyle(cr, layout, i, plot.series[i].dashed);
    cairo_new_path(cr);
    cairo_move_to(cr, x0, y);
    cairo_line_to(cr, x0 + layout.legend_sample_px, y);
    cairo_stroke(cr);
    cairo_arc(cr, layout.LegendSampleXPx(), y, MarkerRadius(layout), 0.0, 2 * std::numbers::pi);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    DrawText(cr, layout.legend_labels[i], x0 + layout.legend_sample_px + layout.font_px * 0.5,
             y + layout.font_px * 0.35);
  }
}

void Draw(cairo_t* cr, const LinePlot& plot, const PlotLayout& layout) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  DrawGridAndTicks(cr, layout);

  cairo_save(cr);
  cairo_rectangle(cr, layout.area_left_px, layout.area_top_px,
                  layout.area_right_px - layout.area_left_px,
                  layout.area_bottom_px - layout.area_top_px);
  cairo_clip(cr);
  for (size_t i = 0; i < plot.series.size(); ++i) DrawSeries(cr, plot, layout, i);
  cairo_restore(cr);

  // The frame lies just outside the area, on whole pixels.
  SetColour(cr, kFrameColour);
  cairo_set_line_width(cr, 1.0);
  cairo_set_dash(cr, nullptr, 0, 0.0);
  cairo_rectangle(cr, layout.area_left_px - 0.5, layout.area_top_px - 0.5,
                  layout.area_right_px - layout.area_left_px + 1.0,
                  layout.area_bottom_px - layout.area_top_px + 1.0);
  cairo_stroke(cr);

  DrawTickLabels(cr, layout);
  DrawTitleAndAxisLabels(cr, plot, layout);
  DrawLegend(cr, plot, layout);
}

Status CheckText(const std::string& text, std::string_view name) {
  if (IsValidUtf8(text)) return Status::Ok();
  return InvalidArgumentError(fmt::format("{} is not valid UTF-8", name));
}

Status ValidatePlot(const LinePlot& plot, int width_px, int height_px) {
  if (width_px < kMinSizePx || width_px > kMaxSizePx || height_px < kMinSizePx ||
      height_px > kMaxSizePx) {
    return InvalidArgumentError(fmt::format("plot size {} x {} px is outside [{}, {}]", width_px,
                                            height_px, kMinSizePx, kMaxSizePx));
  }
  GROVE_RETURN_IF_ERROR(CheckText(plot.title, "title"));
  GROVE_RETURN_IF_ERROR(CheckText(plot.x_label, "x_label"));
  GROVE_RETURN_IF_ERROR(CheckText(plot.y_label, "y_label"));
  for (size_t i = 0; i < plot.series.size(); ++i) {
    const PlotSeries& s = plot.series[i];
    GROVE_RETURN_IF_ERROR(CheckText(s.label, fmt::format("series[{}].label", i)));
    if (s.x.size() != s.y.size()) {
      return InvalidArgumentError(fmt::format("series[{}] ('{}'): x has {} values, y has {}", i,
                                              s.label, s.x.size(), s.y.size()));
    }
  }
  return Status::Ok();
}

}  // namespace

PlotRgb SeriesColour(size_t index) { return kDark2[index % kDark2.size()]; }

double PlotLayout::XPx(double x) const {
  double v = log_x ? std::log10(x) : x;
  return area_left_px + (v - x_min) / (x_max - x_min) * (area_right_px - area_left_px);
}

double PlotLayout::YPx(double y) const {
  double v = log_y ? std::log10(y) : y;
  return area_bottom_px - (v - y_min) / (y_max - y_min) * (area_bottom_px - area_top_px);
}

std::vector<double> NiceTicks(double lo, double hi, int target) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) return {};
  if (lo > hi) std::swap(lo, hi);
  if (lo == hi) return {lo};
  target = std::max(target, 1);
  // Divide first: hi - lo may overflow.
  const double raw = hi / target - lo / target;
  static constexpr int kMultiples[] = {1, 2, 5};
  int k = FloorLog10(raw);
  const double norm = raw / Pow10(k);
  // The step is multiple x 10^k, the 1-2-5 multiple nearest to `norm` on a log scale.
  int m;
  if (norm < std::sqrt(2.0)) {
    m = 0;
  } else if (norm < std::sqrt(10.0)) {
    m = 1;
  } else if (norm < std::sqrt(50.0)) {
    m = 2;
  } else {
    m = 0;
    ++k;
  }
  double first = 0.0, last = 0.0;
  // A smaller step while fewer than two multiples fall inside; a few rounds suffice, as the
  // chosen step is at most ~1.6 (hi - lo) / target.
  for (int round = 0; round < 8; ++round) {
    const double step = kMultiples[m] * Pow10(k);
    first = std::ceil(lo / step - 1e-9);
    last = std::floor(hi / step + 1e-9);
    if (last > first) break;
    if (m == 0) {
      m = 2;
      --k;
    } else {
      --m;
    }
  }
  const int multiple = kMultiples[m];
  // Far more ticks than asked for, or fewer than two, means lo / step has lost its integer
  // precision: hi - lo is tiny next to |lo|.
  if (!(last - first < 100.0 * target) || !(last > first)) return {lo, hi};
  std::vector<double> ticks;
  for (double i = first; i <= last; i += 1.0) {
    // i * multiple / 10^-k rounds once, so 0.6 comes out as 0.6, not 0.6000000000000001.
    double v = k < 0 ? (i * multiple) / Pow10(-k) : (i * multiple) * Pow10(k);
    ticks.push_back(v == 0.0 ? 0.0 : v);  // no -0
  }
  return ticks;
}

std::vector<double> LogTicks(double lo, double hi, int target) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo <= 0.0 || hi <= 0.0) return {};
  if (lo > hi) std::swap(lo, hi);
  target = std::max(target, 1);
  const double a = std::log10(lo);
  const double b = std::log10(hi);
  const int k0 = static_cast<int>(std::ceil(a - 1e-9));
  const int k1 = static_cast<int>(std::floor(b + 1e-9));
  std::vector<double> ticks;
  if (k1 - k0 + 1 >= 2) {
    int stride = 1;
    for (int s : {1, 2, 5, 10, 20, 50, 100, 200}) {
      stride = s;
      if ((k1 - k0) / s + 1 <= target + target / 2) break;
    }
    for (int k = k0; k <= k1; ++k) {
      if (((k % stride) + stride) % stride == 0) ticks.push_back(Pow10(k));
    }
    if (ticks.empty()) ticks.push_back(Pow10(k0));
    return ticks;
  }
  for (int k = static_cast<int>(std::floor(a)) - 1; k <= k1 + 1; ++k) {
    for (int m : {1, 2, 5}) {
      double v = k < 0 ? m / Pow10(-k) : m * Pow10(k);
      if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) ticks.push_back(v);
    }
  }
  if (ticks.size() >= 2) return ticks;
  ticks = NiceTicks(lo, hi, target);
  std::erase_if(ticks, [](double v) { return v <= 0.0; });
  return ticks;
}

std::string FormatTickLabel(double value, double step) {
  if (!std::isfinite(value)) return fmt::format("{}", value);
  step = std::abs(step);
  if (!std::isfinite(step) || step == 0.0) step = std::abs(value);
  const double magnitude = std::abs(value);
  if (value == 0.0 || magnitude < step * 1e-9) return "0";
  if (magnitude >= 1e15 || magnitude < 1e-6) return fmt::format("{:g}", value);
  struct Suffix {
    double scale;
    const char* name;
  };
  static constexpr Suffix kSuffixes[] = {{1e12, "T"}, {1e9, "G"}, {1e6, "M"}, {1e3, "k"}};
  double scale = 1.0;
  const char* suffix = "";
  for (const Suffix& s : kSuffixes) {
    if (magnitude >= s.scale) {
      scale = s.scale;
      suffix = s.name;
      break;
    }
  }
  const double scaled_step = step / scale;
  const int decimals = std::clamp(-FloorLog10(scaled_step), 0, 12);
  std::string text = fmt::format("{:.{}f}", value / scale, decimals);
  if (text.find('.') != std::string::npos) {
    while (text.back() == '0') text.pop_back();
    if (text.back() == '.') text.pop_back();
  }
  if (text == "-0") text = "0";
  return text + suffix;
}

PlotLayout ComputePlotLayout(const LinePlot& plot, int width_px, int height_px) {
  PlotLayout layout;
  layout.width_px = width_px;
  layout.height_px = height_px;
  layout.log_x = plot.log_x;
  layout.log_y = plot.log_y;
  const double font = std::max(10.0, std::min(width_px, height_px * 3 / 2) / 90.0);
  layout.font_px = font;
  layout.line_px = std::max(2.0, std::min(width_px, height_px) / 300.0);

  Range x_range, y_range;
  for (const PlotSeries& s : plot.series) {
    const size_t n = std::min(s.x.size(), s.y.size());
    for (size_t i = 0; i < n; ++i) {
      double ax, ay;
      if (AxisValue(s.x[i], plot.log_x, &ax) && AxisValue(s.y[i], plot.log_y, &ay)) {
        x_range.Add(ax);
        y_range.Add(ay);
      }
    }
  }
  x_range = PadRange(x_range, plot.log_x);
  y_range = PadRange(y_range, plot.log_y);
  layout.x_min = x_range.lo;
  layout.x_max = x_range.hi;
  layout.y_min = y_range.lo;
  layout.y_max = y_range.hi;

  // Text is measured with the font the renderer uses.
  SurfacePtr surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, 1, 1));
  ContextPtr cr(cairo_create(surface.get()));
  SelectFont(cr.get(), font, false);

  const double tick_px = font * 0.4;
  const double min_area_px = 20.0;
  // Vertical bands first: the y ticks depend on the area's height only.
  const double top = std::round(plot.title.empty() ? font * 1.2 : font * 3.0);
  const double bottom =
      std::round(tick_px + font * 1.6 + (plot.x_label.empty() ? 0 : font * 1.6) + font * 0.6);
  layout.area_top_px = top;
  layout.area_bottom_px = std::max(top + min_area_px, height_px - bottom);
  const double area_h = layout.area_bottom_px - layout.area_top_px;
  const double max_legend_label_px = width_px * 0.25;
  int y_target = std::max(2, static_cast<int>(area_h / (font * 4.0)));
  AxisTicks y_ticks = MakeTicks(cr.get(), y_range, plot.log_y, y_target);

  const double left = std::round(font * 0.6 + (plot.y_label.empty() ? 0 : font * 1.8) +
                                 y_ticks.max_label_px + tick_px * 2.5);
  layout.legend_pad_px = font * 0.6;
  layout.legend_row_px = font * 1.5;
  layout.legend_sample_px = font * 2.5;
  double right = font * 1.5;
  if (!plot.series.empty()) {
    double max_label_px = 0.0;
    for (const PlotSeries& s : plot.series) {
      layout.legend_labels.push_back(FitText(cr.get(), s.label, max_legend_label_px));
      max_label_px = std::max(max_label_px, TextWidth(cr.get(), layout.legend_labels.back()));
    }
    layout.legend_width_px =
        2 * layout.legend_pad_px + layout.legend_sample_px + font * 0.5 + max_label_px;
    layout.legend_height_px =
        2 * layout.legend_pad_px + layout.legend_row_px * static_cast<double>(plot.series.size());
    right = layout.legend_width_px + font * 2.0;
  }
  layout.area_left_px = left;
  layout.area_right_px = std::max(left + min_area_px, std::round(width_px - right));
  layout.legend_left_px = layout.area_right_px + font * 1.0;
  layout.legend_top_px = layout.area_top_px;

  // Fewer x ticks while their labels would touch.
  const double area_w = layout.area_right_px - layout.area_left_px;
  int x_target = std::max(2, static_cast<int>(area_w / (font * 8.0)));
  AxisTicks x_ticks;
  while (true) {
    x_ticks = MakeTicks(cr.get(), x_range, plot.log_x, x_target);
    double min_gap_px = std::numeric_limits<double>::infinity();
    for (size_t i = 1; i < x_ticks.values.size(); ++i) {
      min_gap_px =
          std::min(min_gap_px, layout.XPx(x_ticks.values[i]) - layout.XPx(x_ticks.values[i - 1]));
    }
    if (x_target <= 2 || x_ticks.max_label_px + font <= min_gap_px) break;
    x_target = x_target * 2 / 3;
  }
  layout.x_ticks = std::move(x_ticks.values);
  layout.x_tick_labels = std::move(x_ticks.labels);
  layout.y_ticks = std::move(y_ticks.values);
  layout.y_tick_labels = std::move(y_ticks.labels);
  return layout;
}

StatusOr<std::string> RenderLinePlotPng(const LinePlot& plot, int width_px, int height_px) {
  GROVE_RETURN_IF_ERROR(ValidatePlot(plot, width_px, height_px));
  const PlotLayout layout = ComputePlotLayout(plot, width_px, height_px);
  SurfacePtr surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width_px, height_px));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    return CairoError(cairo_surface_status(surface.get()), "rendering the line plot");
  }
  ContextPtr cr(cairo_create(surface.get()));
  Draw(cr.get(), plot, layout);
  if (cairo_status(cr.get()) != CAIRO_STATUS_SUCCESS) {
    return CairoError(cairo_status(cr.get()), "rendering the line plot");
  }
  std::string png;
  cairo_status_t status = cairo_surface_write_to_png_stream(surface.get(), AppendToString, &png);
  if (status != CAIRO_STATUS_SUCCESS) return CairoError(status, "encoding the line plot PNG");
  return png;
}

Status WriteLinePlotPng(const std::string& path, const LinePlot& plot, int width_px,
                        int height_px) {
  StatusOr<std::string> png = RenderLinePlotPng(plot, width_px, height_px);
  if (!png.ok()) return png.status();
  return WriteFileAtomically(path, *png);
}

std::string CsvTable(const std::vector<std::string>& header,
                     const std::vector<std::vector<std::string>>& rows) {
  std::string out;
  auto append_record = [&out](const std::vector<std::string>& fields) {
    for (size_t i = 0; i < fields.size(); ++i) {
      if (i > 0) out += ',';
      const std::string& f = fields[i];
      if (f.find_first_of(",\"\r\n") == std::string::npos) {
        out += f;
        continue;
      }
      out += '"';
      for (char c : f) {
        if (c == '"') out += '"';
        out += c;
      }
      out += '"';
    }
    out += '\n';
  };
  if (!header.empty()) append_record(header);
  for (const std::vector<std::string>& row : rows) append_record(row);
  return out;
}

std::string MarkdownTable(const std::vector<std::string>& header,
                          const std::vector<std::vector<std::string>>& rows) {
  size_t columns = header.size();
  for (const std::vector<std::string>& row : rows) columns = std::max(columns, row.size());
  if (columns == 0) return "";
  std::string out;
  auto append_line = [&out, columns](const std::vector<std::string>& cells) {
    out += '|';
    for (size_t i = 0; i < columns; ++i) {
      out += ' ';
      if (i < cells.size()) {
        const std::string& cell = cells[i];
        for (size_t j = 0; j < cell.size(); ++j) {
          char c = cell[j];
          if (c == '|') {
            out += "\\|";
          } else if (c == '\n') {
            out += "<br>";
          } else if (c == '\r') {
            if (j + 1 >= cell.size() || cell[j + 1] != '\n') out += "<br>";  // lone CR
          } else {
            out += c;
          }
        }
      }
      out += " |";
    }
    out += '\n';
  };
  append_line(header);
  out += '|';
  for (size_t i = 0; i < columns; ++i) out += " --- |";
  out += '\n';
  for (const std::vector<std::string>& row : rows) append_line(row);
  return out;
}

}  // namespace grove::tools

#include "tools/report/map_render.h"

#include <cairo-svg.h>
#include <cairo.h>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <numbers>
#include <string_view>

#include "tools/io/atomic_file.h"
#include "tools/report/cairo_output.h"

namespace grove::tools {
namespace {

constexpr double kSqrt3 = 1.7320508075688772;
constexpr int kMinWidthPx = 200;
constexpr int kMaxWidthPx = 8192;
// Hexes are filled one path per colour level: one <path> per level keeps the SVG small.
constexpr int kColourLevels = 64;
// Palette position of the least used hexagon: the palette's first colour is too close to the
// white background to be seen.
constexpr double kPaletteLow = 0.1;

struct Rgb {
  double r, g, b;
};

// ColorBrewer YlGnBu (9 classes): a light-to-dark sequential scale, light yellow to dark blue.
constexpr std::array<Rgb, 9> kYlGnBu = {{
    {0xff / 255.0, 0xff / 255.0, 0xd9 / 255.0},
    {0xed / 255.0, 0xf8 / 255.0, 0xb1 / 255.0},
    {0xc7 / 255.0, 0xe9 / 255.0, 0xb4 / 255.0},
    {0x7f / 255.0, 0xcd / 255.0, 0xbb / 255.0},
    {0x41 / 255.0, 0xb6 / 255.0, 0xc4 / 255.0},
    {0x1d / 255.0, 0x91 / 255.0, 0xc0 / 255.0},
    {0x22 / 255.0, 0x5e / 255.0, 0xa8 / 255.0},
    {0x25 / 255.0, 0x34 / 255.0, 0x94 / 255.0},
    {0x08 / 255.0, 0x1d / 255.0, 0x58 / 255.0},
}};

constexpr Rgb kPathColour = {0.70, 0.05, 0.10};
constexpr Rgb kOdometryColour = {0.10, 0.35, 0.95};
constexpr Rgb kTruthColour = {0.10, 0.62, 0.20};
constexpr Rgb kFrameColour = {0.6, 0.6, 0.6};
constexpr Rgb kLandmarkColour = {0.90, 0.45, 0.0};

Rgb Palette(double t) {
  t = std::clamp(t, 0.0, 1.0) * (kYlGnBu.size() - 1);
  size_t i = std::min(static_cast<size_t>(t), kYlGnBu.size() - 2);
  double f = t - static_cast<double>(i);
  const Rgb& a = kYlGnBu[i];
  const Rgb& b = kYlGnBu[i + 1];
  return {a.r + (b.r - a.r) * f, a.g + (b.g - a.g) * f, a.b + (b.b - a.b) * f};
}

struct Box {
  double min_x = std::numeric_limits<double>::infinity();
  double min_y = std::numeric_limits<double>::infinity();
  double max_x = -std::numeric_limits<double>::infinity();
  double max_y = -std::numeric_limits<double>::infinity();
  bool empty() const { return min_x > max_x; }
  void Add(double x0, double y0, double x1, double y1) {
    min_x = std::min(min_x, x0);
    min_y = std::min(min_y, y0);
    max_x = std::max(max_x, x1);
    max_y = std::max(max_y, y1);
  }
};

Status CheckPoints(const std::vector<RenderPoint>& points, std::string_view name) {
  for (size_t i = 0; i < points.size(); ++i) {
    if (!std::isfinite(points[i].x_m) || !std::isfinite(points[i].y_m)) {
      return InvalidArgumentError(
          fmt::format("{}[{}] = ({}, {}) is not finite", name, i, points[i].x_m, points[i].y_m));
    }
  }
  return Status::Ok();
}

int LegendEntries(const MapImage& image) {
  return (image.path.empty() ? 0 : 1) + (image.odometry.empty() ? 0 : 1) +
         (image.truth.empty() ? 0 : 1) + (image.landmarks.empty() ? 0 : 1) +
         (image.landmarks_truth.empty() ? 0 : 1);
}

void SetColour(cairo_t* cr, const Rgb& c) { cairo_set_source_rgb(cr, c.r, c.g, c.b); }

struct LineStyle {
  Rgb colour;
  double width_px;
  bool dashed;
};

// `dash_offset_px`: how far into the dash pattern the next path starts.
void ApplyLineStyle(cairo_t* cr, const LineStyle& style, double dash_offset_px = 0.0) {
  SetColour(cr, style.colour);
  cairo_set_line_width(cr, style.width_px);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  if (style.dashed) {
    const double dashes[] = {4.0 * style.width_px, 3.0 * style.width_px};
    cairo_set_dash(cr, dashes, 2, dash_offset_px);
  } else {
    cairo_set_dash(cr, nullptr, 0, 0.0);
  }
}

// Decimation tolerance: invisible at line widths of 2 px and more.
constexpr double kDecimationPx = 0.5;
// Points per stroked piece of a polyline. Pieces meet at a shared point, where their round caps
// draw what a round join would. On a 500k-point random walk 16 to 128 drew fastest (8 s; 10 s at
// 2048, 393 s as one path); each piece is one SVG <path> element, so not fewer.
constexpr size_t kStrokePiecePoints = 128;

// DecimatePolyline of the points `at(0)`, ..., `at(n - 1)`.
template <typename PointAt>
std::vector<PixelPoint> Decimate(size_t n, PointAt at, double tolerance_px) {
  std::vector<PixelPoint> kept;
  if (n == 0) return kept;
  kept.push_back(at(0));
  for (size_t i = 1; i + 1 < n; ++i) {
    const PixelPoint p = at(i);
    const PixelPoint& last = kept.back();
    if (std::hypot(p.x_px - last.x_px, p.y_px - last.y_px) >= tolerance_px) kept.push_back(p);
  }
  if (n > 1) kept.push_back(at(n - 1));
  return kept;
}

// Strokes a polyline (decimated, in pieces); the dash pattern runs on across pieces.
void DrawPolyline(cairo_t* cr, const MapLayout& layout, const std::vector<RenderPoint>& points,
                  const LineStyle& style) {
  if (points.empty()) return;
  const std::vector<PixelPoint> kept = Decimate(
      points.size(),
      [&](size_t i) {
        return PixelPoint{layout.XPx(points[i].x_m), layout.YPx(points[i].y_m)};
      },
      kDecimationPx);
  double dash_offset = 0.0;
  size_t begin = 0;
  do {
    const size_t end = std::min(begin + kStrokePiecePoints, kept.size());
    cairo_new_path(cr);
    ApplyLineStyle(cr, style, dash_offset);
    cairo_move_to(cr, kept[begin].x_px, kept[begin].y_px);
    for (size_t i = begin + 1; i < end; ++i) {
      cairo_line_to(cr, kept[i].x_px, kept[i].y_px);
      dash_offset += std::hypot(kept[i].x_px - kept[i - 1].x_px, kept[i].y_px - kept[i - 1].y_px);
    }
    // A single point still shows as a dot (round cap on a zero-length segment).
    if (kept.size() == 1) cairo_line_to(cr, kept[0].x_px, kept[0].y_px);
    cairo_stroke(cr);
    begin = end - 1;
  } while (begin + 1 < kept.size());
}

// Quarter-pixel vertices: invisible, and they print as "12.25" instead of "12.234375" in the
// SVG, where 100k hexagons would otherwise cost ~145 bytes each.
double Snap(double px) { return std::round(px * 4.0) / 4.0; }

void DrawHexes(cairo_t* cr, const MapImage& image, const MapLayout& layout, double max_use) {
  if (max_use <= 0.0) return;
  std::vector<std::vector<size_t>> levels(kColourLevels);
  const double log_max = std::log1p(max_use);
  for (size_t i = 0; i < image.hexes.size(); ++i) {
    double use = image.hexes[i].use;
    if (use <= 0.0) continue;
    double t = std::log1p(use) / log_max;
    int level = static_cast<int>(std::lround(t * (kColourLevels - 1)));
    levels[std::clamp(level, 0, kColourLevels - 1)].push_back(i);
  }
  // Half a pixel of overlap hides the antialiasing seams between neighbours.
  const double radius_px = image.hex_radius_m * layout.px_per_m + 0.5;
  std::array<double, 6> dx, dy;
  for (int k = 0; k < 6; ++k) {
    double angle = std::numbers::pi / 2.0 + k * std::numbers::pi / 3.0;  // pointy top
    dx[k] = radius_px * std::cos(angle);
    dy[k] = -radius_px * std::sin(angle);
  }
  for (int level = 0; level < kColourLevels; ++level) {
    if (levels[level].empty()) continue;
    cairo_new_path(cr);
    for (size_t i : levels[level]) {
      RenderPoint c = HexCenter(image.hexes[i].q, image.hexes[i].r, image.hex_radius_m);
      double cx = layout.XPx(c.x_m);
      double cy = layout.YPx(c.y_m);
      cairo_move_to(cr, Snap(cx + dx[0]), Snap(cy + dy[0]));
      for (int k = 1; k < 6; ++k) cairo_line_to(cr, Snap(cx + dx[k]), Snap(cy + dy[k]));
      cairo_close_path(cr);
    }
    double t = static_cast<double>(level) / (kColourLevels - 1);
    SetColour(cr, Palette(kPaletteLow + (1.0 - kPaletteLow) * t));
    cairo_fill(cr);
  }
}

int ScaleBarDecimals(double length_m) {
  return std::max(0, -static_cast<int>(std::floor(std::log10(length_m) + 1e-9)));
}

void DrawScaleBar(cairo_t* cr, const MapLayout& layout) {
  const double max_px = layout.width_px / 5.0;
  double length_m = ScaleBarLengthM(max_px / layout.px_per_m);
  int decimals = ScaleBarDecimals(length_m);
  double length_px = length_m * layout.px_per_m;
  double x0 = layout.font_px;
  double y = layout.height_px - layout.footer_px * 0.45;
  double tick = layout.font_px * 0.35;
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_set_line_width(cr, 2.0);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
  cairo_set_dash(cr, nullptr, 0, 0.0);
  cairo_new_path(cr);
  cairo_move_to(cr, x0, y - tick);
  cairo_line_to(cr, x0, y + tick);
  cairo_move_to(cr, x0, y);
  cairo_line_to(cr, x0 + length_px, y);
  cairo_move_to(cr, x0 + length_px, y - tick);
  cairo_line_to(cr, x0 + length_px, y + tick);
  cairo_stroke(cr);
  std::string label = fmt::format("{:.{}f} m", length_m, decimals);
  cairo_set_font_size(cr, layout.font_px);
  cairo_move_to(cr, x0 + length_px + layout.font_px * 0.5, y + layout.font_px * 0.35);
  cairo_show_text(cr, label.c_str());
}

double TextWidth(cairo_t* cr, const std::string& text) {
  cairo_text_extents_t extents;
  cairo_text_extents(cr, text.c_str(), &extents);
  return extents.x_advance;
}

void DrawColourBar(cairo_t* cr, const MapLayout& layout, double max_use) {
  if (max_use <= 0.0) return;
  cairo_set_font_size(cr, layout.font_px * 0.9);
  std::string low = "use 0";
  std::string high = fmt::format("{:.4g} (log scale)", max_use);
  double bar_w = std::min(layout.width_px / 5.0, 300.0);
  double bar_h = layout.font_px * 0.7;
  double gap = layout.font_px * 0.4;
  double right = layout.width_px - layout.font_px;
  double high_x = right - TextWidth(cr, high);
  double bar_x = high_x - gap - bar_w;
  double low_x = bar_x - gap - TextWidth(cr, low);
  double y = layout.height_px - layout.footer_px * 0.45;
  cairo_pattern_t* gradient = cairo_pattern_create_linear(bar_x, 0, bar_x + bar_w, 0);
  for (size_t i = 0; i < kYlGnBu.size(); ++i) {
    double t = static_cast<double>(i) / (kYlGnBu.size() - 1);
    Rgb c = Palette(kPaletteLow + (1.0 - kPaletteLow) * t);
    cairo_pattern_add_color_stop_rgb(gradient, t, c.r, c.g, c.b);
  }
  cairo_rectangle(cr, bar_x, y - bar_h / 2, bar_w, bar_h);
  cairo_set_source(cr, gradient);
  cairo_fill(cr);
  cairo_pattern_destroy(gradient);
  cairo_set_source_rgb(cr, 0, 0, 0);
  cairo_move_to(cr, low_x, y + layout.font_px * 0.3);
  cairo_show_text(cr, low.c_str());
  cairo_move_to(cr, high_x, y + layout.font_px * 0.3);
  cairo_show_text(cr, high.c_str());
}

void DrawHeader(cairo_t* cr, const MapImage& image, const MapLayout& layout,
                const LineStyle& path_style, const LineStyle& odometry_style,
                const LineStyle& truth_style) {
  const double row_px = layout.font_px * 1.6;
  double baseline = layout.font_px * 0.5 + layout.font_px * 1.15;
  if (!image.title.empty()) {
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    cairo_set_font_size(cr, layout.font_px * 1.1);
    cairo_move_to(cr, layout.font_px, baseline);
    cairo_show_text(cr, image.title.c_str());
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    baseline += row_px;
  }
  struct Entry {
    const std::vector<RenderPoint>* points;
    const char* label;
    const LineStyle* style;
  };
  const std::vector<RenderPoint> landmarks_mark(image.landmarks.empty() ? 0 : 1);
  const LineStyle landmark_style{kLandmarkColour, path_style.width_px, false};
  const LineStyle landmark_truth_style{kTruthColour, truth_style.width_px, true};
  const Entry entries[] = {{&image.path, image.path_label.c_str(), &path_style},
                           {&image.odometry, "odometry", &odometry_style},
                           {&image.truth, image.truth_label.c_str(), &truth_style},
                           {&landmarks_mark, "landmarks, 2-sigma ellipses", &landmark_style},
                           {&image.landmarks_truth, "true landmarks", &landmark_truth_style}};
  cairo_set_font_size(cr, layout.font_px);
  double x = layout.font_px;
  const double sample_px = layout.font_px * 2.5;
  for (const Entry& entry : entries) {
    if (entry.points->empty()) continue;
    double line_y = baseline - layout.font_px * 0.35;
    ApplyLineStyle(cr, *entry.style);
    cairo_new_path(cr);
    cairo_move_to(cr, x, line_y);
    cairo_line_to(cr, x + sample_px, line_y);
    cairo_stroke(cr);
    x += sample_px + layout.font_px * 0.5;
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_move_to(cr, x, baseline);
    cairo_show_text(cr, entry.label);
    x += TextWidth(cr, entry.label) + layout.font_px * 1.5;
  }
}

// The half axes (m) and the angle of the major axis of the 2-sigma ellipse of a covariance.
void EllipseOf(const RenderLandmark& l, double* a_m, double* b_m, double* angle_rad) {
  const double mean = 0.5 * (l.sxx + l.syy);
  const double d = std::hypot(0.5 * (l.sxx - l.syy), l.sxy);
  *a_m = 2.0 * std::sqrt(std::max(mean + d, 0.0));
  *b_m = 2.0 * std::sqrt(std::max(mean - d, 0.0));
  *angle_rad = 0.5 * std::atan2(2.0 * l.sxy, l.sxx - l.syy);
}

void DrawLandmarks(cairo_t* cr, const MapImage& image, const MapLayout& layout, double line_px) {
  const double mark_px = line_px * 2.5;
  SetColour(cr, kTruthColour);
  cairo_set_line_width(cr, line_px * 0.8);
  cairo_set_dash(cr, nullptr, 0, 0.0);
  for (const RenderPoint& p : image.landmarks_truth) {
    const double x = layout.XPx(p.x_m), y = layout.YPx(p.y_m);
    cairo_move_to(cr, x - mark_px, y - mark_px);
    cairo_line_to(cr, x + mark_px, y + mark_px);
    cairo_move_to(cr, x - mark_px, y + mark_px);
    cairo_line_to(cr, x + mark_px, y - mark_px);
  }
  cairo_stroke(cr);
  SetColour(cr, kLandmarkColour);
  for (const RenderLandmark& l : image.landmarks) {
    const double x = layout.XPx(l.x_m), y = layout.YPx(l.y_m);
    double a, b, angle;
    EllipseOf(l, &a, &b, &angle);
    // At least half a pixel: a point estimate still shows its ring.
    const double a_px = std::max(a * layout.px_per_m, 0.5),
                 b_px = std::max(b * layout.px_per_m, 0.5);
    cairo_save(cr);
    cairo_translate(cr, x, y);
    cairo_rotate(cr, -angle);  // device y points down
    cairo_scale(cr, a_px, b_px);
    cairo_new_sub_path(cr);
    cairo_arc(cr, 0, 0, 1, 0, 2 * std::numbers::pi);
    cairo_restore(cr);
    cairo_set_line_width(cr, line_px * 0.6);
    cairo_stroke(cr);
    cairo_new_sub_path(cr);
    cairo_arc(cr, x, y, line_px * 1.2, 0, 2 * std::numbers::pi);
    cairo_fill(cr);
  }
}

void Draw(cairo_t* cr, const MapImage& image, const MapLayout& layout) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);

  double max_use = 0.0;
  for (const RenderHex& hex : image.hexes) max_use = std::max(max_use, hex.use);

  const double map_top = layout.header_px;
  const double map_h = layout.height_px - layout.header_px - layout.footer_px;
  // At least 2 px, so some pixel row is always fully covered by the path.
  const double line_px = std::max(2.0, layout.width_px / 500.0);
  const LineStyle path_style{kPathColour, line_px, false};
  const LineStyle odometry_style{kOdometryColour, line_px * 0.6, true};
  const LineStyle truth_style{kTruthColour, line_px * 0.8, false};

  cairo_save(cr);
  cairo_rectangle(cr, 0, map_top, layout.width_px, map_h);
  cairo_clip(cr);
  DrawHexes(cr, image, layout, max_use);
  DrawPolyline(cr, layout, image.odometry, odometry_style);
  DrawPolyline(cr, layout, image.truth, truth_style);
  DrawPolyline(cr, layout, image.path, path_style);
  DrawLandmarks(cr, image, layout, line_px);
  cairo_restore(cr);

  SetColour(cr, kFrameColour);
  cairo_set_line_width(cr, 1.0);
  cairo_set_dash(cr, nullptr, 0, 0.0);
  cairo_rectangle(cr, 0.5, map_top + 0.5, layout.width_px - 1.0, map_h - 1.0);
  cairo_stroke(cr);

  DrawHeader(cr, image, layout, path_style, odometry_style, truth_style);
  DrawScaleBar(cr, layout);
  DrawColourBar(cr, layout, max_use);
}

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* cr) const { cairo_destroy(cr); }
};
using SurfacePtr = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using ContextPtr = std::unique_ptr<cairo_t, ContextDeleter>;

Status DrawOnSurface(cairo_surface_t* surface, const MapImage& image, const MapLayout& layout,
                     std::string_view what) {
  if (cairo_surface_status(surface) != CAIRO_STATUS_SUCCESS) {
    return CairoError(cairo_surface_status(surface), what);
  }
  ContextPtr cr(cairo_create(surface));
  Draw(cr.get(), image, layout);
  if (cairo_status(cr.get()) != CAIRO_STATUS_SUCCESS)
    return CairoError(cairo_status(cr.get()), what);
  return Status::Ok();
}

}  // namespace

double ScaleBarLengthM(double max_m) {
  if (!std::isfinite(max_m) || max_m <= 0.0) return 0.0;
  int k = static_cast<int>(std::floor(std::log10(max_m)));
  // log10 is not exact: 1000 may come out as 2.9999...
  if (std::pow(10.0, k + 1) <= max_m) ++k;
  double unit = std::pow(10.0, k);
  for (double m : {5.0, 2.0}) {
    if (m * unit <= max_m) return m * unit;
  }
  return unit;
}

std::vector<PixelPoint> DecimatePolyline(const std::vector<PixelPoint>& points,
                                         double tolerance_px) {
  return Decimate(
      points.size(), [&](size_t i) { return points[i]; }, tolerance_px);
}

RenderPoint HexCenter(int32_t q, int32_t r, double hex_radius_m) {
  return {hex_radius_m * kSqrt3 * (q + r / 2.0), 1.5 * hex_radius_m * r};
}

StatusOr<MapLayout> ComputeMapLayout(const MapImage& image, const RenderOptions& options) {
  if (options.width_px < kMinWidthPx || options.width_px > kMaxWidthPx) {
    return InvalidArgumentError(fmt::format("width_px = {} is outside [{}, {}]", options.width_px,
                                            kMinWidthPx, kMaxWidthPx));
  }
  if (!std::isfinite(options.margin_m) || options.margin_m < 0.0) {
    return InvalidArgumentError(
        fmt::format("margin_m = {} must be finite and >= 0", options.margin_m));
  }
  if (!std::isfinite(image.hex_radius_m) || image.hex_radius_m <= 0.0) {
    return InvalidArgumentError(
        fmt::format("hex_radius_m = {} must be finite and > 0", image.hex_radius_m));
  }
  GROVE_RETURN_IF_ERROR(CheckPoints(image.path, "path"));
  GROVE_RETURN_IF_ERROR(CheckPoints(image.odometry, "odometry"));
  GROVE_RETURN_IF_ERROR(CheckPoints(image.truth, "truth"));
  GROVE_RETURN_IF_ERROR(CheckPoints(image.landmarks_truth, "landmarks_truth"));
  for (size_t i = 0; i < image.landmarks.size(); ++i) {
    const RenderLandmark& l = image.landmarks[i];
    if (!std::isfinite(l.x_m) || !std::isfinite(l.y_m) || !std::isfinite(l.sxx) ||
        !std::isfinite(l.sxy) || !std::isfinite(l.syy) || l.sxx < 0 || l.syy < 0) {
      return InvalidArgumentError(fmt::format(
          "landmarks[{}] = ({}, {}) with covariance ({}, {}, {}) is not finite or not a "
          "covariance",
          i, l.x_m, l.y_m, l.sxx, l.sxy, l.syy));
    }
  }

  Box box;
  const double half_w = image.hex_radius_m * kSqrt3 / 2.0;
  for (size_t i = 0; i < image.hexes.size(); ++i) {
    const RenderHex& hex = image.hexes[i];
    if (!std::isfinite(hex.use) || hex.use < 0.0) {
      return InvalidArgumentError(fmt::format(
          "hexes[{}] ({}, {}): use = {} must be finite and >= 0", i, hex.q, hex.r, hex.use));
    }
    if (hex.use == 0.0) continue;
    RenderPoint c = HexCenter(hex.q, hex.r, image.hex_radius_m);
    box.Add(c.x_m - half_w, c.y_m - image.hex_radius_m, c.x_m + half_w, c.y_m + image.hex_radius_m);
  }
  for (const auto* points : {&image.path, &image.odometry, &image.truth, &image.landmarks_truth}) {
    for (const RenderPoint& p : *points) box.Add(p.x_m, p.y_m, p.x_m, p.y_m);
  }
  for (const RenderLandmark& l : image.landmarks) box.Add(l.x_m, l.y_m, l.x_m, l.y_m);
  if (box.empty()) box.Add(0, 0, 0, 0);
  box.Add(box.min_x - options.margin_m, box.min_y - options.margin_m, box.max_x + options.margin_m,
          box.max_y + options.margin_m);
  // A single point with no margin still needs an area to draw into.
  constexpr double kMinExtentM = 1.0;
  double width_m = box.max_x - box.min_x;
  double height_m = box.max_y - box.min_y;
  if (width_m < kMinExtentM) {
    box.min_x -= (kMinExtentM - width_m) / 2;
    width_m = kMinExtentM;
  }
  if (height_m < kMinExtentM) {
    box.min_y -= (kMinExtentM - height_m) / 2;
    height_m = kMinExtentM;
  }

  MapLayout layout;
  layout.width_px = options.width_px;
  layout.font_px = std::max(11.0, options.width_px / 90.0);
  int header_rows = (image.title.empty() ? 0 : 1) + (LegendEntries(image) > 0 ? 1 : 0);
  layout.header_px = std::round(layout.font_px * (0.8 + 1.6 * header_rows));
  layout.footer_px = std::round(layout.font_px * 2.6);
  const double map_w = options.width_px;
  // Very wide or very tall content is letterboxed rather than giving an extreme image.
  const double map_h = std::round(std::clamp(map_w * height_m / width_m, map_w / 4.0, map_w * 2.0));
  layout.px_per_m = std::min(map_w / width_m, map_h / height_m);
  if (!std::isfinite(layout.px_per_m) || layout.px_per_m <= 0.0) {
    return InvalidArgumentError(
        fmt::format("content extent {} m x {} m cannot be drawn", width_m, height_m));
  }
  layout.height_px = static_cast<int>(layout.header_px + map_h + layout.footer_px);
  layout.min_x_m = box.min_x;
  layout.min_y_m = box.min_y;
  layout.origin_x_px = (map_w - width_m * layout.px_per_m) / 2.0;
  layout.origin_y_px = layout.header_px + map_h - (map_h - height_m * layout.px_per_m) / 2.0;
  return layout;
}

StatusOr<std::string> RenderPng(const MapImage& image, const RenderOptions& options) {
  StatusOr<MapLayout> layout = ComputeMapLayout(image, options);
  if (!layout.ok()) return layout.status();
  SurfacePtr surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, layout->width_px, layout->height_px));
  GROVE_RETURN_IF_ERROR(DrawOnSurface(surface.get(), image, *layout, "rendering the PNG map"));
  std::string png;
  cairo_status_t status = cairo_surface_write_to_png_stream(surface.get(), AppendToString, &png);
  if (status != CAIRO_STATUS_SUCCESS) return CairoError(status, "encoding the PNG map");
  return png;
}

namespace {

// cairo names an SVG's groups after its surfaces, numbered across the whole process: the same
// map drawn after other images would differ. Renumbers them 1, 2, ... in order of appearance.
std::string RenumberSurfaces(const std::string& svg) {
  constexpr std::string_view kName = "surface";
  std::map<std::string, std::string> numbers;
  std::string out;
  out.reserve(svg.size());
  size_t at = 0;
  for (size_t found; (found = svg.find(kName, at)) != std::string::npos;) {
    size_t end = found + kName.size();
    while (end < svg.size() && svg[end] >= '0' && svg[end] <= '9') ++end;
    out.append(svg, at, found + kName.size() - at);
    const std::string number = svg.substr(found + kName.size(), end - found - kName.size());
    if (!number.empty()) {
      auto [it, added] = numbers.emplace(number, "");
      if (added) it->second = std::to_string(numbers.size());
      out += it->second;
    }
    at = end;
  }
  out.append(svg, at, std::string::npos);
  return out;
}

}  // namespace

StatusOr<std::string> RenderSvg(const MapImage& image, const RenderOptions& options) {
  StatusOr<MapLayout> layout = ComputeMapLayout(image, options);
  if (!layout.ok()) return layout.status();
  std::string svg;
  SurfacePtr surface(cairo_svg_surface_create_for_stream(AppendToString, &svg, layout->width_px,
                                                         layout->height_px));
  cairo_svg_surface_set_document_unit(surface.get(), CAIRO_SVG_UNIT_PX);
  GROVE_RETURN_IF_ERROR(DrawOnSurface(surface.get(), image, *layout, "rendering the SVG map"));
  // The SVG is only complete once the surface is finished.
  cairo_surface_finish(surface.get());
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    return CairoError(cairo_surface_status(surface.get()), "encoding the SVG map");
  }
  return RenumberSurfaces(svg);
}

Status WriteMapImages(const std::string& png_path, const std::string& svg_path,
                      const MapImage& image, const RenderOptions& options) {
  std::string png, svg;
  if (!png_path.empty()) {
    StatusOr<std::string> bytes = RenderPng(image, options);
    if (!bytes.ok()) return bytes.status();
    png = std::move(bytes).value();
  }
  if (!svg_path.empty()) {
    StatusOr<std::string> text = RenderSvg(image, options);
    if (!text.ok()) return text.status();
    svg = std::move(text).value();
  }
  if (!png_path.empty()) GROVE_RETURN_IF_ERROR(WriteFileAtomically(png_path, png));
  if (!svg_path.empty()) GROVE_RETURN_IF_ERROR(WriteFileAtomically(svg_path, svg));
  return Status::Ok();
}

}  // namespace grove::tools

// Map images (PNG and SVG, drawn with cairo) in the style of the FootSLAM paper's Figure 8: the
// hexagons shaded by use, the heaviest particle's path, the raw odometry and optional truth; for a
// landmark map, the landmarks with their 2-sigma ellipses and the true landmarks.
#ifndef GROVE_TOOLS_REPORT_MAP_RENDER_H_
#define GROVE_TOOLS_REPORT_MAP_RENDER_H_

#include <cstdint>
#include <string>
#include <vector>

#include "grove/status.h"

namespace grove::tools {

// A hexagon in axial coordinates; `use` is its total (weighted) transition count, >= 0.
struct RenderHex {
  int32_t q = 0;
  int32_t r = 0;
  double use = 0.0;
};

struct RenderPoint {
  double x_m = 0.0;
  double y_m = 0.0;
};

// A landmark estimate: its mean and covariance (m^2), drawn as a dot with its 2-sigma ellipse.
struct RenderLandmark {
  double x_m = 0.0;
  double y_m = 0.0;
  double sxx = 0.0;
  double sxy = 0.0;
  double syy = 0.0;
};

struct MapImage {
  // Pointy-top hexagons with circumradius R; the centre of (q, r) is
  // x = R * sqrt(3) * (q + r / 2), y = 1.5 * R * r.
  double hex_radius_m = 1.0;
  std::vector<RenderHex> hexes;                         // hexes with use 0 are not drawn
  std::vector<RenderPoint> path;                        // the estimated path: solid dark red
  std::string path_label = "path (heaviest particle)";  // its legend entry
  std::vector<RenderPoint> odometry;                    // raw odometry: thin dashed blue
  std::vector<RenderPoint> truth;                       // optional ground truth: green
  std::string truth_label = "ground truth";             // its legend entry
  std::vector<RenderLandmark> landmarks;     // estimated landmarks: orange, 2-sigma ellipses
  std::vector<RenderPoint> landmarks_truth;  // true landmarks: green crosses
  std::string title;
};

struct RenderOptions {
  int width_px = 1600;    // [200, 8192]; the height follows from the content's aspect ratio
  double margin_m = 2.0;  // around the content, >= 0
};

// Where the map lands in the image: a title/legend band on top, the map area, and a footer band
// with the scale bar and the colour bar. World y points up.
struct MapLayout {
  int width_px = 0;
  int height_px = 0;
  double px_per_m = 0.0;
  double min_x_m = 0.0;  // world point drawn at (origin_x_px, origin_y_px)
  double min_y_m = 0.0;
  double origin_x_px = 0.0;
  double origin_y_px = 0.0;  // device y of world min_y_m (bottom of the content)
  double header_px = 0.0;
  double footer_px = 0.0;
  double font_px = 0.0;

  double XPx(double x_m) const { return origin_x_px + (x_m - min_x_m) * px_per_m; }
  double YPx(double y_m) const { return origin_y_px - (y_m - min_y_m) * px_per_m; }
};

// A point in device space (pixels, y down).
struct PixelPoint {
  double x_px = 0.0;
  double y_px = 0.0;
};

// The points of a polyline worth drawing at `tolerance_px`: the first and the last, and each one
// at least `tolerance_px` from the point kept before it. Kept points are not moved, and every
// point dropped lies within `tolerance_px` of the kept point before it, so the drawn line passes
// that close to every input point. A polyline whose segments are shorter than the tolerance thus
// keeps at most 2 + (its length / tolerance_px) points, however many it had. REQUIRES:
// tolerance_px >= 0.
std::vector<PixelPoint> DecimatePolyline(const std::vector<PixelPoint>& points,
                                         double tolerance_px);

// Returns the centre of hexagon (q, r) in metres.
RenderPoint HexCenter(int32_t q, int32_t r, double hex_radius_m);

// The scale bar's length: the largest 1, 2 or 5 x 10^k metres not longer than `max_m`.
double ScaleBarLengthM(double max_m);

// Validates `image` and `options` (finite coordinates, use >= 0, hex_radius_m > 0) and fits the
// content plus margin into the map area. Empty content is valid: a blank map around the origin.
StatusOr<MapLayout> ComputeMapLayout(const MapImage& image, const RenderOptions& options = {});

// Both return the encoded file (PNG bytes, SVG text). Empty content gives an image with the frame,
// title and scale bar only. Polylines are decimated at half a pixel (DecimatePolyline) and stroked
// in pieces of a bounded number of points: one path of a million self-overlapping segments costs
// cairo's stroker time quadratic in its crossings, pieces cost time linear in the points.
StatusOr<std::string> RenderPng(const MapImage& image, const RenderOptions& options = {});
StatusOr<std::string> RenderSvg(const MapImage& image, const RenderOptions& options = {});

// Renders both images and writes each with WriteFileAtomically; nothing is written unless both
// renderings succeed. An empty path skips that format.
Status WriteMapImages(const std::string& png_path, const std::string& svg_path,
                      const MapImage& image, const RenderOptions& options = {});

}  // namespace grove::tools

#endif  // GROVE_TOOLS_REPORT_MAP_RENDER_H_

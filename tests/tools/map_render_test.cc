#include "tools/report/map_render.h"

// Rooted at /usr/include: cairo is a private dependency of grove_tools, so its include path
// does not reach this test.
#include <cairo/cairo.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "tests/tools/decoded_png.h"
#include "tools/io/atomic_file.h"

namespace grove::tools {
namespace {

using test_images::DecodedPng;
using test_images::ExpectColourNear;
using test_images::kWhite;
using test_images::Rgb8;

// The renderer's documented colours, in 8 bits.
constexpr Rgb8 kPathRgb = {179, 13, 26};
constexpr Rgb8 kTruthRgb = {26, 158, 51};

MapImage HexMap() {
  MapImage image;
  image.hex_radius_m = 0.5;
  image.title = "test map";
  image.hexes = {{0, 0, 1000.0}, {1, 0, 300.0}, {5, 0, 1.0}, {6, 0, 0.0}};
  return image;
}

TEST(HexCenterTest, FollowsPointyTopAxialFormula) {
  RenderPoint c = HexCenter(2, -1, 0.5);
  EXPECT_DOUBLE_EQ(c.x_m, 0.5 * std::sqrt(3.0) * 1.5);
  EXPECT_DOUBLE_EQ(c.y_m, -0.75);
  RenderPoint origin = HexCenter(0, 0, 2.0);
  EXPECT_EQ(origin.x_m, 0.0);
  EXPECT_EQ(origin.y_m, 0.0);
}

TEST(ScaleBarLengthTest, PicksLargestOneTwoOrFiveTimesPowerOfTen) {
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(9.9), 5.0);
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(10.0), 10.0);
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(19.0), 10.0);
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(20.0), 20.0);
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(1000.0), 1000.0);
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(0.3), 0.2);
  EXPECT_DOUBLE_EQ(ScaleBarLengthM(0.07), 0.05);
}

TEST(MapLayoutTest, FitsAllContentWithTheMarginAndPutsYUp) {
  MapImage image = HexMap();
  image.path = {{-3.0, 4.0}, {10.0, -2.0}};
  RenderOptions options{800, 2.0};
  StatusOr<MapLayout> layout = ComputeMapLayout(image, options);
  ASSERT_TRUE(layout.ok()) << layout.status().ToString();
  EXPECT_EQ(layout->width_px, 800);
  const double top = layout->header_px;
  const double bottom = layout->height_px - layout->footer_px;
  const double margin_px = options.margin_m * layout->px_per_m;
  for (const RenderPoint& p : image.path) {
    EXPECT_GE(layout->XPx(p.x_m), margin_px - 1e-6);
    EXPECT_LE(layout->XPx(p.x_m), 800 - margin_px + 1e-6);
    EXPECT_GE(layout->YPx(p.y_m), top + margin_px - 1e-6);
    EXPECT_LE(layout->YPx(p.y_m), bottom - margin_px + 1e-6);
  }
  // The x extent (13 m + 2 margins) is the wider one, so it fills the width exactly.
  EXPECT_NEAR(layout->px_per_m, 800.0 / 17.0, 1e-9);
  EXPECT_LT(layout->YPx(4.0), layout->YPx(-2.0));
}

TEST(MapLayoutTest, VeryWideContentIsLetterboxedNotFlattened) {
  MapImage image;
  image.path = {{0.0, 0.0}, {1000.0, 0.0}};
  StatusOr<MapLayout> layout = ComputeMapLayout(image, {800, 0.0});
  ASSERT_TRUE(layout.ok());
  double map_h = layout->height_px - layout->header_px - layout->footer_px;
  EXPECT_NEAR(map_h, 200.0, 1.0);
  // The line is centred vertically in the map area.
  EXPECT_NEAR(layout->YPx(0.0), layout->header_px + map_h / 2, 1.0);
}

TEST(MapLayoutTest, RejectsInvalidInputWithTheFieldName) {
  MapImage image = HexMap();
  image.path = {{0.0, std::nan("")}};
  StatusOr<MapLayout> layout = ComputeMapLayout(image);
  EXPECT_EQ(layout.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(layout.status().message().find("path[0]"), std::string::npos);

  image = HexMap();
  image.hexes[1].use = -1.0;
  EXPECT_EQ(ComputeMapLayout(image).status().code(), StatusCode::kInvalidArgument);

  image = HexMap();
  image.hex_radius_m = 0.0;
  EXPECT_NE(ComputeMapLayout(image).status().message().find("hex_radius_m"), std::string::npos);

  EXPECT_EQ(ComputeMapLayout(HexMap(), {10, 2.0}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ComputeMapLayout(HexMap(), {800, -1.0}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(RenderPng(HexMap(), {10, 2.0}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(RenderSvg(HexMap(), {10, 2.0}).status().code(), StatusCode::kInvalidArgument);
}

TEST(RenderPngTest, StartsWithPngSignatureAndDecodesToRequestedWidth) {
  MapImage image = HexMap();
  StatusOr<std::string> png = RenderPng(image, {640, 2.0});
  ASSERT_TRUE(png.ok()) << png.status().ToString();
  ASSERT_GE(png->size(), 8u);
  EXPECT_EQ(png->substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  DecodedPng decoded(*png);
  ASSERT_TRUE(decoded.ok());
  EXPECT_EQ(decoded.width(), 640);
  EXPECT_EQ(decoded.height(), ComputeMapLayout(image, {640, 2.0})->height_px);
}

TEST(RenderPngTest, HeavilyUsedHexIsDarkerThanLightlyUsedHexAndEmptyGround) {
  MapImage image = HexMap();
  RenderOptions options{800, 2.0};
  StatusOr<MapLayout> layout = ComputeMapLayout(image, options);
  StatusOr<std::string> png = RenderPng(image, options);
  ASSERT_TRUE(layout.ok() && png.ok());
  DecodedPng decoded(*png);
  ASSERT_TRUE(decoded.ok());
  auto pixel_at_hex = [&](int q, int r) {
    RenderPoint c = HexCenter(q, r, image.hex_radius_m);
    return decoded.At(layout->XPx(c.x_m), layout->YPx(c.y_m));
  };
  Rgb8 heavy = pixel_at_hex(0, 0);
  Rgb8 medium = pixel_at_hex(1, 0);
  Rgb8 light = pixel_at_hex(5, 0);
  Rgb8 absent = pixel_at_hex(3, 0);    // not in the map
  Rgb8 zero_use = pixel_at_hex(6, 0);  // listed with use 0: not drawn
  EXPECT_LT(heavy.Luma(), medium.Luma());
  EXPECT_LT(medium.Luma(), light.Luma());
  EXPECT_LT(light.Luma(), absent.Luma());
  EXPECT_LT(heavy.Luma(), 80);
  ExpectColourNear(absent, kWhite, 0);
  ExpectColourNear(zero_use, kWhite, 0);
  // Light-to-dark runs from yellowish to blue: the heaviest hex is more blue than red.
  EXPECT_GT(heavy.b, heavy.r);
  EXPECT_GE(light.r, light.b);
}

TEST(RenderPngTest, PathAndTruthPixelsHaveTheirColours) {
  MapImage image;
  image.path = {{0.0, 0.0}, {4.0, 0.0}, {10.0, 0.0}};
  image.truth = {{0.0, 3.0}, {10.0, 3.0}};
  image.odometry = {{0.0, 6.0}, {10.0, 6.0}};
  RenderOptions options{1000, 1.0};
  StatusOr<MapLayout> layout = ComputeMapLayout(image, options);
  StatusOr<std::string> png = RenderPng(image, options);
  ASSERT_TRUE(layout.ok() && png.ok());
  DecodedPng decoded(*png);
  ASSERT_TRUE(decoded.ok());
  ExpectColourNear(decoded.NearestAlongColumn(layout->XPx(7.0), layout->YPx(0.0), kPathRgb),
                   kPathRgb, 3);
  ExpectColourNear(decoded.NearestAlongColumn(layout->XPx(7.0), layout->YPx(3.0), kTruthRgb),
                   kTruthRgb, 3);
  // Between the lines there is only background.
  ExpectColourNear(decoded.At(layout->XPx(7.0), layout->YPx(1.5)), kWhite, 0);
  // The dashed odometry line leaves some blue pixels along its length.
  int blue = 0;
  for (double x = 1.0; x < 9.0; x += 0.05) {
    Rgb8 p = decoded.At(layout->XPx(x), layout->YPx(6.0));
    if (p.b > 200 && p.r < 120) ++blue;
  }
  EXPECT_GT(blue, 10);
}

// A random walk in device space with steps of up to `max_step_px`, from (x0, y0).
std::vector<PixelPoint> RandomWalkPx(size_t n, double max_step_px, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<PixelPoint> points;
  points.reserve(n);
  PixelPoint p{800.0, 500.0};
  for (size_t i = 0; i < n; ++i) {
    points.push_back(p);
    const double angle = 2.0 * std::acos(-1.0) * unit(rng);
    const double step = max_step_px * unit(rng);
    p.x_px = std::clamp(p.x_px + step * std::cos(angle), 0.0, 1600.0);
    p.y_px = std::clamp(p.y_px + step * std::sin(angle), 0.0, 1000.0);
  }
  return points;
}

bool SamePoint(const PixelPoint& a, const PixelPoint& b) {
  return a.x_px == b.x_px && a.y_px == b.y_px;
}

TEST(DecimatePolylineTest, KeepsTheEndsAndMovesNoPointByMoreThanTheTolerance) {
  constexpr double kTolerance = 0.5;
  const std::vector<PixelPoint> points = RandomWalkPx(20000, 2.0, 7);
  const std::vector<PixelPoint> kept = DecimatePolyline(points, kTolerance);
  ASSERT_GE(kept.size(), 2u);
  EXPECT_LT(kept.size(), points.size());
  EXPECT_TRUE(SamePoint(kept.front(), points.front()));
  EXPECT_TRUE(SamePoint(kept.back(), points.back()));
  // The kept points are input points, unmoved and in order; each dropped one is within the
  // tolerance of the kept point before it; kept neighbours (but the last) are that far apart.
  size_t k = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (k + 1 < kept.size() && SamePoint(points[i], kept[k + 1]) &&
        (k + 2 < kept.size() || i + 1 == points.size())) {
      ++k;
      if (k + 1 < kept.size()) {
        EXPECT_GE(std::hypot(kept[k].x_px - kept[k - 1].x_px, kept[k].y_px - kept[k - 1].y_px),
                  kTolerance)
            << "kept point " << k;
      }
      continue;
    }
    if (i == 0) continue;
    EXPECT_LT(std::hypot(points[i].x_px - kept[k].x_px, points[i].y_px - kept[k].y_px), kTolerance)
        << "input point " << i << " is not near kept point " << k;
  }
  EXPECT_EQ(k + 1, kept.size()) << "a kept point is not an input point in order";
}

TEST(DecimatePolylineTest, HalfAMillionDensePointsBecomeAtMostTheirLengthOverTheTolerance) {
  // A long walk drawn small: 500k points, steps below a tenth of a pixel, in a 1600 x 1000 image.
  constexpr double kTolerance = 0.5;
  const std::vector<PixelPoint> points = RandomWalkPx(500000, 0.1, 11);
  double length_px = 0.0;
  for (size_t i = 1; i < points.size(); ++i) {
    length_px +=
        std::hypot(points[i].x_px - points[i - 1].x_px, points[i].y_px - points[i - 1].y_px);
  }
  const std::vector<PixelPoint> kept = DecimatePolyline(points, kTolerance);
  EXPECT_LE(static_cast<double>(kept.size()), 2.0 + length_px / kTolerance);
  EXPECT_LT(kept.size(), 60000u);  // the bound above is 2 + 25,000 px / 0.5 px = 50,002
}

TEST(DecimatePolylineTest, SmallInputsKeepEveryEnd) {
  EXPECT_TRUE(DecimatePolyline({}, 0.5).empty());
  EXPECT_EQ(DecimatePolyline({{1.0, 2.0}}, 0.5).size(), 1u);
  // A path that returns to its start is still drawn: a dot of both ends.
  EXPECT_EQ(DecimatePolyline({{1.0, 2.0}, {1.1, 2.0}, {1.0, 2.0}}, 0.5).size(), 2u);
  EXPECT_EQ(DecimatePolyline({{0.0, 0.0}, {0.2, 0.0}, {0.6, 0.0}, {0.7, 0.0}}, 0.5).size(), 3u);
}

// The odometry's dashes run on across the pieces a long line is stroked in: a straight line of
// 2,000 points shows the same dashes as the same line of 2 points.
TEST(RenderPngTest, DashesOfALongLineContinueAcrossStrokedPieces) {
  RenderOptions options{1000, 1.0};
  MapImage two_points;
  two_points.odometry = {{0.0, 0.0}, {100.0, 0.0}};
  MapImage many_points;
  for (int i = 0; i <= 2000; ++i) many_points.odometry.push_back({i * 0.05, 0.0});
  StatusOr<MapLayout> layout = ComputeMapLayout(two_points, options);
  StatusOr<std::string> reference = RenderPng(two_points, options);
  StatusOr<std::string> pieces = RenderPng(many_points, options);
  ASSERT_TRUE(layout.ok() && reference.ok() && pieces.ok());
  DecodedPng a(*reference);
  DecodedPng b(*pieces);
  ASSERT_TRUE(a.ok() && b.ok());
  int inked = 0;
  int differ = 0;
  int columns = 0;
  for (double x = layout->XPx(1.0); x < layout->XPx(99.0); x += 1.0, ++columns) {
    const bool ink_a = test_images::Distance(a.At(x, layout->YPx(0.0)), kWhite) > 60;
    const bool ink_b = test_images::Distance(b.At(x, layout->YPx(0.0)), kWhite) > 60;
    inked += ink_a;
    differ += ink_a != ink_b;
  }
  // Dashes, not a solid line or nothing; and where they are, up to antialiasing at their ends.
  EXPECT_GT(inked, columns / 3);
  EXPECT_LT(inked, columns * 5 / 6);
  EXPECT_LE(differ, columns / 50) << inked << " of " << columns << " columns inked";
}

TEST(RenderPngTest, PathIsDrawnOverHexes) {
  MapImage image = HexMap();
  image.path = {{-1.0, 0.0}, {1.0, 0.0}};
  RenderOptions options{800, 2.0};
  StatusOr<MapLayout> layout = ComputeMapLayout(image, options);
  StatusOr<std::string> png = RenderPng(image, options);
  ASSERT_TRUE(layout.ok() && png.ok());
  DecodedPng decoded(*png);
  ExpectColourNear(decoded.NearestAlongColumn(layout->XPx(0.0), layout->YPx(0.0), kPathRgb),
                   kPathRgb, 3);
}

TEST(RenderPngTest, EmptyInputGivesBlankMapWithFrame) {
  MapImage image;
  StatusOr<MapLayout> layout = ComputeMapLayout(image, {400, 2.0});
  StatusOr<std::string> png = RenderPng(image, {400, 2.0});
  ASSERT_TRUE(layout.ok() && png.ok()) << png.status().ToString();
  DecodedPng decoded(*png);
  ASSERT_TRUE(decoded.ok());
  EXPECT_EQ(decoded.width(), 400);
  ExpectColourNear(decoded.At(layout->XPx(0.0), layout->YPx(0.0)), kWhite, 0);
  // The frame's left edge runs through the map area.
  Rgb8 frame = decoded.At(0.5, layout->YPx(0.0));
  EXPECT_LT(frame.Luma(), 250);
  StatusOr<std::string> svg = RenderSvg(image, {400, 2.0});
  ASSERT_TRUE(svg.ok());
  EXPECT_NE(svg->find("<svg"), std::string::npos);
}

TEST(RenderSvgTest, IsAnSvgDocumentOfTheRequestedPixelSize) {
  MapImage image = HexMap();
  image.path = {{0.0, 0.0}, {3.0, 1.0}};
  StatusOr<std::string> svg = RenderSvg(image, {700, 2.0});
  ASSERT_TRUE(svg.ok()) << svg.status().ToString();
  EXPECT_NE(svg->find("<svg"), std::string::npos);
  EXPECT_NE(svg->find("width=\"700px\""), std::string::npos);
  EXPECT_NE(svg->find("</svg>"), std::string::npos);
}

TEST(RenderSvgTest, SizeGrowsAboutLinearlyWithHexCount) {
  MapImage image;
  image.hex_radius_m = 0.5;
  for (int q = 0; q < 100; ++q) {
    for (int r = 0; r < 100; ++r) image.hexes.push_back({q, r, 1.0 + (q * r) % 50});
  }
  StatusOr<std::string> svg = RenderSvg(image, {1600, 2.0});
  ASSERT_TRUE(svg.ok());
  // Hexes are grouped by colour level, so each costs only its coordinates.
  EXPECT_LT(svg->size(), 120u * image.hexes.size()) << svg->size();
}

class WriteMapImagesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        (std::filesystem::path(::testing::TempDir()) / ("map_render_" + std::to_string(::getpid())))
            .string();
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  static std::string ReadFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  std::string dir_;
};

TEST_F(WriteMapImagesTest, WritesBothFiles) {
  MapImage image = HexMap();
  ASSERT_TRUE(WriteMapImages(dir_ + "/map.png", dir_ + "/map.svg", image, {400, 2.0}).ok());
  EXPECT_EQ(ReadFile(dir_ + "/map.png").substr(0, 4), "\x89PNG");
  EXPECT_NE(ReadFile(dir_ + "/map.svg").find("<svg"), std::string::npos);
}

TEST_F(WriteMapImagesTest, InvalidImageLeavesEarlierOutputsUntouched) {
  ASSERT_TRUE(WriteFileAtomically(dir_ + "/map.png", "old png").ok());
  ASSERT_TRUE(WriteFileAtomically(dir_ + "/map.svg", "old svg").ok());
  MapImage image = HexMap();
  image.truth = {{std::numeric_limits<double>::infinity(), 0.0}};
  Status status = WriteMapImages(dir_ + "/map.png", dir_ + "/map.svg", image, {400, 2.0});
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ReadFile(dir_ + "/map.png"), "old png");
  EXPECT_EQ(ReadFile(dir_ + "/map.svg"), "old svg");
}

}  // namespace
}  // namespace grove::tools

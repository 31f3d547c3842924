// Reading pixels back from a rendered PNG, for the image tests (map_render_test, chart_test).
#ifndef GROVE_TESTS_TOOLS_DECODED_PNG_H_
#define GROVE_TESTS_TOOLS_DECODED_PNG_H_

#include <cairo/cairo.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

namespace grove::tools::test_images {

struct Rgb8 {
  int r, g, b;
  int Luma() const { return (299 * r + 587 * g + 114 * b) / 1000; }
};

inline constexpr Rgb8 kWhite = {255, 255, 255};

// Sum of the channel differences.
inline int Distance(const Rgb8& a, const Rgb8& b) {
  return std::abs(a.r - b.r) + std::abs(a.g - b.g) + std::abs(a.b - b.b);
}

inline void ExpectColourNear(const Rgb8& actual, const Rgb8& expected, int tolerance) {
  EXPECT_NEAR(actual.r, expected.r, tolerance);
  EXPECT_NEAR(actual.g, expected.g, tolerance);
  EXPECT_NEAR(actual.b, expected.b, tolerance);
}

// A PNG decoded back with cairo.
class DecodedPng {
 public:
  explicit DecodedPng(const std::string& png) : png_(png) {
    surface_.reset(cairo_image_surface_create_from_png_stream(&DecodedPng::Read, this));
  }
  bool ok() const { return cairo_surface_status(surface_.get()) == CAIRO_STATUS_SUCCESS; }
  int width() const { return cairo_image_surface_get_width(surface_.get()); }
  int height() const { return cairo_image_surface_get_height(surface_.get()); }
  // The pixel containing (x_px, y_px); a test failure and an impossible colour outside.
  Rgb8 At(double x_px, double y_px) const {
    int x = static_cast<int>(std::floor(x_px));
    int y = static_cast<int>(std::floor(y_px));
    EXPECT_TRUE(x >= 0 && x < width() && y >= 0 && y < height()) << x << "," << y;
    if (x < 0 || x >= width() || y < 0 || y >= height()) return {-1000, -1000, -1000};
    cairo_surface_flush(surface_.get());
    const unsigned char* row = cairo_image_surface_get_data(surface_.get()) +
                               y * cairo_image_surface_get_stride(surface_.get());
    uint32_t pixel;
    std::memcpy(&pixel, row + 4 * x, 4);
    return {static_cast<int>((pixel >> 16) & 255), static_cast<int>((pixel >> 8) & 255),
            static_cast<int>(pixel & 255)};
  }
  // The pixel nearest to `expected` among those within a pixel of (x_px, y_px) vertically: a
  // horizontal line of width >= 2 px fully covers one of them, wherever it falls on the grid.
  Rgb8 NearestAlongColumn(double x_px, double y_px, const Rgb8& expected) const {
    Rgb8 best{-1000, -1000, -1000};
    for (double dy : {-1.0, 0.0, 1.0}) {
      Rgb8 c = At(x_px, y_px + dy);
      if (Distance(c, expected) < Distance(best, expected)) best = c;
    }
    return best;
  }

 private:
  static cairo_status_t Read(void* closure, unsigned char* data, unsigned int length) {
    auto* self = static_cast<DecodedPng*>(closure);
    if (self->offset_ + length > self->png_.size()) return CAIRO_STATUS_READ_ERROR;
    std::memcpy(data, self->png_.data() + self->offset_, length);
    self->offset_ += length;
    return CAIRO_STATUS_SUCCESS;
  }
  struct Deleter {
    void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
  };
  std::string png_;
  size_t offset_ = 0;
  std::unique_ptr<cairo_surface_t, Deleter> surface_;
};

}  // namespace grove::tools::test_images

#endif  // GROVE_TESTS_TOOLS_DECODED_PNG_H_

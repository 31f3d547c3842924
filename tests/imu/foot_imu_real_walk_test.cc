// The foot IMU front end on x-io's two real walks (tools/data/foot_imu/, closed loops recorded at
// about 400 Hz with irregular times): the foot must end where it started, at least as closely as
// the vendor's own drift-removal method does (82 mm and 421 mm).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "grove/foot_imu.h"
#include "tools/io/imu_reader.h"
#include "tools/io/imu_step_source.h"

namespace grove {
namespace {

struct Loop {
  int steps = 0;
  double closure_m = 0;  // horizontal distance from the first stance to the last
  double distance_m = 0;
};

Loop WalkLoop(const std::string& name, const FootImuConfig& config) {
  const std::string path = std::string(GROVE_SOURCE_DIR) + "/tools/data/foot_imu/" + name;
  tools::ImuReaderOptions options;
  options.accel_range_mps2 = config.accel_range_mps2;
  options.gyro_range_radps = config.gyro_range_radps;
  options.max_interval_s = config.max_sample_interval_s;
  auto source = tools::ImuStepSource::Open(path, config, options);
  EXPECT_TRUE(source.ok()) << source.status().ToString();
  if (!source.ok()) return {};
  Loop loop;
  double x = 0, y = 0;
  FootStep step;
  int64_t line = 0;
  for (;;) {
    StatusOr<bool> more = source->Next(&step, &line);
    EXPECT_TRUE(more.ok()) << more.status().ToString();
    if (!more.ok() || !*more) break;
    ++loop.steps;
    x += step.dx_m;
    y += step.dy_m;
    loop.distance_m += std::hypot(step.dx_m, step.dy_m);
  }
  loop.closure_m = std::hypot(x, y);
  std::fprintf(stderr, "%s: %d steps, %.2f m walked, ends %.3f m from the start (%.2f %%)\n",
               name.c_str(), loop.steps, loop.distance_m, loop.closure_m,
               100 * loop.closure_m / loop.distance_m);
  return loop;
}

TEST(FootImuRealWalkTest, ShortWalkClosesAsWellAsTheVendorsMethod) {
  const Loop loop = WalkLoop("short_walk.csv.gz", FootImuConfig());
  EXPECT_EQ(loop.steps, 16);
  EXPECT_NEAR(loop.distance_m, 23, 2);
  EXPECT_LE(loop.closure_m, 0.082);
}

TEST(FootImuRealWalkTest, LongWalkClosesAsWellAsTheVendorsMethod) {
  const Loop loop = WalkLoop("long_walk.csv.gz", FootImuConfig());
  EXPECT_EQ(loop.steps, 36);
  EXPECT_NEAR(loop.distance_m, 57, 3);
  EXPECT_LE(loop.closure_m, 0.421);
}

// The window scaled to the rate as FootImuConfig suggests (10 samples at 400 Hz) closes as well.
TEST(FootImuRealWalkTest, WindowScaledToTheRateClosesBothWalks) {
  FootImuConfig config;
  config.detector_window = 10;
  const Loop short_loop = WalkLoop("short_walk.csv.gz", config);
  const Loop long_loop = WalkLoop("long_walk.csv.gz", config);
  EXPECT_EQ(short_loop.steps, 16);
  EXPECT_LE(short_loop.closure_m, 0.082);
  EXPECT_GE(long_loop.steps, 35);
  EXPECT_LE(long_loop.closure_m, 0.421);
}

}  // namespace
}  // namespace grove

// Long-run stability: many thousands of steps around the same loop. Live map memory must stop
// growing once the area is mapped, and the live path history must stay near the bound of
// T + C * N * log N nodes for T steps and N particles (dead branches are freed).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "grove/footslam.h"
#include "tests/api/status_testing.h"

namespace grove {
namespace {

TEST(FootSlamLongRunTest, LiveMemoryStaysBounded) {
  FootSlamConfig config;
  config.particles = 1000;
  config.threads = 2;
  auto slam = FootSlam::Create(config);
  ASSERT_TRUE(slam.ok());
  const int kSteps = 20000;
  // A 20 m x 10 m rectangle walked again and again, 0.7 m steps, with a slow heading drift.
  const double perimeter = 60;
  // The live map size fluctuates with the particles' diversity: compare the peaks of each half.
  int64_t first_half_peak = 0, second_half_peak = 0;
  for (int k = 0; k < kSteps; ++k) {
    double s = std::fmod(k * 0.7, perimeter);
    double heading = s < 20 ? 0 : s < 30 ? M_PI / 2 : s < 50 ? M_PI : 3 * M_PI / 2;
    heading += 0.002 * std::sin(k * 0.001);
    Status st = (*slam)->Step(0.5 * (k + 1), 0.7 * std::cos(heading), 0.7 * std::sin(heading));
    ASSERT_TRUE(st.ok()) << st.ToString();
    if ((k + 1) % 500 == 0) {
      int64_t live = (*slam)->Summary().map_memory.live_nodes;
      int64_t& peak = k < kSteps / 2 ? first_half_peak : second_half_peak;
      peak = std::max(peak, live);
    }
  }
  FootSlamSummary summary = (*slam)->Summary();
  std::printf(
      "peak live map nodes: %ld in the first %d steps, %ld in the next; live history "
      "nodes at the end %ld\n",
      static_cast<long>(first_half_peak), kSteps / 2, static_cast<long>(second_half_peak),
      static_cast<long>(summary.trajectory_memory.live_nodes));
  EXPECT_LE(second_half_peak, first_half_peak * 3 / 2);
  const double n = static_cast<double>(config.particles);
  const double bound = kSteps + 10 * n * std::log2(n);
  EXPECT_LE(static_cast<double>(summary.trajectory_memory.live_nodes), bound);
  // Without freeing dead branches there would be one node per particle per step.
  EXPECT_LT(static_cast<double>(summary.trajectory_memory.live_nodes), 0.02 * n * kSteps);
  EXPECT_EQ(ValueOf((*slam)->HeaviestTrajectory()).size(), static_cast<size_t>(kSteps) + 1);
}

}  // namespace
}  // namespace grove

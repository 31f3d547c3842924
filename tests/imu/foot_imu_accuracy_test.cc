// The foot IMU front end on the simulator's recordings: an ideal sensor gives the true steps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "grove/foot_imu.h"
#include "tools/sim/foot_imu_simulator.h"
#include "tools/sim/walk_simulator.h"

namespace grove {
namespace {

constexpr double kPi = 3.14159265358979323846;

double Wrap(double a) {
  a = std::remainder(a, 2 * kPi);
  return a <= -kPi ? a + 2 * kPi : a;
}

struct WalkRun {
  tools::SimulatedFootImu imu;
  std::vector<FootStep> steps;
};

WalkRun RunWalk(double minutes, uint64_t seed, const tools::MemsModel& mems, FootImuConfig config) {
  tools::SimulatorOptions walk_options;
  walk_options.minutes = minutes;
  walk_options.seed = seed;
  auto walk = tools::SimulateWalk(walk_options);
  EXPECT_TRUE(walk.ok()) << walk.status().ToString();
  tools::FootImuSimOptions options;
  options.mems = mems;
  options.seed = seed;
  auto imu = tools::SimulateFootImu(*walk, options);
  EXPECT_TRUE(imu.ok()) << imu.status().ToString();
  config.alignment_heading_rad = imu->stances.front().heading_rad;
  auto engine = FootImu::Create(config);
  EXPECT_TRUE(engine.ok()) << engine.status().ToString();
  for (const ImuSample& s : imu->samples) {
    Status st = (*engine)->AddSample(s);
    EXPECT_TRUE(st.ok()) << st.ToString();
  }
  EXPECT_TRUE((*engine)->Finish().ok());
  WalkRun run{std::move(*imu), (*engine)->TakeSteps()};
  std::fprintf(stderr, "%s\n", (*engine)->Summary().BriefReport().c_str());
  return run;
}

TEST(FootImuAccuracyTest, IdealSensorGivesTheTrueStepsToAMillimetre) {
  const WalkRun run = RunWalk(2, 3, tools::MemsModel::None(), FootImuConfig());
  const auto& stances = run.imu.stances;
  ASSERT_EQ(run.steps.size() + 1, stances.size());
  double worst_m = 0, worst_rad = 0;
  for (size_t k = 0; k < run.steps.size(); ++k) {
    const FootStep& s = run.steps[k];
    const double dx = stances[k + 1].x_m - stances[k].x_m;
    const double dy = stances[k + 1].y_m - stances[k].y_m;
    const double dh = Wrap(stances[k + 1].heading_rad - stances[k].heading_rad);
    worst_m = std::max(worst_m, std::hypot(s.dx_m - dx, s.dy_m - dy));
    worst_rad = std::max(worst_rad, std::fabs(Wrap(s.dheading_rad - dh)));
  }
  std::fprintf(stderr, "worst step error %.3g m, heading %.3g deg\n", worst_m,
               worst_rad * 180 / kPi);
  EXPECT_LE(worst_m, 1e-3);
  EXPECT_LE(worst_rad, 0.01 * kPi / 180);
}

// With the default (BMI160-like) sensor errors over a 10-minute walk, each step's length stays
// within 1 % RMS of the truth (the front end's target) for three walks.
TEST(FootImuAccuracyTest, MemsSensorGivesStepLengthsToOnePercentRms) {
  for (uint64_t seed : {1, 2, 3}) {
    const WalkRun run = RunWalk(10, seed, tools::MemsModel(), FootImuConfig());
    const auto& stances = run.imu.stances;
    ASSERT_EQ(run.steps.size() + 1, stances.size()) << "seed " << seed;
    double sum_squares = 0;
    for (size_t k = 0; k < run.steps.size(); ++k) {
      const double truth =
          std::hypot(stances[k + 1].x_m - stances[k].x_m, stances[k + 1].y_m - stances[k].y_m);
      const double error = std::hypot(run.steps[k].dx_m, run.steps[k].dy_m) / truth - 1;
      sum_squares += error * error;
    }
    const double rms = std::sqrt(sum_squares / static_cast<double>(run.steps.size()));
    std::fprintf(stderr, "seed %d: step length error %.3f %% RMS over %zu steps\n",
                 static_cast<int>(seed), 100 * rms, run.steps.size());
    EXPECT_LE(rms, 0.01) << "seed " << seed;
  }
}

}  // namespace
}  // namespace grove

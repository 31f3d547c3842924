// FootSLAM against the odometry on simulated building walks with loops: the heaviest particle's
// path, rigidly aligned to the truth, must have at most half the odometry's RMSE.
#include <gtest/gtest.h>

#include <vector>

#include "grove/footslam.h"
#include "tests/api/status_testing.h"
#include "tools/trajectory_metrics.h"
#include "tools/walk_simulator.h"

namespace grove::tools {
namespace {

struct Errors {
  double odometry_m;
  double footslam_m;
};

Errors RunBuildingWalk(uint64_t seed) {
  SimulatorOptions sim;
  sim.scenario = Scenario::kBuilding;
  sim.minutes = 8;
  sim.seed = seed;
  sim.heading_drift_rad_per_sqrt_step = 0.012;
  StatusOr<SimulatedWalk> walk = SimulateWalk(sim);
  EXPECT_TRUE(walk.ok());
  std::vector<TimedPoint> truth, odometry{{0, 0, 0}};
  for (const TruthPoint& p : walk->truth) truth.push_back({p.t_s, p.x_m, p.y_m});
  FootSlamConfig config;  // defaults: 30,000 particles
  config.threads = 2;
  auto slam = FootSlam::Create(config);
  EXPECT_TRUE(slam.ok());
  EXPECT_TRUE((*slam)->SetStartTime(0).ok());
  for (const StepRecord& s : walk->steps) {
    EXPECT_TRUE((*slam)->Step(s.t_s, s.dx_m, s.dy_m).ok());
    odometry.push_back({s.t_s, odometry.back().x_m + s.dx_m, odometry.back().y_m + s.dy_m});
  }
  std::vector<TimedPoint> estimate;
  for (const StampedPose& p : ValueOf((*slam)->HeaviestTrajectory())) {
    estimate.push_back({p.t_s, p.pose.x_m, p.pose.y_m});
  }
  return {CompareTrajectories(truth, odometry)->aligned_rmse_m,
          CompareTrajectories(truth, estimate)->aligned_rmse_m};
}

TEST(FootSlamAccuracyTest, AlignedErrorIsAtMostHalfTheOdometrys) {
  for (uint64_t seed : {3, 4}) {
    Errors e = RunBuildingWalk(seed);
    RecordProperty("seed_" + std::to_string(seed) + "_odometry_mm",
                   static_cast<int>(e.odometry_m * 1000));
    RecordProperty("seed_" + std::to_string(seed) + "_footslam_mm",
                   static_cast<int>(e.footslam_m * 1000));
    std::printf("building walk seed %d: aligned RMSE odometry %.3f m, FootSLAM %.3f m\n",
                static_cast<int>(seed), e.odometry_m, e.footslam_m);
    EXPECT_GT(e.odometry_m, 1.0) << "seed " << seed << ": the walk should drift";
    EXPECT_LE(e.footslam_m, 0.5 * e.odometry_m) << "seed " << seed;
  }
}

}  // namespace
}  // namespace grove::tools

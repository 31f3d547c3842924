// FootSLAM against the odometry on simulated building walks with loops: the heaviest particle's
// path, rigidly aligned to the truth, must have at most half the odometry's RMSE.
#include <gtest/gtest.h>

#include <vector>

#include "grove/footslam.h"
#include "tests/api/status_testing.h"
#include "tools/report/trajectory_metrics.h"
#include "tools/sim/walk_simulator.h"

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

// The true map of a walk: the crossings of its true path, counted by one noiseless particle.
std::vector<HexCounts> TrueMap(const SimulatedWalk& walk) {
  FootSlamConfig config;
  config.particles = 1;
  config.heading_drift_sigma_rad = 0;
  config.heading_sigma_rad = 0;
  config.step_length_sigma_m = 0;
  auto slam = FootSlam::Create(config);
  EXPECT_TRUE(slam.ok());
  double x = 0, y = 0;
  for (const TruthPoint& p : walk.truth) {
    if (p.t_s == 0) continue;
    EXPECT_TRUE((*slam)->Step(p.t_s, p.x_m - x, p.y_m - y).ok());
    x = p.x_m;
    y = p.y_m;
  }
  return ValueOf((*slam)->CumulativeMap());
}

SimulatedWalk Building(uint64_t seed) {
  SimulatorOptions sim;
  sim.scenario = Scenario::kBuilding;
  sim.seed = seed;
  sim.heading_drift_rad_per_sqrt_step = 0.012;
  StatusOr<SimulatedWalk> walk = SimulateWalk(sim);
  EXPECT_TRUE(walk.ok());
  return *walk;
}

// The smoothed path's error against the truth, not aligned (a prior map fixes the frame), over
// the first quarter of the walk: how fast the filter finds the map.
double EarlyError(const SimulatedWalk& walk, const std::vector<HexCounts>* prior) {
  FootSlamConfig config;
  config.particles = 5000;
  config.threads = 2;
  auto slam = FootSlam::Create(config);
  EXPECT_TRUE(slam.ok());
  if (prior != nullptr) {
    EXPECT_TRUE((*slam)->SetPriorMap(*prior).ok());
  }
  EXPECT_TRUE((*slam)->SetStartTime(0).ok());
  for (const StepRecord& s : walk.steps) EXPECT_TRUE((*slam)->Step(s.t_s, s.dx_m, s.dy_m).ok());
  std::vector<TimedPoint> truth, estimate;
  for (const TruthPoint& p : walk.truth) truth.push_back({p.t_s, p.x_m, p.y_m});
  for (const StampedPose& p : ValueOf((*slam)->SmoothedTrajectory())) {
    estimate.push_back({p.t_s, p.pose.x_m, p.pose.y_m});
  }
  truth.resize(truth.size() / 4);
  estimate.resize(estimate.size() / 4);
  return CompareTrajectories(truth, estimate)->rmse_m;
}

// A prior map equal to the true map of the building (from another walk through it) makes a second
// walk find its map sooner. Measured (README, bench/studies/footslam_prior_map.sh) on more walks;
// here three whose first-quarter errors without the prior are 0.9 to 1.1 m and with it about 0.3 m.
TEST(FootSlamPriorMapTest, ATrueMapPriorMakesASecondWalkConvergeFaster) {
  const std::vector<HexCounts> prior = TrueMap(Building(1));
  double without = 0, with = 0;
  for (uint64_t seed : {3, 5, 6}) {
    const SimulatedWalk walk = Building(seed);
    const double a = EarlyError(walk, nullptr), b = EarlyError(walk, &prior);
    std::printf(
        "building walk seed %d: first-quarter RMSE %.3f m without a prior map, %.3f m "
        "with the true map\n",
        static_cast<int>(seed), a, b);
    without += a;
    with += b;
  }
  EXPECT_LE(with, 0.6 * without);
}

}  // namespace
}  // namespace grove::tools

#include "tools/sim/walk_simulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "tools/io/step_reader.h"
#include "tools/report/trajectory_metrics.h"

namespace grove::tools {
namespace {

SimulatedWalk Simulate(const SimulatorOptions& options) {
  StatusOr<SimulatedWalk> walk = SimulateWalk(options);
  EXPECT_TRUE(walk.ok()) << walk.status().ToString();
  return walk.ok() ? std::move(walk).value() : SimulatedWalk{};
}

SimulatorOptions NoOdometryErrors(SimulatorOptions options) {
  options.heading_drift_rad_per_sqrt_step = 0;
  options.scale_error = 0;
  options.step_length_noise_m = 0;
  options.heading_noise_rad = 0;
  options.initial_heading_rad = 0;
  return options;
}

// Largest distance between the integrated odometry and the truth.
double MaxDrift(const SimulatedWalk& walk) {
  double x = 0;
  double y = 0;
  double drift = 0;
  for (size_t k = 0; k < walk.steps.size(); ++k) {
    x += walk.steps[k].dx_m;
    y += walk.steps[k].dy_m;
    drift = std::max(drift, std::hypot(x - walk.truth[k + 1].x_m, y - walk.truth[k + 1].y_m));
  }
  return drift;
}

std::string WriteTempFile(const std::string& content, const std::string& name) {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path path =
      std::filesystem::path(::testing::TempDir()) /
      (std::string("grove_") + info->test_suite_name() + "_" + info->name() + "_" + name);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << content;
  return path.string();
}

TEST(WalkSimulatorTest, SameSeedGivesIdenticalWalk) {
  for (Scenario scenario : {Scenario::kBuilding, Scenario::kOpen, Scenario::kCampus}) {
    SimulatorOptions options;
    options.scenario = scenario;
    options.seed = 42;
    const SimulatedWalk a = Simulate(options);
    const SimulatedWalk b = Simulate(options);
    ASSERT_FALSE(a.steps.empty());
    EXPECT_EQ(StepsCsv(a), StepsCsv(b));
    EXPECT_EQ(TruthCsv(a), TruthCsv(b));
  }
}

TEST(WalkSimulatorTest, DifferentSeedsGiveDifferentWalks) {
  SimulatorOptions options;
  options.seed = 1;
  const SimulatedWalk a = Simulate(options);
  options.seed = 2;
  const SimulatedWalk b = Simulate(options);
  EXPECT_NE(TruthCsv(a), TruthCsv(b));
  EXPECT_NE(StepsCsv(a), StepsCsv(b));
}

TEST(WalkSimulatorTest, DurationMatchesMinutes) {
  SimulatorOptions options;
  options.minutes = 2;
  options.step_period_s = 0.55;
  const SimulatedWalk walk = Simulate(options);
  ASSERT_EQ(walk.steps.size(), 218u);  // floor(120 / 0.55)
  ASSERT_EQ(walk.truth.size(), walk.steps.size() + 1);
  EXPECT_LE(walk.truth.back().t_s, 120.0);
  EXPECT_GT(walk.truth.back().t_s, 120.0 - 0.55);
  for (size_t k = 0; k < walk.steps.size(); ++k) {
    ASSERT_EQ(walk.steps[k].t_s, walk.truth[k + 1].t_s);
    ASSERT_GT(walk.truth[k + 1].t_s, walk.truth[k].t_s);
  }

  options.minutes = 1;
  options.step_period_s = 0.5;
  EXPECT_EQ(Simulate(options).steps.size(), 120u);  // exact multiple: no step lost to rounding
}

TEST(WalkSimulatorTest, TruthStartsAtOriginAndStaysInsideTheScenarioArea) {
  for (Scenario scenario : {Scenario::kBuilding, Scenario::kOpen, Scenario::kCampus}) {
    const Area area = ScenarioArea(scenario);
    for (uint64_t seed = 1; seed <= 8; ++seed) {
      SCOPED_TRACE(testing::Message()
                   << "scenario " << static_cast<int>(scenario) << " seed " << seed);
      SimulatorOptions options;
      options.scenario = scenario;
      options.seed = seed;
      options.minutes = 15;
      const SimulatedWalk walk = Simulate(options);
      ASSERT_FALSE(walk.truth.empty());
      EXPECT_EQ(walk.truth[0].t_s, 0);
      EXPECT_EQ(walk.truth[0].x_m, 0);
      EXPECT_EQ(walk.truth[0].y_m, 0);
      // The walk sets off heading 0, along +x.
      EXPECT_GT(walk.truth[1].x_m, 0.3);
      EXPECT_LT(std::abs(walk.truth[1].y_m), 0.5);
      for (const TruthPoint& p : walk.truth) {
        ASSERT_GE(p.x_m, area.min_x_m) << "t = " << p.t_s;
        ASSERT_LE(p.x_m, area.max_x_m) << "t = " << p.t_s;
        ASSERT_GE(p.y_m, area.min_y_m) << "t = " << p.t_s;
        ASSERT_LE(p.y_m, area.max_y_m) << "t = " << p.t_s;
      }
    }
  }
}

TEST(WalkSimulatorTest, TrueStepsHaveAboutTheStepLength) {
  SimulatorOptions options;
  options.step_length_m = 0.8;
  const SimulatedWalk walk = Simulate(options);
  double sum = 0;
  for (size_t k = 1; k < walk.truth.size(); ++k) {
    const double length = std::hypot(walk.truth[k].x_m - walk.truth[k - 1].x_m,
                                     walk.truth[k].y_m - walk.truth[k - 1].y_m);
    ASSERT_LE(length, 1.5 * 0.8 + 1e-12);
    sum += length;
  }
  const double mean = sum / static_cast<double>(walk.truth.size() - 1);
  // Slightly below 0.8: steps shorten next to waypoints.
  EXPECT_GT(mean, 0.7);
  EXPECT_LT(mean, 0.82);
}

TEST(WalkSimulatorTest, ZeroNoiseGivesOdometryEqualToTruth) {
  for (Scenario scenario : {Scenario::kBuilding, Scenario::kOpen, Scenario::kCampus}) {
    SimulatorOptions options = NoOdometryErrors(SimulatorOptions{});
    options.scenario = scenario;
    options.seed = 5;
    const SimulatedWalk walk = Simulate(options);
    ASSERT_EQ(walk.truth.size(), walk.steps.size() + 1);
    double x = 0;
    double y = 0;
    for (size_t k = 0; k < walk.steps.size(); ++k) {
      // The truth is built by the same sums, so equality is exact.
      x += walk.steps[k].dx_m;
      y += walk.steps[k].dy_m;
      ASSERT_EQ(x, walk.truth[k + 1].x_m) << "step " << k;
      ASSERT_EQ(y, walk.truth[k + 1].y_m) << "step " << k;
    }
    EXPECT_EQ(MaxDrift(walk), 0);
  }
}

TEST(WalkSimulatorTest, TruthDoesNotDependOnOdometryErrors) {
  SimulatorOptions noisy;
  noisy.seed = 9;
  noisy.heading_noise_rad = 0.1;
  const SimulatedWalk a = Simulate(noisy);
  const SimulatedWalk b = Simulate(NoOdometryErrors(noisy));
  EXPECT_EQ(TruthCsv(a), TruthCsv(b));
  EXPECT_NE(StepsCsv(a), StepsCsv(b));
}

TEST(WalkSimulatorTest, ScaleErrorScalesEveryStep) {
  SimulatorOptions options = NoOdometryErrors(SimulatorOptions{});
  options.minutes = 1;
  const SimulatedWalk truth = Simulate(options);
  options.scale_error = 0.1;
  const SimulatedWalk scaled = Simulate(options);
  ASSERT_EQ(truth.steps.size(), scaled.steps.size());
  for (size_t k = 0; k < truth.steps.size(); ++k) {
    ASSERT_NEAR(scaled.steps[k].dx_m, 1.1 * truth.steps[k].dx_m, 1e-12) << "step " << k;
    ASSERT_NEAR(scaled.steps[k].dy_m, 1.1 * truth.steps[k].dy_m, 1e-12) << "step " << k;
  }
}

TEST(WalkSimulatorTest, InitialHeadingRotatesTheOdometryFrame) {
  SimulatorOptions options = NoOdometryErrors(SimulatorOptions{});
  options.minutes = 1;
  const SimulatedWalk truth = Simulate(options);
  options.initial_heading_rad = 0.5;
  const SimulatedWalk rotated = Simulate(options);
  ASSERT_EQ(truth.steps.size(), rotated.steps.size());
  const double c = std::cos(0.5);
  const double s = std::sin(0.5);
  for (size_t k = 0; k < truth.steps.size(); ++k) {
    const StepRecord& u = truth.steps[k];
    ASSERT_NEAR(rotated.steps[k].dx_m, c * u.dx_m - s * u.dy_m, 1e-12) << "step " << k;
    ASSERT_NEAR(rotated.steps[k].dy_m, s * u.dx_m + c * u.dy_m, 1e-12) << "step " << k;
  }
}

// Counts, for every 1 m cell, how many separate times the walk entered it.
std::map<std::pair<int64_t, int64_t>, int> CellEntries(const SimulatedWalk& walk) {
  std::map<std::pair<int64_t, int64_t>, int> entries;
  std::pair<int64_t, int64_t> last{std::numeric_limits<int64_t>::min(), 0};
  for (const TruthPoint& p : walk.truth) {
    const std::pair<int64_t, int64_t> cell{static_cast<int64_t>(std::floor(p.x_m)),
                                           static_cast<int64_t>(std::floor(p.y_m))};
    if (cell != last) ++entries[cell];
    last = cell;
  }
  return entries;
}

TEST(WalkSimulatorTest, BuildingWalkRevisitsPlacesManyTimes) {
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    SimulatorOptions options;
    options.seed = seed;
    int most = 0;
    int revisited_cells = 0;
    for (const auto& [cell, count] : CellEntries(Simulate(options))) {
      most = std::max(most, count);
      if (count >= 3) ++revisited_cells;
    }
    EXPECT_GE(most, 5);
    EXPECT_GE(revisited_cells, 20);
  }
}

TEST(WalkSimulatorTest, OpenWalkExploresMoreGroundThanTheBuildingWalk) {
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    SimulatorOptions options;
    options.seed = seed;
    options.minutes = 13;
    const size_t building_cells = CellEntries(Simulate(options)).size();
    options.scenario = Scenario::kOpen;
    const auto open = CellEntries(Simulate(options));
    EXPECT_GT(open.size(), 2 * building_cells);
    int revisited_cells = 0;
    for (const auto& [cell, count] : open) revisited_cells += count >= 2;
    EXPECT_GT(revisited_cells, 0);  // exploration plus some revisits
  }
}

TEST(WalkSimulatorTest, DefaultNoiseMakesOdometryDriftVisiblyButBoundedly) {
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    SimulatorOptions options;
    options.seed = seed;
    const double drift = MaxDrift(Simulate(options));
    EXPECT_GT(drift, 1.0);
    EXPECT_LT(drift, 20.0);
  }
}

TEST(WalkSimulatorTest, StepsCsvReadsBackToTheSameDoubles) {
  SimulatorOptions options;
  options.minutes = 3;
  options.seed = 11;
  const SimulatedWalk walk = Simulate(options);
  const std::string csv = StepsCsv(walk);
  ASSERT_EQ(csv.rfind("t,dx,dy\n", 0), 0u);
  StatusOr<std::vector<StepRecord>> steps = ReadAllSteps(WriteTempFile(csv, "steps.csv"));
  ASSERT_TRUE(steps.ok()) << steps.status().ToString();
  ASSERT_EQ(steps->size(), walk.steps.size());
  for (size_t k = 0; k < walk.steps.size(); ++k) {
    ASSERT_EQ((*steps)[k].t_s, walk.steps[k].t_s) << "step " << k;
    ASSERT_EQ((*steps)[k].dx_m, walk.steps[k].dx_m) << "step " << k;
    ASSERT_EQ((*steps)[k].dy_m, walk.steps[k].dy_m) << "step " << k;
  }
}

TEST(WalkSimulatorTest, TruthCsvStartsAtTheOriginAndReadsBack) {
  SimulatorOptions options;
  options.minutes = 1;
  const SimulatedWalk walk = Simulate(options);
  const std::string csv = TruthCsv(walk);
  ASSERT_EQ(csv.rfind("t,x,y\n0,0,0\n", 0), 0u) << csv.substr(0, 40);
  StatusOr<std::vector<TimedPoint>> points = ReadTimedPoints(WriteTempFile(csv, "truth.csv"));
  ASSERT_TRUE(points.ok()) << points.status().ToString();
  ASSERT_EQ(points->size(), walk.truth.size());
  for (size_t k = 0; k < walk.truth.size(); ++k) {
    ASSERT_EQ((*points)[k].t_s, walk.truth[k].t_s);
    ASSERT_EQ((*points)[k].x_m, walk.truth[k].x_m);
    ASSERT_EQ((*points)[k].y_m, walk.truth[k].y_m);
  }
}

TEST(WalkSimulatorTest, InvalidOptionsNameTheFieldAndTheRule) {
  SimulatorOptions options;
  options.minutes = 0;
  EXPECT_EQ(SimulateWalk(options).status().message(), "minutes = 0: must be in (0, 1440]");
  options = {};
  options.step_period_s = std::nan("");
  EXPECT_EQ(SimulateWalk(options).status().message(), "step_period_s = nan: must be in [0.1, 5]");
  options = {};
  options.heading_noise_rad = -0.1;
  EXPECT_EQ(SimulateWalk(options).status().message(),
            "heading_noise_rad = -0.1: must be in [0, 1]");
  options = {};
  options.scale_error = 0.5;
  EXPECT_EQ(SimulateWalk(options).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(SimulateWalk(options).status().message(), "scale_error = 0.5: must be in (-0.5, 0.5)");
}

}  // namespace
}  // namespace grove::tools

#include "tools/report/trajectory_metrics.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "tools/io/truth_trajectory.h"

namespace grove::tools {
namespace {

std::string WriteTempFile(const std::string& content, const std::string& name = "track.csv") {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path path =
      std::filesystem::path(::testing::TempDir()) /
      (std::string("grove_") + info->test_suite_name() + "_" + info->name() + "_" + name);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << content;
  return path.string();
}

// A non-degenerate test path: an L turning into a curve, one point per second.
std::vector<TimedPoint> CurvedPath(int n) {
  std::vector<TimedPoint> points;
  for (int i = 0; i < n; ++i) {
    const double t = i;
    points.push_back({t, 0.7 * t + 2 * std::sin(0.3 * t), 0.02 * t * t - std::cos(0.2 * t)});
  }
  return points;
}

std::vector<TimedPoint> Transformed(const std::vector<TimedPoint>& points, double angle_rad,
                                    double tx_m, double ty_m) {
  const double c = std::cos(angle_rad);
  const double s = std::sin(angle_rad);
  std::vector<TimedPoint> out;
  for (const TimedPoint& p : points) {
    out.push_back({p.t_s, c * p.x_m - s * p.y_m + tx_m, s * p.x_m + c * p.y_m + ty_m});
  }
  return out;
}

TrajectoryError Compare(const std::vector<TimedPoint>& truth,
                        const std::vector<TimedPoint>& estimate) {
  StatusOr<TrajectoryError> error = CompareTrajectories(truth, estimate);
  EXPECT_TRUE(error.ok()) << error.status().ToString();
  return error.ok() ? *error : TrajectoryError{};
}

TEST(TrajectoryMetricsTest, IdenticalTrajectoriesHaveZeroError) {
  const std::vector<TimedPoint> path = CurvedPath(50);
  const TrajectoryError e = Compare(path, path);
  EXPECT_EQ(e.matched, 50u);
  EXPECT_EQ(e.rmse_m, 0);
  EXPECT_EQ(e.max_m, 0);
  EXPECT_NEAR(e.aligned_rmse_m, 0, 1e-12);
  EXPECT_NEAR(e.aligned_max_m, 0, 1e-12);
  EXPECT_NEAR(e.rotation_rad, 0, 1e-12);
  EXPECT_NEAR(e.translation_x_m, 0, 1e-12);
  EXPECT_NEAR(e.translation_y_m, 0, 1e-12);
}

TEST(TrajectoryMetricsTest, RotatedAndTranslatedCopyAlignsExactly) {
  const std::vector<TimedPoint> truth = CurvedPath(60);
  // estimate = R(0.3) truth + (5, -2), so truth = R(-0.3) estimate - R(-0.3) (5, -2).
  const TrajectoryError e = Compare(truth, Transformed(truth, 0.3, 5, -2));
  EXPECT_EQ(e.matched, 60u);
  EXPECT_GT(e.rmse_m, 5);
  EXPECT_GT(e.max_m, e.rmse_m);
  EXPECT_NEAR(e.aligned_rmse_m, 0, 1e-9);
  EXPECT_NEAR(e.aligned_max_m, 0, 1e-9);
  EXPECT_NEAR(e.rotation_rad, -0.3, 1e-12);
  const double c = std::cos(-0.3);
  const double s = std::sin(-0.3);
  EXPECT_NEAR(e.translation_x_m, -(c * 5 - s * -2), 1e-9);
  EXPECT_NEAR(e.translation_y_m, -(s * 5 + c * -2), 1e-9);
}

TEST(TrajectoryMetricsTest, HalfTurnIsReportedAsPlusPi) {
  const std::vector<TimedPoint> truth = CurvedPath(30);
  const TrajectoryError e = Compare(truth, Transformed(truth, std::numbers::pi, 1, 1));
  EXPECT_NEAR(e.aligned_rmse_m, 0, 1e-9);
  EXPECT_NEAR(std::abs(e.rotation_rad), std::numbers::pi, 1e-12);
  EXPECT_GT(e.rotation_rad, 0);
}

TEST(TrajectoryMetricsTest, AlignmentRecoversRandomRigidTransforms) {
  for (uint64_t seed = 1; seed <= 50; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    std::mt19937_64 engine(seed);
    const auto uniform = [&](double low, double high) {
      return low + (high - low) * static_cast<double>(engine() >> 11) * 0x1.0p-53;
    };
    std::vector<TimedPoint> truth;
    double t = 0;
    for (int i = 0; i < 40; ++i) {
      t += uniform(0.1, 1);
      truth.push_back({t, uniform(-50, 50), uniform(-50, 50)});
    }
    const double angle = uniform(-3, 3);
    const double tx = uniform(-100, 100);
    const double ty = uniform(-100, 100);
    const TrajectoryError e = Compare(Transformed(truth, angle, tx, ty), truth);
    EXPECT_NEAR(e.rotation_rad, angle, 1e-9);
    EXPECT_NEAR(e.translation_x_m, tx, 1e-7);
    EXPECT_NEAR(e.translation_y_m, ty, 1e-7);
    EXPECT_NEAR(e.aligned_max_m, 0, 1e-7);
  }
}

TEST(TrajectoryMetricsTest, ConstantOffsetGivesItsLengthAsRmse) {
  const std::vector<TimedPoint> truth = CurvedPath(20);
  const TrajectoryError e = Compare(truth, Transformed(truth, 0, 3, 4));
  EXPECT_NEAR(e.rmse_m, 5, 1e-12);
  EXPECT_NEAR(e.max_m, 5, 1e-12);
  EXPECT_NEAR(e.aligned_rmse_m, 0, 1e-9);
  EXPECT_NEAR(e.rotation_rad, 0, 1e-12);
  EXPECT_NEAR(e.translation_x_m, -3, 1e-9);
  EXPECT_NEAR(e.translation_y_m, -4, 1e-9);
}

TEST(TrajectoryMetricsTest, KnownErrorsGiveKnownRmseAndMax) {
  const std::vector<TimedPoint> truth = {{0, 0, 0}, {1, 10, 0}, {2, 10, 10}, {3, 0, 10}};
  // Errors of length 3, 4, 0, 0: rmse sqrt(25 / 4) = 2.5, max 4.
  const std::vector<TimedPoint> estimate = {{0, 3, 0}, {1, 10, 4}, {2, 10, 10}, {3, 0, 10}};
  const TrajectoryError e = Compare(truth, estimate);
  EXPECT_EQ(e.matched, 4u);
  EXPECT_DOUBLE_EQ(e.rmse_m, 2.5);
  EXPECT_DOUBLE_EQ(e.max_m, 4);
  EXPECT_GT(e.aligned_rmse_m, 0);
  EXPECT_LT(e.aligned_rmse_m, e.rmse_m);  // the best rigid fit can only do better
}

TEST(TrajectoryMetricsTest, EstimateIsInterpolatedAtTruthTimes) {
  const std::vector<TimedPoint> estimate = {{0, 0, 0}, {2, 4, 0}, {4, 4, 8}};
  // Mid times land halfway: (2, 0) at t = 1 and (4, 4) at t = 3; t = 3.5 lands at (4, 6).
  const std::vector<TimedPoint> truth = {{1, 2, 0}, {3, 4, 4}, {3.5, 4, 6}};
  const TrajectoryError exact = Compare(truth, estimate);
  EXPECT_EQ(exact.matched, 3u);
  EXPECT_NEAR(exact.rmse_m, 0, 1e-12);

  const std::vector<TimedPoint> off = {{1, 2, 1}, {3, 4, 4}, {3.5, 4, 6}};
  const TrajectoryError e = Compare(off, estimate);
  EXPECT_NEAR(e.max_m, 1, 1e-12);
  EXPECT_NEAR(e.rmse_m, std::sqrt(1.0 / 3), 1e-12);
}

TEST(TrajectoryMetricsTest, TruthOutsideTheEstimateSpanIsSkipped) {
  const std::vector<TimedPoint> truth = CurvedPath(20);                     // t = 0 .. 19
  std::vector<TimedPoint> estimate(truth.begin() + 5, truth.begin() + 15);  // t = 5 .. 14
  const TrajectoryError e = Compare(truth, estimate);
  EXPECT_EQ(e.matched, 10u);
  EXPECT_EQ(e.rmse_m, 0);
}

TEST(TrajectoryMetricsTest, FewerThanTwoMatchesIsAnError) {
  const std::vector<TimedPoint> truth = {{0, 0, 0}, {1, 1, 0}, {10, 2, 0}};
  const std::vector<TimedPoint> estimate = {{0.5, 0, 0}, {1.5, 1, 0}};
  StatusOr<TrajectoryError> e = CompareTrajectories(truth, estimate);
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(e.status().message(),
            "1 truth point(s) fall within the estimate's time span [0.5, 1.5] s: need at least 2");
  EXPECT_FALSE(CompareTrajectories(truth, {}).ok());
}

TEST(TrajectoryMetricsTest, UnsortedOrNonFiniteInputIsAnError) {
  const std::vector<TimedPoint> good = CurvedPath(5);
  std::vector<TimedPoint> unsorted = good;
  unsorted[3].t_s = unsorted[2].t_s;
  StatusOr<TrajectoryError> e = CompareTrajectories(good, unsorted);
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().message(),
            "estimate[3].t_s = 2 is not after estimate[2].t_s = 2: times must be strictly "
            "increasing");
  std::vector<TimedPoint> nan = good;
  nan[1].y_m = std::nan("");
  e = CompareTrajectories(nan, good);
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.status().message(), "truth[1].y_m = nan: must be finite");
}

TEST(TrajectoryMetricsTest, JsonHoldsEveryField) {
  const std::vector<TimedPoint> truth = CurvedPath(20);
  const TrajectoryError e = Compare(truth, Transformed(truth, 0.1, 1, 2));
  const std::string text = TrajectoryErrorJson(e);
  EXPECT_NE(text.find("\n  \"matched\": 20"), std::string::npos) << text;  // pretty printed
  const nlohmann::json json = nlohmann::json::parse(text);
  EXPECT_EQ(json.size(), 8u);
  EXPECT_EQ(json.at("matched").get<size_t>(), e.matched);
  EXPECT_EQ(json.at("rmse_m").get<double>(), e.rmse_m);
  EXPECT_EQ(json.at("max_m").get<double>(), e.max_m);
  EXPECT_EQ(json.at("aligned_rmse_m").get<double>(), e.aligned_rmse_m);
  EXPECT_EQ(json.at("aligned_max_m").get<double>(), e.aligned_max_m);
  EXPECT_EQ(json.at("rotation_rad").get<double>(), e.rotation_rad);
  EXPECT_EQ(json.at("translation_x_m").get<double>(), e.translation_x_m);
  EXPECT_EQ(json.at("translation_y_m").get<double>(), e.translation_y_m);
}

TEST(TrajectoryMetricsTest, ReadsPointsIgnoringExtraColumns) {
  const std::string path = WriteTempFile(
      "# estimate\r\nt, x, y, heading_rad\r\n0,0,0,0\r\n\r\n0.5, 1.5 ,-2,0.1\r\n1,+3,4e-1,0.2");
  StatusOr<std::vector<TimedPoint>> points = ReadTimedPoints(path);
  ASSERT_TRUE(points.ok()) << points.status().ToString();
  ASSERT_EQ(points->size(), 3u);
  EXPECT_EQ((*points)[1].t_s, 0.5);
  EXPECT_EQ((*points)[1].x_m, 1.5);
  EXPECT_EQ((*points)[1].y_m, -2);
  EXPECT_EQ((*points)[2].x_m, 3);
  EXPECT_EQ((*points)[2].y_m, 0.4);
}

TEST(TrajectoryMetricsTest, ReadErrorsGiveFileLineAndColumn) {
  struct Case {
    const char* content;
    const char* expected;  // after the path
  };
  const Case cases[] = {
      {"t,y,x\n0,0,0\n", ":1:1: unknown header \"t,y,x\": expected one starting with \"t,x,y\""},
      {"t,x,y\n0,0,0\n1,0,zz\n", ":3:5: y: \"zz\" is not a number"},
      {"t,x,y,h\n0,0,0,0\n1,0,0\n", ":3:1: expected 4 fields as in the header, found 3"},
      {"t,x,y\n0,0,0\n\n  2,0,0\n  1.5,0,0\n",
       ":5:3: t = 1.5 is not after the previous time 2: times must be strictly increasing"},
      {"t,x,y\n0,inf,0\n", ":2:3: x = inf: must be finite"},
      {"", ": empty file: expected a header starting with \"t,x,y\""},
      {"t,x,y\n", ": no points after the header"},
  };
  int index = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.content);
    const std::string path = WriteTempFile(c.content, "case" + std::to_string(index++) + ".csv");
    StatusOr<std::vector<TimedPoint>> points = ReadTimedPoints(path);
    ASSERT_FALSE(points.ok());
    EXPECT_EQ(points.status().code(), StatusCode::kInvalidArgument);
    EXPECT_EQ(points.status().message(), path + c.expected);
  }
  StatusOr<std::vector<TimedPoint>> missing =
      ReadTimedPoints(::testing::TempDir() + "/grove_no_such_track.csv");
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
}

// Regression: the unknown-header message echoed the line raw and whole.
TEST(TrajectoryMetricsTest, UnknownHeaderIsEscapedAndCut) {
  const std::string path =
      WriteTempFile("\x1b[1;31mtime\x7f,x,y" + std::string(4000, 'z') + "\n0,0,0\n");
  StatusOr<std::vector<TimedPoint>> points = ReadTimedPoints(path);
  ASSERT_FALSE(points.ok());
  const std::string& message = points.status().message();
  EXPECT_TRUE(message.starts_with(path + ":1:1: unknown header \"\\x1b[1;31mtime\\x7f,x,yzzz"))
      << message;
  EXPECT_NE(message.find("zzz...\": expected one starting with \"t,x,y\""), std::string::npos)
      << message;
  EXPECT_EQ(message.find('\x1b'), std::string::npos) << message;
  EXPECT_LT(message.size(), path.size() + 200) << message;
}

TEST(TruthTrajectoryTest, TumFileGivesPositionsAndTheQuaternionsYaw) {
  const double h = 0.7;
  const std::string text = fmt::format(
      "# t x y z qx qy qz qw\n\n0 1 2 3 0 0 0 1\n 0.5\t-1.5  2e-1 0 0 0 {} {}\n"
      "1 0 0 0 0 0 {} {}\n",
      std::sin(h / 2), std::cos(h / 2), 2 * std::sin(-h / 2), 2 * std::cos(-h / 2));
  for (const char* name : {"truth.tum", "truth.txt", "truth.poses"}) {
    SCOPED_TRACE(name);
    StatusOr<TruthTrajectory> truth = ReadTruthTrajectory(WriteTempFile(text, name));
    ASSERT_TRUE(truth.ok()) << truth.status().ToString();
    EXPECT_TRUE(truth->has_heading);
    ASSERT_EQ(truth->poses.size(), 3u);
    EXPECT_EQ(truth->poses[0].pose.x_m, 1);
    EXPECT_EQ(truth->poses[0].pose.y_m, 2);
    EXPECT_EQ(truth->poses[0].pose.heading_rad, 0);
    EXPECT_EQ(truth->poses[1].t_s, 0.5);
    EXPECT_EQ(truth->poses[1].pose.x_m, -1.5);
    EXPECT_EQ(truth->poses[1].pose.y_m, 0.2);
    EXPECT_NEAR(truth->poses[1].pose.heading_rad, h, 1e-15);
    EXPECT_NEAR(truth->poses[2].pose.heading_rad, -h, 1e-15);  // not a unit quaternion
  }
}

TEST(TruthTrajectoryTest, CsvHeadingColumnIsReadWhenNamedSo) {
  StatusOr<TruthTrajectory> with =
      ReadTruthTrajectory(WriteTempFile("t,x,y,heading\n0,1,2,0.25\n1,2,3,-0.5\n"));
  ASSERT_TRUE(with.ok()) << with.status().ToString();
  EXPECT_TRUE(with->has_heading);
  EXPECT_EQ(with->poses[1].pose.heading_rad, -0.5);
  StatusOr<TruthTrajectory> without =
      ReadTruthTrajectory(WriteTempFile("t,x,y,yaw\n0,1,2,0.25\n", "other.csv"));
  ASSERT_TRUE(without.ok()) << without.status().ToString();
  EXPECT_FALSE(without->has_heading);
  EXPECT_EQ(without->poses[0].pose.heading_rad, 0);
}

TEST(TruthTrajectoryTest, TumErrorsGiveFileLineAndColumn) {
  struct Case {
    const char* content;
    const char* expected;  // after the path
  };
  const Case cases[] = {
      {"0 0 0 0 0 0 0 1\n1 0 0 0 0 0 1\n",
       ":2:1: expected 8 numbers \"t x y z qx qy qz qw\" separated by spaces, found 7 field(s)"},
      {"0 0 0 0 0 0 0 1\n1 0  nan 0 0 0 0 1\n", ":2:6: y = nan: must be finite"},
      {"1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n",
       ":2:1: t = 1 is not after the previous time 1: times must be strictly increasing"},
      {"0 0 0 0 0 0 0 0\n",
       ":1:9: qx, qy, qz, qw = 0, 0, 0, 0: a rotation needs a non-zero quaternion"},
      {"# only a comment\n", ": no poses: expected lines \"t x y z qx qy qz qw\""},
  };
  int index = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.content);
    const std::string path = WriteTempFile(c.content, "case" + std::to_string(index++) + ".tum");
    StatusOr<TruthTrajectory> truth = ReadTruthTrajectory(path);
    ASSERT_FALSE(truth.ok());
    EXPECT_EQ(truth.status().code(), StatusCode::kInvalidArgument);
    EXPECT_EQ(truth.status().message(), path + c.expected);
  }
}

}  // namespace
}  // namespace grove::tools

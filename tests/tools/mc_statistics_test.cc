#include "tools/montecarlo/mc_statistics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace grove::tools {
namespace {

TEST(McStatisticsTest, MeanAndVariances) {
  const std::vector<double> v = {2, 4, 4, 4, 5, 5, 7, 9};
  EXPECT_DOUBLE_EQ(Mean(v), 5);
  EXPECT_DOUBLE_EQ(PopulationVariance(v), 4);       // 32 / 8
  EXPECT_DOUBLE_EQ(SampleVariance(v), 32.0 / 7.0);  // 32 / 7
  EXPECT_TRUE(std::isnan(Mean({})));
  EXPECT_TRUE(std::isnan(PopulationVariance({})));
  const std::vector<double> one = {3};
  EXPECT_DOUBLE_EQ(PopulationVariance(one), 0);
  EXPECT_TRUE(std::isnan(SampleVariance(one)));
}

TEST(McStatisticsTest, QuantilesMatchTables) {
  // chi2inv(0.025, 90) and chi2inv(0.975, 90), as MATLAB gives them.
  EXPECT_NEAR(ChiSquareQuantile(0.025, 90), 65.647, 1e-3);
  EXPECT_NEAR(ChiSquareQuantile(0.975, 90), 118.136, 1e-3);
  // tinv(0.975, 4) and tinv(0.975, 29).
  EXPECT_NEAR(StudentTQuantile(0.975, 4), 2.776445, 1e-6);
  EXPECT_NEAR(StudentTQuantile(0.975, 29), 2.045230, 1e-6);
  EXPECT_TRUE(std::isnan(StudentTQuantile(1.0, 4)));
  EXPECT_TRUE(std::isnan(ChiSquareQuantile(0.5, 0)));
}

TEST(McStatisticsTest, AverageNeesIntervalForThreeDofAndThirtyRunsIsTheSeeds) {
  // The seed paper (Section 4.3): 30 Monte Carlo runs, two-sided 95 %: "between 2.19 and 3.93".
  // By hand: 65.647 / 30 = 2.1882 and 118.136 / 30 = 3.9379; the paper cuts the upper bound
  // (3.94 rounded).
  const NeesInterval i = AverageNeesInterval(3, 30);
  EXPECT_NEAR(i.low, 65.647 / 30, 1e-4);
  EXPECT_NEAR(i.high, 118.136 / 30, 1e-4);
  EXPECT_DOUBLE_EQ(std::round(i.low * 100) / 100, 2.19);
  EXPECT_DOUBLE_EQ(std::floor(i.high * 100) / 100, 3.93);
  // One run: the chi-square interval of 3 degrees of freedom itself, 0.2158 .. 9.3484.
  const NeesInterval one = AverageNeesInterval(3, 1);
  EXPECT_NEAR(one.low, 0.215795, 1e-5);
  EXPECT_NEAR(one.high, 9.348404, 1e-5);
  EXPECT_TRUE(std::isnan(AverageNeesInterval(3, 0).low));
}

TEST(McStatisticsTest, StudentTIntervalOfAHandComputedSample) {
  // 1..5: mean 3, s^2 = 2.5, s / sqrt(5) = 0.7071068; t(0.975, 4) = 2.776445:
  // half width 1.963243.
  const std::vector<double> v = {1, 2, 3, 4, 5};
  const ConfidenceInterval ci = StudentTInterval(v);
  EXPECT_DOUBLE_EQ(ci.mean, 3);
  EXPECT_EQ(ci.count, 5);
  EXPECT_NEAR(ci.half_width, 1.963243, 1e-6);
  EXPECT_NEAR(ci.low, 3 - 1.963243, 1e-6);
  EXPECT_NEAR(ci.high, 3 + 1.963243, 1e-6);
  // One value: a mean without an interval.
  const std::vector<double> one = {7};
  const ConfidenceInterval single = StudentTInterval(one);
  EXPECT_DOUBLE_EQ(single.mean, 7);
  EXPECT_TRUE(std::isnan(single.half_width));
  EXPECT_TRUE(std::isnan(single.low));
}

TEST(McStatisticsTest, PoseNeesIsTheMahalanobisDistance) {
  // Diagonal: each component contributes (d_i / sigma_i)^2 = 1.
  EXPECT_NEAR(PoseNees(2, 1, 0.5, {.xx = 4, .yy = 1, .hh = 0.25}), 3, 1e-12);
  // Correlated: P = [[2, 1, 0], [1, 2, 0], [0, 0, 1]], P^-1 of the xy block is
  // [[2, -1], [-1, 2]] / 3, so d = (1, 1, 1) gives 2/3 + 1.
  EXPECT_NEAR(PoseNees(1, 1, 1, {.xx = 2, .xy = 1, .yy = 2, .hh = 1}), 2.0 / 3 + 1, 1e-12);
  // Full 3 x 3 with heading coupling, against d^T P^-1 d with P^-1 by hand:
  // P = [[4, 2, 0.4], [2, 5, 0.2], [0.4, 0.2, 0.1]]; P^-1 d for d = (1, -1, 0.1) solved exactly.
  const Pose2Covariance p{.xx = 4, .xy = 2, .xh = 0.4, .yy = 5, .yh = 0.2, .hh = 0.1};
  // Solve with Cramer's rule here, independently of the Cholesky in PoseNees.
  const double a[3][3] = {{4, 2, 0.4}, {2, 5, 0.2}, {0.4, 0.2, 0.1}};
  const double d[3] = {1, -1, 0.1};
  auto det = [](const double m[3][3]) {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  };
  const double da = det(a);
  double nees = 0;
  for (int c = 0; c < 3; ++c) {
    double m[3][3];
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) m[i][j] = j == c ? d[i] : a[i][j];
    }
    nees += d[c] * det(m) / da;
  }
  EXPECT_NEAR(PoseNees(d[0], d[1], d[2], p), nees, 1e-9);
}

TEST(McStatisticsTest, PoseNeesIsNanWhenTheCovarianceIsNotPositiveDefinite) {
  EXPECT_TRUE(std::isnan(PoseNees(1, 1, 0.1, {})));  // all particles at one pose
  // Rank 2: heading exactly determined by x (three particles on a line in pose space).
  EXPECT_TRUE(std::isnan(PoseNees(1, 1, 0.1, {.xx = 1, .xh = 1, .yy = 1, .hh = 1})));
  EXPECT_TRUE(std::isnan(PoseNees(1, 1, 0.1, {.xx = -1, .yy = 1, .hh = 1})));
  // Singular up to round-off: heading given x has a variance of 2e-11 of its own.
  EXPECT_TRUE(std::isnan(PoseNees(1, 1, 0.1, {.xx = 1, .xh = 1 - 1e-11, .yy = 1, .hh = 1})));
  EXPECT_TRUE(std::isfinite(PoseNees(1, 1, 0.1, {.xx = 1, .xh = 0.999, .yy = 1, .hh = 1})));
  EXPECT_TRUE(std::isnan(PoseNees(NAN, 1, 0.1, {.xx = 1, .yy = 1, .hh = 1})));
}

TEST(McStatisticsTest, WrapAngleStaysWithinPi) {
  EXPECT_NEAR(WrapAngle(3 * std::numbers::pi / 2), -std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(WrapAngle(-3 * std::numbers::pi / 2), std::numbers::pi / 2, 1e-12);
  EXPECT_DOUBLE_EQ(WrapAngle(0.25), 0.25);
}

}  // namespace
}  // namespace grove::tools

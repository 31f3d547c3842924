#include "engine/fastslam/landmark_math.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include "tests/fastslam/matrix_testing.h"

namespace grove::fastslam {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// The closed-form log density of N(v; 0, c) by explicit inverse and determinant.
template <int N>
double ClosedFormLogDensity(const Eigen::Matrix<double, N, 1>& v,
                            const Eigen::Matrix<double, N, N>& c) {
  return -0.5 * v.dot(c.inverse() * v) - 0.5 * std::log(std::pow(2 * kPi, N) * c.determinant());
}

bool SameBytes(const Landmark& a, const Landmark& b) { return std::memcmp(&a, &b, sizeof a) == 0; }
template <typename M>
bool SameBytes(const M& a, const M& b) {
  return std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

template <typename Derived>
double MinEigenvalue(const Eigen::MatrixBase<Derived>& a) {
  using Plain = typename Derived::PlainObject;
  return Eigen::SelfAdjointEigenSolver<Plain>(Plain(a)).eigenvalues().minCoeff();
}

// ---------------------------------------------------------------------------------------------
// Angles.

TEST(WrapAngleTest, LeavesTheIntervalUnchanged) {
  for (double a : {0.0, -0.0, 1.0, -1.0, 3.0, -3.0, kPi, std::nextafter(-kPi, 0.0), 1e-300}) {
    EXPECT_EQ(WrapAngle(a), a) << a;
  }
}

TEST(WrapAngleTest, PiStaysPiAndMinusPiBecomesPi) {
  EXPECT_EQ(WrapAngle(kPi), kPi);
  EXPECT_EQ(WrapAngle(-kPi), kPi);
  // Just past either end the value comes back in at the other end.
  const double above = WrapAngle(std::nextafter(kPi, 4.0));
  EXPECT_GT(above, -kPi);
  EXPECT_LT(above, -kPi + 1e-15);
  const double below = WrapAngle(std::nextafter(-kPi, -4.0));
  EXPECT_LE(below, kPi);
  EXPECT_GT(below, kPi - 1e-15);
}

TEST(WrapAngleTest, CrossesPlusMinusPi) {
  EXPECT_NEAR(WrapAngle(kPi + 0.1), -kPi + 0.1, 1e-15);
  EXPECT_NEAR(WrapAngle(-kPi - 0.1), kPi - 0.1, 1e-15);
  EXPECT_NEAR(WrapAngle(2 * kPi - 0.25), -0.25, 1e-15);
  EXPECT_NEAR(WrapAngle(-2 * kPi + 0.25), 0.25, 1e-15);
  EXPECT_EQ(WrapAngle(2 * kPi), 0.0);
  EXPECT_EQ(WrapAngle(-4 * kPi), 0.0);
}

TEST(WrapAngleTest, ResultIsAlwaysInTheHalfOpenInterval) {
  const uint64_t seed = 11;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> exponent(-3, 300);
  for (int i = 0; i < 20000; ++i) {
    const double x = (i % 2 == 0 ? 1 : -1) * std::pow(10.0, exponent(rng));
    const double r = WrapAngle(x);
    ASSERT_GT(r, -kPi) << x;
    ASSERT_LE(r, kPi) << x;
    ASSERT_EQ(WrapAngle(r), r) << x;  // idempotent
  }
  // Odd multiples of pi land on an end of the interval, which is pi.
  for (int k = -9; k <= 9; k += 2) {
    const double r = WrapAngle(k * kPi);
    EXPECT_GT(r, -kPi);
    EXPECT_LE(r, kPi);
    EXPECT_NEAR(std::abs(r), kPi, 1e-14) << k;
  }
}

TEST(WrapAngleTest, LargeInputsAreReducedExactlyByTheDoublePeriod) {
  const uint64_t seed = 12;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::uniform_int_distribution<int64_t> turns(-1'000'000'000, 1'000'000'000);
  for (int i = 0; i < 20000; ++i) {
    const double theta = angle(rng);
    const double k = static_cast<double>(turns(rng));
    const double y = theta + k * (2 * kPi);
    // The only error is the rounding of y itself.
    const double slack = 2 * (std::nextafter(std::abs(y), kInf) - std::abs(y));
    ASSERT_LE(std::abs(WrapAngle(WrapAngle(y) - theta)), slack) << "theta " << theta << " k " << k;
  }
}

TEST(WrapAngleTest, LargeInputsAgreeWithAnExtendedPrecisionReduction) {
  if constexpr (std::numeric_limits<long double>::digits <= 53) {
    GTEST_SKIP() << "long double is no wider than double here";
  } else {
    const long double two_pi = 2 * 3.141592653589793238462643383279502884L;
    for (double x : {7.0, -7.0, 1e3, -1e3 - 0.5, 1e6 + 0.3, -1e6, 123456789.123, 1e9, 1e12}) {
      const long double reference = std::remainder(static_cast<long double>(x), two_pi);
      const double got = WrapAngle(x);
      // The documented bound: about 4e-17 * |x| from using the double 2pi as the period.
      const double diff = std::abs(WrapAngle(static_cast<double>(got - reference)));
      EXPECT_LE(diff, 4.5e-17 * std::abs(x) + 1e-15) << x;
    }
  }
}

TEST(WrapAngleTest, AgreesWithSineAndCosine) {
  for (double x = -1e4; x <= 1e4; x += 0.731) {
    const double r = WrapAngle(x);
    ASSERT_NEAR(std::sin(r), std::sin(x), 1e-11) << x;
    ASSERT_NEAR(std::cos(r), std::cos(x), 1e-11) << x;
  }
}

TEST(WrapAngleTest, NonFiniteGivesNan) {
  EXPECT_TRUE(std::isnan(WrapAngle(kNan)));
  EXPECT_TRUE(std::isnan(WrapAngle(kInf)));
  EXPECT_TRUE(std::isnan(WrapAngle(-kInf)));
}

TEST(InnovationTest, BearingDifferenceAcrossPiIsSmall) {
  const Eigen::Vector2d v = Innovation({5.0, kPi - 0.01}, {4.5, -kPi + 0.01});
  EXPECT_DOUBLE_EQ(v(0), 0.5);
  EXPECT_NEAR(v(1), -0.02, 1e-14);
  const Eigen::Vector2d w = Innovation({5.0, -kPi + 0.01}, {5.0, kPi - 0.01});
  EXPECT_NEAR(w(1), 0.02, 1e-14);
}

// ---------------------------------------------------------------------------------------------
// The sensor and its Jacobians.

TEST(ObserveTest, RangeAndBearingOfKnownGeometry) {
  const VehiclePose pose{1, 2, kPi / 2};  // facing +y
  RangeBearing z = Observe(pose, 1, 5);   // straight ahead
  EXPECT_DOUBLE_EQ(z.range_m, 3);
  EXPECT_NEAR(z.bearing_rad, 0, 1e-15);
  z = Observe(pose, -1, 2);  // to the left: counter-clockwise from the heading is positive
  EXPECT_DOUBLE_EQ(z.range_m, 2);
  EXPECT_NEAR(z.bearing_rad, kPi / 2, 1e-15);
  z = Observe(pose, 4, 2);  // to the right
  EXPECT_NEAR(z.bearing_rad, -kPi / 2, 1e-15);
  z = Observe(pose, 1, -1);  // straight behind: -pi wraps to pi
  EXPECT_DOUBLE_EQ(z.range_m, 3);
  EXPECT_EQ(z.bearing_rad, kPi);
  z = Observe({0, 0, 3.0}, -10, -1e-9);  // just past -pi behind a heading of 3 rad
  EXPECT_GT(z.bearing_rad, -kPi);
  EXPECT_LE(z.bearing_rad, kPi);
  EXPECT_NEAR(z.bearing_rad, WrapAngle(std::atan2(-1e-9, -10.0) - 3.0), 1e-15);
}

TEST(ObserveTest, JacobiansMatchCentralDifferences) {
  const uint64_t seed = 21;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> coord(-100, 100);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::uniform_real_distribution<double> log_range(std::log(0.5), std::log(100.0));
  for (int trial = 0; trial < 500; ++trial) {
    SCOPED_TRACE(testing::Message() << "trial " << trial);
    const VehiclePose pose{coord(rng), coord(rng), angle(rng)};
    // Landmarks all around, behind included, so that bearings straddle +-pi.
    const double r = std::exp(log_range(rng));
    const double b = angle(rng);
    const double lx = pose.x_m + r * std::cos(pose.heading_rad + b);
    const double ly = pose.y_m + r * std::sin(pose.heading_rad + b);
    ObservationLinearization lin;
    ASSERT_TRUE(LinearizeObservation(pose, lx, ly, &lin).ok());
    const RangeBearing z0 = Observe(pose, lx, ly);
    EXPECT_EQ(lin.z_pred.range_m, z0.range_m);
    EXPECT_EQ(lin.z_pred.bearing_rad, z0.bearing_rad);

    const double h = 1e-5;
    auto difference = [&](const RangeBearing& plus, const RangeBearing& minus) -> Eigen::Vector2d {
      return Innovation(plus, minus) / (2 * h);
    };
    Eigen::Matrix2d fd_landmark;
    fd_landmark.col(0) = difference(Observe(pose, lx + h, ly), Observe(pose, lx - h, ly));
    fd_landmark.col(1) = difference(Observe(pose, lx, ly + h), Observe(pose, lx, ly - h));
    Matrix23d fd_pose;
    for (int i = 0; i < 3; ++i) {
      VehiclePose plus = pose;
      VehiclePose minus = pose;
      double* p = i == 0 ? &plus.x_m : i == 1 ? &plus.y_m : &plus.heading_rad;
      double* m = i == 0 ? &minus.x_m : i == 1 ? &minus.y_m : &minus.heading_rad;
      *p += h;
      *m -= h;
      fd_pose.col(i) = difference(Observe(plus, lx, ly), Observe(minus, lx, ly));
    }
    EXPECT_TRUE(MatrixNear(lin.h_landmark, fd_landmark, 1e-6));
    EXPECT_TRUE(MatrixNear(lin.h_pose, fd_pose, 1e-6));
    // Moving the landmark and the vehicle together changes nothing but the heading term.
    EXPECT_TRUE(MatrixNear(lin.h_pose.leftCols<2>(), -lin.h_landmark, 1e-15));
    EXPECT_EQ(lin.h_pose(0, 2), 0.0);
    EXPECT_EQ(lin.h_pose(1, 2), -1.0);
  }
}

TEST(ObserveTest, LinearizationAtTheSensorPositionIsReported) {
  ObservationLinearization lin;
  lin.z_pred = {-7, -7};
  Status s = LinearizeObservation({3, 4, 1}, 3, 4, &lin);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition) << s.ToString();
  EXPECT_NE(s.message().find("sensor position"), std::string::npos) << s.message();
  EXPECT_EQ(lin.z_pred.range_m, -7);  // untouched
  s = LinearizeObservation({3, kNan, 1}, 3, 4, &lin);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("pose.y_m"), std::string::npos) << s.message();
  s = LinearizeObservation({3, 4, 1}, kInf, 4, &lin);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
}

// ---------------------------------------------------------------------------------------------
// The landmark leaf and its initialisation.

TEST(LandmarkTest, IsASmallTriviallyCopyableLeaf) {
  static_assert(std::is_trivially_copyable_v<Landmark>);
  static_assert(std::is_trivially_destructible_v<Landmark>);
  EXPECT_EQ(sizeof(Landmark), 48u);
}

TEST(LandmarkTest, CovarianceAndCholeskyReadingsRoundTrip) {
  Landmark l;
  Eigen::Matrix2d p;
  p << 4, 1.5, 1.5, 2;
  SetCovariance(p, &l);
  EXPECT_EQ(Covariance(l), p);
  EXPECT_EQ(l.xy, 1.5);
  // A slightly asymmetric input is stored as its symmetric part.
  Eigen::Matrix2d q;
  q << 4, 1, 2, 2;
  SetCovariance(q, &l);
  EXPECT_EQ(l.xy, 1.5);

  const Eigen::Matrix2d factor = p.llt().matrixL();
  SetCholeskyFactor(factor, &l);
  EXPECT_EQ(CholeskyFactor(l), factor);
  EXPECT_EQ(CholeskyFactor(l)(0, 1), 0.0);
  EXPECT_TRUE(MatrixNear(CholeskyFactor(l) * CholeskyFactor(l).transpose(), p, 1e-15));
}

TEST(InitLandmarkTest, InvertsTheObservation) {
  const uint64_t seed = 31;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> coord(-100, 100);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::uniform_real_distribution<double> range(0.1, 80);
  for (int trial = 0; trial < 500; ++trial) {
    const VehiclePose pose{coord(rng), coord(rng), angle(rng)};
    const RangeBearing z{range(rng), angle(rng)};
    const Landmark l = InitLandmark(pose, z, {0.1, 0.01});
    const RangeBearing back = Observe(pose, l.x_m, l.y_m);
    ASSERT_NEAR(back.range_m, z.range_m, 1e-12) << trial;
    ASSERT_NEAR(WrapAngle(back.bearing_rad - z.bearing_rad), 0, 1e-12) << trial;
  }
}

TEST(InitLandmarkTest, CovarianceIsGRGTransposed) {
  // Ahead along +x at 10 m: range noise along x, bearing noise along y scaled by the range.
  Landmark l = InitLandmark({0, 0, 0}, {10, 0}, {0.5, 0.1});
  EXPECT_NEAR(l.x_m, 10, 1e-15);
  EXPECT_NEAR(l.y_m, 0, 1e-15);
  EXPECT_NEAR(l.xx, 0.25, 1e-15);
  EXPECT_NEAR(l.xy, 0, 1e-15);
  EXPECT_NEAR(l.yy, 1.0, 1e-14);
  // Facing +y with the landmark 90 degrees to the right: it lies along +x again.
  l = InitLandmark({1, 1, kPi / 2}, {10, -kPi / 2}, {0.5, 0.1});
  EXPECT_NEAR(l.x_m, 11, 1e-14);
  EXPECT_NEAR(l.y_m, 1, 1e-14);
  EXPECT_NEAR(l.xx, 0.25, 1e-15);
  EXPECT_NEAR(l.yy, 1.0, 1e-14);
  // General direction: P = G R G^T with G = [c, -r s; s, r c].
  const double a = 0.3 + 0.7;
  l = InitLandmark({2, 3, 0.3}, {7, 0.7}, {0.2, 0.05});
  Eigen::Matrix2d g;
  g << std::cos(a), -7 * std::sin(a), std::sin(a), 7 * std::cos(a);
  const Eigen::Matrix2d expected = g * Eigen::Vector2d(0.04, 0.0025).asDiagonal() * g.transpose();
  EXPECT_TRUE(MatrixNear(Covariance(l), expected, 1e-14));
}

TEST(InitLandmarkTest, UpdateWithTheSameObservationKeepsTheMeanAndHalvesTheCovariance) {
  // Hl G = I, so S = 2R, K = G/2 and P' = P/2 exactly (to round-off).
  const uint64_t seed = 32;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> coord(-100, 100);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::uniform_real_distribution<double> range(0.5, 50);
  std::uniform_real_distribution<double> sigma(0.01, 1);
  for (int trial = 0; trial < 300; ++trial) {
    SCOPED_TRACE(testing::Message() << "trial " << trial);
    const VehiclePose pose{coord(rng), coord(rng), angle(rng)};
    const RangeBearing z{range(rng), angle(rng)};
    const SensorNoise noise{sigma(rng), 0.1 * sigma(rng)};
    const Landmark before = InitLandmark(pose, z, noise);
    Landmark after = before;
    double ll = 0;
    ASSERT_TRUE(UpdateLandmark(pose, z, noise, &after, &ll).ok());
    EXPECT_NEAR(after.x_m, before.x_m, 1e-10 * z.range_m);
    EXPECT_NEAR(after.y_m, before.y_m, 1e-10 * z.range_m);
    EXPECT_TRUE(
        MatrixNear(Covariance(after), 0.5 * Covariance(before), 1e-9 * Covariance(before).norm()));
    // It shrinks: P - P' is positive semi-definite and the determinant drops.
    EXPECT_GE(MinEigenvalue(Covariance(before) - Covariance(after)),
              -1e-12 * Covariance(before).norm());
    EXPECT_LT(Covariance(after).determinant(), Covariance(before).determinant());
    const Eigen::Matrix2d two_r = 2 * SensorCovariance(noise);
    EXPECT_NEAR(ll, ClosedFormLogDensity<2>(Eigen::Vector2d::Zero(), two_r), 1e-9);
  }
}

// ---------------------------------------------------------------------------------------------
// FastSLAM 1.0: the EKF landmark update.

TEST(KalmanUpdateTest, EqualsTheClosedFormPosteriorOnALinearGaussianProblem) {
  const uint64_t seed = 41;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 500; ++trial) {
    SCOPED_TRACE(testing::Message() << "trial " << trial);
    const Eigen::Matrix2d p = RandomSpd<2>(rng, 2.0);
    const Eigen::Matrix2d r = RandomSpd<2>(rng, 0.3);  // not diagonal: the formulas are general
    const Eigen::Matrix2d h = RandomMatrix<2, 2>(rng, 1.0) + 2 * Eigen::Matrix2d::Identity();
    const Eigen::Vector2d m = RandomMatrix<2, 1>(rng, 10.0);
    const Eigen::Vector2d v = RandomMatrix<2, 1>(rng, 1.0);

    Eigen::Vector2d mean = m;
    Eigen::Matrix2d cov = p;
    double ll = 0;
    ASSERT_TRUE(KalmanUpdate(v, h, r, &mean, &cov, &ll).ok());

    // Bayes in information form: P+^-1 = P^-1 + H^T R^-1 H, m+ = m + P+ H^T R^-1 v.
    const Eigen::Matrix2d post = (p.inverse() + h.transpose() * r.inverse() * h).inverse();
    const Eigen::Vector2d post_mean = m + post * h.transpose() * r.inverse() * v;
    EXPECT_TRUE(MatrixNear(mean, post_mean, 1e-10));
    EXPECT_TRUE(MatrixNear(cov, post, 1e-10));
    EXPECT_EQ(cov(0, 1), cov(1, 0));
    EXPECT_NEAR(ll, ClosedFormLogDensity<2>(v, h * p * h.transpose() + r), 1e-9);
  }
}

TEST(KalmanUpdateTest, CovarianceStaysPositiveDefiniteAcrossScales) {
  // A prior much wider than the noise (P' is a small difference of large numbers: the regime where
  // P - K S K^T loses definiteness), much narrower, and between.
  const uint64_t seed = 42;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  for (double p_scale : {1e-10, 1.0, 1e6}) {
    for (double r_scale : {1e-10, 1.0, 1e6}) {
      SCOPED_TRACE(testing::Message() << "P scale " << p_scale << " R scale " << r_scale);
      for (int trial = 0; trial < 500; ++trial) {
        SCOPED_TRACE(testing::Message() << "trial " << trial);
        Eigen::Vector2d mean(3, 4);
        Eigen::Matrix2d cov = RandomSpd<2>(rng, p_scale);
        const Eigen::Matrix2d before = cov;
        const Eigen::Matrix2d r = RandomSpd<2>(rng, r_scale);
        const Eigen::Matrix2d h = RandomMatrix<2, 2>(rng, 1.0);
        const Eigen::Vector2d v = RandomMatrix<2, 1>(rng, 1.0);
        ASSERT_TRUE(KalmanUpdate(v, h, r, &mean, &cov, nullptr).ok());
        ASSERT_EQ(cov(0, 1), cov(1, 0));
        ASSERT_EQ(Eigen::LLT<Eigen::Matrix2d>(cov).info(), Eigen::Success) << cov;
        ASSERT_GE(MinEigenvalue(before - cov), -1e-12 * before.norm());
      }
    }
  }
}

TEST(UpdateLandmarkTest, MatchesAHandComputedAxisAlignedUpdate) {
  // Vehicle at the origin facing +x, landmark at (10, 0) with P = diag(1, 4), sigma = (0.5, 0.1):
  // Hl = diag(1, 0.1), S = diag(1.25, 0.05), K = diag(0.8, 8); z = (10.5, 0.05), v = (0.5, 0.05)
  // give mean (10.4, 0.4), P' = diag(0.2, 0.8).
  Landmark l{10, 0, 1, 0, 4};
  double ll = 0;
  ASSERT_TRUE(UpdateLandmark({0, 0, 0}, {10.5, 0.05}, {0.5, 0.1}, &l, &ll).ok());
  EXPECT_NEAR(l.x_m, 10.4, 1e-14);
  EXPECT_NEAR(l.y_m, 0.4, 1e-14);
  EXPECT_NEAR(l.xx, 0.2, 1e-14);
  EXPECT_NEAR(l.xy, 0, 1e-14);
  EXPECT_NEAR(l.yy, 0.8, 1e-14);
  // log N(v; 0, S) = -(0.25/1.25 + 0.0025/0.05)/2 - log(2 pi) - log(1.25 * 0.05)/2.
  EXPECT_NEAR(ll, -0.125 - std::log(2 * kPi) - 0.5 * std::log(0.0625), 1e-14);
}

TEST(UpdateLandmarkTest, IsTheKalmanUpdateOfItsLinearization) {
  const uint64_t seed = 43;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> coord(-50, 50);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  for (int trial = 0; trial < 300; ++trial) {
    SCOPED_TRACE(testing::Message() << "trial " << trial);
    const VehiclePose pose{coord(rng), coord(rng), angle(rng)};
    Landmark l{pose.x_m + coord(rng), pose.y_m + coord(rng), 0, 0, 0};
    SetCovariance(RandomSpd<2>(rng, 0.5), &l);
    const RangeBearing truth = Observe(pose, l.x_m + 0.3, l.y_m - 0.2);
    const RangeBearing z{truth.range_m, WrapAngle(truth.bearing_rad + 0.01)};
    const SensorNoise noise{0.2, 0.02};

    ObservationLinearization lin;
    ASSERT_TRUE(LinearizeObservation(pose, l.x_m, l.y_m, &lin).ok());
    Eigen::Vector2d mean = Mean(l);
    Eigen::Matrix2d cov = Covariance(l);
    double expected_ll = 0;
    ASSERT_TRUE(KalmanUpdate(Innovation(z, lin.z_pred), lin.h_landmark, SensorCovariance(noise),
                             &mean, &cov, &expected_ll)
                    .ok());
    double prior_ll = 0;
    double m2 = 0;
    ASSERT_TRUE(ObservationLogLikelihood(pose, z, noise, l, &prior_ll, &m2).ok());

    const Eigen::Matrix2d s =
        lin.h_landmark * Covariance(l) * lin.h_landmark.transpose() + SensorCovariance(noise);
    const Eigen::Vector2d v = Innovation(z, lin.z_pred);

    double ll = 0;
    ASSERT_TRUE(UpdateLandmark(pose, z, noise, &l, &ll).ok());
    EXPECT_TRUE(MatrixNear(Mean(l), mean, 1e-14));
    EXPECT_TRUE(MatrixNear(Covariance(l), cov, 1e-14));
    EXPECT_NEAR(ll, expected_ll, 1e-12);
    EXPECT_DOUBLE_EQ(prior_ll, ll);
    EXPECT_NEAR(m2, v.dot(s.inverse() * v), 1e-9 * std::max(1.0, m2));
    EXPECT_NEAR(ll, -0.5 * m2 - std::log(2 * kPi) - 0.5 * std::log(s.determinant()), 1e-9);
  }
}

TEST(UpdateLandmarkTest, BearingInnovationAcrossPiIsSmall) {
  // A landmark straight behind the vehicle, predicted at bearing pi - 0.01 and seen at
  // -pi + 0.01: the innovation is 0.02 rad, not 2 pi - 0.02.
  const VehiclePose pose{0, 0, 0};
  const Landmark before = InitLandmark(pose, {20, kPi - 0.01}, {0.1, 0.02});
  Landmark wrapped = before;
  double ll_wrapped = 0;
  ASSERT_TRUE(UpdateLandmark(pose, {20, -kPi + 0.01}, {0.1, 0.02}, &wrapped, &ll_wrapped).ok());
  // The same observation written as pi + 0.01 gives the same update.
  Landmark unwrapped = before;
  double ll_unwrapped = 0;
  ASSERT_TRUE(UpdateLandmark(pose, {20, kPi + 0.01}, {0.1, 0.02}, &unwrapped, &ll_unwrapped).ok());
  EXPECT_NEAR(wrapped.x_m, unwrapped.x_m, 1e-12);
  EXPECT_NEAR(wrapped.y_m, unwrapped.y_m, 1e-12);
  EXPECT_NEAR(ll_wrapped, ll_unwrapped, 1e-9);
  // The mean moves by about half the 0.02 rad arc (K = G/2), i.e. 0.2 m, not across the map.
  const double moved = std::hypot(wrapped.x_m - before.x_m, wrapped.y_m - before.y_m);
  EXPECT_NEAR(moved, 0.5 * 20 * 0.02, 1e-3);
  // And the likelihood is that of a 0.02 rad error: Mahalanobis (0.02)^2 / (2 * 0.02^2) = 0.5.
  EXPECT_NEAR(ll_wrapped,
              ClosedFormLogDensity<2>(Eigen::Vector2d(0, 0.02), 2 * SensorCovariance({0.1, 0.02})),
              1e-9);
}

TEST(UpdateLandmarkTest, ZeroSensorNoiseIsFlooredAndStaysExact) {
  EXPECT_EQ(SensorCovariance({0, 0}), (Eigen::Vector2d(1e-18, 1e-18).asDiagonal().toDenseMatrix()));
  EXPECT_EQ(SensorCovariance({0.5, 0})(0, 0), 0.25);
  const VehiclePose pose{12.5, -3.25, 0.7};
  const double tx = 40.1, ty = 7.3;  // the true landmark
  const SensorNoise none{0, 0};
  Landmark l = InitLandmark(pose, Observe(pose, tx, ty), none);
  EXPECT_NEAR(l.x_m, tx, 1e-12);
  EXPECT_NEAR(l.y_m, ty, 1e-12);
  for (int i = 0; i < 20; ++i) {
    const VehiclePose p{pose.x_m + i, pose.y_m - 0.5 * i, pose.heading_rad + 0.1 * i};
    double ll = 0;
    ASSERT_TRUE(UpdateLandmark(p, Observe(p, tx, ty), none, &l, &ll).ok()) << i;
    EXPECT_TRUE(std::isfinite(ll));
    EXPECT_NEAR(l.x_m, tx, 1e-12);
    EXPECT_NEAR(l.y_m, ty, 1e-12);
    EXPECT_GE(MinEigenvalue(Covariance(l)), 0);
    EXPECT_LT(Covariance(l).norm(), 1e-14);
  }
}

TEST(UpdateLandmarkTest, RejectsNonFiniteAndNegativeInputsLeavingTheLandmarkUnchanged) {
  const VehiclePose pose{1, 2, 0.3};
  const RangeBearing z{10, 0.2};
  const SensorNoise noise{0.1, 0.01};
  const Landmark good = InitLandmark(pose, z, noise);
  struct Case {
    const char* field;
    VehiclePose pose;
    RangeBearing z;
    SensorNoise noise;
    Landmark landmark;
  };
  std::vector<Case> cases;
  for (double bad : {kNan, kInf, -kInf}) {
    cases.push_back({"pose.x_m", {bad, 2, 0.3}, z, noise, good});
    cases.push_back({"pose.y_m", {1, bad, 0.3}, z, noise, good});
    cases.push_back({"pose.heading_rad", {1, 2, bad}, z, noise, good});
    cases.push_back({"z.range_m", pose, {bad, 0.2}, noise, good});
    cases.push_back({"z.bearing_rad", pose, {10, bad}, noise, good});
    cases.push_back({"noise.sigma_range_m", pose, z, {bad, 0.01}, good});
    cases.push_back({"noise.sigma_bearing_rad", pose, z, {0.1, bad}, good});
    Landmark l = good;
    l.x_m = bad;
    cases.push_back({"landmark.x_m", pose, z, noise, l});
    l = good;
    l.yy = bad;
    cases.push_back({"landmark.yy", pose, z, noise, l});
  }
  cases.push_back({"z.range_m", pose, {-1, 0.2}, noise, good});
  cases.push_back({"noise.sigma_range_m", pose, z, {-0.1, 0.01}, good});
  cases.push_back({"noise.sigma_bearing_rad", pose, z, {0.1, -0.01}, good});
  for (const Case& c : cases) {
    SCOPED_TRACE(c.field);
    Landmark l = c.landmark;
    double ll = 1234;
    const Status s = UpdateLandmark(c.pose, c.z, c.noise, &l, &ll);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << s.ToString();
    EXPECT_NE(s.message().find(c.field), std::string::npos) << s.message();
    EXPECT_TRUE(SameBytes(l, c.landmark));
    EXPECT_EQ(ll, 1234);
    double prior_ll = 1234;
    EXPECT_EQ(ObservationLogLikelihood(c.pose, c.z, c.noise, c.landmark, &prior_ll).code(),
              StatusCode::kInvalidArgument);
    EXPECT_EQ(prior_ll, 1234);
  }
  // A landmark initialised from a non-finite observation is non-finite and rejected.
  Landmark from_nan = InitLandmark(pose, {kNan, 0.2}, noise);
  EXPECT_FALSE(std::isfinite(from_nan.x_m));
  EXPECT_EQ(UpdateLandmark(pose, z, noise, &from_nan, nullptr).code(),
            StatusCode::kInvalidArgument);
}

TEST(UpdateLandmarkTest, IndefiniteLandmarkCovarianceIsReportedNotPropagated) {
  const VehiclePose pose{0, 0, 0};
  for (Landmark bad :
       {Landmark{10, 0, 1, 2, 1}, Landmark{10, 0, -1, 0, 1}, Landmark{10, 0, 0, 1e-3, 0}}) {
    Landmark l = bad;
    double ll = 99;
    const Status s = UpdateLandmark(pose, {10, 0}, {0.1, 0.01}, &l, &ll);
    EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition) << s.ToString();
    EXPECT_NE(s.message().find("landmark covariance"), std::string::npos) << s.message();
    EXPECT_TRUE(SameBytes(l, bad));
    EXPECT_EQ(ll, 99);
  }
  // A rank-one covariance (a landmark initialised at range 0) is positive semi-definite: accepted.
  Landmark rank_one{10, 0, 1, 1, 1};
  EXPECT_TRUE(UpdateLandmark(pose, {10, 0}, {0.1, 0.01}, &rank_one, nullptr).ok());
}

TEST(UpdateLandmarkTest, LandmarkAtTheSensorIsReported) {
  Landmark l{5, 5, 1, 0, 1};
  const Landmark before = l;
  const Status s = UpdateLandmark({5, 5, 0}, {1, 0}, {0.1, 0.01}, &l, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition) << s.ToString();
  EXPECT_TRUE(SameBytes(l, before));
}

TEST(UpdateLandmarkTest, OverflowIsReportedNotNan) {
  // 1 mm away with a huge covariance: Hl's bearing row is 1e3, S overflows.
  Landmark l{1e-3, 0, 1e305, 0, 1e305};
  const Landmark before = l;
  double ll = 5;
  const Status s = UpdateLandmark({0, 0, 0}, {1e-3, 0}, {0.1, 0.01}, &l, &ll);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition) << s.ToString();
  EXPECT_TRUE(SameBytes(l, before));
  EXPECT_EQ(ll, 5);
}

TEST(KalmanUpdateTest, NonPositiveDefiniteInnovationCovarianceIsReported) {
  const Eigen::Vector2d mean0(1, 2);
  for (const Eigen::Matrix2d& r :
       {Eigen::Matrix2d(Eigen::Vector2d(1, -1).asDiagonal()), Eigen::Matrix2d::Zero().eval(),
        (Eigen::Matrix2d() << 1, 2, 2, 1).finished()}) {
    Eigen::Vector2d mean = mean0;
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    double ll = 7;
    const Status s =
        KalmanUpdate(Eigen::Vector2d(0.1, 0.1), Eigen::Matrix2d::Identity(), r, &mean, &cov, &ll);
    EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition) << s.ToString();
    EXPECT_NE(s.message().find("not positive definite"), std::string::npos) << s.message();
    EXPECT_EQ(mean, mean0);
    EXPECT_EQ(cov, Eigen::Matrix2d::Zero());
    EXPECT_EQ(ll, 7);
  }
}

// ---------------------------------------------------------------------------------------------
// FastSLAM 2.0: the proposal and the weight.

// Information form of the Gaussian product N(x; mu, sigma) N(v; H (x - mu), S):
// sigma'^-1 = sigma^-1 + H^T S^-1 H, mu' = mu + sigma' H^T S^-1 v.
template <int M>
void ClosedFormProduct(const Eigen::Vector3d& mu, const Eigen::Matrix3d& sigma,
                       const Eigen::Matrix<double, M, 3>& h, const Eigen::Matrix<double, M, M>& s,
                       const Eigen::Matrix<double, M, 1>& v, Eigen::Vector3d* mu_post,
                       Eigen::Matrix3d* sigma_post) {
  *sigma_post = (h.transpose() * s.inverse() * h + sigma.inverse()).inverse();
  *mu_post = mu + *sigma_post * h.transpose() * s.inverse() * v;
}

TEST(ProposalUpdateTest, EqualsTheClosedFormGaussianProduct) {
  const uint64_t seed = 51;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 500; ++trial) {
    SCOPED_TRACE(testing::Message() << "trial " << trial);
    const Eigen::Vector3d mu0 = RandomMatrix<3, 1>(rng, 5.0);
    const Eigen::Matrix3d sigma0 = RandomSpd<3>(rng, 0.5);
    const Matrix23d h = RandomMatrix<2, 3>(rng, 1.0);
    const Eigen::Matrix2d s = RandomSpd<2>(rng, 0.2);
    const Eigen::Vector2d v = RandomMatrix<2, 1>(rng, 1.0);
    Eigen::Vector3d mu = mu0;
    Eigen::Matrix3d sigma = sigma0;
    double lw = 0;
    ASSERT_TRUE(ProposalUpdate(v, h, s, &mu, &sigma, &lw).ok());
    Eigen::Vector3d mu_post;
    Eigen::Matrix3d sigma_post;
    ClosedFormProduct<2>(mu0, sigma0, h, s, v, &mu_post, &sigma_post);
    EXPECT_TRUE(MatrixNear(mu, mu_post, 1e-9));
    EXPECT_TRUE(MatrixNear(sigma, sigma_post, 1e-9));
    EXPECT_EQ(sigma, sigma.transpose());
    EXPECT_NEAR(lw, ClosedFormLogDensity<2>(v, h * sigma0 * h.transpose() + s), 1e-9);
  }
}

TEST(ProposalUpdateTest, TwoObservationsOneByOneEqualBothJointly) {
  // Linear model z_i = H_i x + c_i + noise (S_i): applied one by one, each innovation formed at
  // the current mean, against the stacked 4-D observation applied once.
  const uint64_t seed = 52;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 300; ++trial) {
    SCOPED_TRACE(testing::Message() << "trial " << trial);
    const Eigen::Vector3d mu0 = RandomMatrix<3, 1>(rng, 5.0);
    const Eigen::Matrix3d sigma0 = RandomSpd<3>(rng, 0.5);
    const Matrix23d h1 = RandomMatrix<2, 3>(rng, 1.0);
    const Matrix23d h2 = RandomMatrix<2, 3>(rng, 1.0);
    const Eigen::Matrix2d s1 = RandomSpd<2>(rng, 0.2);
    const Eigen::Matrix2d s2 = RandomSpd<2>(rng, 0.3);
    const Eigen::Vector2d c1 = RandomMatrix<2, 1>(rng, 3.0);
    const Eigen::Vector2d c2 = RandomMatrix<2, 1>(rng, 3.0);
    const Eigen::Vector2d z1 = RandomMatrix<2, 1>(rng, 5.0);
    const Eigen::Vector2d z2 = RandomMatrix<2, 1>(rng, 5.0);

    Eigen::Vector3d mu = mu0;
    Eigen::Matrix3d sigma = sigma0;
    double lw1 = 0, lw2 = 0;
    ASSERT_TRUE(ProposalUpdate(z1 - h1 * mu - c1, h1, s1, &mu, &sigma, &lw1).ok());
    ASSERT_TRUE(ProposalUpdate(z2 - h2 * mu - c2, h2, s2, &mu, &sigma, &lw2).ok());

    Eigen::Matrix<double, 4, 3> h;
    h << h1, h2;
    Eigen::Matrix4d s = Eigen::Matrix4d::Zero();
    s.topLeftCorner<2, 2>() = s1;
    s.bottomRightCorner<2, 2>() = s2;
    Eigen::Vector4d v;
    v << z1 - h1 * mu0 - c1, z2 - h2 * mu0 - c2;
    Eigen::Vector3d mu_joint;
    Eigen::Matrix3d sigma_joint;
    ClosedFormProduct<4>(mu0, sigma0, h, s, v, &mu_joint, &sigma_joint);
    EXPECT_TRUE(MatrixNear(mu, mu_joint, 1e-9));
    EXPECT_TRUE(MatrixNear(sigma, sigma_joint, 1e-9));
    // The weight factors multiply to the joint marginal p(z1, z2) (chain rule).
    EXPECT_NEAR(lw1 + lw2, ClosedFormLogDensity<4>(v, h * sigma0 * h.transpose() + s), 1e-8);
  }
}

TEST(ProposalUpdateTest, WeightEqualsLikelihoodTimesPriorOverProposalAtAnyPose) {
  // Bailey's form of the FastSLAM 2.0 weight, p(z|x) p(x) / q(x), equals Montemerlo's
  // N(v; 0, H sigma H^T + S) for every x when the model is linear.
  const uint64_t seed = 53;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 200; ++trial) {
    SCOPED_TRACE(testing::Message() << "trial " << trial);
    const Eigen::Vector3d mu0 = RandomMatrix<3, 1>(rng, 1.0);
    const Eigen::Matrix3d sigma0 = RandomSpd<3>(rng, 0.05);
    const Matrix23d h = RandomMatrix<2, 3>(rng, 1.0);
    const Eigen::Matrix2d s = RandomSpd<2>(rng, 0.1);
    const Eigen::Vector2d c = RandomMatrix<2, 1>(rng, 1.0);
    const Eigen::Vector2d z = h * mu0 + c + RandomMatrix<2, 1>(rng, 0.5);
    Eigen::Vector3d mu = mu0;
    Eigen::Matrix3d sigma = sigma0;
    double lw = 0;
    ASSERT_TRUE(ProposalUpdate(z - h * mu0 - c, h, s, &mu, &sigma, &lw).ok());
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d x = mu + RandomMatrix<3, 1>(rng, 0.2);
      double like = 0, prior = 0, proposal = 0;
      ASSERT_TRUE(LogGaussianDensity(Eigen::Vector2d(z - h * x - c), s, &like).ok());
      ASSERT_TRUE(LogGaussianDensity(PoseDifference(x, mu0), sigma0, &prior).ok());
      ASSERT_TRUE(LogGaussianDensity(PoseDifference(x, mu), sigma, &proposal).ok());
      EXPECT_NEAR(like + prior - proposal, lw, 1e-8);
    }
  }
}

TEST(ProposalUpdateTest, SingularPriorIsUsedWithoutInverting) {
  const Matrix23d h = (Matrix23d() << -0.8, -0.6, 0, 0.06, -0.08, -1).finished();
  const Eigen::Matrix2d s = Eigen::Vector2d(0.04, 0.001).asDiagonal();
  const Eigen::Vector2d v(0.3, -0.02);
  // Zero prior covariance (zero motion noise): nothing moves, the weight is N(v; 0, S).
  Eigen::Vector3d mu(1, 2, 0.5);
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();
  double lw = 0;
  ASSERT_TRUE(ProposalUpdate(v, h, s, &mu, &sigma, &lw).ok());
  EXPECT_EQ(mu, Eigen::Vector3d(1, 2, 0.5));
  EXPECT_EQ(sigma, Eigen::Matrix3d::Zero());
  EXPECT_NEAR(lw, ClosedFormLogDensity<2>(v, s), 1e-12);
  // A known heading (zero heading variance): the heading stays, the position moves.
  mu = Eigen::Vector3d(1, 2, 0.5);
  sigma = Eigen::Vector3d(0.5, 0.5, 0).asDiagonal();
  ASSERT_TRUE(ProposalUpdate(v, h, s, &mu, &sigma, &lw).ok());
  EXPECT_EQ(mu(2), 0.5);
  EXPECT_NE(mu(0), 1);
  EXPECT_EQ(sigma.row(2), Eigen::RowVector3d::Zero());
  EXPECT_GE(MinEigenvalue(sigma), -1e-15);
  // It is the limit of the information form: compare with a heading variance of 1e-12.
  Eigen::Vector3d mu_limit;
  Eigen::Matrix3d sigma_limit;
  ClosedFormProduct<2>(Eigen::Vector3d(1, 2, 0.5), Eigen::Vector3d(0.5, 0.5, 1e-12).asDiagonal(), h,
                       s, v, &mu_limit, &sigma_limit);
  EXPECT_TRUE(MatrixNear(mu, mu_limit, 1e-9));
  EXPECT_TRUE(MatrixNear(sigma, sigma_limit, 1e-9));
}

TEST(ProposalUpdateTest, NonPositiveDefiniteInnovationCovarianceIsReported) {
  const Matrix23d h = Matrix23d::Zero();
  Eigen::Vector3d mu(1, 2, 3);
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Identity();
  double lw = 4;
  const Status s = ProposalUpdate(Eigen::Vector2d(1, 1), h, Eigen::Vector2d(1, -1).asDiagonal(),
                                  &mu, &sigma, &lw);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition) << s.ToString();
  EXPECT_EQ(mu, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(sigma, Eigen::Matrix3d::Identity());
  EXPECT_EQ(lw, 4);
}

TEST(ProposalStepTest, IsTheProposalUpdateOfItsLinearization) {
  const uint64_t seed = 54;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> coord(-50, 50);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  for (int trial = 0; trial < 300; ++trial) {
    SCOPED_TRACE(testing::Message() << "trial " << trial);
    const Eigen::Vector3d mu0(coord(rng), coord(rng), angle(rng));
    const Eigen::Matrix3d sigma0 = RandomSpd<3>(rng, 0.01);
    Landmark l{mu0(0) + coord(rng), mu0(1) + coord(rng), 0, 0, 0};
    SetCovariance(RandomSpd<2>(rng, 0.2), &l);
    const SensorNoise noise{0.3, 0.03};
    const RangeBearing truth = Observe(ToPose(mu0), l.x_m - 0.4, l.y_m + 0.1);
    const RangeBearing z{truth.range_m + 0.05, WrapAngle(truth.bearing_rad - 0.02)};

    ObservationLinearization lin;
    ASSERT_TRUE(LinearizeObservation(ToPose(mu0), l.x_m, l.y_m, &lin).ok());
    Eigen::Vector3d mu_expected = mu0;
    Eigen::Matrix3d sigma_expected = sigma0;
    double lw_expected = 0;
    const Eigen::Matrix2d s =
        lin.h_landmark * Covariance(l) * lin.h_landmark.transpose() + SensorCovariance(noise);
    ASSERT_TRUE(ProposalUpdate(Innovation(z, lin.z_pred), lin.h_pose, s, &mu_expected,
                               &sigma_expected, &lw_expected)
                    .ok());

    double lw_alone = 0;
    ASSERT_TRUE(ProposalLogWeight(mu0, sigma0, l, z, noise, &lw_alone).ok());
    Eigen::Vector3d mu = mu0;
    Eigen::Matrix3d sigma = sigma0;
    double lw = 0;
    ASSERT_TRUE(ProposalStep(&mu, &sigma, l, z, noise, &lw).ok());
    EXPECT_TRUE(MatrixNear(mu.head<2>(), mu_expected.head<2>(), 1e-12));
    EXPECT_NEAR(WrapAngle(mu(2) - mu_expected(2)), 0, 1e-12);
    EXPECT_GT(mu(2), -kPi);
    EXPECT_LE(mu(2), kPi);
    EXPECT_TRUE(MatrixNear(sigma, sigma_expected, 1e-12));
    EXPECT_NEAR(lw, lw_expected, 1e-12);
    EXPECT_DOUBLE_EQ(lw, lw_alone);
    // The proposal is narrower than the prior.
    EXPECT_GE(MinEigenvalue(sigma0 - sigma), -1e-12);
  }
}

TEST(ProposalStepTest, PullsThePoseTowardsTheObservation) {
  // Landmark known well at (10, 0); the prior says the vehicle is at the origin, the range says
  // it is 9.5 m away: the proposal moves the vehicle forward, part of the way.
  const Landmark l{10, 0, 1e-4, 0, 1e-4};
  Eigen::Vector3d mu(0, 0, 0);
  Eigen::Matrix3d sigma = Eigen::Vector3d(1, 1, 0.01).asDiagonal();
  double lw = 0;
  ASSERT_TRUE(ProposalStep(&mu, &sigma, l, {9.5, 0}, {0.1, 0.01}, &lw).ok());
  EXPECT_GT(mu(0), 0.4);
  EXPECT_LT(mu(0), 0.5);
  EXPECT_NEAR(mu(1), 0, 1e-12);
  EXPECT_LT(sigma(0, 0), 0.02);
  // An observation that agrees with the prior mean moves nothing and still narrows sigma.
  Eigen::Vector3d mu2(0, 0, 0.3);
  Eigen::Matrix3d sigma2 = Eigen::Vector3d(1, 1, 0.01).asDiagonal();
  ASSERT_TRUE(ProposalStep(&mu2, &sigma2, l, Observe({0, 0, 0.3}, 10, 0), {0.1, 0.01}).ok());
  EXPECT_TRUE(MatrixNear(mu2, Eigen::Vector3d(0, 0, 0.3), 1e-15));
  EXPECT_LT(sigma2.trace(), 1.1);  // the range pins down the position along the landmark's line
}

TEST(ProposalStepTest, BearingInnovationAcrossPiIsSmall) {
  const Landmark l{-20, 0.2, 0.01, 0, 0.01};  // behind the vehicle, bearing just below pi
  const Eigen::Vector3d mu0(0, 0, 0);
  const Eigen::Matrix3d sigma0 = Eigen::Vector3d(0.1, 0.1, 0.01).asDiagonal();
  const double predicted = Observe(ToPose(mu0), l.x_m, l.y_m).bearing_rad;
  ASSERT_GT(predicted, kPi - 0.02);
  Eigen::Vector3d mu = mu0;
  Eigen::Matrix3d sigma = sigma0;
  ASSERT_TRUE(ProposalStep(&mu, &sigma, l, {20, -kPi + 0.005}, {0.1, 0.01}).ok());
  EXPECT_LT((mu - mu0).norm(), 0.05);
  Eigen::Vector3d mu_unwrapped = mu0;
  Eigen::Matrix3d sigma_unwrapped = sigma0;
  ASSERT_TRUE(
      ProposalStep(&mu_unwrapped, &sigma_unwrapped, l, {20, kPi + 0.005}, {0.1, 0.01}).ok());
  EXPECT_TRUE(MatrixNear(mu, mu_unwrapped, 1e-12));
  double lw = 0;
  ASSERT_TRUE(ProposalLogWeight(mu0, sigma0, l, {20, -kPi + 0.005}, {0.1, 0.01}, &lw).ok());
  EXPECT_GT(lw, -10);  // a 2 pi innovation would give about -1.9e3
}

TEST(ProposalStepTest, ZeroNoiseKeepsThePoseExact) {
  const Eigen::Vector3d mu0(3, 4, 1.2);
  const Landmark l = InitLandmark(ToPose(mu0), {15, -0.4}, {0, 0});
  Eigen::Vector3d mu = mu0;
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();
  double lw = 0;
  ASSERT_TRUE(ProposalStep(&mu, &sigma, l, {15, -0.4}, {0, 0}, &lw).ok());
  EXPECT_EQ(mu, mu0);
  EXPECT_EQ(sigma, Eigen::Matrix3d::Zero());
  EXPECT_TRUE(std::isfinite(lw));
  VehiclePose sample;
  ASSERT_TRUE(SamplePose(mu, sigma, Eigen::Vector3d(0.3, -1.2, 2.0), &sample).ok());
  EXPECT_EQ(sample.x_m, 3);
  EXPECT_EQ(sample.y_m, 4);
  EXPECT_EQ(sample.heading_rad, 1.2);
}

TEST(ProposalStepTest, RejectsBadVehicleCovarianceAndInputsLeavingThemUnchanged) {
  const Landmark l{10, 0, 0.1, 0, 0.1};
  const Eigen::Vector3d mu0(0, 0, 0);
  struct Case {
    const char* what;
    StatusCode code;
    Eigen::Vector3d mu;
    Eigen::Matrix3d sigma;
    RangeBearing z;
  };
  Eigen::Matrix3d asymmetric = Eigen::Matrix3d::Identity();
  asymmetric(0, 1) = 0.5;
  Eigen::Matrix3d with_nan = Eigen::Matrix3d::Identity();
  with_nan(2, 1) = kNan;
  const Eigen::Matrix3d eye = Eigen::Matrix3d::Identity();
  const std::vector<Case> cases = {
      {"sigma", StatusCode::kInvalidArgument, mu0, asymmetric, {10, 0}},
      {"sigma(2,1)", StatusCode::kInvalidArgument, mu0, with_nan, {10, 0}},
      {"positive semi-definite",
       StatusCode::kFailedPrecondition,
       mu0,
       Eigen::Vector3d(1, -1, 1).asDiagonal(),
       {10, 0}},
      {"mu(1)", StatusCode::kInvalidArgument, Eigen::Vector3d(0, kInf, 0), eye, {10, 0}},
      {"z.bearing_rad", StatusCode::kInvalidArgument, mu0, eye, {10, kNan}},
      {"sensor position", StatusCode::kFailedPrecondition, Eigen::Vector3d(10, 0, 0), eye, {1, 0}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    Eigen::Vector3d mu = c.mu;
    Eigen::Matrix3d sigma = c.sigma;
    double lw = 8;
    Status s = ProposalStep(&mu, &sigma, l, c.z, {0.1, 0.01}, &lw);
    EXPECT_EQ(s.code(), c.code) << s.ToString();
    EXPECT_NE(s.message().find(c.what), std::string::npos) << s.message();
    EXPECT_EQ(lw, 8);
    EXPECT_TRUE(SameBytes(mu, c.mu));
    EXPECT_TRUE(SameBytes(sigma, c.sigma));
    s = ProposalLogWeight(c.mu, c.sigma, l, c.z, {0.1, 0.01}, &lw);
    EXPECT_EQ(s.code(), c.code) << s.ToString();
    EXPECT_EQ(lw, 8);
  }
  Landmark indefinite{10, 0, 1, 3, 1};
  Eigen::Vector3d mu = mu0;
  Eigen::Matrix3d sigma = eye;
  EXPECT_EQ(ProposalStep(&mu, &sigma, indefinite, {10, 0}, {0.1, 0.01}).code(),
            StatusCode::kFailedPrecondition);
  EXPECT_EQ(mu, mu0);
  EXPECT_EQ(sigma, eye);
}

// ---------------------------------------------------------------------------------------------
// Drawing a pose.

// The matrix A of the affine map n -> SamplePose(mu, sigma, n) - mu, read off unit draws.
Eigen::Matrix3d SampleMap(const Eigen::Matrix3d& sigma) {
  Eigen::Matrix3d a;
  for (int i = 0; i < 3; ++i) {
    VehiclePose p;
    EXPECT_TRUE(SamplePose(Eigen::Vector3d::Zero(), sigma, Eigen::Vector3d::Unit(i), &p).ok());
    a.col(i) = ToVector(p);
  }
  return a;
}

TEST(SamplePoseTest, UsesTheCholeskyFactorOfAPositiveDefiniteSigma) {
  const uint64_t seed = 61;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Matrix3d sigma = RandomSpd<3>(rng, 0.1);
    const Eigen::Matrix3d a = SampleMap(sigma);
    EXPECT_TRUE(MatrixNear(a * a.transpose(), sigma, 1e-12)) << trial;
    EXPECT_EQ(a(0, 1), 0.0);  // lower triangular: LLT
    EXPECT_EQ(a(0, 2), 0.0);
    EXPECT_EQ(a(1, 2), 0.0);
  }
  // Affine in the draws, around mu.
  const Eigen::Matrix3d sigma = RandomSpd<3>(rng, 0.1);
  const Eigen::Vector3d n(0.3, -1.1, 0.4);
  VehiclePose p;
  ASSERT_TRUE(SamplePose(Eigen::Vector3d(5, 6, 0.1), sigma, n, &p).ok());
  EXPECT_TRUE(MatrixNear(ToVector(p), Eigen::Vector3d(5, 6, 0.1) + SampleMap(sigma) * n, 1e-13));
}

TEST(SamplePoseTest, AcceptsPositiveSemiDefiniteSigma) {
  const Eigen::Vector3d u(1, 2, 0.1), w(-0.5, 0.3, 0.2);
  for (const Eigen::Matrix3d& sigma :
       {(u * u.transpose()).eval(), (u * u.transpose() + w * w.transpose()).eval(),
        Eigen::Vector3d(0.5, 0, 0.1).asDiagonal().toDenseMatrix(),
        Eigen::Matrix3d::Zero().eval()}) {
    SCOPED_TRACE(testing::Message() << "sigma\n" << sigma);
    const Eigen::Matrix3d a = SampleMap(sigma);
    EXPECT_TRUE(MatrixNear(a * a.transpose(), sigma, 1e-12));
  }
}

TEST(SamplePoseTest, RejectsIndefiniteAsymmetricAndNonFiniteSigma) {
  Eigen::Matrix3d asymmetric = Eigen::Matrix3d::Identity();
  asymmetric(2, 0) = 0.1;
  const std::vector<std::pair<Eigen::Matrix3d, StatusCode>> cases = {
      {Eigen::Vector3d(1, -1, 1).asDiagonal(), StatusCode::kFailedPrecondition},
      {(Eigen::Matrix3d() << 1, 2, 0, 2, 1, 0, 0, 0, 1).finished(),
       StatusCode::kFailedPrecondition},
      {(Eigen::Matrix3d() << 0, 1, 0, 1, 0, 0, 0, 0, 0).finished(),
       StatusCode::kFailedPrecondition},
      {asymmetric, StatusCode::kInvalidArgument},
      {Eigen::Matrix3d::Constant(kNan), StatusCode::kInvalidArgument},
  };
  for (const auto& [sigma, code] : cases) {
    VehiclePose p{7, 8, 9};
    const Status s = SamplePose(Eigen::Vector3d::Zero(), sigma, Eigen::Vector3d(1, 1, 1), &p);
    EXPECT_EQ(s.code(), code) << s.ToString() << "\n" << sigma;
    EXPECT_EQ(p.x_m, 7);
    EXPECT_EQ(p.y_m, 8);
    EXPECT_EQ(p.heading_rad, 9);
  }
  VehiclePose p{7, 8, 9};
  EXPECT_EQ(SamplePose(Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(),
                       Eigen::Vector3d(0, kNan, 0), &p)
                .code(),
            StatusCode::kInvalidArgument);
}

TEST(SamplePoseTest, WrapsTheHeading) {
  VehiclePose p;
  ASSERT_TRUE(SamplePose(Eigen::Vector3d(0, 0, kPi - 0.01),
                         Eigen::Vector3d(1, 1, 1e-4).asDiagonal(), Eigen::Vector3d(0, 0, 2), &p)
                  .ok());
  EXPECT_NEAR(p.heading_rad, -kPi + 0.01, 1e-12);
}

TEST(LogGaussianDensityTest, MatchesTheClosedFormAndRejectsBadCovariance) {
  const uint64_t seed = 71;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Matrix3d c = RandomSpd<3>(rng, 0.7);
    const Eigen::Vector3d v = RandomMatrix<3, 1>(rng, 1.0);
    double got = 0;
    ASSERT_TRUE(LogGaussianDensity(v, c, &got).ok());
    EXPECT_NEAR(got, ClosedFormLogDensity<3>(v, c), 1e-10);
  }
  // Far in the tail the log density is finite where the density itself underflows.
  double far = 0;
  ASSERT_TRUE(LogGaussianDensity(Eigen::Vector2d(100, 0), Eigen::Matrix2d::Identity(), &far).ok());
  EXPECT_NEAR(far, -5000 - std::log(2 * kPi), 1e-9);
  EXPECT_EQ(std::exp(far), 0.0);
  double untouched = 3;
  EXPECT_EQ(LogGaussianDensity(Eigen::Vector2d(1, 0), Eigen::Matrix2d::Zero(), &untouched).code(),
            StatusCode::kFailedPrecondition);
  EXPECT_EQ(untouched, 3);
}

// Cholesky3 is Eigen's LLT bit for bit on positive definite matrices (near-singular ones too)
// and fails where it fails; PositivePivots3 decides as it does.
TEST(Cholesky3Test, MatchesEigensLltBitForBit) {
  std::mt19937_64 rng(91);
  std::normal_distribution<double> normal(0, 1);
  int failures = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::Matrix3d a;
    for (int k = 0; k < 9; ++k) a(k / 3, k % 3) = normal(rng);
    Eigen::Matrix3d m = a * a.transpose();
    if (trial % 4 == 1) m(2, 2) -= 1.5 * std::fabs(normal(rng));  // often indefinite
    if (trial % 4 == 2) m = a.col(0) * a.col(0).transpose() + 1e-13 * Eigen::Matrix3d::Identity();
    const Eigen::LLT<Eigen::Matrix3d> llt(m);
    Eigen::Matrix3d l;
    const bool ok = Cholesky3(m, &l);
    ASSERT_EQ(ok, llt.info() == Eigen::Success) << m;
    // The square-root-free test decides alike away from the boundary (the near-singular ones
    // are positive definite by a margin of 1e-13 here).
    EXPECT_EQ(PositivePivots3(m), ok) << m;
    if (!ok) {
      ++failures;
      continue;
    }
    const Eigen::Matrix3d want = llt.matrixL();
    EXPECT_EQ(std::memcmp(l.data(), want.data(), sizeof(double) * 9), 0) << m;
  }
  EXPECT_GT(failures, 0);  // both outcomes were exercised
}

}  // namespace
}  // namespace grove::fastslam

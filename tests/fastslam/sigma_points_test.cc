// The sigma-point transforms and the per-particle steps of U-FastSLAM and SRCD-FastSLAM: exact on
// linear-Gaussian problems (the Kalman filter's answer), close to the EKF on near-linear ones,
// Cholesky updates and downdates against recomputed factors, and lost definiteness reported.
#include "engine/fastslam/sigma_points.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <random>

#include "engine/fastslam/data_association.h"
#include "engine/fastslam/landmark_math.h"
#include "engine/fastslam/sigma_point_filters.h"
#include "engine/fastslam/vehicle_model.h"
#include "tests/fastslam/matrix_testing.h"

namespace grove::fastslam {
namespace {

constexpr double kPi = std::numbers::pi;

template <int N>
bool LowerWithNonNegativeDiagonal(const Mat<N, N>& s) {
  for (int i = 0; i < N; ++i) {
    if (s(i, i) < 0) return false;
    for (int j = i + 1; j < N; ++j) {
      if (s(i, j) != 0) return false;
    }
  }
  return true;
}

TEST(SigmaPointWeights, MeanWeightsSumToOne) {
  for (int l : {2, 4, 5, 7}) {
    const UnscentedWeights u = UnscentedWeightsFor(l, 0.9, 2, 0, 2);
    EXPECT_NEAR(u.wm0 + 2 * l * u.wi, 1, 1e-14) << l;
    const CentralDifferenceWeights c = CentralDifferenceWeightsFor(l, std::sqrt(3.0));
    EXPECT_NEAR(c.wm0 + 2 * l * c.wi, 1, 1e-14) << l;
    // van der Merwe's Eq. 3.100: wc1 = 1 / (4 h^2), wc2 = (h^2 - 1) / (4 h^4).
    EXPECT_NEAR(c.sqrt_wc1 * c.sqrt_wc1, 1.0 / 12, 1e-15);
    EXPECT_NEAR(c.sqrt_wc2 * c.sqrt_wc2, 2.0 / 36, 1e-15);
  }
}

TEST(TriangularFactorTest, FactorsTheCompoundMatrix) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const Mat<3, 8> b = RandomMatrix<3, 8>(rng, 2.0);
    const Mat<3, 3> s = TriangularFactor<3, 8>(b);
    EXPECT_TRUE(LowerWithNonNegativeDiagonal<3>(s)) << "seed 7, trial " << trial << "\n" << s;
    EXPECT_TRUE(MatrixNear(Mat<3, 3>(s * s.transpose()), Mat<3, 3>(b * b.transpose()), 1e-12))
        << "seed 7, trial " << trial;
  }
}

TEST(CholeskyRankOneTest, UpdateAndDowndateMatchRecomputedFactors) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 100; ++trial) {
    const Mat<4, 4> a = RandomSpd<4>(rng, 1.5);
    const Vec<4> v = RandomMatrix<4, 1>(rng, 1.0);
    const Mat<4, 4> l = a.llt().matrixL();
    Mat<4, 4> up = l;
    ASSERT_TRUE(CholeskyRankOne<4>(&up, v, +1).ok());
    const Mat<4, 4> expected_up = Mat<4, 4>(a + v * v.transpose()).llt().matrixL();
    EXPECT_TRUE(MatrixNear(up, expected_up, 1e-11)) << "seed 11, trial " << trial;
    // And back down.
    Mat<4, 4> down = up;
    ASSERT_TRUE(CholeskyRankOne<4>(&down, v, -1).ok()) << "seed 11, trial " << trial;
    EXPECT_TRUE(MatrixNear(down, l, 1e-9)) << "seed 11, trial " << trial;
  }
}

TEST(CholeskyRankOneTest, ADowndateThatLosesDefinitenessIsReportedAndChangesNothing) {
  const Mat<2, 2> l = Mat<2, 2>(Eigen::Vector2d(2.0, 1.0).asDiagonal());  // P = diag(4, 1)
  Mat<2, 2> s = l;
  // Removing (0, 1.5)(0, 1.5)^T from diag(4, 1) leaves diag(4, -1.25).
  Status st = CholeskyRankOne<2>(&s, Vec<2>(0, 1.5), -1);
  EXPECT_EQ(st.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(st.message().find("positive definite"), std::string::npos) << st.message();
  EXPECT_EQ(s, l);
  // Exactly singular is not positive definite either.
  st = CholeskyRankOne<2>(&s, Vec<2>(0, 1.0), -1);
  EXPECT_EQ(st.code(), StatusCode::kFailedPrecondition);
  EXPECT_TRUE(s.allFinite());
}

// A linear f: both transforms give A m + b, A P A^T and P A^T exactly (to round-off), for any
// parameters; the square-root update then gives the Kalman filter's mean and covariance.
TEST(SigmaPointTransforms, ExactOnLinearGaussianProblems) {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 30; ++trial) {
    const Vec<4> m = RandomMatrix<4, 1>(rng, 3.0);
    const Mat<4, 4> p = RandomSpd<4>(rng, 0.7);
    const Mat<4, 4> root = p.llt().matrixL();
    const Mat<2, 4> a = RandomMatrix<2, 4>(rng, 1.0);
    const Vec<2> b = RandomMatrix<2, 1>(rng, 1.0);
    auto f = [&](const Vec<4>& x, Vec<2>* y) {
      *y = a * x + b;
      return true;
    };
    const Vec<2> y_mean = a * m + b;
    const Mat<2, 2> y_cov = a * p * a.transpose();
    const Mat<4, 2> cross = p * a.transpose();

    for (const UnscentedWeights& w :
         {UnscentedWeightsFor(4, 0.9, 2, 0), UnscentedWeightsFor(4, 0.9, 2, 0, 2),
          UnscentedWeightsFor(4, 1.0, 0, 1)}) {
      Vec<2> ym;
      Mat<2, 2> yc;
      Mat<4, 2> xc;
      ASSERT_TRUE((UnscentedTransform<4, 2>(m, root, w, -1, f, &ym, &yc, &xc)));
      EXPECT_TRUE(MatrixNear(ym, y_mean, 1e-12)) << "seed 3, trial " << trial;
      EXPECT_TRUE(MatrixNear(yc, y_cov, 1e-12)) << "seed 3, trial " << trial;
      EXPECT_TRUE(MatrixNear(xc, cross, 1e-12)) << "seed 3, trial " << trial;
    }
    for (double h : {std::sqrt(3.0), 1.5}) {
      Vec<2> ym;
      Mat<2, 2> ys;
      Mat<2, 4> d;
      ASSERT_TRUE((CentralDifferenceTransform<4, 2>(m, root, CentralDifferenceWeightsFor(4, h), -1,
                                                    f, nullptr, &ym, &ys, &d)));
      EXPECT_TRUE(MatrixNear(ym, y_mean, 1e-12)) << "seed 3, trial " << trial;
      EXPECT_TRUE(MatrixNear(Mat<2, 2>(ys * ys.transpose()), y_cov, 1e-12))
          << "seed 3, trial " << trial;
      EXPECT_TRUE(MatrixNear(Mat<4, 2>(root * d.transpose()), cross, 1e-12))
          << "seed 3, trial " << trial;
    }
  }
}

TEST(SigmaPointTransforms, SquareRootAndUnscentedUpdatesEqualTheKalmanFilter) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 30; ++trial) {
    const Vec<3> m = RandomMatrix<3, 1>(rng, 2.0);
    const Mat<3, 3> p = RandomSpd<3>(rng, 0.5);
    const Mat<3, 3> root = p.llt().matrixL();
    const Mat<2, 3> h = RandomMatrix<2, 3>(rng, 1.0);
    const Mat<2, 2> r = RandomSpd<2>(rng, 0.1);
    const Mat<2, 2> r_root = r.llt().matrixL();
    const Vec<2> z = RandomMatrix<2, 1>(rng, 1.0);
    // The Kalman filter.
    const Mat<2, 2> s = h * p * h.transpose() + r;
    const Mat<3, 2> k = p * h.transpose() * s.inverse();
    const Vec<3> kf_mean = m + k * (z - h * m);
    const Mat<3, 3> kf_cov = p - k * s * k.transpose();
    const Vec<2> v = z - h * m;
    const double kf_ll =
        -0.5 * v.dot(s.inverse() * v) - 0.5 * std::log(std::pow(2 * kPi, 2) * s.determinant());
    auto f = [&](const Vec<3>& x, Vec<2>* y) {
      *y = h * x;
      return true;
    };
    // SR-CDKF.
    Vec<2> z_hat;
    Mat<2, 2> s_z;
    Mat<2, 3> d;
    ASSERT_TRUE((CentralDifferenceTransform<3, 2>(m, root, CentralDifferenceWeightsFor(3, 1.7), -1,
                                                  f, &r_root, &z_hat, &s_z, &d)));
    Vec<3> x = m;
    Mat<3, 3> sx = root;
    double ll = 0;
    ASSERT_TRUE((SquareRootUpdate<3, 2>(root * d.transpose(), s_z, z - z_hat, &x, &sx, &ll)).ok());
    EXPECT_TRUE(MatrixNear(x, kf_mean, 1e-10)) << "seed 5, trial " << trial;
    EXPECT_TRUE(MatrixNear(Mat<3, 3>(sx * sx.transpose()), kf_cov, 1e-10))
        << "seed 5, trial " << trial;
    EXPECT_TRUE(LowerWithNonNegativeDiagonal<3>(sx));
    EXPECT_NEAR(ll, kf_ll, 1e-10) << "seed 5, trial " << trial;
    // UKF.
    Mat<2, 2> sy;
    Mat<3, 2> xc;
    ASSERT_TRUE((UnscentedTransform<3, 2>(m, root, UnscentedWeightsFor(3, 0.9, 2, 0), -1, f, &z_hat,
                                          &sy, &xc)));
    sy += r;
    const Mat<3, 2> ku = xc * sy.inverse();
    EXPECT_TRUE(MatrixNear(Vec<3>(m + ku * (z - z_hat)), kf_mean, 1e-10))
        << "seed 5, trial " << trial;
    EXPECT_TRUE(MatrixNear(Mat<3, 3>(p - ku * sy * ku.transpose()), kf_cov, 1e-10));
  }
}

TEST(SigmaPointTransforms, AnglesAcrossPiAverageCorrectly) {
  // x = heading near pi, y = x wrapped: the points straddle +-pi.
  const Vec<1> m(kPi - 0.01);
  const Mat<1, 1> root(0.05);
  auto f = [](const Vec<1>& x, Vec<1>* y) {
    (*y)(0) = WrapAngle(x(0));
    return true;
  };
  Vec<1> ym;
  Mat<1, 1> yc;
  ASSERT_TRUE((UnscentedTransform<1, 1>(m, root, UnscentedWeightsFor(1, 0.9, 2, 0), 0, f, &ym, &yc,
                                        nullptr)));
  EXPECT_NEAR(WrapAngle(ym(0)), kPi - 0.01, 1e-12);
  EXPECT_NEAR(yc(0, 0), 0.0025, 1e-12);
  Mat<1, 1> ys;
  ASSERT_TRUE((CentralDifferenceTransform<1, 1>(m, root, CentralDifferenceWeightsFor(1, 1.7320508),
                                                0, f, nullptr, &ym, &ys, nullptr)));
  EXPECT_NEAR(WrapAngle(ym(0)), kPi - 0.01, 1e-12);
  EXPECT_NEAR(ys(0, 0), 0.05, 1e-12);
}

TEST(SquareRootUpdateTest, InconsistentCrossCovarianceIsReportedNotNaN) {
  // A cross-covariance far larger than the state's own: the downdate would remove more than the
  // covariance holds.
  Vec<2> x(1, 2);
  Mat<2, 2> s = Mat<2, 2>::Identity();
  const Mat<2, 2> s_z = Mat<2, 2>::Identity();
  const Mat<2, 2> pxz = 3 * Mat<2, 2>::Identity();
  Status st = SquareRootUpdate<2, 2>(pxz, s_z, Vec<2>(0.5, 0.5), &x, &s, nullptr);
  EXPECT_EQ(st.code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(x, Vec<2>(1, 2));
  EXPECT_EQ(s, (Mat<2, 2>::Identity()));
  // A singular innovation factor.
  st = SquareRootUpdate<2, 2>(Mat<2, 2>::Zero(), Mat<2, 2>::Zero(), Vec<2>(0, 0), &x, &s, nullptr);
  EXPECT_EQ(st.code(), StatusCode::kFailedPrecondition);
}

// Near-linear problems (a landmark far away and well known, small noise): the unscented and
// central-difference steps agree with the EKF's and with each other.
TEST(SigmaPointFilters, AgreeWithTheEkfOnNearLinearProblems) {
  const SensorNoise noise{0.05, 0.2 * kPi / 180};
  const VehiclePose pose{1.0, -2.0, 0.3};
  Landmark l;
  l.x_m = 60;
  l.y_m = 25;
  SetCovariance((Eigen::Matrix2d() << 0.02, 0.004, 0.004, 0.01).finished(), &l);
  const RangeBearing z = Observe(VehiclePose{1.05, -2.02, 0.301}, l.x_m + 0.05, l.y_m - 0.03);
  Landmark ekf = l, ukf = l;
  double ll_ekf = 0, ll_ukf = 0, ll_cd = 0;
  ASSERT_TRUE(UpdateLandmark(pose, z, noise, &ekf, &ll_ekf).ok());
  ASSERT_TRUE(UnscentedUpdateLandmark(pose, z, noise, UnscentedRule{}, &ukf, &ll_ukf).ok());
  Landmark root = l;  // the square-root reading of l
  SetCholeskyFactor(Covariance(l).llt().matrixL(), &root);
  Landmark cd = root;
  ASSERT_TRUE(CentralDifferenceUpdateLandmark(pose, z, noise, std::sqrt(3.0), &cd, &ll_cd).ok());
  const Landmark cd_cov = WithCovariance(cd);
  const Landmark* estimates[] = {&ukf, &cd_cov};
  for (const Landmark* x : estimates) {
    EXPECT_NEAR(x->x_m, ekf.x_m, 1e-4);
    EXPECT_NEAR(x->y_m, ekf.y_m, 1e-4);
    EXPECT_TRUE(MatrixNear(Covariance(*x), Covariance(ekf), 1e-3));
  }
  EXPECT_NEAR(ll_ukf, ll_ekf, 1e-2);
  EXPECT_NEAR(ll_cd, ll_ekf, 1e-2);
  // And with each other.
  EXPECT_TRUE(MatrixNear(Mean(ukf), Mean(cd_cov), 1e-4));
  EXPECT_TRUE(MatrixNear(Covariance(ukf), Covariance(cd_cov), 1e-3));
  EXPECT_NEAR(ll_ukf, ll_cd, 1e-2);

  // The proposal step.
  const Eigen::Vector3d mu(1.0, -2.0, 0.3);
  const Eigen::Matrix3d sigma = Eigen::Vector3d(0.01, 0.02, 1e-5).asDiagonal();
  Eigen::Vector3d mu_ekf = mu, mu_ukf = mu, mu_cd = mu;
  Eigen::Matrix3d s_ekf = sigma, s_ukf = sigma, f_cd = sigma.llt().matrixL();
  double w_ekf = 0, w_ukf = 0, w_cd = 0;
  ASSERT_TRUE(ProposalStep(&mu_ekf, &s_ekf, l, z, noise, &w_ekf).ok());
  ASSERT_TRUE(UnscentedProposalStep(&mu_ukf, &s_ukf, l, z, noise, UnscentedRule{}, &w_ukf).ok());
  ASSERT_TRUE(
      CentralDifferenceProposalStep(&mu_cd, &f_cd, root, z, noise, std::sqrt(3.0), &w_cd).ok());
  EXPECT_TRUE(MatrixNear(mu_ukf, mu_ekf, 1e-4));
  EXPECT_TRUE(MatrixNear(mu_cd, mu_ekf, 1e-4));
  EXPECT_TRUE(MatrixNear(s_ukf, s_ekf, 1e-3));
  EXPECT_TRUE(MatrixNear(Eigen::Matrix3d(f_cd * f_cd.transpose()), s_ekf, 1e-3));
  EXPECT_NEAR(w_ukf, w_ekf, 1e-2);
  EXPECT_NEAR(w_cd, w_ekf, 1e-2);
  EXPECT_TRUE(MatrixNear(mu_ukf, mu_cd, 1e-4));
  EXPECT_NEAR(w_ukf, w_cd, 1e-2);

  // The prediction over one control with small noise.
  const VehicleGeometry g{FastSlamVehicle::kBailey, 4.0};
  const ControlNoise q{0.05, 0.5 * kPi / 180};
  Eigen::Vector3d m_ukf = mu, m_cd = mu;
  Eigen::Matrix3d c_ukf = sigma, c_cd = sigma.llt().matrixL();
  ASSERT_TRUE(UnscentedPredict(g, 3.0, 0.1, 0.025, q, UnscentedRule{}, &m_ukf, &c_ukf).ok());
  ASSERT_TRUE(CentralDifferencePredict(g, 3.0, 0.1, 0.025, q, std::sqrt(3.0), &m_cd, &c_cd).ok());
  Eigen::Matrix3d gv;
  Eigen::Matrix<double, 3, 2> gu;
  VehicleJacobians(g, ToPose(mu), 3.0, 0.1, 0.025, &gv, &gu);
  const VehiclePose moved = MoveVehicle(g, ToPose(mu), 3.0, 0.1, 0.025);
  const Eigen::Matrix3d ekf_cov =
      gv * sigma * gv.transpose() + gu *
                                        Eigen::Vector2d(q.sigma_speed_mps * q.sigma_speed_mps,
                                                        q.sigma_steer_rad * q.sigma_steer_rad)
                                            .asDiagonal() *
                                        gu.transpose();
  EXPECT_TRUE(MatrixNear(m_ukf, ToVector(moved), 1e-5));
  EXPECT_TRUE(MatrixNear(m_cd, ToVector(moved), 1e-5));
  EXPECT_TRUE(MatrixNear(c_ukf, ekf_cov, 1e-4));
  EXPECT_TRUE(MatrixNear(Eigen::Matrix3d(c_cd * c_cd.transpose()), ekf_cov, 1e-4));
}

TEST(SigmaPointFilters, CentralDifferenceInitIsCloseToTheEkfAndWithinItsBound) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const VehiclePose pose{10 * u(rng), -5 * u(rng), kPi * (2 * u(rng) - 1)};
    const SensorNoise noise{2 * u(rng), 0.5 * u(rng)};
    const RangeBearing z{60 * u(rng), kPi * (2 * u(rng) - 1)};
    const Landmark cd = CentralDifferenceInitLandmark(pose, z, noise, std::sqrt(3.0));
    const Eigen::Matrix2d p = Covariance(WithCovariance(cd));
    const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(p).eigenvalues()(1);
    EXPECT_LE(largest, InitCovarianceBound(z.range_m, noise, std::sqrt(3.0)) * (1 + 1e-9))
        << "seed 13, trial " << trial;
  }
  // Small noise: the EKF's G R G^T.
  const VehiclePose pose{1, 2, 0.4};
  const SensorNoise noise{0.01, 0.001};
  const RangeBearing z{20, -0.7};
  const Landmark ekf = InitLandmark(pose, z, noise);
  const Landmark cd = WithCovariance(CentralDifferenceInitLandmark(pose, z, noise, std::sqrt(3.0)));
  // The means differ by the second-order bias r (1 - cos(h sb)) / h^2 ~ r sb^2 / 2 = 1e-5 m.
  EXPECT_NEAR(cd.x_m, ekf.x_m, 3e-5);
  EXPECT_NEAR(cd.y_m, ekf.y_m, 3e-5);
  EXPECT_TRUE(MatrixNear(Covariance(cd), Covariance(ekf), 1e-6));
}

TEST(SigmaPointFilters, UnusableSigmaPointsAreReported) {
  // A landmark at the sensor: every step reports it.
  const SensorNoise noise{0.1, 0.01};
  Landmark l;
  l.x_m = 1;
  l.y_m = 1;
  SetCovariance(Eigen::Matrix2d::Zero(), &l);
  Landmark copy = l;
  Status s = UnscentedUpdateLandmark(VehiclePose{1, 1, 0}, RangeBearing{1, 0}, noise,
                                     UnscentedRule{}, &copy, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(copy.x_m, l.x_m);
  Landmark cd = l;
  s = CentralDifferenceUpdateLandmark(VehiclePose{1, 1, 0}, RangeBearing{1, 0}, noise, 1.7, &cd,
                                      nullptr);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  // A non-finite pose.
  Eigen::Vector3d mu(NAN, 0, 0);
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
  s = CentralDifferenceProposalStep(&mu, &f, l, RangeBearing{1, 0}, noise, 1.7, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace grove::fastslam

#include "engine/fastslam/landmark_math.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <string_view>

#include "engine/fastslam/landmark_batch.h"

// Structure: each public function validates its inputs once, then runs an unchecked core
// (Linearize, KalmanCore, ProposalCore) that checks only what the arithmetic itself can break
// (a factorisation failing, a result overflowing). These run once per observation and particle,
// the filter's innermost loop, so error messages are formatted only on the error path.

namespace grove::fastslam {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2 * std::numbers::pi;  // exactly twice kPi
const double kLogTwoPi = std::log(kTwoPi);

// Messages (error path only).

template <typename Derived>
std::string FormatMatrix(const Eigen::MatrixBase<Derived>& m) {
  std::string out = "[";
  for (int i = 0; i < m.rows(); ++i) {
    out += i == 0 ? "[" : ", [";
    for (int j = 0; j < m.cols(); ++j) out += fmt::format("{}{}", j == 0 ? "" : ", ", m(i, j));
    out += "]";
  }
  return out + "]";
}

Eigen::Matrix2d Matrix2Of(double a, double b, double c) {
  return (Eigen::Matrix2d() << a, b, b, c).finished();
}

Status NotFinite(std::string_view name, double value) {
  return InvalidArgumentError(fmt::format("{} = {}: must be finite", name, value));
}

// The first non-finite entry of `m`, named name(i) or name(i,j); Ok if there is none.
template <typename Derived>
Status NotFiniteEntry(std::string_view name, const Eigen::MatrixBase<Derived>& m) {
  for (int i = 0; i < m.rows(); ++i) {
    for (int j = 0; j < m.cols(); ++j) {
      if (!std::isfinite(m(i, j))) {
        return NotFinite(
            m.cols() == 1 ? fmt::format("{}({})", name, i) : fmt::format("{}({},{})", name, i, j),
            m(i, j));
      }
    }
  }
  return Status::Ok();
}

Status NotPositiveDefinite(std::string_view what, const Eigen::Matrix2d& m) {
  return FailedPreconditionError(
      fmt::format("{} = {} is not positive definite", what, FormatMatrix(m)));
}

// Small numerical helpers.

// The symmetric part of a square matrix (expression), evaluated.
template <typename Derived>
typename Derived::PlainObject Symmetric(const Eigen::MatrixBase<Derived>& expression) {
  const typename Derived::PlainObject a = expression;
  return 0.5 * (a + a.transpose());
}

// log N(v; 0, C) from C = L L^T: -|L^-1 v|^2 / 2 - (N/2) log 2pi - log prod L_ii. (The product
// of the pivots under- or overflows only for covariances beyond 1e+-150 per axis; the caller's
// finiteness check reports that.)
template <int N>
double LogDensity(const Eigen::LLT<Eigen::Matrix<double, N, N>>& llt,
                  const Eigen::Matrix<double, N, 1>& v, double* mahalanobis_sq = nullptr) {
  const Eigen::Matrix<double, N, 1> w = llt.matrixL().solve(v);
  const double m2 = w.squaredNorm();
  if (mahalanobis_sq != nullptr) *mahalanobis_sq = m2;
  return -0.5 * m2 - 0.5 * N * kLogTwoPi - std::log(llt.matrixLLT().diagonal().prod());
}

// Validation.

bool Finite(const VehiclePose& p) {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.heading_rad);
}

Status ValidatePose(const VehiclePose& p) {
  if (Finite(p)) [[likely]]
    return Status::Ok();
  if (!std::isfinite(p.x_m)) return NotFinite("pose.x_m", p.x_m);
  if (!std::isfinite(p.y_m)) return NotFinite("pose.y_m", p.y_m);
  return NotFinite("pose.heading_rad", p.heading_rad);
}

// Why the inputs of one observation are unusable. Called only when the fast test failed.
Status DescribeBadInputs(const VehiclePose& pose, const RangeBearing& z, const SensorNoise& noise,
                         const Landmark& l) {
  GROVE_RETURN_IF_ERROR(ValidatePose(pose));
  if (!std::isfinite(z.range_m)) return NotFinite("z.range_m", z.range_m);
  if (!std::isfinite(z.bearing_rad)) return NotFinite("z.bearing_rad", z.bearing_rad);
  if (z.range_m < 0) {
    return InvalidArgumentError(fmt::format("z.range_m = {}: must be >= 0", z.range_m));
  }
  GROVE_RETURN_IF_ERROR(ValidateSensorNoise(noise));
  if (!std::isfinite(l.x_m)) return NotFinite("landmark.x_m", l.x_m);
  if (!std::isfinite(l.y_m)) return NotFinite("landmark.y_m", l.y_m);
  if (!std::isfinite(l.xx)) return NotFinite("landmark.xx", l.xx);
  if (!std::isfinite(l.xy)) return NotFinite("landmark.xy", l.xy);
  if (!std::isfinite(l.yy)) return NotFinite("landmark.yy", l.yy);
  return FailedPreconditionError(
      fmt::format("landmark covariance (xx = {}, xy = {}, yy = {}) is not positive semi-definite",
                  l.xx, l.xy, l.yy));
}

// Finite pose, z, noise and landmark; range and sigmas >= 0; landmark covariance positive
// semi-definite.
bool InputsUsable(const VehiclePose& pose, const RangeBearing& z, const SensorNoise& noise,
                  const Landmark& l) {
  // x * 0 is 0 for a finite x and NaN otherwise, and a NaN survives the sum: one test for all.
  const double zeros = (pose.x_m * 0 + pose.y_m * 0 + pose.heading_rad * 0) +
                       (z.range_m * 0 + z.bearing_rad * 0) +
                       (noise.sigma_range_m * 0 + noise.sigma_bearing_rad * 0) +
                       (l.x_m * 0 + l.y_m * 0 + l.xx * 0 + l.xy * 0 + l.yy * 0);
  // Positive definite (leading minors above 0: the usual case) without a factorisation, else
  // the semi-definite test.
  return zeros == 0 && z.range_m >= 0 && noise.sigma_range_m >= 0 && noise.sigma_bearing_rad >= 0 &&
         ((l.xx > 0 && l.xx * l.yy - l.xy * l.xy > 0) || PsdSquareRoot<2>(Covariance(l), nullptr));
}

Status ValidateInputs(const VehiclePose& pose, const RangeBearing& z, const SensorNoise& noise,
                      const Landmark& l) {
  if (InputsUsable(pose, z, noise, l)) [[likely]] {
    return Status::Ok();
  }
  return DescribeBadInputs(pose, z, noise, l);
}

// Finite and symmetric within kSymmetryTolerance.
Status ValidateVehicleCovariance(const Eigen::Matrix3d& a) {
  if (!a.allFinite()) [[unlikely]]
    return NotFiniteEntry("sigma", a);
  const double scale = std::max({std::abs(a(0, 0)), std::abs(a(1, 1)), std::abs(a(2, 2))});
  const double tol = kSymmetryTolerance * scale;
  if (std::abs(a(0, 1) - a(1, 0)) > tol || std::abs(a(0, 2) - a(2, 0)) > tol ||
      std::abs(a(1, 2) - a(2, 1)) > tol) [[unlikely]] {
    return InvalidArgumentError(fmt::format("sigma = {}: must be symmetric", FormatMatrix(a)));
  }
  return Status::Ok();
}

// Cores: inputs already validated.

// The linearisation at (pose, lx, ly). REQUIRES: finite inputs.
Status Linearize(const VehiclePose& pose, double lx, double ly, ObservationLinearization* out) {
  const double dx = lx - pose.x_m;
  const double dy = ly - pose.y_m;
  const double q = dx * dx + dy * dy;
  if (!(q > 0)) [[unlikely]] {
    return FailedPreconditionError(fmt::format(
        "landmark ({}, {}) is at the sensor position: the bearing has no derivative", lx, ly));
  }
  const double r = std::sqrt(q);
  out->z_pred = {r, WrapAngle(std::atan2(dy, dx) - pose.heading_rad)};
  out->h_landmark << dx / r, dy / r, -dy / q, dx / q;
  out->h_pose << -dx / r, -dy / r, 0, dy / q, -dx / q, -1;
  if (!std::isfinite(q) || !out->h_landmark.allFinite()) [[unlikely]] {
    return FailedPreconditionError(
        fmt::format("landmark ({}, {}) seen from ({}, {}): the observation Jacobian overflows", lx,
                    ly, pose.x_m, pose.y_m));
  }
  return Status::Ok();
}

// The innovation S = H P H^T + R of a 2x2 Kalman update, in closed form: the symmetric
// entries, the determinant, and the products H P that the gain reuses.
struct Innovation2 {
  double hp00, hp01, hp10, hp11;  // H P
  double s00, s01, s11;           // S
  double det;                     // det S
};

// S and its determinant, or why S is unusable (not finite, not positive definite). REQUIRES:
// finite inputs, p and r symmetric (only their upper triangles are read).
Status InnovationOf(const Eigen::Matrix2d& h, const Eigen::Matrix2d& p, const Eigen::Matrix2d& r,
                    Innovation2* out) {
  const double h00 = h(0, 0), h01 = h(0, 1), h10 = h(1, 0), h11 = h(1, 1);
  const double a = p(0, 0), b = p(0, 1), c = p(1, 1);
  Innovation2& n = *out;
  n.hp00 = h00 * a + h01 * b;
  n.hp01 = h00 * b + h01 * c;
  n.hp10 = h10 * a + h11 * b;
  n.hp11 = h10 * b + h11 * c;
  n.s00 = n.hp00 * h00 + n.hp01 * h01 + r(0, 0);
  n.s01 = n.hp00 * h10 + n.hp01 * h11 + r(0, 1);
  n.s11 = n.hp10 * h10 + n.hp11 * h11 + r(1, 1);
  n.det = n.s00 * n.s11 - n.s01 * n.s01;
  if (!std::isfinite(n.s00) || !std::isfinite(n.s01) || !std::isfinite(n.s11)) [[unlikely]] {
    return FailedPreconditionError(fmt::format("innovation covariance S = {} is not finite",
                                               FormatMatrix(Matrix2Of(n.s00, n.s01, n.s11))));
  }
  if (!(n.s00 > 0 && n.det > 0) || !std::isfinite(n.det)) [[unlikely]] {
    return NotPositiveDefinite("innovation covariance S", Matrix2Of(n.s00, n.s01, n.s11));
  }
  return Status::Ok();
}

// v^T S^-1 v through S = L D L^T (never negative for a positive definite S).
double Mahalanobis2(const Innovation2& n, double v0, double v1) {
  const double t = v1 - (n.s01 / n.s00) * v0;
  return v0 * v0 / n.s00 + t * t * (n.s00 / n.det);
}

// log N(v; 0, S) from S's determinant and v^T S^-1 v.
double LogDensity2(const Innovation2& n, double m2) {
  return -0.5 * m2 - kLogTwoPi - 0.5 * std::log(n.det);
}

// Kalman update in Joseph form, in closed form for 2x2; writes nothing on error. REQUIRES:
// finite inputs, cov and r symmetric.
Status KalmanCore(const Eigen::Vector2d& v, const Eigen::Matrix2d& h, const Eigen::Matrix2d& r,
                  Eigen::Vector2d* mean, Eigen::Matrix2d* cov, double* log_likelihood) {
  Innovation2 n;
  GROVE_RETURN_IF_ERROR(InnovationOf(h, *cov, r, &n));
  const double h00 = h(0, 0), h01 = h(0, 1), h10 = h(1, 0), h11 = h(1, 1);
  const double a = (*cov)(0, 0), b = (*cov)(0, 1), c = (*cov)(1, 1);
  const double r00 = r(0, 0), r01 = r(0, 1), r11 = r(1, 1);
  // K = P H^T S^-1 = (H P)^T S^-1.
  const double inv = 1 / n.det;
  const double k00 = (n.hp00 * n.s11 - n.hp10 * n.s01) * inv;
  const double k01 = (n.hp10 * n.s00 - n.hp00 * n.s01) * inv;
  const double k10 = (n.hp01 * n.s11 - n.hp11 * n.s01) * inv;
  const double k11 = (n.hp11 * n.s00 - n.hp01 * n.s01) * inv;
  const double m0 = (*mean)(0) + (k00 * v(0) + k01 * v(1));
  const double m1 = (*mean)(1) + (k10 * v(0) + k11 * v(1));
  // P' = A P A^T + K R K^T, A = I - K H.
  const double a00 = 1 - (k00 * h00 + k01 * h10), a01 = -(k00 * h01 + k01 * h11);
  const double a10 = -(k10 * h00 + k11 * h10), a11 = 1 - (k10 * h01 + k11 * h11);
  const double ap00 = a00 * a + a01 * b, ap01 = a00 * b + a01 * c;
  const double ap10 = a10 * a + a11 * b, ap11 = a10 * b + a11 * c;
  const double kr00 = k00 * r00 + k01 * r01, kr01 = k00 * r01 + k01 * r11;
  const double kr10 = k10 * r00 + k11 * r01, kr11 = k10 * r01 + k11 * r11;
  const double p00 = ap00 * a00 + ap01 * a01 + (kr00 * k00 + kr01 * k01);
  const double p11 = ap10 * a10 + ap11 * a11 + (kr10 * k10 + kr11 * k11);
  const double p01 = 0.5 * ((ap00 * a10 + ap01 * a11 + (kr00 * k10 + kr01 * k11)) +
                            (ap10 * a00 + ap11 * a01 + (kr10 * k00 + kr11 * k01)));
  const double ll = LogDensity2(n, Mahalanobis2(n, v(0), v(1)));
  if (!std::isfinite(m0 + m1) || !std::isfinite(p00 + p01 + p11) || !std::isfinite(ll))
      [[unlikely]] {
    return FailedPreconditionError(
        fmt::format("Kalman update is not finite (innovation covariance S = {})",
                    FormatMatrix(Matrix2Of(n.s00, n.s01, n.s11))));
  }
  (*mean)(0) = m0;
  (*mean)(1) = m1;
  *cov << p00, p01, p01, p11;
  if (log_likelihood != nullptr) *log_likelihood = ll;
  return Status::Ok();
}

// The innovation Q = Hv sigma Hv^T + S of the proposal, in closed form: the products Hv sigma
// the gain reuses, Q's symmetric entries and its determinant.
struct PoseInnovation {
  double hp[2][3];       // Hv sigma
  double q00, q01, q11;  // Q
  double det;            // det Q
};

// Q and its determinant, or why Q is unusable (not finite, not positive definite). REQUIRES:
// finite inputs, sigma and s symmetric.
Status PoseInnovationOf(const Matrix23d& h_pose, const Eigen::Matrix3d& sigma,
                        const Eigen::Matrix2d& s, PoseInnovation* out) {
  PoseInnovation& n = *out;
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 3; ++j) {
      n.hp[i][j] =
          h_pose(i, 0) * sigma(0, j) + h_pose(i, 1) * sigma(1, j) + h_pose(i, 2) * sigma(2, j);
    }
  }
  auto times_h = [&](int i, int k) {
    return n.hp[i][0] * h_pose(k, 0) + n.hp[i][1] * h_pose(k, 1) + n.hp[i][2] * h_pose(k, 2);
  };
  n.q00 = times_h(0, 0) + s(0, 0);
  n.q01 = 0.5 * (times_h(0, 1) + times_h(1, 0)) + s(0, 1);
  n.q11 = times_h(1, 1) + s(1, 1);
  n.det = n.q00 * n.q11 - n.q01 * n.q01;
  if (!std::isfinite(n.q00) || !std::isfinite(n.q01) || !std::isfinite(n.q11)) [[unlikely]] {
    return FailedPreconditionError(
        fmt::format("innovation covariance Hv sigma Hv^T + S = {} is not finite",
                    FormatMatrix(Matrix2Of(n.q00, n.q01, n.q11))));
  }
  if (!(n.q00 > 0 && n.det > 0) || !std::isfinite(n.det)) [[unlikely]] {
    return NotPositiveDefinite("innovation covariance Hv sigma Hv^T + S",
                               Matrix2Of(n.q00, n.q01, n.q11));
  }
  return Status::Ok();
}

// log N(v; 0, Q): v^T Q^-1 v through Q = L D L^T (never negative), and Q's determinant.
double PoseLogDensity(const PoseInnovation& n, const Eigen::Vector2d& v) {
  const double t = v(1) - (n.q01 / n.q00) * v(0);
  const double m2 = v(0) * v(0) / n.q00 + t * t * (n.q00 / n.det);
  return -0.5 * m2 - kLogTwoPi - 0.5 * std::log(n.det);
}

// The FastSLAM 2.0 proposal update (covariance form, Joseph), in closed form; writes nothing on
// error. REQUIRES: finite inputs, sigma and s symmetric.
Status ProposalCore(const Eigen::Vector2d& v, const Matrix23d& h_pose, const Eigen::Matrix2d& s,
                    Eigen::Vector3d* mu, Eigen::Matrix3d* sigma, double* log_weight) {
  const Eigen::Matrix3d& p = *sigma;
  PoseInnovation n;
  GROVE_RETURN_IF_ERROR(PoseInnovationOf(h_pose, p, s, &n));
  // K = sigma Hv^T Q^-1 = (Hv sigma)^T Q^-1 (equal to sigma' Hv^T S^-1: Woodbury).
  const double inv = 1 / n.det;
  Eigen::Matrix<double, 3, 2> k;
  for (int j = 0; j < 3; ++j) {
    k(j, 0) = (n.hp[0][j] * n.q11 - n.hp[1][j] * n.q01) * inv;
    k(j, 1) = (n.hp[1][j] * n.q00 - n.hp[0][j] * n.q01) * inv;
  }
  const Eigen::Vector3d new_mu = *mu + k * v;
  // A sigma A^T + K S K^T with A = I - K Hv.
  Eigen::Matrix3d a;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      a(i, j) = (i == j ? 1.0 : 0.0) - (k(i, 0) * h_pose(0, j) + k(i, 1) * h_pose(1, j));
    }
  }
  Eigen::Matrix3d ap;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j)
      ap(i, j) = a(i, 0) * p(0, j) + a(i, 1) * p(1, j) + a(i, 2) * p(2, j);
  }
  Eigen::Matrix<double, 3, 2> ks;
  for (int i = 0; i < 3; ++i) {
    ks(i, 0) = k(i, 0) * s(0, 0) + k(i, 1) * s(1, 0);
    ks(i, 1) = k(i, 0) * s(0, 1) + k(i, 1) * s(1, 1);
  }
  auto entry = [&](int i, int j) {
    return (ap(i, 0) * a(j, 0) + ap(i, 1) * a(j, 1) + ap(i, 2) * a(j, 2)) +
           (ks(i, 0) * k(j, 0) + ks(i, 1) * k(j, 1));
  };
  Eigen::Matrix3d new_sigma;
  for (int i = 0; i < 3; ++i) {
    new_sigma(i, i) = entry(i, i);
    for (int j = i + 1; j < 3; ++j)
      new_sigma(i, j) = new_sigma(j, i) = 0.5 * (entry(i, j) + entry(j, i));
  }
  const double lw = PoseLogDensity(n, v);
  if (!new_mu.allFinite() || !new_sigma.allFinite() || !std::isfinite(lw)) [[unlikely]] {
    return FailedPreconditionError(
        fmt::format("proposal update is not finite (Hv sigma Hv^T + S = {})",
                    FormatMatrix(Matrix2Of(n.q00, n.q01, n.q11))));
  }
  *mu = new_mu;
  *sigma = new_sigma;
  if (log_weight != nullptr) *log_weight = lw;
  return Status::Ok();
}

// The shared front of ProposalStep and ProposalLogWeight: validates, linearises at (mu, landmark)
// and returns v, Hv, S = Hl P Hl^T + R and the symmetric part of sigma.
Status PrepareProposal(const Eigen::Vector3d& mu, const Eigen::Matrix3d& sigma,
                       const Landmark& landmark, const RangeBearing& z, const SensorNoise& noise,
                       Eigen::Vector2d* v, Matrix23d* h_pose, Eigen::Matrix2d* s,
                       Eigen::Matrix3d* sigma_sym) {
  if (!mu.allFinite()) [[unlikely]]
    return NotFiniteEntry("mu", mu);
  GROVE_RETURN_IF_ERROR(ValidateVehicleCovariance(sigma));
  *sigma_sym = Symmetric(sigma);
  if (!PsdSquareRoot<3>(*sigma_sym, nullptr)) [[unlikely]] {
    return FailedPreconditionError(
        fmt::format("sigma = {} is not positive semi-definite", FormatMatrix(sigma)));
  }
  const VehiclePose pose = ToPose(mu);
  GROVE_RETURN_IF_ERROR(ValidateInputs(pose, z, noise, landmark));
  ObservationLinearization lin;
  GROVE_RETURN_IF_ERROR(Linearize(pose, landmark.x_m, landmark.y_m, &lin));
  *v = Innovation(z, lin.z_pred);
  *h_pose = lin.h_pose;
  *s = Symmetric(lin.h_landmark * Covariance(landmark) * lin.h_landmark.transpose() +
                 SensorCovariance(noise));
  if (!s->allFinite()) [[unlikely]] {
    return FailedPreconditionError(
        fmt::format("innovation covariance S = {} is not finite", FormatMatrix(*s)));
  }
  return Status::Ok();
}

template <int N>
Status LogGaussianDensityImpl(const Eigen::Matrix<double, N, 1>& v,
                              const Eigen::Matrix<double, N, N>& cov, double* out) {
  if (!v.allFinite()) return NotFiniteEntry("v", v);
  if (!cov.allFinite()) {
    return FailedPreconditionError(fmt::format("covariance {} is not finite", FormatMatrix(cov)));
  }
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(cov);
  if (llt.info() != Eigen::Success) {
    return FailedPreconditionError(
        fmt::format("covariance {} is not positive definite", FormatMatrix(cov)));
  }
  const double result = LogDensity<N>(llt, v);
  if (!std::isfinite(result)) {
    return FailedPreconditionError(
        fmt::format("log density is not finite (covariance {})", FormatMatrix(cov)));
  }
  *out = result;
  return Status::Ok();
}

// Why the landmark update (or likelihood) of UpdateLandmarkBatch() failed for usable inputs: the
// same steps with their checks, for the message.
Status WhyUpdateFailed(const VehiclePose& pose, const RangeBearing& z, const SensorNoise& noise,
                       const Landmark& landmark) {
  ObservationLinearization lin;
  GROVE_RETURN_IF_ERROR(Linearize(pose, landmark.x_m, landmark.y_m, &lin));
  Eigen::Vector2d mean = Mean(landmark);
  Eigen::Matrix2d cov = Covariance(landmark);
  GROVE_RETURN_IF_ERROR(KalmanCore(Innovation(z, lin.z_pred), lin.h_landmark,
                                   SensorCovariance(noise), &mean, &cov, nullptr));
  return FailedPreconditionError("the landmark update is not finite");
}

}  // namespace

double WrapAngleFar(double angle) {
  // remainder() is exact and returns r in [-kPi, kPi] with angle - r a multiple of kTwoPi.
  const double r = std::remainder(angle, kTwoPi);
  return r == -kPi ? kPi : r;
}

RangeBearing Observe(const VehiclePose& pose, double lx, double ly) {
  const double dx = lx - pose.x_m;
  const double dy = ly - pose.y_m;
  return {std::sqrt(dx * dx + dy * dy), WrapAngle(std::atan2(dy, dx) - pose.heading_rad)};
}

Eigen::Vector2d Innovation(const RangeBearing& z, const RangeBearing& z_pred) {
  return {z.range_m - z_pred.range_m, WrapAngle(z.bearing_rad - z_pred.bearing_rad)};
}

Eigen::Matrix2d SensorCovariance(const SensorNoise& noise) {
  const double sr = std::max(noise.sigma_range_m, kMinSigma);
  const double sb = std::max(noise.sigma_bearing_rad, kMinSigma);
  return Eigen::Vector2d(sr * sr, sb * sb).asDiagonal();
}

Status ValidateSensorNoise(const SensorNoise& noise) {
  if (!std::isfinite(noise.sigma_range_m)) {
    return NotFinite("noise.sigma_range_m", noise.sigma_range_m);
  }
  if (!std::isfinite(noise.sigma_bearing_rad)) {
    return NotFinite("noise.sigma_bearing_rad", noise.sigma_bearing_rad);
  }
  if (noise.sigma_range_m < 0) {
    return InvalidArgumentError(
        fmt::format("noise.sigma_range_m = {}: must be >= 0", noise.sigma_range_m));
  }
  if (noise.sigma_bearing_rad < 0) {
    return InvalidArgumentError(
        fmt::format("noise.sigma_bearing_rad = {}: must be >= 0", noise.sigma_bearing_rad));
  }
  return Status::Ok();
}

Status LinearizeObservation(const VehiclePose& pose, double lx, double ly,
                            ObservationLinearization* out) {
  GROVE_RETURN_IF_ERROR(ValidatePose(pose));
  if (!std::isfinite(lx)) return NotFinite("landmark x", lx);
  if (!std::isfinite(ly)) return NotFinite("landmark y", ly);
  ObservationLinearization lin;
  GROVE_RETURN_IF_ERROR(Linearize(pose, lx, ly, &lin));
  *out = lin;
  return Status::Ok();
}

Landmark InitLandmark(const VehiclePose& pose, const RangeBearing& z, const SensorNoise& noise) {
  const double a = pose.heading_rad + z.bearing_rad;
  const double c = std::cos(a);
  const double s = std::sin(a);
  const double r = z.range_m;
  Landmark l;
  l.x_m = pose.x_m + r * c;
  l.y_m = pose.y_m + r * s;
  Eigen::Matrix2d g;
  g << c, -r * s, s, r * c;
  SetCovariance(g * SensorCovariance(noise) * g.transpose(), &l);
  return l;
}

Status KalmanUpdate(const Eigen::Vector2d& innovation, const Eigen::Matrix2d& h,
                    const Eigen::Matrix2d& r, Eigen::Vector2d* mean, Eigen::Matrix2d* cov,
                    double* log_likelihood) {
  if (!innovation.allFinite()) return NotFiniteEntry("innovation", innovation);
  if (!h.allFinite()) return NotFiniteEntry("h", h);
  if (!r.allFinite()) return NotFiniteEntry("r", r);
  if (!mean->allFinite()) return NotFiniteEntry("mean", *mean);
  if (!cov->allFinite()) return NotFiniteEntry("cov", *cov);
  return KalmanCore(innovation, h, r, mean, cov, log_likelihood);
}

Status UpdateLandmark(const VehiclePose& pose, const RangeBearing& z, const SensorNoise& noise,
                      Landmark* landmark, double* log_likelihood) {
  if (!InputsUsable(pose, z, noise, *landmark)) [[unlikely]] {
    return DescribeBadInputs(pose, z, noise, *landmark);
  }
  const double sr = std::max(noise.sigma_range_m, kMinSigma);
  const double sb = std::max(noise.sigma_bearing_rad, kMinSigma);
  Landmark* const leaf = landmark;
  double ll = 0;
  if (UpdateLandmarkBatch(&pose, &leaf, z, sr * sr, sb * sb, &ll, 1) == 1) [[likely]] {
    if (log_likelihood != nullptr) *log_likelihood = ll;
    return Status::Ok();
  }
  return WhyUpdateFailed(pose, z, noise, *landmark);
}

Status ObservationLogLikelihood(const VehiclePose& pose, const RangeBearing& z,
                                const SensorNoise& noise, const Landmark& landmark,
                                double* log_likelihood, double* mahalanobis_sq) {
  if (!InputsUsable(pose, z, noise, landmark)) [[unlikely]] {
    return DescribeBadInputs(pose, z, noise, landmark);
  }
  const double sr = std::max(noise.sigma_range_m, kMinSigma);
  const double sb = std::max(noise.sigma_bearing_rad, kMinSigma);
  // The innovation UpdateLandmark() forms, so the value equals its log-likelihood.
  const Landmark* const leaf = &landmark;
  double ll = 0, m2 = 0;
  if (LandmarkLikelihoodBatch(&pose, &leaf, z, sr * sr, sb * sb, &ll, &m2, 1) == 1) [[likely]] {
    if (log_likelihood != nullptr) *log_likelihood = ll;
    if (mahalanobis_sq != nullptr) *mahalanobis_sq = m2;
    return Status::Ok();
  }
  return WhyUpdateFailed(pose, z, noise, landmark);
}

Status UpdateLandmarks(const VehiclePose& pose, const RangeBearing* zs, Landmark* const* leaves,
                       const SensorNoise& noise, size_t n, size_t* failed) {
  bool usable = true;
  for (size_t k = 0; k < n && usable; ++k) usable = InputsUsable(pose, zs[k], noise, *leaves[k]);
  if (!usable) [[unlikely]] {
    // One at a time, nothing updated yet: the first failure's status.
    for (size_t k = 0; k < n; ++k) {
      Status s = UpdateLandmark(pose, zs[k], noise, leaves[k], nullptr);
      if (!s.ok()) {
        *failed = k;
        return s;
      }
    }
    return Status::Ok();
  }
  const double sr = std::max(noise.sigma_range_m, kMinSigma);
  const double sb = std::max(noise.sigma_bearing_rad, kMinSigma);
  constexpr size_t kChunk = 64;
  double sums[kChunk];
  for (size_t first = 0; first < n; first += kChunk) {
    const size_t m = std::min(kChunk, n - first);
    std::fill(sums, sums + m, 0.0);
    const size_t f =
        UpdateLandmarkPairs(pose, leaves + first, zs + first, sr * sr, sb * sb, sums, m);
    if (f < m) [[unlikely]] {
      // Landmark first + f is unchanged: UpdateLandmark() runs the same lane on it, and says why.
      *failed = first + f;
      Status s = UpdateLandmark(pose, zs[first + f], noise, leaves[first + f], nullptr);
      return s.ok() ? InternalError("a landmark update failed in a batch and not alone") : s;
    }
  }
  return Status::Ok();
}

Status ObservationLogLikelihoods(const VehiclePose& pose, const RangeBearing* zs,
                                 const Landmark* const* leaves, const SensorNoise& noise,
                                 double* log_likelihoods, double* mahalanobis_sq, size_t n,
                                 size_t* failed) {
  bool usable = true;
  for (size_t k = 0; k < n && usable; ++k) usable = InputsUsable(pose, zs[k], noise, *leaves[k]);
  if (usable) [[likely]] {
    const double sr = std::max(noise.sigma_range_m, kMinSigma);
    const double sb = std::max(noise.sigma_bearing_rad, kMinSigma);
    if (LandmarkLikelihoodPairs(pose, leaves, zs, sr * sr, sb * sb, log_likelihoods, mahalanobis_sq,
                                n) == n) [[likely]] {
      return Status::Ok();
    }
  }
  // A pair fails: one at a time, for the first failure's status.
  for (size_t k = 0; k < n; ++k) {
    Status s = ObservationLogLikelihood(pose, zs[k], noise, *leaves[k], &log_likelihoods[k],
                                        &mahalanobis_sq[k]);
    if (!s.ok()) {
      *failed = k;
      return s;
    }
  }
  return Status::Ok();
}

Status ProposalUpdate(const Eigen::Vector2d& innovation, const Matrix23d& h_pose,
                      const Eigen::Matrix2d& s, Eigen::Vector3d* mu, Eigen::Matrix3d* sigma,
                      double* log_weight) {
  if (!innovation.allFinite()) return NotFiniteEntry("innovation", innovation);
  if (!h_pose.allFinite()) return NotFiniteEntry("h_pose", h_pose);
  if (!s.allFinite()) return NotFiniteEntry("s", s);
  if (!mu->allFinite()) return NotFiniteEntry("mu", *mu);
  if (!sigma->allFinite()) return NotFiniteEntry("sigma", *sigma);
  return ProposalCore(innovation, h_pose, s, mu, sigma, log_weight);
}

Status ProposalStep(Eigen::Vector3d* mu, Eigen::Matrix3d* sigma, const Landmark& landmark,
                    const RangeBearing& z, const SensorNoise& noise, double* log_weight) {
  Eigen::Vector2d v;
  Matrix23d h_pose;
  Eigen::Matrix2d s;
  Eigen::Matrix3d new_sigma;
  GROVE_RETURN_IF_ERROR(
      PrepareProposal(*mu, *sigma, landmark, z, noise, &v, &h_pose, &s, &new_sigma));
  Eigen::Vector3d new_mu = *mu;
  double lw = 0;
  GROVE_RETURN_IF_ERROR(ProposalCore(v, h_pose, s, &new_mu, &new_sigma, &lw));
  new_mu(2) = WrapAngle(new_mu(2));
  *mu = new_mu;
  *sigma = new_sigma;
  if (log_weight != nullptr) *log_weight = lw;
  return Status::Ok();
}

Status ProposalLogWeight(const Eigen::Vector3d& mu, const Eigen::Matrix3d& sigma,
                         const Landmark& landmark, const RangeBearing& z, const SensorNoise& noise,
                         double* log_weight) {
  Eigen::Vector2d v;
  Matrix23d h_pose;
  Eigen::Matrix2d s;
  Eigen::Matrix3d sigma_sym;
  GROVE_RETURN_IF_ERROR(
      PrepareProposal(mu, sigma, landmark, z, noise, &v, &h_pose, &s, &sigma_sym));
  // The Q ProposalCore forms, so the value equals ProposalStep's.
  PoseInnovation n;
  GROVE_RETURN_IF_ERROR(PoseInnovationOf(h_pose, sigma_sym, s, &n));
  const double lw = PoseLogDensity(n, v);
  if (!std::isfinite(lw)) [[unlikely]] {
    return FailedPreconditionError(fmt::format("log weight is not finite (Hv sigma Hv^T + S = {})",
                                               FormatMatrix(Matrix2Of(n.q00, n.q01, n.q11))));
  }
  *log_weight = lw;
  return Status::Ok();
}

Status SamplePose(const Eigen::Vector3d& mu, const Eigen::Matrix3d& sigma,
                  const Eigen::Vector3d& standard_normals, VehiclePose* out) {
  if (!mu.allFinite()) return NotFiniteEntry("mu", mu);
  if (!standard_normals.allFinite()) return NotFiniteEntry("standard_normals", standard_normals);
  GROVE_RETURN_IF_ERROR(ValidateVehicleCovariance(sigma));
  Eigen::Matrix3d root;
  if (!PsdSquareRoot<3>(Symmetric(sigma), &root)) {
    return FailedPreconditionError(
        fmt::format("sigma = {} is not positive semi-definite", FormatMatrix(sigma)));
  }
  Eigen::Vector3d x = mu + root * standard_normals;
  if (!x.allFinite()) {
    return FailedPreconditionError(fmt::format("pose sample is not finite (mu = {}, sigma = {})",
                                               FormatMatrix(mu), FormatMatrix(sigma)));
  }
  x(2) = WrapAngle(x(2));
  *out = ToPose(x);
  return Status::Ok();
}

Eigen::Vector3d PoseDifference(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Eigen::Vector3d d = a - b;
  d(2) = WrapAngle(d(2));
  return d;
}

Status LogGaussianDensity(const Eigen::Vector2d& v, const Eigen::Matrix2d& cov, double* out) {
  return LogGaussianDensityImpl<2>(v, cov, out);
}

Status LogGaussianDensity(const Eigen::Vector3d& v, const Eigen::Matrix3d& cov, double* out) {
  return LogGaussianDensityImpl<3>(v, cov, out);
}

}  // namespace grove::fastslam

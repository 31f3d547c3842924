#include "engine/fastslam/landmark_math.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>
#include <string>
#include <string_view>

// Structure: each public function validates its inputs once, then runs an unchecked core
// (Linearize, KalmanCore, ProposalCore) that checks only what the arithmetic itself can break
// (a factorisation failing, a result overflowing). These run once per observation and particle,
// the filter's innermost loop, so error messages are formatted only on the error path.

namespace grove::fastslam {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2 * std::numbers::pi;  // exactly twice kPi
const double kLogTwoPi = std::log(kTwoPi);

using Llt2 = Eigen::LLT<Eigen::Matrix2d>;

// ---- Messages (error path only).

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

// ---- Small numerical helpers.

// The symmetric part of a square matrix (expression), evaluated.
template <typename Derived>
typename Derived::PlainObject Symmetric(const Eigen::MatrixBase<Derived>& expression) {
  const typename Derived::PlainObject a = expression;
  return 0.5 * (a + a.transpose());
}

// C^-1 B from the LLT of C, one column at a time: Eigen sends a matrix right-hand side through its
// blocked, packing triangular solver, several times the cost of the vector path at these sizes.
template <int N, int M>
Eigen::Matrix<double, N, M> SolveColumns(const Eigen::LLT<Eigen::Matrix<double, N, N>>& llt,
                                         const Eigen::Matrix<double, N, M>& b) {
  Eigen::Matrix<double, N, M> x;
  for (int j = 0; j < M; ++j) {
    Eigen::Matrix<double, N, 1> column = b.col(j);
    llt.solveInPlace(column);
    x.col(j) = column;
  }
  return x;
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

// ---- Validation.

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
Status ValidateInputs(const VehiclePose& pose, const RangeBearing& z, const SensorNoise& noise,
                      const Landmark& l) {
  const bool finite = Finite(pose) && std::isfinite(z.range_m) && std::isfinite(z.bearing_rad) &&
                      std::isfinite(noise.sigma_range_m) &&
                      std::isfinite(noise.sigma_bearing_rad) && std::isfinite(l.x_m) &&
                      std::isfinite(l.y_m) && std::isfinite(l.xx) && std::isfinite(l.xy) &&
                      std::isfinite(l.yy);
  if (finite && z.range_m >= 0 && noise.sigma_range_m >= 0 && noise.sigma_bearing_rad >= 0 &&
      PsdSquareRoot<2>(Covariance(l), nullptr)) [[likely]] {
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

// ---- Cores: inputs already validated.

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

// S = H P H^T + R (symmetric), its LLT, or why not. REQUIRES: finite inputs.
Status InnovationFactor(const Eigen::Matrix2d& h, const Eigen::Matrix2d& p,
                        const Eigen::Matrix2d& r, Eigen::Matrix2d* s, Llt2* llt) {
  *s = Symmetric(h * p * h.transpose() + r);
  if (!s->allFinite()) [[unlikely]] {
    return FailedPreconditionError(
        fmt::format("innovation covariance S = {} is not finite", FormatMatrix(*s)));
  }
  llt->compute(*s);
  if (llt->info() != Eigen::Success) [[unlikely]] {
    return NotPositiveDefinite("innovation covariance S", *s);
  }
  return Status::Ok();
}

// Kalman update in Joseph form; writes nothing on error. REQUIRES: finite inputs, cov and r
// symmetric.
Status KalmanCore(const Eigen::Vector2d& v, const Eigen::Matrix2d& h, const Eigen::Matrix2d& r,
                  Eigen::Vector2d* mean, Eigen::Matrix2d* cov, double* log_likelihood) {
  const Eigen::Matrix2d& p = *cov;
  Eigen::Matrix2d s;
  Llt2 llt;
  GROVE_RETURN_IF_ERROR(InnovationFactor(h, p, r, &s, &llt));
  // K = P H^T S^-1, from K^T = S^-1 H P (P and S symmetric).
  const Eigen::Matrix2d k = SolveColumns<2, 2>(llt, h * p).transpose();
  const Eigen::Vector2d new_mean = *mean + k * v;
  const Eigen::Matrix2d a = Eigen::Matrix2d::Identity() - k * h;
  const Eigen::Matrix2d new_cov = Symmetric(a * p * a.transpose() + k * r * k.transpose());
  const double ll = LogDensity<2>(llt, v);
  if (!new_mean.allFinite() || !new_cov.allFinite() || !std::isfinite(ll)) [[unlikely]] {
    return FailedPreconditionError(
        fmt::format("Kalman update is not finite (innovation covariance S = {})", FormatMatrix(s)));
  }
  *mean = new_mean;
  *cov = new_cov;
  if (log_likelihood != nullptr) *log_likelihood = ll;
  return Status::Ok();
}

// Q = Hv sigma Hv^T + S: the innovation covariance with the pose uncertain.
Eigen::Matrix2d PoseInnovationCovariance(const Matrix23d& h_pose, const Eigen::Matrix3d& sigma,
                                         const Eigen::Matrix2d& s) {
  return Symmetric(h_pose * sigma * h_pose.transpose() + s);
}

// Q and its LLT, or why not.
Status PoseInnovationFactor(const Matrix23d& h_pose, const Eigen::Matrix3d& sigma,
                            const Eigen::Matrix2d& s, Eigen::Matrix2d* q, Llt2* llt) {
  *q = PoseInnovationCovariance(h_pose, sigma, s);
  if (!q->allFinite()) [[unlikely]] {
    return FailedPreconditionError(fmt::format(
        "innovation covariance Hv sigma Hv^T + S = {} is not finite", FormatMatrix(*q)));
  }
  llt->compute(*q);
  if (llt->info() != Eigen::Success) [[unlikely]] {
    return NotPositiveDefinite("innovation covariance Hv sigma Hv^T + S", *q);
  }
  return Status::Ok();
}

// The FastSLAM 2.0 proposal update (covariance form, Joseph); writes nothing on error.
// REQUIRES: finite inputs, sigma and s symmetric.
Status ProposalCore(const Eigen::Vector2d& v, const Matrix23d& h_pose, const Eigen::Matrix2d& s,
                    Eigen::Vector3d* mu, Eigen::Matrix3d* sigma, double* log_weight) {
  const Eigen::Matrix3d& p = *sigma;
  Eigen::Matrix2d q;
  Llt2 llt;
  GROVE_RETURN_IF_ERROR(PoseInnovationFactor(h_pose, p, s, &q, &llt));
  // K = sigma Hv^T Q^-1, from K^T = Q^-1 Hv sigma; equal to sigma' Hv^T S^-1 (Woodbury).
  const Eigen::Matrix<double, 3, 2> k = SolveColumns<2, 3>(llt, h_pose * p).transpose();
  const Eigen::Vector3d new_mu = *mu + k * v;
  const Eigen::Matrix3d a = Eigen::Matrix3d::Identity() - k * h_pose;
  const Eigen::Matrix3d new_sigma = Symmetric(a * p * a.transpose() + k * s * k.transpose());
  const double lw = LogDensity<2>(llt, v);
  if (!new_mu.allFinite() || !new_sigma.allFinite() || !std::isfinite(lw)) [[unlikely]] {
    return FailedPreconditionError(
        fmt::format("proposal update is not finite (Hv sigma Hv^T + S = {})", FormatMatrix(q)));
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
  GROVE_RETURN_IF_ERROR(ValidateInputs(pose, z, noise, *landmark));
  ObservationLinearization lin;
  GROVE_RETURN_IF_ERROR(Linearize(pose, landmark->x_m, landmark->y_m, &lin));
  Eigen::Vector2d mean = Mean(*landmark);
  Eigen::Matrix2d cov = Covariance(*landmark);
  double ll = 0;
  GROVE_RETURN_IF_ERROR(KalmanCore(Innovation(z, lin.z_pred), lin.h_landmark,
                                   SensorCovariance(noise), &mean, &cov, &ll));
  landmark->x_m = mean(0);
  landmark->y_m = mean(1);
  SetCovariance(cov, landmark);
  if (log_likelihood != nullptr) *log_likelihood = ll;
  return Status::Ok();
}

Status ObservationLogLikelihood(const VehiclePose& pose, const RangeBearing& z,
                                const SensorNoise& noise, const Landmark& landmark,
                                double* log_likelihood, double* mahalanobis_sq) {
  GROVE_RETURN_IF_ERROR(ValidateInputs(pose, z, noise, landmark));
  ObservationLinearization lin;
  GROVE_RETURN_IF_ERROR(Linearize(pose, landmark.x_m, landmark.y_m, &lin));
  // The S and factorisation KalmanCore forms, so the value equals UpdateLandmark's.
  Eigen::Matrix2d s;
  Llt2 llt;
  GROVE_RETURN_IF_ERROR(
      InnovationFactor(lin.h_landmark, Covariance(landmark), SensorCovariance(noise), &s, &llt));
  double m2 = 0;
  const double ll = LogDensity<2>(llt, Innovation(z, lin.z_pred), &m2);
  if (!std::isfinite(ll)) [[unlikely]] {
    return FailedPreconditionError(fmt::format(
        "log-likelihood is not finite (innovation covariance S = {})", FormatMatrix(s)));
  }
  if (log_likelihood != nullptr) *log_likelihood = ll;
  if (mahalanobis_sq != nullptr) *mahalanobis_sq = m2;
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
  // The Q and factorisation ProposalCore forms, so the value equals ProposalStep's.
  Eigen::Matrix2d q;
  Llt2 llt;
  GROVE_RETURN_IF_ERROR(PoseInnovationFactor(h_pose, sigma_sym, s, &q, &llt));
  const double lw = LogDensity<2>(llt, v);
  if (!std::isfinite(lw)) [[unlikely]] {
    return FailedPreconditionError(
        fmt::format("log weight is not finite (Hv sigma Hv^T + S = {})", FormatMatrix(q)));
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

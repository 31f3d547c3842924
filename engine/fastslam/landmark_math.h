// The per-landmark and per-observation mathematics of landmark FastSLAM: the range-bearing sensor,
// its Jacobians and inverse, the EKF landmark update of FastSLAM 1.0, and the observation-by-
// observation pose proposal and importance weight of FastSLAM 2.0.
//
// Sources: Thrun, Burgard, Fox, "Probabilistic Robotics" (2005), ch. 13 (FastSLAM 1.0 and 2.0);
// Montemerlo, Thrun, Koller, Wegbreit, "FastSLAM 2.0", IJCAI 2003 (proposal and weight);
// Bailey's MATLAB FastSLAM (compute_jacobians, add_feature, feature_update, sample_proposal) for
// the conventions; Bar-Shalom, Li, Kirubarajan, "Estimation with Applications to Tracking and
// Navigation" (2001), sec. 5.2 (Joseph form).
//
// Conventions. A pose is (x_m, y_m, heading_rad), heading counter-clockwise from +x. The sensor
// sits at the vehicle's position: range = |l - p|, bearing = atan2(ly - y, lx - x) - heading,
// wrapped to (-pi, pi]. Every innovation wraps its bearing difference (Innovation()). Sensor
// noise is R = diag(sigma_range^2, sigma_bearing^2) with each sigma floored at kMinSigma
// (SensorCovariance()), so zero noise is accepted and stays exact to round-off.
//
// Use, per particle and scan (known association):
//   FastSLAM 1.0: for each observed landmark, UpdateLandmark from the sampled pose and add its
//     log_likelihood to the particle's log weight; InitLandmark for a new landmark.
//   FastSLAM 2.0: (mu, sigma) = the predicted pose and its covariance; for each observation of a
//     landmark already in the map, ProposalStep(&mu, &sigma, ...) and add its log_weight; then
//     SamplePose(mu, sigma, draws), then UpdateLandmark from the sampled pose for each observed
//     landmark (its log_likelihood is not added again) and InitLandmark for the new ones.
//     Bailey's form of the weight, p(z | x) p(x) / q(x) at the sampled x, is
//     ObservationLogLikelihood (summed) + LogGaussianDensity(PoseDifference(x, mu_predicted),
//     sigma_predicted) - LogGaussianDensity(PoseDifference(x, mu), sigma); it equals the sum of
//     the log_weights when the model is linear (tested).
//
// Errors. Every function that can fail returns a Status and leaves its outputs unchanged on error:
// InvalidArgument for a non-finite input or a negative range or sigma (naming the field and value),
// FailedPrecondition for a state the mathematics cannot use (a landmark at the sensor position, a
// covariance that is not positive semi-definite, an innovation covariance that is not positive
// definite, a result that overflowed). Nothing returns NaN silently.
//
// Thread safety: free functions on values; all may be called concurrently.
#ifndef GROVE_ENGINE_FASTSLAM_LANDMARK_MATH_H_
#define GROVE_ENGINE_FASTSLAM_LANDMARK_MATH_H_

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <type_traits>

#include "grove/status.h"

namespace grove::fastslam {

using Matrix23d = Eigen::Matrix<double, 2, 3>;

struct VehiclePose {
  double x_m = 0;
  double y_m = 0;
  double heading_rad = 0;
};

struct RangeBearing {
  double range_m = 0;
  double bearing_rad = 0;
};

// Standard deviations of the range-bearing sensor. REQUIRES (checked where used): finite, >= 0.
struct SensorNoise {
  double sigma_range_m = 0;
  double sigma_bearing_rad = 0;
};

// Each sigma is raised to at least this before use (m for range, rad for bearing): zero noise then
// gives R = 1e-18 * I instead of a singular S, far below any physical sensor and far above the
// round-off of coordinates up to 1e6 m, so a noise-free run stays exact to round-off.
inline constexpr double kMinSigma = 1e-9;

// A covariance counts as positive semi-definite when its Cholesky factorisation (LLT) succeeds or
// its smallest eigenvalue is >= -kPsdTolerance times its largest diagonal entry; slightly negative
// eigenvalues are round-off.
inline constexpr double kPsdTolerance = 1e-10;
// A 3x3 covariance counts as symmetric when |A(i,j) - A(j,i)| <= kSymmetryTolerance * max |A(k,k)|.
inline constexpr double kSymmetryTolerance = 1e-9;

// The lower Cholesky factor of a 3x3 `a` from its lower triangle, in the operations and order
// of Eigen's unblocked LLT (so the same bits, without its loops and its norm for rcond()); false
// where Eigen's LLT fails (a pivot at or below 0; NaN passes, as there).
inline bool Cholesky3(const Eigen::Matrix3d& a, Eigen::Matrix3d* l) {
  const double d0 = a(0, 0);
  if (d0 <= 0) return false;
  const double l00 = std::sqrt(d0);
  const double l10 = a(1, 0) / l00, l20 = a(2, 0) / l00;
  const double d1 = a(1, 1) - l10 * l10;
  if (d1 <= 0) return false;
  const double l11 = std::sqrt(d1);
  const double l21 = (a(2, 1) - l20 * l10) / l11;
  const double d2 = a(2, 2) - (l20 * l20 + l21 * l21);
  if (d2 <= 0) return false;
  if (l != nullptr) *l << l00, 0, 0, l10, l11, 0, l20, l21, std::sqrt(d2);
  return true;
}

// Whether a 3x3 `a` is positive definite by the pivots of its L D L^T (from its lower triangle),
// without square roots: the quick test of PsdSquareRoot() when no root is wanted.
inline bool PositivePivots3(const Eigen::Matrix3d& a) {
  const double d0 = a(0, 0);
  if (!(d0 > 0)) return false;
  const double l10 = a(1, 0) / d0, l20 = a(2, 0) / d0;
  const double d1 = a(1, 1) - l10 * a(1, 0);
  if (!(d1 > 0)) return false;
  const double e21 = a(2, 1) - l20 * a(1, 0);
  return a(2, 2) - l20 * a(2, 0) - e21 * e21 / d1 > 0;
}

// A with A A^T = a when `a` is positive semi-definite in the sense of kPsdTolerance: the Cholesky
// factor when LLT succeeds (positive definite, the usual case), else V diag(lambda)^1/2 from the
// symmetric eigendecomposition with round-off eigenvalues clamped to 0 (a pivoted LDLT can stop
// at a zero pivot followed by round-off; the eigenvalues decide semi-definiteness robustly).
// False when `a` is not positive semi-definite. `root` may be null (a check only).
// REQUIRES: a finite and symmetric.
template <int N>
bool PsdSquareRoot(const Eigen::Matrix<double, N, N>& a, Eigen::Matrix<double, N, N>* root) {
  using Matrix = Eigen::Matrix<double, N, N>;
  if constexpr (N == 3) {
    if (root == nullptr ? PositivePivots3(a) : Cholesky3(a, root)) [[likely]]
      return true;
  } else {
    const Eigen::LLT<Matrix> llt(a);
    if (llt.info() == Eigen::Success) [[likely]] {
      if (root != nullptr) *root = llt.matrixL();
      return true;
    }
  }
  const Eigen::SelfAdjointEigenSolver<Matrix> eigen(a);
  if (eigen.info() != Eigen::Success) return false;
  const double scale = a.diagonal().cwiseAbs().maxCoeff();
  if (eigen.eigenvalues().minCoeff() < -kPsdTolerance * scale) return false;
  if (root != nullptr) {
    *root = eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  }
  return true;
}

// A landmark's 2-D Gaussian: the leaf of the persistent landmark trie. 48 bytes, trivially
// copyable. Under unknown association it also carries its existence evidence (raised when the
// landmark is seen, lowered when it is in view and not seen) and a tag: the id an observation
// that created it carried (a simulator's truth, for the association error rate), or -1. The three
// slots (xx, xy, yy) hold one of two readings, fixed by the filter that owns the map (every leaf of
// one map uses the same reading, so no tag is stored):
//   - covariance (FastSLAM 1.0/2.0, U-FastSLAM): P = [xx xy; xy yy], m^2. Covariance() and
//     SetCovariance() read and write it; every function below uses this reading.
//   - square root (the SRCD filters of Ankışhan et al.): the lower Cholesky factor L of P = L L^T,
//     L = [xx 0; xy yy], m. CholeskyFactor() and SetCholeskyFactor() read and write it.
struct Landmark {
  double x_m = 0;
  double y_m = 0;
  double xx = 0;
  double xy = 0;
  double yy = 0;
  int32_t evidence = 0;
  int32_t tag = -1;
};
static_assert(std::is_trivially_copyable_v<Landmark> && sizeof(Landmark) == 48);

inline Eigen::Vector2d Mean(const Landmark& l) { return {l.x_m, l.y_m}; }
inline Eigen::Matrix2d Covariance(const Landmark& l) {
  return (Eigen::Matrix2d() << l.xx, l.xy, l.xy, l.yy).finished();
}
// Stores the symmetric part of `p`.
inline void SetCovariance(const Eigen::Matrix2d& p, Landmark* l) {
  l->xx = p(0, 0);
  l->xy = 0.5 * (p(0, 1) + p(1, 0));
  l->yy = p(1, 1);
}
inline Eigen::Matrix2d CholeskyFactor(const Landmark& l) {
  return (Eigen::Matrix2d() << l.xx, 0, l.xy, l.yy).finished();
}
// Stores the lower triangle of `factor` (its upper right entry is ignored).
inline void SetCholeskyFactor(const Eigen::Matrix2d& factor, Landmark* l) {
  l->xx = factor(0, 0);
  l->xy = factor(1, 0);
  l->yy = factor(1, 1);
}

// The landmark with its square-root reading turned into the covariance reading (P = L L^T).
inline Landmark WithCovariance(const Landmark& l) {
  Landmark c = l;
  const Eigen::Matrix2d f = CholeskyFactor(l);
  SetCovariance(f * f.transpose(), &c);
  return c;
}

inline Eigen::Vector3d ToVector(const VehiclePose& p) { return {p.x_m, p.y_m, p.heading_rad}; }
inline VehiclePose ToPose(const Eigen::Vector3d& v) { return {v(0), v(1), v(2)}; }

// `angle` reduced to (-pi, pi]: pi stays pi, -pi becomes pi. Exact: the result is
// angle - k * 2pi for an integer k, computed without rounding (std::remainder), where 2pi is the
// double nearest 2pi; it therefore differs from the reduction by the true 2pi by at most about
// 4e-17 * |angle| (4e-11 at 1e6 rad). Non-finite input gives NaN. Inline for an angle within
// one turn of the interval; WrapAngleFar() (std::remainder) beyond.
double WrapAngleFar(double angle);
inline double WrapAngle(double angle) {
  constexpr double kPi = std::numbers::pi;
  if (angle > -kPi && angle <= kPi) [[likely]] {
    return angle;
  }
  // One turn off (a difference of two wrapped angles): angle -+ 2 pi is exact there (Sterbenz)
  // and is what the remainder gives.
  if (angle > kPi && angle < 9.0) return angle - 2 * kPi;
  if (angle <= -kPi && angle > -9.0) return angle + 2 * kPi;
  return WrapAngleFar(angle);
}

// The range-bearing observation of landmark (lx, ly) from `pose`. At zero distance the range is 0
// and the bearing, atan2 of two zeros less the heading, carries no information.
// REQUIRES: coordinate differences below 1e150 m (the range is sqrt(dx^2 + dy^2)).
RangeBearing Observe(const VehiclePose& pose, double lx, double ly);

// z - z_pred with the bearing difference wrapped to (-pi, pi].
Eigen::Vector2d Innovation(const RangeBearing& z, const RangeBearing& z_pred);

// R = diag(max(sigma_range, kMinSigma)^2, max(sigma_bearing, kMinSigma)^2).
// REQUIRES: ValidateSensorNoise(noise).ok().
Eigen::Matrix2d SensorCovariance(const SensorNoise& noise);

// InvalidArgument naming the field unless both sigmas are finite and >= 0.
Status ValidateSensorNoise(const SensorNoise& noise);

// The observation model linearised at (pose, landmark): the predicted observation and the
// Jacobians of h = (range, bearing) with respect to the landmark (lx, ly) and the pose
// (x, y, heading). With d = (lx - x, ly - y), q = |d|^2 (Bailey's compute_jacobians):
//   h_landmark = [ dx/r  dy/r ; -dy/q  dx/q ],   h_pose = [ -dx/r  -dy/r  0 ; dy/q  -dx/q  -1 ].
struct ObservationLinearization {
  RangeBearing z_pred;
  Eigen::Matrix2d h_landmark;
  Matrix23d h_pose;
};

// FailedPrecondition when the landmark is at the sensor position (the bearing has no derivative)
// or the Jacobians overflow; InvalidArgument for a non-finite input.
Status LinearizeObservation(const VehiclePose& pose, double lx, double ly,
                            ObservationLinearization* out);

// The inverse model: the landmark at range and bearing z from `pose`, with covariance G R G^T,
// G = d(lx, ly)/d(range, bearing) = [cos a  -r sin a ; sin a  r cos a], a = heading + bearing
// (Bailey's add_feature; Probabilistic Robotics ch. 13). At r = 0 the covariance has rank one.
// REQUIRES: finite pose and z, z.range_m >= 0, ValidateSensorNoise(noise).ok(). A non-finite input
// gives a non-finite landmark, which every function below rejects with InvalidArgument.
Landmark InitLandmark(const VehiclePose& pose, const RangeBearing& z, const SensorNoise& noise);

// FastSLAM 1.0 landmark update (Probabilistic Robotics ch. 13): the EKF update of `landmark` by
// observation z from the known pose, S = Hl P Hl^T + R, K = P Hl^T S^-1, mean += K v, and
// P' = (I - K Hl) P (I - K Hl)^T + K R K^T: the Joseph form, a sum of two positive semi-definite
// terms for any K, so round-off in K cannot make P' indefinite. P - K S K^T can: when R is small
// next to Hl P Hl^T, P' is a small difference of large numbers (with P ~ 1e6 I and R ~ 1e-10 I it
// fails where the Joseph form holds: KalmanUpdateTest.CovarianceStaysPositiveDefiniteAcrossScales).
// `log_likelihood` (may be null) gets log N(v; 0, S), never the raw likelihood.
// Errors: InvalidArgument (non-finite pose, z, landmark or noise; negative range or sigma);
// FailedPrecondition (landmark covariance not positive semi-definite, landmark at the sensor,
// S not positive definite, non-finite result). On error nothing is written.
// REQUIRES: landmark != nullptr.
Status UpdateLandmark(const VehiclePose& pose, const RangeBearing& z, const SensorNoise& noise,
                      Landmark* landmark, double* log_likelihood);

// UpdateLandmark() of n distinct landmarks seen from one pose, *leaves[k] by zs[k] for k < n,
// in SIMD lanes (the same values; the log-likelihoods are not kept). On an error, the first
// failing landmark's: its index in *failed and UpdateLandmark()'s status (that landmark is
// unchanged; the others may be updated).
Status UpdateLandmarks(const VehiclePose& pose, const RangeBearing* zs, Landmark* const* leaves,
                       const SensorNoise& noise, size_t n, size_t* failed);

// log N(v; 0, S) for z at `pose` without updating the landmark (Bailey's likelihood_given_xv; the
// FastSLAM 1.0 weight factor), and optionally the squared Mahalanobis distance v^T S^-1 v (for
// gating and nearest-neighbour association). Same errors as UpdateLandmark; equals the
// log-likelihood UpdateLandmark reports for the same arguments.
Status ObservationLogLikelihood(const VehiclePose& pose, const RangeBearing& z,
                                const SensorNoise& noise, const Landmark& landmark,
                                double* log_likelihood, double* mahalanobis_sq = nullptr);

// ObservationLogLikelihood() of n pairs seen from one pose, zs[k] against *leaves[k], into
// log_likelihoods[k] and mahalanobis_sq[k], for k < n, in SIMD lanes (the same values). On an
// error, the first failing pair's: its index in *failed and ObservationLogLikelihood()'s status.
Status ObservationLogLikelihoods(const VehiclePose& pose, const RangeBearing* zs,
                                 const Landmark* const* leaves, const SensorNoise& noise,
                                 double* log_likelihoods, double* mahalanobis_sq, size_t n,
                                 size_t* failed);

// FastSLAM 2.0 proposal step for one observation (Montemerlo et al. 2003; applied observation by
// observation as Bailey's sample_proposal, relinearising at the current mean): with Hv, Hl and
// z_pred at (mu, landmark), v = Innovation(z, z_pred), S = Hl P Hl^T + R,
//   sigma' = (Hv^T S^-1 Hv + sigma^-1)^-1,   mu' = mu + sigma' Hv^T S^-1 v.
// Computed in the equal covariance form, which needs no inverse of sigma (so sigma may be
// singular, e.g. zero motion noise) and inverts only the 2x2 Q = Hv sigma Hv^T + S (closed form):
//   K = sigma Hv^T Q^-1,   mu' = mu + K v,   sigma' = (I - K Hv) sigma (I - K Hv)^T + K S K^T
// (Woodbury; Joseph form). mu'(2), the heading, is wrapped to (-pi, pi].
// `log_weight` (may be null) gets ProposalLogWeight() at the mu and sigma given, from the same
// Q. Errors as UpdateLandmark, and InvalidArgument when sigma is not symmetric,
// FailedPrecondition when it is not positive semi-definite. On error nothing is written.
// REQUIRES: mu, sigma != nullptr.
Status ProposalStep(Eigen::Vector3d* mu, Eigen::Matrix3d* sigma, const Landmark& landmark,
                    const RangeBearing& z, const SensorNoise& noise, double* log_weight = nullptr);

// The FastSLAM 2.0 importance weight factor of one observation (Montemerlo et al. 2003):
//   log N(z; h(mu, landmark), Hv sigma Hv^T + Hl P Hl^T + R),
// with mu and sigma the proposal before this observation's ProposalStep (the prediction for the
// scan's first observation). Over a scan the factors multiply to p(z_1..z_n | prediction, map)
// in the linear case (chain rule). Same errors as ProposalStep.
Status ProposalLogWeight(const Eigen::Vector3d& mu, const Eigen::Matrix3d& sigma,
                         const Landmark& landmark, const RangeBearing& z, const SensorNoise& noise,
                         double* log_weight);

// A draw from N(mu, sigma): mu + A n with A A^T = sigma, heading wrapped to (-pi, pi].
// A is the lower Cholesky factor L (Eigen LLT) when sigma is positive definite, else, for a
// positive semi-definite sigma (zero motion noise, a degenerate proposal), V Lambda^1/2 from
// Eigen's symmetric eigendecomposition with eigenvalues above -kPsdTolerance clamped to 0.
// `standard_normals`: three independent N(0, 1) draws. Errors: InvalidArgument for non-finite
// inputs or a non-symmetric sigma; FailedPrecondition when sigma is not positive semi-definite.
// REQUIRES: out != nullptr.
Status SamplePose(const Eigen::Vector3d& mu, const Eigen::Matrix3d& sigma,
                  const Eigen::Vector3d& standard_normals, VehiclePose* out);

// a - b with the heading difference wrapped (Bailey's delta_xv): for evaluating pose densities.
Eigen::Vector3d PoseDifference(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

// log N(v; 0, cov) through the Cholesky factor of cov. FailedPrecondition when cov is not
// positive definite (or not finite), InvalidArgument when v is not finite.
// REQUIRES: cov symmetric (only its lower triangle is read).
Status LogGaussianDensity(const Eigen::Vector2d& v, const Eigen::Matrix2d& cov, double* out);
Status LogGaussianDensity(const Eigen::Vector3d& v, const Eigen::Matrix3d& cov, double* out);

// The linear-Gaussian steps the functions above apply to their linearisation, exposed so that
// tests compare them with closed forms. No wrapping happens here: `innovation` is v = z - z_pred.

// Kalman update of N(mean, cov) by v with Jacobian h and noise r, as UpdateLandmark (Joseph
// form). `log_likelihood` (may be null) gets log N(v; 0, h cov h^T + r).
// REQUIRES: cov and r symmetric; mean, cov != nullptr.
Status KalmanUpdate(const Eigen::Vector2d& innovation, const Eigen::Matrix2d& h,
                    const Eigen::Matrix2d& r, Eigen::Vector2d* mean, Eigen::Matrix2d* cov,
                    double* log_likelihood);

// FastSLAM 2.0 proposal update of N(mu, sigma) by v with pose Jacobian h_pose and
// "observation given the pose" covariance s = Hl P Hl^T + R, as ProposalStep but without the
// heading wrap. `log_weight` (may be null) gets log N(v; 0, h_pose sigma h_pose^T + s).
// REQUIRES: sigma and s symmetric; mu, sigma != nullptr.
Status ProposalUpdate(const Eigen::Vector2d& innovation, const Matrix23d& h_pose,
                      const Eigen::Matrix2d& s, Eigen::Vector3d* mu, Eigen::Matrix3d* sigma,
                      double* log_weight);

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_LANDMARK_MATH_H_

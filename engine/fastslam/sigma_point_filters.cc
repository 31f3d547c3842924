#include "engine/fastslam/sigma_point_filters.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace grove::fastslam {
namespace {

Status NotFinite(const char* what) {
  return InvalidArgumentError(fmt::format("{} is not finite", what));
}

bool Finite(const VehiclePose& p) {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.heading_rad);
}

Status CheckObservation(const RangeBearing& z, const SensorNoise& noise) {
  if (!std::isfinite(z.range_m) || !std::isfinite(z.bearing_rad)) return NotFinite("z");
  if (z.range_m < 0) {
    return InvalidArgumentError(fmt::format("z.range_m = {}: must be >= 0", z.range_m));
  }
  return ValidateSensorNoise(noise);
}

Status CheckLandmark(const Landmark& l) {
  if (!std::isfinite(l.x_m) || !std::isfinite(l.y_m) || !std::isfinite(l.xx) ||
      !std::isfinite(l.xy) || !std::isfinite(l.yy)) {
    return NotFinite("the landmark");
  }
  return Status::Ok();
}

// diag(sigma_range, sigma_bearing), each floored at kMinSigma: the root of SensorCovariance().
Eigen::Matrix2d SensorRoot(const SensorNoise& noise) {
  return Eigen::Vector2d(std::max(noise.sigma_range_m, kMinSigma),
                         std::max(noise.sigma_bearing_rad, kMinSigma))
      .asDiagonal();
}

// The vehicle model on an augmented point [x, y, heading, dv, dg].
struct Motion {
  const VehicleGeometry& g;
  double v, steer, dt;
  bool operator()(const Vec<5>& a, Vec<3>* y) const {
    const double s = steer + a(4);
    if (!SteeringUsable(g, s)) return false;
    const VehiclePose p =
        MoveVehicle(g, ControlTermsOf(g, v + a(3), s, dt), VehiclePose{a(0), a(1), a(2)});
    *y << p.x_m, p.y_m, p.heading_rad;
    return y->allFinite();
  }
};

// (range, bearing) of landmark (lx, ly) from (x, y, heading); false at the sensor position.
bool RangeBearingOf(double x, double y, double heading, double lx, double ly, Vec<2>* out) {
  const double dx = lx - x, dy = ly - y;
  const double r = std::sqrt(dx * dx + dy * dy);
  if (!(r > 0) || !std::isfinite(r)) return false;
  *out << r, WrapAngle(std::atan2(dy, dx) - heading);
  return true;
}

Eigen::Vector2d InnovationOf(const RangeBearing& z, const Vec<2>& z_hat) {
  return {z.range_m - z_hat(0), WrapAngle(z.bearing_rad - z_hat(1))};
}

Status PointFailed(const char* step) {
  return FailedPreconditionError(fmt::format(
      "{}: a sigma point cannot be evaluated (a landmark at the sensor position or a steering "
      "angle the vehicle model cannot use)",
      step));
}

Status NotPsd(const char* what) {
  return FailedPreconditionError(fmt::format("{} is not positive semi-definite", what));
}

// x += K v, P -= K S K^T with K = Pxz S^-1; *log_likelihood = log N(v; 0, S). Writes nothing on
// error.
template <int N>
Status CovarianceUpdate(const Mat<N, 2>& pxz, const Eigen::Matrix2d& s, const Eigen::Vector2d& v,
                        Vec<N>* x, Mat<N, N>* p, double* log_likelihood) {
  const Eigen::LLT<Eigen::Matrix2d> llt(s);
  if (llt.info() != Eigen::Success || !s.allFinite()) {
    return FailedPreconditionError("the innovation covariance is not positive definite");
  }
  const Mat<N, 2> k = llt.solve(pxz.transpose()).transpose();
  const Vec<N> nx = *x + k * v;
  Mat<N, N> np = *p - k * s * k.transpose();
  np = 0.5 * (np + np.transpose());
  const Eigen::Vector2d w = llt.matrixL().solve(v);
  const double ll = -0.5 * w.squaredNorm() - std::log(2 * std::numbers::pi) -
                    std::log(llt.matrixLLT().diagonal().prod());
  if (!nx.allFinite() || !np.allFinite() || !std::isfinite(ll)) {
    return FailedPreconditionError("the unscented update is not finite");
  }
  *x = nx;
  *p = np;
  if (log_likelihood != nullptr) *log_likelihood = ll;
  return Status::Ok();
}

}  // namespace

Status UnscentedPredict(const VehicleGeometry& g, double v_mps, double steer_rad, double dt_s,
                        const ControlNoise& q, const UnscentedRule& rule, Eigen::Vector3d* mean,
                        Eigen::Matrix3d* cov) {
  if (!mean->allFinite() || !cov->allFinite()) return NotFinite("the pose or its covariance");
  Mat<5, 5> root = Mat<5, 5>::Zero();
  Eigen::Matrix3d r3;
  if (!PsdSquareRoot<3>(0.5 * (*cov + cov->transpose()), &r3)) return NotPsd("the pose covariance");
  root.topLeftCorner<3, 3>() = r3;
  root(3, 3) = q.sigma_speed_mps;
  root(4, 4) = q.sigma_steer_rad;
  Vec<5> a;
  a << *mean, 0, 0;
  const UnscentedWeights w = UnscentedWeightsFor(5, rule.alpha, rule.beta, rule.kappa, 2);
  Vec<3> m;
  Mat<3, 3> c;
  if (!UnscentedTransform<5, 3>(a, root, w, 2, Motion{g, v_mps, steer_rad, dt_s}, &m, &c,
                                nullptr)) {
    return PointFailed("unscented prediction");
  }
  m(2) = WrapAngle(m(2));
  if (!m.allFinite() || !c.allFinite()) {
    return FailedPreconditionError("unscented prediction is not finite");
  }
  *mean = m;
  *cov = c;
  return Status::Ok();
}

Status UnscentedProposalStep(Eigen::Vector3d* mu, Eigen::Matrix3d* sigma, const Landmark& landmark,
                             const RangeBearing& z, const SensorNoise& noise,
                             const UnscentedRule& rule, double* log_weight) {
  if (!mu->allFinite() || !sigma->allFinite()) return NotFinite("the pose or its covariance");
  GROVE_RETURN_IF_ERROR(CheckObservation(z, noise));
  GROVE_RETURN_IF_ERROR(CheckLandmark(landmark));
  Eigen::Matrix3d rv;
  Eigen::Matrix2d rl;
  if (!PsdSquareRoot<3>(0.5 * (*sigma + sigma->transpose()), &rv)) {
    return NotPsd("the pose covariance");
  }
  if (!PsdSquareRoot<2>(Covariance(landmark), &rl)) return NotPsd("the landmark covariance");
  Mat<5, 5> root = Mat<5, 5>::Zero();
  root.topLeftCorner<3, 3>() = rv;
  root.bottomRightCorner<2, 2>() = rl;
  Vec<5> a;
  a << *mu, landmark.x_m, landmark.y_m;
  const UnscentedWeights w = UnscentedWeightsFor(5, rule.alpha, rule.beta, rule.kappa, 2);
  auto observe = [](const Vec<5>& p, Vec<2>* y) {
    return RangeBearingOf(p(0), p(1), p(2), p(3), p(4), y);
  };
  Vec<2> z_hat;
  Eigen::Matrix2d s;
  Mat<5, 2> cross;
  if (!UnscentedTransform<5, 2>(a, root, w, 1, observe, &z_hat, &s, &cross)) {
    return PointFailed("unscented proposal");
  }
  s += SensorCovariance(noise);
  Eigen::Vector3d m = *mu;
  Eigen::Matrix3d p = *sigma;
  GROVE_RETURN_IF_ERROR(
      CovarianceUpdate<3>(cross.topRows<3>(), s, InnovationOf(z, z_hat), &m, &p, log_weight));
  m(2) = WrapAngle(m(2));
  *mu = m;
  *sigma = p;
  return Status::Ok();
}

Status UnscentedUpdateLandmark(const VehiclePose& pose, const RangeBearing& z,
                               const SensorNoise& noise, const UnscentedRule& rule,
                               Landmark* landmark, double* log_likelihood) {
  if (!Finite(pose)) return NotFinite("the pose");
  GROVE_RETURN_IF_ERROR(CheckObservation(z, noise));
  GROVE_RETURN_IF_ERROR(CheckLandmark(*landmark));
  Eigen::Matrix2d rl;
  if (!PsdSquareRoot<2>(Covariance(*landmark), &rl)) return NotPsd("the landmark covariance");
  Mat<4, 4> root = Mat<4, 4>::Zero();
  root.topLeftCorner<2, 2>() = rl;
  root.bottomRightCorner<2, 2>() = SensorRoot(noise);
  Vec<4> a;
  a << landmark->x_m, landmark->y_m, 0, 0;
  const UnscentedWeights w = UnscentedWeightsFor(4, rule.alpha, rule.beta, rule.kappa);
  auto observe = [&](const Vec<4>& p, Vec<2>* y) {
    if (!RangeBearingOf(pose.x_m, pose.y_m, pose.heading_rad, p(0), p(1), y)) return false;
    *y += p.tail<2>();
    return true;
  };
  Vec<2> z_hat;
  Eigen::Matrix2d s;
  Mat<4, 2> cross;
  if (!UnscentedTransform<4, 2>(a, root, w, 1, observe, &z_hat, &s, &cross)) {
    return PointFailed("unscented landmark update");
  }
  Eigen::Vector2d m = Mean(*landmark);
  Eigen::Matrix2d p = Covariance(*landmark);
  GROVE_RETURN_IF_ERROR(
      CovarianceUpdate<2>(cross.topRows<2>(), s, InnovationOf(z, z_hat), &m, &p, log_likelihood));
  landmark->x_m = m(0);
  landmark->y_m = m(1);
  SetCovariance(p, landmark);
  return Status::Ok();
}

Status CentralDifferencePredict(const VehicleGeometry& g, double v_mps, double steer_rad,
                                double dt_s, const ControlNoise& q, double h, Eigen::Vector3d* mean,
                                Eigen::Matrix3d* factor) {
  if (!mean->allFinite() || !factor->allFinite()) return NotFinite("the pose or its factor");
  Mat<5, 5> f = Mat<5, 5>::Zero();
  f.topLeftCorner<3, 3>() = factor->triangularView<Eigen::Lower>();
  f(3, 3) = q.sigma_speed_mps;
  f(4, 4) = q.sigma_steer_rad;
  Vec<5> a;
  a << *mean, 0, 0;
  Vec<3> m;
  Mat<3, 3> s;
  if (!CentralDifferenceTransform<5, 3>(a, f, CentralDifferenceWeightsFor(5, h), 2,
                                        Motion{g, v_mps, steer_rad, dt_s}, nullptr, &m, &s,
                                        nullptr)) {
    return PointFailed("central-difference prediction");
  }
  m(2) = WrapAngle(m(2));
  if (!m.allFinite() || !s.allFinite()) {
    return FailedPreconditionError("central-difference prediction is not finite");
  }
  *mean = m;
  *factor = s;
  return Status::Ok();
}

Status CentralDifferenceProposalStep(Eigen::Vector3d* mu, Eigen::Matrix3d* factor,
                                     const Landmark& landmark, const RangeBearing& z,
                                     const SensorNoise& noise, double h, double* log_weight) {
  if (!mu->allFinite() || !factor->allFinite()) return NotFinite("the pose or its factor");
  GROVE_RETURN_IF_ERROR(CheckObservation(z, noise));
  GROVE_RETURN_IF_ERROR(CheckLandmark(landmark));
  Mat<5, 5> f = Mat<5, 5>::Zero();
  f.topLeftCorner<3, 3>() = factor->triangularView<Eigen::Lower>();
  f.bottomRightCorner<2, 2>() = CholeskyFactor(landmark);
  Vec<5> a;
  a << *mu, landmark.x_m, landmark.y_m;
  auto observe = [](const Vec<5>& p, Vec<2>* y) {
    return RangeBearingOf(p(0), p(1), p(2), p(3), p(4), y);
  };
  const Eigen::Matrix2d noise_root = SensorRoot(noise);
  Vec<2> z_hat;
  Eigen::Matrix2d s_z;
  Mat<2, 5> d;
  if (!CentralDifferenceTransform<5, 2>(a, f, CentralDifferenceWeightsFor(5, h), 1, observe,
                                        &noise_root, &z_hat, &s_z, &d)) {
    return PointFailed("central-difference proposal");
  }
  const Mat<3, 2> pxz = f.topLeftCorner<3, 3>() * d.leftCols<3>().transpose();
  Eigen::Vector3d m = *mu;
  Eigen::Matrix3d s = f.topLeftCorner<3, 3>();
  GROVE_RETURN_IF_ERROR(
      (SquareRootUpdate<3, 2>(pxz, s_z, InnovationOf(z, z_hat), &m, &s, log_weight)));
  m(2) = WrapAngle(m(2));
  *mu = m;
  *factor = s;
  return Status::Ok();
}

Status CentralDifferenceUpdateLandmark(const VehiclePose& pose, const RangeBearing& z,
                                       const SensorNoise& noise, double h, Landmark* landmark,
                                       double* log_likelihood) {
  if (!Finite(pose)) return NotFinite("the pose");
  GROVE_RETURN_IF_ERROR(CheckObservation(z, noise));
  GROVE_RETURN_IF_ERROR(CheckLandmark(*landmark));
  const Eigen::Matrix2d f = CholeskyFactor(*landmark);
  auto observe = [&](const Vec<2>& p, Vec<2>* y) {
    return RangeBearingOf(pose.x_m, pose.y_m, pose.heading_rad, p(0), p(1), y);
  };
  const Eigen::Matrix2d noise_root = SensorRoot(noise);
  Vec<2> z_hat;
  Eigen::Matrix2d s_y;
  Mat<2, 2> d;
  if (!CentralDifferenceTransform<2, 2>(Mean(*landmark), f, CentralDifferenceWeightsFor(2, h), 1,
                                        observe, &noise_root, &z_hat, &s_y, &d)) {
    return PointFailed("central-difference landmark update");
  }
  const Eigen::Matrix2d ply = f * d.transpose();
  Eigen::Vector2d m = Mean(*landmark);
  Eigen::Matrix2d s = f;
  GROVE_RETURN_IF_ERROR(
      (SquareRootUpdate<2, 2>(ply, s_y, InnovationOf(z, z_hat), &m, &s, log_likelihood)));
  landmark->x_m = m(0);
  landmark->y_m = m(1);
  SetCholeskyFactor(s, landmark);
  return Status::Ok();
}

Landmark CentralDifferenceInitLandmark(const VehiclePose& pose, const RangeBearing& z,
                                       const SensorNoise& noise, double h) {
  auto inverse = [&](const Vec<2>& rb, Vec<2>* y) {
    const double a = pose.heading_rad + rb(1);
    *y << pose.x_m + rb(0) * std::cos(a), pose.y_m + rb(0) * std::sin(a);
    return true;
  };
  Vec<2> m;
  Eigen::Matrix2d s;
  CentralDifferenceTransform<2, 2>(Vec<2>(z.range_m, z.bearing_rad), SensorRoot(noise),
                                   CentralDifferenceWeightsFor(2, h), -1, inverse, nullptr, &m, &s,
                                   nullptr);
  Landmark l;
  l.x_m = m(0);
  l.y_m = m(1);
  SetCholeskyFactor(s, &l);
  return l;
}

Status SamplePoseFromFactor(const Eigen::Vector3d& mu, const Eigen::Matrix3d& factor,
                            const Eigen::Vector3d& standard_normals, VehiclePose* out) {
  if (!mu.allFinite() || !factor.allFinite() || !standard_normals.allFinite()) {
    return NotFinite("the pose, its factor or the normal draws");
  }
  Eigen::Vector3d x = mu + factor.triangularView<Eigen::Lower>() * standard_normals;
  if (!x.allFinite()) return FailedPreconditionError("the pose sample is not finite");
  x(2) = WrapAngle(x(2));
  *out = ToPose(x);
  return Status::Ok();
}

}  // namespace grove::fastslam

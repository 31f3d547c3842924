// FilterSteps: the pose and landmark steps of one filter of FastSlamFilter, as its FilterTraits
// choose them, with the noise and parameters they use.
//
//   Pose prediction: FastSLAM 1.0 draws the particle's own control from N(u, Q) and moves;
//     FastSLAM 2.0 moves the mean with the control and propagates the pose covariance,
//     Sigma' = Gv Sigma Gv^T + Gu Q Gu^T; the sigma-point steps predict mean and covariance by
//     the unscented or central-difference transform.
//   Proposal: one observation's refinement of the pose mean and covariance, with its predictive
//     log-likelihood; the draw from the proposal; for the sigma-point particle filter the
//     importance ratio's pose terms.
//   Landmarks: a leaf's update from a known pose and a new leaf's initialisation.
//
// Every method is const and reads only the configuration: one FilterSteps serves every worker.
#ifndef GROVE_ENGINE_FASTSLAM_FILTER_STEPS_H_
#define GROVE_ENGINE_FASTSLAM_FILTER_STEPS_H_

#include <fmt/format.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>

#include "concurrency/normal_batch.h"
#include "concurrency/normal_pairs.h"
#include "concurrency/random_stream.h"
#include "engine/fastslam/filter_traits.h"
#include "engine/fastslam/landmark_math.h"
#include "engine/fastslam/sampled_motion.h"
#include "engine/fastslam/sigma_point_filters.h"
#include "engine/fastslam/vehicle_model.h"
#include "grove/fastslam.h"
#include "grove/status.h"

namespace grove::fastslam {

// Errors of the filter's particle `particle`.
inline Status NoMemoryError(uint64_t particle, const char* what) {
  return ResourceExhaustedError(fmt::format("out of memory for particle {}'s {}", particle, what));
}
inline Status ParticleError(uint64_t particle, const LandmarkObservation& z, const Status& s) {
  return Status(s.code(), fmt::format("particle {}, landmark {}: {}", particle, z.id, s.message()));
}
inline Status ParticleStatus(uint64_t particle, const Status& s) {
  return Status(s.code(), fmt::format("particle {}: {}", particle, s.message()));
}

// A control held over dt_s.
struct ControlStep {
  double v_mps = 0;
  double steer_rad = 0;
  double dt_s = 0;
};

// One prediction: a control, and whether it is the first after the start or a scan (it starts
// a path segment: fastslam_model.h).
struct PredictStep {
  ControlStep control;
  bool starts_segment = false;
};

// One scan's observations (validated by the facade).
struct ScanStep {
  std::span<const LandmarkObservation> observations;
};

class FilterSteps {
 public:
  // REQUIRES: config.Validate() is ok.
  explicit FilterSteps(const FastSlamConfig& config)
      : traits_(TraitsOf(config.filter)),
        geometry_(VehicleGeometry::Of(config)),
        noise_{config.sigma_range_m, config.sigma_bearing_rad},
        control_noise_{config.sigma_speed_mps, config.sigma_steer_rad},
        rule_{config.ut_alpha, config.ut_beta, config.ut_kappa},
        cd_step_(config.cd_step),
        seed_(config.seed) {
    q_ << config.sigma_speed_mps * config.sigma_speed_mps, 0, 0,
        config.sigma_steer_rad * config.sigma_steer_rad;
  }

  const FilterTraits& traits() const { return traits_; }
  const VehicleGeometry& geometry() const { return geometry_; }
  const SensorNoise& noise() const { return noise_; }

  // The pose covariance every particle starts with and, for the sigma-point pose steps, returns
  // to after each scan's draw: 0 for FastSLAM 2.0's EKF; eps I (unscented) or its factor
  // sqrt(eps) I (central difference), as Kim's code.
  PoseCovariance restart_covariance() const {
    if (traits_.pose == FilterTraits::Pose::kUnscented) {
      return PoseCovariance{kPoseRestartVariance, 0, 0,
                            kPoseRestartVariance, 0, kPoseRestartVariance};
    }
    if (traits_.square_root_pose()) {
      const double s = std::sqrt(kPoseRestartVariance);
      return PoseCovariance{s, 0, 0, s, 0, s};
    }
    return PoseCovariance{};
  }

  // The stored pose covariance as a matrix: the covariance, or the lower factor.
  Eigen::Matrix3d Stored(const PoseCovariance& c) const {
    if (!traits_.square_root_pose()) return Full(c);
    return (Eigen::Matrix3d() << c.xx, 0, 0, c.xy, c.yy, 0, c.xh, c.yh, c.hh).finished();
  }
  PoseCovariance Store(const Eigen::Matrix3d& m) const {
    if (!traits_.square_root_pose()) return Upper(m);
    return PoseCovariance{m(0, 0), m(1, 0), m(2, 0), m(1, 1), m(2, 1), m(2, 2)};
  }

  // The pose particle `index` reaches from `p`, whose covariance is *cov, by the prediction of
  // filter step `step` (*cov is advanced too): the one computation of a prediction, for
  // FastSlamModel::Predict() and for the replay of paths. *usable is false when the model cannot
  // use the control (or, for the sigma-point steps, one of its sigma points).
  VehiclePose PredictPose(const VehiclePose& p, PoseCovariance* cov, const ControlStep& c,
                          uint64_t step, uint32_t index, bool* usable) const {
    switch (traits_.pose) {
      case FilterTraits::Pose::kSampledMotion: {
        // The unit vector is SinCos of the heading (sampled_motion.h): recomputed, not stored.
        VehiclePose q = p;
        HeadingUnit unit;
        *usable = PredictSampled(c, step, index, true, &q, &unit, 1).first_failed == 1;
        return *usable ? q : p;
      }
      case FilterTraits::Pose::kEkf: {
        // As kSampledMotion: the unit vector is recomputed; the covariance is not needed.
        VehiclePose q = p;
        HeadingUnit unit;
        *usable = SteeringUsable(geometry_, c.steer_rad) &&
                  PredictLinearized(c, true, &q, &unit, nullptr, 1).first_failed == 1;
        return *usable ? q : p;
      }
      case FilterTraits::Pose::kUnscented:
      case FilterTraits::Pose::kCentralDifference: {
        Eigen::Vector3d mean = ToVector(p);
        Eigen::Matrix3d m = Stored(*cov);
        *usable = SigmaPointPredict(c, &mean, &m).ok();
        if (!*usable) return p;
        *cov = Store(m);
        return ToPose(mean);
      }
    }
    *usable = false;
    return p;
  }

  // The unscented or central-difference prediction of (mean, m) over the control.
  Status SigmaPointPredict(const ControlStep& c, Eigen::Vector3d* mean, Eigen::Matrix3d* m) const {
    if (traits_.pose == FilterTraits::Pose::kUnscented) {
      return UnscentedPredict(geometry_, c.v_mps, c.steer_rad, c.dt_s, control_noise_, rule_, mean,
                              m);
    }
    return CentralDifferencePredict(geometry_, c.v_mps, c.steer_rad, c.dt_s, control_noise_,
                                    cd_step_, mean, m);
  }

  // FastSLAM 1.0: the predictions of the filter's particles first, first + 1, ... at
  // poses[0, n) and units[0, n) by `step`'s control c (MoveSampled()), each with its own pair of
  // normals from its stream for the step (DrawNormalPairs(): the speed's first when both sigmas
  // are above 0). units_from_headings: as MoveSampled()'s.
  MotionResult PredictSampled(const ControlStep& c, uint64_t step, uint32_t first,
                              bool units_from_headings, VehiclePose* poses, HeadingUnit* units,
                              size_t n) const {
    const SampledControl u{geometry_,
                           c.v_mps,
                           c.steer_rad,
                           c.dt_s,
                           control_noise_.sigma_speed_mps,
                           control_noise_.sigma_steer_rad};
    constexpr size_t kBlock = 256;
    double noise[2][kBlock];
    double* const rows[2] = {noise[0], noise[1]};
    for (size_t b = 0; b < n; b += kBlock) {
      const size_t m = std::min(kBlock, n - b);
      if (u.normals() > 0) {
        const uint32_t at = first + static_cast<uint32_t>(b);
        DrawNormalPairs(seed_, step + 1, StreamPurpose::kMotion, at, at + static_cast<uint32_t>(m),
                        noise[0], noise[1]);
      }
      const MotionResult r = MoveSampled(u, rows, units_from_headings, poses + b, units + b, m);
      if (r.first_failed < m) return {b + r.first_failed, r.why};
    }
    return {n, MotionFailure::kNone};
  }

  // The EKF pose steps' prediction of particles [0, n) over control c (MoveLinearized(); covs
  // nullptr: the poses only). REQUIRES: SteeringUsable() of c's steering.
  MotionResult PredictLinearized(const ControlStep& c, bool units_from_headings, VehiclePose* poses,
                                 HeadingUnit* units, PoseCovariance* covs, size_t n) const {
    const SampledControl u{geometry_, c.v_mps, c.steer_rad, c.dt_s, 0, 0};
    return MoveLinearized(u, q_(0, 0), q_(1, 1), units_from_headings, poses, units, covs, n);
  }

  // The covariance reading of a leaf.
  Landmark CovarianceLeaf(const Landmark& leaf) const {
    return traits_.square_root_map() ? WithCovariance(leaf) : leaf;
  }

  // One observation's proposal step on (mu, sigma) by the filter's pose step; *w gets its
  // predictive log-likelihood.
  Status ProposalStep(const LandmarkObservation& z, const Landmark& leaf, Eigen::Vector3d* mu,
                      Eigen::Matrix3d* sigma, double* w) const {
    const RangeBearing rb{z.range_m, z.bearing_rad};
    switch (traits_.pose) {
      case FilterTraits::Pose::kUnscented:
        return UnscentedProposalStep(mu, sigma, CovarianceLeaf(leaf), rb, noise_, rule_, w);
      case FilterTraits::Pose::kCentralDifference: {
        Landmark root;
        Status s = SquareRootLeaf(leaf, &root);
        if (!s.ok()) return s;
        return CentralDifferenceProposalStep(mu, sigma, root, rb, noise_, cd_step_, w);
      }
      default:
        return fastslam::ProposalStep(mu, sigma, CovarianceLeaf(leaf), rb, noise_, w);
    }
  }

  // A draw for the filter's particle `particle` from N(mu, sigma) (sigma a covariance or a
  // factor) keyed by (step, particle).
  Status Draw(uint64_t step, uint64_t particle, const Eigen::Vector3d& mu,
              const Eigen::Matrix3d& sigma, VehiclePose* out) const {
    RandomStream rs(seed_, step + 1, static_cast<uint32_t>(particle), StreamPurpose::kProposal);
    Eigen::Vector3d normals;
    for (int k = 2; k >= 0; --k) normals(k) = rs.NextNormal();
    return DrawWith(normals, particle, mu, sigma, out);
  }

  // The deviates Draw() takes, for up to kDrawChunk consecutive particles drawn at once
  // (DrawNormals: the same numbers as their streams, particles in SIMD lanes).
  static constexpr size_t kDrawChunk = 64;
  struct Deviates {
    double normal[3][kDrawChunk];  // normal[j][k]: the k-th particle's j-th
    // The k-th particle's, by pose entry (x, y, heading): its third, second and first, the
    // order Draw() has always used.
    Eigen::Vector3d of(size_t k) const { return {normal[2][k], normal[1][k], normal[0][k]}; }
  };
  // Draws the deviates of the filter's particles [begin, end) at `step` into *d.
  // REQUIRES: end - begin <= kDrawChunk.
  void DrawDeviates(uint64_t step, uint64_t begin, uint64_t end, Deviates* d) const {
    double* out[3] = {d->normal[0], d->normal[1], d->normal[2]};
    DrawNormals(seed_, step + 1, StreamPurpose::kProposal, static_cast<uint32_t>(begin),
                static_cast<uint32_t>(end), std::span<double* const>(out, 3));
  }

  // Draw() with its deviates given, normals(k) for entry k of the pose (x, y, heading).
  Status DrawWith(const Eigen::Vector3d& normals, uint64_t particle, const Eigen::Vector3d& mu,
                  const Eigen::Matrix3d& sigma, VehiclePose* out) const {
    Status s = traits_.square_root_pose() ? SamplePoseFromFactor(mu, sigma, normals, out)
                                          : SamplePose(mu, sigma, normals, out);
    if (!s.ok()) {
      return FailedPreconditionError(
          fmt::format("particle {}'s proposal: {}", particle, s.message()));
    }
    return Status::Ok();
  }

  // The sigma-point particle filter: adds to *w the pose terms of the importance weight at the
  // drawn x, log N(x; prediction) - log N(x; proposal), the prediction (prior_mu, prior) and the
  // proposal (mu, sigma) given by their factors; errors name the filter's particle `particle`.
  Status AddImportanceRatio(uint64_t particle, const Eigen::Vector3d& prior_mu,
                            const Eigen::Matrix3d& prior, const VehiclePose& x,
                            const Eigen::Vector3d& mu, const Eigen::Matrix3d& sigma,
                            double* w) const {
    const Eigen::Vector3d xv = ToVector(x);
    if (!(prior.diagonal().array() > 0).all() || !(sigma.diagonal().array() > 0).all()) {
      return FailedPreconditionError(
          fmt::format("particle {}: a pose covariance is singular: the importance ratio is not "
                      "defined",
                      particle));
    }
    *w += LogDensityOfFactor<3>(prior, PoseDifference(xv, prior_mu)) -
          LogDensityOfFactor<3>(sigma, PoseDifference(xv, mu));
    if (!std::isfinite(*w)) {
      return FailedPreconditionError(
          fmt::format("particle {}'s importance weight is not finite", particle));
    }
    return Status::Ok();
  }

  // A leaf's update by z from a known pose, by the filter's landmark step.
  Status UpdateLeaf(const VehiclePose& pose, const RangeBearing& z, Landmark* l, double* ll) const {
    switch (traits_.map) {
      case FilterTraits::Map::kUnscented:
        return UnscentedUpdateLandmark(pose, z, noise_, rule_, l, ll);
      case FilterTraits::Map::kCentralDifference:
        return CentralDifferenceUpdateLandmark(pose, z, noise_, cd_step_, l, ll);
      default:
        return UpdateLandmark(pose, z, noise_, l, ll);
    }
  }
  // A new leaf from z seen at `pose` (U-FastSLAM initialises as the EKF does: Kim's add_feature)
  // into *out. FailedPrecondition when its mean or covariance is not finite.
  Status NewLeaf(const VehiclePose& pose, const RangeBearing& z, Landmark* out) const {
    *out = traits_.map == FilterTraits::Map::kCentralDifference
               ? CentralDifferenceInitLandmark(pose, z, noise_, cd_step_)
               : InitLandmark(pose, z, noise_);
    const Landmark& l = *out;
    if (!std::isfinite(l.x_m) || !std::isfinite(l.y_m) || !std::isfinite(l.xx) ||
        !std::isfinite(l.xy) || !std::isfinite(l.yy)) {
      return FailedPreconditionError(fmt::format(
          "the new landmark of range = {}, bearing = {} from ({}, {}, {}) is not finite: mean "
          "({}, {}), covariance ({}, {}, {})",
          z.range_m, z.bearing_rad, pose.x_m, pose.y_m, pose.heading_rad, l.x_m, l.y_m, l.xx, l.xy,
          l.yy));
    }
    return Status::Ok();
  }

 private:
  static Eigen::Matrix3d Full(const PoseCovariance& c) {
    return (Eigen::Matrix3d() << c.xx, c.xy, c.xh, c.xy, c.yy, c.yh, c.xh, c.yh, c.hh).finished();
  }
  static PoseCovariance Upper(const Eigen::Matrix3d& m) {
    return PoseCovariance{m(0, 0), 0.5 * (m(0, 1) + m(1, 0)), 0.5 * (m(0, 2) + m(2, 0)),
                          m(1, 1), 0.5 * (m(1, 2) + m(2, 1)), m(2, 2)};
  }

  // The square-root reading of a leaf: the lower Cholesky factor of a covariance leaf (for a
  // singular one, the triangular factor of its eigen-root).
  Status SquareRootLeaf(const Landmark& leaf, Landmark* out) const {
    *out = leaf;
    if (traits_.square_root_map()) return Status::Ok();
    Eigen::Matrix2d root;
    if (!PsdSquareRoot<2>(Covariance(leaf), &root)) {
      return FailedPreconditionError("the landmark covariance is not positive semi-definite");
    }
    SetCholeskyFactor(TriangularFactor<2, 2>(root), out);
    return Status::Ok();
  }

  const FilterTraits traits_;
  const VehicleGeometry geometry_;
  const SensorNoise noise_;
  const ControlNoise control_noise_;
  const UnscentedRule rule_;
  const double cd_step_;  // the central-difference steps' h
  const uint64_t seed_;
  Eigen::Matrix2d q_;  // the control noise's covariance Q
};

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_FILTER_STEPS_H_

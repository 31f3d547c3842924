// The per-particle steps of the sigma-point landmark filters: U-FastSLAM's unscented steps (Kim,
// Sakthivel, Chung, "Unscented FastSLAM", IEEE T-RO 24(4), 2008) and the square-root
// central-difference steps of SRCD-FastSLAM (Ankışhan et al., "Square root central
// difference-based FastSLAM approach improved by differential evolution", 2016, §3.1), built on
// sigma_points.h. Conventions (poses, sensor, wrapping, Landmark) as landmark_math.h.
//
// U-FastSLAM, as Kim's released implementation (OpenSLAM ufastslam: predictACFRu,
// sample_proposaluf, feature_updateu, add_feature), which realises the paper's augmented vehicle
// state [x; q; r] by augmenting each step with what it needs and adding the dimension of the
// measurement noise (2) to lambda where that noise is left out:
//   prediction    [x; q] (L = 5), lambda + 2: x' = f(x, u + q); the covariance of the points.
//   proposal      [x; landmark] (L = 5), lambda + 2, per observation of a known landmark:
//                 S = Cov(Z) + R, Pxz, K = Pxz S^-1, mu += K v, Sigma -= K S K^T; the weight
//                 factor log N(v; 0, S).
//   landmark      [landmark; r] (L = 4): S = Cov(Z) (the noise is in the points), Plz,
//                 mean += K v, P -= K S K^T.
//   new landmark  Kim's add_feature: the EKF's G R G^T (InitLandmark).
// Kim's proposal stacks all of a scan's observations into one update; grove applies them one at
// a time (recomputing the sigma points from the refined pose each time), as its FastSLAM 2.0
// does, because the stacked form puts different landmarks' perturbations in the same sigma-point
// column and so correlates landmarks that are independent.
//
// SRCD (square-root central difference, h = sqrt(3) by default), every covariance kept as its
// lower Cholesky factor (the vehicle's and the landmarks'):
//   prediction    [x; q] (L = 5), Eqs. 9-14: the seed augments with r too (L = 7), but the motion
//                 does not depend on r, so its points add nothing: the result is identical.
//   proposal      [x; landmark] (L = 5) with the sensor noise additive, per observation of a known
//                 landmark, Eqs. 15-18: Z = h(x, landmark), S_z = qr(...; sqrt(R)),
//                 Pxz = S_x D_x^T, K = Pxz (S_z S_z^T)^-1, mu += K v, S_x downdated by K S_z; the
//                 weight factor log N(v; 0, S_z S_z^T) (Eq. 26, see below). For additive noise
//                 the seed's augmentation with r (Eq. 9) gives exactly the sqrt(R) columns.
//   landmark      [landmark] (L = 2) with R additive (Eqs. 20-23 with Appendix B's [mu; 0],
//                 diag(P, R)): S_y, Ply = S_l D^T, K, mean += K v, S_l downdated by K S_y.
//   new landmark  Eqs. 24-25: the points z, z +- h sqrt(R)_k through the inverse model; their
//                 mean, and the factor of their central-difference covariance.
// Readings of the seed (its equations lost their layout in extraction; see also
// engine/fastslam/README.md, "Readings of the seed paper's text"):
//   - Eq. 16 predicts each observation from the landmark's mean only, while Eq. 26's weight
//     covariance B = (P^{x,L})^T S^-1 P^{x,L} + S_y adds the landmark's innovation covariance S_y
//     to the vehicle's part. grove puts the landmark into the proposal's sigma points (as Kim's
//     code does), so S_z S_z^T is that B: the proposal and the weight use one covariance.
//   - Eq. 25 appends sqrt(R_t) to the landmark's columns and ends with a cholupdate by
//     M_0 - mu with weight wc0: that is the square-root unscented form. In the central-difference
//     form the noise is already in the points z +- h sqrt(R) and there is no zeroth covariance
//     weight, so grove takes the factor of the points' central-difference covariance alone
//     (appending sqrt(R), a range-bearing quantity, to landmark-space columns would mix units).
//
// Errors: InvalidArgument for non-finite inputs; FailedPrecondition for a sigma point the models
// cannot evaluate (a landmark at the sensor, a steering angle the vehicle cannot use), a
// covariance that is not positive semi-definite, a downdate that would lose positive
// definiteness, or a non-finite result. On error nothing is written.
//
// Thread safety: free functions on values.
#ifndef GROVE_ENGINE_FASTSLAM_SIGMA_POINT_FILTERS_H_
#define GROVE_ENGINE_FASTSLAM_SIGMA_POINT_FILTERS_H_

#include <Eigen/Core>

#include "engine/fastslam/landmark_math.h"
#include "engine/fastslam/sigma_points.h"
#include "engine/fastslam/vehicle_model.h"
#include "grove/status.h"

namespace grove::fastslam {

// The scaled unscented transform's parameters (Kim's defaults 0.9, 2, 0).
struct UnscentedRule {
  double alpha = 0.9;
  double beta = 2;
  double kappa = 0;
};

// Standard deviations of the control noise (speed m/s, steering rad).
struct ControlNoise {
  double sigma_speed_mps = 0;
  double sigma_steer_rad = 0;
};

// The restart value of a vehicle covariance after each draw, as Kim's code (Pv = eps I): the
// factor sqrt(eps) I, so that square-root downdates always have a pivot. Physically nil
// (1.5e-8 m and rad).
inline constexpr double kPoseRestartVariance = 2.220446049250313e-16;

// ---- U-FastSLAM (covariances) ----

// The prediction of N(mean, cov) over one control (v, steer) held for dt_s.
Status UnscentedPredict(const VehicleGeometry& g, double v_mps, double steer_rad, double dt_s,
                        const ControlNoise& q, const UnscentedRule& rule, Eigen::Vector3d* mean,
                        Eigen::Matrix3d* cov);

// The proposal step of one observation z of `landmark` (covariance reading); *log_weight (may
// be null) gets log N(v; 0, S).
Status UnscentedProposalStep(Eigen::Vector3d* mu, Eigen::Matrix3d* sigma, const Landmark& landmark,
                             const RangeBearing& z, const SensorNoise& noise,
                             const UnscentedRule& rule, double* log_weight);

// The update of `landmark` (covariance reading) by z from a known pose; *log_likelihood (may be
// null) gets log N(v; 0, S).
Status UnscentedUpdateLandmark(const VehiclePose& pose, const RangeBearing& z,
                               const SensorNoise& noise, const UnscentedRule& rule,
                               Landmark* landmark, double* log_likelihood);

// ---- SRCD (Cholesky factors) ----

// The prediction of N(mean, factor factor^T).
Status CentralDifferencePredict(const VehicleGeometry& g, double v_mps, double steer_rad,
                                double dt_s, const ControlNoise& q, double h, Eigen::Vector3d* mean,
                                Eigen::Matrix3d* factor);

// The proposal step of one observation z of the landmark N(landmark_mean, landmark_factor
// landmark_factor^T); *log_weight (may be null) gets log N(v; 0, S_z S_z^T).
Status CentralDifferenceProposalStep(Eigen::Vector3d* mu, Eigen::Matrix3d* factor,
                                     const Landmark& landmark, const RangeBearing& z,
                                     const SensorNoise& noise, double h, double* log_weight);

// The update of `landmark` (square-root reading) by z from a known pose; *log_likelihood (may
// be null) gets log N(v; 0, S_y S_y^T).
Status CentralDifferenceUpdateLandmark(const VehiclePose& pose, const RangeBearing& z,
                                       const SensorNoise& noise, double h, Landmark* landmark,
                                       double* log_likelihood);

// A new landmark (square-root reading) from z seen at `pose`. REQUIRES: as InitLandmark.
Landmark CentralDifferenceInitLandmark(const VehiclePose& pose, const RangeBearing& z,
                                       const SensorNoise& noise, double h);

// A draw mu + factor n (heading wrapped). InvalidArgument for non-finite inputs.
Status SamplePoseFromFactor(const Eigen::Vector3d& mu, const Eigen::Matrix3d& factor,
                            const Eigen::Vector3d& standard_normals, VehiclePose* out);

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_SIGMA_POINT_FILTERS_H_

// MoveSampled: FastSLAM 1.0's prediction of many particles at once, each with its own noisy
// control, with particles in SIMD lanes (Google Highway, dispatched at run time like
// DrawNormals). MoveLinearized: FastSLAM 2.0's, the same step with the control itself and each
// particle's pose covariance carried through it.
//
// Per particle, from its pose (x, y, phi), its heading's unit vector (cos phi, sin phi) and its
// standard normals n: V = v + sigma_v n, G = g + sigma_g n (each term drawn only when its sigma
// is above 0, the speed's first), then one Euler step of the vehicle (vehicle_model.h), with
// sin G and cos G from SinCosVector (concurrency/sin_cos-inl.h) and the heading's terms from
// the unit vector:
//   Bailey: cos(G + phi) = cos G cos phi - sin G sin phi (and sin(G + phi) alike); the heading
//     turns by V dt sin G / B. No sine or cosine of G + phi is taken.
//   Guivant-Nebot: tan G = sin G / cos G.
// The new heading is wrapped to (-pi, pi] (one add of 2 pi, exact, as WrapAngle() gives it;
// WrapAngle() itself for a turn beyond that) and the unit vector becomes SinCos of it. So a
// particle's unit vector is always SinCosReference of its heading after its first step, and a
// step's result depends only on the particle's own values: the same bits in any lane, in any
// batch, on any Highway target (every operation rounds: the source is compiled with
// -ffp-contract=off), and for one particle replayed alone (FilterSteps::PredictPose()).
//
// MoveLinearized adds Sigma <- Gv Sigma Gv^T + Gu Q Gu^T with Q = diag(q_speed, q_steer) and
// the Jacobians of the step with respect to the pose (Gv: the identity but for its heading
// column) and the control (Gu), as VehicleJacobians() gives them, from the same sines and
// cosines as the step; the covariance's upper triangle in six terms, lane by lane.
//
// Thread safety: a pure function of its arguments on the particles it is given.
#ifndef GROVE_ENGINE_FASTSLAM_SAMPLED_MOTION_H_
#define GROVE_ENGINE_FASTSLAM_SAMPLED_MOTION_H_

#include <cstddef>
#include <cstdint>

#include "engine/fastslam/landmark_math.h"
#include "engine/fastslam/vehicle_model.h"

namespace grove::fastslam {

// The heading's unit vector (cos, sin).
struct HeadingUnit {
  double c, s;
};

// A particle's pose covariance, its upper triangle, or for the central-difference filters the
// lower Cholesky factor [xx 0 0; xy yy 0; xh yh hh].
struct PoseCovariance {
  double xx = 0, xy = 0, xh = 0, yy = 0, yh = 0, hh = 0;
};

// A control step as MoveSampled moves particles with it.
struct SampledControl {
  VehicleGeometry geometry;
  double v_mps = 0, steer_rad = 0, dt_s = 0;
  double sigma_speed_mps = 0, sigma_steer_rad = 0;

  // Standard normals a particle's step uses: one per sigma above 0.
  int normals() const { return (sigma_speed_mps > 0) + (sigma_steer_rad > 0); }
};

// Why a particle's step failed.
enum class MotionFailure : uint8_t {
  kNone,
  kSteering,   // the vehicle model cannot use the noisy steering angle (SteeringUsable())
  kNotFinite,  // the new pose is not finite
};
struct MotionResult {
  size_t first_failed;  // the first particle whose step failed, or n
  MotionFailure why;
};

// Moves particles [0, n): poses[i] and units[i] with the normals noise[k][i] (k <
// u.normals()). units_from_headings: the unit vectors are first set from the headings (a
// path segment's first step, whose stored unit vectors may come from elsewhere). A failed
// particle's values are unspecified; the others are moved.
MotionResult MoveSampled(const SampledControl& u, const double* const* noise,
                         bool units_from_headings, VehiclePose* poses, HeadingUnit* units,
                         size_t n);

// Moves particles [0, n) with the control (v_mps, steer_rad; u's sigmas are not used) as
// MoveSampled() does and, when covs is not nullptr, propagates covs[i] (covariances, not
// factors) through the step with Q = diag(q_speed, q_steer).
MotionResult MoveLinearized(const SampledControl& u, double q_speed, double q_steer,
                            bool units_from_headings, VehiclePose* poses, HeadingUnit* units,
                            PoseCovariance* covs, size_t n);

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_SAMPLED_MOTION_H_

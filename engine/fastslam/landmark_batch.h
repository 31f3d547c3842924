// The EKF landmark update and the observation likelihood of landmark_math.h for many landmarks
// at once, one per SIMD lane (Google Highway, dispatched at run time like MoveSampled): FastSLAM
// 1.0 updates the landmark an observation names in every particle of a batch together, and
// UpdateLandmark() and ObservationLogLikelihood() are these for one landmark.
//
// Per lane, with d = (lx - x, ly - y), q = |d|^2, r = sqrt(q), H = [dx/r dy/r; -dy/q dx/q] and
// R = diag(r0, r1): v = (z.range - r, z.bearing - (atan2(dy, dx) - heading)) with both angle
// differences wrapped to (-pi, pi] exactly as WrapAngle(), S = H P H^T + R, and for the update
// K = (H P)^T S^-1 from S's adjugate, the mean plus K v and P' = (I - K H) P (I - K H)^T + K R K^T
// (the Joseph form, entry by entry); log N(v; 0, S) = -v^T S^-1 v / 2 - log 2 pi - log det S / 2
// with v^T S^-1 v through S = L D L^T. atan2 and log are Atan2Vector's and LogVector's
// (concurrency/log_atan2.h) and the source is compiled with -ffp-contract=off: a lane's result
// depends on its values alone, the same in any lane, batch and Highway target.
//
// A lane fails, writing nothing, when the landmark is at the sensor, S is not positive definite
// (or det S is below the smallest normal double, 2.2e-308: R's floor kMinSigma keeps it above
// 1e-36) or a result is not finite. REQUIRES: finite poses, z and leaves, P positive
// semi-definite, r0, r1 > 0 (the callers check them).
//
// Thread safety: pure functions on the leaves they are given.
#ifndef GROVE_ENGINE_FASTSLAM_LANDMARK_BATCH_H_
#define GROVE_ENGINE_FASTSLAM_LANDMARK_BATCH_H_

#include <cstddef>

#include "engine/fastslam/landmark_math.h"

namespace grove::fastslam {

// Updates *leaves[i] (the covariance reading) by z seen from poses[i] for i < n and adds the
// update's log-likelihood to sums[i]; a lane whose leaf is nullptr has nothing to update.
// Returns the first i whose update failed (its leaf and sum unchanged), or n.
size_t UpdateLandmarkBatch(const VehiclePose* poses, Landmark* const* leaves, const RangeBearing& z,
                           double r0, double r1, double* sums, size_t n);

// The log-likelihood log N(v; 0, S) of z for the landmark *leaves[i] seen from poses[i], into
// log_likelihoods[i], and v^T S^-1 v into mahalanobis_sq[i], for i < n (no nullptr leaves).
// Returns the first i that failed (its outputs unwritten), or n.
size_t LandmarkLikelihoodBatch(const VehiclePose* poses, const Landmark* const* leaves,
                               const RangeBearing& z, double r0, double r1, double* log_likelihoods,
                               double* mahalanobis_sq, size_t n);

// As UpdateLandmarkBatch() for n landmarks seen from one pose: *leaves[i] by zs[i].
size_t UpdateLandmarkPairs(const VehiclePose& pose, Landmark* const* leaves, const RangeBearing* zs,
                           double r0, double r1, double* sums, size_t n);

// As LandmarkLikelihoodBatch() for n pairs seen from one pose: zs[i] against *leaves[i].
size_t LandmarkLikelihoodPairs(const VehiclePose& pose, const Landmark* const* leaves,
                               const RangeBearing* zs, double r0, double r1,
                               double* log_likelihoods, double* mahalanobis_sq, size_t n);

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_LANDMARK_BATCH_H_

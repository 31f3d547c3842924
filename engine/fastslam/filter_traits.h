// FilterTraits: what each filter of FastSlamFilter is made of (the seed's family).
//
// Each filter is a choice of pose step (motion sampling, EKF, unscented, central difference),
// landmark step (EKF, unscented, central difference), weight (the scan's predictive likelihood,
// or for the sigma-point particle filter the importance ratio at a pose drawn in Advance) and an
// optional population step (differential evolution, run by Population() after Complete()). The
// pose covariance holds a covariance (EKF, unscented) or a lower Cholesky factor (central
// difference), and so do the landmark leaves; the sigma-point pose steps restart their
// covariance at a fixed value after every scan's draw, so that a path segment's predictions,
// which depend on it, replay from the segment's start (kPoseRestartVariance).
#ifndef GROVE_ENGINE_FASTSLAM_FILTER_TRAITS_H_
#define GROVE_ENGINE_FASTSLAM_FILTER_TRAITS_H_

#include "grove/fastslam.h"

namespace grove::fastslam {

// How a filter of FastSlamFilter moves, weights and maps (fastslam.h; engine/fastslam/README.md,
// "The filters").
struct FilterTraits {
  enum class Pose { kSampledMotion, kEkf, kUnscented, kCentralDifference };
  enum class Map { kEkf, kUnscented, kCentralDifference };
  Pose pose = Pose::kEkf;
  Map map = Map::kEkf;
  // The pose is drawn after resampling (Complete()); otherwise in Advance(), before the weight.
  bool draws_after_resampling = true;
  // The weight is p(z | x) p(x | prediction) / q(x) at the drawn pose (the sigma-point particle
  // filter), not the predictive likelihood.
  bool importance_ratio = false;
  // Differential evolution after the draw (Population()).
  bool evolution = false;

  bool square_root_pose() const { return pose == Pose::kCentralDifference; }
  bool square_root_map() const { return map == Map::kCentralDifference; }
  // Whether every scan ends in a draw that restarts the pose covariance: the sigma-point pose
  // steps need it for the replay of paths (FastSLAM 2.0's mean does not depend on its
  // covariance, and it draws only at scans with observations, as Bailey's).
  bool draws_every_scan() const {
    return pose == Pose::kUnscented || pose == Pose::kCentralDifference;
  }
};

inline FilterTraits TraitsOf(FastSlamFilter f) {
  using P = FilterTraits::Pose;
  using M = FilterTraits::Map;
  switch (f) {
    case FastSlamFilter::kFastSlam1:
      return {P::kSampledMotion, M::kEkf, false, false, false};
    case FastSlamFilter::kFastSlam2:
      return {P::kEkf, M::kEkf, true, false, false};
    case FastSlamFilter::kUnscented:
      return {P::kUnscented, M::kUnscented, true, false, false};
    case FastSlamFilter::kSrcd:
      return {P::kCentralDifference, M::kCentralDifference, true, false, false};
    case FastSlamFilter::kSrcdAided:
      return {P::kEkf, M::kCentralDifference, true, false, false};
    case FastSlamFilter::kSrcdParticle:
      return {P::kCentralDifference, M::kEkf, false, true, false};
    case FastSlamFilter::kDeSrcd:
      return {P::kCentralDifference, M::kCentralDifference, true, false, true};
  }
  return {};
}

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_FILTER_TRAITS_H_

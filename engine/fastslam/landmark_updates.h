// LandmarkUpdates: the EKF landmark updates of a batch of particles by one scan under known
// association, observation by observation across the particles (UpdateLandmarkBatch), instead
// of particle by particle.
//
// First, particle by particle, the trie path to each observed landmark: a new landmark is
// initialised from the particle's pose there, an existing one's leaf is noted (a path copied
// once is the particle's own, so its later updates in the scan are in place and the leaves noted
// stay where they are). Then, observation by observation, every noted leaf is updated in SIMD
// lanes and its log-likelihood added to its particle's sum, in observation order as before. A
// particle one of whose leaves fails the quick test of UpdateLandmarkBatch's requirements
// (finite, positive definite by its leading minors) takes UpdateLandmark() instead, with its
// checks. The error reported is that of the lowest failing particle and, within it, the first
// failing observation, as a particle-by-particle loop would stop at.
//
// Thread safety: distinct batches may run on distinct worker slots at once.
#ifndef GROVE_ENGINE_FASTSLAM_LANDMARK_UPDATES_H_
#define GROVE_ENGINE_FASTSLAM_LANDMARK_UPDATES_H_

#include <algorithm>
#include <cstdint>
#include <vector>

#include "alloc/cache_line.h"
#include "engine/fastslam/filter_steps.h"
#include "engine/fastslam/landmark_batch.h"
#include "engine/fastslam/landmark_math.h"
#include "grove/status.h"

namespace grove::fastslam {

template <typename Trie>
class LandmarkUpdates {
 public:
  using Node = typename Trie::Node;

  explicit LandmarkUpdates(int slots) : scratch_(static_cast<size_t>(slots)) {}

  // Updates the maps roots[0, n) (keyed by landmark id) of the filter's particles first, first +
  // 1, ... at poses[0, n) by `scan`, from worker slot `slot`; with log_w, adds each particle's sum
  // of log-likelihoods to log_w[k]. REQUIRES: steps' map step is the EKF's; finite poses.
  Status Apply(const FilterSteps& steps, Trie* trie, Node** roots, const VehiclePose* poses,
               uint64_t first, const ScanStep& scan, size_t n, int slot, double* log_w) {
    Scratch& sc = scratch_[static_cast<size_t>(slot)];
    const size_t m = scan.observations.size();
    sc.leaves.assign(m * n, nullptr);
    sc.sums.assign(n, 0.0);
    sc.checked.clear();
    Failure failure;
    const size_t ready = FindLeaves(steps, trie, roots, poses, first, scan, n, slot, &sc, &failure);
    const SensorNoise& noise = steps.noise();
    const double sr = std::max(noise.sigma_range_m, kMinSigma);
    const double sb = std::max(noise.sigma_bearing_rad, kMinSigma);
    for (size_t j = 0; j < m; ++j) {
      const LandmarkObservation& z = scan.observations[j];
      const size_t k = UpdateLandmarkBatch(poses, sc.leaves.data() + j * n,
                                           RangeBearing{z.range_m, z.bearing_rad}, sr * sr, sb * sb,
                                           sc.sums.data(), ready);
      if (k < ready) failure.Note(k, j, Status(), sc.leaves[j * n + k]);
    }
    for (const Checked& c : sc.checked) {
      const LandmarkObservation& z = scan.observations[c.observation];
      double ll = 0;
      Status s =
          steps.UpdateLeaf(poses[c.particle], RangeBearing{z.range_m, z.bearing_rad}, c.leaf, &ll);
      if (s.ok()) {
        sc.sums[c.particle] += ll;
      } else {
        failure.Note(c.particle, c.observation, ParticleError(first + c.particle, z, s), c.leaf);
      }
    }
    if (failure.particle < n) {
      return failure.status.ok() ? WhyFailed(steps, poses, first, scan, failure) : failure.status;
    }
    if (log_w != nullptr) {
      for (size_t k = 0; k < n; ++k) log_w[k] += sc.sums[k];
    }
    return Status::Ok();
  }

 private:
  // The lowest failing particle and, within it, observation; an ok status: the batch kernel's
  // failure, to be described.
  struct Failure {
    size_t particle = SIZE_MAX;
    size_t observation = SIZE_MAX;
    Status status;
    const Landmark* leaf = nullptr;
    void Note(size_t k, size_t j, Status s, const Landmark* l) {
      if (k < particle || (k == particle && j < observation)) {
        particle = k;
        observation = j;
        status = std::move(s);
        leaf = l;
      }
    }
  };
  // A leaf updated by UpdateLandmark() rather than in the batch.
  struct Checked {
    size_t particle, observation;
    Landmark* leaf;
  };
  struct alignas(kFalseSharingBytes) Scratch {
    std::vector<Landmark*> leaves;  // observation-major: leaves[j * n + k]; nullptr: none
    std::vector<double> sums;
    std::vector<Checked> checked;  // by particle, then observation
  };

  // UpdateLandmarkBatch's requirements on a leaf, quickly.
  static bool BatchUsable(const Landmark& l) {
    return (l.x_m * 0 + l.y_m * 0) + (l.xx * 0 + l.xy * 0 + l.yy * 0) == 0 && l.xx > 0 &&
           l.xx * l.yy - l.xy * l.xy > 0;
  }

  // The paths of every particle to the landmarks of the scan; returns the particles whose
  // paths are all made (all but from the first that ran out of memory or made a non-finite new
  // landmark on).
  static size_t FindLeaves(const FilterSteps& steps, Trie* trie, Node** roots,
                           const VehiclePose* poses, uint64_t first, const ScanStep& scan, size_t n,
                           int slot, Scratch* sc, Failure* failure) {
    const size_t m = scan.observations.size();
    for (size_t k = 0; k < n; ++k) {
      bool checked = false;
      for (size_t j = 0; j < m; ++j) {
        const LandmarkObservation& z = scan.observations[j];
        Landmark* leaf = nullptr;
        Status made;
        const bool ok = trie->Update(
            &roots[k], static_cast<uint64_t>(z.id), slot, [&](Landmark& l, bool existed) {
              if (existed) {
                leaf = &l;
              } else {
                made = steps.NewLeaf(poses[k], RangeBearing{z.range_m, z.bearing_rad}, &l);
              }
            });
        if (!ok) {
          failure->Note(k, 0, NoMemoryError(first + k, "map"), nullptr);
          return k;
        }
        if (!made.ok()) {
          failure->Note(k, j, ParticleError(first + k, z, made), nullptr);
          return k;
        }
        if (leaf == nullptr) continue;
        if (!checked && !BatchUsable(*leaf)) {
          // The whole particle takes the checked path, its updates in order.
          checked = true;
          for (size_t i = 0; i < j; ++i) {
            Landmark*& earlier = sc->leaves[i * n + k];
            if (earlier != nullptr) sc->checked.push_back({k, i, earlier});
            earlier = nullptr;
          }
        }
        if (checked) {
          sc->checked.push_back({k, j, leaf});
        } else {
          sc->leaves[j * n + k] = leaf;
        }
      }
    }
    return n;
  }

  // The error of the batch's failing update, from UpdateLandmark() on a copy of its leaf (left
  // unchanged by the batch).
  static Status WhyFailed(const FilterSteps& steps, const VehiclePose* poses, uint64_t first,
                          const ScanStep& scan, const Failure& f) {
    const LandmarkObservation& z = scan.observations[f.observation];
    Landmark copy = *f.leaf;
    double unused = 0;
    Status s =
        steps.UpdateLeaf(poses[f.particle], RangeBearing{z.range_m, z.bearing_rad}, &copy, &unused);
    if (s.ok()) s = FailedPreconditionError("the landmark update is not finite");
    return ParticleError(first + f.particle, z, s);
  }

  std::vector<Scratch> scratch_;  // per worker slot
};

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_LANDMARK_UPDATES_H_

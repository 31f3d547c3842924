// ParticlePoses: the pose part of FastSlamModel's particles, as structure of arrays: each
// particle's pose, its heading's unit vector, its pose covariance (PoseCovariance: a covariance
// or a factor, as the filter stores it) and, for the filters that draw after resampling, the
// current scan's proposal from Advance() to Complete(). With their gather after resampling and
// their bytes in checkpoints and between ranks, each value read checked.
#ifndef GROVE_ENGINE_FASTSLAM_PARTICLE_POSES_H_
#define GROVE_ENGINE_FASTSLAM_PARTICLE_POSES_H_

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/fastslam/filter_steps.h"
#include "engine/fastslam/landmark_math.h"
#include "engine/fastslam/sampled_motion.h"
#include "engine/filter/generation.h"
#include "engine/io/checkpoint_io.h"
#include "grove/status.h"

namespace grove::fastslam {

class ParticlePoses {
 public:
  // `n` particles at `start` with the pose covariance `cov`; with `proposals`, room for each
  // one's proposal.
  ParticlePoses(size_t n, const VehiclePose& start, const PoseCovariance& cov, bool proposals)
      : proposals_(proposals) {
    pose_.assign(n, start);
    unit_.assign(n, HeadingUnit{std::cos(start.heading_rad), std::sin(start.heading_rad)});
    cov_.assign(n, cov);
    if (proposals_) {
      proposal_mu_.resize(n);
      proposal_sigma_.resize(n);
    }
  }

  VehiclePose& pose(size_t i) { return pose_[i]; }
  const VehiclePose& pose(size_t i) const { return pose_[i]; }
  HeadingUnit& unit(size_t i) { return unit_[i]; }
  const HeadingUnit& unit(size_t i) const { return unit_[i]; }
  PoseCovariance& cov(size_t i) { return cov_[i]; }
  Eigen::Vector3d& proposal_mu(size_t i) { return proposal_mu_[i]; }
  PoseCovariance& proposal_sigma(size_t i) { return proposal_sigma_[i]; }
  std::span<VehiclePose> poses() { return pose_; }

  // Calls f(Gathered<T>) on each value with its buffer for the next generation, which
  // FastSlamModel gathers in chunks (Gathered's Begin, Range and End).
  template <typename F>
  void ForEachGathered(F f) {
    f(Gathered<VehiclePose>{&pose_, &spare_.pose});
    f(Gathered<HeadingUnit>{&unit_, &spare_.unit});
    f(Gathered<PoseCovariance>{&cov_, &spare_.cov});
    if (proposals_) {
      f(Gathered<Eigen::Vector3d>{&proposal_mu_, &spare_.proposal_mu});
      f(Gathered<PoseCovariance>{&proposal_sigma_, &spare_.proposal_sigma});
    }
  }

  // The checkpoint's part: poses, covariances and heading vectors (a checkpoint is taken after
  // Complete(), when no proposal is pending).
  void Save(ByteWriter* w) const {
    w->PutBytes(pose_.data(), pose_.size() * sizeof(VehiclePose));
    w->PutBytes(cov_.data(), cov_.size() * sizeof(PoseCovariance));
    w->PutBytes(unit_.data(), unit_.size() * sizeof(HeadingUnit));
  }
  // What Save() wrote for `n` particles, read and checked by Read(); Restore() takes it.
  struct Saved {
    std::vector<VehiclePose> pose;
    std::vector<PoseCovariance> cov;
    std::vector<HeadingUnit> unit;
  };
  static Status Read(ByteReader* r, size_t n, Saved* out) {
    out->pose.resize(n);
    out->cov.resize(n);
    GROVE_RETURN_IF_ERROR(r->GetBytes("poses", out->pose.data(), n * sizeof(VehiclePose)));
    GROVE_RETURN_IF_ERROR(
        r->GetBytes("pose covariances", out->cov.data(), n * sizeof(PoseCovariance)));
    out->unit.resize(n);
    GROVE_RETURN_IF_ERROR(
        r->GetBytes("heading vectors", out->unit.data(), n * sizeof(HeadingUnit)));
    for (size_t i = 0; i < n; ++i) {
      GROVE_RETURN_IF_ERROR(CheckParticle(r, i, out->pose[i], out->unit[i], out->cov[i]));
    }
    return Status::Ok();
  }
  void Restore(Saved* saved) {
    pose_.swap(saved->pose);
    cov_.swap(saved->cov);
    unit_.swap(saved->unit);
  }

  // The fewest bytes a particle takes in a message of Export().
  static constexpr size_t kMessageBytes =
      sizeof(VehiclePose) + sizeof(HeadingUnit) + sizeof(PoseCovariance);

  // Particles `which` for another rank: their values and pending proposals.
  void Export(std::span<const uint32_t> which, ByteWriter* w) const {
    for (uint32_t i : which) w->Put(pose_[i]);
    for (uint32_t i : which) w->Put(unit_[i]);
    for (uint32_t i : which) w->Put(cov_[i]);
    if (proposals_) {
      for (uint32_t i : which) {
        for (int k = 0; k < 3; ++k) w->Put<double>(proposal_mu_[i](k));
        w->Put(proposal_sigma_[i]);
      }
    }
  }

  // Appends `count` particles' values written by Export().
  Status Import(ByteReader* r, size_t count) {
    const size_t at = pose_.size(), end = at + count;
    pose_.resize(end);
    unit_.resize(end);
    cov_.resize(end);
    GROVE_RETURN_IF_ERROR(r->GetBytes("poses", pose_.data() + at, count * sizeof(VehiclePose)));
    GROVE_RETURN_IF_ERROR(
        r->GetBytes("heading vectors", unit_.data() + at, count * sizeof(HeadingUnit)));
    GROVE_RETURN_IF_ERROR(
        r->GetBytes("pose covariances", cov_.data() + at, count * sizeof(PoseCovariance)));
    for (size_t i = at; i < end; ++i) {
      GROVE_RETURN_IF_ERROR(CheckParticle(r, i - at, pose_[i], unit_[i], cov_[i]));
    }
    if (!proposals_) return Status::Ok();
    proposal_mu_.resize(end);
    proposal_sigma_.resize(end);
    for (size_t i = at; i < end; ++i) {
      for (int k = 0; k < 3; ++k) {
        GROVE_RETURN_IF_ERROR(r->Get("proposal mean", &proposal_mu_[i](k)));
      }
      GROVE_RETURN_IF_ERROR(r->Get("proposal covariance", &proposal_sigma_[i]));
      const PoseCovariance& c = proposal_sigma_[i];
      if (!proposal_mu_[i].allFinite() || !std::isfinite(c.xx + c.xy + c.xh + c.yy + c.yh + c.hh)) {
        return r->Error("proposal", "a value is not finite");
      }
    }
    return Status::Ok();
  }

 private:
  // Checks of a particle's values read from a checkpoint or a message (`k`: its place there).
  static Status CheckParticle(ByteReader* r, size_t k, const VehiclePose& p, const HeadingUnit& u,
                              const PoseCovariance& c) {
    if (!(std::fabs(u.c * u.c + u.s * u.s - 1) < 1e-6)) {
      return r->Error("heading vectors", "not a unit vector");
    }
    if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !(std::fabs(p.heading_rad) <= 4)) {
      return r->Error("poses", "particle " + std::to_string(k) + "'s pose is not finite");
    }
    for (double v : {c.xx, c.xy, c.xh, c.yy, c.yh, c.hh}) {
      if (!std::isfinite(v)) return r->Error("pose covariances", "a value is not finite");
    }
    // Variances, or a factor's diagonal.
    if (!(c.xx >= 0 && c.yy >= 0 && c.hh >= 0)) {
      return r->Error("pose covariances", "a variance is negative");
    }
    return Status::Ok();
  }

  const bool proposals_;
  std::vector<VehiclePose> pose_;
  std::vector<HeadingUnit> unit_;
  std::vector<PoseCovariance> cov_;
  std::vector<Eigen::Vector3d> proposal_mu_;
  std::vector<PoseCovariance> proposal_sigma_;
  // The previous generation's values, kept as the next gather's buffers.
  struct {
    std::vector<VehiclePose> pose;
    std::vector<HeadingUnit> unit;
    std::vector<PoseCovariance> cov;
    std::vector<Eigen::Vector3d> proposal_mu;
    std::vector<PoseCovariance> proposal_sigma;
  } spare_;
};

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_PARTICLE_POSES_H_

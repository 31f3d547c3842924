// FastSlamModel: the landmark FastSLAM particle for ParticleFilter (grove/fastslam.h), generic
// over the degree of its landmark trees.
//
// Per particle (structure of arrays): the vehicle pose and its unit heading vector, FastSLAM
// 2.0's pose covariance, the map (a version of a PersistentTrie keyed by landmark id, leaves
// holding a landmark Gaussian) and the path history.
//
// Steps:
//   Predict(ControlStep): FastSLAM 1.0 draws the particle's own control from N(u, Q) and moves;
//     FastSLAM 2.0 moves the mean with the control and propagates the pose covariance,
//     Sigma' = Gv Sigma Gv^T + Gu Q Gu^T.
//   Advance(ScanStep): FastSLAM 1.0 adds log N(v; 0, S) of each observation of a known
//     landmark and updates it (EKF, Joseph form); FastSLAM 2.0 refines the pose mean and
//     covariance by each observation of a known landmark and adds each one's predictive
//     log-likelihood, which does not depend on the pose drawn next.
//   Complete(ScanStep), after resampling (FastSLAM 2.0): the refinement again, the draw of the
//     pose from it (its covariance then starts again at 0) and the landmark updates from the
//     drawn pose. Copies of one parent draw distinct poses (Bailey's order: resample, then
//     sample). Both filters initialise new landmarks from the pose.
//
// Unknown association (config.association != kKnown): the map is keyed by SpatialKey (a
// landmark's cell and a slot in it) instead of by id. At a scan each particle finds the
// candidates of every detection with a range query of its own trie, decides with the gates
// (data_association.h), adds the associated detections' likelihoods and p0 for the others, and
// then (FastSLAM 1.0 in Advance, 2.0 in Complete from the drawn pose) updates the associated
// landmarks, lowers the evidence of those in view and not seen (removing the ones below the
// threshold; the view is found by the same range query as the candidates, so it is judged from
// the pose the decisions were made from: for FastSLAM 2.0 the predicted mean), moves an updated
// landmark whose mean left its cell to a slot of its new cell, and adds the new landmarks.
// FastSLAM 2.0 decides from the predicted pose mean (Bailey's order); the query Advance() made is
// kept per particle and gathered with it for Complete().
//
// Paths: a particle does not store a pose per step. Its history holds one entry per path
// segment: the pose and particle index at the first prediction after the start or a scan.
// Within a segment a particle keeps its index (resampling happens only at scans), so its poses
// there are the same predictions redone from the segment's start (PredictPose() draws the same
// numbers from the counter-based streams). The pose after a segment's closing scan is the next
// entry's start pose. A path thus costs one node per scan, not one per control step, and the
// histories of copies share their common part (Ancestry).
#ifndef GROVE_ENGINE_FASTSLAM_FASTSLAM_MODEL_H_
#define GROVE_ENGINE_FASTSLAM_FASTSLAM_MODEL_H_

#include <fmt/format.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "concurrency/random_stream.h"
#include "concurrency/worker_pool.h"
#include "engine/ancestry.h"
#include "engine/checkpoint_io.h"
#include "engine/fastslam/data_association.h"
#include "engine/fastslam/landmark_math.h"
#include "engine/fastslam/vehicle_model.h"
#include "engine/generation.h"
#include "engine/memory_use.h"
#include "engine/persistent_trie.h"
#include "engine/version_set.h"
#include "grove/fastslam.h"

namespace grove::fastslam {

// A control held over dt_s.
struct ControlStep {
  double v_mps = 0;
  double steer_rad = 0;
  double dt_s = 0;
};

// One scan's observations (validated by the facade).
struct ScanStep {
  std::span<const LandmarkObservation> observations;
};

// The start of a path segment: the pose before the segment's first prediction and the
// particle's index during the segment.
struct SegmentStart {
  double x_m, y_m, heading_rad;
  uint32_t index;
  uint32_t unused;
};
using SegmentHistory = Ancestry<SegmentStart>;

inline bool ValidSegmentStart(const SegmentStart& s) {
  return std::isfinite(s.x_m) && std::isfinite(s.y_m) && std::isfinite(s.heading_rad) &&
         std::fabs(s.heading_rad) <= 4 && s.unused == 0;
}

// FastSLAM 2.0's pose covariance, its upper triangle.
struct PoseCovariance {
  double xx = 0, xy = 0, xh = 0, yy = 0, yh = 0, hh = 0;
};

template <int kLog2Degree>
class FastSlamModel {
 public:
  using Trie = PersistentTrie<Landmark, kLog2Degree>;

  // REQUIRES: config.Validate() is ok.
  FastSlamModel(const FastSlamConfig& config, int slots)
      : config_(config),
        geometry_(VehicleGeometry::Of(config)),
        noise_{config.sigma_range_m, config.sigma_bearing_rad},
        n_(static_cast<size_t>(config.particles)),
        trie_(1, slots),
        history_(slots),
        maps_(&trie_, n_),
        paths_(&history_, n_),
        ml_(config.association != FastSlamAssociation::kKnown),
        params_{FastSlamGateDistance2(config.reject_gate, config.gate_unit),
                FastSlamGateDistance2(config.augment_gate, config.gate_unit),
                config.association == FastSlamAssociation::kExclusive, config.index_cell_m, noise_},
        log_p0_(NewLandmarkLogLikelihood(noise_, params_.augment_gate)),
        counts_(ml_ ? n_ : 0),
        pending_(ml_ && config.filter == FastSlamFilter::kFastSlam2 ? n_ : 0),
        scratch_(slots) {
    const VehiclePose start{config.start_x_m, config.start_y_m,
                            WrapAngle(config.start_heading_rad)};
    pose_.assign(n_, start);
    unit_.assign(n_, Unit{std::cos(start.heading_rad), std::sin(start.heading_rad)});
    cov_.assign(n_, PoseCovariance{});
    if (config.filter == FastSlamFilter::kFastSlam2) {
      proposal_mu_.resize(n_);
      proposal_sigma_.resize(n_);
    }
    q_ << config.sigma_speed_mps * config.sigma_speed_mps, 0, 0,
        config.sigma_steer_rad * config.sigma_steer_rad;
  }

  size_t size() const { return n_; }

  // Before each scan's update: the longest range so far bounds the landmarks' covariances
  // (SearchRadius()).
  void NoteScan(const ScanStep& scan) {
    for (const LandmarkObservation& z : scan.observations)
      max_range_ = std::max(max_range_, z.range_m);
  }
  bool unknown_association() const { return ml_; }
  // Unknown association: stores `l` in particle i's map as a new landmark would be (benchmarks
  // build big maps with it). REQUIRES: ml_, and l's covariance within the bound SearchRadius()
  // assumes for the ranges NoteScan() has seen.
  Status InsertLandmark(size_t i, const Landmark& l, int slot) { return Insert(i, slot, l); }
  const AssociationCounts& counts(size_t i) const { return counts_[i]; }

  // The next Predict() is the first of a path segment (after the start or a scan).
  void set_segment_start(bool v) { segment_start_ = v; }

  // The pose particle `index` reaches from `p` by the prediction of filter step `step`: the
  // one computation of a prediction, for Predict() and for the replay of paths.
  VehiclePose PredictPose(const VehiclePose& p, const ControlStep& c, uint64_t step, uint32_t index,
                          bool* usable) const {
    if (config_.filter == FastSlamFilter::kFastSlam2) {
      *usable = SteeringUsable(geometry_, c.steer_rad);
      if (!*usable) return p;
      return MoveVehicle(geometry_, ControlTermsOf(geometry_, c.v_mps, c.steer_rad, c.dt_s), p);
    }
    ControlTerms u;
    *usable = NoisyTerms(c, step, index, &u);
    if (!*usable) return p;
    return MoveVehicle(geometry_, u, p);
  }

  Status Predict(const ControlStep& c, uint64_t step, size_t begin, size_t end, int slot) {
    const bool fs2 = config_.filter == FastSlamFilter::kFastSlam2;
    // FastSLAM 2.0 moves every particle with the same control: its terms once per batch.
    ControlTerms shared;
    Unit turn{1, 0};
    if (fs2) {
      if (!SteeringUsable(geometry_, c.steer_rad)) return BadSteering(begin);
      shared = ControlTermsOf(geometry_, c.v_mps, c.steer_rad, c.dt_s);
      turn = Unit{std::cos(shared.turn_rad), std::sin(shared.turn_rad)};
    }
    for (size_t i = begin; i < end; ++i) {
      const VehiclePose p = pose_[i];
      if (segment_start_) {
        SegmentStart s{p.x_m, p.y_m, p.heading_rad, static_cast<uint32_t>(i), 0};
        SegmentHistory::Node* node =
            history_.Append(paths_[i], static_cast<uint32_t>(step), s, slot);
        if (node == nullptr) return NoMemory(i, "path");
        paths_[i] = node;
      }
      ControlTerms own;
      if (!fs2 && !NoisyTerms(c, step, static_cast<uint32_t>(i), &own)) return BadSteering(i);
      const ControlTerms& u = fs2 ? shared : own;
      StepTrig trig;
      const VehiclePose next = MoveVehicle(geometry_, u, p, &trig);
      if (!std::isfinite(next.x_m) || !std::isfinite(next.y_m) ||
          !std::isfinite(next.heading_rad)) {
        return FailedPreconditionError(fmt::format("particle {}'s pose ({}, {}, {}) is not finite",
                                                   i, next.x_m, next.y_m, next.heading_rad));
      }
      if (fs2) {
        Eigen::Matrix3d gv;
        Eigen::Matrix<double, 3, 2> gu;
        VehicleJacobians(geometry_, u, trig, &gv, &gu);
        PropagateCovariance(gv, gu, &cov_[i]);
      }
      pose_[i] = next;
      if (fs2) {
        // The heading turns by the same angle for every particle: rotate its unit vector (only
        // the mean pose reads it) instead of a sine and cosine per particle.
        const Unit& h = unit_[i];
        unit_[i] = Unit{h.c * turn.c - h.s * turn.s, h.s * turn.c + h.c * turn.s};
      } else {
        unit_[i] = Unit{std::cos(next.heading_rad), std::sin(next.heading_rad)};
      }
    }
    return Status::Ok();
  }

  // FastSLAM 1.0: the whole update. FastSLAM 2.0: the weight only (the predictive likelihood
  // of the observations of known landmarks); Complete() draws and updates after resampling.
  Status Advance(const ScanStep& scan, uint64_t step, size_t begin, size_t end, int slot,
                 double* log_w) {
    if (ml_) return AdvanceUnknown(scan, begin, end, slot, log_w);
    if (scan.observations.empty()) return Status::Ok();
    for (size_t i = begin; i < end; ++i) {
      double lw = 0;
      if (config_.filter == FastSlamFilter::kFastSlam2) {
        Eigen::Matrix3d sigma;
        GROVE_RETURN_IF_ERROR(Proposal(scan, i, &proposal_mu_[i], &sigma, &lw));
        proposal_sigma_[i] = Upper(sigma);
      } else {
        GROVE_RETURN_IF_ERROR(UpdateLandmarks(scan, i, slot, &lw));
      }
      log_w[i] += lw;
    }
    return Status::Ok();
  }

  // FastSLAM 2.0, after resampling: the draw from the proposal Advance() computed (a copy has
  // its parent's), keyed by the particle's new index, then the landmark updates from the drawn
  // pose. Nothing for FastSLAM 1.0.
  Status Complete(const ScanStep& scan, uint64_t step, size_t begin, size_t end, int slot) {
    if (scan.observations.empty() || config_.filter != FastSlamFilter::kFastSlam2) {
      return Status::Ok();
    }
    for (size_t i = begin; i < end; ++i) {
      // The proposal Advance() computed, gathered with the particle.
      const Eigen::Vector3d& mu = proposal_mu_[i];
      const Eigen::Matrix3d sigma = Full(proposal_sigma_[i]);
      RandomStream rs(config_.seed, step + 1, static_cast<uint32_t>(i), StreamPurpose::kProposal);
      const Eigen::Vector3d normals(rs.NextNormal(), rs.NextNormal(), rs.NextNormal());
      VehiclePose drawn;
      Status s = SamplePose(mu, sigma, normals, &drawn);
      if (!s.ok()) {
        return FailedPreconditionError(fmt::format("particle {}'s proposal: {}", i, s.message()));
      }
      pose_[i] = drawn;
      unit_[i] = Unit{std::cos(drawn.heading_rad), std::sin(drawn.heading_rad)};
      cov_[i] = PoseCovariance{};
      if (ml_) {
        // The matches Advance() found from the predicted mean (a copy has its parent's).
        Scratch& sc = scratch_[slot];
        sc.query = pending_[i];
        Decide(sc.query.matches, scan.observations.size(), params_, &sc.decisions);
        GROVE_RETURN_IF_ERROR(ApplyScan(scan, i, slot, &sc));
        continue;
      }
      double unused = 0;
      GROVE_RETURN_IF_ERROR(UpdateLandmarks(scan, i, slot, &unused));
    }
    return Status::Ok();
  }

  void Gather(std::span<const uint32_t> parents, WorkerPool& workers) {
    GatherValues(parents, workers, &pose_);
    GatherValues(parents, workers, &unit_);
    GatherValues(parents, workers, &cov_);
    if (config_.filter == FastSlamFilter::kFastSlam2) {
      GatherValues(parents, workers, &proposal_mu_);
      GatherValues(parents, workers, &proposal_sigma_);
    }
    if (ml_) GatherValues(parents, workers, &counts_);
    if (!pending_.empty()) GatherValues(parents, workers, &pending_);
    maps_.Gather(parents, workers);
    paths_.Gather(parents, workers);
  }

  void ReleaseDead(WorkerPool& workers) {
    maps_.ReleaseDead(workers);
    paths_.ReleaseDead(workers);
  }

  Status CheckCounts() const {
    GROVE_RETURN_IF_ERROR(trie_.CheckCounts(maps_.AllReferences()));
    return history_.CheckCounts(paths_.AllReferences());
  }

  double x(size_t i) const { return pose_[i].x_m; }
  double y(size_t i) const { return pose_[i].y_m; }
  // The heading's unit vector: cos and sin of heading(i) to round-off (FastSLAM 2.0 turns it
  // by rotation between scans).
  double cos_heading(size_t i) const { return unit_[i].c; }
  double sin_heading(size_t i) const { return unit_[i].s; }
  const VehiclePose& pose(size_t i) const { return pose_[i]; }
  const typename Trie::Node* map(size_t i) const { return maps_[i]; }
  const SegmentHistory::Node* path(size_t i) const { return paths_[i]; }
  const Trie& trie() const { return trie_; }

  MemoryUse map_memory() const {
    MemoryUse m;
    AddPoolStats(trie_.inner_stats(), &m);
    AddPoolStats(trie_.bottom_stats(), &m);
    return m;
  }
  MemoryUse path_memory() const {
    MemoryUse m;
    AddPoolStats(history_.stats(), &m);
    return m;
  }

  // The particles' state after a step: poses, covariances, the segment flag, maps and paths.
  void Save(ByteWriter* w) const {
    w->Put<uint64_t>(n_);
    w->PutBytes(pose_.data(), n_ * sizeof(VehiclePose));
    w->PutBytes(cov_.data(), n_ * sizeof(PoseCovariance));
    w->PutBytes(unit_.data(), n_ * sizeof(Unit));
    w->Put<uint8_t>(segment_start_ ? 1 : 0);
    w->Put<double>(max_range_);
    w->PutBytes(counts_.data(), counts_.size() * sizeof(AssociationCounts));
    trie_.Save(maps_.roots(), w);
    SegmentHistory::Save(paths_.roots(), w);
  }

  // Replaces the state of a new model with a saved one taken after step `steps`.
  Status Load(ByteReader* r, uint64_t steps) {
    GROVE_RETURN_IF_ERROR(ReadParticleCount(r, n_));
    std::vector<VehiclePose> pose(n_);
    std::vector<PoseCovariance> cov(n_);
    GROVE_RETURN_IF_ERROR(r->GetBytes("poses", pose.data(), n_ * sizeof(VehiclePose)));
    GROVE_RETURN_IF_ERROR(r->GetBytes("pose covariances", cov.data(), n_ * sizeof(PoseCovariance)));
    std::vector<Unit> unit(n_);
    GROVE_RETURN_IF_ERROR(r->GetBytes("heading vectors", unit.data(), n_ * sizeof(Unit)));
    for (const Unit& u : unit) {
      if (!(std::fabs(u.c * u.c + u.s * u.s - 1) < 1e-6)) {
        return r->Error("heading vectors", "not a unit vector");
      }
    }
    for (size_t i = 0; i < n_; ++i) {
      if (!std::isfinite(pose[i].x_m) || !std::isfinite(pose[i].y_m) ||
          !(std::fabs(pose[i].heading_rad) <= 4)) {
        return r->Error("poses", "particle " + std::to_string(i) + "'s pose is not finite");
      }
      const PoseCovariance& c = cov[i];
      for (double v : {c.xx, c.xy, c.xh, c.yy, c.yh, c.hh}) {
        if (!std::isfinite(v)) return r->Error("pose covariances", "a value is not finite");
      }
      if (!(c.xx >= 0 && c.yy >= 0 && c.hh >= 0)) {
        return r->Error("pose covariances", "a variance is negative");
      }
    }
    uint8_t segment = 0;
    GROVE_RETURN_IF_ERROR(r->Get("segment flag", &segment));
    if (segment > 1) return r->Error("segment flag", "not 0 or 1");
    double max_range = 0;
    GROVE_RETURN_IF_ERROR(r->Get("longest range", &max_range));
    if (!(max_range >= 0) || !std::isfinite(max_range)) {
      return r->Error("longest range", "negative or not finite");
    }
    std::vector<AssociationCounts> counts(counts_.size());
    GROVE_RETURN_IF_ERROR(r->GetBytes("association counts", counts.data(),
                                      counts.size() * sizeof(AssociationCounts)));
    for (const AssociationCounts& c : counts) {
      for (int64_t v :
           {c.associated, c.created, c.ignored, c.removed, c.dropped, c.tagged, c.wrong}) {
        if (v < 0) return r->Error("association counts", "a count is negative");
      }
    }
    std::vector<typename Trie::Node*> roots;
    GROVE_RETURN_IF_ERROR(trie_.Load(r, n_, 0, &ValidLandmark, &roots));
    if (steps >= UINT32_MAX) {
      for (auto* root : roots) trie_.Release(root, 0);
      return r->Error("step", "too many steps");
    }
    std::vector<SegmentHistory::Node*> heads;
    Status s = history_.Load(r, n_, static_cast<uint32_t>(steps), 0, &ValidSegmentStart, &heads);
    if (s.ok() && steps > 0) {
      for (size_t i = 0; i < n_ && s.ok(); ++i) {
        if (heads[i] == nullptr || heads[i]->value.index >= n_) {
          s = r->Error("path", "particle " + std::to_string(i) + " has no path or a bad index");
        }
      }
      if (!s.ok()) {
        for (auto* h : heads) history_.Release(h, 0);
      }
    }
    if (!s.ok()) {
      for (auto* root : roots) trie_.Release(root, 0);
      return s;
    }
    pose_.swap(pose);
    cov_.swap(cov);
    unit_.swap(unit);
    segment_start_ = segment == 1;
    max_range_ = max_range;
    counts_.swap(counts);
    maps_.Replace(std::move(roots));
    paths_.Replace(std::move(heads));
    return Status::Ok();
  }

 private:
  struct Unit {
    double c, s;
  };

  static bool ValidLandmark(const Landmark& l) {
    return std::isfinite(l.x_m) && std::isfinite(l.y_m) && std::isfinite(l.xx) &&
           std::isfinite(l.xy) && std::isfinite(l.yy) && l.xx >= 0 && l.yy >= 0 && l.tag >= -1;
  }

  static Eigen::Matrix3d Full(const PoseCovariance& c) {
    return (Eigen::Matrix3d() << c.xx, c.xy, c.xh, c.xy, c.yy, c.yh, c.xh, c.yh, c.hh).finished();
  }
  static PoseCovariance Upper(const Eigen::Matrix3d& m) {
    return PoseCovariance{m(0, 0), 0.5 * (m(0, 1) + m(1, 0)), 0.5 * (m(0, 2) + m(2, 0)),
                          m(1, 1), 0.5 * (m(1, 2) + m(2, 1)), m(2, 2)};
  }
  Eigen::Matrix3d Covariance(size_t i) const { return Full(cov_[i]); }
  void SetCovariance(size_t i, const Eigen::Matrix3d& m) { cov_[i] = Upper(m); }

  // Sigma <- Gv Sigma Gv^T + Gu Q Gu^T on the upper triangle, for the Jacobians' shape: Gv is
  // the identity but for its heading column (gv(0,2), gv(1,2)) and Q is diagonal. Writing
  // Gv = I + a e_h^T with a = (gv(0,2), gv(1,2), 0) and c = Sigma e_h, the first term is
  // Sigma + a c^T + c a^T + Sigma_hh a a^T; the second is q_v g_v g_v^T + q_g g_g g_g^T.
  void PropagateCovariance(const Eigen::Matrix3d& gv, const Eigen::Matrix<double, 3, 2>& gu,
                           PoseCovariance* p) const {
    const double ax = gv(0, 2), ay = gv(1, 2);
    const double cx = p->xh, cy = p->yh, ch = p->hh;
    const double qv = q_(0, 0), qg = q_(1, 1);
    const double v0 = gu(0, 0), v1 = gu(1, 0), v2 = gu(2, 0);
    const double g0 = gu(0, 1), g1 = gu(1, 1), g2 = gu(2, 1);
    PoseCovariance out;
    out.xx = p->xx + 2 * ax * cx + ch * ax * ax + qv * v0 * v0 + qg * g0 * g0;
    out.xy = p->xy + ax * cy + cx * ay + ch * ax * ay + qv * v0 * v1 + qg * g0 * g1;
    out.xh = p->xh + ax * ch + qv * v0 * v2 + qg * g0 * g2;
    out.yy = p->yy + 2 * ay * cy + ch * ay * ay + qv * v1 * v1 + qg * g1 * g1;
    out.yh = p->yh + ay * ch + qv * v1 * v2 + qg * g1 * g2;
    out.hh = p->hh + qv * v2 * v2 + qg * g2 * g2;
    *p = out;
  }

  // FastSLAM 1.0: particle `index`'s own control for step `step`, drawn from N(u, Q); false
  // when the vehicle model cannot use the drawn steering angle.
  bool NoisyTerms(const ControlStep& c, uint64_t step, uint32_t index, ControlTerms* u) const {
    double v = c.v_mps, g = c.steer_rad;
    RandomStream rs(config_.seed, step + 1, index, StreamPurpose::kMotion);
    if (config_.sigma_speed_mps > 0) v += config_.sigma_speed_mps * rs.NextNormal();
    if (config_.sigma_steer_rad > 0) g += config_.sigma_steer_rad * rs.NextNormal();
    if (!SteeringUsable(geometry_, g)) return false;
    *u = ControlTermsOf(geometry_, v, g, c.dt_s);
    return true;
  }

  Status BadSteering(size_t i) const {
    return FailedPreconditionError(fmt::format(
        "particle {}'s steering angle is outside what the {} model can use (|G| < pi/2 and "
        "1 - tan(G) H / L > 0)",
        i, FastSlamVehicleName(config_.vehicle)));
  }

  // FastSLAM 2.0's proposal for particle i: its predicted pose refined by each observation of a
  // known landmark in turn; *log_w gets the sum of their predictive log-likelihoods.
  Status Proposal(const ScanStep& scan, size_t i, Eigen::Vector3d* mu, Eigen::Matrix3d* sigma,
                  double* log_w) const {
    *mu = ToVector(pose_[i]);
    *sigma = Covariance(i);
    for (const LandmarkObservation& z : scan.observations) {
      const Landmark* l = trie_.Find(maps_[i], static_cast<uint64_t>(z.id));
      if (l == nullptr) continue;
      double w = 0;
      Status s = ProposalStep(mu, sigma, *l, RangeBearing{z.range_m, z.bearing_rad}, noise_, &w);
      if (!s.ok()) return ParticleError(i, z, s);
      *log_w += w;
    }
    return Status::Ok();
  }

  // The EKF update of each observed landmark from particle i's pose (new ones initialised);
  // *log_w gets the sum of the known ones' log-likelihoods.
  Status UpdateLandmarks(const ScanStep& scan, size_t i, int slot, double* log_w) {
    const VehiclePose pose = pose_[i];
    for (const LandmarkObservation& z : scan.observations) {
      const RangeBearing rb{z.range_m, z.bearing_rad};
      Status s;
      double ll = 0;
      const bool ok = trie_.Update(&maps_[i], static_cast<uint64_t>(z.id), slot,
                                   [&](Landmark& l, bool existed) {
                                     if (!existed) {
                                       l = InitLandmark(pose, rb, noise_);
                                     } else {
                                       s = UpdateLandmark(pose, rb, noise_, &l, &ll);
                                     }
                                   });
      if (!ok) return NoMemory(i, "map");
      if (!s.ok()) return ParticleError(i, z, s);
      *log_w += ll;
    }
    return Status::Ok();
  }

  // ---- Unknown association ----

  // What one range query found for a particle's scan: the pairs within an augment gate and,
  // with the evidence on, the landmarks in view.
  struct ScanQuery {
    std::vector<Match> matches;
    std::vector<uint64_t> in_view;  // increasing
  };
  struct alignas(kFalseSharingBytes) Scratch {
    ScanQuery query;
    std::vector<Decision> decisions;
    std::vector<uint64_t> keys;
  };

  // The query and decisions of particle i's scan seen from `pose`, into sc.
  Status DecideScan(const ScanStep& scan, size_t i, const VehiclePose& pose, Scratch* sc) const {
    sc->query.matches.clear();
    sc->query.in_view.clear();
    const SensorView view{config_.sensor_range_m, config_.sensor_fov_rad};
    const bool evidence = config_.evidence == FastSlamEvidence::kOn;
    Status s = FindMatches(trie_, maps_[i], pose, scan.observations, params_, max_range_,
                           /*use_index=*/true, &sc->query.matches, evidence ? &view : nullptr,
                           &sc->query.in_view);
    if (!s.ok()) return Status(s.code(), fmt::format("particle {}, {}", i, s.message()));
    Decide(sc->query.matches, scan.observations.size(), params_, &sc->decisions);
    return Status::Ok();
  }

  Status AdvanceUnknown(const ScanStep& scan, size_t begin, size_t end, int slot, double* log_w) {
    Scratch& sc = scratch_[slot];
    if (scan.observations.empty()) {
      // Nothing to weigh or draw; the evidence of what is in view still falls.
      if (config_.evidence == FastSlamEvidence::kOff) return Status::Ok();
      for (size_t i = begin; i < end; ++i) {
        GROVE_RETURN_IF_ERROR(DecideScan(scan, i, pose_[i], &sc));
        GROVE_RETURN_IF_ERROR(ApplyScan(scan, i, slot, &sc));
      }
      return Status::Ok();
    }
    const bool fs2 = config_.filter == FastSlamFilter::kFastSlam2;
    for (size_t i = begin; i < end; ++i) {
      GROVE_RETURN_IF_ERROR(DecideScan(scan, i, pose_[i], &sc));
      double lw = 0;
      Eigen::Vector3d mu;
      Eigen::Matrix3d sigma;
      if (fs2) {
        mu = ToVector(pose_[i]);
        sigma = Covariance(i);
      }
      for (size_t j = 0; j < sc.decisions.size(); ++j) {
        const Decision& d = sc.decisions[j];
        if (d.kind != Decision::kAssociated) {
          lw += log_p0_;
        } else if (!fs2) {
          lw += d.log_likelihood;
        } else {
          const LandmarkObservation& z = scan.observations[j];
          const Landmark* l = trie_.Find(maps_[i], d.key);
          double w = 0;
          Status s =
              ProposalStep(&mu, &sigma, *l, RangeBearing{z.range_m, z.bearing_rad}, noise_, &w);
          if (!s.ok()) return ParticleError(i, z, s);
          lw += w;
        }
      }
      if (fs2) {
        proposal_mu_[i] = mu;
        proposal_sigma_[i] = Upper(sigma);
        pending_[i] = sc.query;
      } else {
        GROVE_RETURN_IF_ERROR(ApplyScan(scan, i, slot, &sc));
      }
      log_w[i] += lw;
    }
    return Status::Ok();
  }

  // The first free slot of `cell` in particle i's map, or -1.
  int FreeSlot(size_t i, const Cell& cell) const {
    for (int k = 0; k < kSlotsPerCell; ++k) {
      if (trie_.Find(maps_[i], SpatialKey(cell, k)) == nullptr) return k;
    }
    return -1;
  }

  // Stores `l` in a free slot of the cell of its mean; counts a drop when the cell is full.
  Status Insert(size_t i, int slot, const Landmark& l) {
    Cell cell;
    if (!CellOf(l.x_m, l.y_m, params_.cell_m, &cell)) {
      return FailedPreconditionError(fmt::format(
          "particle {}: a landmark at ({}, {}) is outside the landmark index (|x|, |y| < {} m)", i,
          l.x_m, l.y_m, static_cast<double>(kMaxCell) * params_.cell_m));
    }
    const int k = FreeSlot(i, cell);
    if (k < 0) {
      ++counts_[i].dropped;
      return Status::Ok();
    }
    if (!trie_.Update(&maps_[i], SpatialKey(cell, k), slot,
                      [&](Landmark& leaf, bool) { leaf = l; })) {
      return NoMemory(i, "map");
    }
    return Status::Ok();
  }

  // Applies particle i's decisions in sc from its pose now (the view in sc is the one the
  // decisions were made from; see the file comment).
  Status ApplyScan(const ScanStep& scan, size_t i, int slot, Scratch* sc) {
    const VehiclePose pose = pose_[i];
    AssociationCounts& counts = counts_[i];
    std::vector<uint64_t>& touched = sc->keys;
    touched.clear();
    // 1. Updates of the associated landmarks.
    for (size_t j = 0; j < sc->decisions.size(); ++j) {
      const Decision& d = sc->decisions[j];
      const LandmarkObservation& z = scan.observations[j];
      if (d.kind == Decision::kIgnored) ++counts.ignored;
      if (d.kind != Decision::kAssociated) continue;
      Status s;
      int32_t tag = -1;
      const bool ok = trie_.Update(&maps_[i], d.key, slot, [&](Landmark& l, bool) {
        s = UpdateLandmark(pose, RangeBearing{z.range_m, z.bearing_rad}, noise_, &l, nullptr);
        if (l.evidence < (1 << 30)) ++l.evidence;
        tag = l.tag;
      });
      if (!ok) return NoMemory(i, "map");
      if (!s.ok()) return ParticleError(i, z, s);
      ++counts.associated;
      if (z.id >= 0 && tag >= 0) {
        ++counts.tagged;
        counts.wrong += tag != z.id;
      }
      touched.push_back(d.key);
    }
    // 2. Evidence of the landmarks in view and not seen: near no detection's augment gate.
    if (config_.evidence == FastSlamEvidence::kOn) {
      std::vector<Match>& near = sc->query.matches;  // every pair within an augment gate
      std::sort(near.begin(), near.end(),
                [](const Match& a, const Match& b) { return a.key < b.key; });
      const size_t first_missed = touched.size();
      for (uint64_t key : sc->query.in_view) {
        auto it = std::lower_bound(near.begin(), near.end(), key,
                                   [](const Match& m, uint64_t k) { return m.key < k; });
        if (it == near.end() || it->key != key) touched.push_back(key);
      }
      for (size_t k = first_missed; k < touched.size(); ++k) {
        bool remove = false;
        if (!trie_.Update(&maps_[i], touched[k], slot, [&](Landmark& l, bool) {
              --l.evidence;
              remove = l.evidence < config_.evidence_threshold;
            })) {
          return NoMemory(i, "map");
        }
        if (remove) {
          if (!trie_.Erase(&maps_[i], touched[k], slot)) return NoMemory(i, "map");
          ++counts.removed;
        }
      }
      touched.resize(first_missed);
    }
    // 3. An updated landmark whose mean left its cell moves to a slot of its new cell.
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    for (uint64_t key : touched) {
      const Landmark l = *trie_.Find(maps_[i], key);
      Cell cell;
      if (CellOf(l.x_m, l.y_m, params_.cell_m, &cell) && cell == CellOfKey(key)) continue;
      if (!trie_.Erase(&maps_[i], key, slot)) return NoMemory(i, "map");
      GROVE_RETURN_IF_ERROR(Insert(i, slot, l));
    }
    // 4. New landmarks.
    for (size_t j = 0; j < sc->decisions.size(); ++j) {
      if (sc->decisions[j].kind != Decision::kNew) continue;
      const LandmarkObservation& z = scan.observations[j];
      Landmark l = InitLandmark(pose, RangeBearing{z.range_m, z.bearing_rad}, noise_);
      l.evidence = 1;
      l.tag = z.id >= 0 ? static_cast<int32_t>(z.id) : -1;
      GROVE_RETURN_IF_ERROR(Insert(i, slot, l));
      ++counts.created;
    }
    return Status::Ok();
  }

  static Status NoMemory(size_t i, const char* what) {
    return ResourceExhaustedError(fmt::format("out of memory for particle {}'s {}", i, what));
  }
  static Status ParticleError(size_t i, const LandmarkObservation& z, const Status& s) {
    return Status(s.code(), fmt::format("particle {}, landmark {}: {}", i, z.id, s.message()));
  }

  const FastSlamConfig config_;
  const VehicleGeometry geometry_;
  const SensorNoise noise_;
  const size_t n_;
  Eigen::Matrix2d q_;
  Trie trie_;
  SegmentHistory history_;
  VersionSet<Trie> maps_;
  VersionSet<SegmentHistory> paths_;
  std::vector<VehiclePose> pose_;
  std::vector<Unit> unit_;
  std::vector<PoseCovariance> cov_;
  // FastSLAM 2.0: each particle's proposal of the current scan, from Advance() to Complete().
  std::vector<Eigen::Vector3d> proposal_mu_;
  std::vector<PoseCovariance> proposal_sigma_;
  bool segment_start_ = true;
  // Unknown association.
  const bool ml_;
  const AssociationParams params_;
  const double log_p0_;
  double max_range_ = 0;                   // the longest detection range so far
  std::vector<AssociationCounts> counts_;  // per particle, along its ancestry
  // FastSLAM 2.0: each particle's matches of the current scan, from Advance() to Complete().
  std::vector<ScanQuery> pending_;
  std::vector<Scratch> scratch_;  // per worker slot
};

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_FASTSLAM_MODEL_H_

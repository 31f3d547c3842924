// FastSlamModel: the landmark FastSLAM particle for ParticleFilter (grove/fastslam.h), generic
// over the degree of its landmark trees' inner and bottom nodes.
//
// Per particle (structure of arrays): the vehicle pose and its unit heading vector, FastSLAM
// 2.0's pose covariance (ParticlePoses), the map (a version of a PersistentTrie keyed by landmark
// id, leaves holding a landmark Gaussian) and the path history.
//
// Steps (each filter's pose and landmark steps: FilterTraits, FilterSteps):
//   Predict(ControlStep): FastSLAM 1.0 draws the particle's own control from N(u, Q) and moves;
//     FastSLAM 2.0 moves the mean with the control and propagates the pose covariance.
//   Advance(ScanStep): FastSLAM 1.0 adds log N(v; 0, S) of each observation of a known
//     landmark and updates it (EKF, Joseph form); FastSLAM 2.0 refines the pose mean and
//     covariance by each observation of a known landmark and adds each one's predictive
//     log-likelihood, which does not depend on the pose drawn next.
//   Complete(ScanStep), after resampling (FastSLAM 2.0): the refinement again, the draw of the
//     pose from it (its covariance then starts again at 0) and the landmark updates from the
//     drawn pose. Copies of one parent draw distinct poses (Bailey's order: resample, then
//     sample). Both filters initialise new landmarks from the pose.
//   Population(ScanStep), after Complete(): differential evolution (DifferentialEvolution), then
//     the landmark updates from the moved poses.
// Under unknown association (config.association != kKnown) the map is keyed by SpatialKey and
// each scan's decisions and map changes are UnknownAssociation's.
//
// Paths: a particle does not store a pose per step. Its history holds one entry per path
// segment: the pose and particle index at the first prediction after the start or a scan.
// Within a segment a particle keeps its index (resampling happens only at scans), so its poses
// there are the same predictions redone from the segment's start (FilterSteps::PredictPose()
// draws the same numbers from the counter-based streams). The pose after a segment's closing
// scan is the next entry's start pose. A path thus costs one node per scan, not one per control
// step, and the histories of copies share their common part (Ancestry).
#ifndef GROVE_ENGINE_FASTSLAM_FASTSLAM_MODEL_H_
#define GROVE_ENGINE_FASTSLAM_FASTSLAM_MODEL_H_

#include <fmt/format.h>

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/fastslam/data_association.h"
#include "engine/fastslam/differential_evolution.h"
#include "engine/fastslam/filter_steps.h"
#include "engine/fastslam/filter_traits.h"
#include "engine/fastslam/landmark_math.h"
#include "engine/fastslam/landmark_updates.h"
#include "engine/fastslam/particle_poses.h"
#include "engine/fastslam/unknown_association.h"
#include "engine/fastslam/vehicle_model.h"
#include "engine/filter/particle_filter.h"
#include "engine/io/checkpoint_io.h"
#include "engine/persistent/ancestry.h"
#include "engine/persistent/memory_use.h"
#include "engine/persistent/persistent_trie.h"
#include "engine/persistent/version_set.h"
#include "grove/fastslam.h"

namespace grove::fastslam {

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

template <int kLog2Degree, int kLog2BottomDegree = kLog2Degree>
class FastSlamModel {
 public:
  using Trie = PersistentTrie<Landmark, kLog2Degree, kLog2BottomDegree>;

  // A model of every particle, or across ranks of this rank's `share` of the filter's
  // config.particles (particle i here is the filter's first + i; `ranks` carries differential
  // evolution's exchanges). REQUIRES: config.Validate() is ok.
  FastSlamModel(const FastSlamConfig& config, int slots, ParticleShare share = {},
                Collective* ranks = nullptr)
      : config_(config),
        steps_(config),
        n_(ranks == nullptr ? static_cast<size_t>(config.particles) : share.count),
        first_(ranks == nullptr ? 0 : share.first),
        total_(static_cast<uint64_t>(config.particles)),
        trie_(1, slots),
        history_(slots),
        maps_(&trie_, n_),
        paths_(&history_, n_),
        poses_(n_,
               VehiclePose{config.start_x_m, config.start_y_m, WrapAngle(config.start_heading_rad)},
               steps_.restart_covariance(), steps_.traits().draws_after_resampling),
        association_(config, steps_.traits(), n_, first_, slots),
        updates_(slots),
        evolution_(config, steps_.traits().evolution, n_, first_, ranks) {}

  size_t size() const { return n_; }
  const FilterTraits& traits() const { return steps_.traits(); }
  const FilterSteps& steps() const { return steps_; }

  // Before each scan's update (UnknownAssociation::NoteScan()).
  void NoteScan(const ScanStep& scan) { association_.NoteScan(scan); }
  bool unknown_association() const { return association_.active(); }
  // Unknown association: stores `l` in particle i's map as a new landmark would be (benchmarks
  // build big maps with it). REQUIRES: unknown_association(), and l's covariance within the
  // bound SearchRadius() assumes for the ranges NoteScan() has seen.
  Status InsertLandmark(size_t i, const Landmark& l, int slot) {
    return association_.Insert(&trie_, &maps_[i], i, slot, l);
  }
  const AssociationCounts& counts(size_t i) const { return association_.counts(i); }
  const EvolutionCounts& evolution_counts() const { return evolution_.counts(); }

  // The prediction of particles [begin, end) over control c (FilterSteps::PredictPose() redoes
  // one of them).
  Status Predict(const PredictStep& prediction, uint64_t step, size_t begin, size_t end, int slot) {
    const ControlStep& c = prediction.control;
    if (prediction.starts_segment) GROVE_RETURN_IF_ERROR(StartSegments(step, begin, end, slot));
    if (traits().pose == FilterTraits::Pose::kSampledMotion) {
      return PredictSampled(c, step, prediction.starts_segment, begin, end);
    }
    const VehicleGeometry& geometry = steps_.geometry();
    if (!SteeringUsable(geometry, c.steer_rad)) return BadSteering(begin);
    if (traits().pose == FilterTraits::Pose::kEkf) {
      const MotionResult r =
          steps_.PredictLinearized(c, prediction.starts_segment, &poses_.pose(begin),
                                   &poses_.unit(begin), &poses_.cov(begin), end - begin);
      if (r.first_failed == end - begin) return Status::Ok();
      return PoseNotFinite(begin + r.first_failed, poses_.pose(begin + r.first_failed));
    }
    for (size_t i = begin; i < end; ++i) {
      Eigen::Vector3d mean = ToVector(poses_.pose(i));
      Eigen::Matrix3d m = steps_.Stored(poses_.cov(i));
      Status s = steps_.SigmaPointPredict(c, &mean, &m);
      if (!s.ok()) return ParticleStatus(first_ + i, s);
      const VehiclePose next = ToPose(mean);
      if (!std::isfinite(next.x_m) || !std::isfinite(next.y_m) ||
          !std::isfinite(next.heading_rad)) {
        return PoseNotFinite(i, next);
      }
      poses_.cov(i) = steps_.Store(m);
      poses_.pose(i) = next;
      poses_.unit(i) = HeadingUnit{std::cos(next.heading_rad), std::sin(next.heading_rad)};
    }
    return Status::Ok();
  }

  // FastSLAM 1.0: the whole update. The filters that draw after resampling: the weight only
  // (the predictive likelihood of the observations of known landmarks); Complete() draws and
  // updates. The sigma-point particle filter: the proposal, the draw, the importance weight and
  // the landmark updates.
  Status Advance(const ScanStep& scan, uint64_t step, size_t begin, size_t end, int slot,
                 double* log_w) {
    if (association_.active()) return AdvanceUnknown(scan, step, begin, end, slot, log_w);
    if (scan.observations.empty() && !traits().draws_every_scan()) return Status::Ok();
    if (traits().pose == FilterTraits::Pose::kSampledMotion) {
      return updates_.Apply(steps_, &trie_, &maps_[begin], &poses_.pose(begin), first_ + begin,
                            scan, end - begin, slot, log_w + begin);
    }
    for (size_t i = begin; i < end; ++i) {
      double lw = 0;
      Eigen::Vector3d mu = ToVector(poses_.pose(i));
      Eigen::Matrix3d sigma = steps_.Stored(poses_.cov(i));
      for (const LandmarkObservation& z : scan.observations) {
        const Landmark* l = trie_.Find(maps_[i], static_cast<uint64_t>(z.id));
        if (l == nullptr) continue;
        double w = 0;
        GROVE_RETURN_IF_ERROR(ProposalStepOf(i, z, *l, &mu, &sigma, &w));
        lw += w;
      }
      if (traits().draws_after_resampling) {
        poses_.proposal_mu(i) = mu;
        poses_.proposal_sigma(i) = steps_.Store(sigma);
      } else {
        // The importance ratio replaces the predictive likelihood.
        GROVE_RETURN_IF_ERROR(DrawAndWeigh(scan, step, i, nullptr, mu, sigma, &lw));
        double unused = 0;
        GROVE_RETURN_IF_ERROR(UpdateLandmarks(scan, i, slot, &unused));
      }
      log_w[i] += lw;
    }
    return Status::Ok();
  }

  // The filters that draw after resampling: the draw from the proposal Advance() computed (a
  // copy has its parent's), keyed by the particle's new index, then the landmark updates from
  // the drawn pose (for differential evolution, Population() does them after moving the poses).
  Status Complete(const ScanStep& scan, uint64_t step, size_t begin, size_t end, int slot) {
    if (!traits().draws_after_resampling) return Status::Ok();
    if (scan.observations.empty() && !traits().draws_every_scan()) return Status::Ok();
    // The EKF map under known association: every pose drawn, then the landmark updates of the
    // particles drawn, observation by observation across them (LandmarkUpdates), reporting the
    // lowest failing particle's error as the loop below does.
    if (traits().map == FilterTraits::Map::kEkf && !traits().evolution && !association_.active()) {
      size_t i = end;
      const Status drawn = DrawEach(
          step, begin, end, [](size_t) { return Status::Ok(); }, &i);
      if (!scan.observations.empty() && i > begin) {
        GROVE_RETURN_IF_ERROR(updates_.Apply(steps_, &trie_, &maps_[begin], &poses_.pose(begin),
                                             first_ + begin, scan, i - begin, slot, nullptr));
      }
      return drawn;
    }
    size_t unused = 0;
    return DrawEach(
        step, begin, end,
        [&](size_t i) {
          if (traits().evolution || scan.observations.empty()) return Status::Ok();
          return UpdateMap(scan, i, slot);
        },
        &unused);
  }

  // Differential evolution (kDeSrcd) over the drawn poses, then their landmark updates; nothing
  // for the other filters (PopulationMoves() false).
  bool PopulationMoves(const ScanStep& scan) const {
    return traits().evolution && !scan.observations.empty();
  }
  Status Population(const ScanStep& scan, uint64_t step, WorkerPool& workers) {
    if (!PopulationMoves(scan)) return Status::Ok();
    GROVE_RETURN_IF_ERROR(
        evolution_.Evolve(step, workers, poses_.poses(),
                          [&](size_t i, const VehiclePose& pose, int slot, int* terms) {
                            return Fitness(scan, i, pose, slot, terms);
                          }));
    return RunInBatches(
        workers, n_, static_cast<size_t>(config_.batch), &batch_status_,
        [&](int slot, size_t b, size_t e) -> Status {
          for (size_t i = b; i < e; ++i) {
            const VehiclePose& p = poses_.pose(i);
            poses_.unit(i) = HeadingUnit{std::cos(p.heading_rad), std::sin(p.heading_rad)};
            GROVE_RETURN_IF_ERROR(UpdateMap(scan, i, slot));
          }
          return Status::Ok();
        });
  }

  // Differential evolution's fitness of `pose` for particle i at this scan, from worker slot
  // `slot` (public for tests): the seed's Eq. 32 as a logarithm, -1/2 sum_j v_j^T R^-1 v_j over
  // the scan's observations of landmarks in particle i's map (under unknown association its
  // associations, from the query Advance() kept).
  // *terms (may be null) gets the number of observations summed.
  double Fitness(const ScanStep& scan, size_t i, const VehiclePose& pose, int slot,
                 int* terms = nullptr) const {
    const Eigen::Matrix2d r = SensorCovariance(steps_.noise());
    double f = 0;
    if (terms != nullptr) *terms = 0;
    auto add = [&](const LandmarkObservation& z, const Landmark& l) {
      if (terms != nullptr) ++*terms;
      const Eigen::Vector2d v =
          Innovation(RangeBearing{z.range_m, z.bearing_rad}, Observe(pose, l.x_m, l.y_m));
      f -= 0.5 * (v(0) * v(0) / r(0, 0) + v(1) * v(1) / r(1, 1));
    };
    if (association_.active()) {
      const std::vector<Decision>& decisions = association_.PendingDecisions(scan, i, slot);
      for (size_t j = 0; j < decisions.size(); ++j) {
        if (decisions[j].kind != Decision::kAssociated) continue;
        add(scan.observations[j], *trie_.Find(maps_[i], decisions[j].key));
      }
    } else {
      for (const LandmarkObservation& z : scan.observations) {
        const Landmark* l = trie_.Find(maps_[i], static_cast<uint64_t>(z.id));
        if (l != nullptr) add(z, *l);
      }
    }
    return std::isfinite(f) ? f : -std::numeric_limits<double>::infinity();
  }

  // The next generation in chunks (ChunkGatheringModel). Imported particles are named by
  // parents or dropped.
  void GatherBegin(std::span<const uint32_t> parents) {
    const size_t n = parents.size();
    ForEachGathered([&](auto g) { g.Begin(n); });
    maps_.GatherBegin(n);
    paths_.GatherBegin(n);
  }
  void GatherRange(std::span<const uint32_t> parents, size_t begin, size_t end) {
    ForEachGathered([&](auto g) { g.Range(parents, begin, end); });
    maps_.GatherRange(parents, begin, end);
    paths_.GatherRange(parents, begin, end);
  }
  void GatherEnd(std::span<const uint32_t> parents, size_t grain) {
    ForEachGathered([](auto g) { g.End(); });
    maps_.GatherEnd(parents, grain);
    paths_.GatherEnd(parents, grain);
    n_ = parents.size();
  }

  void ReleaseDead(WorkerPool& workers) {
    maps_.ReleaseDead(workers);
    paths_.ReleaseDead(workers);
  }
  // ReleaseDead() in pieces, inside the next step's batches (PieceReleasingModel).
  void ReleaseDeadRange(size_t lo, size_t hi, int slot) {
    maps_.ReleaseDeadRange(lo, hi, slot);
    paths_.ReleaseDeadRange(lo, hi, slot);
  }
  void DeadReleased() {
    maps_.DeadReleased();
    paths_.DeadReleased();
  }

  Status CheckCounts() const {
    GROVE_RETURN_IF_ERROR(trie_.CheckCounts(maps_.AllReferences()));
    return history_.CheckCounts(paths_.AllReferences());
  }

  double x(size_t i) const { return poses_.pose(i).x_m; }
  double y(size_t i) const { return poses_.pose(i).y_m; }
  // The heading's unit vector: cos and sin of heading(i) to round-off (FastSLAM 2.0 turns it
  // by rotation between scans).
  double cos_heading(size_t i) const { return poses_.unit(i).c; }
  double sin_heading(size_t i) const { return poses_.unit(i).s; }
  const VehiclePose& pose(size_t i) const { return poses_.pose(i); }
  const typename Trie::Node* map(size_t i) const { return maps_[i]; }
  const SegmentHistory::Node* path(size_t i) const { return paths_[i]; }
  const Trie& trie() const { return trie_; }

  MemoryUse map_memory() const {
    MemoryUse m;
    trie_.AddMemory(&m);
    return m;
  }
  MemoryUse path_memory() const {
    MemoryUse m;
    AddPoolStats(history_.stats(), &m);
    return m;
  }

  // The particles' state after a step: poses, covariances, maps and paths.
  void Save(ByteWriter* w) const {
    w->Put<uint64_t>(n_);
    poses_.Save(w);
    association_.Save(w);
    evolution_.Save(w);
    trie_.Save(maps_.roots(), w);
    SegmentHistory::Save(paths_.roots(), w);
  }

  // Replaces the state of a new model with a saved one taken after step `steps`.
  Status Load(ByteReader* r, uint64_t steps) {
    GROVE_RETURN_IF_ERROR(ReadParticleCount(r, n_));
    ParticlePoses::Saved poses;
    GROVE_RETURN_IF_ERROR(ParticlePoses::Read(r, n_, &poses));
    typename UnknownAssociation<Trie>::Saved association;
    GROVE_RETURN_IF_ERROR(association_.Read(r, &association));
    EvolutionCounts evolution;
    GROVE_RETURN_IF_ERROR(DifferentialEvolution::ReadCounts(r, &evolution));
    std::vector<typename Trie::Node*> roots;
    GROVE_RETURN_IF_ERROR(trie_.Load(r, n_, 0, &ValidLandmark, &roots));
    if (steps >= UINT32_MAX) {
      for (auto* root : roots) trie_.Release(root, 0);
      return r->Error("step", "too many steps");
    }
    std::vector<SegmentHistory::Node*> heads;
    Status s = history_.Load(r, n_, static_cast<uint32_t>(steps), 0, &ValidSegmentStart, &heads);
    if (s.ok() && steps > 0) {
      s = CheckPaths(r, heads);
      if (!s.ok()) {
        for (auto* h : heads) history_.Release(h, 0);
      }
    }
    if (!s.ok()) {
      for (auto* root : roots) trie_.Release(root, 0);
      return s;
    }
    poses_.Restore(&poses);
    association_.Restore(&association);
    evolution_.Restore(evolution);
    maps_.Replace(std::move(roots));
    paths_.Replace(std::move(heads));
    return Status::Ok();
  }

  // Particles `which` (increasing) for another rank: their values, the scan's pending
  // proposals and matches, their paths and their maps, each shared entry and node written once.
  void Export(std::span<const uint32_t> which, ByteWriter* w) const {
    poses_.Export(which, w);
    association_.Export(which, w);
    SegmentHistory::Save(paths_.Pick(which), w);
    trie_.Save(maps_.Pick(which), w);
  }

  // Appends `count` particles written by Export() after step `steps`: size() grows by count
  // until the next Gather(). Checks every value. On error the model must not step again.
  Status Import(ByteReader* r, size_t count, uint64_t steps) {
    if (count > r->remaining() / ParticlePoses::kMessageBytes) {
      return r->Error("particle count", "larger than the message");
    }
    if (steps >= UINT32_MAX) return r->Error("step", "too many steps");
    const size_t at = n_;
    GROVE_RETURN_IF_ERROR(poses_.Import(r, count));
    GROVE_RETURN_IF_ERROR(association_.Import(r, at, count));
    std::vector<SegmentHistory::Node*> heads;
    GROVE_RETURN_IF_ERROR(
        history_.Load(r, count, static_cast<uint32_t>(steps), 0, &ValidSegmentStart, &heads));
    std::vector<typename Trie::Node*> roots;
    Status s = steps > 0 ? CheckPaths(r, heads) : Status::Ok();
    if (s.ok()) s = trie_.Load(r, count, 0, &ValidLandmark, &roots);
    // The pending matches and views name landmarks of the particle's own map.
    if (s.ok()) s = association_.CheckImported(r, trie_, roots, at);
    if (!s.ok()) {
      for (auto* h : heads) history_.Release(h, 0);
      for (auto* root : roots) trie_.Release(root, 0);
      return s;
    }
    paths_.Append(heads);
    maps_.Append(roots);
    n_ = at + count;
    return Status::Ok();
  }

 private:
  // Calls f on each per-particle value the model gathers by copying (Gathered<T>).
  template <typename F>
  void ForEachGathered(F f) {
    poses_.ForEachGathered(f);
    association_.ForEachGathered(f);
  }

  using Scratch = typename UnknownAssociation<Trie>::Scratch;

  static bool ValidLandmark(const Landmark& l) {
    return std::isfinite(l.x_m) && std::isfinite(l.y_m) && std::isfinite(l.xx) &&
           std::isfinite(l.xy) && std::isfinite(l.yy) && l.xx >= 0 && l.yy >= 0 && l.tag >= -1;
  }

  // Every particle of `heads` read after a step has a path, its index one of the filter's.
  Status CheckPaths(ByteReader* r, const std::vector<SegmentHistory::Node*>& heads) const {
    for (size_t k = 0; k < heads.size(); ++k) {
      if (heads[k] == nullptr || heads[k]->value.index >= total_) {
        return r->Error("path", "particle " + std::to_string(k) + " has no path or a bad index");
      }
    }
    return Status::Ok();
  }

  // FastSLAM 1.0's Predict(): every particle of [begin, end) at once (MoveSampled()).
  Status PredictSampled(const ControlStep& c, uint64_t step, bool segment_start, size_t begin,
                        size_t end) {
    const MotionResult r =
        steps_.PredictSampled(c, step, static_cast<uint32_t>(first_ + begin), segment_start,
                              &poses_.pose(begin), &poses_.unit(begin), end - begin);
    if (r.first_failed == end - begin) return Status::Ok();
    const size_t i = begin + r.first_failed;
    if (r.why == MotionFailure::kSteering) return BadSteering(i);
    return PoseNotFinite(i, poses_.pose(i));
  }

  // Particles [begin, end) start a path segment at `step` from their poses now.
  Status StartSegments(uint64_t step, size_t begin, size_t end, int slot) {
    for (size_t i = begin; i < end; ++i) {
      const VehiclePose& p = poses_.pose(i);
      const SegmentStart s{p.x_m, p.y_m, p.heading_rad, static_cast<uint32_t>(first_ + i), 0};
      SegmentHistory::Node* node = history_.Append(paths_[i], static_cast<uint32_t>(step), s, slot);
      if (node == nullptr) return NoMemoryError(first_ + i, "path");
      paths_[i] = node;
    }
    return Status::Ok();
  }

  Status PoseNotFinite(size_t i, const VehiclePose& p) const {
    return FailedPreconditionError(fmt::format("particle {}'s pose ({}, {}, {}) is not finite",
                                               first_ + i, p.x_m, p.y_m, p.heading_rad));
  }

  Status BadSteering(size_t i) const {
    return FailedPreconditionError(fmt::format(
        "particle {}'s steering angle is outside what the {} model can use (|G| < pi/2 and "
        "1 - tan(G) H / L > 0)",
        first_ + i, FastSlamVehicleName(config_.vehicle)));
  }

  // One observation's proposal step on (mu, sigma) by the filter's pose step; *w gets its
  // predictive log-likelihood.
  Status ProposalStepOf(size_t i, const LandmarkObservation& z, const Landmark& leaf,
                        Eigen::Vector3d* mu, Eigen::Matrix3d* sigma, double* w) const {
    Status s = steps_.ProposalStep(z, leaf, mu, sigma, w);
    if (!s.ok()) return ParticleError(first_ + i, z, s);
    return Status::Ok();
  }

  // The sigma-point particle filter: draws particle i's pose from its proposal
  // N(mu, sigma sigma^T) and sets *lw to the importance weight at the drawn x,
  //   sum_j log p(z_j | x, landmark_j) + log N(x; prediction) - log N(x; proposal),
  // over the scan's observations of known landmarks (p(z | x, landmark) = N(z; h(x), Hl P Hl^T +
  // R), the landmark marginalised), or with `decisions` (unknown association) over the
  // associated ones plus log p0 for each other detection. The pose covariance restarts.
  Status DrawAndWeigh(const ScanStep& scan, uint64_t step, size_t i,
                      const std::vector<Decision>* decisions, const Eigen::Vector3d& mu,
                      const Eigen::Matrix3d& sigma, double* lw) {
    const Eigen::Vector3d prior_mu = ToVector(poses_.pose(i));
    const Eigen::Matrix3d prior = steps_.Stored(poses_.cov(i));
    VehiclePose x;
    GROVE_RETURN_IF_ERROR(steps_.Draw(step, first_ + i, mu, sigma, &x));
    double w = 0;
    for (size_t j = 0; j < scan.observations.size(); ++j) {
      const LandmarkObservation& z = scan.observations[j];
      const Landmark* l = nullptr;
      if (decisions != nullptr) {
        if ((*decisions)[j].kind != Decision::kAssociated) {
          w += association_.log_p0();
          continue;
        }
        l = trie_.Find(maps_[i], (*decisions)[j].key);
      } else {
        l = trie_.Find(maps_[i], static_cast<uint64_t>(z.id));
        if (l == nullptr) continue;
      }
      double ll = 0;
      Status s = ObservationLogLikelihood(x, RangeBearing{z.range_m, z.bearing_rad}, steps_.noise(),
                                          steps_.CovarianceLeaf(*l), &ll);
      if (!s.ok()) return ParticleError(first_ + i, z, s);
      w += ll;
    }
    GROVE_RETURN_IF_ERROR(steps_.AddImportanceRatio(first_ + i, prior_mu, prior, x, mu, sigma, &w));
    *lw = w;
    poses_.pose(i) = x;
    poses_.unit(i) = HeadingUnit{std::cos(x.heading_rad), std::sin(x.heading_rad)};
    poses_.cov(i) = steps_.restart_covariance();
    return Status::Ok();
  }

  // The leaf of `key` in particle i's map, a landmark the scan's range query handed over: the
  // copy the query noted (the leaf itself unless the map holds square-root factors, which the
  // copies hold converted), or else found in the map.
  const Landmark& NotedLeaf(const Scratch& sc, size_t i, uint64_t key) const {
    if (!traits().square_root_map()) {
      const std::vector<uint64_t>& keys = sc.matches.key;
      for (size_t k = 0; k < keys.size(); ++k) {
        if (keys[k] == key) return sc.matches.leaf[k];
      }
    }
    return *trie_.Find(maps_[i], key);
  }

  // Unknown association's Advance(): particle by particle, the decisions from its pose now,
  // the weight, and (but for the filters that draw after resampling) the map changes.
  Status AdvanceUnknown(const ScanStep& scan, uint64_t step, size_t begin, size_t end, int slot,
                        double* log_w) {
    Scratch& sc = association_.scratch(slot);
    const bool sampled = traits().pose == FilterTraits::Pose::kSampledMotion;
    if (scan.observations.empty() && !traits().draws_every_scan()) {
      // Nothing to weigh or draw; the evidence of what is in view still falls.
      if (!association_.evidence()) return Status::Ok();
      for (size_t i = begin; i < end; ++i) {
        GROVE_RETURN_IF_ERROR(DecideScan(scan, step, i, &sc));
        GROVE_RETURN_IF_ERROR(ApplyScan(scan, i, slot, &sc));
      }
      return Status::Ok();
    }
    for (size_t i = begin; i < end; ++i) {
      GROVE_RETURN_IF_ERROR(DecideScan(scan, step, i, &sc));
      double lw = 0;
      Eigen::Vector3d mu = ToVector(poses_.pose(i));
      Eigen::Matrix3d sigma = steps_.Stored(poses_.cov(i));
      for (size_t j = 0; j < sc.decisions.size(); ++j) {
        const Decision& d = sc.decisions[j];
        if (d.kind != Decision::kAssociated) {
          lw += association_.log_p0();
        } else if (sampled) {
          lw += d.log_likelihood;
        } else {
          double w = 0;
          GROVE_RETURN_IF_ERROR(
              ProposalStepOf(i, scan.observations[j], NotedLeaf(sc, i, d.key), &mu, &sigma, &w));
          lw += w;
        }
      }
      if (sampled) {
        GROVE_RETURN_IF_ERROR(ApplyScan(scan, i, slot, &sc));
      } else if (traits().draws_after_resampling) {
        poses_.proposal_mu(i) = mu;
        poses_.proposal_sigma(i) = steps_.Store(sigma);
        association_.KeepQuery(i, sc);
        if (scan.observations.empty() && association_.evidence()) {
          // The evidence of an empty scan is applied now, from the predicted mean (Complete()
          // only draws).
          GROVE_RETURN_IF_ERROR(ApplyScan(scan, i, slot, &sc));
        }
      } else {
        GROVE_RETURN_IF_ERROR(DrawAndWeigh(scan, step, i, &sc.decisions, mu, sigma, &lw));
        GROVE_RETURN_IF_ERROR(ApplyScan(scan, i, slot, &sc));
      }
      if (association_.sampled()) lw += sc.log_correction;
      log_w[i] += lw;
    }
    return Status::Ok();
  }

  // Unknown association: particle i's query and decisions from its pose now, into sc.
  Status DecideScan(const ScanStep& scan, uint64_t step, size_t i, Scratch* sc) const {
    return association_.DecideScan(trie_, maps_[i], scan, step, i, poses_.pose(i), sc);
  }
  // Unknown association: applies particle i's decisions in sc from its pose now.
  Status ApplyScan(const ScanStep& scan, size_t i, int slot, Scratch* sc) {
    return association_.ApplyScan(steps_, &trie_, &maps_[i], scan, i, poses_.pose(i), slot, sc);
  }

  // Draws the poses of particles [begin, end) in order, their deviates kDrawChunk particles at a
  // time, and calls then(i) -> Status after each; stops at the first error and returns it,
  // *stopped the particle it came from (end when none).
  template <typename Then>
  Status DrawEach(uint64_t step, size_t begin, size_t end, Then&& then, size_t* stopped) {
    FilterSteps::Deviates d;
    for (size_t from = begin; from < end; from += FilterSteps::kDrawChunk) {
      const size_t to = std::min(end, from + FilterSteps::kDrawChunk);
      steps_.DrawDeviates(step, first_ + from, first_ + to, &d);
      for (size_t i = from; i < to; ++i) {
        Status s = DrawWith(d.of(i - from), i);
        if (s.ok()) s = then(i);
        if (!s.ok()) {
          *stopped = i;
          return s;
        }
      }
    }
    *stopped = end;
    return Status::Ok();
  }
  // Particle i's pose drawn from its proposal with the given deviates (FilterSteps::Deviates,
  // those of its stream at the scan's step); its covariance restarts.
  Status DrawWith(const Eigen::Vector3d& normals, size_t i) {
    VehiclePose& pose = poses_.pose(i);
    GROVE_RETURN_IF_ERROR(steps_.DrawWith(normals, first_ + i, poses_.proposal_mu(i),
                                          steps_.Stored(poses_.proposal_sigma(i)), &pose));
    poses_.unit(i) = HeadingUnit{std::cos(pose.heading_rad), std::sin(pose.heading_rad)};
    poses_.cov(i) = steps_.restart_covariance();
    return Status::Ok();
  }

  // The landmark updates of particle i's scan from its pose now.
  Status UpdateMap(const ScanStep& scan, size_t i, int slot) {
    if (association_.active()) {
      return association_.ApplyPending(steps_, &trie_, &maps_[i], scan, i, poses_.pose(i), slot);
    }
    double unused = 0;
    return UpdateLandmarks(scan, i, slot, &unused);
  }

  // The update of each observed landmark from particle i's pose (new ones initialised);
  // *log_w gets the sum of the known ones' log-likelihoods.
  Status UpdateLandmarks(const ScanStep& scan, size_t i, int slot, double* log_w) {
    const VehiclePose pose = poses_.pose(i);
    for (const LandmarkObservation& z : scan.observations) {
      const RangeBearing rb{z.range_m, z.bearing_rad};
      Status s;
      double ll = 0;
      const bool ok = trie_.Update(&maps_[i], static_cast<uint64_t>(z.id), slot,
                                   [&](Landmark& l, bool existed) {
                                     if (!existed) {
                                       s = steps_.NewLeaf(pose, rb, &l);
                                     } else {
                                       s = steps_.UpdateLeaf(pose, rb, &l, &ll);
                                     }
                                   });
      if (!ok) return NoMemoryError(first_ + i, "map");
      if (!s.ok()) return ParticleError(first_ + i, z, s);
      *log_w += ll;
    }
    return Status::Ok();
  }

  const FastSlamConfig config_;
  const FilterSteps steps_;
  size_t n_;              // particles here (more after an Import(), until the next Gather())
  const uint64_t first_;  // the filter's index of particle 0 here
  const uint64_t total_;  // the filter's particles
  Trie trie_;
  SegmentHistory history_;
  VersionSet<Trie> maps_;
  VersionSet<SegmentHistory> paths_;
  ParticlePoses poses_;
  UnknownAssociation<Trie> association_;
  LandmarkUpdates<Trie> updates_;
  DifferentialEvolution evolution_;
  std::vector<Status> batch_status_;  // RunInBatches' scratch
};

// The landmark trees' degree, 2^kLandmarkLog2Degree (engine/fastslam/README.md, "FastSLAM 1.0
// and 2.0: accuracy and speed", has the measurement).
inline constexpr int kLandmarkLog2Degree = 3;
// Under unknown association a bottom node holds the landmarks of 2^kLog2CellsPerBottom cells of
// the spatial index, packed: most cells hold one landmark or none, so a query visits fewer,
// fuller nodes (engine/fastslam/README.md, "Unknown data association"). Landmark ids are dense
// keys: a bottom node holds the leaves of 2^kLandmarkLog2Degree ids, unpacked.
inline constexpr int kLog2CellsPerBottom = 3;

// The model of a run under known association (maps keyed by landmark id) and under unknown
// association (maps keyed by SpatialKey).
using IdKeyedModel = FastSlamModel<kLandmarkLog2Degree>;
using CellKeyedModel =
    FastSlamModel<kLandmarkLog2Degree, kLandmarkLog2Degree + kLog2CellsPerBottom>;

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_FASTSLAM_MODEL_H_

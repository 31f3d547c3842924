// UnknownAssociation: landmark FastSLAM's maps under unknown association
// (config.association != kKnown), per particle and scan.
//
// The map is keyed by SpatialKey (a landmark's cell and a slot in it) instead of by id. At a
// scan each particle finds the candidates of every detection with a range query of its own trie,
// decides with the gates (data_association.h; Decide()) or, under `jcbb`, by joint compatibility
// (joint_compatibility.h; both redone from the kept matches when needed again) or, under
// `sampled`, draws the decisions (association_sampling.h; kept with the query, since a draw is
// not redone), adds the
// associated detections' likelihoods and p0 for the others (FastSlamModel), and then (FastSLAM 1.0
// in Advance, 2.0 in Complete from the drawn pose; Apply()) updates the associated landmarks,
// lowers the evidence of those in view and not seen (removing the ones below the threshold; the
// view is found by the same range query as the candidates, so it is judged from the pose the
// decisions were made from: for FastSLAM 2.0 the predicted mean), moves an updated landmark whose
// mean left its cell to a slot of its new cell, and adds the new landmarks. FastSLAM 2.0 decides
// from the predicted pose mean (Bailey's order); the query Advance() made is kept per particle
// (KeepQuery()) and gathered with it for Complete() (ApplyPending()).
//
// Thread safety: the per-particle methods touch particle i's entries and the scratch of the
// worker slot they are given; distinct particles may run on distinct slots at once.
#ifndef GROVE_ENGINE_FASTSLAM_UNKNOWN_ASSOCIATION_H_
#define GROVE_ENGINE_FASTSLAM_UNKNOWN_ASSOCIATION_H_

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "alloc/cache_line.h"
#include "concurrency/random_stream.h"
#include "concurrency/worker_pool.h"
#include "engine/fastslam/association_sampling.h"
#include "engine/fastslam/data_association.h"
#include "engine/fastslam/filter_steps.h"
#include "engine/fastslam/filter_traits.h"
#include "engine/fastslam/joint_compatibility.h"
#include "engine/fastslam/spatial_key.h"
#include "engine/filter/generation.h"
#include "engine/io/checkpoint_io.h"
#include "grove/fastslam.h"

namespace grove::fastslam {

template <typename Trie>
class UnknownAssociation {
 public:
  using Node = typename Trie::Node;

  // What one range query found for a particle's scan: the pairs within an augment gate and,
  // with the evidence on, the landmarks in view.
  struct ScanQuery {
    std::vector<Match> matches;
    std::vector<uint64_t> in_view;  // increasing
    // Sampled association: the decisions drawn at Advance(), one per detection (a draw cannot
    // be redone from the matches after resampling renumbers the particle).
    std::vector<Decision> drawn;
  };
  // A worker slot's buffers, reused from particle to particle.
  struct alignas(kFalseSharingBytes) Scratch {
    ScanQuery query;
    std::vector<Decision> decisions;
    std::vector<uint64_t> keys;
    MatchScratch matches;
    // UpdateAssociated(): the leaves to update, their observations and detections.
    std::vector<Landmark*> update_leaves;
    std::vector<RangeBearing> update_zs;
    std::vector<uint32_t> update_detections;
    // Sampled association: the scan's log T - log L_drawn summed over detections
    // (association_sampling.h), to add to the particle's log-weight.
    double log_correction = 0;
    JointCompatibility jcbb;
    bool truncated = false;  // jcbb: the decisions' search stopped at its node budget
  };

  // The association state of `n` particles, the first of them the filter's particle `first`,
  // with scratch for `slots` worker slots. Inactive (it holds no per-particle state) under known
  // association. REQUIRES: config.Validate() is ok.
  UnknownAssociation(const FastSlamConfig& config, const FilterTraits& traits, size_t n,
                     uint64_t first, int slots)
      : active_(config.association != FastSlamAssociation::kKnown),
        first_(first),
        params_{FastSlamGateDistance2(config.reject_gate, config.gate_unit),
                FastSlamGateDistance2(config.augment_gate, config.gate_unit),
                config.association == FastSlamAssociation::kExclusive,
                config.index_cell_m,
                SensorNoise{config.sigma_range_m, config.sigma_bearing_rad},
                traits.square_root_map(),
                traits.map == FilterTraits::Map::kCentralDifference ? config.cd_step : 0},
        log_p0_(NewLandmarkLogLikelihood(params_.noise, params_.augment_gate)),
        sampled_(config.association == FastSlamAssociation::kSampled),
        joint_(config.association == FastSlamAssociation::kJointCompatibility),
        seed_(config.seed),
        evidence_(config.evidence == FastSlamEvidence::kOn),
        evidence_threshold_(config.evidence_threshold),
        view_{config.sensor_range_m, config.sensor_fov_rad},
        counts_(active_ ? n : 0),
        pending_(active_ && traits.draws_after_resampling ? n : 0),
        scratch_(slots) {}

  bool active() const { return active_; }
  bool evidence() const { return evidence_; }
  bool sampled() const { return sampled_; }
  // log p0, the weight of a detection that updates no landmark.
  double log_p0() const { return log_p0_; }
  const AssociationCounts& counts(size_t i) const { return counts_[i]; }
  // The scratch of worker slot `slot`: buffers, not state (hence mutable).
  Scratch& scratch(int slot) const { return scratch_[slot]; }

  // Before each scan's update: the longest range so far bounds the landmarks' covariances
  // (SearchRadius()); jcbb's joint gates reach the scan's size.
  void NoteScan(const ScanStep& scan) {
    for (const LandmarkObservation& z : scan.observations)
      max_range_ = std::max(max_range_, z.range_m);
    scan_size_ = scan.observations.size();
    if (joint_) ExtendJointGates(params_.reject_gate, scan_size_, &joint_gates_);
  }

  // The query and decisions of particle i's scan (filter step `step`) against its map `root`
  // seen from `pose`, into sc; sampled association draws them (and keeps the draw in sc.query).
  Status DecideScan(const Trie& trie, const Node* root, const ScanStep& scan, uint64_t step,
                    size_t i, const VehiclePose& pose, Scratch* sc) const {
    sc->query.matches.clear();
    sc->query.in_view.clear();
    Status s = FindMatches(trie, root, pose, scan.observations, params_, max_range_,
                           /*use_index=*/true, &sc->query.matches, &sc->matches,
                           evidence_ ? &view_ : nullptr, &sc->query.in_view);
    if (!s.ok()) return Status(s.code(), fmt::format("particle {}, {}", first_ + i, s.message()));
    if (sampled_) {
      RandomStream rs(seed_, step + 1, static_cast<uint32_t>(first_ + i),
                      StreamPurpose::kAssociation);
      SampleDecisions(sc->query.matches, scan.observations.size(), log_p0_, &rs, &sc->query.drawn,
                      &sc->log_correction);
      sc->decisions = sc->query.drawn;
      return Status::Ok();
    }
    DecideBy(sc->query.matches, scan.observations.size(), sc);
    return Status::Ok();
  }

  // Keeps sc's query as particle i's for Complete() (the filters that draw after resampling).
  void KeepQuery(size_t i, const Scratch& sc) { pending_[i] = sc.query; }

  // The decisions of particle i's kept query (the matches Advance() found from the predicted
  // mean; a copy has its parent's), in the scratch of `slot`.
  const std::vector<Decision>& PendingDecisions(const ScanStep& scan, size_t i, int slot) const {
    Scratch& sc = scratch_[slot];
    if (sampled_) return pending_[i].drawn;
    sc.query.matches = pending_[i].matches;  // Decide() reorders them
    DecideBy(sc.query.matches, scan.observations.size(), &sc);
    return sc.decisions;
  }

  // Applies particle i's kept query to its map `*root` from its pose now.
  Status ApplyPending(const FilterSteps& steps, Trie* trie, Node** root, const ScanStep& scan,
                      size_t i, VehiclePose pose, int slot) {
    Scratch& sc = scratch_[slot];
    sc.query = pending_[i];
    if (sampled_) {
      sc.decisions = sc.query.drawn;
    } else {
      DecideBy(sc.query.matches, scan.observations.size(), &sc);
    }
    return ApplyScan(steps, trie, root, scan, i, pose, slot, &sc);
  }

  // Applies particle i's decisions in sc to its map `*root` from `pose`, its pose now (the view
  // in sc is the one the decisions were made from; see the file comment).
  Status ApplyScan(const FilterSteps& steps, Trie* trie, Node** root, const ScanStep& scan,
                   size_t i, VehiclePose pose, int slot, Scratch* sc) {
    sc->keys.clear();
    if (sc->truncated) ++counts_[i].truncated;
    GROVE_RETURN_IF_ERROR(UpdateAssociated(steps, trie, root, scan, i, slot, pose, sc));
    if (evidence_) GROVE_RETURN_IF_ERROR(LowerMissed(trie, root, i, slot, sc));
    GROVE_RETURN_IF_ERROR(MoveToNewCells(trie, root, i, slot, &sc->keys));
    // New landmarks.
    for (size_t j = 0; j < sc->decisions.size(); ++j) {
      if (sc->decisions[j].kind != Decision::kNew) continue;
      const LandmarkObservation& z = scan.observations[j];
      Landmark l;
      Status s = steps.NewLeaf(pose, RangeBearing{z.range_m, z.bearing_rad}, &l);
      if (!s.ok()) return ParticleError(first_ + i, z, s);
      l.evidence = 1;
      l.tag = z.id >= 0 ? static_cast<int32_t>(z.id) : -1;
      GROVE_RETURN_IF_ERROR(Insert(trie, root, i, slot, l));
      ++counts_[i].created;
    }
    return Status::Ok();
  }

  // Stores `l` in particle i's map `*root`, in a free slot of the cell of its mean; counts a
  // drop when the cell is full.
  Status Insert(Trie* trie, Node** root, size_t i, int slot, const Landmark& l) {
    Cell cell;
    if (!CellOf(l.x_m, l.y_m, params_.cell_m, &cell)) {
      return FailedPreconditionError(fmt::format(
          "particle {}: a landmark at ({}, {}) is outside the landmark index (|x|, |y| < {} m)",
          first_ + i, l.x_m, l.y_m, static_cast<double>(kMaxCell) * params_.cell_m));
    }
    const int k = FreeSlot(*trie, *root, cell);
    if (k < 0) {
      ++counts_[i].dropped;
      return Status::Ok();
    }
    if (!trie->Update(root, SpatialKey(cell, k), slot, [&](Landmark& leaf, bool) { leaf = l; })) {
      return NoMemoryError(first_ + i, "map");
    }
    return Status::Ok();
  }

  // Calls f(Gathered<T>) on each per-particle value kept, with its buffer for the next
  // generation (as ParticlePoses::ForEachGathered).
  template <typename F>
  void ForEachGathered(F f) {
    if (active_) f(Gathered<AssociationCounts>{&counts_, &spare_counts_});
    if (!pending_.empty()) f(Gathered<ScanQuery>{&pending_, &spare_pending_});
  }

  // The checkpoint's part: the longest range and the counts.
  void Save(ByteWriter* w) const {
    w->Put<double>(max_range_);
    w->PutBytes(counts_.data(), counts_.size() * sizeof(AssociationCounts));
  }
  // What Save() wrote, read and checked by Read(); Restore() takes it.
  struct Saved {
    double max_range = 0;
    std::vector<AssociationCounts> counts;
  };
  Status Read(ByteReader* r, Saved* out) const {
    GROVE_RETURN_IF_ERROR(r->Get("longest range", &out->max_range));
    if (!(out->max_range >= 0) || !std::isfinite(out->max_range)) {
      return r->Error("longest range", "negative or not finite");
    }
    out->counts.resize(counts_.size());
    GROVE_RETURN_IF_ERROR(r->GetBytes("association counts", out->counts.data(),
                                      out->counts.size() * sizeof(AssociationCounts)));
    for (const AssociationCounts& c : out->counts) GROVE_RETURN_IF_ERROR(CheckCounts(r, c));
    return Status::Ok();
  }
  void Restore(Saved* saved) {
    max_range_ = saved->max_range;
    counts_.swap(saved->counts);
  }

  // Particles `which` for another rank: their counts and their kept queries.
  void Export(std::span<const uint32_t> which, ByteWriter* w) const {
    if (active_) {
      for (uint32_t i : which) w->Put(counts_[i]);
    }
    if (pending_.empty()) return;
    // An empty scan's query is not used after Advance() (and its view may name landmarks its
    // evidence removed): none is sent.
    const ScanQuery none;
    for (uint32_t i : which) {
      const ScanQuery& q = scan_size_ > 0 ? pending_[i] : none;
      w->Put<uint64_t>(q.matches.size());
      for (const Match& m : q.matches) {
        w->Put<uint32_t>(m.detection);
        w->Put<uint64_t>(m.key);
        w->Put<double>(m.log_likelihood);
        w->Put<double>(m.d2);
      }
      w->Put<uint64_t>(q.in_view.size());
      w->PutBytes(q.in_view.data(), q.in_view.size() * sizeof(uint64_t));
      if (!sampled_) continue;
      w->Put<uint64_t>(q.drawn.size());
      for (const Decision& d : q.drawn) {
        w->Put<uint8_t>(d.kind);
        w->Put<uint64_t>(d.key);
        w->Put<double>(d.log_likelihood);
      }
    }
  }

  // Appends `count` particles' counts and queries written by Export() after the `at` held here.
  Status Import(ByteReader* r, size_t at, size_t count) {
    const size_t end = at + count;
    if (active_) {
      counts_.resize(end);
      GROVE_RETURN_IF_ERROR(r->GetBytes("association counts", counts_.data() + at,
                                        count * sizeof(AssociationCounts)));
      for (size_t i = at; i < end; ++i) GROVE_RETURN_IF_ERROR(CheckCounts(r, counts_[i]));
    }
    if (!pending_.empty()) {
      pending_.resize(end);
      for (size_t i = at; i < end; ++i) GROVE_RETURN_IF_ERROR(ReadQuery(r, &pending_[i]));
    }
    return Status::Ok();
  }

  // Checks that the kept queries of the particles imported at `at` name landmarks of their own
  // maps, `roots` (the reader `r` names the error).
  Status CheckImported(ByteReader* r, const Trie& trie, std::span<Node* const> roots,
                       size_t at) const {
    Status s;
    for (size_t k = 0; k < roots.size() && s.ok() && !pending_.empty(); ++k) {
      const ScanQuery& q = pending_[at + k];
      auto known = [&](uint64_t key) { return trie.Find(roots[k], key) != nullptr; };
      for (const Match& m : q.matches) {
        if (!known(m.key)) s = r->Error("matches", "a match names a landmark not in the map");
      }
      for (uint64_t key : q.in_view) {
        if (!known(key)) s = r->Error("view", "a landmark in view is not in the map");
      }
      for (const Decision& d : q.drawn) {
        if (d.kind == Decision::kAssociated && !known(d.key)) {
          s = r->Error("decisions", "a drawn association names a landmark not in the map");
        }
      }
    }
    return s;
  }

 private:
  static Status CheckCounts(ByteReader* r, const AssociationCounts& c) {
    for (int64_t v : {c.associated, c.created, c.ignored, c.removed, c.dropped, c.tagged, c.wrong,
                      c.truncated}) {
      if (v < 0) return r->Error("association counts", "a count is negative");
    }
    return Status::Ok();
  }

  // A kept ScanQuery as Export() writes it: matches of this scan's detections, the view's
  // keys increasing (their landmarks are checked against the map once it is read).
  Status ReadQuery(ByteReader* r, ScanQuery* q) const {
    constexpr size_t kMatchBytes = sizeof(uint32_t) + sizeof(uint64_t) + 2 * sizeof(double);
    uint64_t count = 0;
    GROVE_RETURN_IF_ERROR(r->GetCount("match count", kMatchBytes, &count));
    q->matches.resize(count);
    for (Match& m : q->matches) {
      GROVE_RETURN_IF_ERROR(r->Get("match detection", &m.detection));
      GROVE_RETURN_IF_ERROR(r->Get("match key", &m.key));
      GROVE_RETURN_IF_ERROR(r->Get("match likelihood", &m.log_likelihood));
      GROVE_RETURN_IF_ERROR(r->Get("match distance", &m.d2));
      if (m.detection >= scan_size_ || std::isnan(m.log_likelihood) || !(m.d2 >= 0)) {
        return r->Error("matches", "a detection that is not the scan's, or a bad likelihood");
      }
    }
    GROVE_RETURN_IF_ERROR(r->GetCount("view count", sizeof(uint64_t), &count));
    q->in_view.resize(count);
    GROVE_RETURN_IF_ERROR(r->GetBytes("view", q->in_view.data(), count * sizeof(uint64_t)));
    for (size_t k = 1; k < count; ++k) {
      if (q->in_view[k] <= q->in_view[k - 1]) return r->Error("view", "keys not increasing");
    }
    q->drawn.clear();
    if (!sampled_) return Status::Ok();
    constexpr size_t kDecisionBytes = sizeof(uint8_t) + sizeof(uint64_t) + sizeof(double);
    GROVE_RETURN_IF_ERROR(r->GetCount("decision count", kDecisionBytes, &count));
    if (count != 0 && count != scan_size_) {
      return r->Error("decisions", "not one decision per detection of the scan");
    }
    q->drawn.resize(count);
    for (Decision& d : q->drawn) {
      uint8_t kind = 0;
      GROVE_RETURN_IF_ERROR(r->Get("decision kind", &kind));
      GROVE_RETURN_IF_ERROR(r->Get("decision key", &d.key));
      GROVE_RETURN_IF_ERROR(r->Get("decision likelihood", &d.log_likelihood));
      if (kind != Decision::kAssociated && kind != Decision::kNew) {
        return r->Error("decisions", "a drawn decision is neither associated nor new");
      }
      d.kind = static_cast<Decision::Kind>(kind);
      if (std::isnan(d.log_likelihood)) return r->Error("decisions", "a bad likelihood");
    }
    return Status::Ok();
  }

  // The decisions of `detections` detections from their matches under ml, ml_exclusive or jcbb,
  // into sc (sc->truncated: jcbb's search stopped at its node budget).
  void DecideBy(std::span<Match> matches, size_t detections, Scratch* sc) const {
    if (joint_) {
      sc->truncated = sc->jcbb.Decide(matches, detections, params_.reject_gate, joint_gates_,
                                      JointCompatibility::kDefaultNodeBudget, &sc->decisions);
    } else {
      sc->truncated = false;
      Decide(matches, detections, params_, &sc->decisions);
    }
  }

  // The first free slot of `cell` in the map `root`, or -1.
  static int FreeSlot(const Trie& trie, const Node* root, const Cell& cell) {
    for (int k = 0; k < kSlotsPerCell; ++k) {
      if (trie.Find(root, SpatialKey(cell, k)) == nullptr) return k;
    }
    return -1;
  }

  // ApplyScan's first stage: the updates of the associated landmarks, the keys of those whose
  // mean left its cell in sc->keys. The paths to them are copied first, with the evidence and the
  // counts (a path copied once is the particle's own, so the leaves noted stay where they are),
  // then the updates run together: the EKF map's in SIMD lanes (UpdateLandmarks()), the others'
  // leaf by leaf. Two detections associated with one landmark update it in turn.
  Status UpdateAssociated(const FilterSteps& steps, Trie* trie, Node** root, const ScanStep& scan,
                          size_t i, int slot, const VehiclePose& pose, Scratch* sc) {
    AssociationCounts& counts = counts_[i];
    sc->update_leaves.clear();
    sc->update_zs.clear();
    sc->update_detections.clear();
    size_t start = 0;  // the first noted update not yet applied
    auto apply = [&]() -> Status {
      const size_t n = sc->update_leaves.size() - start;
      Landmark* const* leaves = sc->update_leaves.data() + start;
      const RangeBearing* zs = sc->update_zs.data() + start;
      size_t failed = 0;
      Status s;
      if (steps.traits().map == FilterTraits::Map::kEkf) {
        s = UpdateLandmarks(pose, zs, leaves, steps.noise(), n, &failed);
      } else {
        for (; failed < n; ++failed) {
          s = steps.UpdateLeaf(pose, zs[failed], leaves[failed], nullptr);
          if (!s.ok()) break;
        }
      }
      if (!s.ok()) {
        return ParticleError(first_ + i, scan.observations[sc->update_detections[start + failed]],
                             s);
      }
      start = sc->update_leaves.size();
      return Status::Ok();
    };
    for (size_t j = 0; j < sc->decisions.size(); ++j) {
      const Decision& d = sc->decisions[j];
      const LandmarkObservation& z = scan.observations[j];
      if (d.kind == Decision::kIgnored) ++counts.ignored;
      if (d.kind != Decision::kAssociated) continue;
      if (std::find(sc->keys.begin() + static_cast<std::ptrdiff_t>(start), sc->keys.end(), d.key) !=
          sc->keys.end()) {
        GROVE_RETURN_IF_ERROR(apply());  // this landmark's earlier update first
      }
      Landmark* leaf = nullptr;
      int32_t tag = -1;
      const bool ok = trie->Update(root, d.key, slot, [&](Landmark& l, bool) {
        if (l.evidence < (1 << 30)) ++l.evidence;
        tag = l.tag;
        leaf = &l;
      });
      if (!ok) return NoMemoryError(first_ + i, "map");
      sc->update_leaves.push_back(leaf);
      sc->update_zs.push_back(RangeBearing{z.range_m, z.bearing_rad});
      sc->update_detections.push_back(static_cast<uint32_t>(j));
      ++counts.associated;
      if (z.id >= 0 && tag >= 0) {
        ++counts.tagged;
        counts.wrong += tag != z.id;
      }
      sc->keys.push_back(d.key);
    }
    GROVE_RETURN_IF_ERROR(apply());
    // Of the updated landmarks, only those whose mean left its cell stay in sc->keys for
    // MoveToNewCells(): the leaves noted are read while they are still where they are.
    size_t moved = 0;
    for (size_t k = 0; k < sc->keys.size(); ++k) {
      const Landmark& l = *sc->update_leaves[k];
      Cell cell;
      if (CellOf(l.x_m, l.y_m, params_.cell_m, &cell) && cell == CellOfKey(sc->keys[k])) continue;
      sc->keys[moved++] = sc->keys[k];
    }
    sc->keys.resize(moved);
    return Status::Ok();
  }

  // ApplyScan's second stage: the evidence of the landmarks in view and not seen (near no
  // detection's augment gate) falls; those below the threshold are removed.
  Status LowerMissed(Trie* trie, Node** root, size_t i, int slot, Scratch* sc) {
    std::vector<uint64_t>& touched = sc->keys;
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
      if (!trie->Update(root, touched[k], slot, [&](Landmark& l, bool) {
            --l.evidence;
            remove = l.evidence < evidence_threshold_;
          })) {
        return NoMemoryError(first_ + i, "map");
      }
      if (remove) {
        if (!trie->Erase(root, touched[k], slot)) return NoMemoryError(first_ + i, "map");
        ++counts_[i].removed;
      }
    }
    touched.resize(first_missed);
    return Status::Ok();
  }

  // ApplyScan's third stage: the updated landmarks whose mean left its cell (`moved`, from
  // UpdateAssociated(); reordered) move to a slot of their new cell.
  Status MoveToNewCells(Trie* trie, Node** root, size_t i, int slot, std::vector<uint64_t>* moved) {
    std::sort(moved->begin(), moved->end());
    moved->erase(std::unique(moved->begin(), moved->end()), moved->end());
    for (uint64_t key : *moved) {
      const Landmark l = *trie->Find(*root, key);
      if (!trie->Erase(root, key, slot)) return NoMemoryError(first_ + i, "map");
      GROVE_RETURN_IF_ERROR(Insert(trie, root, i, slot, l));
    }
    return Status::Ok();
  }

  const bool active_;
  const uint64_t first_;  // the filter's index of particle 0 here
  const AssociationParams params_;
  const double log_p0_;
  const bool sampled_;   // association = sampled
  const bool joint_;     // association = jcbb
  const uint64_t seed_;  // the random streams' (sampled association)
  const bool evidence_;
  const int64_t evidence_threshold_;
  const SensorView view_;
  double max_range_ = 0;                   // the longest detection range so far
  size_t scan_size_ = 0;                   // the last scan's detections (NoteScan())
  std::vector<double> joint_gates_;        // jcbb: chi2(2k) for k = 1.. (NoteScan())
  std::vector<AssociationCounts> counts_;  // per particle, along its ancestry
  // Each particle's query of the current scan, from Advance() to Complete().
  std::vector<ScanQuery> pending_;
  // The previous generation's, kept as the next gather's buffers.
  std::vector<AssociationCounts> spare_counts_;
  std::vector<ScanQuery> spare_pending_;
  mutable std::vector<Scratch> scratch_;  // per worker slot
};

}  // namespace grove::fastslam

#endif  // GROVE_ENGINE_FASTSLAM_UNKNOWN_ASSOCIATION_H_

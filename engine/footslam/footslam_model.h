// FootSlamModel: the FootSLAM particle (paper §II-B) for ParticleFilter, generic over the map.
//
// Per particle (structure of arrays): position, heading, heading error (a random walk), step
// scale error, the current hexagon, the path history and the map. One Advance() per step:
//   1. propagate: rotate and scale the odometry step by the particle's error states and add
//      white noise (paper steps 2a-2b);
//   2. for each hexagon edge the step crosses, in order: weight by the counters before the
//      crossing, then count it (steps 2c and 2e);
//   3. append the pose to the particle's history.
// Copies of one parent cross the same edges often (a step crosses about one edge, and copies
// differ only by this step's noise). Consecutive particles that hold one map at the start of the
// step form a group: the first holds its crossings back, and while the others repeat them, in
// order, they wait too; at the group's end the crossings are counted once (in place when the
// group holds every reference to the map) and every member takes the new map and weight. A
// member whose crossings differ ends the waiting there (the group's map is copied as before),
// and a particle whose map and crossings repeat the previous one's takes that one's result.
// Same contents, same weights: only the sharing changes.
#ifndef GROVE_ENGINE_FOOTSLAM_FOOTSLAM_MODEL_H_
#define GROVE_ENGINE_FOOTSLAM_FOOTSLAM_MODEL_H_

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "concurrency/normal_batch.h"
#include "concurrency/random_stream.h"
#include "concurrency/sin_cos.h"
#include "concurrency/worker_pool.h"
#include "engine/filter/generation.h"
#include "engine/footslam/footslam_map.h"
#include "engine/footslam/hex_grid.h"
#include "engine/footslam/htc.h"
#include "engine/footslam/htree_layout.h"
#include "engine/footslam/prior_map.h"
#include "engine/io/checkpoint_io.h"
#include "engine/persistent/ancestry.h"
#include "engine/persistent/version_set.h"
#include "engine/ranks/collective.h"
#include "grove/footslam.h"

namespace grove::footslam {

struct StepInput {
  double dx_m;
  double dy_m;
};

// A pose of a particle's path as its history keeps it: the position relative to the start, so
// that single precision keeps a path far from the origin (georeferenced coordinates) at the
// resolution of a path near it (about 0.1 mm at 1 km from the start), in a 32-byte node.
struct PathPose {
  float dx_m, dy_m, heading_rad;  // position minus the start position
};
using PoseHistory = Ancestry<PathPose>;

inline bool FinitePathPose(const PathPose& p) {
  return std::isfinite(p.dx_m) && std::isfinite(p.dy_m) && std::isfinite(p.heading_rad);
}

template <FootSlamMap Map>
class FootSlamModel {
 public:
  // REQUIRES: config.Validate() is ok. Call Init() before the first step. `share`: the
  // particles this model holds, of config.particles (a rank of a filter across ranks; default
  // all); particle i here is particle share.first + i of the filter, whose random streams it
  // draws. The map must hold share.count particles.
  FootSlamModel(const FootSlamConfig& config, const HexGrid* grid, const HTreeLayout* layout,
                Map* map, int slots, ParticleShare share = {})
      : config_(config),
        grid_(grid),
        layout_(layout),
        map_(map),
        history_(slots),
        first_(share.first),
        n_(share.count != 0 || share.first != 0 ? static_cast<size_t>(share.count)
                                                : static_cast<size_t>(config.particles)),
        max_step_crossings_(8 * int64_t{config.grid_size}),
        history_roots_(&history_, n_) {
    x_.assign(n_, config.start_x_m);
    y_.assign(n_, config.start_y_m);
    heading_.assign(n_, config.start_heading_rad);
    Unit start_unit;
    SinCosReference(&config.start_heading_rad, 1, &start_unit.s, &start_unit.c);
    heading_unit_.assign(n_, start_unit);
    heading_error_.resize(n_);
    scale_.resize(n_);
    Hex start = grid_->HexAt(config.start_x_m, config.start_y_m);
    start_hex_ = start;
    hex_.assign(n_, start);
    uint64_t start_key = 0;
    KeyOf(start, &start_key);  // the grid is centred on the start: always on it
    key_.assign(n_, start_key);
    for (size_t i = 0; i < n_; ++i) {
      RandomStream rs(config.seed, 0, static_cast<uint32_t>(first_ + i), StreamPurpose::kInit);
      heading_error_[i] = config.initial_heading_sigma_rad * rs.NextNormal();
      scale_[i] = 1.0 + config.scale_sigma * rs.NextNormal();
    }
    for (double sigma : {config.heading_drift_sigma_rad, config.scale_drift_sigma,
                         config.step_length_sigma_m, config.heading_sigma_rad}) {
      motion_draws_ += sigma > 0 ? 1 : 0;
    }
    motion_draws_ += config.position_sigma_m > 0 ? 2 : 0;
    if (config.weighting == FootSlamWeighting::kPriorRatio) log_edge_bias_ = std::log(6.0);
    for (uint32_t c = 0; c < kLogTable; ++c) {
      log_edge_[c] = std::log(c + config.prior_count) + log_edge_bias_;
      log_total_[c] = std::log(c + 6 * config.prior_count);
    }
  }

  // Gives every particle the shared start pose; false when out of memory.
  bool Init() {
    PoseHistory::Node* root = history_.Append(
        nullptr, 0, PathPoseOf(config_.start_x_m, config_.start_y_m, config_.start_heading_rad), 0);
    if (root == nullptr) return false;
    history_roots_.ShareAll(root);
    return true;
  }

  size_t size() const { return n_; }

  // The prior map the weighting adds to every particle's counters, or nullptr; it must outlive
  // the steps.
  void set_prior(const PriorMap* prior) { prior_ = prior; }

  // The hot loop: one step of particles [begin, end), in the stages the file comment lists.
  Status Advance(const StepInput& in, uint64_t step, size_t begin, size_t end, int slot,
                 double* log_w) {
    MotionBlock motion;
    motion.odo_length = std::hypot(in.dx_m, in.dy_m);
    motion.odo_heading = std::atan2(in.dy_m, in.dx_m) + config_.start_heading_rad;
    int levels = map_->height();
    if (levels > kMaxPathLevels) levels = kMaxPathLevels;
    // The previous particle's map at the start of the step, and the group it belongs to.
    typename Map::Version prev_version{};
    Group group;
    Crossed crossed[kMaxHeldCrossings];
    for (size_t i = begin; i < end; ++i) {
      PrefetchAhead(i, end, levels);
      const size_t at = (i - begin) % kNoiseBlock;
      if (at == 0) DrawMotion(step, i, std::min(end, i + kNoiseBlock), &motion);
      const double heading = motion.heading[at];
      const double cos_heading = motion.cos[at];
      const double sin_heading = motion.sin[at];
      double nx = x_[i] + motion.length[at] * cos_heading;
      double ny = y_[i] + motion.length[at] * sin_heading;
      if (config_.position_sigma_m > 0) {  // the last two deviates
        nx += config_.position_sigma_m * motion.noise[motion_draws_ - 2][at];
        ny += config_.position_sigma_m * motion.noise[motion_draws_ - 1][at];
      }
      if (!std::isfinite(nx) || !std::isfinite(ny) || !std::isfinite(heading)) {
        return PoseNotFinite(i, nx, ny, heading);
      }
      double lw = 0;
      bool outside = false, too_long = false, no_memory = false;
      // Counts a crossing in particle i's map and weights it.
      auto cross = [&](Crossed c) {
        if (WeighCrossing(i, c, 1, slot, &lw)) return true;
        no_memory = true;
        return false;
      };
      const typename Map::Version version = map_->version(i);
      if (group.pending && version != prev_version && !Resolve(&group, i, slot, log_w)) {
        return NoMemory(first_ + group.leader, "map");
      }
      // While `holding`, the crossings so far repeat the previous particle's and are not yet
      // counted; at the first that differs they are counted, in order (and a pending group
      // parts there). While `deferring`, i leads a group: the next particle's map is its.
      bool holding = group.count >= 0 && version == prev_version;
      bool deferring = !holding && i + 1 < end && map_->version(i + 1) == version;
      int count = 0;  // crossings recorded in `crossed`; -1 past kMaxHeldCrossings
      // A particle that leaves the grid, or a step that crosses more hexagons than a straight
      // line across the first grid can, ends the run: stop walking there, so a step of any
      // length costs at most a few times the first grid's width.
      int64_t crossings = 0;
      Hex end_hex = grid_->Traverse(hex_[i], x_[i], y_[i], nx, ny, [&](const Crossing& c) {
        uint64_t key = key_[i];  // the first crossing leaves the particle's hexagon
        if (crossings != 0 && !KeyOf(c.from, &key)) {
          outside = true;
          return false;
        }
        if (++crossings > max_step_crossings_) {
          too_long = true;
          return false;
        }
        const Crossed now{key, c.edge};
        if (holding) {
          if (count < group.count && now == group.crossed[count]) {
            crossed[count++] = now;
            return true;
          }
          holding = false;
          if (group.pending && !Resolve(&group, i, slot, log_w)) {
            no_memory = true;
            return false;
          }
          for (int k = 0; k < count; ++k) {
            if (!cross(crossed[k])) return false;
          }
        } else if (deferring) {
          if (count < kMaxHeldCrossings) {
            crossed[count++] = now;
            return true;
          }
          deferring = false;
          for (int k = 0; k < count; ++k) {
            if (!cross(crossed[k])) return false;
          }
        }
        if (count >= 0 && count < kMaxHeldCrossings) {
          crossed[count++] = now;
        } else {
          count = -1;
        }
        return cross(now);
      });
      bool waits = false;  // i's weight comes when its group is resolved
      if (holding && !outside && !too_long) {
        if (count == group.count && group.pending) {  // one more member of the group
          waits = true;
        } else if (count == group.count) {  // the same crossings: the same new map and weight
          if (count > 0) map_->Share(i, i - 1, slot);
          lw = group.lw;
        } else {  // a prefix of them
          if (group.pending && !Resolve(&group, i, slot, log_w)) no_memory = true;
          for (int k = 0; k < count && !no_memory; ++k) cross(crossed[k]);
        }
      } else if (deferring && !outside && !too_long) {
        group.pending = true;
        group.leader = i;
        waits = true;
      }
      if (no_memory) return NoMemory(first_ + i, "map");
      if (too_long) return StepTooLong(i, nx, ny);
      uint64_t end_key;
      if (outside || !KeyOf(end_hex, &end_key)) return LeftGrid(i, nx, ny);
      PoseHistory::Node* pose = history_.Append(history_roots_[i], static_cast<uint32_t>(step + 1),
                                                PathPoseOf(nx, ny, heading), slot);
      if (pose == nullptr) return NoMemory(first_ + i, "path");
      history_roots_[i] = pose;
      if (!waits) log_w[i] += lw;
      x_[i] = nx;
      y_[i] = ny;
      heading_[i] = heading;
      heading_unit_[i] = {cos_heading, sin_heading};
      hex_[i] = end_hex;
      key_[i] = end_key;
      prev_version = version;
      std::copy(crossed, crossed + std::max(count, 0), group.crossed);
      group.count = count;
      group.lw = lw;
    }
    if (group.pending && !Resolve(&group, end, slot, log_w)) {
      return NoMemory(first_ + group.leader, "map");
    }
    return Status::Ok();
  }

  void Gather(std::span<const uint32_t> parents, WorkerPool& workers) {
    n_ = parents.size();
    GatherValuesTogether(
        parents, workers, Gathered<double>{&x_, &spare_.x}, Gathered<double>{&y_, &spare_.y},
        Gathered<double>{&heading_, &spare_.heading},
        Gathered<double>{&heading_error_, &spare_.heading_error},
        Gathered<double>{&scale_, &spare_.scale}, Gathered<Unit>{&heading_unit_, &spare_.units},
        Gathered<Hex>{&hex_, &spare_.hexes}, Gathered<uint64_t>{&key_, &spare_.keys});
    history_roots_.Gather(parents, workers);
    map_->Gather(parents, workers);
  }

  void ReleaseDead(WorkerPool& workers) {
    history_roots_.ReleaseDead(workers);
    map_->ReleaseDead(workers);
  }
  // ReleaseDead() in pieces during the next advance (ParticleFilter's PieceReleasingModel).
  void ReleaseDeadRange(size_t lo, size_t hi, int slot) {
    history_roots_.ReleaseDeadRange(lo, hi, slot);
    map_->ReleaseDeadRange(lo, hi, slot);
  }
  void DeadReleased() {
    history_roots_.DeadReleased();
    map_->DeadReleased();
  }

  // The expensive invariant walk of every shared node: histories and maps (tests).
  Status CheckCounts() const {
    GROVE_RETURN_IF_ERROR(history_.CheckCounts(history_roots_.AllReferences()));
    return map_->CheckCounts();
  }

  // log(C_h^e + a) (+ log 6 for the prior-ratio weighting) and log(C_h + 6a), from tables for
  // small counts: a crossing costs two loads instead of a logarithm.
  double LogEdge(uint32_t c) const {
    return c < kLogTable ? log_edge_[c] : std::log(c + config_.prior_count) + log_edge_bias_;
  }
  double LogTotal(uint32_t c) const {
    return c < kLogTable ? log_total_[c] : std::log(c + 6 * config_.prior_count);
  }

  // The H-tree grid is centred on the start hexagon.
  bool KeyOf(Hex h, uint64_t* key) const {
    return layout_->KeyOf(Hex{h.q - start_hex_.q, h.r - start_hex_.r}, key);
  }
  Hex HexOfKey(uint64_t key) const {
    Hex h = layout_->HexOfKey(key);
    return Hex{h.q + start_hex_.q, h.r + start_hex_.r};
  }

  // The particles' state after a step: pose, error states, hexagon and path history.
  void Save(ByteWriter* w) const {
    w->Put<uint64_t>(n_);
    for (const std::vector<double>* v : {&x_, &y_, &heading_, &heading_error_, &scale_}) {
      w->PutBytes(v->data(), n_ * sizeof(double));
    }
    w->PutBytes(hex_.data(), n_ * sizeof(Hex));
    PoseHistory::Save(history_roots_.roots(), w);
  }

  // Replaces the state of a new model with a saved one taken after step `steps`.
  Status Load(ByteReader* r, uint64_t steps) {
    GROVE_RETURN_IF_ERROR(ReadParticleCount(r, n_));
    GROVE_RETURN_IF_ERROR(ReadValues(r, 0, n_));
    if (steps >= UINT32_MAX) return r->Error("step", "too many steps");
    std::vector<PoseHistory::Node*> heads;
    GROVE_RETURN_IF_ERROR(ReadPaths(r, n_, steps, &heads));
    history_roots_.Replace(std::move(heads));
    return Status::Ok();
  }

  // Particles `which` (increasing) for another rank: their values, their paths and their maps,
  // each shared entry and node written once.
  void Export(std::span<const uint32_t> which, ByteWriter* w) const {
    for (const std::vector<double>* v : {&x_, &y_, &heading_, &heading_error_, &scale_}) {
      for (uint32_t i : which) w->Put((*v)[i]);
    }
    for (uint32_t i : which) w->Put(hex_[i]);
    PoseHistory::Save(history_roots_.Pick(which), w);
    map_->SaveSome(which, w);
  }

  // Appends `count` particles written by Export() after step `steps`: size() grows by count
  // until the next Gather(). On error the model must not step again.
  Status Import(ByteReader* r, size_t count, uint64_t steps) {
    if (count > r->remaining() / (5 * sizeof(double) + sizeof(Hex))) {
      return r->Error("particle count", "larger than the message");
    }
    const size_t at = n_;
    for (std::vector<double>* v : {&x_, &y_, &heading_, &heading_error_, &scale_}) {
      v->resize(at + count);
    }
    heading_unit_.resize(at + count);
    hex_.resize(at + count);
    key_.resize(at + count);
    GROVE_RETURN_IF_ERROR(ReadValues(r, at, at + count));
    if (steps >= UINT32_MAX) return r->Error("step", "too many steps");
    std::vector<PoseHistory::Node*> heads;
    GROVE_RETURN_IF_ERROR(ReadPaths(r, count, steps, &heads));
    if (Status s = map_->LoadMore(r, count, layout_->key_count()); !s.ok()) {
      for (auto* h : heads) history_.Release(h, 0);
      return s;
    }
    history_roots_.Append(heads);
    n_ = at + count;
    return Status::Ok();
  }

  double x(size_t i) const { return x_[i]; }
  double y(size_t i) const { return y_[i]; }
  double heading(size_t i) const { return heading_[i]; }
  // cos(heading(i)) and sin(heading(i)) by SinCos (within 2 ulp of std::cos and std::sin),
  // kept from the motion that set the heading.
  double cos_heading(size_t i) const { return heading_unit_[i].c; }
  double sin_heading(size_t i) const { return heading_unit_[i].s; }
  double scale(size_t i) const { return scale_[i]; }
  double heading_error(size_t i) const { return heading_error_[i]; }
  const PoseHistory::Node* history(size_t i) const { return history_roots_[i]; }
  // A pose of a path in the map frame.
  Pose2 PoseOf(const PathPose& p) const {
    return Pose2{config_.start_x_m + p.dx_m, config_.start_y_m + p.dy_m, p.heading_rad};
  }
  const PoseHistory& history() const { return history_; }
  const Map& map() const { return *map_; }

 private:
  PathPose PathPoseOf(double x, double y, double heading) const {
    return PathPose{static_cast<float>(x - config_.start_x_m),
                    static_cast<float>(y - config_.start_y_m), static_cast<float>(heading)};
  }
  // Reads particles [begin, end)'s values as Save() writes them (each array in turn) and checks
  // them; derives their sines, cosines and keys.
  Status ReadValues(ByteReader* r, size_t begin, size_t end) {
    const size_t count = end - begin;
    const char* names[] = {"x", "y", "heading", "heading error", "scale"};
    std::vector<double>* vectors[] = {&x_, &y_, &heading_, &heading_error_, &scale_};
    for (int k = 0; k < 5; ++k) {
      GROVE_RETURN_IF_ERROR(
          r->GetBytes(names[k], vectors[k]->data() + begin, count * sizeof(double)));
      for (size_t i = begin; i < end; ++i) {
        if (!std::isfinite((*vectors[k])[i])) return r->Error(names[k], "a value is not finite");
      }
    }
    // Derived state: the same calls on the same values as in Advance(), so bit-identical.
    for (size_t i = begin; i < end; ++i) {
      double c, s;
      SinCosReference(&heading_[i], 1, &s, &c);
      heading_unit_[i] = {c, s};
    }
    GROVE_RETURN_IF_ERROR(r->GetBytes("hexagon", hex_.data() + begin, count * sizeof(Hex)));
    // Every hexagon of the grid lies within this distance of the start on each axis.
    const double extent = (layout_->max_grid_size() + 2.0) * 2.0 * grid_->radius_m();
    for (size_t i = begin; i < end; ++i) {
      const size_t id = i - begin;  // the particle's place in what is read
      if (std::abs(x_[i] - config_.start_x_m) > extent ||
          std::abs(y_[i] - config_.start_y_m) > extent) {
        return r->Error("x", "particle " + std::to_string(id) + " is far outside the grid");
      }
      // The hexagon is where the particle stands (or a neighbour, for a point on an edge), on
      // the grid.
      Hex at = grid_->HexAt(x_[i], y_[i]);
      int64_t dq = int64_t{hex_[i].q} - at.q, dr = int64_t{hex_[i].r} - at.r;
      uint64_t key;
      if (std::max({std::abs(dq), std::abs(dr), std::abs(dq + dr)}) > 1 || !KeyOf(hex_[i], &key)) {
        return r->Error("hexagon", "particle " + std::to_string(id) +
                                       " is not on the grid or not in the hexagon of its position");
      }
      key_[i] = key;
    }
    return Status::Ok();
  }

  // Reads `count` paths as PoseHistory::Save() writes them, each ending at step `steps`.
  Status ReadPaths(ByteReader* r, size_t count, uint64_t steps,
                   std::vector<PoseHistory::Node*>* heads) {
    GROVE_RETURN_IF_ERROR(
        history_.Load(r, count, static_cast<uint32_t>(steps), 0, &FinitePathPose, heads));
    for (size_t i = 0; i < count; ++i) {
      if ((*heads)[i] == nullptr || (*heads)[i]->step != steps) {
        for (auto* h : *heads) history_.Release(h, 0);
        heads->clear();
        return r->Error("path head", "particle " + std::to_string(i) +
                                         "'s path does not end at the checkpoint's step");
      }
    }
    return Status::Ok();
  }

  static constexpr size_t kPrefetchAhead = 4;
  static constexpr size_t kPathGap = 2;
  static constexpr int kMaxPathLevels = 8;
  static constexpr uint32_t kLogTable = 256;
  static constexpr size_t kNoiseBlock = 256;
  static constexpr int kMaxHeldCrossings = 8;  // a particle with more is not followed

  // A crossing as a follower compares it: the hexagon's key and the edge.
  struct Crossed {
    uint64_t key;
    int edge;
    bool operator==(const Crossed&) const = default;
  };

  // The motion of kNoiseBlock particles at a time (Advance's first stage): the odometry step's
  // length and heading, the normal deviates of each particle, then its step's length and
  // heading and the heading's sine and cosine.
  struct MotionBlock {
    double odo_length, odo_heading;
    double noise[kMaxBatchNormals][kNoiseBlock];
    double length[kNoiseBlock], heading[kNoiseBlock], sin[kNoiseBlock], cos[kNoiseBlock];
  };

  // Particles following one another (Advance's second stage): the previous particle's
  // crossings (count -1: not to be followed) and weight, and the group: particles from `leader`
  // on whose maps are one at the start of the step. While `pending`, the leader's crossings
  // wait and every member so far repeats them.
  struct Group {
    Crossed crossed[kMaxHeldCrossings];
    int count = -1;
    double lw = 0;
    size_t leader = 0;
    bool pending = false;
  };

  // Particles are independent: start the cache misses of later ones while this one runs. A
  // particle's first crossing (if any) leaves its current hexagon, so its map path is known
  // before its motion is drawn: particle i + kPathGap * (levels - depth) has the node at
  // `depth` of that path loaded, one level deeper every kPathGap particles.
  [[gnu::always_inline]] void PrefetchAhead(size_t i, size_t end, int levels) const {
    if (i + kPrefetchAhead < end) {
      if (levels == 0) map_->Prefetch(i + kPrefetchAhead);
      __builtin_prefetch(history_roots_[i + kPrefetchAhead]);
    }
    for (int depth = 0; depth < levels; ++depth) {
      const size_t j = i + kPathGap * static_cast<size_t>(levels - depth);
      if (j < end) map_->PrefetchPath(j, key_[j], depth);
    }
  }

  // The motion of particles [begin, end) at `step` into *m: the deviates (the first
  // motion_draws_ of each particle's stream for this step), the error states, lengths and
  // headings, then the headings' sines and cosines.
  void DrawMotion(uint64_t step, size_t begin, size_t end, MotionBlock* m) {
    if (motion_draws_ > 0) {
      double* noise[kMaxBatchNormals];
      for (int k = 0; k < kMaxBatchNormals; ++k) noise[k] = m->noise[k];
      DrawNormals(config_.seed, step + 1, StreamPurpose::kMotion,
                  static_cast<uint32_t>(first_ + begin), static_cast<uint32_t>(first_ + end),
                  std::span<double* const>(noise, static_cast<size_t>(motion_draws_)));
    }
    for (size_t k = begin; k < end; ++k) {
      const size_t b = k - begin;
      int draw = 0;
      auto normal = [&] { return m->noise[draw++][b]; };
      if (config_.heading_drift_sigma_rad > 0) {
        heading_error_[k] += config_.heading_drift_sigma_rad * normal();
      }
      if (config_.scale_drift_sigma > 0) scale_[k] += config_.scale_drift_sigma * normal();
      double length = m->odo_length * scale_[k];
      if (config_.step_length_sigma_m > 0) length += config_.step_length_sigma_m * normal();
      double heading = m->odo_heading + heading_error_[k];
      if (config_.heading_sigma_rad > 0) heading += config_.heading_sigma_rad * normal();
      m->length[b] = length;
      m->heading[b] = heading;
    }
    SinCos(m->heading, end - begin, m->sin, m->cos);
  }

  // Counts crossing c in particle p's map (held by `owners` particles that all take the result)
  // and adds its weight to *lw; false when out of memory.
  bool WeighCrossing(size_t p, Crossed c, uint32_t owners, int slot, double* lw) {
    EdgeCounts before;
    if (!map_->Cross(p, c.key, c.edge, slot, &before, owners)) return false;
    const PriorHex* prior = prior_ == nullptr ? nullptr : prior_->Find(c.key);
    if (prior == nullptr) {
      *lw += LogEdge(before.edge) - LogTotal(before.total);
    } else {
      // The counts first, then a, as LogEdge() and LogTotal() add them: with a prior that
      // holds whole counts this is bit for bit the weight of a map holding their sum.
      *lw += std::log(before.edge + prior->edge[c.edge] + config_.prior_count) + log_edge_bias_ -
             std::log(before.total + prior->total + 6 * config_.prior_count);
    }
    return true;
  }

  // Counts the group's crossings once for its members [g->leader, upto), in place when these
  // hold every reference to the map, and gives every member the new map and the weight (adding
  // it to log_w); false when out of memory.
  bool Resolve(Group* g, size_t upto, int slot, double* log_w) {
    g->pending = false;
    double group_lw = 0;
    const auto owners = static_cast<uint32_t>(upto - g->leader);
    for (int k = 0; k < g->count; ++k) {
      if (!WeighCrossing(g->leader, g->crossed[k], owners, slot, &group_lw)) return false;
    }
    for (size_t j = g->leader + 1; j < upto; ++j) {
      if (map_->version(j) != map_->version(g->leader)) map_->Share(j, g->leader, slot);
    }
    for (size_t j = g->leader; j < upto; ++j) log_w[j] += group_lw;
    g->lw = group_lw;
    return true;
  }

  // The errors that end a step at particle i, whose step goes to (nx, ny).
  [[gnu::cold]] Status PoseNotFinite(size_t i, double nx, double ny, double heading) const {
    return FailedPreconditionError(
        fmt::format("particle {}'s pose ({}, {}, {}) is not finite: the motion noise is too large",
                    first_ + i, nx, ny, heading));
  }
  [[gnu::cold]] Status StepTooLong(size_t i, double nx, double ny) const {
    return OutOfRangeError(fmt::format(
        "particle {}'s step from ({:.7g}, {:.7g}) to ({:.7g}, {:.7g}) m crosses more than {} "
        "hexagons, 8 x grid_size: the odometry or the motion noise is wrong",
        first_ + i, x_[i], y_[i], nx, ny, max_step_crossings_));
  }
  [[gnu::cold]] Status LeftGrid(size_t i, double nx, double ny) const {
    const bool fixed = config_.grid == FootSlamGrid::kFixed;
    return OutOfRangeError(fmt::format(
        "particle {} at ({:.7g}, {:.7g}) m left the {} x {} hexagon grid {}; {}", first_ + i, nx,
        ny, layout_->max_grid_size(), layout_->max_grid_size(),
        fixed ? "centred on the start" : "around the start, the largest a grid grows to",
        fixed ? "raise grid_size or let the grid grow (grid = growing)"
              : "the motion noise is too large or the odometry wrong"));
  }

  static Status NoMemory(size_t i, const char* what) {
    return ResourceExhaustedError(fmt::format("out of memory for particle {}'s {}", i, what));
  }

  const FootSlamConfig config_;
  const HexGrid* grid_;
  const HTreeLayout* layout_;
  Map* map_;
  const PriorMap* prior_ = nullptr;
  PoseHistory history_;
  uint64_t first_;  // the filter's index of particle 0 here
  size_t n_;
  int motion_draws_ = 0;        // normal deviates per particle-step: one per noise term in use
  int64_t max_step_crossings_;  // 8 x grid_size: more than a straight line across the first grid
  double log_edge_bias_ = 0;
  double log_edge_[kLogTable];
  double log_total_[kLogTable];
  std::vector<double> x_, y_, heading_, heading_error_, scale_;
  struct Unit {
    double c, s;
  };
  std::vector<Unit> heading_unit_;
  Hex start_hex_;
  std::vector<Hex> hex_;
  std::vector<uint64_t> key_;  // KeyOf(hex_[i]): the H-tree key of the particle's hexagon
  // Gather's buffers, kept between generations.
  struct {
    std::vector<double> x, y, heading, heading_error, scale;
    std::vector<Unit> units;
    std::vector<Hex> hexes;
    std::vector<uint64_t> keys;
  } spare_;
  VersionSet<PoseHistory> history_roots_;
};

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_FOOTSLAM_MODEL_H_

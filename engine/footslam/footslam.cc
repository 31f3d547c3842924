// The FootSLAM facade: an engine per map kind on the generic FilterDriver, its read-outs,
// checkpoints and memory estimate.
#include "grove/footslam.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <thread>
#include <tuple>
#include <unordered_map>

#include "concurrency/worker_pool.h"
#include "engine/filter/filter_driver.h"
#include "engine/footslam/alphabet.h"
#include "engine/footslam/alphabet_htree_map.h"
#include "engine/footslam/footslam_model.h"
#include "engine/footslam/hex_grid.h"
#include "engine/footslam/htree_layout.h"
#include "engine/footslam/htree_map.h"
#include "engine/footslam/naive_map.h"
#include "engine/io/checkpoint_io.h"
#include "engine/persistent/persistent_trie.h"
#include "engine/ranks/collective.h"

namespace grove {

using footslam::Alphabet;
using footslam::AlphabetHTreeMap;
using footslam::FootSlamModel;
using footslam::Hex;
using footslam::HexGrid;
using footslam::Htc;
using footslam::HTreeLayout;
using footslam::HTreeMap;
using footslam::NaiveMap;
using footslam::PriorHex;
using footslam::PriorMap;
using footslam::StepInput;

namespace {

// Weights in fixed point (2^-52 units) make the cumulative map an exact integer sum, the same
// whichever nodes happen to be shared, so it is bit-identical at any thread count.
constexpr double kWeightScale = 4503599627370496.0;  // 2^52

constexpr char kCheckpointKind[] = "grove footslam";
// FootSLAM's checkpoint body layout; bumped whenever it changes. 2: path positions relative to
// the start, the filter's count of weighting steps. 3: the grid field, maps grown past
// the first grid. 4: the stored map of storage of diversity. 5: the island fields. 6: the
// alphabet's symbol tree with bottom nodes of two H-tree levels (degrees 4 and 16).
constexpr uint32_t kFootSlamFormatVersion = 6;

// Storage of diversity looks for blocks to store after every kStoreEverySteps-th step: often
// enough that an area is stored soon after the walk leaves it (50 steps, about 35 m), rarely
// enough that listing the blocks (every distinct node above them) costs little per step.
constexpr int64_t kStoreEverySteps = 50;

// The counts a fold gives one edge: sum / total, whole when every particle held the same count.
double MeanOf(unsigned __int128 sum, unsigned __int128 total) {
  return static_cast<double>(sum / total) +
         static_cast<double>(sum % total) / static_cast<double>(total);
}

// A pose of the smoothed path with the sum of the weights (fixed point) of the particles whose
// ancestry holds it at that step.
struct SmoothedPart {
  uint32_t step;
  footslam::PathPose pose;
  unsigned __int128 weight;
};
static_assert(sizeof(SmoothedPart) == 32, "no padding: parts are compared and sent as bytes");

// Sorts parts by step, then by the bits of the pose, merging equal ones (weights added, exactly):
// the same list whichever paths share which nodes, so the smoothed path's sums are taken in an
// order that depends on the poses alone.
void MergeParts(std::vector<SmoothedPart>* parts) {
  auto key = [](const SmoothedPart& p) {
    return std::make_tuple(p.step, std::bit_cast<uint32_t>(p.pose.dx_m),
                           std::bit_cast<uint32_t>(p.pose.dy_m),
                           std::bit_cast<uint32_t>(p.pose.heading_rad));
  };
  std::sort(parts->begin(), parts->end(),
            [&](const SmoothedPart& a, const SmoothedPart& b) { return key(a) < key(b); });
  size_t out = 0;
  for (size_t i = 0; i < parts->size(); ++i) {
    if (out > 0 && key((*parts)[out - 1]) == key((*parts)[i])) {
      (*parts)[out - 1].weight += (*parts)[i].weight;
    } else {
      (*parts)[out++] = (*parts)[i];
    }
  }
  parts->resize(out);
}

}  // namespace

class FootSlam::Impl {
 public:
  virtual ~Impl() = default;
  virtual Status Init() = 0;
  virtual Status Step(double t_s, double dx_m, double dy_m) = 0;
  virtual Status SetStartTime(double t_s) = 0;
  virtual Status SetPriorMap(const std::vector<HexCounts>& map) = 0;
  virtual const FootSlamConfig& config() const = 0;
  virtual int64_t steps() const = 0;
  virtual Pose2 HeaviestPose() const = 0;
  virtual Pose2 MeanPose() const = 0;
  virtual StatusOr<std::vector<StampedPose>> HeaviestTrajectory() const = 0;
  virtual StatusOr<std::vector<StampedPose>> SmoothedTrajectory() const = 0;
  virtual const std::vector<StampedPose>& MeanTrajectory() const = 0;
  virtual StatusOr<std::vector<HexCounts>> CumulativeMap() const = 0;
  virtual StatusOr<std::vector<HexCounts>> HeaviestMap() const = 0;
  virtual std::vector<HexCounts> StoredMap() const = 0;
  virtual FootSlamSummary Summary() const = 0;
  virtual StatusOr<std::string> Save(std::string_view user_data) const = 0;
  // Replaces the state of a freshly created engine with the rest of a checkpoint body.
  virtual Status Load(ByteReader* r) = 0;
  virtual Status CheckInvariants() const = 0;
};

namespace {

template <typename Map>
class Engine final : public FootSlam::Impl {
 public:
  Engine(const FootSlamConfig& config, int threads, HTreeLayout layout,
         std::unique_ptr<const Alphabet> alphabet, Collective* ranks)
      : config_(config),
        ranks_(ranks),
        share_(ShareOf(static_cast<uint64_t>(config.particles), ranks, kSumBlock)),
        workers_(threads),
        grid_(config.hex_radius_m),
        layout_(std::move(layout)),
        alphabet_(std::move(alphabet)),
        map_(layout_, workers_.num_slots(), static_cast<size_t>(share_.count), alphabet_.get()),
        model_(config, &grid_, &layout_, &map_, workers_.num_slots(), share_),
        driver_(&model_, &workers_, FilterOptionsOf(config, ranks), config.threads,
                Pose2{config.start_x_m, config.start_y_m, config.start_heading_rad},
                TimeOrder::kIncreasing) {
    // Blocks: the largest subtrees no wider than the store distance, below the first grid's
    // root (Validate() asks for a first grid of at least two levels).
    const double hex_width = std::sqrt(3.0) * config.hex_radius_m;
    const int side_bits = layout_.log2_degree() / 2;
    int level = 0;
    while (level + 1 <= layout_.height() - 2 &&
           std::ldexp(hex_width, side_bits * (level + 2)) <= config.store_distance_m) {
      ++level;
    }
    store_bits_ = layout_.log2_degree() * (level + 1);
  }

  Status Init() override {
    if (!model_.Init()) return ResourceExhaustedError("out of memory for the start pose");
    return Status::Ok();
  }

  Status Step(double t_s, double dx_m, double dy_m) override {
    if (!std::isfinite(t_s) || !std::isfinite(dx_m) || !std::isfinite(dy_m)) {
      return InvalidArgumentError(
          fmt::format("step {}: t = {}, dx = {}, dy = {}: every value must be finite",
                      driver_.steps() + 1, t_s, dx_m, dy_m));
    }
    GROVE_RETURN_IF_ERROR(driver_.Update(t_s, StepInput{dx_m, dy_m}));
    if constexpr (kCanStore) {
      if (config_.store_distance_m > 0 && driver_.steps() % kStoreEverySteps == 0) {
        return driver_.AfterStep([&] { return StoreFarBlocks(); });
      }
    }
    return Status::Ok();
  }

  Status SetStartTime(double t_s) override { return driver_.SetStartTime(t_s); }

  Status SetPriorMap(const std::vector<HexCounts>& map) override {
    if (driver_.steps() != 0) {
      return FailedPreconditionError("a prior map must be set before the first step");
    }
    PriorMap prior;
    int64_t outside = 0;
    for (size_t k = 0; k < map.size(); ++k) {
      const HexCounts& h = map[k];
      PriorHex p{};
      for (int e = 0; e < 6; ++e) {
        if (!std::isfinite(h.counts[e]) || h.counts[e] < 0) {
          return InvalidArgumentError(
              fmt::format("prior map row {} (q = {}, r = {}): c{} = {}: counts must be finite "
                          "and >= 0",
                          k, h.q, h.r, e, h.counts[e]));
        }
        p.edge[e] = config_.prior_map_confidence * h.counts[e];
        p.total += p.edge[e];
      }
      if (!std::isfinite(p.total)) {
        return InvalidArgumentError(fmt::format(
            "prior map row {} (q = {}, r = {}): the counts times prior_map_confidence = {} "
            "overflow",
            k, h.q, h.r, config_.prior_map_confidence));
      }
      uint64_t key;
      if (!model_.KeyOf(Hex{h.q, h.r}, &key)) {
        ++outside;
        continue;
      }
      if (!prior.Insert(key, p)) {
        return InvalidArgumentError(
            fmt::format("prior map row {}: hexagon (q = {}, r = {}) is given twice", k, h.q, h.r));
      }
    }
    UsePrior(std::move(prior), outside);
    return Status::Ok();
  }
  const FootSlamConfig& config() const override { return config_; }
  int64_t steps() const override { return driver_.steps(); }

  Pose2 HeaviestPose() const override {
    std::vector<Pose2> mine;
    size_t i;
    if (Holds(driver_.filter().heaviest(), &i)) {
      mine.push_back(Pose2{model_.x(i), model_.y(i), model_.heading(i)});
    }
    // Across ranks, from the rank that holds it (the mean pose if that fails).
    StatusOr<std::vector<Pose2>> all = Gathered(std::move(mine));
    return all.ok() && all->size() == 1 ? all->front() : MeanPose();
  }
  Pose2 MeanPose() const override { return driver_.mean_trajectory().back().pose; }

  StatusOr<std::vector<StampedPose>> HeaviestTrajectory() const override {
    std::vector<StampedPose> out;
    const std::vector<double>& times = driver_.times();
    size_t i;
    if (Holds(driver_.filter().heaviest(), &i)) {
      for (const auto* n : footslam::PoseHistory::Path(model_.history(i))) {
        out.push_back({times[n->step], model_.PoseOf(n->value)});
      }
    }
    return Gathered(std::move(out));
  }
  const std::vector<StampedPose>& MeanTrajectory() const override {
    return driver_.mean_trajectory();
  }

  StatusOr<std::vector<StampedPose>> SmoothedTrajectory() const override {
    const size_t n = model_.size();
    std::vector<const footslam::PoseHistory::Node*> heads(n);
    const std::vector<uint64_t> fixed = FixedWeights();
    const std::vector<unsigned __int128> weights(fixed.begin(), fixed.end());
    uint32_t newest = 0;
    for (size_t i = 0; i < n; ++i) {
      heads[i] = model_.history(i);
      if (heads[i] != nullptr) newest = std::max(newest, heads[i]->step);
    }
    StatusOr<std::vector<uint32_t>> newest_all = Gathered(std::vector<uint32_t>{newest});
    if (!newest_all.ok()) return newest_all.status();
    const uint32_t last = *std::max_element(newest_all->begin(), newest_all->end());
    const std::vector<double>& times = driver_.times();
    if (last >= times.size()) {
      return InternalError(fmt::format("smoothed path: a path entry of step {} but {} step times",
                                       last, times.size()));
    }
    // Smooth() visits the steps from the last back to the first; each step's distinct poses
    // (across ranks, every rank's, merged) are summed in their sorted order once the step is
    // complete. Every rank has a pose at every step, so every rank gathers once per step.
    struct Sum {
      double w = 0, x = 0, y = 0, c = 0, s = 0;
    };
    std::vector<Sum> sums(last + 1);
    std::vector<SmoothedPart> level;
    Status status;
    auto sum_level = [&] {
      if (level.empty() || !status.ok()) return;
      const uint32_t k = level.front().step;
      MergeParts(&level);
      if (ranks_ != nullptr) {
        StatusOr<std::vector<SmoothedPart>> all = Gathered(std::move(level));
        if (!all.ok()) {
          status = all.status();
          return;
        }
        level = std::move(all).value();
        MergeParts(&level);
      }
      Sum& s = sums[k];
      for (const SmoothedPart& part : level) {
        const Pose2 pose = model_.PoseOf(part.pose);
        const double w = static_cast<double>(part.weight);
        s.w += w;
        s.x += w * pose.x_m;
        s.y += w * pose.y_m;
        s.c += w * std::cos(pose.heading_rad);
        s.s += w * std::sin(pose.heading_rad);
      }
      level.clear();
    };
    footslam::PoseHistory::Smooth<unsigned __int128>(
        heads, weights, last, [&](uint32_t k, unsigned __int128 w, const footslam::PathPose& p) {
          if (!level.empty() && level.front().step != k) sum_level();
          level.push_back({k, p, w});
        });
    sum_level();
    GROVE_RETURN_IF_ERROR(status);
    std::vector<StampedPose> out(last + 1);
    for (uint32_t k = 0; k <= last; ++k) {
      const Sum& s = sums[k];
      out[k] = {times[k], Pose2{s.x / s.w, s.y / s.w, std::atan2(s.s, s.c)}};
    }
    return out;
  }

  StatusOr<std::vector<HexCounts>> CumulativeMap() const override {
    const std::vector<uint64_t> fixed = FixedWeights();
    std::unordered_map<uint64_t, std::array<unsigned __int128, 6>> sums;
    map_.Cumulative(fixed, [&](uint64_t key, const Htc& h, uint64_t w) {
      auto& s = sums[key];
      for (int e = 0; e < 6; ++e) s[e] += static_cast<unsigned __int128>(h.c[e]) * w;
    });
    // Integer sums: every rank's, added in any order, give one process's bits.
    struct KeyedSums {
      unsigned __int128 sum[6];
      uint64_t key;
      uint64_t zero;  // no padding: the parts are sent as bytes
    };
    std::vector<KeyedSums> mine;
    mine.reserve(sums.size());
    for (const auto& [key, sum] : sums) {
      KeyedSums k{{}, key, 0};
      std::copy(sum.begin(), sum.end(), k.sum);
      mine.push_back(k);
    }
    StatusOr<std::vector<KeyedSums>> all = Gathered(std::move(mine));
    if (!all.ok()) return all.status();
    std::sort(all->begin(), all->end(),
              [](const KeyedSums& a, const KeyedSums& b) { return a.key < b.key; });
    std::vector<std::pair<uint64_t, HexCounts>> hexes;
    hexes.reserve(all->size());
    for (size_t i = 0; i < all->size();) {
      unsigned __int128 sum[6] = {};
      const uint64_t key = (*all)[i].key;
      for (; i < all->size() && (*all)[i].key == key; ++i) {
        for (int e = 0; e < 6; ++e) sum[e] += (*all)[i].sum[e];
      }
      HexCounts hc;
      for (int e = 0; e < 6; ++e) hc.counts[e] = static_cast<double>(sum[e]) / kWeightScale;
      hexes.push_back({key, hc});
    }
    return WithStored(std::move(hexes));
  }

  StatusOr<std::vector<HexCounts>> HeaviestMap() const override {
    struct KeyedCounts {
      uint64_t key;
      double counts[6];
    };
    std::vector<KeyedCounts> mine;
    size_t i;
    if (Holds(driver_.filter().heaviest(), &i)) {
      map_.ForEachHex(i, [&](uint64_t key, const Htc& h) {
        KeyedCounts k{key, {}};
        for (int e = 0; e < 6; ++e) k.counts[e] = h.c[e];
        mine.push_back(k);
      });
    }
    StatusOr<std::vector<KeyedCounts>> all = Gathered(std::move(mine));
    if (!all.ok()) return all.status();
    std::vector<std::pair<uint64_t, HexCounts>> hexes;
    hexes.reserve(all->size());
    for (const KeyedCounts& k : *all) {
      HexCounts hc;
      std::copy(k.counts, k.counts + 6, hc.counts);
      hexes.push_back({k.key, hc});
    }
    return WithStored(std::move(hexes));
  }

  std::vector<HexCounts> StoredMap() const override { return WithStored({}); }

  FootSlamSummary Summary() const override {
    FootSlamSummary s;
    static_cast<FilterSummary&>(s) = driver_.Summary();
    StatusOr<ErrorSums> e = SumErrors();
    s.mean_scale = e.ok() ? e->scale / e->w : std::nan("");
    s.mean_heading_error_rad = e.ok() ? e->heading / e->w : std::nan("");
    s.map_memory = map_.memory();
    s.grid_size = int64_t{1} << (layout_.log2_degree() / 2 * map_.grown_height());
    s.prior_hexagons = static_cast<int64_t>(user_prior_.size());
    s.prior_hexagons_outside = prior_outside_;
    s.stored_blocks = stored_blocks_;
    s.stored_blocks_exact = stored_blocks_exact_;
    s.stored_hexagons = static_cast<int64_t>(stored_.size());
    s.store_s = store_s_;
    footslam::AddPoolStats(model_.history().stats(), &s.trajectory_memory);
    return s;
  }

  StatusOr<std::string> Save(std::string_view user_data) const override {
    GROVE_RETURN_IF_ERROR(driver_.CheckNotFailed("there is no state to save"));
    ByteWriter w;
    WriteCheckpointHead(&w, kCheckpointKind, CheckpointFieldsOf(FootSlamConfigFields(), config_),
                        user_data);
    // Across ranks, each rank saves its own share: which share it is comes first.
    WriteCheckpointRank(&w, ranks_);
    driver_.Save(&w);
    model_.Save(&w);
    map_.Save(&w);
    SavePrior(&w);
    SaveStored(&w);
    w.Put<uint32_t>(kCheckpointEndMarker);
    return w.Take();
  }

  Status Load(ByteReader* r) override {
    GROVE_RETURN_IF_ERROR(ReadCheckpointRank(r, ranks_));
    GROVE_RETURN_IF_ERROR(driver_.Load(r));
    GROVE_RETURN_IF_ERROR(model_.Load(r, static_cast<uint64_t>(driver_.steps())));
    GROVE_RETURN_IF_ERROR(map_.Load(r, layout_.key_count()));
    GROVE_RETURN_IF_ERROR(LoadPrior(r));
    GROVE_RETURN_IF_ERROR(LoadStored(r));
    uint32_t end = 0;
    GROVE_RETURN_IF_ERROR(r->Get("end marker", &end));
    if (end != kCheckpointEndMarker || !r->at_end()) {
      return r->Error("end marker", "missing, or bytes follow it");
    }
    return Status::Ok();
  }

  Status CheckInvariants() const override { return model_.CheckCounts(); }

 private:
  // Storage of diversity (config.store_distance_m): folds every block of the particles' maps
  // farther than the store distance from every particle into the stored map and the prior, and
  // drops it from the particles' maps. Across ranks (collective) the box, the blocks and the
  // folds are every rank's, so every rank stores the same map, one process's bits.
  Status StoreFarBlocks() {
    const auto t0 = std::chrono::steady_clock::now();
    // The particles' bounding box: a block this far from it is this far from every particle.
    constexpr double kInf = std::numeric_limits<double>::infinity();
    struct Box {
      double lo_x = kInf, lo_y = kInf, hi_x = -kInf, hi_y = -kInf;
    };
    Box mine;
    for (size_t i = 0; i < model_.size(); ++i) {
      mine.lo_x = std::min(mine.lo_x, model_.x(i));
      mine.hi_x = std::max(mine.hi_x, model_.x(i));
      mine.lo_y = std::min(mine.lo_y, model_.y(i));
      mine.hi_y = std::max(mine.hi_y, model_.y(i));
    }
    StatusOr<std::vector<Box>> boxes = Gathered(std::vector<Box>{mine});
    if (!boxes.ok()) return boxes.status();
    Box box;
    for (const Box& b : *boxes) {
      box.lo_x = std::min(box.lo_x, b.lo_x);
      box.hi_x = std::max(box.hi_x, b.hi_x);
      box.lo_y = std::min(box.lo_y, b.lo_y);
      box.hi_y = std::max(box.hi_y, b.hi_y);
    }
    // The blocks any particle's map holds, in increasing order.
    StatusOr<std::vector<uint64_t>> blocks = Gathered(map_.Blocks(store_bits_));
    if (!blocks.ok()) return blocks.status();
    std::sort(blocks->begin(), blocks->end());
    blocks->erase(std::unique(blocks->begin(), blocks->end()), blocks->end());
    // A block's box: its corner hexagons' centres, widened by a hexagon's width (the odd rows
    // are offset by half of one) and its circumradius.
    const int shift = store_bits_;
    const double margin = (std::sqrt(3.0) + 1) * config_.hex_radius_m;
    std::vector<uint64_t> far;
    for (uint64_t prefix : *blocks) {
      const uint64_t first = prefix << shift;
      const uint64_t last = first | ((uint64_t{1} << shift) - 1);
      double x0, y0, x1, y1;
      grid_.Center(model_.HexOfKey(first), &x0, &y0);
      grid_.Center(model_.HexOfKey(last), &x1, &y1);
      const double gap_x = std::max(
          {0.0, std::min(x0, x1) - margin - box.hi_x, box.lo_x - std::max(x0, x1) - margin});
      const double gap_y = std::max(
          {0.0, std::min(y0, y1) - margin - box.hi_y, box.lo_y - std::max(y0, y1) - margin});
      if (std::hypot(gap_x, gap_y) > config_.store_distance_m) far.push_back(prefix);
    }
    if (!far.empty()) {
      Status stored = StoreBlocks(far);
      // A rank out of memory stops every rank.
      if (ranks_ != nullptr) stored = AgreeStatus(*ranks_, stored);
      GROVE_RETURN_IF_ERROR(stored);
      SelectPrior();
    }
    store_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return Status::Ok();
  }

  // Folds blocks `far` (increasing): each hexagon's counters become their weighted mean over the
  // particles, exact when every particle held the same counters there (counted per block in
  // stored_blocks_exact_). Across ranks each rank folds its particles and the folds are merged
  // by integer sums, so every rank gets one process's values.
  Status StoreBlocks(const std::vector<uint64_t>& far) {
    // One hexagon's fold on one rank; no padding (the parts are sent as bytes).
    struct Fold {
      unsigned __int128 sum[6];
      unsigned __int128 weight;
      uint64_t key;
      uint32_t first[6];  // the first counters folded
      uint32_t block;     // its index in `far`
      uint32_t differs;   // 1 when another particle's counters differ from `first`
      uint32_t zero[2];
    };
    static_assert(sizeof(Fold) == 160);
    struct Weights {
      unsigned __int128 total;
      uint64_t all_weighted;  // a weightless particle's counts would leave no trace
      uint64_t zero;
    };
    const std::vector<uint64_t> weights = FixedWeights();
    Weights w{0, 1, 0};
    for (uint64_t v : weights) {
      w.total += v;
      w.all_weighted = w.all_weighted && v > 0;
    }
    StatusOr<std::vector<Weights>> all_weights = Gathered(std::vector<Weights>{w});
    if (!all_weights.ok()) return all_weights.status();
    unsigned __int128 total = 0;
    bool all_weighted = true;
    for (const Weights& r : *all_weights) {
      total += r.total;
      all_weighted = all_weighted && r.all_weighted != 0;
    }
    std::vector<Fold> mine;
    for (uint32_t b = 0; b < far.size(); ++b) {
      std::map<uint64_t, Fold> folds;
      map_.FoldBlock(store_bits_, far[b], weights, [&](uint64_t key, const Htc& h, uint64_t wk) {
        auto [it, inserted] = folds.try_emplace(key);
        Fold& f = it->second;
        if (inserted) {
          f = Fold{{}, 0, key, {}, b, 0, {}};
          std::copy(h.c, h.c + 6, f.first);
        } else if (!std::equal(h.c, h.c + 6, f.first)) {
          f.differs = 1;
        }
        for (int e = 0; e < 6; ++e) f.sum[e] += static_cast<unsigned __int128>(h.c[e]) * wk;
        f.weight += wk;
      });
      for (const auto& [key, f] : folds) mine.push_back(f);
    }
    StatusOr<std::vector<Fold>> all = Gathered(std::move(mine));
    if (!all.ok()) return all.status();
    // Every rank's folds of a hexagon, merged (integer sums, and whether any counters differ:
    // the same in any order).
    std::sort(all->begin(), all->end(), [](const Fold& a, const Fold& b) {
      return a.block != b.block ? a.block < b.block : a.key < b.key;
    });
    if (user_prior_.size() > 0 && combined_.size() == 0) combined_ = user_prior_;
    std::vector<bool> exact(far.size(), all_weighted);
    for (size_t i = 0; i < all->size();) {
      Fold f = (*all)[i];
      for (++i; i < all->size() && (*all)[i].block == f.block && (*all)[i].key == f.key; ++i) {
        const Fold& g = (*all)[i];
        for (int e = 0; e < 6; ++e) f.sum[e] += g.sum[e];
        f.weight += g.weight;
        if (g.differs || !std::equal(g.first, g.first + 6, f.first)) f.differs = 1;
      }
      if (f.differs || f.weight != total) exact[f.block] = false;
      PriorHex& stored = stored_.FindOrInsert(f.key);
      PriorHex* combined = combined_.size() > 0 ? &combined_.FindOrInsert(f.key) : nullptr;
      for (int e = 0; e < 6; ++e) {
        const double mean = MeanOf(f.sum[e], total);
        stored.edge[e] += mean;
        if (combined != nullptr) combined->edge[e] += mean;
      }
      stored.total = EdgeSum(stored);
      if (combined != nullptr) combined->total = EdgeSum(*combined);
    }
    for (size_t b = 0; b < far.size(); ++b) {
      if (!map_.DropBlock(store_bits_, far[b], 0)) {
        return ResourceExhaustedError("out of memory while dropping a stored map block");
      }
      ++stored_blocks_;
      stored_blocks_exact_ += exact[b] ? 1 : 0;
    }
    return Status::Ok();
  }

  // The weighted sums of the error states, block by block (kSumBlock) and the blocks in order.
  struct ErrorSums {
    double w = 0, scale = 0, heading = 0;
  };
  StatusOr<ErrorSums> SumErrors() const {
    auto lw = driver_.filter().log_weights();
    std::vector<ErrorSums> blocks;
    for (size_t b = 0; b < model_.size(); b += kSumBlock) {
      ErrorSums block;
      for (size_t i = b; i < std::min(model_.size(), b + kSumBlock); ++i) {
        const double w = std::exp(lw[i]);
        block.w += w;
        block.scale += w * model_.scale(i);
        block.heading += w * model_.heading_error(i);
      }
      blocks.push_back(block);
    }
    StatusOr<std::vector<ErrorSums>> all = Gathered(std::move(blocks));
    if (!all.ok()) return all.status();
    ErrorSums total;
    for (const ErrorSums& block : *all) {
      total.w += block.w;
      total.scale += block.scale;
      total.heading += block.heading;
    }
    return total;
  }

  // Whether this rank holds particle `global` (a global index), and its index here.
  bool Holds(size_t global, size_t* local) const {
    if (global < share_.first || global - share_.first >= model_.size()) return false;
    *local = global - share_.first;
    return true;
  }

  // Every rank's `mine`, concatenated in rank order (on one process, `mine`).
  template <typename T>
  StatusOr<std::vector<T>> Gathered(std::vector<T> mine) const {
    return GatherOverRanks(ranks_, std::move(mine));
  }

  // The particles' weights in fixed point (kWeightScale).
  std::vector<uint64_t> FixedWeights() const {
    std::vector<uint64_t> fixed(model_.size());
    auto lw = driver_.filter().log_weights();
    for (size_t i = 0; i < fixed.size(); ++i) {
      fixed[i] = static_cast<uint64_t>(std::llround(std::exp(lw[i]) * kWeightScale));
    }
    return fixed;
  }

  // The sum of a prior hexagon's edges in edge order, as every reader of one computes it.
  static double EdgeSum(const PriorHex& p) {
    double total = 0;
    for (double c : p.edge) total += c;
    return total;
  }

  // `hexes` (in key order) plus the stored map, in key order with their hexagons filled in.
  std::vector<HexCounts> WithStored(std::vector<std::pair<uint64_t, HexCounts>> hexes) const {
    if (stored_.size() > 0) {
      std::vector<std::pair<uint64_t, HexCounts>> merged;
      std::vector<std::pair<uint64_t, const PriorHex*>> stored = SortedHexes(stored_);
      merged.reserve(hexes.size() + stored.size());
      size_t j = 0;
      for (const auto& [key, p] : stored) {
        for (; j < hexes.size() && hexes[j].first < key; ++j) merged.push_back(hexes[j]);
        HexCounts hc;
        if (j < hexes.size() && hexes[j].first == key) hc = hexes[j++].second;
        for (int e = 0; e < 6; ++e) hc.counts[e] += p->edge[e];
        merged.push_back({key, hc});
      }
      for (; j < hexes.size(); ++j) merged.push_back(hexes[j]);
      hexes.swap(merged);
    }
    std::vector<HexCounts> out;
    out.reserve(hexes.size());
    for (const auto& [key, counts] : hexes) {
      HexCounts hc = HexOf(key);
      std::copy(counts.counts, counts.counts + 6, hc.counts);
      out.push_back(hc);
    }
    return out;
  }

  static std::vector<std::pair<uint64_t, const PriorHex*>> SortedHexes(const PriorMap& map) {
    std::vector<std::pair<uint64_t, const PriorHex*>> hexes;
    map.ForEach([&](uint64_t key, const PriorHex& p) { hexes.push_back({key, &p}); });
    std::sort(hexes.begin(), hexes.end());
    return hexes;
  }

  // A table of hexagons in key order: u64 hexagon count, then per hexagon its u64 key and six
  // f64 counters.
  static void SaveTable(const PriorMap& map, ByteWriter* w) {
    std::vector<std::pair<uint64_t, const PriorHex*>> hexes = SortedHexes(map);
    w->Put<uint64_t>(hexes.size());
    for (const auto& [key, p] : hexes) {
      w->Put(key);
      w->PutBytes(p->edge, sizeof(p->edge));
    }
  }
  Status LoadTable(ByteReader* r, const char* what, PriorMap* map) const {
    const std::string name(what);
    uint64_t count = 0;
    GROVE_RETURN_IF_ERROR(
        r->GetCount((name + " hexagon count").c_str(), 7 * sizeof(uint64_t), &count));
    uint64_t last = 0;
    for (uint64_t k = 0; k < count; ++k) {
      uint64_t key = 0;
      PriorHex p{};
      GROVE_RETURN_IF_ERROR(r->Get((name + " hexagon key").c_str(), &key));
      if (key >= layout_.key_count() || (k > 0 && key <= last)) {
        return r->Error((name + " hexagon key").c_str(),
                        "outside the grid or not in increasing order");
      }
      last = key;
      GROVE_RETURN_IF_ERROR(
          r->GetBytes((name + " hexagon counters").c_str(), p.edge, sizeof(p.edge)));
      for (double c : p.edge) {
        if (!std::isfinite(c) || c < 0)
          return r->Error((name + " hexagon counters").c_str(), "impossible value");
      }
      p.total = EdgeSum(p);
      if (!std::isfinite(p.total))
        return r->Error((name + " hexagon counters").c_str(), "impossible value");
      map->Insert(key, p);
    }
    return Status::Ok();
  }

  // The user's prior map (times the confidence): the table, then u64 hexagons outside the grid.
  void SavePrior(ByteWriter* w) const {
    SaveTable(user_prior_, w);
    w->Put<uint64_t>(static_cast<uint64_t>(prior_outside_));
  }
  Status LoadPrior(ByteReader* r) {
    PriorMap prior;
    GROVE_RETURN_IF_ERROR(LoadTable(r, "prior", &prior));
    uint64_t outside = 0;
    GROVE_RETURN_IF_ERROR(r->Get("prior hexagons outside", &outside));
    if (outside > (uint64_t{1} << 62)) return r->Error("prior hexagons outside", "too large");
    UsePrior(std::move(prior), static_cast<int64_t>(outside));
    return Status::Ok();
  }

  // Storage of diversity: u64 blocks stored, u64 of them exact, f64 seconds spent, then the
  // stored map's table and the combined table (saved, not summed again: the same bits).
  void SaveStored(ByteWriter* w) const {
    w->Put<uint64_t>(static_cast<uint64_t>(stored_blocks_));
    w->Put<uint64_t>(static_cast<uint64_t>(stored_blocks_exact_));
    w->Put<double>(store_s_);
    SaveTable(stored_, w);
    SaveTable(combined_, w);
  }
  Status LoadStored(ByteReader* r) {
    uint64_t blocks = 0, exact = 0;
    double seconds = 0;
    GROVE_RETURN_IF_ERROR(r->Get("stored blocks", &blocks));
    GROVE_RETURN_IF_ERROR(r->Get("exactly stored blocks", &exact));
    GROVE_RETURN_IF_ERROR(r->Get("store time", &seconds));
    if (blocks > (uint64_t{1} << 62) || exact > blocks) {
      return r->Error("stored blocks", "too many, or more exact ones than blocks");
    }
    if (!(seconds >= 0 && seconds < 1e12)) return r->Error("store time", "not a duration");
    PriorMap stored, combined;
    GROVE_RETURN_IF_ERROR(LoadTable(r, "stored", &stored));
    GROVE_RETURN_IF_ERROR(LoadTable(r, "combined prior", &combined));
    const bool both = user_prior_.size() > 0 && stored.size() > 0;
    if (both != (combined.size() > 0)) {
      return r->Error("combined prior hexagon count",
                      "a combined prior without both a prior map and a stored map, or missing");
    }
    stored_blocks_ = static_cast<int64_t>(blocks);
    stored_blocks_exact_ = static_cast<int64_t>(exact);
    store_s_ = seconds;
    stored_ = std::move(stored);
    combined_ = std::move(combined);
    SelectPrior();
    return Status::Ok();
  }
  void UsePrior(PriorMap prior, int64_t outside) {
    user_prior_ = std::move(prior);
    prior_outside_ = outside;
    SelectPrior();
  }
  // The table the weighting reads: the user's prior map plus the stored map.
  void SelectPrior() {
    const PriorMap* prior = combined_.size() > 0     ? &combined_
                            : stored_.size() > 0     ? &stored_
                            : user_prior_.size() > 0 ? &user_prior_
                                                     : nullptr;
    model_.set_prior(prior);
  }

  HexCounts HexOf(uint64_t key) const {
    Hex h = model_.HexOfKey(key);
    HexCounts hc;
    hc.q = h.q;
    hc.r = h.r;
    grid_.Center(h, &hc.x_m, &hc.y_m);
    return hc;
  }

  FootSlamConfig config_;
  Collective* ranks_;    // null: one process
  ParticleShare share_;  // the particles this rank holds
  WorkerPool workers_;
  HexGrid grid_;
  HTreeLayout layout_;
  std::unique_ptr<const Alphabet> alphabet_;  // null unless the map uses the alphabet
  Map map_;
  // The user's prior map (times the confidence); empty: none.
  PriorMap user_prior_;
  int64_t prior_outside_ = 0;
  // Storage of diversity: the key bits below a block (a block's keys agree above them), the
  // stored map (the folded blocks' weighted mean counters, summed over every time a block was
  // stored), its sum with the user's prior map (only while both are non-empty) and the
  // statistics.
  static constexpr bool kCanStore = requires(Map & m) { m.DropBlock(0, uint64_t{0}, 0); };
  int store_bits_ = 0;
  PriorMap stored_;
  PriorMap combined_;
  int64_t stored_blocks_ = 0;
  int64_t stored_blocks_exact_ = 0;
  double store_s_ = 0;
  FootSlamModel<Map> model_;
  FilterDriver<FootSlamModel<Map>> driver_;
};

template <int kLog2Degree>
std::unique_ptr<FootSlam::Impl> MakeHTreeEngine(const FootSlamConfig& config, int threads,
                                                HTreeLayout layout, Collective* ranks) {
  if (config.alphabet > 0) {
    auto alphabet = std::make_unique<const Alphabet>(*Alphabet::Create(config.alphabet));
    return std::make_unique<Engine<AlphabetHTreeMap<kLog2Degree>>>(
        config, threads, std::move(layout), std::move(alphabet), ranks);
  }
  return std::make_unique<Engine<HTreeMap<kLog2Degree>>>(config, threads, std::move(layout),
                                                         nullptr, ranks);
}

// Bytes one particle's own copy of a path costs: the inner nodes above the bottom one plus the
// bottom node, for a trie `height` levels high. A packed bottom node is counted at the size of
// one holding a narrow node's digits (16 symbols at s = 16: 128 bytes; at the end of the paper's
// walk, 30,000 particles, 65 % of the live symbol bottom nodes were of 64 bytes and 35 % of 128).
template <typename Trie>
int64_t PathBytes(int height) {
  return (height - 1) * static_cast<int64_t>(Trie::kInnerNodeBytes) +
         static_cast<int64_t>(Trie::BottomBytesFor(Trie::kDegree));
}

template <int kLog2Degree>
int64_t PathBytesFor(const FootSlamConfig& config, int height) {
  using Alphabet = footslam::AlphabetHTreeMap<kLog2Degree>;
  return config.alphabet > 0
             ? PathBytes<typename Alphabet::SymbolTrie>(Alphabet::SymbolHeight(height))
             : PathBytes<typename footslam::HTreeMap<kLog2Degree>::Trie>(height);
}

}  // namespace

int64_t FootSlam::EstimatePeakBytes(const FootSlamConfig& config, int64_t steps) {
  const int64_t n = config.particles;
  // Calibrated on `grove footslam run` over the paper walk (13 minutes; s = 16, T = 5; 2
  // threads; bench/results/2026-12-05-AMD-EPYC-2c-session27/memory_prediction.md): at 30,000,
  // 300,000 and 1,000,000 particles the pools reserved 1,398, 909 and 826 bytes of map and
  // 1,258, 783 and 797 bytes of path history per particle; the rest of the peak RSS was 30 MiB
  // at 30,000 particles and about 18 MiB plus 410 to 417 bytes per particle at the others.
  const int64_t fixed = int64_t{48} << 20;
  // Pose (and its heading's cosine and sine), errors, hexagon and key, each with the gather's
  // spare buffer; the versions of the maps and paths, the weights and parents; the allocator's
  // slack on all of them.
  const int64_t state = 448;
  // Live poses: the walk's common ancestry (one node a step, below) plus the branches since the
  // particles' paths last met, which peaked at 18.6 to 33.3 nodes per particle on the bundled
  // and paper walks at 30,000 to 1,000,000 particles.
  const int64_t pose_node = (sizeof(footslam::PoseHistory::Node) + 15) / 16 * 16;
  const int64_t history = 32 * pose_node;
  // What grows with the walk whatever the particles: the time and mean pose of every step
  // (40 bytes), the common ancestry of the paths (one pose node a step) and the map nodes of
  // the area walked, shared by all particles (about 1.2 new hexagons a step, 64 bytes each
  // with the inner nodes above them).
  const int64_t per_step = 40 + pose_node + 77;
  int64_t map;
  if (config.map == FootSlamMapKind::kNaive) {
    const int64_t grid = int64_t{config.grid_size} * config.grid_size;
    const int64_t hexes = std::min(grid, steps + steps / 5 + 16);
    // 32-byte slots at most half full, two generations alive while resampling.
    map = hexes * 32 * 2 * 2;
  } else {
    StatusOr<HTreeLayout> layout = HTreeLayout::Create(config.grid_size, config.degree);
    const int height = layout.ok() ? layout->height() : 1;
    int64_t path = 0;
    switch (config.degree) {
      case 4:
        path = PathBytesFor<2>(config, height);
        break;
      case 16:
        path = PathBytesFor<4>(config, height);
        break;
      case 64:
        path = PathBytesFor<6>(config, height);
        break;
      default:
        path = PathBytesFor<8>(config, height);
        break;
    }
    // Every particle owns the path it updated last, in two generations while resampling.
    map = 2 * path;
  }
  return fixed + n * (state + history + map) + steps * per_step;
}

FootSlam::FootSlam(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FootSlam::~FootSlam() = default;

Status FootSlam::CheckAcrossRanks(const FootSlamConfig& config, int ranks) {
  GROVE_RETURN_IF_ERROR(
      CheckIslands(static_cast<uint64_t>(config.particles), config.islands, ranks, kSumBlock));
  return CheckRankShares(static_cast<uint64_t>(config.particles), ranks, kSumBlock);
}

StatusOr<std::unique_ptr<FootSlam>> FootSlam::Create(const FootSlamConfig& config) {
  return Create(config, nullptr);
}

StatusOr<std::unique_ptr<FootSlam>> FootSlam::Create(const FootSlamConfig& config,
                                                     Collective* ranks) {
  GROVE_RETURN_IF_ERROR(config.Validate());
  if (ranks != nullptr && ranks->size() > 1) {
    GROVE_RETURN_IF_ERROR(CheckAcrossRanks(config, ranks->size()));
  } else {
    ranks = nullptr;
  }
  return NoThrow([&]() -> StatusOr<std::unique_ptr<FootSlam>> {
    int threads = config.threads > 0
                      ? config.threads
                      : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
    StatusOr<HTreeLayout> layout =
        HTreeLayout::Create(config.grid_size, config.degree, config.grid);
    if (!layout.ok()) return layout.status();
    std::unique_ptr<Impl> impl;
    if (config.map == FootSlamMapKind::kNaive) {
      impl =
          std::make_unique<Engine<NaiveMap>>(config, threads, std::move(*layout), nullptr, ranks);
    } else {
      switch (config.degree) {
        case 4:
          impl = MakeHTreeEngine<2>(config, threads, std::move(*layout), ranks);
          break;
        case 16:
          impl = MakeHTreeEngine<4>(config, threads, std::move(*layout), ranks);
          break;
        case 64:
          impl = MakeHTreeEngine<6>(config, threads, std::move(*layout), ranks);
          break;
        default:
          impl = MakeHTreeEngine<8>(config, threads, std::move(*layout), ranks);
          break;
      }
    }
    GROVE_RETURN_IF_ERROR(impl->Init());
    return std::unique_ptr<FootSlam>(new FootSlam(std::move(impl)));
  });
}

Status FootSlam::Step(double t_s, double dx_m, double dy_m) { return impl_->Step(t_s, dx_m, dy_m); }
Status FootSlam::SetStartTime(double t_s) { return impl_->SetStartTime(t_s); }
Status FootSlam::SetPriorMap(const std::vector<HexCounts>& map) {
  return NoThrow([&] { return impl_->SetPriorMap(map); });
}
const FootSlamConfig& FootSlam::config() const { return impl_->config(); }
int64_t FootSlam::steps() const { return impl_->steps(); }
Pose2 FootSlam::HeaviestPose() const { return impl_->HeaviestPose(); }
Pose2 FootSlam::MeanPose() const { return impl_->MeanPose(); }
StatusOr<std::vector<StampedPose>> FootSlam::HeaviestTrajectory() const {
  return NoThrow([&]() { return impl_->HeaviestTrajectory(); });
}

StatusOr<std::vector<StampedPose>> FootSlam::SmoothedTrajectory() const {
  return NoThrow([&]() { return impl_->SmoothedTrajectory(); });
}
const std::vector<StampedPose>& FootSlam::MeanTrajectory() const { return impl_->MeanTrajectory(); }
StatusOr<std::vector<HexCounts>> FootSlam::CumulativeMap() const {
  return NoThrow([&]() { return impl_->CumulativeMap(); });
}
StatusOr<std::vector<HexCounts>> FootSlam::HeaviestMap() const {
  return NoThrow([&]() { return impl_->HeaviestMap(); });
}
StatusOr<std::vector<HexCounts>> FootSlam::StoredMap() const {
  return NoThrow([&]() -> StatusOr<std::vector<HexCounts>> { return impl_->StoredMap(); });
}
FootSlamSummary FootSlam::Summary() const { return impl_->Summary(); }
Status FootSlam::CheckInvariants() const { return impl_->CheckInvariants(); }

StatusOr<std::string> FootSlam::Checkpoint(std::string_view user_data) const {
  return NoThrow([&]() -> StatusOr<std::string> {
    StatusOr<std::string> body = impl_->Save(user_data);
    if (!body.ok()) return body.status();
    return SealCheckpoint(*body, kFootSlamFormatVersion);
  });
}

StatusOr<std::unique_ptr<FootSlam>> FootSlam::Resume(const FootSlamConfig& config,
                                                     std::string_view checkpoint,
                                                     const std::string& name,
                                                     std::string* user_data) {
  return Resume(config, checkpoint, name, user_data, nullptr);
}

StatusOr<std::unique_ptr<FootSlam>> FootSlam::Resume(const FootSlamConfig& config,
                                                     std::string_view checkpoint,
                                                     const std::string& name,
                                                     std::string* user_data, Collective* ranks) {
  return ResumeOnRanks<FootSlam>(
      ranks, [&](Collective* r) { return ResumeShare(config, checkpoint, name, user_data, r); });
}

StatusOr<std::unique_ptr<FootSlam>> FootSlam::ResumeShare(const FootSlamConfig& config,
                                                          std::string_view checkpoint,
                                                          const std::string& name,
                                                          std::string* user_data,
                                                          Collective* ranks) {
  GROVE_RETURN_IF_ERROR(config.Validate());
  return NoThrow([&]() -> StatusOr<std::unique_ptr<FootSlam>> {
    StatusOr<UnsealedCheckpoint> file = UnsealCheckpoint(checkpoint, name);
    if (!file.ok()) return file.status();
    ByteReader reader(file->body, name);
    // The kind, format and configuration first: a checkpoint of another run costs no engine.
    std::string user;
    GROVE_RETURN_IF_ERROR(ReadCheckpointHead(
        &reader, kCheckpointKind, "FootSLAM", file->format_version, kFootSlamFormatVersion,
        CheckpointFieldsOf(FootSlamConfigFields(), config), &user));
    StatusOr<std::unique_ptr<FootSlam>> slam = Create(config, ranks);
    if (!slam.ok()) return slam.status();
    GROVE_RETURN_IF_ERROR((*slam)->impl_->Load(&reader));
    if (user_data != nullptr) user_data->swap(user);
    return slam;
  });
}

}  // namespace grove

// DiversityStore: FootSLAM's storage of diversity (FootSlamConfig::store_distance_m). Every
// kStoreEverySteps steps, the blocks of the particles' maps farther than the store distance from
// every particle are folded into the stored map (each hexagon's counters become their weighted
// mean over the particles) and dropped from the particles' maps; the weighting then reads the
// stored map, summed with the user's prior map, as its prior. Across ranks (collective) the box,
// the blocks and the folds are every rank's, so every rank stores the same map, one process's
// bits.
//
// Thread safety: one thread drives an engine and its store.
#ifndef GROVE_ENGINE_FOOTSLAM_DIVERSITY_STORE_H_
#define GROVE_ENGINE_FOOTSLAM_DIVERSITY_STORE_H_

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <span>
#include <utility>
#include <vector>

#include "engine/footslam/fixed_weights.h"
#include "engine/footslam/footslam_map.h"
#include "engine/footslam/hex_grid.h"
#include "engine/footslam/htc.h"
#include "engine/footslam/htree_layout.h"
#include "engine/footslam/prior_map.h"
#include "engine/io/checkpoint_io.h"
#include "engine/ranks/collective.h"
#include "grove/footslam.h"
#include "grove/status.h"

namespace grove::footslam {

class DiversityStore {
 public:
  // Blocks of the grid `layout` no wider than config.store_distance_m; `ranks` as the engine's.
  DiversityStore(const FootSlamConfig& config, const HTreeLayout& layout, Collective* ranks);

  // Whether to look for blocks to store after step `steps`: often enough that an area is stored
  // soon after the walk leaves it (50 steps, about 35 m), rarely enough that listing the blocks
  // (every distinct node above them) costs little per step.
  bool Due(int64_t steps) const {
    return config_.store_distance_m > 0 && steps % kStoreEverySteps == 0;
  }

  // Folds every block of the maps of `model`'s particles farther than the store distance from
  // every particle into the stored map, the particles weighing `log_w` (normalised), and drops
  // it from their maps in *map; `user_prior` is the user's prior map. Across ranks, the same
  // status on every rank. ResourceExhausted when out of memory: the engine must then stop.
  template <typename Model, BlockStoringMap Map>
  Status StoreFarBlocks(const Model& model, const HexGrid& grid, std::span<const double> log_w,
                        const PriorMap& user_prior, Map* map);

  // The table the weighting reads: the user's prior map plus the stored map (nullptr: neither).
  const PriorMap* Prior(const PriorMap& user_prior) const;

  // The stored map: every stored block's folds, summed over every time a block was stored.
  const PriorMap& stored() const { return stored_; }
  int64_t blocks() const { return blocks_; }
  // Blocks whose particles all held the same counters (their fold is exact).
  int64_t exact_blocks() const { return exact_blocks_; }
  double seconds() const { return seconds_; }

  // u64 blocks stored, u64 of them exact, f64 seconds spent, then the stored map's table and the
  // combined table (saved, not summed again: the same bits).
  void Save(ByteWriter* w) const;
  // Replaces the state with what Save() wrote, keys below key_count; `user_prior` is the engine's
  // (loaded before).
  Status Load(ByteReader* r, uint64_t key_count, const PriorMap& user_prior);

 private:
  static constexpr int64_t kStoreEverySteps = 50;

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
  // The particles' summed fixed-point weights, and whether each weighs something (a weightless
  // particle's counts would leave no trace): every rank's, summed.
  struct Weights {
    unsigned __int128 total;
    uint64_t all_weighted;
    uint64_t zero;
  };

  // Folds blocks `far` (increasing): each hexagon's counters become their weighted mean over the
  // particles, exact when every particle held the same counters there (counted per block in
  // exact_blocks_). Across ranks each rank folds its particles and the folds are merged by
  // integer sums, so every rank gets one process's values.
  template <BlockStoringMap Map>
  Status StoreBlocks(const std::vector<uint64_t>& far, std::span<const double> log_w,
                     const PriorMap& user_prior, Map* map);

  // Merges every rank's folds `all` into the stored map (and the combined map, which starts as
  // `user_prior`), the particles weighing `weights` in all; clears (*exact)[b] for a block b
  // whose fold is not exact.
  void MergeFolds(std::vector<Fold>* all, const Weights& weights, const PriorMap& user_prior,
                  std::vector<bool>* exact);

  // Every rank's `mine`, concatenated in rank order (on one process, `mine`).
  template <typename T>
  StatusOr<std::vector<T>> Gathered(std::vector<T> mine) const {
    return GatherOverRanks(ranks_, std::move(mine));
  }

  FootSlamConfig config_;
  Collective* ranks_;  // null: one process
  int bits_ = 0;       // the key bits below a block: a block's keys agree above them
  PriorMap stored_;
  PriorMap combined_;  // the stored map plus the user's prior map, while both are non-empty
  int64_t blocks_ = 0;
  int64_t exact_blocks_ = 0;
  double seconds_ = 0;
};

template <typename Model, BlockStoringMap Map>
Status DiversityStore::StoreFarBlocks(const Model& model, const HexGrid& grid,
                                      std::span<const double> log_w, const PriorMap& user_prior,
                                      Map* map) {
  const auto t0 = std::chrono::steady_clock::now();
  // The particles' bounding box: a block this far from it is this far from every particle.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  struct Box {
    double lo_x = kInf, lo_y = kInf, hi_x = -kInf, hi_y = -kInf;
  };
  Box mine;
  for (size_t i = 0; i < model.size(); ++i) {
    mine.lo_x = std::min(mine.lo_x, model.x(i));
    mine.hi_x = std::max(mine.hi_x, model.x(i));
    mine.lo_y = std::min(mine.lo_y, model.y(i));
    mine.hi_y = std::max(mine.hi_y, model.y(i));
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
  StatusOr<std::vector<uint64_t>> blocks = Gathered(map->Blocks(bits_));
  if (!blocks.ok()) return blocks.status();
  std::sort(blocks->begin(), blocks->end());
  blocks->erase(std::unique(blocks->begin(), blocks->end()), blocks->end());
  // A block's box: its corner hexagons' centres, widened by a hexagon's width (the odd rows
  // are offset by half of one) and its circumradius.
  const int shift = bits_;
  const double margin = (std::sqrt(3.0) + 1) * config_.hex_radius_m;
  std::vector<uint64_t> far;
  for (uint64_t prefix : *blocks) {
    const uint64_t first = prefix << shift;
    const uint64_t last = first | ((uint64_t{1} << shift) - 1);
    double x0, y0, x1, y1;
    grid.Center(model.HexOfKey(first), &x0, &y0);
    grid.Center(model.HexOfKey(last), &x1, &y1);
    const double gap_x =
        std::max({0.0, std::min(x0, x1) - margin - box.hi_x, box.lo_x - std::max(x0, x1) - margin});
    const double gap_y =
        std::max({0.0, std::min(y0, y1) - margin - box.hi_y, box.lo_y - std::max(y0, y1) - margin});
    if (std::hypot(gap_x, gap_y) > config_.store_distance_m) far.push_back(prefix);
  }
  if (!far.empty()) {
    Status stored = StoreBlocks(far, log_w, user_prior, map);
    // A rank out of memory stops every rank.
    if (ranks_ != nullptr) stored = AgreeStatus(*ranks_, stored);
    GROVE_RETURN_IF_ERROR(stored);
  }
  seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return Status::Ok();
}

template <BlockStoringMap Map>
Status DiversityStore::StoreBlocks(const std::vector<uint64_t>& far, std::span<const double> log_w,
                                   const PriorMap& user_prior, Map* map) {
  const std::vector<uint64_t> weights = FixedWeights(log_w);
  Weights w{0, 1, 0};
  for (uint64_t v : weights) {
    w.total += v;
    w.all_weighted = w.all_weighted && v > 0;
  }
  StatusOr<std::vector<Weights>> all_weights = Gathered(std::vector<Weights>{w});
  if (!all_weights.ok()) return all_weights.status();
  Weights all{0, 1, 0};
  for (const Weights& r : *all_weights) {
    all.total += r.total;
    all.all_weighted = all.all_weighted && r.all_weighted != 0;
  }
  std::vector<Fold> mine;
  for (uint32_t b = 0; b < far.size(); ++b) {
    std::map<uint64_t, Fold> folds;
    map->FoldBlock(bits_, far[b], weights, [&](uint64_t key, const Htc& h, uint64_t wk) {
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
  StatusOr<std::vector<Fold>> folds = Gathered(std::move(mine));
  if (!folds.ok()) return folds.status();
  std::vector<bool> exact(far.size(), all.all_weighted != 0);
  MergeFolds(&*folds, all, user_prior, &exact);
  for (size_t b = 0; b < far.size(); ++b) {
    if (!map->DropBlock(bits_, far[b], 0)) {
      return ResourceExhaustedError("out of memory while dropping a stored map block");
    }
    ++blocks_;
    exact_blocks_ += exact[b] ? 1 : 0;
  }
  return Status::Ok();
}

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_DIVERSITY_STORE_H_

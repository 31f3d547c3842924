// FootSlamEngine: FootSLAM's engine behind the FootSlam facade, one per map kind: the filter (a
// FilterDriver over a FootSlamModel) and its stepping, the prior map and storage of diversity
// (DiversityStore) the weighting reads, the read-outs (poses, trajectories, maps, summary) and
// checkpoints.
#include "engine/footslam/footslam_engine.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "concurrency/worker_pool.h"
#include "engine/filter/filter_driver.h"
#include "engine/footslam/alphabet.h"
#include "engine/footslam/alphabet_htree_map.h"
#include "engine/footslam/diversity_store.h"
#include "engine/footslam/fixed_weights.h"
#include "engine/footslam/footslam_map.h"
#include "engine/footslam/footslam_model.h"
#include "engine/footslam/hex_grid.h"
#include "engine/footslam/htree_map.h"
#include "engine/footslam/naive_map.h"
#include "engine/footslam/prior_map.h"
#include "grove/input_rules.h"

namespace grove::footslam {
namespace {

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

template <FootSlamMap Map>
class FootSlamEngine final : public FootSlam::Impl {
 public:
  FootSlamEngine(const FootSlamConfig& config, int threads, HTreeLayout layout,
                 std::unique_ptr<const Alphabet> alphabet, Collective* ranks)
      : config_(config),
        ranks_(ranks),
        share_(ShareOf(static_cast<uint64_t>(config.particles), ranks, kSumBlock)),
        workers_(threads),
        grid_(config.hex_radius_m),
        layout_(std::move(layout)),
        alphabet_(std::move(alphabet)),
        map_(layout_, workers_.num_slots(), static_cast<size_t>(share_.count), alphabet_.get()),
        store_(config, layout_, ranks),
        model_(config, &grid_, &layout_, &map_, workers_.num_slots(), share_),
        driver_(&model_, &workers_, FilterOptionsOf(config, ranks), config.threads,
                Pose2{config.start_x_m, config.start_y_m, config.start_heading_rad},
                TimeOrder::kIncreasing) {}

  Status Init() override {
    if (!model_.Init()) return ResourceExhaustedError("out of memory for the start pose");
    return Status::Ok();
  }

  Status Step(double t_s, double dx_m, double dy_m) override {
    Status s = CheckInput(InputField::kStepDx, dx_m);
    if (s.ok()) s = CheckInput(InputField::kStepDy, dy_m);
    if (!s.ok()) {
      return InvalidArgumentError(
          fmt::format("step {} (t = {}): {}", driver_.steps() + 1, t_s, s.message()));
    }
    GROVE_RETURN_IF_ERROR(driver_.Update(t_s, StepInput{dx_m, dy_m}));
    if constexpr (BlockStoringMap<Map>) {
      if (store_.Due(driver_.steps())) return driver_.AfterStep([&] { return StoreFarBlocks(); });
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
    GROVE_RETURN_IF_ERROR(BuildPriorMap(
        map, config_.prior_map_confidence,
        [&](Hex h, uint64_t* key) { return model_.KeyOf(h, key); }, &prior, &outside));
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
    s.stored_blocks = store_.blocks();
    s.stored_blocks_exact = store_.exact_blocks();
    s.stored_hexagons = static_cast<int64_t>(store_.stored().size());
    s.store_s = store_.seconds();
    footslam::AddPoolStats(model_.history().stats(), &s.trajectory_memory);
    return s;
  }

  StatusOr<std::string> Checkpoint(std::string_view user_data) const override {
    return SaveCheckpoint(kFootSlamCheckpoint, FootSlamConfigFields(), config_, ranks_, driver_,
                          user_data, [&](ByteWriter* w) {
                            model_.Save(w);
                            map_.Save(w);
                            SavePrior(w);
                            store_.Save(w);
                          });
  }

  Status Load(ByteReader* r) override {
    return LoadCheckpoint(r, ranks_, &driver_, [&](ByteReader* body) -> Status {
      GROVE_RETURN_IF_ERROR(model_.Load(body, static_cast<uint64_t>(driver_.steps())));
      GROVE_RETURN_IF_ERROR(map_.Load(body, layout_.key_count()));
      GROVE_RETURN_IF_ERROR(LoadPrior(body));
      GROVE_RETURN_IF_ERROR(store_.Load(body, layout_.key_count(), user_prior_));
      SelectPrior();
      return Status::Ok();
    });
  }

  Status CheckInvariants() const override { return model_.CheckCounts(); }

 private:
  // Storage of diversity: stores the far blocks and has the weighting read the new prior.
  Status StoreFarBlocks() {
    GROVE_RETURN_IF_ERROR(
        store_.StoreFarBlocks(model_, grid_, driver_.filter().log_weights(), user_prior_, &map_));
    SelectPrior();
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
    return footslam::FixedWeights(driver_.filter().log_weights());
  }

  // `hexes` (in key order) plus the stored map, in key order with their hexagons filled in.
  std::vector<HexCounts> WithStored(std::vector<std::pair<uint64_t, HexCounts>> hexes) const {
    if (store_.stored().size() > 0) {
      std::vector<std::pair<uint64_t, HexCounts>> merged;
      std::vector<std::pair<uint64_t, const PriorHex*>> stored = SortedHexes(store_.stored());
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

  // The user's prior map (times the confidence): the table, then u64 hexagons outside the grid.
  void SavePrior(ByteWriter* w) const {
    SavePriorMap(user_prior_, w);
    w->Put<uint64_t>(static_cast<uint64_t>(prior_outside_));
  }
  Status LoadPrior(ByteReader* r) {
    PriorMap prior;
    GROVE_RETURN_IF_ERROR(LoadPriorMap(r, "prior", layout_.key_count(), &prior));
    uint64_t outside = 0;
    GROVE_RETURN_IF_ERROR(r->Get("prior hexagons outside", &outside));
    if (outside > (uint64_t{1} << 62)) return r->Error("prior hexagons outside", "too large");
    UsePrior(std::move(prior), static_cast<int64_t>(outside));
    return Status::Ok();
  }

  void UsePrior(PriorMap prior, int64_t outside) {
    user_prior_ = std::move(prior);
    prior_outside_ = outside;
    SelectPrior();
  }
  // The table the weighting reads: the user's prior map plus the stored map.
  void SelectPrior() { model_.set_prior(store_.Prior(user_prior_)); }

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
  DiversityStore store_;
  FootSlamModel<Map> model_;
  FilterDriver<FootSlamModel<Map>> driver_;
};

// Every map policy's model is one a FilterDriver drives.
static_assert(PosedModel<FootSlamModel<NaiveMap>> && PosedModel<FootSlamModel<HTreeMap<4>>> &&
              PosedModel<FootSlamModel<AlphabetHTreeMap<4>>>);

template <int kLog2Degree>
std::unique_ptr<FootSlam::Impl> MakeHTreeEngine(const FootSlamConfig& config, int threads,
                                                HTreeLayout layout, Collective* ranks) {
  if (config.alphabet > 0) {
    auto alphabet = std::make_unique<const Alphabet>(*Alphabet::Create(config.alphabet));
    return std::make_unique<FootSlamEngine<AlphabetHTreeMap<kLog2Degree>>>(
        config, threads, std::move(layout), std::move(alphabet), ranks);
  }
  return std::make_unique<FootSlamEngine<HTreeMap<kLog2Degree>>>(config, threads, std::move(layout),
                                                                 nullptr, ranks);
}

}  // namespace

std::unique_ptr<FootSlam::Impl> MakeFootSlamEngine(const FootSlamConfig& config, int threads,
                                                   HTreeLayout layout, Collective* ranks) {
  if (config.map == FootSlamMapKind::kNaive) {
    return std::make_unique<FootSlamEngine<NaiveMap>>(config, threads, std::move(layout), nullptr,
                                                      ranks);
  }
  switch (config.degree) {
    case 4:
      return MakeHTreeEngine<2>(config, threads, std::move(layout), ranks);
    case 16:
      return MakeHTreeEngine<4>(config, threads, std::move(layout), ranks);
    case 64:
      return MakeHTreeEngine<6>(config, threads, std::move(layout), ranks);
    default:
      return MakeHTreeEngine<8>(config, threads, std::move(layout), ranks);
  }
}

}  // namespace grove::footslam

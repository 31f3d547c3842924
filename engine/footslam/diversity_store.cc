#include "engine/footslam/diversity_store.h"

#include <utility>

namespace grove::footslam {
namespace {

// The counts a fold gives one edge: sum / total, whole when every particle held the same count.
double MeanOf(unsigned __int128 sum, unsigned __int128 total) {
  return static_cast<double>(sum / total) +
         static_cast<double>(sum % total) / static_cast<double>(total);
}

}  // namespace

DiversityStore::DiversityStore(const FootSlamConfig& config, const HTreeLayout& layout,
                               Collective* ranks)
    : config_(config), ranks_(ranks) {
  // Blocks: the largest subtrees no wider than the store distance, below the first grid's
  // root (Validate() asks for a first grid of at least two levels).
  const double hex_width = std::sqrt(3.0) * config.hex_radius_m;
  const int side_bits = layout.log2_degree() / 2;
  int level = 0;
  while (level + 1 <= layout.height() - 2 &&
         std::ldexp(hex_width, side_bits * (level + 2)) <= config.store_distance_m) {
    ++level;
  }
  bits_ = layout.log2_degree() * (level + 1);
}

const PriorMap* DiversityStore::Prior(const PriorMap& user_prior) const {
  return combined_.size() > 0    ? &combined_
         : stored_.size() > 0    ? &stored_
         : user_prior.size() > 0 ? &user_prior
                                 : nullptr;
}

void DiversityStore::MergeFolds(std::vector<Fold>* all, const Weights& weights,
                                const PriorMap& user_prior, std::vector<bool>* exact) {
  // Every rank's folds of a hexagon, merged (integer sums, and whether any counters differ:
  // the same in any order).
  std::sort(all->begin(), all->end(), [](const Fold& a, const Fold& b) {
    return a.block != b.block ? a.block < b.block : a.key < b.key;
  });
  if (user_prior.size() > 0 && combined_.size() == 0) combined_ = user_prior;
  const unsigned __int128 total = weights.total;
  for (size_t i = 0; i < all->size();) {
    Fold f = (*all)[i];
    for (++i; i < all->size() && (*all)[i].block == f.block && (*all)[i].key == f.key; ++i) {
      const Fold& g = (*all)[i];
      for (int e = 0; e < 6; ++e) f.sum[e] += g.sum[e];
      f.weight += g.weight;
      if (g.differs || !std::equal(g.first, g.first + 6, f.first)) f.differs = 1;
    }
    if (f.differs || f.weight != total) (*exact)[f.block] = false;
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
}

void DiversityStore::Save(ByteWriter* w) const {
  w->Put<uint64_t>(static_cast<uint64_t>(blocks_));
  w->Put<uint64_t>(static_cast<uint64_t>(exact_blocks_));
  w->Put<double>(seconds_);
  SavePriorMap(stored_, w);
  SavePriorMap(combined_, w);
}

Status DiversityStore::Load(ByteReader* r, uint64_t key_count, const PriorMap& user_prior) {
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
  GROVE_RETURN_IF_ERROR(LoadPriorMap(r, "stored", key_count, &stored));
  GROVE_RETURN_IF_ERROR(LoadPriorMap(r, "combined prior", key_count, &combined));
  const bool both = user_prior.size() > 0 && stored.size() > 0;
  if (both != (combined.size() > 0)) {
    return r->Error("combined prior hexagon count",
                    "a combined prior without both a prior map and a stored map, or missing");
  }
  blocks_ = static_cast<int64_t>(blocks);
  exact_blocks_ = static_cast<int64_t>(exact);
  seconds_ = seconds;
  stored_ = std::move(stored);
  combined_ = std::move(combined);
  return Status::Ok();
}

}  // namespace grove::footslam

#include "engine/filter/rank_resampler.h"

#include <span>
#include <string>
#include <vector>

namespace grove {

Status AgreeFilterOptions(Collective& c, const FilterOptions& options, uint64_t total, size_t held,
                          Status mine) {
  if (!mine.ok()) {
    // Agreed below.
  } else if (held != RankShare(total, c.size(), c.rank(), kSumBlock).count) {
    mine = InvalidArgumentError("the model holds " + std::to_string(held) +
                                " particles, not this rank's share of " + std::to_string(total));
  }
  GROVE_RETURN_IF_ERROR(AgreeStatus(c, mine));
  struct Key {
    uint64_t total, seed;
    double threshold;
    int64_t scheme, islands;
    uint64_t exchange_steps;
    double exchange_fraction;
    bool operator==(const Key&) const = default;
  };
  Key key{total,
          options.seed,
          options.resample_threshold,
          static_cast<int64_t>(options.resampling),
          options.islands,
          options.exchange_steps,
          options.exchange_fraction};
  std::vector<Key> all;
  GROVE_RETURN_IF_ERROR(AllGatherValues<Key>(c, std::span(&key, 1), &all));
  for (size_t q = 1; q < all.size(); ++q) {
    if (!(all[q] == all[0])) {
      return InvalidArgumentError("rank " + std::to_string(q) +
                                  "'s filter (particles, seed, resampling, threshold, islands, "
                                  "exchange) differs from rank 0's");
    }
  }
  return Status::Ok();
}

}  // namespace grove

#include "engine/filter/island_resampler.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace grove {

Status IslandResampler::Configure(bool migrating) {
  const int islands = options_.islands;
  if (islands <= 1) return Status::Ok();
  GROVE_RETURN_IF_ERROR(CheckIslands(total_, islands, ranks(), kSumBlock));
  if (!(options_.exchange_fraction >= 0 && options_.exchange_fraction <= 0.5)) {
    return InvalidArgumentError(
        "exchange_fraction = " + std::to_string(options_.exchange_fraction) +
        ": must be in [0, 0.5]");
  }
  if (options_.exchange_steps == 0) {
    return InvalidArgumentError("exchange_steps = 0: must be at least 1");
  }
  if (!migrating) {
    return InvalidArgumentError("islands = " + std::to_string(islands) +
                                ": the model's particles cannot move between islands");
  }
  island_lo_ = rank() * (islands / ranks());
  island_hi_ = island_lo_ + islands / ranks();
  uint64_t smallest = total_;
  for (int j = 0; j < islands; ++j) {
    smallest = std::min(smallest, RankShare(total_, islands, j, kSumBlock).count);
  }
  migrants_ =
      static_cast<uint64_t>(std::floor(options_.exchange_fraction * static_cast<double>(smallest)));
  return Status::Ok();
}

Status IslandResampler::DrawIsland(uint64_t step, int j, uint64_t m, std::span<const double> log_w,
                                   WorkerPool& workers, size_t heaviest,
                                   std::vector<uint32_t>* kept, uint64_t* first_copy) {
  const ParticleShare island = RankShare(total_, options_.islands, j, kSumBlock);
  const size_t begin = island.first - first_, n = island.count;
  // Weights relative to the island's heaviest: an island far behind the others may have every
  // normalised weight underflow.
  std::span<const double> w = log_w.subspan(begin, n);
  const double max = *std::max_element(w.begin(), w.end());
  if (!std::isfinite(max)) {
    return FailedPreconditionError("the filter degenerated: island " + std::to_string(j) +
                                   "'s every particle weight is zero");
  }
  island_w_.resize(n);
  for (size_t i = 0; i < n; ++i) island_w_[i] = std::exp(w[i] - max);
  kept->resize(n - m);
  SystematicResample(island_w_, IslandUniform(options_.seed, step, j, 0), workers, *kept);
  for (uint32_t& p : *kept) p += static_cast<uint32_t>(begin);
  if (heaviest >= island.first && heaviest - island.first < n) {
    // The heaviest particle's first copy, or the next one's (as Resample()).
    *first_copy = island.first + (std::lower_bound(kept->begin(), kept->end(),
                                                   static_cast<uint32_t>(heaviest - first_)) -
                                  kept->begin());
  }
  return Status::Ok();
}

}  // namespace grove

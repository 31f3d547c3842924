// Resampling: which particle each member of the next generation copies.
//
// Systematic resampling (Carpenter, Clifford and Fearnhead, 1999; Kitagawa 1996) runs in parallel
// in two passes over fixed blocks: block sums and their prefix, then each block writes the
// offspring of its own particles. The other schemes (stratified, residual, multinomial; Douc,
// Cappé and Moulines 2005 compare them) run serially; they exist for comparison.
#ifndef GROVE_ENGINE_FILTER_RESAMPLER_H_
#define GROVE_ENGINE_FILTER_RESAMPLER_H_

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "concurrency/worker_pool.h"
#include "grove/resampling.h"

namespace grove {

// Fills parents[k], k in [0, parents.size()), with the index of the particle that slot k of the
// next generation copies; parents come out in nondecreasing order. Draws come from the stream
// (seed, step, purpose "resample"), so the result does not depend on the thread count.
// `block_sums`, when not empty, holds BlockSums(weights) (a caller that has them spares systematic
// resampling a pass over the weights).
// REQUIRES: weights non-negative and finite with a positive sum; parents.size() >= 1.
void Resample(ResamplingScheme scheme, std::span<const double> weights, uint64_t seed,
              uint64_t step, WorkerPool& workers, std::span<uint32_t> parents,
              std::span<const double> block_sums = {});

// Fixed block size for sums over particles: results are independent of the thread count.
inline constexpr size_t kSumBlock = 4096;
// The mean pose's sub-blocks: a block's pose sums are the sums of its runs of kMeanSubBlock
// particles, added in order, so a batch of whole sub-blocks sums its own (FilterDriver).
inline constexpr size_t kMeanSubBlock = 16;
static_assert(kSumBlock % kMeanSubBlock == 0);

// The sums of weights over the fixed blocks of kSumBlock, in block order.
std::vector<double> BlockSums(std::span<const double> weights, WorkerPool& workers);

// The uniform of systematic resampling at `step`: the same on every rank.
double SystematicUniform(uint64_t seed, uint64_t step);

// Systematic resampling with the uniform u: fills parents (nondecreasing) as Resample() does.
// `weights` need not sum to 1. REQUIRES: as Resample().
void SystematicResample(std::span<const double> weights, double u, WorkerPool& workers,
                        std::span<uint32_t> parents, std::span<const double> block_sums = {});

// The uniform of island `island`'s draw `draw` (0: its next generation, 1: the particles it
// sends) at `step`.
double IslandUniform(uint64_t seed, uint64_t step, uint32_t island, uint32_t draw);

// Systematic resampling of one share of the particles (a rank of a filter across ranks), bit for
// bit as Resample(kSystematic) over all of them: `weights` are the share's, starting at block
// `first_block`; `block_sums` holds every block's BlockSums, all ranks' in block order; n_out is
// the next generation's size and u the SystematicUniform. Sets slots[i] to the first slot of the
// next generation that copies share particle i and slots[n] past the last particle's last copy:
// particle i has slots[i + 1] - slots[i] copies. REQUIRES: slots.size() == weights.size() + 1.
void SystematicSlots(std::span<const double> weights, size_t first_block,
                     std::span<const double> block_sums, size_t n_out, double u,
                     WorkerPool& workers, std::span<uint64_t> slots);

}  // namespace grove

#endif  // GROVE_ENGINE_FILTER_RESAMPLER_H_

// Resampling: which particle each member of the next generation copies.
//
// Systematic resampling (Carpenter, Clifford and Fearnhead, 1999; Kitagawa 1996) runs in parallel
// in two passes over fixed blocks: block sums and their prefix, then each block writes the
// offspring of its own particles. The other schemes (stratified, residual, multinomial; Douc,
// Cappé and Moulines 2005 compare them) run serially; they exist for comparison.
#ifndef GROVE_ENGINE_RESAMPLER_H_
#define GROVE_ENGINE_RESAMPLER_H_

#include <cstdint>
#include <span>
#include <string_view>

#include "concurrency/worker_pool.h"
#include "grove/resampling.h"

namespace grove {

// Fills parents[k], k in [0, parents.size()), with the index of the particle that slot k of the
// next generation copies; parents come out in nondecreasing order. Draws come from the stream
// (seed, step, purpose "resample"), so the result does not depend on the thread count.
// REQUIRES: weights non-negative and finite with a positive sum; parents.size() >= 1.
void Resample(ResamplingScheme scheme, std::span<const double> weights, uint64_t seed,
              uint64_t step, WorkerPool& workers, std::span<uint32_t> parents);

// Fixed block size for sums over particles: results are independent of the thread count.
inline constexpr size_t kSumBlock = 4096;

}  // namespace grove

#endif  // GROVE_ENGINE_RESAMPLER_H_

// RankResampler: systematic resampling of a filter whose particles are spread over ranks, bit
// for bit the resampling of one process holding them all; and AgreeFilterOptions, the checks
// the ranks of such a filter make together before its first step.
//
// Thread safety: one thread drives a rank's filter and its resampler.
#ifndef GROVE_ENGINE_FILTER_RANK_RESAMPLER_H_
#define GROVE_ENGINE_FILTER_RANK_RESAMPLER_H_

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/filter/filter_model.h"
#include "engine/filter/filter_options.h"
#include "engine/filter/particle_migration.h"
#include "engine/filter/resampler.h"
#include "engine/ranks/collective.h"
#include "grove/status.h"

namespace grove {

class RankResampler {
 public:
  // This rank's share of a filter of `total` particles across `ranks` starts at global particle
  // `first`; every draw comes from `seed`'s streams.
  RankResampler(Collective* ranks, uint64_t total, uint64_t first, uint64_t seed)
      : ranks_(ranks), total_(total), first_(first), seed_(seed) {}

  // Draws the next generation at `step` from this rank's normalised `weights` and their
  // BlockSums `block_sums`: every rank computes its own particles' copies from the gathered
  // block sums, sends each other rank the particles whose copies it holds (once per rank, with
  // their copy counts), and gathers its new generation from its own and the received ones in
  // rank order, which is slot order. Sets *parents (indices into the model, which has imported
  // the received particles after its own) and *heaviest (a global index: the heaviest
  // particle's first copy); adds what moved to *stats. The same status on every rank.
  template <MigratingModel Model>
  Status Resample(uint64_t step, std::span<const double> weights,
                  std::span<const double> block_sums, WorkerPool& workers, Model* model,
                  std::vector<uint32_t>* parents, size_t* heaviest, MigrationStats* stats) {
    using Clock = std::chrono::steady_clock;
    Collective& c = *ranks_;
    const int ranks = c.size(), me = c.rank();
    const size_t n = weights.size();
    std::vector<double> all_block_sums;
    GROVE_RETURN_IF_ERROR(AllGatherValues<double>(c, block_sums, &all_block_sums));
    slots_.resize(n + 1);
    SystematicSlots(weights, first_ / kSumBlock, all_block_sums, total_,
                    SystematicUniform(seed_, step), workers, slots_);
    // The heaviest particle's first copy (Resample()'s lower bound), from its rank.
    uint64_t first_copy = UINT64_MAX;
    if (*heaviest >= first_ && *heaviest - first_ < n) first_copy = slots_[*heaviest - first_];
    std::vector<uint64_t> first_copies;
    GROVE_RETURN_IF_ERROR(AllGatherValues<uint64_t>(c, std::span(&first_copy, 1), &first_copies));
    *heaviest = *std::min_element(first_copies.begin(), first_copies.end());
    auto m0 = Clock::now();
    std::vector<std::string> to(static_cast<size_t>(ranks));
    std::vector<uint32_t> which, copies;
    for (int q = 0; q < ranks; ++q) {
      if (q == me) continue;
      const ParticleShare share = RankShare(total_, ranks, q, kSumBlock);
      which.clear();
      copies.clear();
      for (size_t i = 0; i < n; ++i) {
        if (uint64_t k = CopiesIn(i, share); k > 0) {
          which.push_back(static_cast<uint32_t>(i));
          copies.push_back(static_cast<uint32_t>(k));
        }
      }
      if (which.empty()) continue;
      to[static_cast<size_t>(q)] = WriteParticles(*model, which, copies);
      stats->sent_bytes += to[static_cast<size_t>(q)].size();
      stats->sent_particles += which.size();
    }
    stats->migrate_s += std::chrono::duration<double>(Clock::now() - m0).count();
    std::vector<std::string> from;
    GROVE_RETURN_IF_ERROR(c.AllToAll(to, &from));
    auto m1 = Clock::now();
    parents->clear();
    const ParticleShare own{first_, n};
    Status s;
    for (int q = 0; q < ranks && s.ok(); ++q) {
      if (q == me) {
        for (size_t i = 0; i < n; ++i) {
          parents->insert(parents->end(), CopiesIn(i, own), static_cast<uint32_t>(i));
        }
        continue;
      }
      if (from[static_cast<size_t>(q)].empty()) continue;
      uint64_t read = 0;
      s = ReadParticles(model, from[static_cast<size_t>(q)],
                        "particles from rank " + std::to_string(q), step + 1,
                        n - std::min(n, parents->size()), parents, &read);
    }
    if (s.ok() && parents->size() != n) {
      s = InternalError("resampling across ranks: " + std::to_string(parents->size()) +
                        " copies for " + std::to_string(n) + " particles");
    }
    stats->migrate_s += std::chrono::duration<double>(Clock::now() - m1).count();
    return AgreeStatus(c, s);
  }

 private:
  // Copies of local particle i that the slots of `s` hold (after SystematicSlots).
  uint64_t CopiesIn(size_t i, const ParticleShare& s) const {
    uint64_t lo = std::max(slots_[i], s.first), hi = std::min(slots_[i + 1], s.first + s.count);
    return hi > lo ? hi - lo : 0;
  }

  Collective* ranks_;
  uint64_t total_;  // particles in the whole filter
  uint64_t first_;  // this rank's first particle
  uint64_t seed_;
  std::vector<uint64_t> slots_;  // each particle's first copy, and past the last one's last
};

// Before a filter's first step across ranks: `held`, the particles this rank's model holds, is
// its RankShare of `total`, and the ranks agree on what changes results. `mine` is this rank's
// verdict on the other options. Returns the same error on every rank.
Status AgreeFilterOptions(Collective& c, const FilterOptions& options, uint64_t total, size_t held,
                          Status mine);

}  // namespace grove

#endif  // GROVE_ENGINE_FILTER_RANK_RESAMPLER_H_

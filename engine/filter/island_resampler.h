// IslandResampler: island mode's resampling (FilterOptions::islands). Each island draws its next
// generation systematically from its own weights; at an exchange, island j also draws a sample
// of migrants and sends it to island j + 1 (written and read back as between ranks, whichever
// rank holds the neighbour), where it follows the island's own draws, as many fewer.
//
// Thread safety: one thread drives a rank's filter and its resampler.
#ifndef GROVE_ENGINE_FILTER_ISLAND_RESAMPLER_H_
#define GROVE_ENGINE_FILTER_ISLAND_RESAMPLER_H_

#include <algorithm>
#include <chrono>
#include <cmath>
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

class IslandResampler {
 public:
  // The islands of a filter of `total` particles whose share here (a rank's, or all of them
  // without ranks) starts at global particle `first`; islands and exchanges as in `options`.
  IslandResampler(const FilterOptions& options, uint64_t total, uint64_t first)
      : options_(options), total_(total), first_(first) {}

  // Island mode's rules (OK when it is off): the islands fit the particles and ranks, the
  // exchange is possible, and the model's particles can move (`migrating`). Sets the islands
  // this rank holds and the migrants of an exchange.
  Status Configure(bool migrating);

  // Whether the resampling after the weighting of step `step` (counted from 0) exchanges
  // migrants: false when island mode is off. REQUIRES: Configure() ok.
  bool Exchanges(uint64_t step) const {
    return options_.islands > 1 && (step + 1) % options_.exchange_steps == 0;
  }

  // Draws the next generation of this rank's islands at `step` from the normalised `log_w` of
  // its particles, exchanging migrants when `exchange`. Sets *parents (indices into the model,
  // which has imported the received migrants after its own) and, on success, *heaviest (a
  // global index) to the heaviest particle's first copy, or the next particle's; adds what
  // moved to another rank to *stats. Across ranks, the same status on every rank.
  template <MigratingModel Model>
  Status Resample(uint64_t step, bool exchange, std::span<const double> log_w, WorkerPool& workers,
                  Model* model, std::vector<uint32_t>* parents, size_t* heaviest,
                  MigrationStats* stats) {
    using Clock = std::chrono::steady_clock;
    const uint64_t m = exchange ? migrants_ : 0;
    const int local = island_hi_ - island_lo_;
    std::vector<std::vector<uint32_t>> own(static_cast<size_t>(local));
    std::vector<std::string> sent(static_cast<size_t>(local));
    uint64_t first_copy = UINT64_MAX;
    size_t last_sent = 0;  // distinct particles the last island sends
    Status s;
    for (int j = island_lo_; j < island_hi_ && s.ok(); ++j) {
      const size_t at = static_cast<size_t>(j - island_lo_);
      s = DrawIsland(step, j, m, log_w, workers, *heaviest, &own[at], &first_copy);
      if (!s.ok() || m == 0) continue;
      auto m0 = Clock::now();
      sent[at] = DrawMigrants(step, j, m, workers, *model, &last_sent);
      stats->migrate_s += std::chrono::duration<double>(Clock::now() - m0).count();
    }
    GROVE_RETURN_IF_ERROR(Agree(s));
    // What each of this rank's islands receives: from the island before it, here or on the
    // rank before.
    std::vector<std::string> from_rank;
    if (m > 0 && ranks() > 1) {
      std::vector<std::string> to(static_cast<size_t>(ranks()));
      to[static_cast<size_t>((rank() + 1) % ranks())] = sent.back();
      stats->sent_bytes += sent.back().size();
      stats->sent_particles += last_sent;
      GROVE_RETURN_IF_ERROR(options_.collective->AllToAll(to, &from_rank));
    }
    auto m1 = Clock::now();
    parents->clear();
    for (int j = island_lo_; j < island_hi_ && s.ok(); ++j) {
      const size_t at = static_cast<size_t>(j - island_lo_);
      parents->insert(parents->end(), own[at].begin(), own[at].end());
      if (m == 0) continue;
      const std::string& bytes =
          at > 0        ? sent[at - 1]
          : ranks() > 1 ? from_rank[static_cast<size_t>((rank() + ranks() - 1) % ranks())]
                        : sent[static_cast<size_t>(local - 1)];
      const std::string name =
          "particles from island " + std::to_string((j + options_.islands - 1) % options_.islands);
      uint64_t read = 0;
      s = ReadParticles(model, bytes, name, step + 1, m, parents, &read);
      if (s.ok() && read != m) {
        s = DataLossError(name + ": " + std::to_string(read) + " copies for " + std::to_string(m) +
                          " migrants");
      }
    }
    if (s.ok() && parents->size() != log_w.size()) {
      s = InternalError("island resampling: " + std::to_string(parents->size()) + " copies for " +
                        std::to_string(log_w.size()) + " particles");
    }
    stats->migrate_s += std::chrono::duration<double>(Clock::now() - m1).count();
    GROVE_RETURN_IF_ERROR(Agree(s));
    if (options_.collective != nullptr) {
      std::vector<uint64_t> all;
      GROVE_RETURN_IF_ERROR(
          AllGatherValues<uint64_t>(*options_.collective, std::span(&first_copy, 1), &all));
      first_copy = *std::min_element(all.begin(), all.end());
    }
    *heaviest = first_copy;
    return Status::Ok();
  }

 private:
  int ranks() const { return options_.collective == nullptr ? 1 : options_.collective->size(); }
  int rank() const { return options_.collective == nullptr ? 0 : options_.collective->rank(); }

  // Across ranks, the same status on every rank; alone, `s`.
  Status Agree(const Status& s) const {
    return options_.collective == nullptr ? s : AgreeStatus(*options_.collective, s);
  }

  // Island j's own draws of its next generation, all but `m` (model indices, into *kept); when
  // the island holds particle `heaviest` (a global index), *first_copy becomes the global index
  // of its first copy (or the next particle's, as Resample()). Leaves the island's weights over
  // its heaviest in island_w_, for DrawMigrants().
  Status DrawIsland(uint64_t step, int j, uint64_t m, std::span<const double> log_w,
                    WorkerPool& workers, size_t heaviest, std::vector<uint32_t>* kept,
                    uint64_t* first_copy);

  // Island j's `m` migrants, drawn from island_w_ as DrawIsland() left them, as a message for
  // the next island; *distinct is the particles in it.
  template <MigratingModel Model>
  std::string DrawMigrants(uint64_t step, int j, uint64_t m, WorkerPool& workers,
                           const Model& model, size_t* distinct) {
    const size_t begin = RankShare(total_, options_.islands, j, kSumBlock).first - first_;
    drawn_.resize(m);
    SystematicResample(island_w_, IslandUniform(options_.seed, step, j, 1), workers, drawn_);
    std::vector<uint32_t> which, copies;
    for (uint32_t p : drawn_) {
      if (which.empty() || which.back() != begin + p) {
        which.push_back(static_cast<uint32_t>(begin + p));
        copies.push_back(0);
      }
      ++copies.back();
    }
    *distinct = which.size();
    return WriteParticles(model, which, copies);
  }

  FilterOptions options_;
  uint64_t total_;     // particles in the whole filter
  uint64_t first_;     // this rank's first particle
  int island_lo_ = 0;  // this rank's islands [island_lo_, island_hi_)
  int island_hi_ = 1;
  uint64_t migrants_ = 0;         // the particles an island sends at an exchange
  std::vector<double> island_w_;  // an island's weights over its heaviest
  std::vector<uint32_t> drawn_;   // an island's migrants
};

}  // namespace grove

#endif  // GROVE_ENGINE_FILTER_ISLAND_RESAMPLER_H_

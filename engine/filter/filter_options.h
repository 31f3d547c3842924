// FilterOptions: how a ParticleFilter resamples, batches and draws, alone or across ranks; and
// FilterOptionsOf, the options a model's configuration gives (grove/filter_config.h).
#ifndef GROVE_ENGINE_FILTER_FILTER_OPTIONS_H_
#define GROVE_ENGINE_FILTER_FILTER_OPTIONS_H_

#include <concepts>
#include <cstddef>
#include <cstdint>

#include "engine/ranks/collective.h"
#include "grove/filter_config.h"
#include "grove/resampling.h"

namespace grove {

struct FilterOptions {
  // Which resampling scheme draws the next generation. Default: systematic.
  ResamplingScheme resampling = ResamplingScheme::kSystematic;
  // Resample when ESS / N falls below this, in (0, 1]; 1 resamples every step. Default: 0.5.
  double resample_threshold = 0.5;
  // Particles per parallel batch, at most: fewer when that leaves a thread under 4 batches,
  // rounded up to a multiple of 16 (BatchSize(); affects speed only). Default: 512.
  size_t batch = 512;
  // Seed of every random stream. Default: 1.
  uint64_t seed = 1;
  // Ranks that run this filter together (nullptr: this process holds every particle). Each
  // rank's model holds its RankShare(total_particles, ranks, rank, kSumBlock) of the particles,
  // as global particles [first, first + model size); weights are normalised and resampled over
  // all of them, and a particle whose copies belong to another rank moves there (the model
  // exports and imports it: MigratingModel). Only systematic resampling runs across ranks.
  Collective* collective = nullptr;
  // The whole filter's particle count, with a collective.
  uint64_t total_particles = 0;
  // Island mode when above 1: the particles form this many islands of whole blocks (island j
  // holds RankShare(total, islands, j, kSumBlock)), each resampled from its own weights alone,
  // after which every particle weighs 1 / N again: an island's share of the total weight is
  // dropped, the price of never moving particles at a resampling. Every `exchange_steps` steps
  // the filter resamples whatever the ESS, and island j then draws a systematic sample of
  // `exchange_fraction` of the smallest island's count from its weights and sends it to island
  // (j + 1) mod islands, where it takes the place of as many of the island's own draws. Results
  // depend on the islands, not on the ranks or threads. Across ranks, islands must be a multiple
  // of the ranks (rank q holds whole islands). Needs a MigratingModel. Default: 1 (off).
  int islands = 1;
  uint64_t exchange_steps = 10;
  double exchange_fraction = 0.1;
};

// The loop's options from a model's configuration (grove/filter_config.h), island mode's too
// when it has them (an IslandConfig).
template <std::derived_from<FilterConfig> Config>
FilterOptions FilterOptionsOf(const Config& c) {
  FilterOptions o;
  o.resampling = c.resampling;
  o.resample_threshold = c.resample_threshold;
  o.batch = static_cast<size_t>(c.batch);
  o.seed = c.seed;
  if constexpr (std::derived_from<Config, IslandConfig>) {
    o.islands = c.islands;
    o.exchange_steps = static_cast<uint64_t>(c.island_exchange_steps);
    o.exchange_fraction = c.island_exchange_fraction;
  }
  return o;
}

// The options of one rank's share of a filter of c.particles across `ranks` (null: one
// process, as FilterOptionsOf(c)).
template <std::derived_from<FilterConfig> Config>
FilterOptions FilterOptionsOf(const Config& c, Collective* ranks) {
  FilterOptions o = FilterOptionsOf(c);
  o.collective = ranks;
  o.total_particles = static_cast<uint64_t>(c.particles);
  return o;
}

}  // namespace grove

#endif  // GROVE_ENGINE_FILTER_FILTER_OPTIONS_H_

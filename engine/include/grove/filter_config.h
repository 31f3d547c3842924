// FilterConfig: the particle filter's part of every model's configuration (particles, seed,
// resampling, threads, batch), IslandConfig: island mode's part, and FilterFields(): their rows
// in a model's field table (grove/config_fields.h), written once for every model.
//
//   struct MyConfig : grove::FilterConfig {
//     MyConfig() { particles = 500; }  // the model's own default
//     double sigma_m = 0.1;
//   };
//   const grove::FilterFieldRows<MyConfig> filter = grove::FilterFields<MyConfig>(
//       "Resample when ESS/N is below this");
//   const std::vector<grove::ConfigField<MyConfig>> table = grove::JoinFields<MyConfig>(
//       {filter.population, filter.resampling,
//        {grove::RealField("sigma_m", &MyConfig::sigma_m, grove::Interval::AtLeast(0),
//                          grove::kChangesResults, "Noise, metres")},
//        filter.speed});
//   MyConfig config;
//   return grove::CheckFieldRanges(table, config);  // OK, or the first field out of range
#ifndef GROVE_FILTER_CONFIG_H_
#define GROVE_FILTER_CONFIG_H_

#include <concepts>
#include <cstdint>
#include <initializer_list>
#include <vector>

#include "grove/config_fields.h"
#include "grove/resampling.h"

namespace grove {

// The filter's fields. A model's configuration derives from it and sets its own defaults for
// particles, resample_threshold and batch in its constructor (FootSlamConfig: 30,000 particles,
// FastSlamConfig: 100 particles, resampling at ESS / N < 0.75).
struct FilterConfig {
  // Options that change results

  // Number of particles. Range: 1..2^31. Default: 1000 (a model's configuration sets its own).
  int64_t particles = 1000;
  // Seed of every random stream. Same seed, same result at any thread count. Default: 1.
  uint64_t seed = 1;
  // Resampling scheme. Default: systematic.
  ResamplingScheme resampling = ResamplingScheme::kSystematic;
  // Resample when ESS / N < threshold. Range: (0, 1]; 1 resamples every step. Default: 0.5.
  double resample_threshold = 0.5;

  // Options that change only speed

  // Worker threads. 0 means one per hardware thread. Range: 0..256 (more threads than cores
  // only add overhead; oneTBB runs at most as many as the process may use). Default: 0.
  int threads = 0;
  // Particles per parallel batch, at most (batches shrink to leave each thread at least 4),
  // rounded up to a multiple of 16. Range: >= 1. Default: 512.
  int64_t batch = 512;
};

// Island mode, for a model whose particles can move between islands (FootSlamConfig).
struct IslandConfig {
  // Above 1, the particles form this many islands of whole blocks of 4,096, each resampled from
  // its own weights (systematic resampling only); across MPI ranks a multiple of the ranks.
  // Range: 1..65536, at most ceil(particles / 4096). Default: 1 (one population, resampled as a
  // whole).
  int islands = 1;
  // Every this many steps the islands resample and each sends the next a sample of
  // island_exchange_fraction of its particles. Range: >= 1. Default: 10.
  int64_t island_exchange_steps = 10;
  // The share of the smallest island's particles an island sends at an exchange.
  // Range: [0, 0.5]. Default: 0.1.
  double island_exchange_fraction = 0.1;
};

// The rows of the filter's fields in a model's table, in three groups the model places among
// its own rows (the checkpoint's field block keeps the table's order).
template <typename Config>
struct FilterFieldRows {
  std::vector<ConfigField<Config>> population;  // particles, seed
  // resampling, resample_threshold, and island mode's three fields for an IslandConfig
  std::vector<ConfigField<Config>> resampling;
  std::vector<ConfigField<Config>> speed;  // threads, batch
};

// `threshold_help`: the help line of resample_threshold, which says when the model weights
// ("Resample after a scan when ESS/N is below this").
template <std::derived_from<FilterConfig> Config>
FilterFieldRows<Config> FilterFields(const char* threshold_help) {
  using C = Config;
  using F = FilterConfig;
  FilterFieldRows<C> rows;
  rows.population = {
      IntegerField<C>("particles", static_cast<int64_t C::*>(&F::particles), 1, int64_t{1} << 31,
                      kChangesResults, "Number of particles"),
      UnsignedField<C>("seed", static_cast<uint64_t C::*>(&F::seed), kChangesResults,
                       "Seed of every random stream"),
  };
  rows.resampling = {
      ChoiceField<C>("resampling", static_cast<ResamplingScheme C::*>(&F::resampling),
                     {"systematic", "stratified", "residual", "multinomial"}, kChangesResults,
                     "Resampling scheme"),
      RealField<C>("resample_threshold", static_cast<double C::*>(&F::resample_threshold),
                   Interval::LeftOpen(0, 1), kChangesResults, threshold_help),
  };
  if constexpr (std::derived_from<C, IslandConfig>) {
    using I = IslandConfig;
    rows.resampling.push_back(IntegerField<C>(
        "islands", static_cast<int C::*>(&I::islands), 1, 65536, kChangesResults,
        "Island mode: islands of whole 4,096-particle blocks, each resampled alone; 1: off"));
    rows.resampling.push_back(IntegerField<C>(
        "island_exchange_steps", static_cast<int64_t C::*>(&I::island_exchange_steps), 1,
        int64_t{1} << 40, kChangesResults,
        "Island mode: steps between exchanges of particles with the next island"));
    rows.resampling.push_back(RealField<C>(
        "island_exchange_fraction", static_cast<double C::*>(&I::island_exchange_fraction),
        Interval::Closed(0, 0.5), kChangesResults,
        "Island mode: share of the smallest island's particles sent at an exchange"));
  }
  rows.speed = {
      IntegerField<C>("threads", static_cast<int C::*>(&F::threads), 0, 256, kChangesSpeedOnly,
                      "Worker threads; 0: one per hardware thread"),
      IntegerField<C>("batch", static_cast<int64_t C::*>(&F::batch), 1, int64_t{1} << 31,
                      kChangesSpeedOnly,
                      "Particles per parallel batch, rounded up to a multiple of 16"),
  };
  return rows;
}

// The groups' rows in the order given: a model's whole table.
template <typename Config>
std::vector<ConfigField<Config>> JoinFields(
    std::initializer_list<std::vector<ConfigField<Config>>> groups) {
  std::vector<ConfigField<Config>> out;
  for (const std::vector<ConfigField<Config>>& g : groups)
    out.insert(out.end(), g.begin(), g.end());
  return out;
}

}  // namespace grove

#endif  // GROVE_FILTER_CONFIG_H_

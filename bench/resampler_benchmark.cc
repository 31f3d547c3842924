// Resampling at 30k and 1M particles, 1 and 2 threads.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/filter/resampler.h"

namespace grove {
namespace {

void BM_Resample(benchmark::State& state) {
  const auto scheme = static_cast<ResamplingScheme>(state.range(0));
  const size_t n = static_cast<size_t>(state.range(1));
  WorkerPool workers(static_cast<int>(state.range(2)));
  std::mt19937_64 rng(3);
  std::exponential_distribution<double> e(1.0);
  std::vector<double> w(n);
  double total = 0;
  for (double& x : w) total += (x = e(rng));
  for (double& x : w) x /= total;
  std::vector<uint32_t> parents(n);
  uint64_t step = 0;
  for (auto _ : state) {
    Resample(scheme, w, 1, step++, workers, parents);
    benchmark::DoNotOptimize(parents.data());
  }
  state.SetItemsProcessed(state.iterations() * n);
  state.SetLabel(ResamplingSchemeName(scheme));
}

BENCHMARK(BM_Resample)
    ->ArgNames({"scheme", "particles", "threads"})
    ->ArgsProduct({{static_cast<int>(ResamplingScheme::kSystematic)}, {30000, 1000000}, {1, 2}})
    ->ArgsProduct({{static_cast<int>(ResamplingScheme::kStratified),
                    static_cast<int>(ResamplingScheme::kResidual),
                    static_cast<int>(ResamplingScheme::kMultinomial)},
                   {30000, 1000000},
                   {1}})
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace grove

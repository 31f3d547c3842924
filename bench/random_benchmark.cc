// Normal deviates for a batch of 512 particles: RandomStream particle by particle against
// DrawNormals (SIMD), as dispatched and on every Highway target this CPU runs. The counter
// time_per_particle is seconds per particle (2.5n = 2.5 ns).
#include <benchmark/benchmark.h>
#include <hwy/highway.h>

#include <cstdint>
#include <vector>

#include "concurrency/normal_batch.h"
#include "concurrency/random_stream.h"

namespace grove {
namespace {

constexpr uint32_t kBatch = 512;

void SetPerParticleCounters(benchmark::State& state) {
  state.SetItemsProcessed(state.iterations() * kBatch);
  state.counters["time_per_particle"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * kBatch,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_NormalsScalar(benchmark::State& state) {
  const int count = static_cast<int>(state.range(0));
  std::vector<double> rows(size_t{kMaxBatchNormals} * kBatch);
  uint64_t step = 0;
  for (auto _ : state) {
    for (uint32_t p = 0; p < kBatch; ++p) {
      RandomStream stream(7, step, p, kMotion);
      for (int k = 0; k < count; ++k) rows[k * kBatch + p] = stream.NextNormal();
    }
    ++step;
    benchmark::DoNotOptimize(rows.data());
    benchmark::ClobberMemory();
  }
  SetPerParticleCounters(state);
}
BENCHMARK(BM_NormalsScalar)->ArgName("count")->Arg(1)->Arg(3)->Arg(6);

// Arguments: draws per particle, Highway target (0: whatever the dispatcher picks).
void BM_DrawNormals(benchmark::State& state) {
  const int count = static_cast<int>(state.range(0));
  const int64_t target = state.range(1);
  if (target != 0) hwy::SetSupportedTargetsForTest(target);
  std::vector<double> rows(size_t{kMaxBatchNormals} * kBatch);
  double* out[kMaxBatchNormals];
  for (int k = 0; k < kMaxBatchNormals; ++k) out[k] = rows.data() + k * kBatch;
  uint64_t step = 0;
  uint64_t scalar = 0;
  for (auto _ : state) {
    scalar += DrawNormals(7, step++, kMotion, 0, kBatch, std::span<double* const>(out, count));
    benchmark::DoNotOptimize(rows.data());
    benchmark::ClobberMemory();
  }
  SetPerParticleCounters(state);
  state.counters["scalar_fraction"] =
      static_cast<double>(scalar) / (static_cast<double>(state.iterations()) * kBatch);
  state.SetLabel(hwy::TargetName(DrawNormalsTarget()));
  if (target != 0) hwy::SetSupportedTargetsForTest(0);
}

void EveryTarget(benchmark::internal::Benchmark* b) {
  for (int count : {1, 3, 6}) b->Args({count, 0});
  for (int64_t target : hwy::SupportedAndGeneratedTargets()) b->Args({3, target});
}
BENCHMARK(BM_DrawNormals)->ArgNames({"count", "target"})->Apply(EveryTarget);

}  // namespace
}  // namespace grove

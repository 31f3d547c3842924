// Sines and cosines of 512 angles in [-1000, 1000]: SinCos (SIMD), as dispatched and on every
// Highway target this CPU runs, against std::sin and std::cos. time_per_angle is seconds per
// angle (2.5n = 2.5 ns).
#include <benchmark/benchmark.h>
#include <hwy/highway.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "concurrency/sin_cos.h"

namespace grove {
namespace {

constexpr size_t kAngles = 512;

std::vector<double> Angles() {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(-1000, 1000);
  std::vector<double> x(kAngles);
  for (double& v : x) v = uniform(rng);
  return x;
}

void SetPerAngleCounters(benchmark::State& state) {
  state.SetItemsProcessed(state.iterations() * kAngles);
  state.counters["time_per_angle"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * kAngles,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_StdSinCos(benchmark::State& state) {
  const std::vector<double> x = Angles();
  std::vector<double> s(kAngles), c(kAngles);
  for (auto _ : state) {
    for (size_t i = 0; i < kAngles; ++i) {
      s[i] = std::sin(x[i]);
      c[i] = std::cos(x[i]);
    }
    benchmark::DoNotOptimize(s.data());
    benchmark::DoNotOptimize(c.data());
    benchmark::ClobberMemory();
  }
  SetPerAngleCounters(state);
}
BENCHMARK(BM_StdSinCos);

void BM_SinCosReference(benchmark::State& state) {
  const std::vector<double> x = Angles();
  std::vector<double> s(kAngles), c(kAngles);
  for (auto _ : state) {
    SinCosReference(x.data(), kAngles, s.data(), c.data());
    benchmark::DoNotOptimize(s.data());
    benchmark::DoNotOptimize(c.data());
    benchmark::ClobberMemory();
  }
  SetPerAngleCounters(state);
}
BENCHMARK(BM_SinCosReference);

// Argument: the Highway target (0: whatever the dispatcher picks).
void BM_SinCos(benchmark::State& state) {
  const int64_t target = state.range(0);
  if (target != 0) hwy::SetSupportedTargetsForTest(target);
  const std::vector<double> x = Angles();
  std::vector<double> s(kAngles), c(kAngles);
  for (auto _ : state) {
    SinCos(x.data(), kAngles, s.data(), c.data());
    benchmark::DoNotOptimize(s.data());
    benchmark::DoNotOptimize(c.data());
    benchmark::ClobberMemory();
  }
  SetPerAngleCounters(state);
  state.SetLabel(target != 0 ? hwy::TargetName(target) : "dispatched");
  if (target != 0) hwy::SetSupportedTargetsForTest(0);
}

void EveryTarget(benchmark::internal::Benchmark* b) {
  b->Arg(0);
  for (int64_t target : hwy::SupportedAndGeneratedTargets()) b->Arg(target);
}
BENCHMARK(BM_SinCos)->ArgName("target")->Apply(EveryTarget);

}  // namespace
}  // namespace grove

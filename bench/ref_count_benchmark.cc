// Reference-count increments and decrements: one thread alone, and every thread on one count.
#include <benchmark/benchmark.h>

#include "concurrency/ref_count.h"

namespace grove {
namespace {

void BM_RefCountUncontended(benchmark::State& state) {
  RefCount rc;
  for (auto _ : state) {
    rc.Acquire();
    benchmark::DoNotOptimize(rc.Release());
  }
  state.SetItemsProcessed(state.iterations() * 2);
}
BENCHMARK(BM_RefCountUncontended);

RefCount shared_count;

void BM_RefCountContended(benchmark::State& state) {
  for (auto _ : state) {
    shared_count.Acquire();
    benchmark::DoNotOptimize(shared_count.Release());
  }
  state.SetItemsProcessed(state.iterations() * 2);
}
BENCHMARK(BM_RefCountContended)->Threads(1)->Threads(2)->UseRealTime();

}  // namespace
}  // namespace grove

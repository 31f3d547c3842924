// Node pool against jemalloc (malloc/free, linked into this program): a generation of nodes is
// allocated, then freed in LIFO or random order, then allocated again. Random-order frees are
// what a particle filter does when a generation dies.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <random>
#include <vector>

#include "alloc/node_pool.h"

namespace grove {
namespace {

constexpr size_t kNodeBytes = 144;  // a degree-16 inner node

template <bool kRandomOrder>
void BM_PoolGeneration(benchmark::State& state) {
  const size_t n = static_cast<size_t>(state.range(0));
  NodePool pool(kNodeBytes, 1);
  std::vector<void*> nodes(n);
  std::mt19937_64 rng(5);
  for (auto& p : nodes) p = pool.Allocate(0);
  for (auto _ : state) {
    if (kRandomOrder) std::shuffle(nodes.begin(), nodes.end(), rng);
    for (void* p : nodes) pool.Free(p, 0);
    for (auto& p : nodes) {
      p = pool.Allocate(0);
      static_cast<char*>(p)[0] = 1;  // touch: allocation locality is part of the cost
    }
  }
  for (void* p : nodes) pool.Free(p, 0);
  state.SetItemsProcessed(state.iterations() * n);
}

template <bool kRandomOrder>
void BM_MallocGeneration(benchmark::State& state) {
  const size_t n = static_cast<size_t>(state.range(0));
  std::vector<void*> nodes(n);
  std::mt19937_64 rng(5);
  for (auto& p : nodes) p = std::malloc(kNodeBytes);
  for (auto _ : state) {
    if (kRandomOrder) std::shuffle(nodes.begin(), nodes.end(), rng);
    for (void* p : nodes) std::free(p);
    for (auto& p : nodes) {
      p = std::malloc(kNodeBytes);
      static_cast<char*>(p)[0] = 1;
    }
  }
  for (void* p : nodes) std::free(p);
  state.SetItemsProcessed(state.iterations() * n);
}

// Each item is one free plus one allocation (the shuffle is included for both allocators).
BENCHMARK(BM_PoolGeneration<false>)->Name("BM_PoolGeneration/lifo")->Arg(1 << 20);
BENCHMARK(BM_PoolGeneration<true>)->Name("BM_PoolGeneration/random")->Arg(1 << 20);
BENCHMARK(BM_MallocGeneration<false>)->Name("BM_JemallocGeneration/lifo")->Arg(1 << 20);
BENCHMARK(BM_MallocGeneration<true>)->Name("BM_JemallocGeneration/random")->Arg(1 << 20);

// Cross-thread frees: another slot frees, the owner allocates again.
void BM_PoolRemoteFree(benchmark::State& state) {
  NodePool pool(kNodeBytes, 2);
  std::vector<void*> nodes(1 << 16);
  for (auto& p : nodes) p = pool.Allocate(0);
  for (auto _ : state) {
    for (void* p : nodes) pool.Free(p, 1);
    for (auto& p : nodes) p = pool.Allocate(0);
  }
  for (void* p : nodes) pool.Free(p, 0);
  state.SetItemsProcessed(state.iterations() * nodes.size());
}
BENCHMARK(BM_PoolRemoteFree);

}  // namespace
}  // namespace grove

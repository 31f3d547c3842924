// Micro-benchmarks of the persistent trie: find, update (unique and shared), version copy.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "engine/persistent/persistent_trie.h"
#include "tests/engine/trie_testing.h"

namespace grove {
namespace {

struct Leaf {
  uint32_t c[6];
};

// A map of 20,000 keys clustered like a walked area: keys are H-tree paths of nearby cells, so
// the tree height for 65,536 hexagons is log_s(65536).
template <int kLog2>
struct Fixture {
  static constexpr int kHeight = 16 / kLog2 + (16 % kLog2 != 0);
  PersistentTrie<Leaf, kLog2> trie{kHeight, 1};
  typename PersistentTrie<Leaf, kLog2>::Root root = nullptr;
  std::vector<uint64_t> keys;
  Fixture() {
    std::mt19937_64 rng(1);
    for (int i = 0; i < 20000; ++i) keys.push_back(rng() % 65536);
    for (uint64_t k : keys) root = TrieUpdated(trie, root, k, 0, [](Leaf& l, bool) { ++l.c[0]; });
  }
  ~Fixture() { trie.Release(root, 0); }
};

template <int kLog2>
void BM_TrieFind(benchmark::State& state) {
  Fixture<kLog2> f;
  size_t i = 0;
  uint64_t sum = 0;
  for (auto _ : state) {
    const Leaf* l = f.trie.Find(f.root, f.keys[i++ % f.keys.size()]);
    sum += l->c[0];
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations());
}

// Update of a uniquely owned version: mutates in place.
template <int kLog2>
void BM_TrieUpdateUnique(benchmark::State& state) {
  Fixture<kLog2> f;
  size_t i = 0;
  for (auto _ : state) {
    f.root = TrieUpdated(f.trie, f.root, f.keys[i++ % f.keys.size()], 0,
                         [](Leaf& l, bool) { ++l.c[1]; });
  }
  state.SetItemsProcessed(state.iterations());
}

// Update of a version shared with another: copies one path (the FootSLAM case after resampling).
template <int kLog2>
void BM_TrieUpdateShared(benchmark::State& state) {
  Fixture<kLog2> f;
  size_t i = 0;
  for (auto _ : state) {
    auto* copy = PersistentTrie<Leaf, kLog2>::Share(f.root);
    copy =
        TrieUpdated(f.trie, copy, f.keys[i++ % f.keys.size()], 0, [](Leaf& l, bool) { ++l.c[1]; });
    f.trie.Release(copy, 0);
  }
  state.SetItemsProcessed(state.iterations());
}

template <int kLog2>
void BM_TrieVersionCopy(benchmark::State& state) {
  Fixture<kLog2> f;
  for (auto _ : state) {
    auto* copy = PersistentTrie<Leaf, kLog2>::Share(f.root);
    benchmark::DoNotOptimize(copy);
    f.trie.Release(copy, 0);
  }
  state.SetItemsProcessed(state.iterations());
}

BENCHMARK(BM_TrieFind<2>)->Name("BM_TrieFind/degree:4");
BENCHMARK(BM_TrieFind<4>)->Name("BM_TrieFind/degree:16");
BENCHMARK(BM_TrieFind<6>)->Name("BM_TrieFind/degree:64");
BENCHMARK(BM_TrieUpdateUnique<2>)->Name("BM_TrieUpdateUnique/degree:4");
BENCHMARK(BM_TrieUpdateUnique<4>)->Name("BM_TrieUpdateUnique/degree:16");
BENCHMARK(BM_TrieUpdateUnique<6>)->Name("BM_TrieUpdateUnique/degree:64");
BENCHMARK(BM_TrieUpdateShared<2>)->Name("BM_TrieUpdateShared/degree:4");
BENCHMARK(BM_TrieUpdateShared<4>)->Name("BM_TrieUpdateShared/degree:16");
BENCHMARK(BM_TrieUpdateShared<6>)->Name("BM_TrieUpdateShared/degree:64");
BENCHMARK(BM_TrieVersionCopy<4>)->Name("BM_TrieVersionCopy/degree:16");

}  // namespace
}  // namespace grove

// Bounded multi-threaded stress: many threads update and release versions that share nodes.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <thread>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/persistent/persistent_trie.h"
#include "tests/engine/trie_testing.h"

namespace grove {
namespace {

struct Value {
  uint64_t v;
};
using Trie = PersistentTrie<Value, 2>;

// Generations of versions, as in a particle filter: every version is updated in parallel, then
// the next generation copies random parents and the old one is released in parallel.
TEST(PersistentTrieStressTest, ParallelGenerationsMatchReference) {
  for (int threads : {2, 4}) {
    SCOPED_TRACE(testing::Message() << "threads " << threads << " seed 99");
    WorkerPool workers(threads);
    Trie trie(7, workers.num_slots());
    const size_t n = 256;
    std::vector<Trie::Root> roots(n, nullptr);
    std::vector<std::map<uint64_t, uint64_t>> models(n);
    std::mt19937_64 rng(99);
    for (int round = 0; round < 60; ++round) {
      std::vector<uint64_t> keys(n * 4);
      for (auto& k : keys) k = rng() % 16384;
      workers.ParallelFor(n, 4, [&](int slot, size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) {
          for (int j = 0; j < 4; ++j) {
            roots[i] = TrieUpdated(trie, roots[i], keys[i * 4 + j], slot,
                                   [&](Value& x, bool) { x.v += i; });
          }
        }
      });
      for (size_t i = 0; i < n; ++i) {
        for (int j = 0; j < 4; ++j) models[i][keys[i * 4 + j]] += i;
      }
      std::vector<uint32_t> parent(n);
      for (auto& p : parent) p = rng() % 8;  // few parents: heavy sharing
      std::vector<Trie::Root> next(n);
      std::vector<std::map<uint64_t, uint64_t>> next_models(n);
      for (size_t i = 0; i < n; ++i) {
        next[i] = Trie::Share(roots[parent[i]]);
        next_models[i] = models[parent[i]];
      }
      workers.ParallelFor(n, 4, [&](int slot, size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) trie.Release(roots[i], slot);
      });
      roots.swap(next);
      models.swap(next_models);
    }
    for (size_t i = 0; i < n; ++i) {
      std::map<uint64_t, uint64_t> seen;
      trie.ForEach(roots[i], [&](uint64_t k, const Value& x) { seen[k] = x.v; });
      ASSERT_EQ(seen, models[i]) << "version " << i;
    }
    workers.ParallelFor(n, 4, [&](int slot, size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) trie.Release(roots[i], slot);
    });
    EXPECT_EQ(trie.live_nodes(), 0);
  }
}

// Free-running threads share, update and drop versions derived from one base at the same time.
TEST(PersistentTrieStressTest, ConcurrentShareUpdateReleaseKeepsBaseIntact) {
  constexpr int kThreads = 4;
  Trie trie(6, kThreads);
  Trie::Root base = nullptr;
  for (uint64_t k = 0; k < 4096; k += 3)
    base = TrieUpdated(trie, base, k, 0, [&](Value& x, bool) { x.v = k; });
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      std::mt19937_64 rng(t + 1);
      std::vector<Trie::Root> mine;
      for (int i = 0; i < 20000; ++i) {
        if (mine.empty() || rng() % 4 == 0) {
          mine.push_back(Trie::Share(base));
        } else if (rng() % 3 == 0) {
          size_t j = rng() % mine.size();
          trie.Release(mine[j], t);
          mine[j] = mine.back();
          mine.pop_back();
        } else {
          size_t j = rng() % mine.size();
          mine[j] =
              TrieUpdated(trie, mine[j], rng() % 4096, t, [](Value& x, bool) { x.v += 1000000; });
          if (rng() % 5 == 0) mine.push_back(Trie::Share(mine[j]));
        }
      }
      for (auto r : mine) trie.Release(r, t);
    });
  }
  for (auto& th : threads) th.join();
  for (uint64_t k = 0; k < 4096; ++k) {
    const Value* x = trie.Find(base, k);
    if (k % 3 == 0) {
      ASSERT_NE(x, nullptr);
      ASSERT_EQ(x->v, k);
    } else {
      ASSERT_EQ(x, nullptr);
    }
  }
  trie.Release(base, 0);
  EXPECT_EQ(trie.live_nodes(), 0);
}

}  // namespace
}  // namespace grove

#include "engine/persistent/persistent_trie.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "tests/engine/trie_testing.h"

namespace grove {
namespace {

struct Value {
  uint64_t v;
};

// Random operations on a handful of live versions, each checked against a std::map copy
// (immer's model-based fuzzing).
template <int kLog2Degree, int kLog2BottomDegree = kLog2Degree>
void RunModelCheck(int height, uint64_t seed, int ops, uint64_t key_space) {
  SCOPED_TRACE(testing::Message() << "seed " << seed << " degree " << (1 << kLog2Degree)
                                  << " bottom degree " << (1 << kLog2BottomDegree) << " height "
                                  << height);
  using Trie = PersistentTrie<Value, kLog2Degree, kLog2BottomDegree>;
  Trie trie(height, 1);
  constexpr int kVersions = 8;
  std::vector<typename Trie::Root> roots(kVersions, nullptr);
  std::vector<std::map<uint64_t, uint64_t>> models(kVersions);
  std::mt19937_64 rng(seed);
  uint64_t limit = trie.key_count() == 0 ? key_space : std::min(key_space, trie.key_count());
  auto check = [&](int v) {
    std::map<uint64_t, uint64_t> seen;
    trie.ForEach(roots[v], [&](uint64_t k, const Value& x) { seen[k] = x.v; });
    ASSERT_EQ(seen, models[v]) << "version " << v;
  };
  for (int op = 0; op < ops; ++op) {
    int v = rng() % kVersions;
    switch (rng() % 10) {
      case 0: {  // copy another version over this one
        int from = rng() % kVersions;
        typename Trie::Root copy = Trie::Share(roots[from]);
        trie.Release(roots[v], 0);
        roots[v] = copy;
        models[v] = models[from];
        break;
      }
      case 1:  // drop the version
        if (rng() % 4 == 0) {
          trie.Release(roots[v], 0);
          roots[v] = nullptr;
          models[v].clear();
        }
        break;
      case 2:
      case 3: {  // look up
        uint64_t k = rng() % limit;
        const Value* found = trie.Find(roots[v], k);
        auto it = models[v].find(k);
        ASSERT_EQ(found != nullptr, it != models[v].end()) << "key " << k;
        if (found != nullptr) {
          ASSERT_EQ(found->v, it->second);
        }
        break;
      }
      case 4: {  // erase a key, present or not
        const uint64_t k = models[v].empty() || rng() % 2 == 0
                               ? rng() % limit
                               : std::next(models[v].begin(), rng() % models[v].size())->first;
        ASSERT_TRUE(trie.Erase(&roots[v], k, 0));
        models[v].erase(k);
        break;
      }
      default: {  // update
        uint64_t k = rng() % limit;
        uint64_t add = rng() % 1000 + 1;
        bool expect_existed = models[v].count(k) > 0;
        bool existed = false;
        roots[v] = TrieUpdated(trie, roots[v], k, 0, [&](Value& x, bool e) {
          existed = e;
          x.v += add;
        });
        ASSERT_EQ(existed, expect_existed);
        models[v][k] += add;
        break;
      }
    }
    if (op % 97 == 0) {
      for (int w = 0; w < kVersions; ++w) check(w);
    }
  }
  for (int w = 0; w < kVersions; ++w) check(w);
  for (auto& r : roots) trie.Release(r, 0);
  EXPECT_EQ(trie.live_nodes(), 0) << "nodes leaked";
}

TEST(PersistentTrieTest, MatchesReferenceMapDegree2) {
  for (uint64_t seed = 1; seed <= 3; ++seed) RunModelCheck<1>(10, seed, 20000, 1 << 10);
}
TEST(PersistentTrieTest, MatchesReferenceMapDegree4) {
  for (uint64_t seed = 1; seed <= 3; ++seed) RunModelCheck<2>(8, seed, 20000, 300);
}
TEST(PersistentTrieTest, MatchesReferenceMapDegree16) {
  for (uint64_t seed = 1; seed <= 3; ++seed) RunModelCheck<4>(4, seed, 20000, 1 << 16);
}
TEST(PersistentTrieTest, MatchesReferenceMapDegree64) { RunModelCheck<6>(2, 11, 20000, 4096); }
TEST(PersistentTrieTest, MatchesReferenceMapDegree256) { RunModelCheck<8>(2, 12, 10000, 1 << 16); }
TEST(PersistentTrieTest, MatchesReferenceMapHeightOne) { RunModelCheck<4>(1, 13, 5000, 16); }
TEST(PersistentTrieTest, MatchesReferenceMapFullWidthKeys) {
  RunModelCheck<4>(16, 14, 20000, ~uint64_t{0});
}
// Bottom nodes wider than inner ones store their leaves packed, in size classes (for these
// 8-byte leaves: 3, 11, 27, 59, 123 and all 256 at 256 digits; 6 and 16 at 16; 6, 14, 30 and 64
// at 64), moved to a larger class as keys arrive.
TEST(PersistentTrieTest, WideBottomNodesComeInSizeClassesOfWholeLines) {
  using Wide = PersistentTrie<Value, 4, 8>;
  EXPECT_EQ(Wide::BottomBytesFor(1), 64u);
  EXPECT_EQ(Wide::BottomBytesFor(3), 64u);
  EXPECT_EQ(Wide::BottomBytesFor(4), 128u);
  EXPECT_EQ(Wide::BottomBytesFor(123), 1024u);
  EXPECT_EQ(Wide::BottomBytesFor(124), 40u + 256 * 8);  // presence words and every digit
  // A bottom node as wide as an inner one holds every digit: one class, as before.
  using Narrow = PersistentTrie<Value, 4>;
  EXPECT_EQ(Narrow::BottomBytesFor(1), 16u + 16 * 8);
}
TEST(PersistentTrieTest, MatchesReferenceMapWideBottoms) {
  for (uint64_t seed = 1; seed <= 3; ++seed) RunModelCheck<4, 8>(3, seed, 20000, 1 << 16);
  RunModelCheck<4, 8>(2, 4, 20000, 2000);  // dense: full bottom nodes
  RunModelCheck<2, 4>(4, 5, 20000, 300);
  RunModelCheck<2, 6>(2, 6, 20000, 256);
  RunModelCheck<4, 8>(1, 7, 5000, 256);  // height one: the root is a bottom node
  RunModelCheck<4, 8>(15, 8, 20000, ~uint64_t{0});
}

TEST(PersistentTrieTest, UpdateDoesNotChangeOtherVersions) {
  PersistentTrie<Value, 4> trie(4, 1);
  auto* a = TrieUpdated(trie, nullptr, 1234, 0, [](Value& x, bool) { x.v = 1; });
  auto* b = decltype(trie)::Share(a);
  b = TrieUpdated(trie, b, 1234, 0, [](Value& x, bool) { x.v = 2; });
  b = TrieUpdated(trie, b, 999, 0, [](Value& x, bool) { x.v = 3; });
  EXPECT_EQ(trie.Find(a, 1234)->v, 1u);
  EXPECT_EQ(trie.Find(a, 999), nullptr);
  EXPECT_EQ(trie.Find(b, 1234)->v, 2u);
  EXPECT_EQ(trie.Find(b, 999)->v, 3u);
  trie.Release(a, 0);
  trie.Release(b, 0);
  EXPECT_EQ(trie.live_nodes(), 0);
}

TEST(PersistentTrieTest, UniqueVersionIsUpdatedInPlace) {
  PersistentTrie<Value, 4> trie(4, 1);
  auto* root = TrieUpdated(trie, nullptr, 77, 0, [](Value& x, bool) { x.v = 1; });
  EXPECT_EQ(trie.live_nodes(), 4);
  auto* again = TrieUpdated(trie, root, 77, 0, [](Value& x, bool) { x.v++; });
  EXPECT_EQ(again, root);
  EXPECT_EQ(trie.live_nodes(), 4);
  // A key in the same bottom node adds nothing; one in another subtree adds only its path.
  root = TrieUpdated(trie, root, 78, 0, [](Value& x, bool) { x.v = 5; });
  EXPECT_EQ(trie.live_nodes(), 4);
  root = TrieUpdated(trie, root, 77 + (1 << 12), 0, [](Value& x, bool) { x.v = 5; });
  EXPECT_EQ(trie.live_nodes(), 7);
  trie.Release(root, 0);
  EXPECT_EQ(trie.live_nodes(), 0);
}

TEST(PersistentTrieTest, SharedVersionCopiesOnlyThePath) {
  PersistentTrie<Value, 4> trie(4, 1);
  decltype(trie)::Root root = nullptr;
  for (uint64_t k = 0; k < 65536; k += 97) {
    root = TrieUpdated(trie, root, k, 0, [&](Value& x, bool) { x.v = k; });
  }
  int64_t before = trie.live_nodes();
  auto* copy = decltype(trie)::Share(root);
  EXPECT_EQ(trie.live_nodes(), before);  // O(1) copy: no node allocated
  copy = TrieUpdated(trie, copy, 97 * 5, 0, [](Value& x, bool) { x.v = 0; });
  EXPECT_EQ(trie.live_nodes(), before + 4);  // one path of height 4
  EXPECT_EQ(trie.CountNodes(copy), trie.CountNodes(root));
  trie.Release(root, 0);
  trie.Release(copy, 0);
  EXPECT_EQ(trie.live_nodes(), 0);
}

// ReleaseMany frees exactly what Release one by one frees: two tries built by the same random
// updates and shares, one released each way, keep the same live nodes and the same contents.
// With more than one slot ReleaseMany sums drops of one node first, with one it does not: both.
template <typename Trie = PersistentTrie<Value, 4>>
void CheckReleaseManyFreesWhatReleaseFrees(int slots) {
  SCOPED_TRACE(testing::Message() << slots << " slots");
  const int last = slots - 1;
  Trie one(4, slots), many(4, slots);
  constexpr int kVersions = 300;
  std::vector<typename Trie::Root> a(kVersions, nullptr), b(kVersions, nullptr);
  std::mt19937_64 rng(21);
  for (int round = 0; round < 6; ++round) {
    for (int op = 0; op < 4000; ++op) {
      int v = rng() % kVersions;
      if (rng() % 4 == 0) {
        int from = rng() % kVersions;
        typename Trie::Root ca = Trie::Share(a[from]);
        typename Trie::Root cb = Trie::Share(b[from]);
        one.Release(a[v], 0);
        many.Release(b[v], 0);
        a[v] = ca;
        b[v] = cb;
      } else {
        uint64_t key = rng() % 65536;
        uint64_t val = rng();
        a[v] = TrieUpdated(one, a[v], key, 0, [&](Value& x, bool) { x.v = val; });
        b[v] = TrieUpdated(many, b[v], key, 0, [&](Value& x, bool) { x.v = val; });
      }
    }
    // Release a random half (and some nullptr entries), in two spans, from the last slot.
    std::vector<typename Trie::Root> dead_a, dead_b;
    for (int v = 0; v < kVersions; ++v) {
      if (rng() % 2 == 0) {
        dead_a.push_back(a[v]);
        dead_b.push_back(b[v]);
        a[v] = b[v] = nullptr;
      }
    }
    for (typename Trie::Root r : dead_a) one.Release(r, last);
    std::span<typename Trie::Root const> all(dead_b);
    many.ReleaseMany(all.first(all.size() / 2), last);
    many.ReleaseMany(all.subspan(all.size() / 2), last);
    ASSERT_EQ(one.live_nodes(), many.live_nodes()) << "round " << round;
    for (int v = 0; v < kVersions; ++v) {
      std::map<uint64_t, uint64_t> ma, mb;
      one.ForEach(a[v], [&](uint64_t k, const Value& x) { ma[k] = x.v; });
      many.ForEach(b[v], [&](uint64_t k, const Value& x) { mb[k] = x.v; });
      ASSERT_EQ(ma, mb) << "round " << round << " version " << v;
    }
  }
  many.ReleaseMany(b, 0);
  for (typename Trie::Root r : a) one.Release(r, 0);
  EXPECT_EQ(one.live_nodes(), 0);
  EXPECT_EQ(many.live_nodes(), 0);
}

TEST(PersistentTrieTest, ReleaseManyFreesWhatReleaseFrees) {
  CheckReleaseManyFreesWhatReleaseFrees(1);
  CheckReleaseManyFreesWhatReleaseFrees(2);
  CheckReleaseManyFreesWhatReleaseFrees<PersistentTrie<Value, 4, 8>>(2);
}

TEST(PersistentTrieTest, DistinctVisitSumsEqualBruteForce) {
  using Trie = PersistentTrie<Value, 2>;
  Trie trie(6, 1);
  std::mt19937_64 rng(5);
  std::vector<Trie::Root> roots(200, nullptr);
  for (uint64_t k = 0; k < 4096; k += 2) {
    roots[0] = TrieUpdated(trie, roots[0], k, 0, [](Value& x, bool) { x.v = 1; });
  }
  // A family of versions: each copies an earlier one and changes a few keys.
  for (size_t i = 1; i < roots.size(); ++i) {
    roots[i] = Trie::Share(roots[rng() % i]);
    for (int j = 0; j < 3; ++j) {
      roots[i] =
          TrieUpdated(trie, roots[i], rng() % 4096, 0, [&](Value& x, bool) { x.v += rng() % 9; });
    }
  }
  std::vector<uint64_t> weights(roots.size());
  for (auto& w : weights) w = rng() % 1000;
  std::map<uint64_t, uint64_t> distinct_sum, brute_sum;
  size_t distinct = trie.VisitDistinct<uint64_t>(
      roots, weights, [&](uint64_t k, const Value& x, uint64_t w) { distinct_sum[k] += x.v * w; });
  size_t total_nodes = 0;
  for (size_t i = 0; i < roots.size(); ++i) {
    total_nodes += trie.CountNodes(roots[i]);
    trie.ForEach(roots[i], [&](uint64_t k, const Value& x) { brute_sum[k] += x.v * weights[i]; });
  }
  EXPECT_EQ(distinct_sum, brute_sum);
  EXPECT_EQ(static_cast<int64_t>(distinct), trie.live_nodes());
  EXPECT_LT(distinct * 10, total_nodes);  // sharing makes the visit much cheaper
  for (auto& r : roots) trie.Release(r, 0);
  EXPECT_EQ(trie.live_nodes(), 0);
}

// Versions that share nodes in every way Update() and Share() make them.
template <typename Trie>
std::vector<typename Trie::Root> SharedVersions(Trie* trie, int versions, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<typename Trie::Root> roots(versions, nullptr);
  for (int op = 0; op < 400; ++op) {
    int v = rng() % versions;
    if (rng() % 5 == 0) {
      typename Trie::Root copy = Trie::Share(roots[rng() % versions]);
      trie->Release(roots[v], 0);
      roots[v] = copy;
    } else {
      uint64_t key = rng() % std::min<uint64_t>(trie->key_count(), 300);
      roots[v] = TrieUpdated(*trie, roots[v], key, 0, [&](Value& x, bool) { x.v = rng(); });
    }
  }
  roots.push_back(nullptr);  // the empty version too
  return roots;
}

template <typename Trie>
std::map<uint64_t, uint64_t> Contents(const Trie& trie, typename Trie::Root root) {
  std::map<uint64_t, uint64_t> m;
  trie.ForEach(root, [&](uint64_t k, const Value& x) { m[k] = x.v; });
  return m;
}

TEST(PersistentTrieSaveTest, LoadRebuildsEveryVersionWithItsSharing) {
  using Trie = PersistentTrie<Value, 4>;
  Trie trie(3, 1);
  auto roots = SharedVersions(&trie, 10, 5);
  ByteWriter w;
  trie.Save(roots, &w);
  std::string bytes = w.Take();

  Trie copy(3, 1);
  std::vector<Trie::Root> loaded;
  ByteReader r(bytes, "t");
  ASSERT_TRUE(copy.Load(
                      &r, roots.size(), 0, [](const Value&) { return true; }, &loaded)
                  .ok());
  EXPECT_TRUE(r.at_end());
  ASSERT_EQ(loaded.size(), roots.size());
  for (size_t v = 0; v < roots.size(); ++v) {
    EXPECT_EQ(Contents(copy, loaded[v]), Contents(trie, roots[v])) << v;
  }
  // The same distinct nodes, and every count right: releasing all versions frees everything,
  // and updating one loaded version leaves the others as they were.
  EXPECT_EQ(copy.live_nodes(), trie.live_nodes());
  auto before = Contents(copy, loaded[1]);
  loaded[0] = TrieUpdated(copy, loaded[0], 7, 0, [](Value& x, bool) { x.v = 42; });
  EXPECT_EQ(Contents(copy, loaded[1]), before);
  for (auto* root : loaded) copy.Release(root, 0);
  EXPECT_EQ(copy.live_nodes(), 0);
  for (auto* root : roots) trie.Release(root, 0);
}

TEST(PersistentTrieSaveTest, EveryTruncationAndBadStructureIsRefusedWithoutLeaks) {
  using Trie = PersistentTrie<Value, 2>;
  Trie trie(4, 1);
  auto roots = SharedVersions(&trie, 4, 9);
  ByteWriter w;
  trie.Save(roots, &w);
  const std::string good = w.Take();
  auto load = [&](const std::string& bytes, auto valid) {
    Trie copy(4, 1);
    std::vector<Trie::Root> loaded;
    ByteReader r(bytes, "t");
    Status s = copy.Load(&r, roots.size(), 0, valid, &loaded);
    if (s.ok()) {
      for (auto* root : loaded) copy.Release(root, 0);
    } else {
      EXPECT_TRUE(loaded.empty());
    }
    EXPECT_EQ(copy.live_nodes(), 0) << "a failed load left nodes allocated";
    return s;
  };
  auto any = [](const Value&) { return true; };
  ASSERT_TRUE(load(good, any).ok());
  for (size_t len = 0; len < good.size(); ++len) {
    Status s = load(good.substr(0, len), any);
    ASSERT_EQ(s.code(), StatusCode::kDataLoss) << len;
  }
  // A rejected leaf value.
  EXPECT_NE(load(good, [](const Value& x) { return x.v != 0 && x.v % 3 != 0; })
                .message()
                .find("trie leaf"),
            std::string::npos);
  // Layout after the u32 height and u64 count: u8 level, one presence word, then children or
  // leaves. The first node saved is a bottom node (level 3): claim it is a root-level node.
  std::string bad = good;
  bad[12] = 0;
  Status s = load(bad, any);
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  // A level past the height.
  bad = good;
  bad[12] = 9;
  EXPECT_NE(load(bad, any).message().find("not below the height"), std::string::npos);
  // A presence bit beyond the degree.
  bad = good;
  bad[13] |= 0x10;
  EXPECT_NE(load(bad, any).message().find("beyond the degree"), std::string::npos);
  // A height below the trie's minimum, a taller one whose levels then do not fit, and a
  // wrong root count.
  bad = good;
  bad[0] = 3;
  EXPECT_NE(load(bad, any).message().find("trie height"), std::string::npos);
  bad[0] = 5;
  EXPECT_EQ(load(bad, any).code(), StatusCode::kDataLoss);
  Trie other(4, 1);
  std::vector<Trie::Root> loaded;
  ByteReader r(good, "t");
  EXPECT_NE(other.Load(&r, roots.size() + 1, 0, any, &loaded).message().find("root count"),
            std::string::npos);
  EXPECT_EQ(other.live_nodes(), 0);
  for (auto* root : roots) trie.Release(root, 0);
}

TEST(PersistentTrieSaveTest, UnreachedAndForwardNodesAreRefused) {
  using Trie = PersistentTrie<Value, 2>;
  // Hand-made: height 2, node 0 = bottom with digit 0, node 1 = inner pointing at node 1
  // (itself, not an earlier node), one root.
  auto bytes = [](uint32_t child, uint32_t root) {
    ByteWriter w;
    w.Put<uint32_t>(2);
    w.Put<uint64_t>(2);
    w.Put<uint8_t>(1);
    w.Put<uint64_t>(1);
    w.Put<uint64_t>(5);  // the leaf
    w.Put<uint8_t>(0);
    w.Put<uint64_t>(1);
    w.Put<uint32_t>(child);
    w.Put<uint64_t>(1);
    w.Put<uint32_t>(root);
    return w.Take();
  };
  auto load = [](const std::string& b) {
    Trie trie(2, 1);
    std::vector<Trie::Root> roots;
    ByteReader r(b, "t");
    Status s = trie.Load(
        &r, 1, 0, [](const Value&) { return true; }, &roots);
    for (auto* root : roots) trie.Release(root, 0);
    EXPECT_EQ(trie.live_nodes(), 0);
    return s;
  };
  EXPECT_TRUE(load(bytes(0, 2)).ok());
  EXPECT_NE(load(bytes(1, 2)).message().find("not an earlier node"), std::string::npos);
  EXPECT_NE(load(bytes(0, 1)).message().find("not a node that can start a version"),
            std::string::npos);
  EXPECT_NE(load(bytes(0, 0)).message().find("reached from nothing"), std::string::npos);
}

}  // namespace
}  // namespace grove

namespace grove {
namespace {

// Random updates and copies on a family of versions, mirrored in std::map models: one operation
// in `copy_one_in` copies a random version over another, the others set the key next_key() gives.
template <typename Trie, typename K>
void GrowFamily(Trie* trie, std::vector<typename Trie::Root>* roots,
                std::vector<std::map<uint64_t, uint64_t>>* models, std::mt19937_64* rng, int ops,
                int copy_one_in, K&& next_key) {
  for (int op = 0; op < ops; ++op) {
    const size_t v = (*rng)() % roots->size();
    if ((*rng)() % copy_one_in == 0) {
      const size_t from = (*rng)() % roots->size();
      typename Trie::Root copy = Trie::Share((*roots)[from]);
      trie->Release((*roots)[v], 0);
      (*roots)[v] = copy;
      (*models)[v] = (*models)[from];
      continue;
    }
    const uint64_t key = next_key();
    ASSERT_TRUE(trie->Update(&(*roots)[v], key, 0, [&](Value& x, bool) { x.v = key ^ op; }));
    (*models)[v][key] = key ^ op;
  }
}

// A trie without a preset size: versions grow in height as keys need, share subtrees across
// heights, and match std::map over full 64-bit keys. Keys are drawn as the fill key with its low
// bits changed, so versions of every height meet; the distinct visit sums what every version's
// own walk sums, and save and load keep every version and its sharing.
template <typename Trie = PersistentTrie<Value, 4>>
void RunGrowthCheck(int min_height, uint64_t fill, uint64_t seed) {
  SCOPED_TRACE(testing::Message() << "min height " << min_height << " fill " << fill << " bottom "
                                  << Trie::kBottomDegree);
  Trie trie(min_height, 1, fill);
  std::mt19937_64 rng(seed);
  constexpr int kVersions = 6;
  std::vector<typename Trie::Root> roots(kVersions, nullptr);
  std::vector<std::map<uint64_t, uint64_t>> models(kVersions);
  // Keys of every size: small changes keep low versions low, large ones grow them.
  GrowFamily(&trie, &roots, &models, &rng, 20000, 8,
             [&] { return fill ^ (rng() >> (rng() % 64)); });
  for (int v = 0; v < kVersions; ++v) {
    for (const auto& [key, value] : models[v]) {
      ASSERT_GE(Trie::Height(roots[v]), std::max(min_height, Trie::HeightFor(key, trie.fill())));
      ASSERT_EQ(trie.Find(roots[v], key)->v, value);
    }
  }
  std::vector<uint64_t> weights(kVersions);
  std::map<uint64_t, uint64_t> brute;
  for (int v = 0; v < kVersions; ++v) {
    weights[v] = rng() % 1000;
    std::map<uint64_t, uint64_t> seen;
    trie.ForEach(roots[v], [&](uint64_t k, const Value& x) {
      seen[k] = x.v;
      brute[k] += x.v * weights[v];
    });
    EXPECT_EQ(seen, models[v]) << "version " << v;
  }
  std::map<uint64_t, uint64_t> distinct;
  trie.template VisitDistinct<uint64_t>(
      roots, weights, [&](uint64_t k, const Value& x, uint64_t w) { distinct[k] += x.v * w; });
  EXPECT_EQ(distinct, brute);
  EXPECT_TRUE(trie.CheckCounts(roots).ok()) << trie.CheckCounts(roots).ToString();
  ByteWriter w;
  trie.Save(roots, &w);
  const std::string bytes = w.Take();
  Trie copy(min_height, 1, fill);
  std::vector<typename Trie::Root> loaded;
  ByteReader r(bytes, "t");
  ASSERT_TRUE(copy.Load(
                      &r, roots.size(), 0, [](const Value&) { return true; }, &loaded)
                  .ok());
  for (int v = 0; v < kVersions; ++v) {
    std::map<uint64_t, uint64_t> seen;
    copy.ForEach(loaded[v], [&](uint64_t k, const Value& x) { seen[k] = x.v; });
    EXPECT_EQ(seen, models[v]) << "loaded version " << v;
  }
  EXPECT_EQ(copy.live_nodes(), trie.live_nodes());
  EXPECT_TRUE(copy.CheckCounts(loaded).ok());
  for (auto* root : loaded) copy.Release(root, 0);
  for (auto* root : roots) trie.Release(root, 0);
  EXPECT_EQ(trie.live_nodes(), 0);
  EXPECT_EQ(copy.live_nodes(), 0);
}

TEST(PersistentTrieGrowthTest, VersionsGrowPastAnyPresetHeightAndStayShared) {
  RunGrowthCheck(1, 0, 21);
}

// A fill key other than 0 (FootSLAM's growing grid): the missing levels stand for its digits.
TEST(PersistentTrieGrowthTest, VersionsGrowAroundANonZeroFillKey) {
  RunGrowthCheck(1, 0x0123456789abcdefULL, 22);
  RunGrowthCheck(3, 0xfedcba9876543210ULL, 23);
  RunGrowthCheck<PersistentTrie<Value, 4, 8>>(1, 0x0123456789abcdefULL, 24);
  RunGrowthCheck<PersistentTrie<Value, 4, 8>>(2, 0xfedcba9876543210ULL, 25);
}

TEST(PersistentTrieGrowthTest, TheFillKeysDigitsNameTheOldRootsPlace) {
  using Trie = PersistentTrie<Value, 4>;
  Trie trie(2, 1, 0x5a7u);  // digit 2 is 5; the low two digits are ignored
  EXPECT_EQ(trie.fill(), 0x500u);
  Trie::Root root = nullptr;
  ASSERT_TRUE(trie.Update(&root, 0x5c3, 0, [](Value& x, bool) { x.v = 1; }));
  EXPECT_EQ(Trie::Height(root), 2);  // digit 2 equals the fill's: the low version holds it
  Trie::Root low = Trie::Share(root);
  ASSERT_TRUE(trie.Update(&root, 0x3c3, 0, [](Value& x, bool) { x.v = 2; }));
  EXPECT_EQ(Trie::Height(root), 3);
  EXPECT_EQ(trie.Find(root, 0x5c3)->v, 1u);
  EXPECT_EQ(trie.Find(root, 0x3c3)->v, 2u);
  EXPECT_EQ(trie.Find(low, 0x3c3), nullptr);
  EXPECT_EQ(trie.Find(low, 0x0c3), nullptr);  // digit 2 is 0, not the fill's 5
  // A new root above the shared old one, and the new key's inner and bottom node.
  EXPECT_EQ(trie.CountNodes(root), trie.CountNodes(low) + 3);
  trie.Release(root, 0);
  trie.Release(low, 0);
  EXPECT_EQ(trie.live_nodes(), 0);
}

TEST(PersistentTrieGrowthTest, SmallKeysOfATallVersionAreFoundAndLargeKeysOfALowOneAreNot) {
  using Trie = PersistentTrie<Value, 2>;
  Trie trie(1, 1);
  Trie::Root root = nullptr;
  ASSERT_TRUE(trie.Update(&root, 3, 0, [](Value& x, bool) { x.v = 3; }));
  EXPECT_EQ(Trie::Height(root), 1);
  EXPECT_EQ(trie.Find(root, 1u << 20), nullptr);
  ASSERT_TRUE(trie.Update(&root, 1u << 20, 0, [](Value& x, bool) { x.v = 7; }));
  EXPECT_EQ(Trie::Height(root), 11);
  EXPECT_EQ(trie.Find(root, 3)->v, 3u);
  EXPECT_EQ(trie.Find(root, 1u << 20)->v, 7u);
  EXPECT_EQ(trie.Find(root, ~uint64_t{0}), nullptr);
  trie.Release(root, 0);
  EXPECT_EQ(trie.live_nodes(), 0);
}

// Versions sharing nodes in every way, some grown above the minimum height around a fill key;
// drops one subtree from all of them and checks every version against its model, the counts,
// that no node leaked, and that the drop adds fewer nodes than a path copy per version.
template <int kLog2BottomDegree = 2>
void RunDropCheck(uint64_t fill, uint64_t seed) {
  SCOPED_TRACE(testing::Message() << "fill " << fill << " seed " << seed << " bottom degree "
                                  << (1 << kLog2BottomDegree));
  using Trie = PersistentTrie<Value, 2, kLog2BottomDegree>;
  constexpr int kMin = 1 + (8 - kLog2BottomDegree) / 2;  // keys below 2^8 fit every version
  Trie trie(kMin, 1, fill);
  std::mt19937_64 rng(seed);
  constexpr int kVersions = 12;
  std::vector<typename Trie::Root> roots(kVersions, nullptr);
  std::vector<std::map<uint64_t, uint64_t>> models(kVersions);
  // Mostly keys of the minimum height, a few that grow a version.
  GrowFamily(&trie, &roots, &models, &rng, 3000, 6,
             [&] { return trie.fill() ^ (rng() % 50 == 0 ? rng() % 4096 : rng() % 256); });
  // Blocks of one digit, part of a bottom node when it is wider, and of 1, 2 and 3 levels.
  for (int shift : {0, 2, 4, 6}) {
    if (shift >= kLog2BottomDegree && (shift - kLog2BottomDegree) % 2 != 0) continue;
    SCOPED_TRACE(testing::Message() << "block bits " << shift);
    // The blocks some version holds, listed once each in key order.
    std::set<uint64_t> blocks;
    for (const auto& model : models) {
      for (const auto& kv : model) blocks.insert(kv.first >> shift);
    }
    EXPECT_EQ(trie.SubtreePrefixes(roots, shift),
              std::vector<uint64_t>(blocks.begin(), blocks.end()));
    // A block some version holds: the one of a key of version 0.
    ASSERT_FALSE(models[0].empty());
    const uint64_t prefix = models[0].begin()->first >> shift;
    // The subtree visit sums what each version's own walk of the block's keys sums.
    std::vector<uint64_t> weights(kVersions);
    std::map<uint64_t, uint64_t> brute, distinct;
    for (int v = 0; v < kVersions; ++v) {
      weights[v] = rng() % 100;
      for (const auto& [k, x] : models[v]) {
        if ((k >> shift) == prefix) brute[k] += x * weights[v];
      }
    }
    trie.template VisitSubtreeDistinct<uint64_t>(
        roots, weights, shift, prefix,
        [&](uint64_t k, const Value& x, uint64_t w) { distinct[k] += x.v * w; });
    ASSERT_FALSE(brute.empty());
    EXPECT_EQ(distinct, brute);
    const int64_t before = trie.live_nodes();
    ASSERT_TRUE(trie.DropSubtree(roots, shift, prefix, 0));
    for (int v = 0; v < kVersions; ++v) {
      std::erase_if(models[v], [&](const auto& kv) { return (kv.first >> shift) == prefix; });
      std::map<uint64_t, uint64_t> seen;
      trie.ForEach(roots[v], [&](uint64_t k, const Value& x) { seen[k] = x.v; });
      ASSERT_EQ(seen, models[v]) << "version " << v;
    }
    ASSERT_TRUE(trie.CheckCounts(roots).ok()) << trie.CheckCounts(roots).ToString();
    // Copies of path nodes replace the originals, which die once no version holds them: the
    // live nodes grow by fewer than the versions' path nodes (versions x height).
    EXPECT_LT(trie.live_nodes(), before + kVersions * 6);
  }
  for (auto* root : roots) trie.Release(root, 0);
  EXPECT_EQ(trie.live_nodes(), 0);
}

TEST(PersistentTrieDropTest, ASubtreeLeavesEveryVersionAndTheirSharingStays) {
  RunDropCheck(0, 1);
  RunDropCheck(0, 2);
  RunDropCheck(0x9c5u << 8, 3);  // a fill key: versions grown around it
  RunDropCheck<4>(0, 4);
  RunDropCheck<4>(0x9c5u << 8, 5);
  RunDropCheck<6>(0, 6);  // a bottom node of 64 under each root
}

// Dropping a subtree shared by many identical versions copies each path node once.
TEST(PersistentTrieDropTest, SharedPathsAreCopiedOnce) {
  using Trie = PersistentTrie<Value, 4>;
  Trie trie(3, 1);
  Trie::Root base = nullptr;
  for (uint64_t k = 0; k < 4096; k += 7) {
    base = TrieUpdated(trie, base, k, 0, [&](Value& x, bool) { x.v = k; });
  }
  std::vector<Trie::Root> roots(1000);
  for (auto& r : roots) r = Trie::Share(base);
  trie.Release(base, 0);
  const int64_t before = trie.live_nodes();
  ASSERT_TRUE(trie.DropSubtree(roots, 4, 0x12, 0));  // the bottom node of keys 0x120..0x12f
  // One new root and one new level-1 node, the old two and the bottom node freed.
  EXPECT_EQ(trie.live_nodes(), before - 1);
  for (Trie::Root r : roots) ASSERT_EQ(r, roots[0]);
  EXPECT_EQ(trie.Find(roots[0], 0x126), nullptr);
  EXPECT_NE(trie.Find(roots[0], 0x118), nullptr);  // 280 = 7 x 40, next to the block
  for (auto* root : roots) trie.Release(root, 0);
  EXPECT_EQ(trie.live_nodes(), 0);
}

// Every allocation of a drop fails in turn: the drop reports it and nothing changes or leaks.
TEST(PersistentTrieFaultTest, AFailedDropLeavesEveryVersionIntact) {
  using Trie = PersistentTrie<Value, 2>;
  int failures = 0;
  // Keys 48..63, and key 50 alone (a block within a bottom node).
  for (int64_t attempt = 0; attempt < 24; ++attempt) {
    const int64_t fail_after = attempt % 12;
    const int bits = attempt < 12 ? 4 : 0;
    SCOPED_TRACE(testing::Message() << "fail after " << fail_after << " bits " << bits);
    Trie trie(4, 1);
    std::vector<Trie::Root> roots(6, nullptr);
    std::mt19937_64 rng(7);
    for (int op = 0; op < 600; ++op) {
      const int v = static_cast<int>(rng() % 6);
      if (op % 5 == 0) {
        Trie::Root copy = Trie::Share(roots[rng() % 6]);
        trie.Release(roots[v], 0);
        roots[v] = copy;
      } else {
        roots[v] = TrieUpdated(trie, roots[v], rng() % 256, 0, [&](Value& x, bool) { x.v = op; });
      }
    }
    std::vector<std::map<uint64_t, uint64_t>> before(6);
    for (int v = 0; v < 6; ++v) {
      trie.ForEach(roots[v], [&](uint64_t k, const Value& x) { before[v][k] = x.v; });
    }
    const int64_t nodes = trie.live_nodes();
    const std::vector<Trie::Root> old = roots;
    FailAllocationsAfter(fail_after);
    const bool dropped = trie.DropSubtree(roots, bits, 50 >> bits, 0);
    FailAllocationsAfter(-1);
    failures += !dropped;
    if (!dropped) {
      EXPECT_EQ(roots, old);
      EXPECT_EQ(trie.live_nodes(), nodes);
      for (int v = 0; v < 6; ++v) {
        std::map<uint64_t, uint64_t> seen;
        trie.ForEach(roots[v], [&](uint64_t k, const Value& x) { seen[k] = x.v; });
        EXPECT_EQ(seen, before[v]);
      }
    }
    EXPECT_TRUE(trie.CheckCounts(roots).ok()) << trie.CheckCounts(roots).ToString();
    for (auto* root : roots) trie.Release(root, 0);
    EXPECT_EQ(trie.live_nodes(), 0);
  }
  EXPECT_GT(failures, 0);  // the first allocations of the drop did fail
}

// Every allocation of a run of updates fails in turn: the update reports it, the version keeps
// its contents, no count is wrong and nothing leaks.
template <typename Trie>
void CheckFailedAllocations() {
  for (int64_t fail_after = 0; fail_after < 400; fail_after += 3) {
    SCOPED_TRACE(testing::Message() << "fail after " << fail_after);
    Trie trie(1, 1);
    std::vector<typename Trie::Root> roots(3, nullptr);
    std::vector<std::map<uint64_t, uint64_t>> models(3);
    std::mt19937_64 rng(fail_after);
    // Shared versions first, so failures hit copies as well as new nodes and growth.
    for (int k = 0; k < 50; ++k) {
      ASSERT_TRUE(trie.Update(&roots[0], k * 37, 0, [&](Value& x, bool) { x.v = k; }));
      models[0][k * 37] = k;
    }
    roots[1] = Trie::Share(roots[0]);
    models[1] = models[0];
    FailAllocationsAfter(fail_after);
    bool failed = false;
    for (int op = 0; op < 300 && !failed; ++op) {
      const int v = static_cast<int>(rng() % 3);
      const uint64_t key = rng() >> (rng() % 50);
      if (trie.Update(&roots[v], key, 0, [&](Value& x, bool) { x.v = op; })) {
        models[v][key] = op;
      } else {
        failed = true;
      }
    }
    FailAllocationsAfter(-1);
    for (int v = 0; v < 3; ++v) {
      std::map<uint64_t, uint64_t> seen;
      trie.ForEach(roots[v], [&](uint64_t k, const Value& x) { seen[k] = x.v; });
      EXPECT_EQ(seen, models[v]) << "version " << v;
    }
    EXPECT_TRUE(trie.CheckCounts(roots).ok()) << trie.CheckCounts(roots).ToString();
    for (auto* root : roots) trie.Release(root, 0);
    EXPECT_EQ(trie.live_nodes(), 0);
  }
}

TEST(PersistentTrieFaultTest, AFailedAllocationLeavesEveryVersionIntactAndLeaksNothing) {
  CheckFailedAllocations<PersistentTrie<Value, 2>>();
  // Wide bottom nodes: a failure can also hit the move of a full node to a larger class.
  CheckFailedAllocations<PersistentTrie<Value, 2, 6>>();
}

// A shared path whose copy runs out of memory at each of its levels in turn: the first copy
// keeps the old path alive until the whole path is copied and the copies do not count their path
// children, so a copy abandoned part way must count the link it left and drop the old path.
TEST(PersistentTrieFaultTest, ACopyAbandonedAtAnyLevelOfASharedPathKeepsEveryCount) {
  using Trie = PersistentTrie<Value, 2>;
  for (int64_t fail_after = 0; fail_after <= 8; ++fail_after) {
    SCOPED_TRACE(testing::Message() << "fail after " << fail_after);
    Trie trie(8, 1);
    std::vector<Trie::Root> roots(2, nullptr);
    std::map<uint64_t, uint64_t> model;
    for (uint64_t k = 0; k < 65536; k += 611) {
      ASSERT_TRUE(trie.Update(&roots[0], k, 0, [&](Value& x, bool) { x.v = k; }));
      model[k] = k;
    }
    roots[1] = Trie::Share(roots[0]);
    FailAllocationsAfter(fail_after);
    const bool updated = trie.Update(&roots[1], 611 * 7, 0, [](Value& x, bool) { x.v = 1; });
    FailAllocationsAfter(-1);
    EXPECT_EQ(updated, fail_after == 8);  // a path of 8 nodes
    std::map<uint64_t, uint64_t> changed = model;
    if (updated) changed[611 * 7] = 1;
    for (int v = 0; v < 2; ++v) {
      std::map<uint64_t, uint64_t> seen;
      trie.ForEach(roots[v], [&](uint64_t k, const Value& x) { seen[k] = x.v; });
      EXPECT_EQ(seen, v == 0 ? model : changed) << "version " << v;
    }
    EXPECT_TRUE(trie.CheckCounts(roots).ok()) << trie.CheckCounts(roots).ToString();
    for (auto* root : roots) trie.Release(root, 0);
    EXPECT_EQ(trie.live_nodes(), 0);
  }
}

// A wide bottom node that must move to a larger class for a new leaf: unique, it is replaced
// and freed; held by several versions that all take the update (`holders`), it is copied and
// the old node stays until the last of them lets it go.
TEST(PersistentTrieTest, AFullWideBottomNodeMovesToALargerClass) {
  using Trie = PersistentTrie<Value, 4, 8>;  // classes of 3, 11, ... leaves
  Trie trie(1, 1);
  Trie::Root root = nullptr;
  for (uint64_t k : {10, 20, 30}) {
    root = TrieUpdated(trie, root, k, 0, [&](Value& x, bool) { x.v = k; });
  }
  EXPECT_EQ(trie.live_nodes(), 1);
  root = TrieUpdated(trie, root, 15, 0, [&](Value& x, bool) { x.v = 15; });  // a fourth leaf
  EXPECT_EQ(trie.live_nodes(), 1);                                           // the full node freed
  std::map<uint64_t, uint64_t> seen;
  trie.ForEach(root, [&](uint64_t k, const Value& x) { seen[k] = x.v; });
  EXPECT_EQ(seen, (std::map<uint64_t, uint64_t>{{10, 10}, {15, 15}, {20, 20}, {30, 30}}));

  // Fill the second class (11 leaves), then let two holders take a twelfth.
  for (uint64_t k = 100; k < 107; ++k) {
    root = TrieUpdated(trie, root, k, 0, [&](Value& x, bool) { x.v = k; });
  }
  Trie::Root other = Trie::Share(root);
  Trie::Root full = root;
  ASSERT_TRUE(trie.Update(
      &root, 5, 0, [](Value& x, bool) { x.v = 5; }, 2));
  EXPECT_NE(root, full);
  EXPECT_EQ(trie.live_nodes(), 2);
  EXPECT_EQ(trie.Find(other, 5), nullptr);  // the old node, intact until its holder lets go
  EXPECT_EQ(trie.Find(other, 106)->v, 106u);
  trie.Release(other, 0);  // the second holder takes the result
  other = Trie::Share(root);
  EXPECT_EQ(trie.live_nodes(), 1);
  EXPECT_EQ(trie.Find(other, 5)->v, 5u);
  std::vector<Trie::Root> all{root, other};
  EXPECT_TRUE(trie.CheckCounts(all).ok()) << trie.CheckCounts(all).ToString();
  trie.Release(root, 0);
  trie.Release(other, 0);
  EXPECT_EQ(trie.live_nodes(), 0);
}

}  // namespace
}  // namespace grove

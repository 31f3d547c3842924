#include "alloc/node_pool.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <set>
#include <thread>
#include <vector>

namespace grove {
namespace {

TEST(NodePoolTest, LiveCountFollowsAllocationsAndFrees) {
  NodePool pool(48, 1);
  std::vector<void*> nodes;
  for (int i = 0; i < 10000; ++i) nodes.push_back(pool.Allocate(0));
  EXPECT_EQ(pool.Stats().live_nodes, 10000);
  EXPECT_EQ(pool.Stats().live_bytes(), 10000 * 48);
  for (int i = 0; i < 4000; ++i) pool.Free(nodes[i], 0);
  EXPECT_EQ(pool.Stats().live_nodes, 6000);
  EXPECT_GE(pool.Stats().peak_live_nodes, 6000);
  for (int i = 4000; i < 10000; ++i) pool.Free(nodes[i], 0);
  EXPECT_EQ(pool.Stats().live_nodes, 0);
}

// The peak is sampled as nodes are allocated, without a Stats() call (pooled: each slot's own
// count at its page refills). Two slots that grow together and then free everything report
// the sum of their highs, short by at most the page each allocated from after its last refill.
TEST(NodePoolTest, PeakCountsEverySlotsHighWithoutStatsCalls) {
  NodePool pool(48, 2);
  std::vector<void*> nodes[2];
  for (int i = 0; i < 20000; ++i) {
    for (int slot = 0; slot < 2; ++slot) nodes[slot].push_back(pool.Allocate(slot));
  }
  for (int slot = 0; slot < 2; ++slot) {
    for (void* p : nodes[slot]) pool.Free(p, slot);
  }
  const PoolStats stats = pool.Stats();
  EXPECT_EQ(stats.live_nodes, 0);
  const int64_t page_nodes = (64 << 10) / 48;
  EXPECT_GE(stats.peak_live_nodes, 40000 - 2 * page_nodes);
  EXPECT_LE(stats.peak_live_nodes, 40000);
}

// Nodes of whole cache lines start on a line, across pages (and without pooling).
TEST(NodePoolTest, NodesOfWholeLinesStartOnALine) {
  for (size_t bytes : {64, 128, 192, 256}) {
    NodePool pool(bytes, 1);
    std::vector<void*> nodes;
    int off_line = 0;
    for (int i = 0; i < 3000; ++i) {
      void* p = pool.Allocate(0);
      ASSERT_NE(p, nullptr);
      off_line += reinterpret_cast<uintptr_t>(p) % 64 != 0;
      nodes.push_back(p);
    }
    for (void* p : nodes) pool.Free(p, 0);
    EXPECT_EQ(off_line, 0) << bytes << "-byte nodes";
  }
}

TEST(NodePoolTest, NodesAreDistinctAlignedAndWritable) {
  NodePool pool(40, 1);
  std::set<void*> seen;
  std::vector<void*> nodes;
  for (int i = 0; i < 5000; ++i) {
    void* p = pool.Allocate(0);
    ASSERT_EQ(reinterpret_cast<uintptr_t>(p) % 16, 0u);
    ASSERT_TRUE(seen.insert(p).second);
    std::fill_n(static_cast<unsigned char*>(p), 40, static_cast<unsigned char>(i));
    nodes.push_back(p);
  }
  for (int i = 0; i < 5000; ++i) {
    ASSERT_EQ(static_cast<unsigned char*>(nodes[i])[39], static_cast<unsigned char>(i));
  }
  for (void* p : nodes) pool.Free(p, 0);
}

TEST(NodePoolTest, FreedNodesAreReused) {
  NodePool pool(64, 1);
  std::vector<void*> first;
  for (int i = 0; i < 20000; ++i) first.push_back(pool.Allocate(0));
  int64_t reserved = pool.Stats().reserved_bytes;
  for (void* p : first) pool.Free(p, 0);
  for (int round = 0; round < 5; ++round) {
    std::vector<void*> again;
    for (int i = 0; i < 20000; ++i) again.push_back(pool.Allocate(0));
    for (void* p : again) pool.Free(p, 0);
  }
  EXPECT_EQ(pool.Stats().reserved_bytes, reserved);
}

// After a generation dies in random order, consecutive allocations must still come mostly from
// the same 64 KiB page: the free lists are per page, not one LIFO list over the whole pool.
TEST(NodePoolTest, RandomOrderFreesKeepAllocationsPageLocal) {
  if (!NodePool::kPooling) GTEST_SKIP() << "pooling is off in this build";
  NodePool pool(128, 1);
  std::vector<void*> nodes;
  for (int i = 0; i < 50000; ++i) nodes.push_back(pool.Allocate(0));
  std::mt19937_64 rng(7);
  std::shuffle(nodes.begin(), nodes.end(), rng);
  for (void* p : nodes) pool.Free(p, 0);
  int page_changes = 0;
  uintptr_t last_page = 0;
  for (int i = 0; i < 50000; ++i) {
    uintptr_t page = reinterpret_cast<uintptr_t>(pool.Allocate(0)) >> 16;
    if (page != last_page) ++page_changes;
    last_page = page;
  }
  // ~511 nodes per page: about 100 page changes; a single shuffled LIFO list would give ~50000.
  EXPECT_LT(page_changes, 200);
}

TEST(NodePoolTest, CrossThreadFreeReturnsNodeToOwner) {
  NodePool pool(32, 2);
  std::vector<void*> nodes;
  for (int i = 0; i < 1000; ++i) nodes.push_back(pool.Allocate(0));
  std::thread other([&] {
    // Slot 1 frees slot 0's nodes: full batches go to the owner as they fill, the rest at the
    // flush.
    for (void* p : nodes) pool.Free(p, 1);
    EXPECT_EQ(pool.Stats().live_nodes, 0);
    pool.Flush(1);
  });
  other.join();
  EXPECT_EQ(pool.Stats().live_nodes, 0);
  // The owner gets them back once its current page runs out and it drains its remote lists.
  std::set<void*> old(nodes.begin(), nodes.end());
  std::vector<void*> again;
  int reused = 0;
  for (int i = 0; i < 5000; ++i) {
    again.push_back(pool.Allocate(0));
    reused += old.count(again.back());
  }
  if (NodePool::kPooling) {
    EXPECT_EQ(reused, 1000);
  }
  for (void* p : again) pool.Free(p, kForeignSlot);
  EXPECT_EQ(pool.Stats().live_nodes, 0);
}

// A full batch of remote frees reaches the owner without a flush; a partial one waits for it.
TEST(NodePoolTest, RemoteFreesReachTheOwnerInFullBatchesOrAtFlush) {
  if (!NodePool::kPooling) GTEST_SKIP() << "pooling is off in this build";
  NodePool pool(48, 2);
  constexpr int kFull = NodePool::kRemoteBatch;
  std::vector<void*> nodes;
  for (int i = 0; i < kFull + 5; ++i) nodes.push_back(pool.Allocate(0));
  std::thread other([&] {
    for (void* p : nodes) pool.Free(p, 1);  // one full batch and 5 left in slot 1's batch
  });
  other.join();
  EXPECT_EQ(pool.Stats().live_nodes, 0);
  // Exhaust the owner's current page so that it drains: exactly the full batch comes back.
  std::set<void*> freed(nodes.begin(), nodes.end());
  auto reuse_after = [&](int allocations) {
    std::vector<void*> got;
    int reused = 0;
    for (int i = 0; i < allocations; ++i) {
      got.push_back(pool.Allocate(0));
      reused += static_cast<int>(freed.count(got.back()));
    }
    for (void* p : got) pool.Free(p, 0);
    return reused;
  };
  EXPECT_EQ(reuse_after(5000), kFull);
  std::thread flusher([&] { pool.Flush(1); });
  flusher.join();
  EXPECT_EQ(reuse_after(20000), kFull + 5);
  EXPECT_EQ(pool.Stats().live_nodes, 0);
}

TEST(NodePoolTest, ConcurrentSlotsWithRemoteFreesBalance) {
  constexpr int kThreads = 4;
  NodePool pool(48, kThreads);
  std::vector<std::vector<void*>> handoff(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      std::mt19937 rng(t);
      std::vector<void*> mine;
      for (int i = 0; i < 20000; ++i) {
        mine.push_back(pool.Allocate(t));
        if (rng() % 3 == 0) {
          pool.Free(mine.back(), t);
          mine.pop_back();
        }
      }
      handoff[t] = std::move(mine);
    });
  }
  for (auto& th : threads) th.join();
  threads.clear();
  // Each thread frees the next thread's nodes: every free is remote.
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (void* p : handoff[(t + 1) % kThreads]) pool.Free(p, t);
    });
  }
  for (auto& th : threads) th.join();
  EXPECT_EQ(pool.Stats().live_nodes, 0);
}

}  // namespace
}  // namespace grove

namespace grove {
namespace {

TEST(NodePoolFaultTest, TheKthAllocationFailsAndStaysFailingUntilReset) {
  for (int64_t k : {0, 1, 5, 1000, 5000}) {
    NodePool pool(48, 2);
    std::vector<void*> nodes;
    FailAllocationsAfter(k);
    for (int i = 0; i < 6000; ++i) {
      void* p = pool.Allocate(i % 2);
      if (i < k) {
        ASSERT_NE(p, nullptr) << "allocation " << i << " of " << k;
        nodes.push_back(p);
      } else {
        ASSERT_EQ(p, nullptr) << "allocation " << i << " should fail after " << k;
      }
    }
    FailAllocationsAfter(-1);
    EXPECT_EQ(pool.Stats().live_nodes, static_cast<int64_t>(nodes.size()));
    void* again = pool.Allocate(0);
    ASSERT_NE(again, nullptr);
    nodes.push_back(again);
    for (size_t i = 0; i < nodes.size(); ++i) pool.Free(nodes[i], static_cast<int>(i % 2));
    EXPECT_EQ(pool.Stats().live_nodes, 0);
  }
}

}  // namespace
}  // namespace grove

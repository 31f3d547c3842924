#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <set>
#include <thread>
#include <vector>

#include "concurrency/random_stream.h"
#include "concurrency/ref_count.h"
#include "concurrency/worker_pool.h"

namespace grove {
namespace {

TEST(RefCountTest, LastReleaseReportsTrue) {
  RefCount rc;
  EXPECT_TRUE(rc.unique());
  rc.Acquire();
  EXPECT_FALSE(rc.unique());
  EXPECT_FALSE(rc.Release());
  EXPECT_TRUE(rc.unique());
  EXPECT_TRUE(rc.Release());
}

TEST(RefCountTest, ConcurrentAcquireReleaseBalances) {
  RefCount rc;
  std::vector<std::thread> threads;
  std::atomic<int> last{0};
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&] {
      for (int i = 0; i < 100000; ++i) {
        rc.Acquire();
        if (rc.Release()) last.fetch_add(1);
      }
    });
  }
  for (auto& th : threads) th.join();
  EXPECT_EQ(last.load(), 0);
  EXPECT_EQ(rc.count(), 1u);
}

TEST(WorkerPoolTest, EveryIndexVisitedOnceWithValidSlot) {
  for (int threads : {1, 2, 4}) {
    WorkerPool pool(threads);
    std::vector<std::atomic<int>> hits(100000);
    std::atomic<bool> bad_slot{false};
    pool.ParallelFor(hits.size(), 100, [&](int slot, size_t b, size_t e) {
      if (slot < 0 || slot >= pool.num_slots()) bad_slot = true;
      for (size_t i = b; i < e; ++i) hits[i].fetch_add(1);
    });
    EXPECT_FALSE(bad_slot);
    for (auto& h : hits) ASSERT_EQ(h.load(), 1);
  }
}

// A helper takes chunks of another home only while more than half of it is unclaimed: an owner
// that is there, even slow, runs the second half of its home itself. Home 0's first chunk waits
// (up to a second) for slot 1's thread to start home 1, whose first chunk is slow; when that
// thread does not come, the others finish its home and there is nothing to check.
TEST(WorkerPoolTest, AHelperLeavesAPresentOwnerTheSecondHalfOfItsHome) {
  WorkerPool pool(2);
  std::vector<std::atomic<int>> ran_on(16);  // slot + 1; homes of 8 chunks
  pool.ParallelFor(ran_on.size(), 1, [&](int slot, size_t b, size_t) {
    ran_on[b] = slot + 1;
    if (b == 0) {
      for (int i = 0; i < 2000 && ran_on[8] == 0; ++i) {
        std::this_thread::sleep_for(std::chrono::microseconds(500));
      }
    }
    if (b == 8 && slot == 1) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  });
  for (size_t c = 0; c < ran_on.size(); ++c) ASSERT_NE(ran_on[c].load(), 0) << c;
  if (ran_on[8] != 2) GTEST_SKIP() << "slot 1's thread did not start its home";
  for (size_t c = 12; c < 16; ++c) EXPECT_EQ(ran_on[c].load(), 2) << "chunk " << c;
}

TEST(WorkerPoolTest, ASlotIsHeldByOneThreadAtATime) {
  WorkerPool pool(4);
  std::vector<std::atomic<int>> in_use(pool.num_slots());
  std::atomic<bool> overlap{false};
  pool.ParallelFor(20000, 10, [&](int slot, size_t, size_t) {
    if (in_use[slot].fetch_add(1) != 0) overlap = true;
    volatile double x = 0;
    for (int i = 0; i < 200; ++i) x = x + std::sqrt(static_cast<double>(i));
    in_use[slot].fetch_sub(1);
  });
  EXPECT_FALSE(overlap);
}

TEST(WorkerPoolTest, BlockSumsDoNotDependOnThreadCount) {
  std::vector<double> values(123457);
  RandomStream stream(3, 0, 0);
  for (double& v : values) v = stream.NextNormal() * 1e6;
  double reference = 0;
  bool first = true;
  for (int threads : {1, 2, 4, 3}) {
    WorkerPool pool(threads);
    std::vector<double> sums =
        pool.MapBlocks<double>(values.size(), 4096, [&](size_t, size_t b, size_t e) {
          double s = 0;
          for (size_t i = b; i < e; ++i) s += values[i];
          return s;
        });
    double total = 0;
    for (double s : sums) total += s;
    if (first) reference = total;
    first = false;
    EXPECT_EQ(total, reference) << "threads " << threads;  // bit-identical
  }
}

// The usage accounting: every loop counted (an empty one is not a loop), one thread's body time
// is exactly its loop time, and no thread is busy for longer than the loop it works in.
TEST(WorkerPoolTest, UsageCountsLoopsAndBoundsBusyTime) {
  for (int threads : {1, 2, 4}) {
    WorkerPool pool(threads);
    EXPECT_EQ(pool.usage().loops, 0u);
    std::vector<double> v(100000, 1.0);
    pool.ParallelFor(0, 16, [](int, size_t, size_t) {});
    for (int k = 0; k < 5; ++k) {
      pool.ParallelFor(v.size(), 1000, [&](int, size_t b, size_t e) {
        for (size_t i = b; i < e; ++i) v[i] = std::sqrt(v[i] + 1.0);
      });
    }
    WorkerPool::Usage u = pool.usage();
    EXPECT_EQ(u.loops, 5u) << threads;
    EXPECT_GT(u.loop_s, 0) << threads;
    EXPECT_GT(u.busy_s, 0) << threads;
    if (threads == 1) {
      EXPECT_DOUBLE_EQ(u.busy_s, u.loop_s);
    } else {
      EXPECT_LE(u.busy_s, threads * u.loop_s * (1 + 1e-12)) << threads;
    }
  }
}

TEST(RandomStreamTest, SameKeyGivesSameDrawsDifferentKeysDiffer) {
  RandomStream a(42, 7, 1000), b(42, 7, 1000), c(42, 7, 1001), d(42, 8, 1000), e(43, 7, 1000),
      f(42, 7, 1000, 1);
  for (int i = 0; i < 100; ++i) {
    uint64_t x = a.NextU64();
    EXPECT_EQ(x, b.NextU64());
    EXPECT_NE(x, c.NextU64());
    EXPECT_NE(x, d.NextU64());
    EXPECT_NE(x, e.NextU64());
    EXPECT_NE(x, f.NextU64());
  }
}

TEST(RandomStreamTest, NormalsHaveUnitMomentsAndUniformsFillUnitInterval) {
  RandomStream s(1, 2, 3);
  const int n = 200000;
  double sum = 0, sum_sq = 0, umin = 1, umax = 0, usum = 0;
  for (int i = 0; i < n; ++i) {
    double z = s.NextNormal();
    sum += z;
    sum_sq += z * z;
    double u = s.NextUniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    usum += u;
  }
  // Standard errors: mean 1/sqrt(n) = 0.0022, variance sqrt(2/n) = 0.0032.
  EXPECT_NEAR(sum / n, 0.0, 0.012);
  EXPECT_NEAR(sum_sq / n, 1.0, 0.016);
  EXPECT_NEAR(usum / n, 0.5, 0.004);
  EXPECT_LT(umin, 1e-4);
  EXPECT_GT(umax, 1 - 1e-4);
}

// The ziggurat against the normal CDF: bin frequencies over [-4, 4] and both tails.
TEST(RandomStreamTest, NormalsFollowTheNormalDistribution) {
  RandomStream s(9, 1, 2);
  const int n = 1000000;
  const int bins = 32;
  std::vector<int> count(bins + 2, 0);
  for (int i = 0; i < n; ++i) {
    double z = s.NextNormal();
    int b = z < -4 ? 0 : z >= 4 ? bins + 1 : 1 + static_cast<int>((z + 4) / 8 * bins);
    ++count[b];
  }
  auto cdf = [](double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); };
  double chi2 = 0;
  for (int b = 0; b < bins + 2; ++b) {
    double lo = b == 0 ? -INFINITY : -4 + 8.0 * (b - 1) / bins;
    double hi = b == bins + 1 ? INFINITY : -4 + 8.0 * b / bins;
    double expected = n * (cdf(hi) - cdf(lo));
    chi2 += (count[b] - expected) * (count[b] - expected) / expected;
  }
  // 33 degrees of freedom: the 99.9th percentile of chi-square is about 63.9.
  EXPECT_LT(chi2, 63.9);
  EXPECT_GT(count[0] + count[bins + 1], 0);  // the tails are reached
}

}  // namespace
}  // namespace grove

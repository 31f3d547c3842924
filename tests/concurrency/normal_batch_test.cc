// DrawNormals against RandomStream, bit for bit, on every Highway target this build compiled and
// this CPU runs (hwy::TestWithParamTarget: one instance of each test per target).
#include "concurrency/normal_batch.h"

#include <gtest/gtest.h>
#include <hwy/highway.h>
#include <hwy/tests/hwy_gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "concurrency/random_stream.h"

namespace grove {
namespace {

// Outputs of one DrawNormals call, with guard values after each row to catch stray writes.
class Rows {
 public:
  static constexpr size_t kGuard = 16;
  static constexpr uint64_t kGuardBits = 0x7FF4DEADBEEF0001;  // a signalling NaN

  Rows(int count, size_t n) : n_(n), storage_(count) {
    for (auto& row : storage_) row.assign(n + kGuard, std::bit_cast<double>(kGuardBits));
    for (auto& row : storage_) pointers_.push_back(row.data());
  }
  std::span<double* const> out() const { return pointers_; }
  double at(int k, size_t i) const { return storage_[k][i]; }
  bool GuardsIntact() const {
    for (const auto& row : storage_) {
      for (size_t i = n_; i < n_ + kGuard; ++i) {
        if (std::bit_cast<uint64_t>(row[i]) != kGuardBits) return false;
      }
    }
    return true;
  }

 private:
  size_t n_;
  std::vector<std::vector<double>> storage_;
  std::vector<double*> pointers_;
};

// The first `count` NextNormal() of every particle in [begin, end), particle-major.
std::vector<double> ScalarNormals(uint64_t seed, uint64_t step, uint32_t purpose, uint32_t begin,
                                  uint32_t end, int count) {
  std::vector<double> v;
  v.reserve(size_t{end - begin} * count);
  for (uint64_t p = begin; p < end; ++p) {
    RandomStream stream(seed, step, static_cast<uint32_t>(p), purpose);
    for (int k = 0; k < count; ++k) v.push_back(stream.NextNormal());
  }
  return v;
}

// Whether the first `count` deviates of a particle's stream all take the ziggurat's fast path
// (computed from the stream's bits and the tables, independently of DrawNormals): when they do,
// they use the stream's first `count` 64-bit words, one each.
bool AllFast(uint64_t seed, uint64_t step, uint32_t purpose, uint32_t particle, int count) {
  const ZigguratTables& z = ZigguratTables::Get();
  RandomStream stream(seed, step, particle, purpose);
  for (int k = 0; k < count; ++k) {
    const uint64_t bits = stream.NextU64();
    const int layer = static_cast<int>(bits & (ZigguratTables::kLayers - 1));
    const double u =
        static_cast<double>(static_cast<int64_t>(bits >> 11) - (int64_t{1} << 52)) * 0x1.0p-52;
    if (!(std::fabs(u) < z.ratio[layer])) return false;
  }
  return true;
}

// The first particle at or after `from` whose first draw leaves the fast path through the base
// layer's tail (`tail`) or through a wedge of layers 1..127 (`!tail`).
uint32_t FindFirstDrawSlow(uint64_t seed, uint64_t step, uint32_t purpose, uint32_t from,
                           bool tail) {
  const ZigguratTables& z = ZigguratTables::Get();
  for (uint32_t p = from;; ++p) {
    RandomStream stream(seed, step, p, purpose);
    const uint64_t bits = stream.NextU64();
    const int layer = static_cast<int>(bits & (ZigguratTables::kLayers - 1));
    const double u =
        static_cast<double>(static_cast<int64_t>(bits >> 11) - (int64_t{1} << 52)) * 0x1.0p-52;
    if (std::fabs(u) < z.ratio[layer]) continue;
    if ((layer == 0) == tail) return p;
  }
}

// Checks one DrawNormals call against RandomStream bit for bit, checks its rows' guards and that
// it reports the particles that left the fast path; returns that number.
uint32_t ExpectMatchesScalar(uint64_t seed, uint64_t step, uint32_t purpose, uint32_t begin,
                             uint32_t end, int count) {
  SCOPED_TRACE(testing::Message() << "seed " << seed << " step " << step << " purpose " << purpose
                                  << " particles [" << begin << ", " << end << ") count " << count);
  const size_t n = end - begin;
  const std::vector<double> want = ScalarNormals(seed, step, purpose, begin, end, count);
  Rows rows(count, n);
  const uint32_t slow = DrawNormals(seed, step, purpose, begin, end, rows.out());
  size_t mismatches = 0;
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < count; ++k) {
      const double got = rows.at(k, i);
      const double expected = want[i * count + k];
      if (std::bit_cast<uint64_t>(got) != std::bit_cast<uint64_t>(expected)) {
        if (mismatches++ == 0) {
          ADD_FAILURE() << "first mismatch: particle " << begin + i << " draw " << k << ": got "
                        << got << ", RandomStream gives " << expected;
        }
      }
    }
  }
  EXPECT_EQ(mismatches, 0u);
  EXPECT_TRUE(rows.GuardsIntact()) << "a write past end - begin";
  uint32_t want_slow = 0;
  if (count > 0) {
    for (uint64_t p = begin; p < end; ++p) {
      want_slow += !AllFast(seed, step, purpose, static_cast<uint32_t>(p), count);
    }
  }
  EXPECT_EQ(slow, want_slow);
  return slow;
}

class DrawNormalsTest : public hwy::TestWithParamTarget {};
HWY_TARGET_INSTANTIATE_TEST_SUITE_P(DrawNormalsTest);

TEST_P(DrawNormalsTest, DispatchesToTheTargetUnderTest) {
  std::printf("Highway target under test: %s\n", hwy::TargetName(GetParam()));
  EXPECT_EQ(DrawNormalsTarget(), GetParam()) << hwy::TargetName(DrawNormalsTarget());
}

TEST_P(DrawNormalsTest, MatchesRandomStreamBitForBit) {
  const uint64_t seeds[] = {0, 1, 0x9E3779B97F4A7C15, 0xFFFFFFFF00000000, ~uint64_t{0}};
  const uint64_t steps[] = {0, 1, 4097, (uint64_t{1} << 32) + 5, ~uint64_t{0} - 2};
  // Begins that are not multiples of any lane count, lengths 0, 1, 7, 17, 512 and 1000.
  const std::pair<uint32_t, uint32_t> ranges[] = {
      {0, 0}, {5, 6}, {3, 10}, {13, 30}, {511, 1023}, {1001, 2001}, {65537, 65537 + 17}};
  uint32_t slow = 0;
  for (uint64_t seed : seeds) {
    for (uint64_t step : steps) {
      for (uint32_t purpose = 1; purpose <= 4; ++purpose) {
        for (auto [begin, end] : ranges) {
          for (int count = 0; count <= kMaxBatchNormals; ++count) {
            slow += ExpectMatchesScalar(seed, step, purpose, begin, end, count);
          }
        }
      }
    }
  }
  // 2.76 % of draws leave the fast path: thousands of particles went through it here.
  EXPECT_GT(slow, 1000u);
}

TEST_P(DrawNormalsTest, ParticlesLeavingTheFastPathMatch) {
  const uint64_t seed = 0xC0FFEE0000000001;
  const uint64_t step = (uint64_t{1} << 33) + 3;
  for (bool tail : {true, false}) {
    SCOPED_TRACE(tail ? "tail of the base layer" : "wedge");
    // Each as the first and as a later lane of a vector, and in a partial last vector.
    const uint32_t p = FindFirstDrawSlow(seed, step, kMotion, 100, tail);
    for (uint32_t before : {0u, 1u, 3u, 9u}) {
      for (uint32_t after : {1u, 2u, 8u}) {
        for (int count = 1; count <= kMaxBatchNormals; ++count) {
          EXPECT_GE(ExpectMatchesScalar(seed, step, kMotion, p - before, p + after, count), 1u);
        }
      }
    }
  }
}

TEST_P(DrawNormalsTest, ReachesTheLastParticleIndex) {
  // The lanes of the last vector would wrap past UINT32_MAX; particle UINT32_MAX itself is out of
  // reach of a half-open range.
  const uint32_t end = UINT32_MAX;
  for (uint32_t n : {1u, 7u, 17u, 100u}) {
    ExpectMatchesScalar(42, 7, kMotion, end - n, end, 3);
  }
}

TEST_P(DrawNormalsTest, SplittingTheRangeChangesNothing) {
  const uint32_t begin = 12345;
  const uint32_t end = begin + 700;
  Rows whole(3, end - begin);
  DrawNormals(99, 5, kInit, begin, end, whole.out());
  for (uint32_t cut : {begin + 1, begin + 5, begin + 256, end - 1}) {
    Rows left(3, cut - begin);
    Rows right(3, end - cut);
    DrawNormals(99, 5, kInit, begin, cut, left.out());
    DrawNormals(99, 5, kInit, cut, end, right.out());
    for (int k = 0; k < 3; ++k) {
      for (uint32_t p = begin; p < end; ++p) {
        const double part = p < cut ? left.at(k, p - begin) : right.at(k, p - cut);
        ASSERT_EQ(std::bit_cast<uint64_t>(part), std::bit_cast<uint64_t>(whole.at(k, p - begin)))
            << "cut " << cut << " particle " << p << " draw " << k;
      }
    }
  }
}

}  // namespace
}  // namespace grove

// DrawNormalPairs against NormalPairReference, bit for bit, on every Highway target this build
// compiled and this CPU runs (hwy::TestWithParamTarget), and the pairs' distribution.
#include "concurrency/normal_pairs.h"

#include <gtest/gtest.h>
#include <hwy/highway.h>
#include <hwy/tests/hwy_gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "concurrency/random_stream.h"

namespace grove {
namespace {

class DrawNormalPairsTest : public hwy::TestWithParamTarget {};
HWY_TARGET_INSTANTIATE_TEST_SUITE_P(DrawNormalPairsTest);

TEST_P(DrawNormalPairsTest, MatchesTheReferenceBitForBit) {
  const uint64_t seeds[] = {0, 1, 0x9E3779B97F4A7C15, ~uint64_t{0}};
  const uint64_t steps[] = {0, 1, 4097, (uint64_t{1} << 32) + 5};
  // Begins that are not multiples of any lane count, lengths 0, 1, 7, 17 and 1000.
  const std::pair<uint32_t, uint32_t> ranges[] = {{0, 0},   {5, 6},       {3, 10},
                                                  {13, 30}, {1001, 2001}, {65537, 65537 + 17}};
  for (uint64_t seed : seeds) {
    for (uint64_t step : steps) {
      for (auto [begin, end] : ranges) {
        SCOPED_TRACE(testing::Message() << "seed " << seed << " step " << step << " particles ["
                                        << begin << ", " << end << ")");
        const size_t n = end - begin;
        // One guard value after each row catches a write past the end.
        std::vector<double> first(n + 1, 7.0), second(n + 1, 7.0);
        DrawNormalPairs(seed, step, StreamPurpose::kMotion, begin, end, first.data(),
                        second.data());
        size_t mismatches = 0;
        for (size_t i = 0; i < n; ++i) {
          double a, b;
          NormalPairReference(seed, step, begin + static_cast<uint32_t>(i), StreamPurpose::kMotion,
                              &a, &b);
          mismatches += std::bit_cast<uint64_t>(first[i]) != std::bit_cast<uint64_t>(a);
          mismatches += std::bit_cast<uint64_t>(second[i]) != std::bit_cast<uint64_t>(b);
        }
        ASSERT_EQ(mismatches, 0u);
        ASSERT_EQ(first[n], 7.0);
        ASSERT_EQ(second[n], 7.0);
      }
    }
  }
}

// 400,000 deviates (200,000 pairs): mean, variance, the share beyond 2 sigma and the fourth
// moment within 5 standard errors of N(0, 1)'s, and the pair's two halves uncorrelated.
TEST(NormalPairsDistributionTest, PairsAreIndependentStandardNormals) {
  constexpr uint32_t kPairs = 200000;
  std::vector<double> a(kPairs), b(kPairs);
  DrawNormalPairs(7, 3, StreamPurpose::kTest, 0, kPairs, a.data(), b.data());
  double sum = 0, sq = 0, fourth = 0, cross = 0, beyond = 0;
  for (uint32_t i = 0; i < kPairs; ++i) {
    for (double x : {a[i], b[i]}) {
      sum += x;
      sq += x * x;
      fourth += x * x * x * x;
      beyond += std::fabs(x) > 2;
      ASSERT_LE(std::fabs(x), 6.7);
    }
    cross += a[i] * b[i];
  }
  const double n = 2.0 * kPairs;
  EXPECT_NEAR(sum / n, 0, 5 / std::sqrt(n));
  EXPECT_NEAR(sq / n, 1, 5 * std::sqrt(2 / n));
  EXPECT_NEAR(fourth / n, 3, 5 * std::sqrt(96 / n));
  EXPECT_NEAR(beyond / n, 0.0455, 5 * std::sqrt(0.0455 * 0.9545 / n));
  EXPECT_NEAR(cross / kPairs, 0, 5 / std::sqrt(double{kPairs}));
}

}  // namespace
}  // namespace grove

#include "engine/filter/resampler.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace grove {
namespace {

std::vector<uint32_t> Counts(const std::vector<uint32_t>& parents, size_t n_in) {
  std::vector<uint32_t> counts(n_in, 0);
  for (uint32_t p : parents) counts.at(p)++;
  return counts;
}

std::vector<double> RandomWeights(size_t n, uint64_t seed, bool skewed) {
  std::mt19937_64 rng(seed);
  std::exponential_distribution<double> e(1.0);
  std::vector<double> w(n);
  double total = 0;
  for (auto& x : w) {
    x = skewed ? std::exp(8 * e(rng)) : e(rng);
    if (rng() % 7 == 0) x = 0;
    total += x;
  }
  for (auto& x : w) x /= total;
  return w;
}

TEST(SystematicResamplerTest, CopyCountIsFloorOrCeil) {
  WorkerPool workers(2);
  for (size_t n : {1u, 7u, 1000u, 4096u, 30000u}) {
    for (uint64_t seed = 1; seed <= 5; ++seed) {
      SCOPED_TRACE(testing::Message() << "n " << n << " seed " << seed);
      auto w = RandomWeights(n, seed, seed % 2 == 0);
      std::vector<uint32_t> parents(n);
      Resample(ResamplingScheme::kSystematic, w, seed, 3, workers, parents);
      auto counts = Counts(parents, n);
      for (size_t i = 0; i < n; ++i) {
        double expected = n * w[i];
        ASSERT_GE(counts[i], std::floor(expected - 1e-9)) << "particle " << i;
        ASSERT_LE(counts[i], std::ceil(expected + 1e-9)) << "particle " << i;
      }
      for (size_t k = 1; k < n; ++k) ASSERT_LE(parents[k - 1], parents[k]);
    }
  }
}

TEST(SystematicResamplerTest, ResultDoesNotDependOnThreadCount) {
  auto w = RandomWeights(100000, 9, true);
  std::vector<uint32_t> reference;
  for (int threads : {1, 2, 4}) {
    WorkerPool workers(threads);
    std::vector<uint32_t> parents(w.size());
    Resample(ResamplingScheme::kSystematic, w, 77, 5, workers, parents);
    if (reference.empty()) reference = parents;
    EXPECT_EQ(parents, reference) << "threads " << threads;
  }
}

// Block sums handed in (as the filter's normalisation computes them) give the same parents as
// block sums computed from the weights; sums that differ move the draw.
TEST(SystematicResamplerTest, GivenBlockSumsGiveTheSameParents) {
  auto w = RandomWeights(30000, 4, true);
  WorkerPool workers(2);
  std::vector<uint32_t> computed(w.size()), given(w.size()), skewed(w.size());
  Resample(ResamplingScheme::kSystematic, w, 77, 5, workers, computed);
  std::vector<double> sums = BlockSums(w, workers);
  ASSERT_EQ(sums.size(), 8u);
  Resample(ResamplingScheme::kSystematic, w, 77, 5, workers, given, sums);
  EXPECT_EQ(given, computed);
  sums[0] *= 2;  // not the weights' sums: block 0's particles get more copies
  Resample(ResamplingScheme::kSystematic, w, 77, 5, workers, skewed, sums);
  EXPECT_NE(skewed, computed);
}

// Unbiasedness: over many draws the mean copy count of each particle approaches N * w_i.
TEST(ResamplerTest, AllSchemesAreUnbiased) {
  WorkerPool workers(1);
  const std::vector<double> w = {0.05, 0.3, 0.0, 0.15, 0.2, 0.001, 0.299};
  const size_t n = 20;
  const int reps = 4000;
  for (ResamplingScheme scheme : {ResamplingScheme::kSystematic, ResamplingScheme::kStratified,
                                  ResamplingScheme::kResidual, ResamplingScheme::kMultinomial}) {
    SCOPED_TRACE(ResamplingSchemeName(scheme));
    std::vector<double> sum(w.size(), 0);
    for (int r = 0; r < reps; ++r) {
      std::vector<uint32_t> parents(n);
      Resample(scheme, w, 2024, r, workers, parents);
      auto counts = Counts(parents, w.size());
      size_t total = 0;
      for (size_t i = 0; i < w.size(); ++i) {
        sum[i] += counts[i];
        total += counts[i];
      }
      ASSERT_EQ(total, n);
      for (size_t k = 1; k < n; ++k) ASSERT_LE(parents[k - 1], parents[k]);
      ASSERT_EQ(counts[2], 0u) << "a zero-weight particle was copied";
      if (scheme == ResamplingScheme::kResidual) {
        for (size_t i = 0; i < w.size(); ++i) ASSERT_GE(counts[i], std::floor(n * w[i]));
      }
    }
    for (size_t i = 0; i < w.size(); ++i) {
      double expected = n * w[i];
      // Multinomial has the largest spread: sd of the mean = sqrt(n w (1 - w) / reps).
      double sd = std::sqrt(n * w[i] * (1 - w[i]) / reps);
      EXPECT_NEAR(sum[i] / reps, expected, 5 * sd + 1e-9) << "particle " << i;
    }
  }
}

// Multinomial resampling has binomial variance; the low-variance schemes have much less.
TEST(ResamplerTest, MultinomialVarianceIsBinomialOthersLower) {
  WorkerPool workers(1);
  const std::vector<double> w = {0.1, 0.25, 0.4, 0.25};
  const size_t n = 50;
  const int reps = 4000;
  auto variance = [&](ResamplingScheme scheme) {
    double s = 0, s2 = 0;
    for (int r = 0; r < reps; ++r) {
      std::vector<uint32_t> parents(n);
      Resample(scheme, w, 11, r, workers, parents);
      double c = Counts(parents, w.size())[2];
      s += c;
      s2 += c * c;
    }
    return s2 / reps - (s / reps) * (s / reps);
  };
  double binomial = n * 0.4 * 0.6;  // 12
  EXPECT_NEAR(variance(ResamplingScheme::kMultinomial), binomial, 0.15 * binomial);
  EXPECT_LT(variance(ResamplingScheme::kSystematic), 0.3);
  EXPECT_LT(variance(ResamplingScheme::kStratified), 0.5 * binomial);
  EXPECT_LT(variance(ResamplingScheme::kResidual), 0.5 * binomial);
}

TEST(ResamplerTest, SchemeNamesRoundTrip) {
  for (ResamplingScheme s : {ResamplingScheme::kSystematic, ResamplingScheme::kStratified,
                             ResamplingScheme::kResidual, ResamplingScheme::kMultinomial}) {
    ResamplingScheme parsed;
    ASSERT_TRUE(ParseResamplingScheme(ResamplingSchemeName(s), &parsed));
    EXPECT_EQ(parsed, s);
  }
  ResamplingScheme parsed;
  EXPECT_FALSE(ParseResamplingScheme("bogus", &parsed));
}

}  // namespace
}  // namespace grove

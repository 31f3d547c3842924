// SinCos: the same bits as SinCosReference on every Highway target this build compiled and this
// CPU runs, and within 2 ulp of the exact values (long double sinl and cosl) for |x| <= 1000.
#include "concurrency/sin_cos.h"

#include <gtest/gtest.h>
#include <hwy/highway.h>
#include <hwy/tests/hwy_gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

namespace grove {
namespace {

constexpr long double kPi = 3.141592653589793238462643383279502884L;

// Angles where sin and cos are hard to get right: uniform in [-1000, 1000], the doubles next to
// multiples of pi/2 (where one of them is nearly 0), small angles, and signed zeros.
std::vector<double> HardAngles(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-1000, 1000);
  std::vector<double> x;
  for (int i = 0; i < 200000; ++i) x.push_back(uniform(rng));
  for (int k = -636; k <= 636; ++k) {
    const double v = static_cast<double>(k * kPi / 2);
    x.push_back(v);
    x.push_back(std::nextafter(v, -2000.0));
    x.push_back(std::nextafter(v, 2000.0));
  }
  for (int e = 0; e < 1074; e += 3) {
    x.push_back(std::ldexp(std::uniform_real_distribution<double>(-1, 1)(rng), -e));
  }
  x.push_back(0.0);
  x.push_back(-0.0);
  x.push_back(1000.0);
  x.push_back(-1000.0);
  return x;
}

// |got - want| in units of the last place of want rounded to double.
double UlpError(double got, long double want) {
  const double w = static_cast<double>(want);
  if (w == 0) return got == 0 ? 0 : std::numeric_limits<double>::infinity();
  const double ulp = std::nextafter(std::fabs(w), INFINITY) - std::fabs(w);
  return static_cast<double>(std::fabs(static_cast<long double>(got) - want) / ulp);
}

class SinCosTest : public hwy::TestWithParamTarget {};
HWY_TARGET_INSTANTIATE_TEST_SUITE_P(SinCosTest);

TEST_P(SinCosTest, MatchesTheReferenceBitForBit) {
  const uint64_t seed = 20240601;
  SCOPED_TRACE(testing::Message() << "seed " << seed);
  const std::vector<double> x = HardAngles(seed);
  // Every length up to 19, then all of them, at offsets that are not multiples of any lane count.
  for (size_t offset : {size_t{0}, size_t{1}, size_t{3}}) {
    std::vector<size_t> lengths;
    for (size_t n = 0; n < 20; ++n) lengths.push_back(n);
    lengths.push_back(x.size() - offset);
    for (size_t n : lengths) {
      std::vector<double> s(n + 1, 7.0), c(n + 1, 7.0), want_s(n), want_c(n);
      SinCos(x.data() + offset, n, s.data(), c.data());
      SinCosReference(x.data() + offset, n, want_s.data(), want_c.data());
      size_t mismatches = 0;
      for (size_t i = 0; i < n; ++i) {
        mismatches += std::bit_cast<uint64_t>(s[i]) != std::bit_cast<uint64_t>(want_s[i]);
        mismatches += std::bit_cast<uint64_t>(c[i]) != std::bit_cast<uint64_t>(want_c[i]);
      }
      ASSERT_EQ(mismatches, 0u) << "offset " << offset << " n " << n;
      ASSERT_EQ(s[n], 7.0) << "a write past n";
      ASSERT_EQ(c[n], 7.0) << "a write past n";
    }
  }
}

TEST_P(SinCosTest, WorksInPlace) {
  const std::vector<double> x = HardAngles(5);
  std::vector<double> s = x;
  std::vector<double> c(x.size());
  std::vector<double> want_s(x.size()), want_c(x.size());
  SinCos(s.data(), s.size(), s.data(), c.data());
  SinCosReference(x.data(), x.size(), want_s.data(), want_c.data());
  for (size_t i = 0; i < x.size(); ++i) {
    ASSERT_EQ(std::bit_cast<uint64_t>(s[i]), std::bit_cast<uint64_t>(want_s[i])) << x[i];
    ASSERT_EQ(std::bit_cast<uint64_t>(c[i]), std::bit_cast<uint64_t>(want_c[i])) << x[i];
  }
}

TEST_P(SinCosTest, InfinityAndNanGiveNan) {
  const double x[] = {
      INFINITY, -INFINITY, std::numeric_limits<double>::quiet_NaN(), 1, 2, 3, 4, 5, 6, 7, 8};
  double s[std::size(x)], c[std::size(x)];
  SinCos(x, std::size(x), s, c);
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(std::isnan(s[i])) << x[i];
    EXPECT_TRUE(std::isnan(c[i])) << x[i];
  }
}

TEST(SinCosAccuracyTest, WithinTwoUlpUpTo1000) {
  const std::vector<double> x = HardAngles(11);
  std::vector<double> s(x.size()), c(x.size());
  SinCosReference(x.data(), x.size(), s.data(), c.data());
  double worst_s = 0, worst_c = 0, worst_s_x = 0, worst_c_x = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double es = UlpError(s[i], sinl(x[i]));
    const double ec = UlpError(c[i], cosl(x[i]));
    if (es > worst_s) worst_s = es, worst_s_x = x[i];
    if (ec > worst_c) worst_c = ec, worst_c_x = x[i];
  }
  std::printf("largest errors: sin %.3f ulp at %a, cos %.3f ulp at %a\n", worst_s, worst_s_x,
              worst_c, worst_c_x);
  EXPECT_LE(worst_s, 2.0) << "at " << worst_s_x;
  EXPECT_LE(worst_c, 2.0) << "at " << worst_c_x;
  // Signed zero: sin(-0) = -0.
  EXPECT_TRUE(std::signbit(s[x.size() - 3]));
}

}  // namespace
}  // namespace grove

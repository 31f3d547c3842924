// LogBatch and Atan2Batch: the same bits as their references on every Highway target this build
// compiled and this CPU runs, and within 2 ulp of the exact values (long double logl, atan2l).
#include "concurrency/log_atan2.h"

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

// Positive normal doubles across the exponent range, and ones next to powers of two and to
// sqrt(2), where the mantissa's interval changes.
std::vector<double> LogArguments(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> mantissa(0.5, 1);
  std::vector<double> x;
  for (int i = 0; i < 200000; ++i) {
    x.push_back(std::ldexp(mantissa(rng), static_cast<int>(rng() % 2000) - 1000));
  }
  for (int e = -1020; e < 1020; e += 7) {
    for (double m : {1.0, std::sqrt(2.0)}) {
      const double v = std::ldexp(m, e);
      x.insert(x.end(), {v, std::nextafter(v, 0.0), std::nextafter(v, INFINITY)});
    }
  }
  x.push_back(1.0);
  return x;
}

// Pairs (y, x) of every sign and scale, with y = +-x (the octant boundary) and zeros.
std::vector<std::pair<double, double>> Atan2Arguments(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<std::pair<double, double>> a;
  for (int i = 0; i < 200000; ++i) {
    const double y = std::ldexp(u(rng), static_cast<int>(rng() % 60) - 30);
    double x = std::ldexp(u(rng), static_cast<int>(rng() % 60) - 30);
    if (i % 5 == 0) x = (i % 2 ? -y : y) * (1 + 1e-9 * u(rng));
    a.emplace_back(y, x);
  }
  for (double y : {0.0, -0.0, 1.0, -1.0}) {
    for (double x : {0.0, -0.0, 1.0, -1.0}) a.emplace_back(y, x);
  }
  return a;
}

double UlpError(double got, long double want) {
  const double w = static_cast<double>(want);
  if (w == 0) return got == 0 ? 0 : std::numeric_limits<double>::infinity();
  const double ulp = std::nextafter(std::fabs(w), INFINITY) - std::fabs(w);
  return static_cast<double>(std::fabs(static_cast<long double>(got) - want) / ulp);
}

class LogAtan2Test : public hwy::TestWithParamTarget {};
HWY_TARGET_INSTANTIATE_TEST_SUITE_P(LogAtan2Test);

TEST_P(LogAtan2Test, BatchesMatchTheReferencesBitForBit) {
  const std::vector<double> x = LogArguments(5);
  std::vector<double> logs(x.size() + 1, 7.0);
  LogBatch(x.data(), x.size(), logs.data());
  for (size_t i = 0; i < x.size(); ++i) {
    ASSERT_EQ(std::bit_cast<uint64_t>(logs[i]), std::bit_cast<uint64_t>(LogReference(x[i])))
        << x[i];
  }
  EXPECT_EQ(logs[x.size()], 7.0) << "a write past n";
  const std::vector<std::pair<double, double>> a = Atan2Arguments(6);
  std::vector<double> ys, xs;
  for (auto [y, xx] : a) ys.push_back(y), xs.push_back(xx);
  // Lengths that leave partial vectors of every size.
  for (size_t n : {a.size(), a.size() - 1, a.size() - 3, size_t{5}}) {
    std::vector<double> out(n + 1, 7.0);
    Atan2Batch(ys.data(), xs.data(), n, out.data());
    for (size_t i = 0; i < n; ++i) {
      ASSERT_EQ(std::bit_cast<uint64_t>(out[i]),
                std::bit_cast<uint64_t>(Atan2Reference(ys[i], xs[i])))
          << ys[i] << ", " << xs[i];
    }
    EXPECT_EQ(out[n], 7.0) << "a write past n";
  }
}

TEST(LogAtan2AccuracyTest, WithinTwoUlp) {
  double worst_log = 0, worst_log_x = 0;
  for (double x : LogArguments(11)) {
    const double e = UlpError(LogReference(x), logl(x));
    if (e > worst_log) worst_log = e, worst_log_x = x;
  }
  double worst_atan2 = 0, worst_y = 0, worst_x = 0;
  for (auto [y, x] : Atan2Arguments(12)) {
    const double e = UlpError(Atan2Reference(y, x), atan2l(y, x));
    if (e > worst_atan2) worst_atan2 = e, worst_y = y, worst_x = x;
  }
  std::printf("largest errors: log %.3f ulp at %a, atan2 %.3f ulp at (%a, %a)\n", worst_log,
              worst_log_x, worst_atan2, worst_y, worst_x);
  EXPECT_LE(worst_log, 2.0) << worst_log_x;
  EXPECT_LE(worst_atan2, 2.0) << worst_y << ", " << worst_x;
}

TEST(LogAtan2AccuracyTest, SignsAndZerosAsTheStandardLibrary) {
  for (double y : {0.0, -0.0, 2.0, -2.0}) {
    for (double x : {0.0, -0.0, 3.0, -3.0}) {
      const double got = Atan2Reference(y, x), want = std::atan2(y, x);
      EXPECT_NEAR(got, want, 1e-15) << y << ", " << x;
      EXPECT_EQ(std::signbit(got), std::signbit(want)) << y << ", " << x;
    }
  }
  EXPECT_EQ(LogReference(1.0), 0.0);
}

}  // namespace
}  // namespace grove

// LogBatch, Atan2Batch and their references (log_atan2.h). Compiled with -ffp-contract=off
// (concurrency/CMakeLists.txt): the references and every target round alike.

#include "concurrency/log_atan2.h"

// Re-includes this file once per Highway target.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "concurrency/log_atan2.cc"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include "concurrency/log_atan2-inl.h"

HWY_BEFORE_NAMESPACE();
namespace grove {
namespace HWY_NAMESPACE {

void LogBatchImpl(const double* x, size_t n, double* out) {
  const hn::ScalableTag<double> d;
  const size_t lanes = hn::Lanes(d);
  size_t i = 0;
  for (; i + lanes <= n; i += lanes) hn::StoreU(LogVector(d, hn::LoadU(d, x + i)), d, out + i);
  for (; i < n; ++i) out[i] = LogReference(x[i]);  // the same bits, and no access past n
}

void Atan2BatchImpl(const double* y, const double* x, size_t n, double* out) {
  const hn::ScalableTag<double> d;
  const size_t lanes = hn::Lanes(d);
  size_t i = 0;
  for (; i + lanes <= n; i += lanes) {
    hn::StoreU(Atan2Vector(d, hn::LoadU(d, y + i), hn::LoadU(d, x + i)), d, out + i);
  }
  for (; i < n; ++i) out[i] = Atan2Reference(y[i], x[i]);
}

}  // namespace HWY_NAMESPACE
}  // namespace grove
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
#include <bit>
#include <cmath>
#include <cstdint>

namespace grove {

HWY_EXPORT(LogBatchImpl);
HWY_EXPORT(Atan2BatchImpl);

void LogBatch(const double* x, size_t n, double* out) {
  HWY_DYNAMIC_DISPATCH(LogBatchImpl)(x, n, out);
}
void Atan2Batch(const double* y, const double* x, size_t n, double* out) {
  HWY_DYNAMIC_DISPATCH(Atan2BatchImpl)(y, x, n, out);
}

double LogReference(double x) {
  namespace k = log_atan2_internal;
  const uint64_t bits = std::bit_cast<uint64_t>(x);
  double e = static_cast<double>(static_cast<int64_t>(bits >> 52)) - 1023.0;
  double m = std::bit_cast<double>((bits & k::kMantissa) | k::kOneBits);
  if (m > k::kSqrt2) {
    m = m * 0.5;
    e = e + 1.0;
  }
  const double f = m - 1.0;
  const double s = f / (2.0 + f);
  const double z = s * s;
  double p = k::kAtanh[0];
  for (int i = 1; i < 10; ++i) p = p * z + k::kAtanh[i];
  const double log_m = 2.0 * (s + s * (z * p));
  return e * k::kLn2Hi + (log_m + e * k::kLn2Lo);
}

double Atan2Reference(double y, double x) {
  namespace k = log_atan2_internal;
  const double ax = std::fabs(x), ay = std::fabs(y);
  const bool swap = ay > ax;
  const double lo = swap ? ax : ay, hi = swap ? ay : ax;
  const bool big = lo > 0.66 * hi;
  const double num = big ? lo - hi : lo;
  const double den = big ? lo + hi : hi;
  const double u = den > 0 ? num / den : 0.0;
  const double z = u * u;
  double p = k::kAtanP[0];
  for (int i = 1; i < 5; ++i) p = p * z + k::kAtanP[i];
  double q = z + k::kAtanQ[0];
  for (int i = 1; i < 5; ++i) q = q * z + k::kAtanQ[i];
  double r = u + u * (z * p / q);
  if (big) r = k::kPiOver4 + (r + 0.5 * k::kMoreBits);
  if (swap) r = (k::kPiOver2 - r) + k::kMoreBits;
  if (std::signbit(x)) r = (k::kPi - r) + 2 * k::kMoreBits;
  return std::bit_cast<double>(std::bit_cast<uint64_t>(r) |
                               (std::bit_cast<uint64_t>(y) & 0x8000000000000000u));
}

}  // namespace grove
#endif  // HWY_ONCE

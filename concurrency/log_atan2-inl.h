// LogVector and Atan2Vector (log_atan2.h) for Highway translation units: include it after
// hwy/highway.h inside a file that foreach_target.h re-includes (a per-target include guard,
// Highway's convention for -inl.h headers). The including file must be compiled with
// -ffp-contract=off, as log_atan2.cc is, for the bits of LogReference and Atan2Reference.

#ifndef GROVE_CONCURRENCY_LOG_ATAN2_CONSTANTS_
#define GROVE_CONCURRENCY_LOG_ATAN2_CONSTANTS_

#include <cstdint>
#include <numbers>

namespace grove::log_atan2_internal {

inline constexpr uint64_t kOneBits = 0x3FF0000000000000;   // 1.0
inline constexpr uint64_t kMantissa = 0x000FFFFFFFFFFFFF;  // the 52 fraction bits
inline constexpr double kSqrt2 = std::numbers::sqrt2;
// ln 2 = kLn2Hi + kLn2Lo, kLn2Hi with 32 low zero bits: e kLn2Hi is exact for |e| < 2^20.
inline constexpr double kLn2Hi = 6.93147180369123816490e-01;
inline constexpr double kLn2Lo = 1.90821492927058770002e-10;
// log m = 2 atanh s = 2 (s + s z P(z)), s = (m - 1) / (m + 1), z = s^2, P(z) = sum z^k / (2k + 3):
// |s| <= 0.1716 for m in [sqrt(1/2), sqrt(2)), where the terms beyond z^9 are below 2^-56.
inline constexpr double kAtanh[10] = {1.0 / 21, 1.0 / 19, 1.0 / 17, 1.0 / 15, 1.0 / 13,
                                      1.0 / 11, 1.0 / 9,  1.0 / 7,  1.0 / 5,  1.0 / 3};
// Cephes atan.c: atan u = u + u z P(z) / Q(z), z = u^2, |u| <= 0.66 (Q monic).
inline constexpr double kAtanP[5] = {-8.750608600031904122785e-1, -1.615753718733365076637e1,
                                     -7.500855792314704667340e1, -1.228866684490136173410e2,
                                     -6.485021904942025371773e1};
inline constexpr double kAtanQ[5] = {2.485846490142306297962e1, 1.650270098316988542046e2,
                                     4.328810604912902668951e2, 4.853903996359136964868e2,
                                     1.945506571482613964425e2};
inline constexpr double kPi = std::numbers::pi;
inline constexpr double kPiOver2 = std::numbers::pi / 2;
inline constexpr double kPiOver4 = std::numbers::pi / 4;
// pi/2 - kPiOver2: what the doubles nearest pi/4, pi/2 and pi lack (half, once, twice).
inline constexpr double kMoreBits = 6.123233995736765886130e-17;

}  // namespace grove::log_atan2_internal

#endif  // GROVE_CONCURRENCY_LOG_ATAN2_CONSTANTS_

// Per-target include guard.
#if defined(GROVE_CONCURRENCY_LOG_ATAN2_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef GROVE_CONCURRENCY_LOG_ATAN2_INL_H_
#undef GROVE_CONCURRENCY_LOG_ATAN2_INL_H_
#else
#define GROVE_CONCURRENCY_LOG_ATAN2_INL_H_
#endif

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace grove {
namespace HWY_NAMESPACE {

namespace hn = hwy::HWY_NAMESPACE;

// log x in every lane: LogReference's operations, in its order.
template <class D>
HWY_INLINE hn::Vec<D> LogVector(D d, hn::Vec<D> x) {
  namespace k = log_atan2_internal;
  using V = hn::Vec<D>;
  const hn::RebindToUnsigned<D> du;
  const hn::RebindToSigned<D> di;
  const auto bits = hn::BitCast(du, x);
  V e = hn::Sub(hn::ConvertTo(d, hn::BitCast(di, hn::ShiftRight<52>(bits))), hn::Set(d, 1023.0));
  V m = hn::BitCast(d, hn::Or(hn::And(bits, hn::Set(du, k::kMantissa)), hn::Set(du, k::kOneBits)));
  const auto big = hn::Gt(m, hn::Set(d, k::kSqrt2));
  m = hn::IfThenElse(big, hn::Mul(m, hn::Set(d, 0.5)), m);
  e = hn::IfThenElse(big, hn::Add(e, hn::Set(d, 1.0)), e);
  const V f = hn::Sub(m, hn::Set(d, 1.0));
  const V s = hn::Div(f, hn::Add(hn::Set(d, 2.0), f));
  const V z = hn::Mul(s, s);
  V p = hn::Set(d, k::kAtanh[0]);
  for (int i = 1; i < 10; ++i) p = hn::Add(hn::Mul(p, z), hn::Set(d, k::kAtanh[i]));
  const V log_m = hn::Mul(hn::Set(d, 2.0), hn::Add(s, hn::Mul(s, hn::Mul(z, p))));
  return hn::Add(hn::Mul(e, hn::Set(d, k::kLn2Hi)),
                 hn::Add(log_m, hn::Mul(e, hn::Set(d, k::kLn2Lo))));
}

// atan2(y, x) in every lane: Atan2Reference's operations, in its order.
template <class D>
HWY_INLINE hn::Vec<D> Atan2Vector(D d, hn::Vec<D> y, hn::Vec<D> x) {
  namespace k = log_atan2_internal;
  using V = hn::Vec<D>;
  const V ax = hn::Abs(x), ay = hn::Abs(y);
  const auto swap = hn::Gt(ay, ax);
  const V lo = hn::IfThenElse(swap, ax, ay), hi = hn::IfThenElse(swap, ay, ax);
  const auto big = hn::Gt(lo, hn::Mul(hn::Set(d, 0.66), hi));
  const V num = hn::IfThenElse(big, hn::Sub(lo, hi), lo);
  const V den = hn::IfThenElse(big, hn::Add(lo, hi), hi);
  const V u = hn::IfThenElseZero(hn::Gt(den, hn::Zero(d)), hn::Div(num, den));
  const V z = hn::Mul(u, u);
  V p = hn::Set(d, k::kAtanP[0]);
  for (int i = 1; i < 5; ++i) p = hn::Add(hn::Mul(p, z), hn::Set(d, k::kAtanP[i]));
  V q = hn::Add(z, hn::Set(d, k::kAtanQ[0]));
  for (int i = 1; i < 5; ++i) q = hn::Add(hn::Mul(q, z), hn::Set(d, k::kAtanQ[i]));
  V r = hn::Add(u, hn::Mul(u, hn::Div(hn::Mul(z, p), q)));
  r = hn::IfThenElse(
      big, hn::Add(hn::Set(d, k::kPiOver4), hn::Add(r, hn::Set(d, 0.5 * k::kMoreBits))), r);
  r = hn::IfThenElse(swap, hn::Add(hn::Sub(hn::Set(d, k::kPiOver2), r), hn::Set(d, k::kMoreBits)),
                     r);
  // x's sign bit (so that x = -0 counts as negative), then y's: r >= 0 takes it as is.
  const hn::RebindToSigned<D> di;
  const auto x_negative = hn::RebindMask(d, hn::Lt(hn::BitCast(di, x), hn::Zero(di)));
  r = hn::IfThenElse(x_negative,
                     hn::Add(hn::Sub(hn::Set(d, k::kPi), r), hn::Set(d, 2 * k::kMoreBits)), r);
  return hn::Or(r, hn::And(y, hn::Set(d, -0.0)));
}

}  // namespace HWY_NAMESPACE
}  // namespace grove
HWY_AFTER_NAMESPACE();

#endif  // GROVE_CONCURRENCY_LOG_ATAN2_INL_H_

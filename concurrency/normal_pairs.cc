// DrawNormalPairs (normal_pairs.h): Philox4x32-10 (philox-inl.h), a logarithm and SinCosVector
// in Highway vectors, one particle per 64-bit lane. Compiled with -ffp-contract=off
// (concurrency/CMakeLists.txt): the scalar reference and every target round alike.
#ifndef GROVE_CONCURRENCY_NORMAL_PAIRS_CC_
#define GROVE_CONCURRENCY_NORMAL_PAIRS_CC_

#include "concurrency/normal_pairs.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <numbers>

#include "alloc/check.h"
#include "concurrency/random_stream.h"
#include "concurrency/sin_cos.h"

namespace grove {
namespace normal_pairs_internal {

constexpr uint64_t kOneBits = 0x3FF0000000000000;   // 1.0
constexpr uint64_t kMantissa = 0x000FFFFFFFFFFFFF;  // the 52 fraction bits
constexpr double kSqrt2 = std::numbers::sqrt2;
// ln 2 = kLn2Hi + kLn2Lo, kLn2Hi with 32 low zero bits: e kLn2Hi is exact for |e| < 2^20.
constexpr double kLn2Hi = 6.93147180369123816490e-01;
constexpr double kLn2Lo = 1.90821492927058770002e-10;
constexpr double kTwoPi = 2 * std::numbers::pi;
// log m = 2 atanh s = 2 (s + s z P(z)), s = (m - 1) / (m + 1), z = s^2, P(z) = sum z^k / (2k + 3):
// |s| <= 0.1716 for m in [sqrt(1/2), sqrt(2)), where the terms beyond z^9 are below 2^-56.
constexpr double kAtanh[10] = {1.0 / 21, 1.0 / 19, 1.0 / 17, 1.0 / 15, 1.0 / 13,
                               1.0 / 11, 1.0 / 9,  1.0 / 7,  1.0 / 5,  1.0 / 3};

// log x for a positive normal x: the vector kernel's operations, in its order.
double LogOne(double x) {
  const uint64_t bits = std::bit_cast<uint64_t>(x);
  double e = static_cast<double>(static_cast<int64_t>(bits >> 52)) - 1023.0;
  double m = std::bit_cast<double>((bits & kMantissa) | kOneBits);
  if (m > kSqrt2) {
    m = m * 0.5;
    e = e + 1.0;
  }
  const double f = m - 1.0;
  const double s = f / (2.0 + f);
  const double z = s * s;
  double p = kAtanh[0];
  for (int k = 1; k < 10; ++k) p = p * z + kAtanh[k];
  const double log_m = 2.0 * (s + s * (z * p));
  return e * kLn2Hi + (log_m + e * kLn2Lo);
}

}  // namespace normal_pairs_internal
}  // namespace grove

#endif  // GROVE_CONCURRENCY_NORMAL_PAIRS_CC_

// Re-includes this file once per Highway target.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "concurrency/normal_pairs.cc"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include "concurrency/philox-inl.h"
#include "concurrency/sin_cos-inl.h"

HWY_BEFORE_NAMESPACE();
namespace grove {
namespace HWY_NAMESPACE {

namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<double>;
using DU = hn::RebindToUnsigned<D>;
using DI = hn::RebindToSigned<D>;
using VD = hn::Vec<D>;
using VU = hn::Vec<DU>;

// LogOne in every lane.
HWY_INLINE VD LogVector(D d, VD x) {
  namespace k = normal_pairs_internal;
  const DU du;
  const DI di;
  const VU bits = hn::BitCast(du, x);
  VD e = hn::Sub(hn::ConvertTo(d, hn::BitCast(di, hn::ShiftRight<52>(bits))), hn::Set(d, 1023.0));
  VD m = hn::BitCast(d, hn::Or(hn::And(bits, hn::Set(du, k::kMantissa)), hn::Set(du, k::kOneBits)));
  const auto big = hn::Gt(m, hn::Set(d, k::kSqrt2));
  m = hn::IfThenElse(big, hn::Mul(m, hn::Set(d, 0.5)), m);
  e = hn::IfThenElse(big, hn::Add(e, hn::Set(d, 1.0)), e);
  const VD f = hn::Sub(m, hn::Set(d, 1.0));
  const VD s = hn::Div(f, hn::Add(hn::Set(d, 2.0), f));
  const VD z = hn::Mul(s, s);
  VD p = hn::Set(d, k::kAtanh[0]);
  for (int i = 1; i < 10; ++i) p = hn::Add(hn::Mul(p, z), hn::Set(d, k::kAtanh[i]));
  const VD log_m = hn::Mul(hn::Set(d, 2.0), hn::Add(s, hn::Mul(s, hn::Mul(z, p))));
  return hn::Add(hn::Mul(e, hn::Set(d, k::kLn2Hi)),
                 hn::Add(log_m, hn::Mul(e, hn::Set(d, k::kLn2Lo))));
}

// Uniforms from the 32-bit words in the low halves of w's lanes: (w + 1) / 2^32 in (0, 1] for
// the logarithm, or w / 2^32 in [0, 1) for the angle.
HWY_INLINE VD OpenUniform(D d, VU w) {
  const DI di;
  const VD x = hn::ConvertTo(d, hn::BitCast(di, hn::And(w, hn::Set(DU(), 0xFFFFFFFFu))));
  return hn::Mul(hn::Add(x, hn::Set(d, 1.0)), hn::Set(d, 0x1p-32));
}
HWY_INLINE VD HalfOpenUniform(D d, VU w) {
  const DI di;
  const VD x = hn::ConvertTo(d, hn::BitCast(di, hn::And(w, hn::Set(DU(), 0xFFFFFFFFu))));
  return hn::Mul(x, hn::Set(d, 0x1p-32));
}

// sqrt(-2 log u) (cos 2 pi f, sin 2 pi f) in every lane.
HWY_INLINE void BoxMuller(D d, VD u, VD f, VD& first, VD& second) {
  const VD r = hn::Sqrt(hn::Mul(hn::Set(d, -2.0), LogVector(d, u)));
  VD s, c;
  SinCosVector(d, hn::Mul(f, hn::Set(d, normal_pairs_internal::kTwoPi)), s, c);
  first = hn::Mul(r, c);
  second = hn::Mul(r, s);
}

// The pairs of particles 2b and 2b + 1 for the blocks b in `block`'s lanes, written to
// first[0, 2 Lanes) and second[0, 2 Lanes) in particle order.
HWY_INLINE void PairsOfBlocks(D d, const StreamKey& key, VU block, double* first, double* second) {
  const DU du;
  VU w0, w1, w2, w3;
  Philox(du, key, 0, block, w0, w1, w2, w3);
  VD first_even, second_even, first_odd, second_odd;
  BoxMuller(d, OpenUniform(d, w0), HalfOpenUniform(d, w1), first_even, second_even);
  BoxMuller(d, OpenUniform(d, w2), HalfOpenUniform(d, w3), first_odd, second_odd);
  hn::StoreInterleaved2(first_even, first_odd, d, first);
  hn::StoreInterleaved2(second_even, second_odd, d, second);
}

void DrawNormalPairsImpl(uint64_t seed, uint64_t step, uint32_t purpose, uint32_t begin,
                         uint32_t end, double* first, double* second) {
  const D d;
  const DU du;
  const StreamKey key{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32),
                      static_cast<uint32_t>(step),
                      static_cast<uint32_t>(step >> 32) ^ (purpose << 16)};
  const uint64_t lanes = hn::Lanes(d);
  HWY_ALIGN double a[2 * hn::MaxLanes(D())], b[2 * hn::MaxLanes(D())];
  // Blocks of particle pairs, a vector of them at a time: particles [2 block, 2 block + 2 lanes).
  for (uint64_t block = begin / 2; 2 * block < end; block += lanes) {
    const uint64_t p0 = 2 * block;
    const uint64_t lo = p0 < begin ? begin : p0;
    const uint64_t hi = p0 + 2 * lanes < end ? p0 + 2 * lanes : end;
    if (lo == p0 && hi == p0 + 2 * lanes) {
      PairsOfBlocks(d, key, hn::Iota(du, block), first + (p0 - begin), second + (p0 - begin));
      continue;
    }
    // A vector that reaches past [begin, end): whole, then the part inside copied.
    PairsOfBlocks(d, key, hn::Iota(du, block), a, b);
    std::memcpy(first + (lo - begin), a + (lo - p0), (hi - lo) * sizeof(double));
    std::memcpy(second + (lo - begin), b + (lo - p0), (hi - lo) * sizeof(double));
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace grove
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace grove {

HWY_EXPORT(DrawNormalPairsImpl);

void DrawNormalPairs(uint64_t seed, uint64_t step, uint32_t purpose, uint32_t begin, uint32_t end,
                     double* first, double* second) {
  GROVE_CHECK(begin <= end);
  HWY_DYNAMIC_DISPATCH(DrawNormalPairsImpl)(seed, step, purpose, begin, end, first, second);
}

void NormalPairReference(uint64_t seed, uint64_t step, uint32_t particle, uint32_t purpose,
                         double* first, double* second) {
  namespace k = normal_pairs_internal;
  RandomStream stream(seed, step, particle / 2, purpose);
  const uint64_t b0 = stream.NextU64();  // Philox words 0 and 1
  const uint64_t b1 = stream.NextU64();  // words 2 and 3
  const uint64_t block = particle % 2 == 0 ? b0 : b1;
  const double u = (static_cast<double>(block >> 32) + 1.0) * 0x1p-32;
  const double f = static_cast<double>(block & 0xFFFFFFFFu) * 0x1p-32;
  const double r = std::sqrt(-2.0 * k::LogOne(u));
  const double angle = f * k::kTwoPi;
  double s, c;
  SinCosReference(&angle, 1, &s, &c);
  *first = r * c;
  *second = r * s;
}

}  // namespace grove
#endif  // HWY_ONCE

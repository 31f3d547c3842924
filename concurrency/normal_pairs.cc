// DrawNormalPairs (normal_pairs.h): Philox4x32-10 (philox-inl.h), LogVector and SinCosVector
// in Highway vectors, one particle per 64-bit lane. Compiled with -ffp-contract=off
// (concurrency/CMakeLists.txt): the scalar reference and every target round alike.
#ifndef GROVE_CONCURRENCY_NORMAL_PAIRS_CC_
#define GROVE_CONCURRENCY_NORMAL_PAIRS_CC_

#include "concurrency/normal_pairs.h"

#include <cmath>
#include <cstring>
#include <numbers>

#include "alloc/check.h"
#include "concurrency/log_atan2.h"
#include "concurrency/random_stream.h"
#include "concurrency/sin_cos.h"

namespace grove::normal_pairs_internal {

constexpr double kTwoPi = 2 * std::numbers::pi;

}  // namespace grove::normal_pairs_internal

#endif  // GROVE_CONCURRENCY_NORMAL_PAIRS_CC_

// Re-includes this file once per Highway target.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "concurrency/normal_pairs.cc"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

#include "concurrency/log_atan2-inl.h"
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
  const double r = std::sqrt(-2.0 * LogReference(u));
  const double angle = f * k::kTwoPi;
  double s, c;
  SinCosReference(&angle, 1, &s, &c);
  *first = r * c;
  *second = r * s;
}

}  // namespace grove
#endif  // HWY_ONCE

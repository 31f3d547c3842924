// Philox4x32-10 (Salmon et al., "Parallel random numbers: as easy as 1, 2, 3", 2011) in Highway
// vectors, one particle's counter per 64-bit lane: the block RandomStream (random_stream.h)
// draws, for the kernels that draw from particles' streams (DrawNormals, DrawNormalPairs).
// Include it after hwy/highway.h inside a file that foreach_target.h re-includes (a per-target
// include guard, Highway's convention for -inl.h headers).

#if defined(GROVE_CONCURRENCY_PHILOX_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef GROVE_CONCURRENCY_PHILOX_INL_H_
#undef GROVE_CONCURRENCY_PHILOX_INL_H_
#else
#define GROVE_CONCURRENCY_PHILOX_INL_H_
#endif

#include <hwy/highway.h>

#include <cstdint>

HWY_BEFORE_NAMESPACE();
namespace grove {
namespace HWY_NAMESPACE {

namespace hn = hwy::HWY_NAMESPACE;

// Products of the low 32 bits of each lane of a and b, as 64-bit lanes; upper halves are ignored.
template <class DU, class VU = hn::Vec<DU>>
HWY_INLINE VU MulLow32(DU du, VU a, VU b) {
#if HWY_TARGET == HWY_SCALAR
  return hn::Set(du, (hn::GetLane(a) & 0xFFFFFFFFu) * (hn::GetLane(b) & 0xFFFFFFFFu));
#else
  const hn::Repartition<uint32_t, DU> d32;
  return hn::MulEven(hn::BitCast(d32, a), hn::BitCast(d32, b));
#endif
}

// What is the same in every lane: the key and the counter's words 2 and 3.
struct StreamKey {
  uint32_t key0, key1;
  uint32_t ctr2, ctr3;
};

// Philox4x32-10 of the counters (index, particle, ctr2, ctr3), as Random123's philox4x32_R:
// each 32-bit word in the low half of a 64-bit lane. The upper halves of w0..w3 are garbage: every
// operation that reads them (xor, MulEven) keeps them out of the low halves.
template <class DU, class VU = hn::Vec<DU>>
HWY_INLINE void Philox(DU du, const StreamKey& s, uint32_t index, VU particle, VU& w0, VU& w1,
                       VU& w2, VU& w3) {
  constexpr uint32_t kM0 = 0xD2511F53u;
  constexpr uint32_t kM1 = 0xCD9E8D57u;
  constexpr uint32_t kW0 = 0x9E3779B9u;
  constexpr uint32_t kW1 = 0xBB67AE85u;
  uint32_t k0 = s.key0;
  uint32_t k1 = s.key1;
  // Only word 1, the particle, differs between lanes, so the first three rounds have words that
  // agree in every lane: those are computed once, in scalar.
  // Round 1: only x0 differs.
  uint64_t p0 = uint64_t{kM0} * index;
  uint64_t p1 = uint64_t{kM1} * s.ctr2;
  VU x0 = hn::Xor(particle, hn::Set(du, static_cast<uint32_t>(p1 >> 32) ^ k0));
  const uint32_t a1 = static_cast<uint32_t>(p1);
  const uint32_t a2 = static_cast<uint32_t>(p0 >> 32) ^ s.ctr3 ^ k1;
  const uint32_t a3 = static_cast<uint32_t>(p0);
  // Round 2: x2 and x3 differ.
  k0 += kW0;
  k1 += kW1;
  VU q = MulLow32(du, hn::Set(du, kM0), x0);
  p1 = uint64_t{kM1} * a2;
  const uint32_t b0 = static_cast<uint32_t>(p1 >> 32) ^ a1 ^ k0;
  const uint32_t b1 = static_cast<uint32_t>(p1);
  VU x2 = hn::Xor(hn::ShiftRight<32>(q), hn::Set(du, a3 ^ k1));
  VU x3 = q;
  // Round 3: all but x3 differ.
  k0 += kW0;
  k1 += kW1;
  p0 = uint64_t{kM0} * b0;
  q = MulLow32(du, hn::Set(du, kM1), x2);
  x0 = hn::Xor(hn::ShiftRight<32>(q), hn::Set(du, b1 ^ k0));
  VU x1 = q;
  x2 = hn::Xor(x3, hn::Set(du, static_cast<uint32_t>(p0 >> 32) ^ k1));
  x3 = hn::Set(du, static_cast<uint32_t>(p0));
  // Rounds 4 to 10.
  const VU m0 = hn::Set(du, kM0);
  const VU m1 = hn::Set(du, kM1);
  for (int round = 3; round < 10; ++round) {
    k0 += kW0;
    k1 += kW1;
    const VU r0 = MulLow32(du, m0, x0);
    const VU r1 = MulLow32(du, m1, x2);
    x0 = hn::Xor(hn::Xor(hn::ShiftRight<32>(r1), x1), hn::Set(du, k0));
    x1 = r1;
    x2 = hn::Xor(hn::Xor(hn::ShiftRight<32>(r0), x3), hn::Set(du, k1));
    x3 = r0;
  }
  w0 = x0;
  w1 = x1;
  w2 = x2;
  w3 = x3;
}

}  // namespace HWY_NAMESPACE
}  // namespace grove
HWY_AFTER_NAMESPACE();

#endif  // GROVE_CONCURRENCY_PHILOX_INL_H_

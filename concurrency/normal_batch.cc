// DrawNormals (normal_batch.h): Philox4x32-10 (Salmon et al., 2011) and the fast path of
// RandomStream's ziggurat in Highway vectors, one particle per 64-bit lane. foreach_target.h
// compiles the HWY_NAMESPACE part once per target; HWY_DYNAMIC_DISPATCH picks one at run time.
#ifndef GROVE_CONCURRENCY_NORMAL_BATCH_CC_
#define GROVE_CONCURRENCY_NORMAL_BATCH_CC_

#include "concurrency/normal_batch.h"

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstring>

#include "alloc/check.h"
#include "concurrency/random_stream.h"

namespace grove {
namespace {

// Writes the first `count` deviates of one particle's RandomStream to out[k][offset].
// Never inlined into the per-target code, which is compiled for wider instruction sets: compiled
// here for the baseline like every other user of RandomStream, its slow path is theirs bit for
// bit (with FMA available, a compiler may contract NextNormal's f1 + u (f0 - f1)).
[[gnu::noinline]] void DrawParticleScalar(uint64_t seed, uint64_t step, uint32_t purpose,
                                          uint32_t particle, double* const* out, int count,
                                          size_t offset) {
  RandomStream stream(seed, step, particle, purpose);
  for (int k = 0; k < count; ++k) out[k][offset] = stream.NextNormal();
}

}  // namespace
}  // namespace grove

#endif  // GROVE_CONCURRENCY_NORMAL_BATCH_CC_

// Re-includes this file once per Highway target.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "concurrency/normal_batch.cc"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace grove {
namespace HWY_NAMESPACE {

namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<double>;
using DU = hn::RebindToUnsigned<D>;
using DI = hn::RebindToSigned<D>;
using VD = hn::Vec<D>;
using VU = hn::Vec<DU>;
using MD = hn::Mask<D>;

// Products of the low 32 bits of each lane of a and b, as 64-bit lanes; upper halves are ignored.
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

// The fast path of RandomStream::NextNormal from its 64 bits hi:lo (32-bit words in the low
// halves): clears the lanes of `fast` whose draw leaves it.
HWY_INLINE VD ZigguratFast(D d, VU hi, VU lo, const ZigguratTables& z, MD& fast) {
  const DU du;
  const DI di;
  const VU bits = hn::Or(hn::ShiftLeft<32>(hi), hn::And(lo, hn::Set(du, 0xFFFFFFFFu)));
  const auto layer = hn::BitCast(di, hn::And(bits, hn::Set(du, ZigguratTables::kLayers - 1)));
  // Exact: the integer is below 2^52 in magnitude, and the scaling is by a power of two.
  const auto centred =
      hn::Sub(hn::BitCast(di, hn::ShiftRight<11>(bits)), hn::Set(di, int64_t{1} << 52));
  const VD u = hn::Mul(hn::ConvertTo(d, centred), hn::Set(d, 0x1.0p-52));
  const VD ratio = hn::GatherIndex(d, z.ratio.data(), layer);
  const VD x = hn::GatherIndex(d, z.x.data(), layer);
  fast = hn::And(fast, hn::Lt(hn::Abs(u), ratio));
  return hn::Mul(u, x);
}

// Draws kCount deviates of the particles in `particle`'s lanes to dst[k] + offset (Lanes(d)
// doubles each); returns the lanes whose every draw took the fast path (the others hold garbage).
template <int kCount>
HWY_INLINE MD DrawBlock(D d, const StreamKey& s, const ZigguratTables& z, VU particle,
                        double* const* dst, size_t offset) {
  const DU du;
  MD fast = hn::FirstN(d, hn::Lanes(d));
  for (int k = 0; k < kCount; k += 2) {
    VU w0, w1, w2, w3;
    Philox(du, s, static_cast<uint32_t>(k / 2), particle, w0, w1, w2, w3);
    hn::StoreU(ZigguratFast(d, w0, w1, z, fast), d, dst[k] + offset);
    if (k + 1 < kCount) hn::StoreU(ZigguratFast(d, w2, w3, z, fast), d, dst[k + 1] + offset);
  }
  return fast;
}

// Particles are drawn in chunks of kChunk: the vector loop over a chunk has no data-dependent
// branch (a mispredicted one would flush the blocks in flight); the chunk's particles that left
// the fast path, marked in a bitmap, are drawn again afterwards.
constexpr size_t kChunk = 512;

// Sets the bits of `slow` for the lanes of `fast` that are false, lane j at bit pos + j.
// REQUIRES: pos is a multiple of Lanes(d), a power of two at most 64.
HWY_INLINE void MarkSlow(D d, MD fast, size_t pos, size_t valid, uint64_t* slow) {
  uint8_t bytes[8] = {};
  hn::StoreMaskBits(d, hn::Not(fast), bytes);
  uint64_t bits;
  std::memcpy(&bits, bytes, sizeof(bits));
  if (valid < 64) bits &= (uint64_t{1} << valid) - 1;
  slow[pos / 64] |= bits << (pos % 64);
}

template <int kCount>
uint32_t DrawRange(const StreamKey& s, uint64_t seed, uint64_t step, uint32_t purpose,
                   uint32_t begin, uint32_t end, double* const* out) {
  const D d;
  const DU du;
  const size_t lanes = hn::Lanes(d);
  const ZigguratTables& z = ZigguratTables::Get();
  const size_t n = end - begin;
  uint32_t scalar = 0;
  for (size_t chunk = 0; chunk < n; chunk += kChunk) {
    const size_t chunk_end = std::min(n, chunk + kChunk);
    uint64_t slow[kChunk / 64] = {};
    size_t i = chunk;
    for (; i + lanes <= chunk_end; i += lanes) {
      const MD fast = DrawBlock<kCount>(d, s, z, hn::Iota(du, uint64_t{begin} + i), out, i);
      MarkSlow(d, fast, i - chunk, lanes, slow);
    }
    if (i < chunk_end) {
      // A partial last block is drawn into `tail`, then copied: no access past end - begin.
      HWY_ALIGN double tail[kCount][hn::MaxLanes(D())];
      double* tail_rows[kCount];
      for (int k = 0; k < kCount; ++k) tail_rows[k] = tail[k];
      const MD fast = DrawBlock<kCount>(d, s, z, hn::Iota(du, uint64_t{begin} + i), tail_rows, 0);
      for (int k = 0; k < kCount; ++k) {
        std::memcpy(out[k] + i, tail[k], (chunk_end - i) * sizeof(double));
      }
      MarkSlow(d, fast, i - chunk, chunk_end - i, slow);
    }
    for (size_t w = 0; w < kChunk / 64; ++w) {
      for (uint64_t bits = slow[w]; bits != 0; bits &= bits - 1) {
        const size_t j = chunk + w * 64 + static_cast<size_t>(std::countr_zero(bits));
        DrawParticleScalar(seed, step, purpose, static_cast<uint32_t>(begin + j), out, kCount, j);
        ++scalar;
      }
    }
  }
  return scalar;
}

uint32_t DrawNormalsImpl(uint64_t seed, uint64_t step, uint32_t purpose, uint32_t begin,
                         uint32_t end, double* const* out, int count) {
  const StreamKey s{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32),
                    static_cast<uint32_t>(step),
                    static_cast<uint32_t>(step >> 32) ^ (purpose << 16)};
  static_assert(kMaxBatchNormals == 6);
  switch (count) {
    case 1:
      return DrawRange<1>(s, seed, step, purpose, begin, end, out);
    case 2:
      return DrawRange<2>(s, seed, step, purpose, begin, end, out);
    case 3:
      return DrawRange<3>(s, seed, step, purpose, begin, end, out);
    case 4:
      return DrawRange<4>(s, seed, step, purpose, begin, end, out);
    case 5:
      return DrawRange<5>(s, seed, step, purpose, begin, end, out);
    case 6:
      return DrawRange<6>(s, seed, step, purpose, begin, end, out);
    default:
      return 0;
  }
}

int64_t TargetImpl() { return HWY_TARGET; }

}  // namespace HWY_NAMESPACE
}  // namespace grove
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace grove {

HWY_EXPORT(DrawNormalsImpl);
HWY_EXPORT(TargetImpl);

uint32_t DrawNormals(uint64_t seed, uint64_t step, uint32_t purpose, uint32_t begin, uint32_t end,
                     std::span<double* const> out) {
  GROVE_CHECK(begin <= end);
  GROVE_CHECK(out.size() <= static_cast<size_t>(kMaxBatchNormals));
  return HWY_DYNAMIC_DISPATCH(DrawNormalsImpl)(seed, step, purpose, begin, end, out.data(),
                                               static_cast<int>(out.size()));
}

int64_t DrawNormalsTarget() { return HWY_DYNAMIC_DISPATCH(TargetImpl)(); }

std::string SimdTargetsCompiled() {
  std::string names;
  // Lower bits are the better targets on x86 (HWY_AVX3 < HWY_AVX2 < ... < HWY_EMU128).
  for (int64_t rest = HWY_TARGETS; rest != 0; rest &= rest - 1) {
    if (!names.empty()) names += ' ';
    names += SimdTargetName(rest & -rest);
  }
  return names;
}

std::string SimdTargetName(int64_t target) { return hwy::TargetName(target); }

}  // namespace grove
#endif  // HWY_ONCE

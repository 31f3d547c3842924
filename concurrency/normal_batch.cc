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

#include "concurrency/philox-inl.h"

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

// SinCos (sin_cos.h). Compiled with -ffp-contract=off (concurrency/CMakeLists.txt): the scalar
// reference and every target must round after each multiply and each add.
#ifndef GROVE_CONCURRENCY_SIN_COS_CC_
#define GROVE_CONCURRENCY_SIN_COS_CC_

#include "concurrency/sin_cos.h"

#include <bit>
#include <cmath>
#include <cstdint>

namespace grove {
namespace {

constexpr double kTwoOverPi = 0x1.45f306dc9c883p-1;
// Adding 1.5 * 2^52 rounds |y| < 2^51 to the nearest integer (ties to even), which then sits in
// the low bits of the sum's representation.
constexpr double kRoundBias = 0x1.8p52;
// pi/2 = kPiOver2[0] + ... + kPiOver2[3] to about 150 bits. The first three have at most 33
// significant bits, so k * kPiOver2[i] is exact for |k| < 2^20.
constexpr double kPiOver2[4] = {0x1.921fb544p0, 0x1.0b4611a6p-34, 0x1.3198a2ep-69,
                                0x1.b839a252049c1p-104};
// Cephes sin.c: sin r = r + r z P(z) and cos r = 1 - z / 2 + z^2 Q(z), z = r^2, |r| <= pi/4.
constexpr double kSin[6] = {1.58962301576546568060e-10, -2.50507477628578072866e-8,
                            2.75573136213857245213e-6,  -1.98412698295895385996e-4,
                            8.33333333332211858878e-3,  -1.66666666666666307295e-1};
constexpr double kCos[6] = {-1.13585365213876817300e-11, 2.08757008419747316778e-9,
                            -2.75573141792967388112e-7,  2.48015872888517045348e-5,
                            -1.38888888888730564116e-3,  4.16666666666665929218e-2};

constexpr double kTiny = 0x1p-27;

// The scalar reference: the same operations, in the same order, as SinCosVector below.
void SinCosOne(double x, double& s, double& c) {
  const double t = x * kTwoOverPi + kRoundBias;
  const double k = t - kRoundBias;
  const uint64_t q = std::bit_cast<uint64_t>(t);  // k mod 4 in the low two bits
  double r = x - k * kPiOver2[0];
  r = r - k * kPiOver2[1];
  r = r - k * kPiOver2[2];
  r = r - k * kPiOver2[3];
  const double z = r * r;
  double ps = kSin[0];
  double pc = kCos[0];
  for (int i = 1; i < 6; ++i) {
    ps = ps * z + kSin[i];
    pc = pc * z + kCos[i];
  }
  // Below 2^-27, sin r rounds to r; the polynomial would turn r = -0 into +0.
  const double sin_r = std::fabs(r) < kTiny ? r : r + r * z * ps;
  const double cos_r = (1.0 - 0.5 * z) + z * z * pc;
  const uint64_t sign_s = (q & 2) << 62;
  const uint64_t sign_c = ((q + 1) & 2) << 62;
  s = std::bit_cast<double>(std::bit_cast<uint64_t>((q & 1) ? cos_r : sin_r) ^ sign_s);
  c = std::bit_cast<double>(std::bit_cast<uint64_t>((q & 1) ? sin_r : cos_r) ^ sign_c);
}

}  // namespace
}  // namespace grove

#endif  // GROVE_CONCURRENCY_SIN_COS_CC_

// Re-includes this file once per Highway target.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "concurrency/sin_cos.cc"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace grove {
namespace HWY_NAMESPACE {

namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<double>;
using VD = hn::Vec<D>;

HWY_INLINE void SinCosVector(D d, VD x, VD& s, VD& c) {
  const hn::RebindToUnsigned<D> du;
  const VD t = hn::Add(hn::Mul(x, hn::Set(d, kTwoOverPi)), hn::Set(d, kRoundBias));
  const VD k = hn::Sub(t, hn::Set(d, kRoundBias));
  const auto q = hn::BitCast(du, t);
  VD r = hn::Sub(x, hn::Mul(k, hn::Set(d, kPiOver2[0])));
  r = hn::Sub(r, hn::Mul(k, hn::Set(d, kPiOver2[1])));
  r = hn::Sub(r, hn::Mul(k, hn::Set(d, kPiOver2[2])));
  r = hn::Sub(r, hn::Mul(k, hn::Set(d, kPiOver2[3])));
  const VD z = hn::Mul(r, r);
  VD ps = hn::Set(d, kSin[0]);
  VD pc = hn::Set(d, kCos[0]);
  for (int i = 1; i < 6; ++i) {
    ps = hn::Add(hn::Mul(ps, z), hn::Set(d, kSin[i]));
    pc = hn::Add(hn::Mul(pc, z), hn::Set(d, kCos[i]));
  }
  const VD sin_r = hn::IfThenElse(hn::Lt(hn::Abs(r), hn::Set(d, kTiny)), r,
                                  hn::Add(r, hn::Mul(hn::Mul(r, z), ps)));
  const VD cos_r =
      hn::Add(hn::Sub(hn::Set(d, 1.0), hn::Mul(hn::Set(d, 0.5), z)), hn::Mul(hn::Mul(z, z), pc));
  const auto odd = hn::RebindMask(d, hn::TestBit(q, hn::Set(du, 1)));
  const VD sign_s = hn::BitCast(d, hn::ShiftLeft<62>(hn::And(q, hn::Set(du, 2))));
  const VD sign_c =
      hn::BitCast(d, hn::ShiftLeft<62>(hn::And(hn::Add(q, hn::Set(du, 1)), hn::Set(du, 2))));
  s = hn::Xor(hn::IfThenElse(odd, cos_r, sin_r), sign_s);
  c = hn::Xor(hn::IfThenElse(odd, sin_r, cos_r), sign_c);
}

void SinCosImpl(const double* x, size_t n, double* s, double* c) {
  const D d;
  const size_t lanes = hn::Lanes(d);
  size_t i = 0;
  for (; i + lanes <= n; i += lanes) {
    VD vs, vc;
    SinCosVector(d, hn::LoadU(d, x + i), vs, vc);
    hn::StoreU(vs, d, s + i);
    hn::StoreU(vc, d, c + i);
  }
  // The last partial vector in scalar: the same bits, and no access past n.
  for (; i < n; ++i) SinCosOne(x[i], s[i], c[i]);
}

}  // namespace HWY_NAMESPACE
}  // namespace grove
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace grove {

HWY_EXPORT(SinCosImpl);

void SinCos(const double* x, size_t n, double* s, double* c) {
  HWY_DYNAMIC_DISPATCH(SinCosImpl)(x, n, s, c);
}

void SinCosReference(const double* x, size_t n, double* s, double* c) {
  for (size_t i = 0; i < n; ++i) SinCosOne(x[i], s[i], c[i]);
}

}  // namespace grove
#endif  // HWY_ONCE

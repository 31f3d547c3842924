// SinCos's vector kernel (sin_cos.h) for other Highway translation units: the constants and
// SinCosVector, one Cody-Waite reduction and one pair of Cephes polynomials per vector of angles.
// Include it after hwy/highway.h inside a file that foreach_target.h re-includes, as Highway's
// -inl.h headers are (a per-target include guard); the including file must be compiled with
// -ffp-contract=off, as sin_cos.cc is, for the bits of SinCosReference.

// Per-target include guard (Highway's convention for -inl.h headers).
#if defined(GROVE_CONCURRENCY_SIN_COS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef GROVE_CONCURRENCY_SIN_COS_INL_H_
#undef GROVE_CONCURRENCY_SIN_COS_INL_H_
#else
#define GROVE_CONCURRENCY_SIN_COS_INL_H_
#endif

#include <hwy/highway.h>

#include "concurrency/sin_cos_constants.h"

HWY_BEFORE_NAMESPACE();
namespace grove {
namespace HWY_NAMESPACE {

// s = sin x and c = cos x in every lane: SinCosReference's operations, in its order.
template <class D>
HWY_INLINE void SinCosVector(D d, hwy::HWY_NAMESPACE::Vec<D> x, hwy::HWY_NAMESPACE::Vec<D>& s,
                             hwy::HWY_NAMESPACE::Vec<D>& c) {
  namespace hn = hwy::HWY_NAMESPACE;
  namespace k = sin_cos_internal;
  using V = hn::Vec<D>;
  const hn::RebindToUnsigned<D> du;
  const V t = hn::Add(hn::Mul(x, hn::Set(d, k::kTwoOverPi)), hn::Set(d, k::kRoundBias));
  const V kq = hn::Sub(t, hn::Set(d, k::kRoundBias));
  const auto q = hn::BitCast(du, t);
  V r = hn::Sub(x, hn::Mul(kq, hn::Set(d, k::kPiOver2[0])));
  r = hn::Sub(r, hn::Mul(kq, hn::Set(d, k::kPiOver2[1])));
  r = hn::Sub(r, hn::Mul(kq, hn::Set(d, k::kPiOver2[2])));
  r = hn::Sub(r, hn::Mul(kq, hn::Set(d, k::kPiOver2[3])));
  const V z = hn::Mul(r, r);
  V ps = hn::Set(d, k::kSin[0]);
  V pc = hn::Set(d, k::kCos[0]);
  for (int i = 1; i < 6; ++i) {
    ps = hn::Add(hn::Mul(ps, z), hn::Set(d, k::kSin[i]));
    pc = hn::Add(hn::Mul(pc, z), hn::Set(d, k::kCos[i]));
  }
  const V sin_r = hn::IfThenElse(hn::Lt(hn::Abs(r), hn::Set(d, k::kTiny)), r,
                                 hn::Add(r, hn::Mul(hn::Mul(r, z), ps)));
  const V cos_r =
      hn::Add(hn::Sub(hn::Set(d, 1.0), hn::Mul(hn::Set(d, 0.5), z)), hn::Mul(hn::Mul(z, z), pc));
  const auto odd = hn::RebindMask(d, hn::TestBit(q, hn::Set(du, 1)));
  const V sign_s = hn::BitCast(d, hn::ShiftLeft<62>(hn::And(q, hn::Set(du, 2))));
  const V sign_c =
      hn::BitCast(d, hn::ShiftLeft<62>(hn::And(hn::Add(q, hn::Set(du, 1)), hn::Set(du, 2))));
  s = hn::Xor(hn::IfThenElse(odd, cos_r, sin_r), sign_s);
  c = hn::Xor(hn::IfThenElse(odd, sin_r, cos_r), sign_c);
}

}  // namespace HWY_NAMESPACE
}  // namespace grove
HWY_AFTER_NAMESPACE();

#endif  // GROVE_CONCURRENCY_SIN_COS_INL_H_

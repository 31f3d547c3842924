// SinCos (sin_cos.h). Compiled with -ffp-contract=off (concurrency/CMakeLists.txt): the scalar
// reference and every target must round after each multiply and each add. The vector kernel is
// SinCosVector (sin_cos-inl.h), which other kernels include.
#ifndef GROVE_CONCURRENCY_SIN_COS_CC_
#define GROVE_CONCURRENCY_SIN_COS_CC_

#include "concurrency/sin_cos.h"

#include <bit>
#include <cmath>
#include <cstdint>

#include "concurrency/sin_cos_constants.h"

namespace grove {
namespace {

// The scalar reference: the same operations, in the same order, as SinCosVector.
void SinCosOne(double x, double& s, double& c) {
  namespace k = sin_cos_internal;
  const double t = x * k::kTwoOverPi + k::kRoundBias;
  const double kq = t - k::kRoundBias;
  const uint64_t q = std::bit_cast<uint64_t>(t);  // kq mod 4 in the low two bits
  double r = x - kq * k::kPiOver2[0];
  r = r - kq * k::kPiOver2[1];
  r = r - kq * k::kPiOver2[2];
  r = r - kq * k::kPiOver2[3];
  const double z = r * r;
  double ps = k::kSin[0];
  double pc = k::kCos[0];
  for (int i = 1; i < 6; ++i) {
    ps = ps * z + k::kSin[i];
    pc = pc * z + k::kCos[i];
  }
  const double sin_r = std::fabs(r) < k::kTiny ? r : r + r * z * ps;
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

#include "concurrency/sin_cos-inl.h"

HWY_BEFORE_NAMESPACE();
namespace grove {
namespace HWY_NAMESPACE {

namespace hn = hwy::HWY_NAMESPACE;

void SinCosImpl(const double* x, size_t n, double* s, double* c) {
  const hn::ScalableTag<double> d;
  const size_t lanes = hn::Lanes(d);
  size_t i = 0;
  for (; i + lanes <= n; i += lanes) {
    hn::Vec<decltype(d)> vs, vc;
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

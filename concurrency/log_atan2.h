// Logarithm and two-argument arc tangent of many values at once, SIMD by Google Highway
// (dispatched at run time like SinCos), with the same bits on every target and in the scalar
// references: every step is one IEEE operation in a fixed order (no fused multiply-add;
// log_atan2.cc is compiled with -ffp-contract=off). For kernels that need them inside their own
// vector loops, the vector code is in log_atan2-inl.h.
//
// Log: the exponent split off, the mantissa m brought into [sqrt(1/2), sqrt(2)), and log m =
// 2 atanh((m - 1) / (m + 1)) by its series to the 21st power: within 2 ulp of the exact value
// for positive normal x (measured in tests/concurrency/log_atan2_test.cc); not for subnormals,
// zero, negatives, infinities or NaN.
// Atan2: |y| and |x| ordered so that t = min / max <= 1, t reduced to (t - 1) / (t + 1) above
// 0.66 (pi/4 added back), Cephes' rational approximation of atan on [-0.66, 0.66] (Moshier,
// "Methods and Programs for Mathematical Functions", 1989), then the octant and quadrant:
// within 2 ulp for finite arguments. atan2(+-0, +-0) is +-0 or +-pi, as std::atan2.
//
// Thread safety: pure functions.
#ifndef GROVE_CONCURRENCY_LOG_ATAN2_H_
#define GROVE_CONCURRENCY_LOG_ATAN2_H_

#include <cstddef>

namespace grove {

// out[i] = log(x[i]) for i < n (out may be x).
void LogBatch(const double* x, size_t n, double* out);
// out[i] = atan2(y[i], x[i]) for i < n (out may be y or x).
void Atan2Batch(const double* y, const double* x, size_t n, double* out);

// The same, one value at a time without SIMD: the references the batches are tested against.
double LogReference(double x);
double Atan2Reference(double y, double x);

}  // namespace grove

#endif  // GROVE_CONCURRENCY_LOG_ATAN2_H_

// SinCos: sines and cosines of many angles at once, SIMD by Google Highway (dispatched at run time
// like DrawNormals), with the same bits on every target and in the scalar SinCosReference: every
// step is one IEEE operation in a fixed order (multiplies and adds kept apart, never fused, since
// only some targets have FMA; sin_cos.cc is compiled with -ffp-contract=off).
//
// Method: Cody and Waite's reduction by pi/2 in four parts (exact products for |k| < 2^20), then
// Cephes' polynomials for sin and cos on [-pi/4, pi/4] (Moshier, "Methods and Programs for
// Mathematical Functions", 1989). Within 2 ulp of the exact values for |x| <= 1000 (measured in
// tests/concurrency/sin_cos_test.cc); the error grows with |x| beyond about 1.6e6 (2^20 pi/2).
// Infinities and NaN give NaN.
//
// Thread safety: pure functions.
#ifndef GROVE_CONCURRENCY_SIN_COS_H_
#define GROVE_CONCURRENCY_SIN_COS_H_

#include <cstddef>

namespace grove {

// s[i] = sin(x[i]) and c[i] = cos(x[i]) for i < n. s or c may be x itself; otherwise no overlap.
void SinCos(const double* x, size_t n, double* s, double* c);

// The same, one angle at a time without SIMD: the reference SinCos is tested against.
void SinCosReference(const double* x, size_t n, double* s, double* c);

}  // namespace grove

#endif  // GROVE_CONCURRENCY_SIN_COS_H_

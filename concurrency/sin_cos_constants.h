// The constants of SinCos (sin_cos.h): Cody and Waite's parts of pi/2 and Cephes' polynomials,
// shared by the scalar reference and the vector kernel (sin_cos-inl.h).
#ifndef GROVE_CONCURRENCY_SIN_COS_CONSTANTS_H_
#define GROVE_CONCURRENCY_SIN_COS_CONSTANTS_H_

namespace grove::sin_cos_internal {

inline constexpr double kTwoOverPi = 0x1.45f306dc9c883p-1;
// Adding 1.5 * 2^52 rounds |y| < 2^51 to the nearest integer (ties to even), which then sits in
// the low bits of the sum's representation.
inline constexpr double kRoundBias = 0x1.8p52;
// pi/2 = kPiOver2[0] + ... + kPiOver2[3] to about 150 bits. The first three have at most 33
// significant bits, so k * kPiOver2[i] is exact for |k| < 2^20.
inline constexpr double kPiOver2[4] = {0x1.921fb544p0, 0x1.0b4611a6p-34, 0x1.3198a2ep-69,
                                       0x1.b839a252049c1p-104};
// Cephes sin.c: sin r = r + r z P(z) and cos r = 1 - z / 2 + z^2 Q(z), z = r^2, |r| <= pi/4.
inline constexpr double kSin[6] = {1.58962301576546568060e-10, -2.50507477628578072866e-8,
                                   2.75573136213857245213e-6,  -1.98412698295895385996e-4,
                                   8.33333333332211858878e-3,  -1.66666666666666307295e-1};
inline constexpr double kCos[6] = {-1.13585365213876817300e-11, 2.08757008419747316778e-9,
                                   -2.75573141792967388112e-7,  2.48015872888517045348e-5,
                                   -1.38888888888730564116e-3,  4.16666666666665929218e-2};
// Below this, sin r rounds to r; the polynomial would turn r = -0 into +0.
inline constexpr double kTiny = 0x1p-27;

}  // namespace grove::sin_cos_internal

#endif  // GROVE_CONCURRENCY_SIN_COS_CONSTANTS_H_

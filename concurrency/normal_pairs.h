// DrawNormalPairs: two standard normal deviates per particle from the counter-based streams by
// the Box-Muller transform, with particles in SIMD lanes (Google Highway, dispatched at run time
// like DrawNormals).
//
// Particles 2b and 2b + 1 share one Philox4x32-10 block, the first of RandomStream(seed, step, b,
// purpose): its 32-bit words w0, w1 are particle 2b's, w2, w3 particle 2b + 1's. With
// u = (w0 + 1) / 2^32 in (0, 1] and f = w1 / 2^32 in [0, 1),
//   first = sqrt(-2 log u) cos(2 pi f),   second = sqrt(-2 log u) sin(2 pi f)
// (Box and Muller, "A note on the generation of random normal deviates", 1958). A block per two
// particles: no rejection, no table and no scalar path, unlike the ziggurat's NextNormal (whose
// draws these are not). log is a fixed sequence of IEEE operations (an atanh series after the
// exponent is split off, within 2 ulp), the sine and cosine SinCosVector's, and the source is
// compiled with -ffp-contract=off: the same bits on every Highway target, in any lane and in
// NormalPairReference. |deviate| <= sqrt(2 ln 2^32) = 6.66.
//
// Thread safety: pure functions of their arguments.
#ifndef GROVE_CONCURRENCY_NORMAL_PAIRS_H_
#define GROVE_CONCURRENCY_NORMAL_PAIRS_H_

#include <cstdint>

namespace grove {

// For every particle p in [begin, end), writes its pair to first[p - begin] and
// second[p - begin]. REQUIRES: begin <= end; first and second hold end - begin doubles.
void DrawNormalPairs(uint64_t seed, uint64_t step, uint32_t purpose, uint32_t begin, uint32_t end,
                     double* first, double* second);

// One particle's pair, without SIMD: the reference DrawNormalPairs is tested against.
void NormalPairReference(uint64_t seed, uint64_t step, uint32_t particle, uint32_t purpose,
                         double* first, double* second);

}  // namespace grove

#endif  // GROVE_CONCURRENCY_NORMAL_PAIRS_H_

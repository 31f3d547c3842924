// DrawNormals: the first few normal deviates of many particles' RandomStreams at once, with
// particles in SIMD lanes (Google Highway, dispatched at run time to the best target the CPU
// has: AVX-512, AVX2, SSE4, SSSE3 or scalar).
//
// Bit-identical to RandomStream: lane i runs Philox4x32-10 on particle begin + i's counter and
// takes the ziggurat's fast path, which 97.24 % of draws stay on (the mean of ZigguratTables'
// ratio[]; the top layer, ratio 0, always leaves it); a particle any of whose draws leaves the fast
// path (8 % of particles for 3 draws) is drawn again, whole, by RandomStream::NextNormal.
// For 3 draws a particle this is 1.8 times as fast as the scalar loop with AVX-512, 1.2 times with
// AVX2, but 0.8 times with SSE4 or SSSE3 (bench/random_benchmark.cc, a 2-core AMD EPYC).
//
// Thread safety: a pure function of its arguments; any number of threads may call it at once.
#ifndef GROVE_CONCURRENCY_NORMAL_BATCH_H_
#define GROVE_CONCURRENCY_NORMAL_BATCH_H_

#include <cstdint>
#include <span>
#include <string>

namespace grove {

// The most deviates DrawNormals draws per particle.
inline constexpr int kMaxBatchNormals = 6;

// For every particle p in [begin, end), writes the first out.size() normal deviates of
// RandomStream(seed, step, p, purpose) (what out.size() calls of NextNormal() return, in order)
// to out[k][p - begin]. Returns how many of the particles were drawn by the scalar path.
// REQUIRES: begin <= end; out.size() <= kMaxBatchNormals; each out[k] has end - begin doubles.
uint32_t DrawNormals(uint64_t seed, uint64_t step, uint32_t purpose, uint32_t begin, uint32_t end,
                     std::span<double* const> out);

// The Highway target DrawNormals dispatches to now (HWY_AVX3, HWY_AVX2, ...: a bit of
// hwy/detect_targets.h), for tests and benchmark labels.
int64_t DrawNormalsTarget();
// The Highway targets compiled in, best first, by name ("AVX3 AVX2 SSE4 SSSE3 EMU128"), and the
// name of one target (hwy::TargetName).
std::string SimdTargetsCompiled();
std::string SimdTargetName(int64_t target);

}  // namespace grove

#endif  // GROVE_CONCURRENCY_NORMAL_BATCH_H_

// RandomStream: counter-based random numbers keyed by (seed, step, particle, purpose), from
// Random123's Philox4x32-10 (Salmon et al., "Parallel random numbers: as easy as 1, 2, 3", 2011);
// normal deviates by the ziggurat.
//
// A draw depends only on its key and its index in the stream, never on which thread makes it or
// in what order, so the same seed gives bit-identical results at any thread count.
#ifndef GROVE_CONCURRENCY_RANDOM_STREAM_H_
#define GROVE_CONCURRENCY_RANDOM_STREAM_H_

#include <Random123/philox.h>

#include <array>
#include <cmath>
#include <cstdint>

namespace grove {

// Tables of the ziggurat for the standard normal with 128 layers (Marsaglia and Tsang, "The
// ziggurat method for generating random variables", 2000; the layout of Doornik, "An improved
// ziggurat method", 2005). x[0] is the base layer's virtual width V / f(R), x[1] = R, x[128] = 0;
// ratio[i] = x[i + 1] / x[i].
struct ZigguratTables {
  static constexpr int kLayers = 128;
  static constexpr double kR = 3.442619855899;
  static constexpr double kV = 9.91256303526217e-3;
  std::array<double, kLayers + 1> x;
  std::array<double, kLayers> ratio;

  ZigguratTables() {
    double f = std::exp(-0.5 * kR * kR);
    x[0] = kV / f;
    x[1] = kR;
    x[kLayers] = 0;
    for (int i = 2; i < kLayers; ++i) {
      x[i] = std::sqrt(-2 * std::log(kV / x[i - 1] + f));
      f = std::exp(-0.5 * x[i] * x[i]);
    }
    for (int i = 0; i < kLayers; ++i) ratio[i] = x[i + 1] / x[i];
  }
  // Immutable once built; shared by every stream.
  static const ZigguratTables& Get() {
    static const ZigguratTables tables;
    return tables;
  }
};

// Every use of the random streams, one value each, so that no two uses of one (step, particle)
// ever draw the same numbers. Values are part of the results: never renumber one.
enum StreamPurpose : uint32_t {
  kTest = 0,      // tests and tools
  kMotion = 1,    // a particle's motion noise in a step
  kInit = 2,      // a particle's initial state
  kProposal = 3,  // a particle's draw from its proposal at a scan (FastSLAM 2.0 and later)
  // Differential evolution's draws for a particle's trial in generation g use
  // kDifferentialEvolution + 256 g (g < 256; the low byte keeps them apart from the others).
  kDifferentialEvolution = 4,
  kAssociation = 5,    // a particle's sampled data associations at a scan (landmark FastSLAM)
  kResample = 0x5E5A,  // the resampling draws of a step
  // Island mode's draws of a step: particle = 2 * island + d, d = 0 for the island's own next
  // generation and 1 for the particles it sends its neighbour.
  kIslandResample = 0x5E5B,
};

class RandomStream {
 public:
  // `purpose` separates independent uses within one (step, particle), e.g. motion noise and
  // resampling.
  RandomStream(uint64_t seed, uint64_t step, uint32_t particle, uint32_t purpose = 0) {
    key_ = {{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32)}};
    ctr_ = {{0, particle, static_cast<uint32_t>(step),
             static_cast<uint32_t>(step >> 32) ^ (purpose << 16)}};
  }

  // 64 uniformly random bits.
  uint64_t NextU64() {
    if (used_ >= 4) Refill();
    uint64_t v = (uint64_t{out_.v[used_]} << 32) | out_.v[used_ + 1];
    used_ += 2;
    return v;
  }

  // Uniform in [0, 1), 53 random bits.
  double NextUniform() { return static_cast<double>(NextU64() >> 11) * 0x1.0p-53; }

  // Standard normal deviate by the ziggurat: one 64-bit draw and no transcendental function on
  // about 97.2 % of calls (the mean of the layers' x[i + 1] / x[i]; Box-Muller needs a log, a
  // square root and a sincos every two).
  double NextNormal() {
    const ZigguratTables& z = ZigguratTables::Get();
    for (;;) {
      uint64_t bits = NextU64();
      int layer = static_cast<int>(bits & (ZigguratTables::kLayers - 1));
      double u = static_cast<double>(static_cast<int64_t>(bits >> 11) - (int64_t{1} << 52)) *
                 0x1.0p-52;  // uniform in [-1, 1)
      if (std::fabs(u) < z.ratio[layer]) return u * z.x[layer];
      if (layer == 0) return Tail(u < 0);
      double x = u * z.x[layer];
      double f0 = std::exp(-0.5 * (z.x[layer] * z.x[layer] - x * x));
      double f1 = std::exp(-0.5 * (z.x[layer + 1] * z.x[layer + 1] - x * x));
      if (f1 + NextUniform() * (f0 - f1) < 1.0) return x;
    }
  }

 private:
  using Philox = r123::Philox4x32;

  // Beyond R: Marsaglia's tail method.
  double Tail(bool negative) {
    double a, b;
    do {
      a = -std::log(1.0 - NextUniform()) / ZigguratTables::kR;
      b = -std::log(1.0 - NextUniform());
    } while (b + b < a * a);
    return negative ? -(ZigguratTables::kR + a) : ZigguratTables::kR + a;
  }

  void Refill() {
    out_ = Philox()(ctr_, key_);
    ++ctr_.v[0];
    used_ = 0;
  }

  Philox::key_type key_;
  Philox::ctr_type ctr_;
  Philox::ctr_type out_{};
  int used_ = 4;
};

}  // namespace grove

#endif  // GROVE_CONCURRENCY_RANDOM_STREAM_H_

// RandomStream: counter-based random numbers keyed by (seed, step, particle, purpose), from
// Random123's Philox4x32-10 (Salmon et al., "Parallel random numbers: as easy as 1, 2, 3", 2011).
//
// A draw depends only on its key and its index in the stream, never on which thread makes it or
// in what order, so the same seed gives bit-identical results at any thread count.
#ifndef GROVE_CONCURRENCY_RANDOM_STREAM_H_
#define GROVE_CONCURRENCY_RANDOM_STREAM_H_

#include <Random123/boxmuller.hpp>
#include <Random123/philox.h>

#include <cstdint>

namespace grove {

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

  // Standard normal deviate (Box-Muller from Random123; pairs are used in turn).
  double NextNormal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    uint64_t a = NextU64();
    uint64_t b = NextU64();
    r123::double2 z = r123::boxmuller(a, b);
    spare_ = z.y;
    has_spare_ = true;
    return z.x;
  }

 private:
  using Philox = r123::Philox4x32;

  void Refill() {
    out_ = Philox()(ctr_, key_);
    ++ctr_.v[0];
    used_ = 0;
  }

  Philox::key_type key_;
  Philox::ctr_type ctr_;
  Philox::ctr_type out_{};
  int used_ = 4;
  bool has_spare_ = false;
  double spare_ = 0;
};

}  // namespace grove

#endif  // GROVE_CONCURRENCY_RANDOM_STREAM_H_

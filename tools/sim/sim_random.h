// Random draws for the simulators, built on the raw 64-bit output of std::mt19937_64 through our
// own uniform and Box-Muller transforms, never an implementation-defined std:: distribution, so
// the same seed gives the same walk with any standard library (libm may still differ in the
// last bits).
#ifndef GROVE_TOOLS_SIM_SIM_RANDOM_H_
#define GROVE_TOOLS_SIM_SIM_RANDOM_H_

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>

namespace grove::tools {

class SimRandom {
 public:
  explicit SimRandom(uint64_t seed) : engine_(seed) {}

  // Uniform in [0, 1), 53 random bits.
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  // Standard normal by Box-Muller (one of the pair; the other is dropped for simplicity).
  double Normal() {
    const double u1 = 1.0 - Uniform();  // in (0, 1], so the log is finite
    const double u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.14159265358979323846 * u2);
  }
  // Uniform in [0, n). REQUIRES: n > 0.
  size_t Index(size_t n) { return std::min(n - 1, static_cast<size_t>(Uniform() * n)); }

 private:
  std::mt19937_64 engine_;
};

// SplitMix64 finaliser: derives independent engine seeds from the user's seed.
inline uint64_t MixSeed(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

}  // namespace grove::tools

#endif  // GROVE_TOOLS_SIM_SIM_RANDOM_H_

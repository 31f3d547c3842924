// NormalSource: standard normal deviates for the simulators, from the raw output of
// std::mt19937_64 seeded by std::seed_seq from (seed, purpose) (both algorithms are fixed by the
// C++ standard) and our own Box-Muller (one of the pair), never an implementation-defined std::
// distribution: the same numbers on every platform (up to libm's last bit).
//
// Thread safety: one thread at a time per object.
#ifndef GROVE_TOOLS_SIM_NORMAL_SOURCE_H_
#define GROVE_TOOLS_SIM_NORMAL_SOURCE_H_

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace grove::tools {

class NormalSource {
 public:
  // `purpose` keeps the streams of one seed apart (a simulator's control and sensor noise).
  NormalSource(uint64_t seed, uint32_t purpose) {
    std::seed_seq seq{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), purpose};
    engine_.seed(seq);
  }
  double Next() {
    const double u1 = 1.0 - Uniform();  // in (0, 1], so the log is finite
    const double u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }

 private:
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  std::mt19937_64 engine_;
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_SIM_NORMAL_SOURCE_H_

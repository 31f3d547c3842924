// FixedWeights: particle weights in fixed point (2^-52 units), which make a sum over the
// particles' maps (the cumulative map, a stored block's fold) an exact integer sum, the same
// whichever nodes happen to be shared, so it is bit-identical at any thread count.
#ifndef GROVE_ENGINE_FOOTSLAM_FIXED_WEIGHTS_H_
#define GROVE_ENGINE_FOOTSLAM_FIXED_WEIGHTS_H_

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace grove::footslam {

// One unit of weight in fixed point.
inline constexpr double kWeightScale = 4503599627370496.0;  // 2^52

// The weights of normalised log weights `log_w` in fixed point (kWeightScale).
inline std::vector<uint64_t> FixedWeights(std::span<const double> log_w) {
  std::vector<uint64_t> fixed(log_w.size());
  for (size_t i = 0; i < fixed.size(); ++i) {
    fixed[i] = static_cast<uint64_t>(std::llround(std::exp(log_w[i]) * kWeightScale));
  }
  return fixed;
}

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_FIXED_WEIGHTS_H_

#include "engine/footslam/alphabet.h"

#include <string>

namespace grove::footslam {

StatusOr<Alphabet> Alphabet::Create(int max_count) {
  if (max_count < 1 || max_count > kMaxCount) {
    return InvalidArgumentError("alphabet = " + std::to_string(max_count) + ": must be in 1.." +
                                std::to_string(kMaxCount) + " (0 switches the alphabet off)");
  }
  return Alphabet(max_count);
}

Alphabet::Alphabet(int max_count) : max_count_(max_count) {
  const uint32_t base = static_cast<uint32_t>(max_count) + 1;
  uint32_t place = 1;
  for (int e = 0; e < kEdges; ++e) {
    place_[e] = place;
    place *= base;
  }
  symbol_count_ = static_cast<int>(place);
  next_.resize(place * kEdges);
  counts_.resize(place * kEdges);
  total_.resize(place);
  for (uint32_t s = 0; s < place; ++s) {
    uint32_t rest = s;
    uint32_t total = 0;
    for (int e = 0; e < kEdges; ++e) {
      const uint32_t c = rest % base;
      rest /= base;
      counts_[s * kEdges + e] = static_cast<uint8_t>(c);
      next_[s * kEdges + e] =
          c == static_cast<uint32_t>(max_count) ? kOverflow : static_cast<uint16_t>(s + place_[e]);
      total += c;
    }
    total_[s] = static_cast<uint16_t>(total);
  }
}

}  // namespace grove::footslam

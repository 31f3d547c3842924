// Htc: the hexagon transition counters of the paper (one per edge), and EdgeCounts, what a
// crossing reads of them. What a map of them provides is FootSlamMap (footslam_map.h).
#ifndef GROVE_ENGINE_FOOTSLAM_HTC_H_
#define GROVE_ENGINE_FOOTSLAM_HTC_H_

#include <cstdint>

#include "engine/persistent/memory_use.h"

namespace grove::footslam {

struct Htc {
  uint32_t c[6];
  uint32_t Total() const { return c[0] + c[1] + c[2] + c[3] + c[4] + c[5]; }
};

// A checkpoint's counters must be ones a run can reach: their total fits in 31 bits.
inline bool PlausibleHtc(const Htc& h) {
  uint64_t total = 0;
  for (uint32_t c : h.c) total += c;
  return total <= 0x7FFFFFFF;
}

struct EdgeCounts {
  uint32_t edge;   // C_h^e before the crossing
  uint32_t total;  // C_h before the crossing
};

using grove::AddPoolStats;

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_HTC_H_

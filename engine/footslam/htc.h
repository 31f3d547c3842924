// Hexagon transition counters (the paper's HTC) and what every FootSLAM map provides.
//
// A map policy (HTreeMap, AlphabetHTreeMap, NaiveMap) holds the maps of all particles:
//   bool Cross(size_t i, uint64_t key, int edge, int slot, EdgeCounts* before,
//              uint32_t owners = 1);
//       particle i leaves hexagon `key` across `edge`: sets the counters before the crossing
//       and adds one; false when out of memory (the engine then stops). owners > 1: that many
//       particles hold particle i's map and the caller gives them all its result afterwards
//       (Share), so a map whose every reference is theirs may be changed in place
//   void Prefetch(size_t i) const;  // a hint: particle i's map will be used soon
//   void PrefetchPath(size_t i, uint64_t key, int depth) const;
//       a hint: load the node at `depth` (< height()) on particle i's path to `key`; the nodes
//       above it were hinted earlier
//   int height() const;  // levels PrefetchPath walks (0: none)
//   void Gather(std::span<const uint32_t> parents, WorkerPool&);  // next generation
//   void ReleaseDead(WorkerPool&);                                  // frees the previous one
//   void ReleaseDeadRange(size_t lo, size_t hi, int slot);  // ReleaseDead() of [lo, hi) only
//   void DeadReleased();  // ends the previous generation, every piece of it released
//   void ForEachHex(size_t i, F f) const;  // f(key, const Htc&) in key order
//   void Cumulative(std::span<const uint64_t> weights, F f) const;
//       f(key, const Htc&, uint64_t weight) once per (distinct node, hexagon); summing
//       weight * counts per key gives sum_i w_i C_i
//   MemoryUse memory() const;
//   void Save(ByteWriter*) const;                      // every particle's map, sharing kept
//   Status Load(ByteReader*, uint64_t key_limit);      // replaces the maps of a new engine
//   Status CheckCounts() const;  // the expensive invariant walk of the shared nodes (tests)
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

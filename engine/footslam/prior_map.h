// PriorMap: the hexagon counters of an earlier walk that FootSLAM's weighting adds to every
// particle's own (FootSlam::SetPriorMap, and the stored map of storage of diversity), with how
// one is built from the user's counts and kept in a checkpoint.
#ifndef GROVE_ENGINE_FOOTSLAM_PRIOR_MAP_H_
#define GROVE_ENGINE_FOOTSLAM_PRIOR_MAP_H_

#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "engine/footslam/hex_grid.h"
#include "engine/footslam/hex_table.h"
#include "engine/io/checkpoint_io.h"
#include "grove/footslam.h"
#include "grove/status.h"

namespace grove::footslam {

// A hexagon of a prior map (a cumulative map of an earlier walk): its counters times the
// configured confidence, added to the prior count a of the weighting. Read-only during steps,
// one table shared by every particle.
struct PriorHex {
  double edge[6];
  double total;  // edge[0] + ... + edge[5]
};
using PriorMap = HexTable<PriorHex>;

// The sum of a prior hexagon's edges in edge order, as every reader of one computes it.
inline double EdgeSum(const PriorHex& p) {
  double total = 0;
  for (double c : p.edge) total += c;
  return total;
}

// The prior map of the user's counts `map` times `confidence` into *prior (empty), keyed by
// key_of(hexagon, &key), which is false for a hexagon off the grid: those are left out and
// counted in *outside. InvalidArgument naming the row for a negative or non-finite count, a
// product that overflows or a hexagon given twice.
Status BuildPriorMap(const std::vector<HexCounts>& map, double confidence,
                     const std::function<bool(Hex, uint64_t*)>& key_of, PriorMap* prior,
                     int64_t* outside);

// The hexagons of `map` in key order.
std::vector<std::pair<uint64_t, const PriorHex*>> SortedHexes(const PriorMap& map);

// A table of hexagons in key order: u64 hexagon count, then per hexagon its u64 key and six f64
// counters.
void SavePriorMap(const PriorMap& map, ByteWriter* w);
// Reads what SavePriorMap() wrote into *map (empty), its fields named after `what`; keys must
// increase and be below key_count, counters finite and >= 0.
Status LoadPriorMap(ByteReader* r, const char* what, uint64_t key_count, PriorMap* map);

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_PRIOR_MAP_H_

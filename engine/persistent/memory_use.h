// MemoryUse (grove/types.h) from the statistics of the node pools behind a model's stores.
#ifndef GROVE_ENGINE_PERSISTENT_MEMORY_USE_H_
#define GROVE_ENGINE_PERSISTENT_MEMORY_USE_H_

#include "alloc/node_pool.h"
#include "grove/types.h"

namespace grove {

// Adds one pool's statistics to *m.
inline void AddPoolStats(const PoolStats& s, MemoryUse* m) {
  m->live_nodes += s.live_nodes;
  m->live_bytes += s.live_bytes();
  m->peak_live_nodes += s.peak_live_nodes;
  m->peak_live_bytes += s.peak_live_bytes();
  m->reserved_bytes += s.reserved_bytes;
}

}  // namespace grove

#endif  // GROVE_ENGINE_PERSISTENT_MEMORY_USE_H_

// GatherShared and GatherValues: the next generation of reference-counted handles (map roots,
// path histories) and of plain per-particle values after resampling.
#ifndef GROVE_ENGINE_FILTER_GENERATION_H_
#define GROVE_ENGINE_FILTER_GENERATION_H_

#include <cstdint>
#include <span>
#include <vector>

#include "concurrency/worker_pool.h"

namespace grove {

// GatherShared's loop body over new particles [b, e), one chunk of a loop whose chunks are
// [c * grain, (c + 1) * grain): for a caller that gathers several things in one loop. `next`
// must have parents.size() entries; GatherSharedSeams() must follow the loop.
template <typename Handle, typename Share>
void GatherSharedRange(std::span<const uint32_t> parents, std::vector<Handle>* current, Share share,
                       std::vector<Handle>* next, size_t b, size_t e) {
  const size_t n = parents.size();
  // A parent's entry must stay readable until all of its copies are made: the chunk that makes
  // them all clears it after the last; one whose copies cross into another chunk is cleared
  // after the loop.
  bool whole = false;  // the current parent's first copy is in this chunk
  for (size_t k = b; k < e; ++k) {
    const uint32_t p = parents[k];
    Handle h = (*current)[p];
    if (k == 0 || parents[k - 1] != p) {
      whole = true;
      (*next)[k] = h;
    } else {
      (*next)[k] = share(h);
    }
    if (whole && (k + 1 == n || parents[k + 1] != p)) (*current)[p] = nullptr;
  }
}

// Clears the entries of *current whose copies crossed a chunk boundary, after the loop.
template <typename Handle>
void GatherSharedSeams(std::span<const uint32_t> parents, size_t grain,
                       std::vector<Handle>* current) {
  for (size_t b = grain; b < parents.size(); b += grain) {
    if (parents[b - 1] == parents[b]) (*current)[parents[b]] = nullptr;
  }
}

// Sets next[k] to a reference to (*current)[parents[k]]. The first copy of each parent takes
// the parent's own reference over and the others call share(), so a parent with c copies costs
// c - 1 increments; the taken-over entries of *current become nullptr, so what is left in
// *current is exactly the references of the dead generation, to be released.
// REQUIRES: the copies of a parent are adjacent in `parents` (every resampling scheme here gives
// a nondecreasing list; across ranks, each rank's particles come in rank order).
// `next` receives the result; a buffer kept between generations spares an allocation and a fill.
template <typename Handle, typename Share>
void GatherShared(std::span<const uint32_t> parents, std::vector<Handle>* current,
                  WorkerPool& workers, Share share, std::vector<Handle>* next) {
  constexpr size_t kGrain = 2048;
  next->resize(parents.size());
  workers.ParallelFor(parents.size(), kGrain, [&](int, size_t b, size_t e) {
    GatherSharedRange(parents, current, share, next, b, e);
  });
  GatherSharedSeams(parents, kGrain, current);
}

// A per-particle value and the buffer its next generation is gathered into, kept by the caller
// between generations (it ends up holding the old values): once it has grown, a gather neither
// allocates nor fills memory on the driving thread alone. Begin(), Range() on each chunk of new
// particles and End() make the gather in parts, for a caller that gathers in its own loop.
template <typename T>
struct Gathered {
  std::vector<T>* values;
  std::vector<T>* spare;

  void Begin(size_t n) const { spare->resize(n); }
  void Range(std::span<const uint32_t> parents, size_t b, size_t e) const {
    for (size_t k = b; k < e; ++k) (*spare)[k] = (*values)[parents[k]];
  }
  void End() const { values->swap(*spare); }
};

// The next generation of per-particle values (a pose, an error state): each (*values)[k] becomes
// the old (*values)[parents[k]], all of them in one parallel loop (one join, not one per value).
template <typename... T>
void GatherValuesTogether(std::span<const uint32_t> parents, WorkerPool& workers,
                          Gathered<T>... v) {
  (v.Begin(parents.size()), ...);
  workers.ParallelFor(parents.size(), 4096,
                      [&](int, size_t b, size_t e) { (v.Range(parents, b, e), ...); });
  (v.End(), ...);
}

// One value into a new buffer each time (for models that keep no spare).
template <typename T>
void GatherValues(std::span<const uint32_t> parents, WorkerPool& workers, std::vector<T>* v) {
  std::vector<T> next;
  GatherValuesTogether(parents, workers, Gathered<T>{v, &next});
}

}  // namespace grove

#endif  // GROVE_ENGINE_FILTER_GENERATION_H_

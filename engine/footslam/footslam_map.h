// FootSlamMap: what a FootSLAM map policy (HTreeMap, AlphabetHTreeMap, NaiveMap) provides, the
// maps of all particles of a FootSlamModel; and BlockStoringMap, what storage of diversity asks
// of one besides.
#ifndef GROVE_ENGINE_FOOTSLAM_FOOTSLAM_MAP_H_
#define GROVE_ENGINE_FOOTSLAM_FOOTSLAM_MAP_H_

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/footslam/alphabet.h"
#include "engine/footslam/htc.h"
#include "engine/footslam/htree_layout.h"
#include "engine/io/checkpoint_io.h"
#include "engine/persistent/memory_use.h"
#include "grove/status.h"

namespace grove::footslam {

// The callables the maps' visits take, as the concepts below check them (declared only).
struct HexVisitor {  // f(key, const Htc&)
  void operator()(uint64_t, const Htc&) const;
};
struct WeightedHexVisitor {  // f(key, const Htc&, uint64_t weight)
  void operator()(uint64_t, const Htc&, uint64_t) const;
};

// A map policy holds the maps of all particles, built as M(layout, slots, particles, alphabet)
// (the alphabet null unless the map uses one):
//   Cross(i, key, edge, slot, &before, owners): particle i leaves hexagon `key` across `edge`:
//       sets the counters before the crossing and adds one; false when out of memory (the engine
//       then stops). owners > 1: that many particles hold particle i's map and the caller gives
//       them all its result afterwards (Share), so a map whose every reference is theirs may be
//       changed in place.
//   version(i): what identifies particle i's map (equal versions: the same map); Share(i, from,
//       slot): particle i's map becomes particle from's.
//   Prefetch(i): a hint, particle i's map will be used soon; PrefetchPath(i, key, depth): a
//       hint, load the node at `depth` (< height()) on particle i's path to `key`, the nodes
//       above it hinted earlier; height(): the levels PrefetchPath walks (0: none);
//       grown_height(): the levels of the highest particle's map.
//   Gather(parents, workers): the next generation; ReleaseDead(workers) frees the previous one,
//       ReleaseDeadRange(lo, hi, slot) that of particles [lo, hi) only, DeadReleased() ends it
//       once every piece is released.
//   ForEachHex(i, f): f(key, const Htc&) in key order; Cumulative(weights, f): f(key, const
//       Htc&, weight) once per (distinct node, hexagon), so that summing weight * counts per
//       key gives sum_i w_i C_i.
//   memory(); Save(w): every particle's map, sharing kept; Load(r, key_limit) replaces the maps
//       of a new engine; SaveSome(which, w) and LoadMore(r, count, key_limit): particles that
//       move between ranks; CheckCounts(): the expensive invariant walk of the shared nodes.
template <typename M>
concept FootSlamMap =
    std::constructible_from<M, const HTreeLayout&, int, size_t, const Alphabet*> &&
    std::equality_comparable<typename M::Version> &&
    requires(M& m, const M& cm, size_t i, uint64_t key, int edge, int depth, int slot,
             EdgeCounts* before, uint32_t owners, std::span<const uint32_t> parents,
             WorkerPool& workers, std::span<const uint64_t> weights, ByteWriter* w, ByteReader* r) {
  { m.Cross(i, key, edge, slot, before, owners) } -> std::same_as<bool>;
  { cm.version(i) } -> std::same_as<typename M::Version>;
  m.Share(i, i, slot);
  cm.Prefetch(i);
  cm.PrefetchPath(i, key, depth);
  { cm.height() } -> std::same_as<int>;
  { cm.grown_height() } -> std::same_as<int>;
  m.Gather(parents, workers);
  m.ReleaseDead(workers);
  m.ReleaseDeadRange(i, i, slot);
  m.DeadReleased();
  cm.ForEachHex(i, HexVisitor{});
  cm.Cumulative(weights, WeightedHexVisitor{});
  { cm.memory() } -> std::same_as<MemoryUse>;
  cm.Save(w);
  { m.Load(r, key) } -> std::same_as<Status>;
  cm.SaveSome(parents, w);
  { m.LoadMore(r, i, key) } -> std::same_as<Status>;
  { cm.CheckCounts() } -> std::same_as<Status>;
};

// A map that can store blocks (the keys under one prefix: DiversityStore): Blocks(bits) lists
// the prefixes of the blocks of `bits` that any particle's map holds; FoldBlock(bits, prefix,
// weights, f) calls f(key, const Htc&, weight) once per (distinct node, hexagon) of the block;
// DropBlock(bits, prefix, slot) removes it from every particle's map (false when out of memory).
template <typename M>
concept BlockStoringMap = FootSlamMap<M> && requires(M& m, const M& cm, int bits, uint64_t prefix,
                                                     std::span<const uint64_t> weights, int slot) {
  { cm.Blocks(bits) } -> std::same_as<std::vector<uint64_t>>;
  cm.FoldBlock(bits, prefix, weights, WeightedHexVisitor{});
  { m.DropBlock(bits, prefix, slot) } -> std::same_as<bool>;
};

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_FOOTSLAM_MAP_H_

// HTreeMap: every particle's transition counters in a dynamic H-tree (paper §IV-B), a version of
// one PersistentTrie keyed by the hexagon's H-tree path. Resampling shares roots; a crossing
// copies only the shared nodes of one path.
#ifndef GROVE_ENGINE_FOOTSLAM_HTREE_MAP_H_
#define GROVE_ENGINE_FOOTSLAM_HTREE_MAP_H_

#include <algorithm>
#include <span>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/footslam/alphabet.h"
#include "engine/footslam/footslam_map.h"
#include "engine/footslam/htc.h"
#include "engine/footslam/htree_layout.h"
#include "engine/persistent/persistent_trie.h"
#include "engine/persistent/version_set.h"

namespace grove::footslam {

template <int kLog2Degree>
class HTreeMap {
 public:
  using Trie = PersistentTrie<Htc, kLog2Degree>;

  HTreeMap(const HTreeLayout& layout, int slots, size_t particles, const Alphabet* /*unused*/)
      : trie_(layout.height(), slots, layout.fill_key(), layout.max_height()),
        roots_(&trie_, particles) {}

  // Returns false when out of memory (the map is unchanged). `owners` > 1: that many particles
  // share particle i's map and will all take its result (see footslam_map.h).
  bool Cross(size_t i, uint64_t key, int edge, int slot, EdgeCounts* before, uint32_t owners = 1) {
    return trie_.Update(
        &roots_[i], key, slot,
        [&](Htc& h, bool) {
          *before = {h.c[edge], h.Total()};
          ++h.c[edge];
        },
        owners);
  }

  // What identifies particle i's map: two particles with equal versions hold the same map.
  using Version = const typename Trie::Node*;
  Version version(size_t i) const { return roots_[i]; }
  // Particle i's map becomes particle `from`'s (shared, as resampling shares it).
  void Share(size_t i, size_t from, int slot) { roots_.Adopt(i, from, slot); }

  // Starts loading particle i's root node into the cache.
  void Prefetch(size_t i) const { __builtin_prefetch(roots_[i]); }
  // Starts loading the node at `depth` on particle i's path to `key` (see PersistentTrie).
  [[gnu::always_inline]] void PrefetchPath(size_t i, uint64_t key, int depth) const {
    trie_.PrefetchPath(roots_[i], key, depth);
  }
  // Levels of a particle's path: the highest map's (a hint for prefetching).
  int height() const { return trie_.top_height(); }
  // The levels of the highest particle's map: the grid the walk has grown to.
  int grown_height() const {
    int h = trie_.min_height();
    for (const auto* root : roots_.roots()) h = std::max(h, Trie::Height(root));
    return h;
  }

  void Gather(std::span<const uint32_t> parents, WorkerPool& workers) {
    roots_.Gather(parents, workers);
  }
  void ReleaseDead(WorkerPool& workers) { roots_.ReleaseDead(workers); }
  void ReleaseDeadRange(size_t lo, size_t hi, int slot) { roots_.ReleaseDeadRange(lo, hi, slot); }
  void DeadReleased() { roots_.DeadReleased(); }

  template <typename F>
  void ForEachHex(size_t i, F&& f) const {
    trie_.ForEach(roots_[i], f);
  }

  template <typename F>
  void Cumulative(std::span<const uint64_t> weights, F&& f) const {
    trie_.template VisitDistinct<uint64_t>(roots_.roots(), weights, f);
  }

  // Storage of diversity: a block is a subtree of the H-tree, the keys with the digits `prefix`
  // above their lowest `bits` (key >> bits == prefix; see PersistentTrie::VisitSubtreeDistinct).
  // REQUIRES: bits a multiple of log2(degree), below those of the first grid.
  // The blocks any particle's map holds, in increasing order.
  std::vector<uint64_t> Blocks(int bits) const {
    return trie_.SubtreePrefixes(roots_.roots(), bits);
  }
  // f(key, const Htc&, weight) for each hexagon of each distinct version of the block, weight
  // the sum of weights[i] over the particles whose maps hold that version.
  template <typename F>
  void FoldBlock(int bits, uint64_t prefix, std::span<const uint64_t> weights, F&& f) const {
    trie_.template VisitSubtreeDistinct<uint64_t>(roots_.roots(), weights, bits, prefix, f);
  }
  // Removes the block from every particle's map; false when out of memory (maps unchanged).
  bool DropBlock(int bits, uint64_t prefix, int slot) {
    return trie_.DropSubtree(roots_.mutable_roots(), bits, prefix, slot);
  }

  void Save(ByteWriter* w) const { trie_.Save(roots_.roots(), w); }

  Status Load(ByteReader* r, uint64_t /*key_limit: every trie key is a grid hexagon*/) {
    std::vector<typename Trie::Root> loaded;
    GROVE_RETURN_IF_ERROR(trie_.Load(r, roots_.size(), 0, &PlausibleHtc, &loaded));
    roots_.Replace(std::move(loaded));
    return Status::Ok();
  }

  // Particles `which` as Save() writes them (shared nodes once); LoadMore() appends `count`
  // particles so written.
  void SaveSome(std::span<const uint32_t> which, ByteWriter* w) const {
    trie_.Save(roots_.Pick(which), w);
  }
  Status LoadMore(ByteReader* r, size_t count, uint64_t /*key_limit*/) {
    std::vector<typename Trie::Root> loaded;
    GROVE_RETURN_IF_ERROR(trie_.Load(r, count, 0, &PlausibleHtc, &loaded));
    roots_.Append(loaded);
    return Status::Ok();
  }

  Status CheckCounts() const { return trie_.CheckCounts(roots_.AllReferences()); }

  MemoryUse memory() const {
    MemoryUse m;
    trie_.AddMemory(&m);
    return m;
  }

 private:
  Trie trie_;
  VersionSet<Trie> roots_;
};

static_assert(BlockStoringMap<HTreeMap<2>> && BlockStoringMap<HTreeMap<4>> &&
              BlockStoringMap<HTreeMap<6>> && BlockStoringMap<HTreeMap<8>>);

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_HTREE_MAP_H_

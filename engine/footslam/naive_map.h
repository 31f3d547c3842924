// NaiveMap: the baseline of paper §III. Each particle owns a hash table of its visited
// hexagons; resampling copies the table of the parent (the first offspring takes it over, every
// further offspring copies it whole), so a step costs time linear in the mapped area.
// Same keys, same counters and the same order of operations as the H-tree maps: the same seed
// gives the same particles, weights and maps.
#ifndef GROVE_ENGINE_FOOTSLAM_NAIVE_MAP_H_
#define GROVE_ENGINE_FOOTSLAM_NAIVE_MAP_H_

#include <algorithm>
#include <span>
#include <utility>
#include <vector>

#include "concurrency/worker_pool.h"
#include "engine/footslam/alphabet.h"
#include "engine/footslam/footslam_map.h"
#include "engine/footslam/hex_table.h"
#include "engine/footslam/htc.h"
#include "engine/footslam/htree_layout.h"
#include "engine/io/checkpoint_io.h"

namespace grove::footslam {

class NaiveMap {
 public:
  NaiveMap(const HTreeLayout& layout, int /*slots*/, size_t particles, const Alphabet* /*unused*/)
      : layout_(&layout), tables_(particles) {}

  // Never fails for want of a node; a table that cannot grow throws std::bad_alloc, which the
  // engine turns into ResourceExhausted.
  bool Cross(size_t i, uint64_t key, int edge, int, EdgeCounts* before, uint32_t = 1) {
    Htc& h = tables_[i].FindOrInsert(key);
    *before = {h.c[edge], h.Total()};
    ++h.c[edge];
    return true;
  }

  // What identifies particle i's map: every particle owns its table, so no two are equal.
  using Version = const HexTable<Htc>*;
  Version version(size_t i) const { return &tables_[i]; }
  // Particle i's map becomes a copy of particle `from`'s.
  void Share(size_t i, size_t from, int) { tables_[i] = tables_[from]; }

  void Prefetch(size_t) const {}
  void PrefetchPath(size_t, uint64_t, int) const {}
  int height() const { return 0; }
  // The levels of the grid that holds every particle's hexagons.
  int grown_height() const {
    int h = layout_->height();
    for (const HexTable<Htc>& t : tables_) {
      t.ForEach([&](uint64_t key, const Htc&) { h = std::max(h, layout_->HeightOf(key)); });
    }
    return h;
  }

  void Gather(std::span<const uint32_t> parents, WorkerPool& workers) {
    std::vector<HexTable<Htc>> next(parents.size());
    // parents is nondecreasing: the first slot of each parent takes its table over.
    workers.ParallelFor(parents.size(), 256, [&](int, size_t b, size_t e) {
      for (size_t k = b; k < e; ++k) {
        bool first = k == 0 || parents[k - 1] != parents[k];
        if (!first) next[k] = tables_[parents[k]];
      }
    });
    for (size_t k = 0; k < parents.size(); ++k) {
      if (k == 0 || parents[k - 1] != parents[k]) next[k] = std::move(tables_[parents[k]]);
    }
    dead_.swap(tables_);
    tables_.swap(next);
  }

  void ReleaseDead(WorkerPool& workers) {
    workers.ParallelFor(dead_.size(), 256,
                        [&](int slot, size_t b, size_t e) { ReleaseDeadRange(b, e, slot); });
    DeadReleased();
  }
  void ReleaseDeadRange(size_t lo, size_t hi, int) {
    for (size_t k = lo; k < std::min(hi, dead_.size()); ++k) dead_[k] = HexTable<Htc>();
  }
  void DeadReleased() { dead_.clear(); }

  template <typename F>
  void ForEachHex(size_t i, F&& f) const {
    for (const auto& [key, h] : Sorted(tables_[i])) f(key, h);
  }

  // Brute force over every particle: this is the cost the H-tree avoids.
  template <typename F>
  void Cumulative(std::span<const uint64_t> weights, F&& f) const {
    for (size_t i = 0; i < tables_.size(); ++i) {
      tables_[i].ForEach([&](uint64_t key, const Htc& h) { f(key, h, weights[i]); });
    }
  }

  // Each particle's table whole: u64 hexagon count, then (u64 key, counters) per hexagon.
  void Save(ByteWriter* w) const {
    for (const HexTable<Htc>& t : tables_) SaveTable(t, w);
  }

  Status Load(ByteReader* r, uint64_t key_limit) {
    std::vector<HexTable<Htc>> loaded(tables_.size());
    for (HexTable<Htc>& t : loaded) GROVE_RETURN_IF_ERROR(LoadTable(r, key_limit, &t));
    tables_.swap(loaded);
    return Status::Ok();
  }

  // Particles `which` as Save() writes them; LoadMore() appends `count` particles so written.
  void SaveSome(std::span<const uint32_t> which, ByteWriter* w) const {
    for (uint32_t i : which) SaveTable(tables_[i], w);
  }
  Status LoadMore(ByteReader* r, size_t count, uint64_t key_limit) {
    std::vector<HexTable<Htc>> loaded(count);
    for (HexTable<Htc>& t : loaded) GROVE_RETURN_IF_ERROR(LoadTable(r, key_limit, &t));
    for (HexTable<Htc>& t : loaded) tables_.push_back(std::move(t));
    return Status::Ok();
  }

  // Tables are owned, not shared: there are no counts to check.
  Status CheckCounts() const { return Status::Ok(); }

  MemoryUse memory() const {
    MemoryUse m;
    for (const HexTable<Htc>& t : tables_) {
      m.live_nodes += static_cast<int64_t>(t.size());
      m.live_bytes += static_cast<int64_t>(t.bytes());
    }
    m.peak_live_nodes = m.live_nodes;
    m.peak_live_bytes = m.live_bytes;
    return m;
  }

 private:
  // A table's hexagons in key order: its slot order depends on how it was filled, and a
  // checkpoint of a resumed engine must be the bytes it was resumed from.
  static std::vector<std::pair<uint64_t, Htc>> Sorted(const HexTable<Htc>& t) {
    std::vector<std::pair<uint64_t, Htc>> hexes;
    hexes.reserve(t.size());
    t.ForEach([&](uint64_t key, const Htc& h) { hexes.push_back({key, h}); });
    std::sort(hexes.begin(), hexes.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    return hexes;
  }

  static void SaveTable(const HexTable<Htc>& t, ByteWriter* w) {
    const std::vector<std::pair<uint64_t, Htc>> hexes = Sorted(t);
    w->Put<uint64_t>(hexes.size());
    for (const auto& [key, h] : hexes) {
      w->Put(key);
      w->Put(h);
    }
  }

  static Status LoadTable(ByteReader* r, uint64_t key_limit, HexTable<Htc>* t) {
    uint64_t count = 0;
    GROVE_RETURN_IF_ERROR(r->GetCount("hexagon count", sizeof(uint64_t) + sizeof(Htc), &count));
    for (uint64_t k = 0; k < count; ++k) {
      uint64_t key = 0;
      Htc h;
      GROVE_RETURN_IF_ERROR(r->Get("hexagon key", &key));
      if (key_limit != 0 && key >= key_limit) {
        return r->Error("hexagon key", std::to_string(key) + " is outside the grid");
      }
      GROVE_RETURN_IF_ERROR(r->Get("hexagon counters", &h));
      if (!PlausibleHtc(h)) return r->Error("hexagon counters", "impossible value");
      if (!t->Insert(key, h)) return r->Error("hexagon key", std::to_string(key) + " repeated");
    }
    return Status::Ok();
  }

  const HTreeLayout* layout_;
  std::vector<HexTable<Htc>> tables_;
  std::vector<HexTable<Htc>> dead_;
};

// A NaiveMap stores no blocks: Validate() refuses storage of diversity with map = naive.
static_assert(FootSlamMap<NaiveMap> && !BlockStoringMap<NaiveMap>);

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_NAIVE_MAP_H_

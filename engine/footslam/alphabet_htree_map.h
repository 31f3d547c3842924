// AlphabetHTreeMap: the H-tree map with the paper's alphabet (§V). A hexagon's six counters
// are one 16-bit symbol while each is at most T, and a symbol's successor for each edge is a
// table lookup. A hexagon whose counter passes T is marked escaped in the symbol tree and its
// full counters move to a second H-tree of full counters; both trees are versions shared the
// same way, so a bottom node of symbols is 2 bytes per hexagon instead of 24. Up to s = 16 a
// bottom node of symbols spans two H-tree levels and stores only the symbols present (see
// PersistentTrie): a walk fills its 16 x 16 hexagons sparsely, and paths are a level shorter.
#ifndef GROVE_ENGINE_FOOTSLAM_ALPHABET_HTREE_MAP_H_
#define GROVE_ENGINE_FOOTSLAM_ALPHABET_HTREE_MAP_H_

#include <algorithm>
#include <span>
#include <utility>
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
class AlphabetHTreeMap {
 public:
  // H-tree levels a bottom node of the symbol tree spans: two up to s = 16 (16 x 16 hexagons at
  // s = 16, which a walk fills sparsely: its nodes store only the symbols present), one above.
  static constexpr int kBottomLevels = kLog2Degree <= 4 ? 2 : 1;
  using SymbolTrie = PersistentTrie<uint16_t, kLog2Degree, kLog2Degree * kBottomLevels>;
  using FullTrie = PersistentTrie<Htc, kLog2Degree>;
  // Marks a hexagon whose counters live in the full tree. Never a symbol: S <= 6^6 < 0xFFFF.
  static constexpr uint16_t kEscaped = 0xFFFF;

  AlphabetHTreeMap(const HTreeLayout& layout, int slots, size_t particles, const Alphabet* alphabet)
      : alphabet_(alphabet),
        layout_height_(layout.height()),
        symbols_(SymbolHeight(layout.height()), slots, layout.fill_key(),
                 SymbolHeight(layout.max_height())),
        full_(layout.height(), slots, layout.fill_key(), layout.max_height()),
        symbol_roots_(&symbols_, particles),
        full_roots_(&full_, particles) {}

  // The symbol tree's height for an H-tree of `height` levels.
  static int SymbolHeight(int height) { return std::max(1, height - (kBottomLevels - 1)); }

  // Returns false when out of memory; the engine is then stopped, and the two trees may
  // disagree on the hexagon (its symbol escaped, its counters not yet moved). `owners` > 1:
  // that many particles share particle i's map and will all take its result (see footslam_map.h).
  bool Cross(size_t i, uint64_t key, int edge, int slot, EdgeCounts* out, uint32_t owners = 1) {
    EdgeCounts before{0, 0};
    bool escaped = false;
    uint16_t last_symbol = 0;
    bool escapes_now = false;
    bool ok = symbols_.Update(
        &symbol_roots_[i], key, slot,
        [&](uint16_t& s, bool) {
          if (s == kEscaped) {
            escaped = true;
            return;
          }
          before = {alphabet_->Count(s, edge), alphabet_->Total(s)};
          uint16_t next = alphabet_->Next(s, edge);
          if (next == Alphabet::kOverflow) {
            escapes_now = true;
            last_symbol = s;
            s = kEscaped;
          } else {
            s = next;
          }
        },
        owners);
    if (ok && escaped) {
      ok = full_.Update(
          &full_roots_[i], key, slot,
          [&](Htc& h, bool) {
            before = {h.c[edge], h.Total()};
            ++h.c[edge];
          },
          owners);
    } else if (ok && escapes_now) {
      ok = full_.Update(
          &full_roots_[i], key, slot,
          [&](Htc& h, bool) {
            alphabet_->Decode(last_symbol, h.c);
            ++h.c[edge];
          },
          owners);
    }
    *out = before;
    return ok;
  }

  // What identifies particle i's map: two particles with equal versions hold the same map.
  using Version = std::pair<const typename SymbolTrie::Node*, const typename FullTrie::Node*>;
  Version version(size_t i) const { return {symbol_roots_[i], full_roots_[i]}; }
  // Particle i's map becomes particle `from`'s (shared, as resampling shares it).
  void Share(size_t i, size_t from, int slot) {
    symbol_roots_.Adopt(i, from, slot);
    full_roots_.Adopt(i, from, slot);
  }

  // Starts loading particle i's root node into the cache.
  void Prefetch(size_t i) const { __builtin_prefetch(symbol_roots_[i]); }
  // Starts loading the node at `depth` on particle i's path to `key` (see PersistentTrie).
  [[gnu::always_inline]] void PrefetchPath(size_t i, uint64_t key, int depth) const {
    symbols_.PrefetchPath(symbol_roots_[i], key, depth);
  }
  // Levels of a particle's path: the highest map's (a hint for prefetching).
  int height() const { return symbols_.top_height(); }
  // The levels of the highest particle's map: the grid the walk has grown to. (A hexagon's
  // symbol stays in the symbol tree when its counters escape.)
  int grown_height() const {
    int h = layout_height_;
    for (const auto* root : symbol_roots_.roots()) {
      // Above the first grid every level of a symbol version is one H-tree level.
      const int height = SymbolTrie::Height(root);
      if (height > symbols_.min_height()) h = std::max(h, height + kBottomLevels - 1);
    }
    return h;
  }

  void Gather(std::span<const uint32_t> parents, WorkerPool& workers) {
    symbol_roots_.Gather(parents, workers);
    full_roots_.Gather(parents, workers);
  }

  void ReleaseDead(WorkerPool& workers) {
    symbol_roots_.ReleaseDead(workers);
    full_roots_.ReleaseDead(workers);
  }
  void ReleaseDeadRange(size_t lo, size_t hi, int slot) {
    symbol_roots_.ReleaseDeadRange(lo, hi, slot);
    full_roots_.ReleaseDeadRange(lo, hi, slot);
  }
  void DeadReleased() {
    symbol_roots_.DeadReleased();
    full_roots_.DeadReleased();
  }

  template <typename F>
  void ForEachHex(size_t i, F&& f) const {
    // Both trees in key order, merged: a hexagon is in exactly one of them.
    std::vector<std::pair<uint64_t, Htc>> full;
    full_.ForEach(full_roots_[i], [&](uint64_t key, const Htc& h) { full.push_back({key, h}); });
    size_t j = 0;
    symbols_.ForEach(symbol_roots_[i], [&](uint64_t key, const uint16_t& s) {
      if (s == kEscaped) {
        for (; j < full.size() && full[j].first <= key; ++j) f(full[j].first, full[j].second);
        return;
      }
      Htc h;
      alphabet_->Decode(s, h.c);
      f(key, h);
    });
    for (; j < full.size(); ++j) f(full[j].first, full[j].second);
  }

  template <typename F>
  void Cumulative(std::span<const uint64_t> weights, F&& f) const {
    symbols_.template VisitDistinct<uint64_t>(symbol_roots_.roots(), weights,
                                              [&](uint64_t key, const uint16_t& s, uint64_t w) {
                                                if (s == kEscaped) return;
                                                Htc h;
                                                alphabet_->Decode(s, h.c);
                                                f(key, h, w);
                                              });
    full_.template VisitDistinct<uint64_t>(full_roots_.roots(), weights, f);
  }

  // Storage of diversity, as HTreeMap's. A hexagon whose counters escaped keeps its symbol in
  // the symbol tree, so the symbol tree's blocks are every block.
  std::vector<uint64_t> Blocks(int bits) const {
    return symbols_.SubtreePrefixes(symbol_roots_.roots(), bits);
  }
  template <typename F>
  void FoldBlock(int bits, uint64_t prefix, std::span<const uint64_t> weights, F&& f) const {
    symbols_.template VisitSubtreeDistinct<uint64_t>(
        symbol_roots_.roots(), weights, bits, prefix,
        [&](uint64_t key, const uint16_t& s, uint64_t w) {
          if (s == kEscaped) return;
          Htc h;
          alphabet_->Decode(s, h.c);
          f(key, h, w);
        });
    full_.template VisitSubtreeDistinct<uint64_t>(full_roots_.roots(), weights, bits, prefix, f);
  }
  // False when out of memory; the engine is then stopped, and the full tree may still hold the
  // block (never read again).
  bool DropBlock(int bits, uint64_t prefix, int slot) {
    return symbols_.DropSubtree(symbol_roots_.mutable_roots(), bits, prefix, slot) &&
           full_.DropSubtree(full_roots_.mutable_roots(), bits, prefix, slot);
  }

  void Save(ByteWriter* w) const {
    symbols_.Save(symbol_roots_.roots(), w);
    full_.Save(full_roots_.roots(), w);
  }

  Status Load(ByteReader* r, uint64_t /*key_limit: every trie key is a grid hexagon*/) {
    std::vector<typename SymbolTrie::Root> symbols;
    std::vector<typename FullTrie::Root> full;
    GROVE_RETURN_IF_ERROR(LoadRoots(r, symbol_roots_.size(), &symbols, &full));
    symbol_roots_.Replace(std::move(symbols));
    full_roots_.Replace(std::move(full));
    return Status::Ok();
  }

  // Particles `which` as Save() writes them (shared nodes once); LoadMore() appends `count`
  // particles so written.
  void SaveSome(std::span<const uint32_t> which, ByteWriter* w) const {
    symbols_.Save(symbol_roots_.Pick(which), w);
    full_.Save(full_roots_.Pick(which), w);
  }
  Status LoadMore(ByteReader* r, size_t count, uint64_t /*key_limit*/) {
    std::vector<typename SymbolTrie::Root> symbols;
    std::vector<typename FullTrie::Root> full;
    GROVE_RETURN_IF_ERROR(LoadRoots(r, count, &symbols, &full));
    symbol_roots_.Append(symbols);
    full_roots_.Append(full);
    return Status::Ok();
  }

  Status CheckCounts() const {
    GROVE_RETURN_IF_ERROR(symbols_.CheckCounts(symbol_roots_.AllReferences()));
    return full_.CheckCounts(full_roots_.AllReferences());
  }

  MemoryUse memory() const {
    MemoryUse m;
    symbols_.AddMemory(&m);
    full_.AddMemory(&m);
    return m;
  }

 private:
  Status LoadRoots(ByteReader* r, size_t count, std::vector<typename SymbolTrie::Root>* symbols,
                   std::vector<typename FullTrie::Root>* full) {
    const int symbol_count = alphabet_->symbol_count();
    GROVE_RETURN_IF_ERROR(symbols_.Load(
        r, count, 0, [&](uint16_t s) { return s == kEscaped || s < symbol_count; }, symbols));
    if (Status s = full_.Load(r, count, 0, &PlausibleHtc, full); !s.ok()) {
      for (auto* root : *symbols) symbols_.Release(root, 0);
      return s;
    }
    return Status::Ok();
  }

  const Alphabet* alphabet_;
  int layout_height_;
  SymbolTrie symbols_;
  FullTrie full_;
  VersionSet<SymbolTrie> symbol_roots_;
  VersionSet<FullTrie> full_roots_;
};

static_assert(BlockStoringMap<AlphabetHTreeMap<2>> && BlockStoringMap<AlphabetHTreeMap<4>> &&
              BlockStoringMap<AlphabetHTreeMap<6>> && BlockStoringMap<AlphabetHTreeMap<8>>);

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_ALPHABET_HTREE_MAP_H_

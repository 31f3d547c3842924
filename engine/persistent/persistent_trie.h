// PersistentTrie: a persistent trie over integer keys whose versions share nodes (path copying:
// Thrun, Burgard and Fox, "Probabilistic Robotics" §13.8; the geographic H-tree of Garcia Puyol
// et al., "Complexity-reduced FootSLAM", §IV).
//
// A version is a root pointer (nullptr: the empty map) that owns one reference. Copying a
// version is one increment; Update() copies only the nodes on the key's path that other
// versions share and mutates uniquely owned nodes in place (immer's `update() &&`).
// Leaf payloads live inline in the bottom nodes, with a presence mask.
//
// Node layout: every node records its level, counted from the bottom (0: a bottom node holding
// leaves; k > 0: an inner node of kDegree children at level k - 1). Key digit k (digit 0 the
// least significant) picks the child of a level-k node: digit 0 is the key's low
// log2(kBottomDegree) bits, every other digit log2(kDegree) bits. A bottom node wider than an
// inner one (kBottomDegree > kDegree: a sparse map whose keys cluster, such as a walked area)
// stores only its present leaves, in digit order, and comes in a few size classes: it grows into
// the next class when a leaf is added to a full one. A path is then one level shorter and its
// copy counts fewer children, and a sparse block costs one small node instead of an inner node
// and several mostly empty bottom ones. A version is at least
// min_height() levels high and grows by new roots on top when a key does not fit. The levels a
// version lacks stand for the digits of a fill key at those levels: a version h levels high holds
// the keys whose digits at levels h and above are the fill key's, and growing puts the old root
// at the fill key's digit of the new level. A fill key of 0 suits keys that grow from 0 (a
// landmark map with no preset size); FootSLAM's growing grid nests its first grid inside ever
// larger ones, so its fill key holds the position of each grid in the next. Versions of
// different heights share their common subtrees.
//
// Invariants:
//   1. A node's reference count equals the number of parent links plus version roots pointing
//      at it (CheckCounts() walks it), outside an Update() in progress: a copied path keeps one
//      reference of its own until the update ends (see Update()).
//   2. A node reachable from a version is never changed unless its count is 1 and every node on
//      the path to it is uniquely owned by that version.
//   3. A node lives at one position (level and key prefix) only.
//
// Memory: nodes come from NodePools and allocation never throws. An Update() that cannot get a
// node returns false and leaves a version with the same contents (the map is unchanged).
//
// This header declares the class and its node layout; the members are defined by concern in
// persistent_trie_update.h (path copying), _lookup.h (reads of one version), _release.h,
// _distinct.h (walks that visit each shared node once), _blocks.h (key-prefix blocks of every
// version) and _checkpoint.h (Save and Load), which it includes.
//
// Thread safety: distinct versions may be updated, read and released concurrently from distinct
// worker slots, even when they share nodes. One version must not be used by two threads at once.
#ifndef GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_H_
#define GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_H_

#include <array>
#include <atomic>
#include <bit>
#include <cstdint>
#include <cstring>
#include <memory>
#include <new>
#include <span>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include "alloc/cache_line.h"
#include "alloc/check.h"
#include "alloc/node_pool.h"
#include "concurrency/ref_count.h"
#include "engine/io/checkpoint_io.h"
#include "engine/persistent/memory_use.h"

namespace grove {

// The leaves each size class of a trie's bottom nodes holds (see PersistentTrie): nodes of 64,
// 128, 256, ... bytes while they hold fewer than half the digits, then one that holds them all.
// Only one class (every digit) when `wide` is false.
struct TrieBottomClasses {
  int count = 0;
  std::array<int, 8> capacity{};
};
constexpr TrieBottomClasses MakeTrieBottomClasses(size_t leaf_offset, size_t leaf_bytes, int degree,
                                                  bool wide) {
  TrieBottomClasses c;
  for (size_t bytes = 64; wide && c.count < 7; bytes *= 2) {
    if (bytes < leaf_offset + leaf_bytes) continue;
    const int capacity = static_cast<int>((bytes - leaf_offset) / leaf_bytes);
    if (2 * capacity >= degree) break;
    c.capacity[c.count++] = capacity;
  }
  c.capacity[c.count++] = degree;
  return c;
}

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree = kLog2Degree>
class PersistentTrie {
  static_assert(kLog2Degree >= 1 && kLog2Degree <= 8, "degree must be 2 .. 256");
  static_assert(kLog2BottomDegree >= kLog2Degree && kLog2BottomDegree <= 8,
                "a bottom node holds degree .. 256 leaves");
  static_assert(std::is_trivially_copyable_v<Leaf> && std::is_trivially_destructible_v<Leaf>,
                "leaves are copied with memcpy when a bottom node is copied");
  static_assert(alignof(Leaf) <= 16, "nodes are 16-byte aligned");

 public:
  static constexpr int kDegree = 1 << kLog2Degree;
  static constexpr int kBottomDegree = 1 << kLog2BottomDegree;
  // Levels that hold every 64-bit key.
  static constexpr int kMaxHeight = 1 + (64 - kLog2BottomDegree + kLog2Degree - 1) / kLog2Degree;

  struct Node {
    RefCount rc;
    uint8_t level;       // 0: bottom; in the padding after the count
    uint8_t size_class;  // a bottom node's size class; 0 for an inner node
    uint16_t leaves;     // a bottom node's leaves; 0 for an inner node
  };
  using Root = Node*;

  // REQUIRES: 1 <= min_height <= kMaxHeight, slots >= 1 (the worker slots that will use it).
  // The digits of `fill` below min_height are ignored. Load() refuses versions higher than
  // max_height (REQUIRES: min_height <= max_height <= kMaxHeight); Update() grows them as keys
  // need, so a caller whose keys stay below kDegree^max_height keeps every version within it.
  PersistentTrie(int min_height, int slots, uint64_t fill = 0, int max_height = kMaxHeight)
      : height_(min_height),
        max_height_(max_height),
        fill_(SpanBits(min_height) >= 64 ? 0
                                         : fill >> SpanBits(min_height) << SpanBits(min_height)),
        inner_pool_(sizeof(Inner), slots),
        release_scratch_(slots) {
    GROVE_CHECK(min_height >= 1 && min_height <= max_height && max_height <= kMaxHeight);
    for (int c = 0; c < kClasses.count; ++c) {
      bottom_pools_[c] = std::make_unique<NodePool>(BottomBytes(c), slots);
    }
  }
  PersistentTrie(const PersistentTrie&) = delete;
  PersistentTrie& operator=(const PersistentTrie&) = delete;

  // The height of every new version; a version grows above it only for a key that needs it.
  int min_height() const { return height_; }
  // The fill key, its digits below min_height() cleared.
  uint64_t fill() const { return fill_; }
  // Levels of a version: 0 for the empty one.
  static int Height(const Node* root) { return root == nullptr ? 0 : root->level + 1; }
  // Levels a version needs to hold `key` under the fill key `fill`: at least 1 (the levels up to
  // the highest digit where the two differ).
  static int HeightFor(uint64_t key, uint64_t fill = 0) {
    const int bits = std::bit_width(key ^ fill);
    return bits <= kLog2BottomDegree
               ? 1
               : 1 + (bits - kLog2BottomDegree + kLog2Degree - 1) / kLog2Degree;
  }
  // Keys a version of min_height() holds without growing, 2^SpanBits(min_height()) (0 when that
  // does not fit in 64 bits: every key).
  uint64_t key_count() const {
    return SpanBits(height_) >= 64 ? 0 : uint64_t{1} << SpanBits(height_);
  }
  // Bits of the keys a version `height` levels high spans: those of its digits.
  static constexpr int SpanBits(int height) {
    return height == 0 ? 0 : kLog2BottomDegree + kLog2Degree * (height - 1);
  }

  // Returns the leaf stored under `key`, or nullptr. The pointer is valid while the version is.
  const Leaf* Find(const Node* root, uint64_t key) const;

  // Starts loading the node at `depth` (0 = the root) on the path to `key`: its count and the
  // link or leaf Update() will read. The nodes above it should already be cached (an earlier
  // call with a smaller depth), so a caller staggers the depths of several versions to overlap
  // their misses; a depth below the version's bottom loads the bottom node again. A hint only:
  // reads links of the caller's own version. Always inlined: GCC deduces that a call to it has
  // no side effects (a prefetch does not count) and would delete the call.
  [[gnu::always_inline]] void PrefetchPath(const Node* root, uint64_t key, int depth) const;

  // The height of the highest version any Update() or Load() has made (at least min_height()):
  // how deep a path is, for PrefetchPath's callers. Relaxed: a hint.
  int top_height() const { return top_height_.load(std::memory_order_relaxed); }

  // A second reference to the same version: O(1).
  static Node* Share(Node* root) {
    if (root != nullptr) root->rc.Acquire();
    return root;
  }

  // Applies f(Leaf& leaf, bool existed) to the leaf under `key` (value-initialised if it did not
  // exist) in the version *root, which it replaces (the caller's reference moves to the new
  // root). Copies only shared nodes on the path and grows the version when `key` does not fit;
  // O(height). Returns false, without calling f, when a node could not be allocated: *root is
  // then a valid version with the same contents. `holders` > 1: *root and holders - 1 other
  // versions hold this root and will all take this update's result (the caller gives it them);
  // when they are all its references, the root is changed in place as if unique.
  template <typename F>
  [[nodiscard]] bool Update(Node** root, uint64_t key, int slot, F&& f, uint32_t holders = 1);

  // Removes the leaf under `key` from the version *root (nothing when it is absent), copying
  // the shared nodes on its path as Update() does and freeing the nodes left empty (the empty
  // map is nullptr; the version keeps its height otherwise). O(height). Returns false when a
  // node could not be allocated: *root then holds the same contents.
  [[nodiscard]] bool Erase(Node** root, uint64_t key, int slot);

  // Drops one reference to a version, freeing every node no other version reaches. Iterative
  // with an explicit stack: a chain of any length cannot overflow the call stack.
  void Release(Node* root, int slot) {
    if (root != nullptr && root->rc.Release()) FreeDead(root, slot);
  }

  // Release() of every version in `roots` (nullptr entries skipped), with the cache misses of
  // many nodes overlapped: a node's count is dropped kInFlight drops after it was queued and
  // prefetched, and a dead inner node's links are read kInFlight dead nodes after its lines
  // were prefetched. With more than one worker slot, drops of one node close together are
  // summed first in a small direct-mapped table and applied as one subtraction: the children of
  // a dead path's nodes are shared by most particles, and on more than one core each separate
  // drop moves the count's line between the cores. Frees the same nodes as Release() one by one;
  // only the order differs. If its queues cannot grow (out of memory) it finishes the work with
  // Release()'s stack.
  void ReleaseMany(std::span<Node* const> roots, int slot);

  // Calls f(key, const Leaf&) for every leaf of one version in increasing key order.
  template <typename F>
  void ForEach(const Node* root, F&& f) const;

  // Calls f(key, const Leaf&) in increasing key order for the leaves of the bottom nodes of one
  // version that the filter admits: may_contain(lo, hi) is asked for the key range [lo, hi] of
  // each node's subtree (a bottom node's too, but not of its single leaves) and a false prunes
  // it. A range query (a spatial one when keys encode positions) costs the nodes it admits, not
  // the size of the map.
  template <typename P, typename F>
  void ForEachIf(const Node* root, P&& may_contain, F&& f) const;

  // Visits every distinct node reachable from `roots` once, with the summed weight of the roots
  // that reach it, and calls on_leaf(key, const Leaf&, W weight) for each leaf of each distinct
  // bottom node. Cost: the number of distinct nodes, not roots x map size. Returns the number of
  // distinct nodes. Sharing between versions may depend on thread timing (a node can be copied
  // or updated in place), so for sums that are bit-identical at any thread count use an exact W
  // (an integer); the visit order is deterministic given the roots.
  template <typename W, typename F>
  size_t VisitDistinct(std::span<Node* const> roots, std::span<const W> weights, F&& on_leaf) const;

  // A block: the keys whose bits above the lowest `bits` are `prefix` (key >> bits == prefix),
  // in every version. REQUIRES of the block functions below: bits < SpanBits(min_height()) (the
  // block is below every root) and bits on a digit boundary, or within the bottom digit (a block
  // smaller than a bottom node: the leaves of some of its digits).

  // VisitDistinct() of one block of every version. Versions without it count for nothing.
  template <typename W, typename F>
  size_t VisitSubtreeDistinct(std::span<Node* const> roots, std::span<const W> weights, int bits,
                              uint64_t prefix, F&& on_leaf) const;

  // The prefixes of the blocks of `bits` that any version in `roots` holds, in increasing order,
  // each once. Cost: the distinct nodes above the blocks (and the bottom nodes, for blocks
  // within them).
  std::vector<uint64_t> SubtreePrefixes(std::span<Node* const> roots, int bits) const;

  // Removes one block from every version in `roots`, replacing each root. Each distinct node on
  // the paths to it (and each bottom node it is part of) is copied once however many versions
  // share it, so the versions keep their sharing; nodes the removal empties are dropped (a
  // version left empty becomes nullptr); the block's nodes are freed when no other reference
  // remains. Cost: the distinct nodes on the paths, not versions x height. Returns false when a
  // node could not be allocated: every version is then unchanged. REQUIRES: no other thread
  // uses these versions.
  [[nodiscard]] bool DropSubtree(std::span<Node*> roots, int bits, uint64_t prefix, int slot);

  // Number of nodes of one version (shared ones included). For tests and statistics.
  size_t CountNodes(const Node* root) const;

  // The expensive check of invariants 1 and 3 over every version: `roots` must be every root
  // reference into this trie (one entry per reference). Walks each distinct node once and
  // compares its count with its parent links plus roots, each child's level with its parent's,
  // a bottom node's leaf count with its presence bits and its class, and the distinct nodes with
  // the pools' live count (so nothing leaked). For tests and
  // GROVE_EXPENSIVE_CHECKS builds; returns Internal naming the first broken rule.
  Status CheckCounts(std::span<Node* const> roots) const;

  // Writes the distinct nodes reachable from `roots`, each once and children before parents,
  // then the roots as node indices: Load() rebuilds the same sharing, so the size follows the
  // distinct nodes, not roots x map size. Levels are written from the top of the highest root
  // H: u32 H, then per node u8 (H - 1 - level), the presence words (of kDegree or kBottomDegree
  // bits), then a u32 child index (inner) or the leaf bytes (bottom) for each present digit.
  void Save(std::span<Node* const> roots, ByteWriter* w) const;

  // Rebuilds versions written by Save(): appends `root_count` roots to `roots`, each owning
  // one reference. valid_leaf(const Leaf&) rejects leaves the caller's model cannot hold.
  // Every structural rule is checked (levels, child indices before parents and one level down,
  // every node referenced, roots at least min_height() high, presence bits within the degree);
  // on error nothing stays allocated and `roots` is unchanged. Nodes come from `slot`'s pools.
  template <typename V>
  Status Load(ByteReader* r, size_t root_count, int slot, V&& valid_leaf,
              std::vector<Node*>* roots);

  // Adds the nodes and bytes of the trie's pools to *m.
  void AddMemory(MemoryUse* m) const {
    AddPoolStats(inner_pool_.Stats(), m);
    for (int c = 0; c < kClasses.count; ++c) AddPoolStats(bottom_pools_[c]->Stats(), m);
  }
  int64_t live_nodes() const {
    MemoryUse m;
    AddMemory(&m);
    return m.live_nodes;
  }

 private:
  struct Inner : Node {
    Node* child[kDegree];
  };
  static constexpr int kWords = (kDegree + 63) / 64;              // presence words of a node
  static constexpr int kBottomWords = (kBottomDegree + 63) / 64;  // of a bottom node
  // A bottom node: the presence words, then (at kLeafOffset) the leaves, kBottomDegree of them
  // indexed by digit, or (kPacked) as many as the size class holds, the present ones in digit
  // order.
  struct Bottom : Node {
    uint64_t present[kBottomWords];
  };
  static constexpr size_t kLeafOffset =
      (sizeof(Bottom) + alignof(Leaf) - 1) / alignof(Leaf) * alignof(Leaf);
  static constexpr TrieBottomClasses kClasses = MakeTrieBottomClasses(
      kLeafOffset, sizeof(Leaf), kBottomDegree, kLog2BottomDegree > kLog2Degree);
  static constexpr bool kPacked = kClasses.count > 1;

 public:
  static constexpr size_t kInnerNodeBytes = sizeof(Inner);
  // Bytes of a bottom node of size class c (a node that holds every digit: the last class).
  static constexpr size_t BottomBytes(int c) {
    return kLeafOffset + static_cast<size_t>(kClasses.capacity[c]) * sizeof(Leaf);
  }
  // Bytes of the smallest bottom node that holds `leaves` leaves.
  static constexpr size_t BottomBytesFor(int leaves) { return BottomBytes(ClassFor(leaves)); }

 private:
  static constexpr int ClassFor(int leaves) {
    int c = 0;
    while (kClasses.capacity[c] < leaves) ++c;
    return c;
  }
  static Leaf* Leaves(Bottom* b) {
    return reinterpret_cast<Leaf*>(reinterpret_cast<char*>(b) + kLeafOffset);
  }
  static const Leaf* Leaves(const Bottom* b) {
    return reinterpret_cast<const Leaf*>(reinterpret_cast<const char*>(b) + kLeafOffset);
  }
  static bool Has(const Bottom* b, int d) { return (b->present[d >> 6] >> (d & 63)) & 1; }
  // std::popcount without a call: baseline x86-64 has no POPCNT instruction, and GCC then calls
  // libgcc's __popcountdi2 (4.4 % of the 1-thread paper walk's samples when SlotOf used it).
  static int PopCount(uint64_t x) {
#if defined(__POPCNT__) || !(defined(__x86_64__) || defined(__i386__))
    return std::popcount(x);
#else
    x -= (x >> 1) & 0x5555555555555555u;
    x = (x & 0x3333333333333333u) + ((x >> 2) & 0x3333333333333333u);
    x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fu;
    return static_cast<int>((x * 0x0101010101010101u) >> 56);
#endif
  }
  // Where digit d's leaf sits: at d, or (kPacked) after the leaves of the present digits below d.
  static int SlotOf(const Bottom* b, int d) {
    if constexpr (!kPacked) return d;
    int rank = 0;
    for (int w = 0; w < (d >> 6); ++w) rank += PopCount(b->present[w]);
    return rank + PopCount(b->present[d >> 6] & ((uint64_t{1} << (d & 63)) - 1));
  }
  // Calls f(digit, const Leaf&) for each leaf of b in digit order.
  template <typename F>
  static void ForEachLeaf(const Bottom* b, F&& f) {
    const Leaf* leaf = Leaves(b);
    int at = 0;
    for (int w = 0; w < kBottomWords; ++w) {
      for (uint64_t bits = b->present[w]; bits != 0; bits &= bits - 1) {
        const int d = w * 64 + std::countr_zero(bits);
        f(d, leaf[kPacked ? at++ : d]);
      }
    }
  }

  // Digit `level` > 0 of `key`: the child of a level-`level` node.
  static int Digit(uint64_t key, int level) {
    return static_cast<int>((key >> (kLog2Degree * (level - 1) + kLog2BottomDegree)) &
                            (kDegree - 1));
  }
  // Digit 0 of `key`: its leaf in a bottom node.
  static int BottomDigit(uint64_t key) { return static_cast<int>(key & (kBottomDegree - 1)); }
  // Inner digit k of a key prefix (a key shifted right by SpanBits(level) for some level > 0).
  static int PrefixDigit(uint64_t prefix, int k) {
    return static_cast<int>((prefix >> (kLog2Degree * k)) & (kDegree - 1));
  }
  // The digits of the fill key above a version `height` levels high: the key prefix of its root.
  uint64_t FillPrefix(int height) const {
    return SpanBits(height) >= 64 ? 0 : fill_ >> SpanBits(height);
  }

  // A new node, or nullptr when the pool has no memory.
  Inner* NewInner(int slot, int level) {
    void* p = inner_pool_.Allocate(slot);
    if (p == nullptr) return nullptr;
    Inner* n = new (p) Inner;
    n->level = static_cast<uint8_t>(level);
    n->size_class = 0;
    n->leaves = 0;
    std::memset(n->child, 0, sizeof(n->child));
    return n;
  }
  // A new bottom node of size class c (its leaves zeroed unless kPacked: a packed node reads
  // only the leaves it holds). Always inlined: Update() copies a bottom node on most crossings,
  // and GCC otherwise inlines it or not by the size of the file that includes the trie (its
  // inline-unit-growth limit).
  [[gnu::always_inline]] Bottom* NewBottom(int slot, int c) {
    void* p = bottom_pools_[c]->Allocate(slot);
    if (p == nullptr) return nullptr;
    Bottom* b = new (p) Bottom;
    b->level = 0;
    b->size_class = static_cast<uint8_t>(c);
    b->leaves = 0;
    std::memset(b->present, 0, sizeof(b->present));
    if constexpr (!kPacked) {
      std::memset(static_cast<void*>(Leaves(b)), 0, kBottomDegree * sizeof(Leaf));
    }
    return b;
  }
  void FreeNode(Node* n, int slot) {
    if (n->level == 0) {
      const int c = n->size_class;
      static_cast<Bottom*>(n)->~Bottom();
      bottom_pools_[c]->Free(n, slot);
    } else {
      static_cast<Inner*>(n)->~Inner();
      inner_pool_.Free(n, slot);
    }
  }
  // Update() could not get a node for `cur`'s place (the path child of the last copy when
  // `held`, the first node copied, is set; that link is then not counted): counts the link and
  // drops `held`, so the version holds the same contents. Returns false.
  bool Abandon(Node* held, Node* cur, int slot);

  // A count of references to one node, to be dropped together.
  struct Drop {
    Node* node = nullptr;
    uint32_t count = 0;
  };
  // Drops d.count references to d.node, freeing what dies (out of memory in ReleaseMany).
  void DropRefs(Drop d, int slot);

  // Frees `dead` (its count has reached zero) and every node only it reached. Iterative, with a
  // fixed stack: allocates nothing.
  void FreeDead(Node* dead, int slot);

  // VisitDistinct() from `roots` whose key prefixes (the digits above each root) are given.
  template <typename W, typename F>
  size_t VisitDistinctFrom(std::span<Node* const> roots, std::span<const uint64_t> prefixes,
                           std::span<const W> weights, F& on_leaf) const;

  // Adds `n` to an open-addressing set of pointers with room for it; false when present.
  static bool InsertPointer(std::vector<const Node*>* set, const Node* n);

  void RaiseTopHeight(int h) {
    int top = top_height_.load(std::memory_order_relaxed);
    while (h > top && !top_height_.compare_exchange_weak(top, h, std::memory_order_relaxed)) {
    }
  }
  // Where a block (see VisitSubtreeDistinct) lives: the node at `level` with the digits `prefix`
  // above it (key >> SpanBits(level + 1) == prefix), or, for a block within a bottom node, that
  // node (level 0) and the block's digits of it: those d with d >> bits == low.
  struct BlockAt {
    int level;
    uint64_t prefix;
    int bits;
    int low;
  };
  BlockAt Locate(int bits, uint64_t prefix) const;
  // Whether version `root` can hold the node at (level, prefix): the prefix's digits above the
  // version are the fill key's.
  bool HoldsSubtree(const Node* root, int level, uint64_t prefix) const;
  // The node at (level, prefix) of a version, or nullptr.
  Node* SubtreeOf(Node* root, int level, uint64_t prefix) const;
  // The replacement of `n` (a node on the path to the block: above it, or the bottom node it is
  // part of) without the block, as a new reference: `n` itself when the block is not under it,
  // nullptr when nothing else is. Memoised in *replaced, so a node is copied once. Sets *ok =
  // false (and returns nullptr, holding nothing) when out of memory.
  Node* Without(Node* n, const BlockAt& block, int slot,
                std::unordered_map<const Node*, Node*>* replaced, bool* ok);
  // Without() of the bottom node a block within a bottom node is part of.
  Node* BottomWithout(Bottom* old, const BlockAt& block, int slot,
                      std::unordered_map<const Node*, Node*>* replaced, bool* ok);

  int height_;
  int max_height_;
  uint64_t fill_;
  std::atomic<int> top_height_{height_};
  NodePool inner_pool_;
  std::array<std::unique_ptr<NodePool>, kClasses.count> bottom_pools_;
  // ReleaseMany's queues, per worker slot (reused: no allocation per call once grown).
  struct alignas(kFalseSharingBytes) ReleaseScratch {
    std::vector<Drop> drop;
    std::vector<Node*> dead;
  };
  std::vector<ReleaseScratch> release_scratch_;
};

}  // namespace grove

// The members' definitions, by concern.
#include "engine/persistent/persistent_trie_blocks.h"
#include "engine/persistent/persistent_trie_checkpoint.h"
#include "engine/persistent/persistent_trie_distinct.h"
#include "engine/persistent/persistent_trie_lookup.h"
#include "engine/persistent/persistent_trie_release.h"
#include "engine/persistent/persistent_trie_update.h"

#endif  // GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_H_

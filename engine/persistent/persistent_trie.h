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
// Thread safety: distinct versions may be updated, read and released concurrently from distinct
// worker slots, even when they share nodes. One version must not be used by two threads at once.
#ifndef GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_H_
#define GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_H_

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstdint>
#include <cstring>
#include <memory>
#include <new>
#include <span>
#include <string>
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
  const Leaf* Find(const Node* root, uint64_t key) const {
    if (root == nullptr || HeightFor(key, fill_) > Height(root)) return nullptr;
    const Node* cur = root;
    while (cur != nullptr && cur->level > 0) {
      cur = static_cast<const Inner*>(cur)->child[Digit(key, cur->level)];
    }
    if (cur == nullptr) return nullptr;
    const Bottom* b = static_cast<const Bottom*>(cur);
    const int d = BottomDigit(key);
    return Has(b, d) ? &Leaves(b)[SlotOf(b, d)] : nullptr;
  }

  // Starts loading the node at `depth` (0 = the root) on the path to `key`: its count and the
  // link or leaf Update() will read. The nodes above it should already be cached (an earlier
  // call with a smaller depth), so a caller staggers the depths of several versions to overlap
  // their misses; a depth below the version's bottom loads the bottom node again. A hint only:
  // reads links of the caller's own version. Always inlined: GCC deduces that a call to it has
  // no side effects (a prefetch does not count) and would delete the call.
  [[gnu::always_inline]] void PrefetchPath(const Node* root, uint64_t key, int depth) const {
    if (root == nullptr) return;
    // Depth 0 must not read the root's header, the very miss this hint is meant to hide: it
    // guesses the level (top_height(); a wrong guess only loads another line of the root).
    // Deeper calls read it, cached by then, and the levels below follow from it.
    int level = depth == 0 ? top_height() - 1 : root->level;
    const Node* cur = root;
    for (int k = 0; k < depth && level > 0; ++k, --level) {
      cur = static_cast<const Inner*>(cur)->child[Digit(key, level)];
      if (cur == nullptr) return;
    }
    __builtin_prefetch(cur);
    if (level > 0) {
      __builtin_prefetch(&static_cast<const Inner*>(cur)->child[Digit(key, level)]);
    } else if constexpr (kPacked) {
      // Where the leaf sits depends on the presence words not yet loaded: the second line.
      __builtin_prefetch(reinterpret_cast<const char*>(cur) + 64);
    } else {
      __builtin_prefetch(&Leaves(static_cast<const Bottom*>(cur))[BottomDigit(key)]);
    }
  }

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
  [[nodiscard]] bool Update(Node** root, uint64_t key, int slot, F&& f, uint32_t holders = 1) {
    const int need = std::max(height_, HeightFor(key, fill_));
    const Node* owned = nullptr;
    if (holders > 1 && *root != nullptr && Height(*root) >= need &&
        (*root)->rc.count() == holders) {
      // As RefCount::unique(): the other holders' last reads happen before our writes.
      std::atomic_thread_fence(std::memory_order_acquire);
      owned = *root;
    }
    if (*root == nullptr) {
      // An empty version starts at the height the key needs.
    } else {
      while (Height(*root) < need) {  // grow: the old root is the fill digit's child of a new one
        Inner* top = NewInner(slot, Height(*root));
        if (top == nullptr) return false;
        top->child[Digit(fill_, Height(*root))] = *root;
        *root = top;
      }
      RaiseTopHeight(Height(*root));
    }
    if (*root == nullptr && need > height_) RaiseTopHeight(need);
    Node* cur = *root;
    Node** link = root;
    // A copy counts every child but its path child: that one is copied next (what lies below a
    // shared node is shared) and the copy links the new node instead. `held`, the first node
    // copied, keeps the reference our link to it had until the whole path is copied: while it
    // lives, every old node below it on the path lives and, shared by it, is changed in place by
    // no other version.
    Node* held = nullptr;
    for (int level = cur == nullptr ? need - 1 : cur->level; level > 0; --level) {
      int d = Digit(key, level);
      Inner* n;
      if (cur == nullptr) {
        n = NewInner(slot, level);
        if (n == nullptr) return Abandon(held, cur, slot);
      } else if (held == nullptr && (cur == owned || cur->rc.unique())) {
        n = static_cast<Inner*>(cur);
      } else {
        Inner* old = static_cast<Inner*>(cur);
        n = NewInner(slot, level);
        if (n == nullptr) return Abandon(held, cur, slot);
        std::memcpy(n->child, old->child, sizeof(n->child));
        for (int i = 0; i < kDegree; ++i) {
          if (i != d && old->child[i] != nullptr) old->child[i]->rc.Acquire();
        }
        if (held == nullptr) held = old;
      }
      *link = n;
      link = &n->child[d];
      cur = n->child[d];
    }
    const int d = BottomDigit(key);
    Bottom* b;
    bool existed = false;
    if (cur == nullptr) {
      b = NewBottom(slot, 0);
      if (b == nullptr) return Abandon(held, cur, slot);
    } else {
      Bottom* old = static_cast<Bottom*>(cur);
      existed = Has(old, d);
      const bool mine = held == nullptr && (cur == owned || cur->rc.unique());
      const int count = kPacked ? old->leaves : kBottomDegree;
      const int need = count + (kPacked && !existed ? 1 : 0);
      if (mine && need <= kClasses.capacity[old->size_class]) {
        b = old;
      } else {
        // A shared node is copied; a node of ours too small for a new leaf, moved to a larger
        // class (our reference to it dropped: it is freed unless other holders take it).
        b = NewBottom(slot, kPacked ? ClassFor(need) : 0);
        if (b == nullptr) return Abandon(held, cur, slot);
        std::memcpy(b->present, old->present, sizeof(b->present));
        b->leaves = old->leaves;
        std::memcpy(static_cast<void*>(Leaves(b)), Leaves(old), count * sizeof(Leaf));
        if (mine) {
          Release(old, slot);
        } else if (held == nullptr) {
          held = old;
        }
      }
    }
    Release(held, slot);
    Leaf* leaf = Leaves(b);
    const int at = SlotOf(b, d);
    if (!existed) {
      if constexpr (kPacked) {
        std::memmove(static_cast<void*>(leaf + at + 1), leaf + at, (b->leaves - at) * sizeof(Leaf));
      }
      leaf[at] = Leaf{};
      b->present[d >> 6] |= uint64_t{1} << (d & 63);
      ++b->leaves;
    }
    f(leaf[at], existed);
    *link = b;
    return true;
  }

  // Removes the leaf under `key` from the version *root (nothing when it is absent), copying
  // the shared nodes on its path as Update() does and freeing the nodes left empty (the empty
  // map is nullptr; the version keeps its height otherwise). O(height). Returns false when a
  // node could not be allocated: *root then holds the same contents.
  [[nodiscard]] bool Erase(Node** root, uint64_t key, int slot) {
    if (Find(*root, key) == nullptr) return true;
    if (!Update(root, key, slot, [](Leaf&, bool) {})) return false;  // the path is now ours
    std::array<Node**, kMaxHeight> links;
    int depth = 0;
    Node** link = root;
    while ((*link)->level > 0) {
      links[depth++] = link;
      link = &static_cast<Inner*>(*link)->child[Digit(key, (*link)->level)];
    }
    Bottom* b = static_cast<Bottom*>(*link);
    const int d = BottomDigit(key);
    if constexpr (kPacked) {
      Leaf* leaf = Leaves(b);
      const int at = SlotOf(b, d);
      std::memmove(static_cast<void*>(leaf + at), leaf + at + 1,
                   (b->leaves - at - 1) * sizeof(Leaf));
    }
    b->present[d >> 6] &= ~(uint64_t{1} << (d & 63));
    if (--b->leaves != 0) return true;
    FreeNode(b, slot);
    *link = nullptr;
    while (depth > 0) {  // free the inner nodes the removal emptied, bottom up
      Node** up = links[--depth];
      Inner* n = static_cast<Inner*>(*up);
      for (Node* c : n->child) {
        if (c != nullptr) return true;
      }
      FreeNode(n, slot);
      *up = nullptr;
    }
    return true;
  }

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
  void ReleaseMany(std::span<Node* const> roots, int slot) {
    constexpr size_t kInFlight = 16;
    constexpr int kTableBits = 8;
    // FIFOs: drops of counts to apply, and dead inner nodes to expand and free.
    std::vector<Drop>& drop = release_scratch_[slot].drop;
    std::vector<Node*>& dead = release_scratch_[slot].dead;
    drop.clear();
    dead.clear();
    std::array<Drop, size_t{1} << kTableBits> table{};
    size_t drop_head = 0, dead_head = 0, next = 0, held = 0;
    auto push = [&](Drop d) {
      __builtin_prefetch(d.node, 1);
      try {
        drop.push_back(d);
      } catch (const std::bad_alloc&) {
        DropRefs(d, slot);
      }
    };
    // One core has no lines to share: there the table costs more than the atomics it saves.
    const bool coalesce = release_scratch_.size() > 1;
    auto queue = [&](Node* n) {
      if (!coalesce) {
        push(Drop{n, 1});
        return;
      }
      Drop& e = table[(reinterpret_cast<uintptr_t>(n) >> 6) & ((size_t{1} << kTableBits) - 1)];
      if (e.node == n) {
        ++e.count;
        return;
      }
      if (e.node != nullptr) {
        push(e);
      } else {
        ++held;
      }
      e = Drop{n, 1};
    };
    for (;;) {
      while (drop.size() - drop_head < kInFlight && next < roots.size()) {
        if (roots[next] != nullptr) push(Drop{roots[next], 1});
        ++next;
      }
      if (drop_head < drop.size()) {
        const Drop d = drop[drop_head++];
        if (drop_head == drop.size()) {
          drop.clear();
          drop_head = 0;
        }
        if (d.node->rc.Release(d.count)) {
          if (d.node->level > 0) {
            const char* p = reinterpret_cast<const char*>(d.node);
            for (size_t off = 0; off < sizeof(Inner); off += 64) __builtin_prefetch(p + off);
            try {
              dead.push_back(d.node);
            } catch (const std::bad_alloc&) {
              FreeDead(d.node, slot);
            }
          } else {
            FreeNode(d.node, slot);
          }
        }
      }
      if (dead_head < dead.size() &&
          (dead.size() - dead_head >= kInFlight || drop_head == drop.size())) {
        Inner* n = static_cast<Inner*>(dead[dead_head++]);
        if (dead_head == dead.size()) {
          dead.clear();
          dead_head = 0;
        }
        for (int i = 0; i < kDegree; ++i) {
          if (n->child[i] != nullptr) queue(n->child[i]);
        }
        FreeNode(n, slot);
      }
      if (drop_head == drop.size() && dead_head == dead.size() && next == roots.size()) {
        if (held == 0) break;
        for (Drop& e : table) {  // the summed drops left in the table
          if (e.node != nullptr) push(e);
          e = Drop{};
        }
        held = 0;
      }
    }
    inner_pool_.Flush(slot);
    for (int c = 0; c < kClasses.count; ++c) bottom_pools_[c]->Flush(slot);
  }

  // Calls f(key, const Leaf&) for every leaf of one version in increasing key order.
  template <typename F>
  void ForEach(const Node* root, F&& f) const {
    if (root == nullptr) return;
    struct Item {
      const Node* node;
      uint64_t prefix;
    };
    std::vector<Item> stack;
    stack.push_back({root, FillPrefix(Height(root))});
    while (!stack.empty()) {
      Item item = stack.back();
      stack.pop_back();
      if (item.node->level > 0) {
        const Inner* n = static_cast<const Inner*>(item.node);
        for (int i = kDegree - 1; i >= 0; --i) {  // pushed in reverse: popped in key order
          if (n->child[i] != nullptr) {
            stack.push_back({n->child[i], (item.prefix << kLog2Degree) | i});
          }
        }
      } else {
        ForEachLeaf(static_cast<const Bottom*>(item.node), [&](int d, const Leaf& leaf) {
          f((item.prefix << kLog2BottomDegree) | d, leaf);
        });
      }
    }
  }

  // Calls f(key, const Leaf&) in increasing key order for the leaves of the bottom nodes of one
  // version that the filter admits: may_contain(lo, hi) is asked for the key range [lo, hi] of
  // each node's subtree (a bottom node's too, but not of its single leaves) and a false prunes
  // it. A range query (a spatial one when keys encode positions) costs the nodes it admits, not
  // the size of the map.
  template <typename P, typename F>
  void ForEachIf(const Node* root, P&& may_contain, F&& f) const {
    if (root == nullptr) return;
    struct Item {
      const Node* node;
      uint64_t prefix;
    };
    std::array<Item, (kDegree - 1) * kMaxHeight + 1> stack;
    int top = 0;
    auto admits = [&](uint64_t prefix, int height) {
      const int shift = SpanBits(height);
      const uint64_t lo = shift >= 64 ? 0 : prefix << shift;
      const uint64_t span = shift >= 64 ? ~uint64_t{0} : (uint64_t{1} << shift) - 1;
      return may_contain(lo, lo + span);
    };
    const uint64_t root_prefix = FillPrefix(Height(root));
    if (!admits(root_prefix, Height(root))) return;
    stack[top++] = {root, root_prefix};
    while (top > 0) {
      const Item item = stack[--top];
      if (item.node->level > 0) {
        const Inner* n = static_cast<const Inner*>(item.node);
        for (int i = kDegree - 1; i >= 0; --i) {  // pushed in reverse: popped in key order
          const uint64_t prefix = (item.prefix << kLog2Degree) | i;
          if (n->child[i] != nullptr && admits(prefix, item.node->level)) {
            stack[top++] = {n->child[i], prefix};
          }
        }
      } else {
        ForEachLeaf(static_cast<const Bottom*>(item.node), [&](int d, const Leaf& leaf) {
          f((item.prefix << kLog2BottomDegree) | d, leaf);
        });
      }
    }
  }

  // Visits every distinct node reachable from `roots` once, with the summed weight of the roots
  // that reach it, and calls on_leaf(key, const Leaf&, W weight) for each leaf of each distinct
  // bottom node. Cost: the number of distinct nodes, not roots x map size. Returns the number of
  // distinct nodes. Sharing between versions may depend on thread timing (a node can be copied
  // or updated in place), so for sums that are bit-identical at any thread count use an exact W
  // (an integer); the visit order is deterministic given the roots.
  template <typename W, typename F>
  size_t VisitDistinct(std::span<Node* const> roots, std::span<const W> weights,
                       F&& on_leaf) const {
    GROVE_CHECK(roots.size() == weights.size());
    std::vector<uint64_t> prefixes(roots.size());
    for (size_t i = 0; i < roots.size(); ++i) prefixes[i] = FillPrefix(Height(roots[i]));
    return VisitDistinctFrom<W>(roots, prefixes, weights, on_leaf);
  }

  // A block: the keys whose bits above the lowest `bits` are `prefix` (key >> bits == prefix),
  // in every version. REQUIRES of the block functions below: bits < SpanBits(min_height()) (the
  // block is below every root) and bits on a digit boundary, or within the bottom digit (a block
  // smaller than a bottom node: the leaves of some of its digits).

  // VisitDistinct() of one block of every version. Versions without it count for nothing.
  template <typename W, typename F>
  size_t VisitSubtreeDistinct(std::span<Node* const> roots, std::span<const W> weights, int bits,
                              uint64_t prefix, F&& on_leaf) const {
    GROVE_CHECK(roots.size() == weights.size());
    const BlockAt block = Locate(bits, prefix);
    std::vector<Node*> nodes;
    std::vector<uint64_t> prefixes;
    std::vector<W> node_weights;
    for (size_t i = 0; i < roots.size(); ++i) {
      Node* node = SubtreeOf(roots[i], block.level, block.prefix);
      if (node == nullptr) continue;
      nodes.push_back(node);
      prefixes.push_back(block.prefix);
      node_weights.push_back(weights[i]);
    }
    if (bits >= kLog2BottomDegree) {
      return VisitDistinctFrom<W>(nodes, prefixes, node_weights, on_leaf);
    }
    auto in_block = [&](uint64_t key, const Leaf& leaf, W w) {
      if ((key >> bits) == prefix) on_leaf(key, leaf, w);
    };
    return VisitDistinctFrom<W>(nodes, prefixes, node_weights, in_block);
  }

  // The prefixes of the blocks of `bits` that any version in `roots` holds, in increasing order,
  // each once. Cost: the distinct nodes above the blocks (and the bottom nodes, for blocks
  // within them).
  std::vector<uint64_t> SubtreePrefixes(std::span<Node* const> roots, int bits) const {
    const BlockAt block = Locate(bits, 0);
    const bool within = bits < kLog2BottomDegree;
    // The nodes visited: an open-addressing set (power-of-two capacity, at most half full), no
    // allocation per node.
    std::vector<const Node*> seen(64, nullptr);
    size_t seen_count = 0;
    auto first_visit = [&](const Node* n) {
      if ((seen_count + 1) * 2 > seen.size()) {
        std::vector<const Node*> bigger(2 * seen.size(), nullptr);
        for (const Node* m : seen) {
          if (m != nullptr) InsertPointer(&bigger, m);
        }
        seen.swap(bigger);
      }
      const bool added = InsertPointer(&seen, n);
      seen_count += added ? 1 : 0;
      return added;
    };
    struct Item {
      const Inner* node;
      uint64_t prefix;
    };
    std::vector<Item> stack;
    std::vector<uint64_t> out;
    // A node at the blocks' level (prefix: the digits above it) or above it.
    auto reach = [&](const Node* n, uint64_t prefix) {
      if (n->level > block.level) {
        if (first_visit(n)) stack.push_back({static_cast<const Inner*>(n), prefix});
      } else if (!within) {
        out.push_back(prefix);
      } else if (first_visit(n)) {
        ForEachLeaf(static_cast<const Bottom*>(n), [&](int d, const Leaf&) {
          out.push_back((prefix << (kLog2BottomDegree - bits)) | static_cast<uint64_t>(d >> bits));
        });
      }
    };
    for (const Node* root : roots) {
      if (root != nullptr) reach(root, FillPrefix(Height(root)));
    }
    while (!stack.empty()) {
      const Item item = stack.back();
      stack.pop_back();
      for (int i = 0; i < kDegree; ++i) {
        const Node* child = item.node->child[i];
        if (child != nullptr) reach(child, (item.prefix << kLog2Degree) | static_cast<uint64_t>(i));
      }
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  // Removes one block from every version in `roots`, replacing each root. Each distinct node on
  // the paths to it (and each bottom node it is part of) is copied once however many versions
  // share it, so the versions keep their sharing; nodes the removal empties are dropped (a
  // version left empty becomes nullptr); the block's nodes are freed when no other reference
  // remains. Cost: the distinct nodes on the paths, not versions x height. Returns false when a
  // node could not be allocated: every version is then unchanged. REQUIRES: no other thread
  // uses these versions.
  [[nodiscard]] bool DropSubtree(std::span<Node*> roots, int bits, uint64_t prefix, int slot) {
    const BlockAt block = Locate(bits, prefix);
    std::unordered_map<const Node*, Node*> replaced;  // old node: its copy (itself if unchanged)
    std::vector<Node*> next(roots.size(), nullptr);
    bool ok = true;
    for (size_t i = 0; i < roots.size() && ok; ++i) {
      Node* root = roots[i];
      if (root == nullptr || !HoldsSubtree(root, block.level, block.prefix)) {
        next[i] = Share(root);
      } else {
        next[i] = Without(root, block, slot, &replaced, &ok);
      }
    }
    if (!ok) {
      for (Node* n : next) Release(n, slot);
      return false;
    }
    for (size_t i = 0; i < roots.size(); ++i) {
      Release(roots[i], slot);
      roots[i] = next[i];
    }
    return true;
  }

  // Number of nodes of one version (shared ones included). For tests and statistics.
  size_t CountNodes(const Node* root) const {
    size_t count = 0;
    if (root == nullptr) return 0;
    std::vector<const Node*> stack{root};
    while (!stack.empty()) {
      const Node* n = stack.back();
      stack.pop_back();
      ++count;
      if (n->level > 0) {
        for (const Node* c : static_cast<const Inner*>(n)->child) {
          if (c != nullptr) stack.push_back(c);
        }
      }
    }
    return count;
  }

  // The expensive check of invariants 1 and 3 over every version: `roots` must be every root
  // reference into this trie (one entry per reference). Walks each distinct node once and
  // compares its count with its parent links plus roots, each child's level with its parent's,
  // a bottom node's leaf count with its presence bits and its class, and the distinct nodes with
  // the pools' live count (so nothing leaked). For tests and
  // GROVE_EXPENSIVE_CHECKS builds; returns Internal naming the first broken rule.
  Status CheckCounts(std::span<Node* const> roots) const {
    std::unordered_map<const Node*, uint32_t> links;
    std::vector<const Node*> stack;
    for (const Node* r : roots) {
      if (r == nullptr) continue;
      if (links[r]++ == 0) stack.push_back(r);
    }
    while (!stack.empty()) {
      const Node* n = stack.back();
      stack.pop_back();
      if (n->level == 0) {
        const Bottom* b = static_cast<const Bottom*>(n);
        int present = 0;
        for (uint64_t word : b->present) present += PopCount(word);
        if (present != b->leaves || b->leaves > kClasses.capacity[b->size_class]) {
          return InternalError("trie: a bottom node's leaf count is not its presence bits");
        }
        continue;
      }
      for (const Node* c : static_cast<const Inner*>(n)->child) {
        if (c == nullptr) continue;
        if (c->level + 1 != n->level) return InternalError("trie: a child is not one level down");
        if (links[c]++ == 0) stack.push_back(c);
      }
    }
    for (const auto& [node, count] : links) {
      if (node->rc.count() != count) {
        return InternalError("trie: a node's count " + std::to_string(node->rc.count()) +
                             " is not its " + std::to_string(count) + " links and roots");
      }
    }
    if (static_cast<int64_t>(links.size()) != live_nodes()) {
      return InternalError("trie: " + std::to_string(live_nodes()) + " live nodes, " +
                           std::to_string(links.size()) + " reachable");
    }
    return Status::Ok();
  }

  // Writes the distinct nodes reachable from `roots`, each once and children before parents,
  // then the roots as node indices: Load() rebuilds the same sharing, so the size follows the
  // distinct nodes, not roots x map size. Levels are written from the top of the highest root
  // H: u32 H, then per node u8 (H - 1 - level), the presence words (of kDegree or kBottomDegree
  // bits), then a u32 child index (inner) or the leaf bytes (bottom) for each present digit.
  void Save(std::span<Node* const> roots, ByteWriter* w) const {
    std::unordered_map<const Node*, uint32_t> index;
    int top = height_;
    for (const Node* r : roots) top = std::max(top, Height(r));
    w->Put<uint32_t>(static_cast<uint32_t>(top));
    const size_t count_at = w->Reserve<uint64_t>();
    struct Frame {
      const Node* node;
      int next;  // the next child digit to visit
    };
    std::vector<Frame> stack;
    for (const Node* root : roots) {
      if (root == nullptr || index.count(root) != 0) continue;
      stack.push_back({root, 0});
      while (!stack.empty()) {
        Frame& f = stack.back();
        if (f.node->level > 0) {
          const Inner* n = static_cast<const Inner*>(f.node);
          while (f.next < kDegree &&
                 (n->child[f.next] == nullptr || index.count(n->child[f.next]) != 0)) {
            ++f.next;
          }
          if (f.next < kDegree) {
            stack.push_back({n->child[f.next], 0});  // invalidates f
            continue;
          }
        }
        Frame done = f;
        stack.pop_back();
        index.emplace(done.node, static_cast<uint32_t>(index.size()));
        w->Put<uint8_t>(static_cast<uint8_t>(top - 1 - done.node->level));
        if (done.node->level > 0) {
          const Inner* n = static_cast<const Inner*>(done.node);
          uint64_t present[kWords] = {};
          for (int d = 0; d < kDegree; ++d) {
            if (n->child[d] != nullptr) present[d >> 6] |= uint64_t{1} << (d & 63);
          }
          w->PutBytes(present, sizeof(present));
          for (int d = 0; d < kDegree; ++d) {
            if (n->child[d] != nullptr) w->Put<uint32_t>(index.at(n->child[d]));
          }
        } else {
          const Bottom* b = static_cast<const Bottom*>(done.node);
          w->PutBytes(b->present, sizeof(b->present));
          ForEachLeaf(b, [&](int, const Leaf& leaf) { w->Put(leaf); });
        }
      }
    }
    w->Patch<uint64_t>(count_at, index.size());
    w->Put<uint64_t>(roots.size());
    for (const Node* root : roots) w->Put<uint32_t>(root == nullptr ? 0 : index.at(root) + 1);
  }

  // Rebuilds versions written by Save(): appends `root_count` roots to `roots`, each owning
  // one reference. valid_leaf(const Leaf&) rejects leaves the caller's model cannot hold.
  // Every structural rule is checked (levels, child indices before parents and one level down,
  // every node referenced, roots at least min_height() high, presence bits within the degree);
  // on error nothing stays allocated and `roots` is unchanged. Nodes come from `slot`'s pools.
  template <typename V>
  Status Load(ByteReader* r, size_t root_count, int slot, V&& valid_leaf,
              std::vector<Node*>* roots) {
    uint32_t top = 0;
    GROVE_RETURN_IF_ERROR(r->Get("trie height", &top));
    if (top < static_cast<uint32_t>(height_) || top > static_cast<uint32_t>(max_height_)) {
      return r->Error("trie height", std::to_string(top) + " is not in " + std::to_string(height_) +
                                         ".." + std::to_string(max_height_) +
                                         " (this configuration's heights)");
    }
    uint64_t count = 0;
    GROVE_RETURN_IF_ERROR(r->GetCount("trie node count", 1 + sizeof(uint64_t) * kWords, &count));
    if (count >= UINT32_MAX) return r->Error("trie node count", "too large");
    std::vector<Node*> nodes;
    std::vector<uint32_t> refs;
    nodes.reserve(count);
    refs.reserve(count);
    auto fail = [&](Status s) {
      for (Node* n : nodes) FreeNode(n, slot);
      return s;
    };
    for (uint64_t k = 0; k < count; ++k) {
      uint8_t depth = 0;
      uint64_t present[kBottomWords];
      Status s = r->Get("trie node level", &depth);
      if (s.ok() && depth >= top) {
        s = r->Error("trie node level",
                     std::to_string(depth) + " is not below the height " + std::to_string(top));
      }
      if (!s.ok()) return fail(s);
      const int level = static_cast<int>(top) - 1 - depth;
      const int degree = level > 0 ? kDegree : kBottomDegree;
      const int words = (degree + 63) / 64;
      s = r->GetBytes("trie node presence", present, words * sizeof(uint64_t));
      if (s.ok() && degree % 64 != 0 && (present[words - 1] >> (degree % 64)) != 0) {
        s = r->Error("trie node presence", "a digit beyond the degree is marked present");
      }
      if (!s.ok()) return fail(s);
      auto has = [&](int d) { return (present[d >> 6] >> (d & 63)) & 1; };
      if (level > 0) {
        Inner* n = NewInner(slot, level);
        if (n == nullptr) return fail(ResourceExhaustedError("out of memory loading a trie"));
        nodes.push_back(n);
        refs.push_back(0);
        for (int d = 0; d < kDegree; ++d) {
          if (!has(d)) continue;
          uint32_t c = 0;
          s = r->Get("trie child index", &c);
          if (s.ok() && (c >= k || nodes[c]->level + 1 != level)) {
            s = r->Error("trie child index",
                         std::to_string(c) + " is not an earlier node one level down");
          }
          if (!s.ok()) return fail(s);
          n->child[d] = nodes[c];
          ++refs[c];
        }
      } else {
        int leaves = 0;
        for (uint64_t word : present) leaves += PopCount(word);
        Bottom* b = NewBottom(slot, kPacked ? ClassFor(leaves) : 0);
        if (b == nullptr) return fail(ResourceExhaustedError("out of memory loading a trie"));
        nodes.push_back(b);
        refs.push_back(0);
        std::memcpy(b->present, present, sizeof(present));
        b->leaves = static_cast<uint16_t>(leaves);
        Leaf* leaf = Leaves(b);
        for (int d = 0, at = 0; d < kBottomDegree; ++d) {
          if (!has(d)) continue;
          Leaf* to = &leaf[kPacked ? at++ : d];
          s = r->GetBytes("trie leaf", to, sizeof(Leaf));
          if (s.ok() && !valid_leaf(*to)) s = r->Error("trie leaf", "impossible value");
          if (!s.ok()) return fail(s);
        }
      }
    }
    uint64_t saved_roots = 0;
    Status s = r->Get("trie root count", &saved_roots);
    if (s.ok() && saved_roots != root_count) {
      s = r->Error("trie root count",
                   std::to_string(saved_roots) + " roots, expected " + std::to_string(root_count));
    }
    if (!s.ok()) return fail(s);
    // Invariant 1: a node's count is its parent links plus the roots reaching it.
    s = LinkRoots(
        r, "trie root", root_count, nodes, &refs,
        [&](size_t k) { return nodes[k]->level + 1 >= height_; }, roots);
    if (!s.ok()) return fail(s);
    for (const Node* root : *roots) RaiseTopHeight(Height(root));
    return s;
  }

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
  // only the leaves it holds).
  Bottom* NewBottom(int slot, int c) {
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
  bool Abandon(Node* held, Node* cur, int slot) {
    if (held != nullptr) {
      if (cur != nullptr) cur->rc.Acquire();
      Release(held, slot);
    }
    return false;
  }

  // A count of references to one node, to be dropped together.
  struct Drop {
    Node* node = nullptr;
    uint32_t count = 0;
  };
  // Drops d.count references to d.node, freeing what dies (out of memory in ReleaseMany).
  void DropRefs(Drop d, int slot) {
    if (d.node->rc.Release(d.count)) FreeDead(d.node, slot);
  }

  // Frees `dead` (its count has reached zero) and every node only it reached. Iterative, with a
  // fixed stack: allocates nothing.
  void FreeDead(Node* dead, int slot) {
    std::array<Node*, (kDegree - 1) * kMaxHeight + 1> stack;
    int top = 0;
    stack[top++] = dead;
    while (top > 0) {
      Node* n = stack[--top];
      if (n->level > 0) {
        for (Node* c : static_cast<Inner*>(n)->child) {
          if (c != nullptr && c->rc.Release()) stack[top++] = c;
        }
      }
      FreeNode(n, slot);
    }
  }

  // VisitDistinct() from `roots` whose key prefixes (the digits above each root) are given.
  template <typename W, typename F>
  size_t VisitDistinctFrom(std::span<Node* const> roots, std::span<const uint64_t> prefixes,
                           std::span<const W> weights, F& on_leaf) const {
    // Level by level from the highest root down; a root joins at its own level.
    int top = 0;
    for (const Node* r : roots) top = std::max(top, Height(r));
    std::vector<const Node*> level_nodes;
    std::vector<uint64_t> level_prefix;
    std::vector<W> level_weight;
    std::unordered_map<const Node*, size_t> index;
    auto add = [&](const Node* n, uint64_t prefix, W w) {
      auto [it, inserted] = index.try_emplace(n, level_nodes.size());
      if (inserted) {
        level_nodes.push_back(n);
        level_prefix.push_back(prefix);
        level_weight.push_back(w);
      } else {
        level_weight[it->second] += w;
      }
    };
    size_t distinct = 0;
    for (int level = top - 1; level >= 0; --level) {
      std::vector<const Node*> parents;
      std::vector<uint64_t> parent_prefix;
      std::vector<W> parent_weight;
      parents.swap(level_nodes);
      parent_prefix.swap(level_prefix);
      parent_weight.swap(level_weight);
      index.clear();
      for (size_t k = 0; k < parents.size(); ++k) {
        const Inner* n = static_cast<const Inner*>(parents[k]);
        for (int i = 0; i < kDegree; ++i) {
          if (n->child[i] != nullptr) {
            add(n->child[i], (parent_prefix[k] << kLog2Degree) | i, parent_weight[k]);
          }
        }
      }
      for (size_t i = 0; i < roots.size(); ++i) {
        if (Height(roots[i]) == level + 1) add(roots[i], prefixes[i], weights[i]);
      }
      distinct += level_nodes.size();
    }
    for (size_t k = 0; k < level_nodes.size(); ++k) {
      ForEachLeaf(static_cast<const Bottom*>(level_nodes[k]), [&](int d, const Leaf& leaf) {
        on_leaf((level_prefix[k] << kLog2BottomDegree) | d, leaf, level_weight[k]);
      });
    }
    return distinct;
  }

  // Adds `n` to an open-addressing set of pointers with room for it; false when present.
  static bool InsertPointer(std::vector<const Node*>* set, const Node* n) {
    const size_t mask = set->size() - 1;
    size_t i = ((reinterpret_cast<uintptr_t>(n) >> 6) * 0x9E3779B97F4A7C15ull >> 20) & mask;
    for (;; i = (i + 1) & mask) {
      const Node*& slot = (*set)[i];
      if (slot == n) return false;
      if (slot == nullptr) {
        slot = n;
        return true;
      }
    }
  }

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
  BlockAt Locate(int bits, uint64_t prefix) const {
    GROVE_CHECK(bits >= 0 && bits < SpanBits(height_) &&
                (bits < kLog2BottomDegree || (bits - kLog2BottomDegree) % kLog2Degree == 0));
    if (bits >= kLog2BottomDegree) {
      return {(bits - kLog2BottomDegree) / kLog2Degree, prefix, bits, 0};
    }
    const int shift = kLog2BottomDegree - bits;
    return {0, prefix >> shift, bits, static_cast<int>(prefix & ((uint64_t{1} << shift) - 1))};
  }
  // Whether version `root` can hold the node at (level, prefix): the prefix's digits above the
  // version are the fill key's.
  bool HoldsSubtree(const Node* root, int level, uint64_t prefix) const {
    const int shift = SpanBits(level + 1);
    if (shift >= 64) return false;
    const uint64_t low = prefix << shift;
    return (low >> shift) == prefix && HeightFor(low, fill_) <= Height(root);
  }
  // The node at (level, prefix) of a version, or nullptr.
  Node* SubtreeOf(Node* root, int level, uint64_t prefix) const {
    if (root == nullptr || !HoldsSubtree(root, level, prefix)) return nullptr;
    Node* cur = root;
    for (int l = root->level; cur != nullptr && l > level; --l) {
      cur = static_cast<Inner*>(cur)->child[PrefixDigit(prefix, l - level - 1)];
    }
    return cur;
  }
  // The replacement of `n` (a node on the path to the block: above it, or the bottom node it is
  // part of) without the block, as a new reference: `n` itself when the block is not under it,
  // nullptr when nothing else is. Memoised in *replaced, so a node is copied once. Sets *ok =
  // false (and returns nullptr, holding nothing) when out of memory.
  Node* Without(Node* n, const BlockAt& block, int slot,
                std::unordered_map<const Node*, Node*>* replaced, bool* ok) {
    if (auto it = replaced->find(n); it != replaced->end()) {
      if (it->second != nullptr) it->second->rc.Acquire();
      return it->second;
    }
    if (n->level == 0) return BottomWithout(static_cast<Bottom*>(n), block, slot, replaced, ok);
    Inner* old = static_cast<Inner*>(n);
    const int d = PrefixDigit(block.prefix, old->level - block.level - 1);
    Node* child = old->child[d];
    Node* kept = nullptr;  // the replacement of the path child: a reference we own, or nullptr
    if (child != nullptr && (old->level - 1 > block.level || block.bits < kLog2BottomDegree)) {
      kept = Without(child, block, slot, replaced, ok);
      if (!*ok) return nullptr;
    }
    if (child == nullptr || kept == child) {          // the block is not under n: n is unchanged
      if (kept != nullptr) (void)kept->rc.Release();  // n holds it too: never the last one
      n->rc.Acquire();
      replaced->emplace(n, n);
      return n;
    }
    bool empty = kept == nullptr;
    for (int i = 0; i < kDegree && empty; ++i) empty = i == d || old->child[i] == nullptr;
    if (empty) {
      replaced->emplace(n, nullptr);
      return nullptr;
    }
    Inner* copy = NewInner(slot, old->level);
    if (copy == nullptr) {
      Release(kept, slot);
      *ok = false;
      return nullptr;
    }
    for (int i = 0; i < kDegree; ++i) {
      Node* c = i == d ? kept : old->child[i];
      if (i != d && c != nullptr) c->rc.Acquire();
      copy->child[i] = c;
    }
    replaced->emplace(n, copy);
    return copy;
  }
  // Without() of the bottom node a block within a bottom node is part of.
  Node* BottomWithout(Bottom* old, const BlockAt& block, int slot,
                      std::unordered_map<const Node*, Node*>* replaced, bool* ok) {
    uint64_t keep[kBottomWords];
    int kept = 0;
    for (int w = 0; w < kBottomWords; ++w) {
      keep[w] = 0;
      for (uint64_t bits = old->present[w]; bits != 0; bits &= bits - 1) {
        const int d = w * 64 + std::countr_zero(bits);
        if ((d >> block.bits) != block.low) keep[w] |= uint64_t{1} << (d & 63);
      }
      kept += PopCount(keep[w]);
    }
    Node* result = nullptr;
    if (kept == old->leaves) {  // no leaf of the block: unchanged
      old->rc.Acquire();
      result = old;
    } else if (kept > 0) {
      Bottom* copy = NewBottom(slot, kPacked ? ClassFor(kept) : 0);
      if (copy == nullptr) {
        *ok = false;
        return nullptr;
      }
      copy->leaves = static_cast<uint16_t>(kept);
      Leaf* to = Leaves(copy);
      int at = 0;
      ForEachLeaf(old, [&](int d, const Leaf& leaf) {
        if ((keep[d >> 6] >> (d & 63)) & 1) to[kPacked ? at++ : d] = leaf;
      });
      std::memcpy(copy->present, keep, sizeof(keep));
      result = copy;
    }
    replaced->emplace(old, result);
    return result;
  }

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

#endif  // GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_H_

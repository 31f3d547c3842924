// PersistentTrie: a persistent trie over integer keys whose versions share nodes (path copying:
// Thrun, Burgard and Fox, "Probabilistic Robotics" §13.8; the geographic H-tree of Garcia Puyol
// et al., "Complexity-reduced FootSLAM", §IV).
//
// A version is a root pointer (nullptr: the empty map) that owns one reference. Copying a
// version is one increment; Update() copies only the nodes on the key's path that other
// versions share and mutates uniquely owned nodes in place (immer's `update() &&`).
// Leaf payloads live inline in the bottom nodes: kDegree of them per node, with a presence mask.
//
// Node layout: every node records its level, counted from the bottom (0: a bottom node holding
// leaves; k > 0: an inner node of kDegree children at level k - 1). Key digit k (base kDegree,
// digit 0 the least significant) picks the child of a level-k node. A version is at least
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
#ifndef GROVE_ENGINE_PERSISTENT_TRIE_H_
#define GROVE_ENGINE_PERSISTENT_TRIE_H_

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstdint>
#include <cstring>
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
#include "engine/checkpoint_io.h"

namespace grove {

template <typename Leaf, int kLog2Degree>
class PersistentTrie {
  static_assert(kLog2Degree >= 1 && kLog2Degree <= 8, "degree must be 2 .. 256");
  static_assert(std::is_trivially_copyable_v<Leaf> && std::is_trivially_destructible_v<Leaf>,
                "leaves are copied with memcpy when a bottom node is copied");

 public:
  static constexpr int kDegree = 1 << kLog2Degree;
  // Levels that hold every 64-bit key.
  static constexpr int kMaxHeight = (64 + kLog2Degree - 1) / kLog2Degree;

  struct Node {
    RefCount rc;
    uint8_t level;  // 0: bottom; in the padding after the count
  };
  using Root = Node*;

  // REQUIRES: 1 <= min_height <= kMaxHeight, slots >= 1 (the worker slots that will use it).
  // The digits of `fill` below min_height are ignored. Load() refuses versions higher than
  // max_height (REQUIRES: min_height <= max_height <= kMaxHeight); Update() grows them as keys
  // need, so a caller whose keys stay below kDegree^max_height keeps every version within it.
  PersistentTrie(int min_height, int slots, uint64_t fill = 0, int max_height = kMaxHeight)
      : height_(min_height),
        max_height_(max_height),
        fill_(min_height * kLog2Degree >= 64
                  ? 0
                  : fill >> (min_height * kLog2Degree) << (min_height * kLog2Degree)),
        inner_pool_(sizeof(Inner), slots),
        bottom_pool_(sizeof(Bottom), slots),
        release_scratch_(slots) {
    GROVE_CHECK(min_height >= 1 && min_height <= max_height && max_height <= kMaxHeight);
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
    const uint64_t differ = key ^ fill;
    return differ == 0 ? 1 : (std::bit_width(differ) + kLog2Degree - 1) / kLog2Degree;
  }
  // Keys a version of min_height() holds without growing, kDegree^min_height (0 when that does
  // not fit in 64 bits: every key).
  uint64_t key_count() const {
    return height_ * kLog2Degree >= 64 ? 0 : uint64_t{1} << (height_ * kLog2Degree);
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
    int d = Digit(key, 0);
    return b->Has(d) ? &b->leaf[d] : nullptr;
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
    } else {
      __builtin_prefetch(&static_cast<const Bottom*>(cur)->leaf[Digit(key, 0)]);
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
    int d = Digit(key, 0);
    Bottom* b;
    if (cur == nullptr) {
      b = NewBottom(slot);
      if (b == nullptr) return Abandon(held, cur, slot);
    } else if (held == nullptr && (cur == owned || cur->rc.unique())) {
      b = static_cast<Bottom*>(cur);
    } else {
      Bottom* old = static_cast<Bottom*>(cur);
      b = NewBottom(slot);
      if (b == nullptr) return Abandon(held, cur, slot);
      std::memcpy(b->present, old->present, sizeof(b->present));
      std::memcpy(static_cast<void*>(b->leaf), old->leaf, sizeof(b->leaf));
      if (held == nullptr) held = old;
    }
    Release(held, slot);
    bool existed = b->Has(d);
    if (!existed) {
      b->leaf[d] = Leaf{};
      b->present[d >> 6] |= uint64_t{1} << (d & 63);
    }
    f(b->leaf[d], existed);
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
    const int d = Digit(key, 0);
    b->present[d >> 6] &= ~(uint64_t{1} << (d & 63));
    for (uint64_t w : b->present) {
      if (w != 0) return true;
    }
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
    bottom_pool_.Flush(slot);
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
        const Bottom* b = static_cast<const Bottom*>(item.node);
        for (int i = 0; i < kDegree; ++i) {
          if (b->Has(i)) f((item.prefix << kLog2Degree) | i, b->leaf[i]);
        }
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
    auto admits = [&](uint64_t prefix, int level) {
      const int shift = kLog2Degree * level;
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
        const Bottom* b = static_cast<const Bottom*>(item.node);
        for (int i = 0; i < kDegree; ++i) {
          if (b->Has(i)) f((item.prefix << kLog2Degree) | i, b->leaf[i]);
        }
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

  // VisitDistinct() of one subtree of every version: the node at `level` whose keys have the
  // digits `prefix` above it (key >> (log2(degree) * (level + 1)) == prefix). Versions without
  // it count for nothing. REQUIRES: level < min_height() - 1 (the subtree is below every root).
  template <typename W, typename F>
  size_t VisitSubtreeDistinct(std::span<Node* const> roots, std::span<const W> weights, int level,
                              uint64_t prefix, F&& on_leaf) const {
    GROVE_CHECK(roots.size() == weights.size() && level < height_ - 1);
    std::vector<Node*> blocks;
    std::vector<uint64_t> prefixes;
    std::vector<W> block_weights;
    for (size_t i = 0; i < roots.size(); ++i) {
      Node* block = SubtreeOf(roots[i], level, prefix);
      if (block == nullptr) continue;
      blocks.push_back(block);
      prefixes.push_back(prefix);
      block_weights.push_back(weights[i]);
    }
    return VisitDistinctFrom<W>(blocks, prefixes, block_weights, on_leaf);
  }

  // The prefixes (as VisitSubtreeDistinct) of the subtrees at `level` that any version in
  // `roots` holds, in increasing order, each once. Cost: the distinct nodes above `level`.
  // REQUIRES: level < min_height() - 1.
  std::vector<uint64_t> SubtreePrefixes(std::span<Node* const> roots, int level) const {
    GROVE_CHECK(level < height_ - 1);
    struct Item {
      const Inner* node;
      uint64_t prefix;
    };
    std::vector<Item> stack;
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
    for (const Node* root : roots) {
      if (root != nullptr && first_visit(root)) {
        stack.push_back({static_cast<const Inner*>(root), FillPrefix(Height(root))});
      }
    }
    std::vector<uint64_t> out;
    while (!stack.empty()) {
      const Item item = stack.back();
      stack.pop_back();
      for (int i = 0; i < kDegree; ++i) {
        const Node* child = item.node->child[i];
        if (child == nullptr) continue;
        const uint64_t prefix = (item.prefix << kLog2Degree) | static_cast<uint64_t>(i);
        if (child->level == level) {
          out.push_back(prefix);
        } else if (first_visit(child)) {
          stack.push_back({static_cast<const Inner*>(child), prefix});
        }
      }
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  // Removes the subtree at `level` with key digits `prefix` above it (as VisitSubtreeDistinct)
  // from every version in `roots`, replacing each root. Each distinct node on the paths to it is
  // copied once however many versions share it, so the versions keep their sharing; nodes the
  // removal empties are dropped (a version left empty becomes nullptr); the subtree's nodes are
  // freed when no other reference remains. Cost: the distinct nodes on the paths, not versions x
  // height. Returns false when a node could not be allocated: every version is then unchanged.
  // REQUIRES: level < min_height() - 1; no other thread uses these versions.
  [[nodiscard]] bool DropSubtree(std::span<Node*> roots, int level, uint64_t prefix, int slot) {
    GROVE_CHECK(level < height_ - 1);
    std::unordered_map<const Node*, Node*> replaced;  // old node: its copy (itself if unchanged)
    std::vector<Node*> next(roots.size(), nullptr);
    bool ok = true;
    for (size_t i = 0; i < roots.size() && ok; ++i) {
      Node* root = roots[i];
      if (root == nullptr || !HoldsSubtree(root, level, prefix)) {
        next[i] = Share(root);
      } else {
        next[i] = Without(root, level, prefix, slot, &replaced, &ok);
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
  // and the distinct nodes with the pools' live count (so nothing leaked). For tests and
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
      if (n->level == 0) continue;
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
  // H: u32 H, then per node u8 (H - 1 - level), the presence words, then a u32 child index
  // (inner) or the leaf bytes (bottom) for each present digit.
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
          for (int d = 0; d < kDegree; ++d) {
            if (b->Has(d)) w->Put(b->leaf[d]);
          }
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
      uint64_t present[kWords];
      Status s = r->Get("trie node level", &depth);
      if (s.ok() && depth >= top) {
        s = r->Error("trie node level",
                     std::to_string(depth) + " is not below the height " + std::to_string(top));
      }
      if (s.ok()) s = r->GetBytes("trie node presence", present, sizeof(present));
      if (s.ok() && kDegree % 64 != 0 && (present[kWords - 1] >> (kDegree % 64)) != 0) {
        s = r->Error("trie node presence", "a digit beyond the degree is marked present");
      }
      if (!s.ok()) return fail(s);
      const int level = static_cast<int>(top) - 1 - depth;
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
        Bottom* b = NewBottom(slot);
        if (b == nullptr) return fail(ResourceExhaustedError("out of memory loading a trie"));
        nodes.push_back(b);
        refs.push_back(0);
        std::memcpy(b->present, present, sizeof(present));
        for (int d = 0; d < kDegree; ++d) {
          if (!has(d)) continue;
          s = r->GetBytes("trie leaf", &b->leaf[d], sizeof(Leaf));
          if (s.ok() && !valid_leaf(b->leaf[d])) s = r->Error("trie leaf", "impossible value");
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

  PoolStats inner_stats() const { return inner_pool_.Stats(); }
  PoolStats bottom_stats() const { return bottom_pool_.Stats(); }
  int64_t live_nodes() const { return inner_stats().live_nodes + bottom_stats().live_nodes; }
  int64_t live_bytes() const { return inner_stats().live_bytes() + bottom_stats().live_bytes(); }
  static constexpr size_t kInnerNodeBytes = sizeof(Node) + kDegree * sizeof(Node*);
  static constexpr size_t kBottomNodeBytes =
      sizeof(Node) + ((kDegree + 63) / 64) * 8 + kDegree * sizeof(Leaf);

 private:
  struct Inner : Node {
    Node* child[kDegree];
  };
  static constexpr int kWords = (kDegree + 63) / 64;  // presence words of a node
  struct Bottom : Node {
    uint64_t present[kWords];
    Leaf leaf[kDegree];
    bool Has(int d) const { return (present[d >> 6] >> (d & 63)) & 1; }
  };

  // Digit `level` of `key` (0: the least significant): the child of a level-`level` node.
  static int Digit(uint64_t key, int level) {
    return static_cast<int>((key >> (kLog2Degree * level)) & (kDegree - 1));
  }
  // The digits of the fill key above a version `height` levels high: the key prefix of its root.
  uint64_t FillPrefix(int height) const {
    return kLog2Degree * height >= 64 ? 0 : fill_ >> (kLog2Degree * height);
  }

  // A new node, or nullptr when the pool has no memory.
  Inner* NewInner(int slot, int level) {
    void* p = inner_pool_.Allocate(slot);
    if (p == nullptr) return nullptr;
    Inner* n = new (p) Inner;
    n->level = static_cast<uint8_t>(level);
    std::memset(n->child, 0, sizeof(n->child));
    return n;
  }
  Bottom* NewBottom(int slot) {
    void* p = bottom_pool_.Allocate(slot);
    if (p == nullptr) return nullptr;
    Bottom* b = new (p) Bottom;
    b->level = 0;
    std::memset(b->present, 0, sizeof(b->present));
    std::memset(static_cast<void*>(b->leaf), 0, sizeof(b->leaf));
    return b;
  }
  void FreeNode(Node* n, int slot) {
    if (n->level == 0) {
      static_cast<Bottom*>(n)->~Bottom();
      bottom_pool_.Free(n, slot);
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
      const Bottom* b = static_cast<const Bottom*>(level_nodes[k]);
      for (int i = 0; i < kDegree; ++i) {
        if (b->Has(i)) on_leaf((level_prefix[k] << kLog2Degree) | i, b->leaf[i], level_weight[k]);
      }
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
  // Whether version `root` (higher than level + 1) can hold the subtree at (level, prefix): the
  // prefix's digits above the version are the fill key's.
  bool HoldsSubtree(const Node* root, int level, uint64_t prefix) const {
    const int shift = kLog2Degree * (level + 1);
    if (shift >= 64) return false;
    const uint64_t low = prefix << shift;
    return (low >> shift) == prefix && HeightFor(low, fill_) <= Height(root);
  }
  // The node at (level, prefix) of a version, or nullptr.
  Node* SubtreeOf(Node* root, int level, uint64_t prefix) const {
    if (root == nullptr || !HoldsSubtree(root, level, prefix)) return nullptr;
    Node* cur = root;
    for (int l = root->level; cur != nullptr && l > level; --l) {
      cur = static_cast<Inner*>(cur)->child[Digit(prefix, l - level - 1)];
    }
    return cur;
  }
  // The replacement of `n` (an inner node above `level` on the path to the subtree) without the
  // subtree, as a new reference: `n` itself when the subtree is not under it, nullptr when
  // nothing else is. Memoised in *replaced, so a node is copied once. Sets *ok = false (and
  // returns nullptr, holding nothing) when out of memory.
  Node* Without(Node* n, int level, uint64_t prefix, int slot,
                std::unordered_map<const Node*, Node*>* replaced, bool* ok) {
    if (auto it = replaced->find(n); it != replaced->end()) {
      if (it->second != nullptr) it->second->rc.Acquire();
      return it->second;
    }
    Inner* old = static_cast<Inner*>(n);
    const int d = Digit(prefix, old->level - level - 1);
    Node* child = old->child[d];
    Node* kept = nullptr;  // the replacement of the path child: a reference we own, or nullptr
    if (child != nullptr && old->level - 1 > level) {
      kept = Without(child, level, prefix, slot, replaced, ok);
      if (!*ok) return nullptr;
    }
    if (child == nullptr || kept == child) {          // the subtree is not under n: n is unchanged
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

  int height_;
  int max_height_;
  uint64_t fill_;
  std::atomic<int> top_height_{height_};
  NodePool inner_pool_;
  NodePool bottom_pool_;
  // ReleaseMany's queues, per worker slot (reused: no allocation per call once grown).
  struct alignas(kFalseSharingBytes) ReleaseScratch {
    std::vector<Drop> drop;
    std::vector<Node*> dead;
  };
  std::vector<ReleaseScratch> release_scratch_;
};

}  // namespace grove

#endif  // GROVE_ENGINE_PERSISTENT_TRIE_H_

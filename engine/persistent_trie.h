// PersistentTrie: a persistent, fixed-height trie over integer keys whose versions share nodes
// (path copying: Thrun, Burgard and Fox, "Probabilistic Robotics" §13.8; the geographic H-tree of
// Garcia Puyol et al., "Complexity-reduced FootSLAM", §IV).
//
// A version is a root pointer (nullptr: the empty map) that owns one reference. Copying a
// version is one increment; Update() copies only the nodes on the key's path that other
// versions share and mutates uniquely owned nodes in place (immer's `update() &&`).
// Leaf payloads live inline in the bottom nodes: kDegree of them per node, with a presence mask.
//
// Node layout: inner nodes hold kDegree child pointers; bottom nodes (level height - 1) hold the
// leaves. Key digit `level` (base kDegree, most significant first) picks the child at that level.
//
// Invariants:
//   1. A node's reference count equals the number of parent links plus version roots pointing
//      at it.
//   2. A node reachable from a version is never changed unless its count is 1 and every node on
//      the path to it is uniquely owned by that version.
//   3. A node lives at one position (key prefix) only.
//
// Thread safety: distinct versions may be updated, read and released concurrently from distinct
// worker slots, even when they share nodes. One version must not be used by two threads at once.
#ifndef GROVE_ENGINE_PERSISTENT_TRIE_H_
#define GROVE_ENGINE_PERSISTENT_TRIE_H_

#include <array>
#include <cstdint>
#include <cstring>
#include <new>
#include <span>
#include <type_traits>
#include <unordered_map>
#include <vector>

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
  static constexpr int kMaxHeight = 64 / kLog2Degree;

  struct Node {
    RefCount rc;
  };
  using Root = Node*;

  // REQUIRES: 1 <= height <= kMaxHeight, slots >= 1 (the worker slots that will use it).
  PersistentTrie(int height, int slots)
      : height_(height),
        inner_pool_(sizeof(Inner), slots),
        bottom_pool_(sizeof(Bottom), slots),
        release_scratch_(slots) {
    GROVE_CHECK(height >= 1 && height <= kMaxHeight);
  }
  PersistentTrie(const PersistentTrie&) = delete;
  PersistentTrie& operator=(const PersistentTrie&) = delete;

  int height() const { return height_; }
  // Number of distinct keys, kDegree^height (0 when it does not fit in 64 bits: all keys valid).
  uint64_t key_count() const {
    return height_ * kLog2Degree >= 64 ? 0 : uint64_t{1} << (height_ * kLog2Degree);
  }

  // Returns the leaf stored under `key`, or nullptr. The pointer is valid while the version is.
  const Leaf* Find(const Node* root, uint64_t key) const {
    const Node* cur = root;
    for (int level = 0; cur != nullptr && level < height_ - 1; ++level) {
      cur = static_cast<const Inner*>(cur)->child[Digit(key, level)];
    }
    if (cur == nullptr) return nullptr;
    const Bottom* b = static_cast<const Bottom*>(cur);
    int d = Digit(key, height_ - 1);
    return b->Has(d) ? &b->leaf[d] : nullptr;
  }

  // Starts loading the node at `depth` (0 = the root, at most height - 1) on the path to `key`:
  // its count and the link or leaf Update() will read. The nodes above it should already be
  // cached (an earlier call with a smaller depth), so a caller staggers the depths of several
  // versions to overlap their misses. A hint only: reads links of the caller's own version.
  // Always inlined: GCC deduces that a call to it has no side effects (a prefetch does not
  // count) and would delete the call.
  [[gnu::always_inline]] void PrefetchPath(const Node* root, uint64_t key, int depth) const {
    const Node* cur = root;
    for (int level = 0; cur != nullptr && level < depth; ++level) {
      cur = static_cast<const Inner*>(cur)->child[Digit(key, level)];
    }
    if (cur == nullptr) return;
    __builtin_prefetch(cur);
    if (depth < height_ - 1) {
      __builtin_prefetch(&static_cast<const Inner*>(cur)->child[Digit(key, depth)]);
    } else {
      __builtin_prefetch(&static_cast<const Bottom*>(cur)->leaf[Digit(key, depth)]);
    }
  }

  // A second reference to the same version: O(1).
  static Node* Share(Node* root) {
    if (root != nullptr) root->rc.Acquire();
    return root;
  }

  // Applies f(Leaf& leaf, bool existed) to the leaf under `key` (value-initialised if it did not
  // exist) and returns the updated version. Consumes the caller's reference to `root`: use the
  // returned root instead. Copies only shared nodes on the path; O(height).
  template <typename F>
  Node* Update(Node* root, uint64_t key, int slot, F&& f) {
    Node* new_root = nullptr;
    Node** link = &new_root;
    Node* cur = root;
    for (int level = 0; level < height_ - 1; ++level) {
      int d = Digit(key, level);
      Inner* n;
      if (cur == nullptr) {
        n = NewInner(slot);
      } else if (cur->rc.unique()) {
        n = static_cast<Inner*>(cur);
      } else {
        // Shared: copy it; every child gains the copy as a parent. The path child is counted
        // too: once `cur` loses our reference another version may own it alone and change it
        // in place, so the copy must not lean on `cur`'s link.
        Inner* old = static_cast<Inner*>(cur);
        n = NewInner(slot);
        std::memcpy(n->child, old->child, sizeof(n->child));
        for (Node* c : old->child) {
          if (c != nullptr) c->rc.Acquire();
        }
        if (old->rc.Release()) {
          // Every other owner dropped `old` meanwhile: its references were the ones just added.
          for (Node* c : old->child) {
            if (c != nullptr) c->rc.Release();
          }
          FreeNode(old, /*bottom=*/false, slot);
        }
      }
      *link = n;
      link = &n->child[d];
      cur = n->child[d];
    }
    int d = Digit(key, height_ - 1);
    Bottom* b;
    if (cur == nullptr) {
      b = NewBottom(slot);
    } else if (cur->rc.unique()) {
      b = static_cast<Bottom*>(cur);
    } else {
      Bottom* old = static_cast<Bottom*>(cur);
      b = NewBottom(slot);
      std::memcpy(b->present, old->present, sizeof(b->present));
      std::memcpy(static_cast<void*>(b->leaf), old->leaf, sizeof(b->leaf));
      if (old->rc.Release()) FreeNode(old, /*bottom=*/true, slot);
    }
    bool existed = b->Has(d);
    if (!existed) {
      b->leaf[d] = Leaf{};
      b->present[d >> 6] |= uint64_t{1} << (d & 63);
    }
    f(b->leaf[d], existed);
    *link = b;
    return new_root;
  }

  // Drops one reference to a version, freeing every node no other version reaches. Iterative
  // with an explicit stack: a chain of any length cannot overflow the call stack.
  void Release(Node* root, int slot) {
    if (root == nullptr || !root->rc.Release()) return;
    struct Item {
      Node* node;
      int level;
    };
    std::array<Item, (kDegree - 1) * kMaxHeight + 1> stack;
    int top = 0;
    stack[top++] = {root, 0};
    while (top > 0) {
      Item item = stack[--top];
      if (item.level < height_ - 1) {
        Inner* n = static_cast<Inner*>(item.node);
        for (int i = 0; i < kDegree; ++i) {
          Node* c = n->child[i];
          if (c != nullptr && c->rc.Release()) stack[top++] = {c, item.level + 1};
        }
        FreeNode(n, /*bottom=*/false, slot);
      } else {
        FreeNode(item.node, /*bottom=*/true, slot);
      }
    }
  }

  // Release() of every version in `roots` (nullptr entries skipped), with the cache misses of
  // many nodes overlapped: a node's count is dropped kInFlight drops after it was queued and
  // prefetched, and a dead inner node's links are read kInFlight dead nodes after its lines
  // were prefetched. Frees the same nodes as Release() one by one; only the order differs.
  void ReleaseMany(std::span<Node* const> roots, int slot) {
    constexpr size_t kInFlight = 16;
    using Item = ReleaseItem;
    // FIFOs: nodes whose count is to be dropped, and dead inner nodes to expand and free.
    std::vector<Item>& drop = release_scratch_[slot].drop;
    std::vector<Item>& dead = release_scratch_[slot].dead;
    drop.clear();
    dead.clear();
    size_t drop_head = 0, dead_head = 0, next = 0;
    auto queue = [&](Node* n, int level) {
      __builtin_prefetch(n, 1);
      drop.push_back({n, level});
    };
    for (;;) {
      while (drop.size() - drop_head < kInFlight && next < roots.size()) {
        if (roots[next] != nullptr) queue(roots[next], 0);
        ++next;
      }
      if (drop_head < drop.size()) {
        Item item = drop[drop_head++];
        if (drop_head == drop.size()) {
          drop.clear();
          drop_head = 0;
        }
        if (item.node->rc.Release()) {
          if (item.level < height_ - 1) {
            const char* p = reinterpret_cast<const char*>(item.node);
            for (size_t off = 0; off < sizeof(Inner); off += 64) __builtin_prefetch(p + off);
            dead.push_back(item);
          } else {
            FreeNode(item.node, /*bottom=*/true, slot);
          }
        }
      }
      if (dead_head < dead.size() &&
          (dead.size() - dead_head >= kInFlight || drop_head == drop.size())) {
        Item item = dead[dead_head++];
        if (dead_head == dead.size()) {
          dead.clear();
          dead_head = 0;
        }
        Inner* n = static_cast<Inner*>(item.node);
        for (int i = 0; i < kDegree; ++i) {
          if (n->child[i] != nullptr) queue(n->child[i], item.level + 1);
        }
        FreeNode(n, /*bottom=*/false, slot);
      }
      if (drop_head == drop.size() && dead_head == dead.size() && next == roots.size()) return;
    }
  }

  // Calls f(key, const Leaf&) for every leaf of one version in increasing key order.
  template <typename F>
  void ForEach(const Node* root, F&& f) const {
    if (root == nullptr) return;
    struct Item {
      const Node* node;
      int level;
      uint64_t prefix;
    };
    std::vector<Item> stack;
    stack.push_back({root, 0, 0});
    while (!stack.empty()) {
      Item item = stack.back();
      stack.pop_back();
      if (item.level < height_ - 1) {
        const Inner* n = static_cast<const Inner*>(item.node);
        for (int i = kDegree - 1; i >= 0; --i) {  // pushed in reverse: popped in key order
          if (n->child[i] != nullptr) {
            stack.push_back({n->child[i], item.level + 1, (item.prefix << kLog2Degree) | i});
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
    for (size_t i = 0; i < roots.size(); ++i) {
      if (roots[i] != nullptr) add(roots[i], 0, weights[i]);
    }
    size_t distinct = level_nodes.size();
    for (int level = 0; level < height_ - 1; ++level) {
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

  // Number of nodes of one version (shared ones included). For tests and statistics.
  size_t CountNodes(const Node* root) const {
    size_t count = 0;
    if (root == nullptr) return 0;
    std::vector<std::pair<const Node*, int>> stack{{root, 0}};
    while (!stack.empty()) {
      auto [n, level] = stack.back();
      stack.pop_back();
      ++count;
      if (level < height_ - 1) {
        for (const Node* c : static_cast<const Inner*>(n)->child) {
          if (c != nullptr) stack.push_back({c, level + 1});
        }
      }
    }
    return count;
  }

  // Writes the distinct nodes reachable from `roots`, each once and children before parents,
  // then the roots as node indices: Load() rebuilds the same sharing, so the size follows the
  // distinct nodes, not roots x map size. Record of a node: u8 level, the presence words, then
  // a u32 child index (inner) or the leaf bytes (bottom) for each present digit.
  void Save(std::span<Node* const> roots, ByteWriter* w) const {
    std::unordered_map<const Node*, uint32_t> index;
    w->Put<uint32_t>(static_cast<uint32_t>(height_));
    const size_t count_at = w->Reserve<uint64_t>();
    struct Frame {
      const Node* node;
      int level;
      int next;  // the next child digit to visit
    };
    std::vector<Frame> stack;
    for (const Node* root : roots) {
      if (root == nullptr || index.count(root) != 0) continue;
      stack.push_back({root, 0, 0});
      while (!stack.empty()) {
        Frame& f = stack.back();
        if (f.level < height_ - 1) {
          const Inner* n = static_cast<const Inner*>(f.node);
          while (f.next < kDegree &&
                 (n->child[f.next] == nullptr || index.count(n->child[f.next]) != 0)) {
            ++f.next;
          }
          if (f.next < kDegree) {
            stack.push_back({n->child[f.next], f.level + 1, 0});  // invalidates f
            continue;
          }
        }
        Frame done = f;
        stack.pop_back();
        index.emplace(done.node, static_cast<uint32_t>(index.size()));
        w->Put<uint8_t>(static_cast<uint8_t>(done.level));
        if (done.level < height_ - 1) {
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
  // Every structural rule is checked (levels, child indices before parents, every node
  // referenced, presence bits within the degree); on error nothing stays allocated and
  // `roots` is unchanged. Nodes come from `slot`'s pools.
  template <typename V>
  Status Load(ByteReader* r, size_t root_count, int slot, V&& valid_leaf,
              std::vector<Node*>* roots) {
    uint32_t height = 0;
    GROVE_RETURN_IF_ERROR(r->Get("trie height", &height));
    if (height != static_cast<uint32_t>(height_)) {
      return r->Error("trie height", std::to_string(height) + " does not match the " +
                                         std::to_string(height_) + " of this configuration");
    }
    uint64_t count = 0;
    GROVE_RETURN_IF_ERROR(r->GetCount("trie node count", 1 + sizeof(uint64_t) * kWords, &count));
    if (count >= UINT32_MAX) return r->Error("trie node count", "too large");
    std::vector<Node*> nodes;
    std::vector<uint8_t> levels;
    std::vector<uint32_t> refs;
    nodes.reserve(count);
    levels.reserve(count);
    refs.reserve(count);
    auto fail = [&](Status s) {
      for (size_t k = 0; k < nodes.size(); ++k) {
        FreeNode(nodes[k], levels[k] == height_ - 1, slot);
      }
      return s;
    };
    for (uint64_t k = 0; k < count; ++k) {
      uint8_t level = 0;
      uint64_t present[kWords];
      Status s = r->Get("trie node level", &level);
      if (s.ok() && level >= height_) {
        s = r->Error("trie node level",
                     std::to_string(level) + " is not below the height " + std::to_string(height_));
      }
      if (s.ok()) s = r->GetBytes("trie node presence", present, sizeof(present));
      if (s.ok() && kDegree % 64 != 0 && (present[kWords - 1] >> (kDegree % 64)) != 0) {
        s = r->Error("trie node presence", "a digit beyond the degree is marked present");
      }
      if (!s.ok()) return fail(s);
      auto has = [&](int d) { return (present[d >> 6] >> (d & 63)) & 1; };
      if (level < height_ - 1) {
        Inner* n = NewInner(slot);
        nodes.push_back(n);
        levels.push_back(level);
        refs.push_back(0);
        for (int d = 0; d < kDegree; ++d) {
          if (!has(d)) continue;
          uint32_t c = 0;
          s = r->Get("trie child index", &c);
          if (s.ok() && (c >= k || levels[c] != level + 1)) {
            s = r->Error("trie child index",
                         std::to_string(c) + " is not an earlier node one level down");
          }
          if (!s.ok()) return fail(s);
          n->child[d] = nodes[c];
          ++refs[c];
        }
      } else {
        Bottom* b = NewBottom(slot);
        nodes.push_back(b);
        levels.push_back(level);
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
        r, "trie root", root_count, nodes, &refs, [&](size_t k) { return levels[k] == 0; }, roots);
    return s.ok() ? s : fail(s);
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

  int Digit(uint64_t key, int level) const {
    return static_cast<int>((key >> (kLog2Degree * (height_ - 1 - level))) & (kDegree - 1));
  }

  Inner* NewInner(int slot) {
    Inner* n = new (inner_pool_.Allocate(slot)) Inner;
    std::memset(n->child, 0, sizeof(n->child));
    return n;
  }
  Bottom* NewBottom(int slot) {
    Bottom* b = new (bottom_pool_.Allocate(slot)) Bottom;
    std::memset(b->present, 0, sizeof(b->present));
    std::memset(static_cast<void*>(b->leaf), 0, sizeof(b->leaf));
    return b;
  }
  void FreeNode(Node* n, bool bottom, int slot) {
    if (bottom) {
      static_cast<Bottom*>(n)->~Bottom();
      bottom_pool_.Free(n, slot);
    } else {
      static_cast<Inner*>(n)->~Inner();
      inner_pool_.Free(n, slot);
    }
  }

  int height_;
  NodePool inner_pool_;
  NodePool bottom_pool_;
  // ReleaseMany's queues, per worker slot (reused: no allocation per call once grown).
  struct ReleaseItem {
    Node* node;
    int level;
  };
  struct alignas(64) ReleaseScratch {
    std::vector<ReleaseItem> drop;
    std::vector<ReleaseItem> dead;
  };
  std::vector<ReleaseScratch> release_scratch_;
};

}  // namespace grove

#endif  // GROVE_ENGINE_PERSISTENT_TRIE_H_

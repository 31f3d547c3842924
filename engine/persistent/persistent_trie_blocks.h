// PersistentTrie's blocks, the keys under one key prefix in every version (see
// persistent_trie.h): VisitSubtreeDistinct(), SubtreePrefixes() and DropSubtree(), with where a
// block lives (Locate(), SubtreeOf()) and a node's copy without it (Without()). Included by
// persistent_trie.h.
#ifndef GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_BLOCKS_H_
#define GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_BLOCKS_H_

#include <algorithm>

#include "engine/persistent/persistent_trie.h"

namespace grove {

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline auto PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::Locate(int bits,
                                                                         uint64_t prefix) const
    -> BlockAt {
  GROVE_CHECK(bits >= 0 && bits < SpanBits(height_) &&
              (bits < kLog2BottomDegree || (bits - kLog2BottomDegree) % kLog2Degree == 0));
  if (bits >= kLog2BottomDegree) {
    return {(bits - kLog2BottomDegree) / kLog2Degree, prefix, bits, 0};
  }
  const int shift = kLog2BottomDegree - bits;
  return {0, prefix >> shift, bits, static_cast<int>(prefix & ((uint64_t{1} << shift) - 1))};
}

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline bool PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::HoldsSubtree(
    const Node* root, int level, uint64_t prefix) const {
  const int shift = SpanBits(level + 1);
  if (shift >= 64) return false;
  const uint64_t low = prefix << shift;
  return (low >> shift) == prefix && HeightFor(low, fill_) <= Height(root);
}

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline auto PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::SubtreeOf(Node* root, int level,
                                                                            uint64_t prefix) const
    -> Node* {
  if (root == nullptr || !HoldsSubtree(root, level, prefix)) return nullptr;
  Node* cur = root;
  for (int l = root->level; cur != nullptr && l > level; --l) {
    cur = static_cast<Inner*>(cur)->child[PrefixDigit(prefix, l - level - 1)];
  }
  return cur;
}

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
template <typename W, typename F>
inline size_t PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::VisitSubtreeDistinct(
    std::span<Node* const> roots, std::span<const W> weights, int bits, uint64_t prefix,
    F&& on_leaf) const {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline std::vector<uint64_t> PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::SubtreePrefixes(
    std::span<Node* const> roots, int bits) const {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline bool PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::InsertPointer(
    std::vector<const Node*>* set, const Node* n) {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline bool PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::DropSubtree(
    std::span<Node*> roots, int bits, uint64_t prefix, int slot) {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline auto PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::Without(
    Node* n, const BlockAt& block, int slot, std::unordered_map<const Node*, Node*>* replaced,
    bool* ok) -> Node* {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline auto PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::BottomWithout(
    Bottom* old, const BlockAt& block, int slot, std::unordered_map<const Node*, Node*>* replaced,
    bool* ok) -> Node* {
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

}  // namespace grove

#endif  // GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_BLOCKS_H_

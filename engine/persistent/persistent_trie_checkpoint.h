// PersistentTrie's checkpoint form (see persistent_trie.h): Save() writes the distinct nodes of
// many versions once, children first, and Load() rebuilds the same sharing, checking every
// structural rule. Included by persistent_trie.h.
#ifndef GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_CHECKPOINT_H_
#define GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_CHECKPOINT_H_

#include <algorithm>
#include <string>

#include "engine/persistent/persistent_trie.h"

namespace grove {

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline void PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::Save(std::span<Node* const> roots,
                                                                       ByteWriter* w) const {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
template <typename V>
inline Status PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::Load(
    ByteReader* r, size_t root_count, int slot, V&& valid_leaf, std::vector<Node*>* roots) {
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

}  // namespace grove

#endif  // GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_CHECKPOINT_H_

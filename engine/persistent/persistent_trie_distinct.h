// PersistentTrie's walks over many versions that visit each distinct node once (see
// persistent_trie.h): VisitDistinct(), weighted sums over every version such as a cumulative
// map, and CheckCounts(), the expensive check of invariants 1 and 3. Included by
// persistent_trie.h.
#ifndef GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_DISTINCT_H_
#define GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_DISTINCT_H_

#include <algorithm>
#include <string>

#include "engine/persistent/persistent_trie.h"

namespace grove {

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
template <typename W, typename F>
inline size_t PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::VisitDistinct(
    std::span<Node* const> roots, std::span<const W> weights, F&& on_leaf) const {
  GROVE_CHECK(roots.size() == weights.size());
  std::vector<uint64_t> prefixes(roots.size());
  for (size_t i = 0; i < roots.size(); ++i) prefixes[i] = FillPrefix(Height(roots[i]));
  return VisitDistinctFrom<W>(roots, prefixes, weights, on_leaf);
}

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
template <typename W, typename F>
inline size_t PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::VisitDistinctFrom(
    std::span<Node* const> roots, std::span<const uint64_t> prefixes, std::span<const W> weights,
    F& on_leaf) const {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline Status PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::CheckCounts(
    std::span<Node* const> roots) const {
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

}  // namespace grove

#endif  // GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_DISTINCT_H_

// PersistentTrie's reads of one version (see persistent_trie.h): Find(), PrefetchPath(),
// ForEach(), the range query ForEachIf() and CountNodes(). Included by persistent_trie.h.
#ifndef GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_LOOKUP_H_
#define GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_LOOKUP_H_

#include "engine/persistent/persistent_trie.h"

namespace grove {

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline const Leaf* PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::Find(const Node* root,
                                                                              uint64_t key) const {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
[[gnu::always_inline]] inline void
PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::PrefetchPath(const Node* root, uint64_t key,
                                                                   int depth) const {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
template <typename F>
inline void PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::ForEach(const Node* root,
                                                                          F&& f) const {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
template <typename P, typename F>
inline void PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::ForEachIf(const Node* root,
                                                                            P&& may_contain,
                                                                            F&& f) const {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline size_t PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::CountNodes(
    const Node* root) const {
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

}  // namespace grove

#endif  // GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_LOOKUP_H_

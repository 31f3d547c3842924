// PersistentTrie's path copying (see persistent_trie.h): Update() copies the shared nodes on a
// key's path, changes uniquely owned ones in place and grows a version a key does not fit;
// Erase() removes a leaf and frees the nodes it empties. Included by persistent_trie.h.
#ifndef GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_UPDATE_H_
#define GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_UPDATE_H_

#include <algorithm>

#include "engine/persistent/persistent_trie.h"

namespace grove {

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
template <typename F>
inline bool PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::Update(Node** root, uint64_t key,
                                                                         int slot, F&& f,
                                                                         uint32_t holders) {
  const int need = std::max(height_, HeightFor(key, fill_));
  const Node* owned = nullptr;
  if (holders > 1 && *root != nullptr && Height(*root) >= need && (*root)->rc.count() == holders) {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline bool PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::Erase(Node** root, uint64_t key,
                                                                        int slot) {
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
    std::memmove(static_cast<void*>(leaf + at), leaf + at + 1, (b->leaves - at - 1) * sizeof(Leaf));
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline bool PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::Abandon(Node* held, Node* cur,
                                                                          int slot) {
  if (held != nullptr) {
    if (cur != nullptr) cur->rc.Acquire();
    Release(held, slot);
  }
  return false;
}

}  // namespace grove

#endif  // GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_UPDATE_H_

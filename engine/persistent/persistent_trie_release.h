// PersistentTrie's release of versions (see persistent_trie.h): ReleaseMany(), which overlaps the
// cache misses of many nodes and coalesces drops of one node, and FreeDead(), which frees what
// only a dead node reached with a fixed stack. Included by persistent_trie.h.
#ifndef GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_RELEASE_H_
#define GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_RELEASE_H_

#include "engine/persistent/persistent_trie.h"

namespace grove {

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline void PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::ReleaseMany(
    std::span<Node* const> roots, int slot) {
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

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline void PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::DropRefs(Drop d, int slot) {
  if (d.node->rc.Release(d.count)) FreeDead(d.node, slot);
}

template <typename Leaf, int kLog2Degree, int kLog2BottomDegree>
inline void PersistentTrie<Leaf, kLog2Degree, kLog2BottomDegree>::FreeDead(Node* dead, int slot) {
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

}  // namespace grove

#endif  // GROVE_ENGINE_PERSISTENT_PERSISTENT_TRIE_RELEASE_H_

// Ancestry: every particle's path as a persistent ancestry tree. A particle's history is a
// pointer to its newest entry (a pose, with whatever else a model keeps per step); each entry
// points at the one before. Resampling shares a pointer (one increment, nothing copied) and a
// dead branch is freed back to the first entry another particle still reaches, so the live tree
// stays near T + C * N * log N nodes for T steps and N particles (Jacob, Murray and
// Rubenthaler, "Path storage in the particle filter", 2015).
//
// Value: a trivially copyable payload, stored and checkpointed as its bytes.
// Memory: nodes come from a NodePool; Append() returns nullptr when none can be had.
//
// Thread safety: as PersistentTrie: distinct histories may be appended to and released from
// distinct worker slots concurrently, even when they share entries.
#ifndef GROVE_ENGINE_PERSISTENT_ANCESTRY_H_
#define GROVE_ENGINE_PERSISTENT_ANCESTRY_H_

#include <cmath>
#include <cstdint>
#include <new>
#include <span>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <utility>
#include <vector>

#include "alloc/node_pool.h"
#include "concurrency/ref_count.h"
#include "engine/io/checkpoint_io.h"

namespace grove {

template <typename Value>
class Ancestry {
  static_assert(std::is_trivially_copyable_v<Value>, "entries are checkpointed as their bytes");

 public:
  struct Node {
    RefCount rc;
    uint32_t step;
    Value value;
    Node* parent;
  };
  using Root = Node*;

  explicit Ancestry(int slots) : pool_(sizeof(Node), slots) {}

  // A new entry after `parent`, whose reference it takes over (nullptr starts a path). Returns
  // nullptr when no node can be had; the caller then still owns `parent`.
  Node* Append(Node* parent, uint32_t step, const Value& value, int slot) {
    void* p = pool_.Allocate(slot);
    if (p == nullptr) return nullptr;
    Node* n = new (p) Node;
    n->step = step;
    n->value = value;
    n->parent = parent;
    return n;
  }

  static Node* Share(Node* n) {
    if (n != nullptr) n->rc.Acquire();
    return n;
  }

  // Drops one reference; frees the poses no other history reaches. Iterative along the chain.
  void Release(Node* n, int slot) {
    while (n != nullptr && n->rc.Release()) {
      Node* parent = n->parent;
      n->~Node();
      pool_.Free(n, slot);
      n = parent;
    }
  }

  // Release() of every history in `nodes` (nullptr entries skipped). Walks many chains at once:
  // a pose is dropped kInFlight drops after it was queued and prefetched, so the cache misses of
  // up to kInFlight chains overlap (one chain alone is a series of dependent misses). The poses
  // freed are the same as by Release() one by one; only the order differs.
  void ReleaseMany(std::span<Node* const> nodes, int slot) {
    constexpr size_t kInFlight = 16;
    constexpr size_t kRing = 32;  // a power of two >= kInFlight + 1
    Node* ring[kRing];
    size_t head = 0, tail = 0;  // queued: ring[head .. tail), indices mod kRing
    size_t next = 0;
    for (;;) {
      while (tail - head < kInFlight && next < nodes.size()) {
        Node* n = nodes[next++];
        if (n == nullptr) continue;
        __builtin_prefetch(n, 1);
        ring[tail++ % kRing] = n;
      }
      if (head == tail) {
        pool_.Flush(slot);
        return;
      }
      Node* n = ring[head++ % kRing];
      if (!n->rc.Release()) continue;
      Node* parent = n->parent;
      n->~Node();
      pool_.Free(n, slot);
      if (parent != nullptr) {
        __builtin_prefetch(parent, 1);
        ring[tail++ % kRing] = parent;
      }
    }
  }

  // The path ending at `n`, oldest entry first.
  static std::vector<const Node*> Path(const Node* n) {
    std::vector<const Node*> path;
    for (; n != nullptr; n = n->parent) path.push_back(n);
    return std::vector<const Node*>(path.rbegin(), path.rend());
  }

  // The smoothed (fixed-interval) path: the final weights pushed back along the ancestry. For
  // every step k in 0..last_step, calls add(k, w, value) once for each distinct entry that is
  // some history's newest entry at or before step k, with w the sum of the weights of the
  // histories that reach it there; a caller summing w * value gets sum_i weights[i] *
  // value_i(k), the weighted mean of the ancestral values at k. Each distinct entry is visited
  // once per step it stands for (once in all when every step has its entry, as in FootSLAM),
  // not once per history. The order of the calls and of every sum of weights depends only on
  // the ancestry's shape and the histories' order, never on addresses: the same bits at any
  // thread count. W: double, or an integer type whose sums are exact in any order.
  // REQUIRES: weights.size() == heads.size(); no head is newer than last_step.
  template <typename W, typename Add>
  static void Smooth(std::span<const Node* const> heads, std::span<const W> weights,
                     uint32_t last_step, Add&& add) {
    std::vector<std::pair<const Node*, W>> level, next;
    std::unordered_map<const Node*, size_t> index;
    auto merge = [&](const Node* n, W w) {
      auto [it, added] = index.try_emplace(n, next.size());
      if (added) {
        next.emplace_back(n, w);
      } else {
        next[it->second].second += w;
      }
    };
    for (size_t i = 0; i < heads.size(); ++i) {
      if (heads[i] != nullptr) merge(heads[i], weights[i]);
    }
    for (int64_t k = last_step; k >= 0 && !next.empty(); --k) {
      level.swap(next);
      next.clear();
      index.clear();
      for (const auto& [n, w] : level) {
        add(static_cast<uint32_t>(k), w, n->value);
        if (n->step < k) {
          merge(n, w);  // it also stands for the step before
        } else if (n->parent != nullptr) {
          merge(n->parent, w);
        }
      }
    }
  }

  // Writes the distinct entries reachable from `heads`, each once and older ones first, then the
  // heads as entry indices: the shared ancestry keeps its sharing. A record: u32 parent index + 1
  // (0: none), u32 step, the value's bytes.
  static void Save(std::span<Node* const> heads, ByteWriter* w) {
    std::unordered_map<const Node*, uint32_t> index;
    const size_t count_at = w->Reserve<uint64_t>();
    std::vector<const Node*> chain;
    for (const Node* head : heads) {
      chain.clear();
      for (const Node* n = head; n != nullptr && index.count(n) == 0; n = n->parent) {
        chain.push_back(n);
      }
      for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
        const Node* n = *it;
        index.emplace(n, static_cast<uint32_t>(index.size()));
        w->Put<uint32_t>(n->parent == nullptr ? 0 : index.at(n->parent) + 1);
        w->Put<uint32_t>(n->step);
        w->Put(n->value);
      }
    }
    w->Patch<uint64_t>(count_at, index.size());
    w->Put<uint64_t>(heads.size());
    for (const Node* head : heads) w->Put<uint32_t>(head == nullptr ? 0 : index.at(head) + 1);
  }

  // Rebuilds histories written by Save(): appends `head_count` heads to `heads`, each owning one
  // reference. Checks that parents come first, steps increase along every path and stay at
  // most `max_step`, valid(const Value&) holds for each value and every entry is reached. On
  // error nothing stays allocated and `heads` is unchanged.
  template <typename Valid>
  Status Load(ByteReader* r, size_t head_count, uint32_t max_step, int slot, Valid&& valid,
              std::vector<Node*>* heads) {
    constexpr size_t kRecordBytes = 8 + sizeof(Value);
    uint64_t count = 0;
    GROVE_RETURN_IF_ERROR(r->GetCount("pose count", kRecordBytes, &count));
    if (count >= UINT32_MAX) return r->Error("pose count", "too large");
    std::vector<Node*> nodes;
    std::vector<uint32_t> refs;
    nodes.reserve(count);
    refs.reserve(count);
    auto fail = [&](Status s) {
      for (Node* n : nodes) {
        n->~Node();
        pool_.Free(n, slot);
      }
      return s;
    };
    for (uint64_t k = 0; k < count; ++k) {
      uint32_t parent = 0, step = 0;
      Value value;
      Status s = r->Get("pose parent", &parent);
      if (s.ok() && parent > k) {
        s = r->Error("pose parent", std::to_string(parent) + " is not an earlier pose");
      }
      if (s.ok()) s = r->Get("pose step", &step);
      if (s.ok() && (step > max_step || (parent != 0 && step <= nodes[parent - 1]->step))) {
        s = r->Error("pose step", std::to_string(step) +
                                      " is past the last step or not after "
                                      "its parent's");
      }
      if (s.ok()) s = r->GetBytes("pose", &value, sizeof(value));
      if (s.ok() && !valid(value)) s = r->Error("pose", "a value is not finite or out of range");
      if (!s.ok()) return fail(s);
      void* p = pool_.Allocate(slot);
      if (p == nullptr) return fail(ResourceExhaustedError("out of memory loading paths"));
      Node* n = new (p) Node;
      n->step = step;
      n->value = value;
      n->parent = parent == 0 ? nullptr : nodes[parent - 1];
      if (parent != 0) ++refs[parent - 1];
      nodes.push_back(n);
      refs.push_back(0);
    }
    uint64_t saved_heads = 0;
    Status s = r->Get("path count", &saved_heads);
    if (s.ok() && saved_heads != head_count) {
      s = r->Error("path count",
                   std::to_string(saved_heads) + " paths, expected " + std::to_string(head_count));
    }
    if (!s.ok()) return fail(s);
    s = LinkRoots(
        r, "path head", head_count, nodes, &refs, [](size_t) { return true; }, heads);
    return s.ok() ? s : fail(s);
  }

  // The expensive check of the counts: `heads` must be every reference into this store (one
  // entry per reference). A node's count must equal its children plus heads, and every live
  // node must be reached (nothing leaked). For tests; Internal naming the broken rule.
  Status CheckCounts(std::span<Node* const> heads) const {
    std::unordered_map<const Node*, uint32_t> links;
    for (const Node* h : heads) {
      for (const Node* n = h; n != nullptr; n = n->parent) {
        if (links[n]++ > 0) break;  // the rest of this chain is counted already
      }
    }
    for (const auto& [node, count] : links) {
      if (node->rc.count() != count) {
        return InternalError("ancestry: an entry's count " + std::to_string(node->rc.count()) +
                             " is not its " + std::to_string(count) + " children and heads");
      }
    }
    if (static_cast<int64_t>(links.size()) != pool_.Stats().live_nodes) {
      return InternalError("ancestry: " + std::to_string(pool_.Stats().live_nodes) +
                           " live entries, " + std::to_string(links.size()) + " reachable");
    }
    return Status::Ok();
  }

  PoolStats stats() const { return pool_.Stats(); }

 private:
  NodePool pool_;
};

}  // namespace grove

#endif  // GROVE_ENGINE_PERSISTENT_ANCESTRY_H_

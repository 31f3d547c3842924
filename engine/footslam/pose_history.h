// PoseHistory: every particle's path as a persistent ancestry tree. A particle's history is a
// pointer to its newest pose; each pose points at the one before. Resampling shares a pointer
// (one increment, nothing copied) and a dead branch is freed back to the first pose another
// particle still reaches, so the live tree stays near T + C * N * log N nodes for T steps and N
// particles (Jacob, Murray and Rubenthaler, "Path storage in the particle filter", 2015).
//
// Thread safety: as PersistentTrie: distinct histories may be appended to and released from
// distinct worker slots concurrently, even when they share poses.
#ifndef GROVE_ENGINE_FOOTSLAM_POSE_HISTORY_H_
#define GROVE_ENGINE_FOOTSLAM_POSE_HISTORY_H_

#include <cstdint>
#include <new>
#include <span>
#include <vector>

#include "alloc/node_pool.h"
#include "concurrency/ref_count.h"

namespace grove::footslam {

class PoseHistory {
 public:
  struct Node {
    RefCount rc;
    uint32_t step;
    float x_m, y_m, heading_rad;
    Node* parent;
  };

  explicit PoseHistory(int slots) : pool_(sizeof(Node), slots) {}

  // A new pose after `parent` (whose reference is consumed; nullptr starts a path).
  Node* Append(Node* parent, uint32_t step, double x, double y, double heading, int slot) {
    Node* n = new (pool_.Allocate(slot)) Node;
    n->step = step;
    n->x_m = static_cast<float>(x);
    n->y_m = static_cast<float>(y);
    n->heading_rad = static_cast<float>(heading);
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
      if (head == tail) return;
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

  // The path ending at `n`, oldest pose first.
  static std::vector<const Node*> Path(const Node* n) {
    std::vector<const Node*> path;
    for (; n != nullptr; n = n->parent) path.push_back(n);
    return std::vector<const Node*>(path.rbegin(), path.rend());
  }

  PoolStats stats() const { return pool_.Stats(); }

 private:
  NodePool pool_;
};

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_POSE_HISTORY_H_

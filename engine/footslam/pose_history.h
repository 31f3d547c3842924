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

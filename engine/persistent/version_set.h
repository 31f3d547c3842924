// VersionSet: one persistent version per particle (a map root, a path history) plus the dead
// generation that resampling leaves, for any store whose versions are reference-counted roots
// (PersistentTrie, Ancestry): what every model needs from a store to follow the filter's
// generations.
//
// The Store provides:
//   using Root = Node*;                                // nullptr: the empty version
//   static Root Share(Root);                           // one more reference, O(1)
//   void Release(Root, int slot);                      // drops one
//   void ReleaseMany(std::span<Root const>, int slot); // drops many, misses overlapped
//
// Thread safety: as the store's; Gather and ReleaseDead run on the driving thread and use the
// workers inside.
#ifndef GROVE_ENGINE_PERSISTENT_VERSION_SET_H_
#define GROVE_ENGINE_PERSISTENT_VERSION_SET_H_

#include <algorithm>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "alloc/check.h"
#include "concurrency/worker_pool.h"
#include "engine/filter/generation.h"

namespace grove {

template <typename Store>
class VersionSet {
 public:
  using Root = typename Store::Root;

  // `particles` empty versions of `store`, which must outlive the set.
  VersionSet(Store* store, size_t particles) : store_(store), roots_(particles, nullptr) {}
  VersionSet(const VersionSet&) = delete;
  VersionSet& operator=(const VersionSet&) = delete;
  ~VersionSet() {
    for (Root r : roots_) store_->Release(r, 0);
    for (Root r : dead_) store_->Release(r, 0);
  }

  size_t size() const { return roots_.size(); }
  // Particle i's version; the set owns the reference (replace it by assigning a new root whose
  // reference moves in, as the stores' updates do).
  Root& operator[](size_t i) { return roots_[i]; }
  Root operator[](size_t i) const { return roots_[i]; }
  std::span<Root const> roots() const { return roots_; }
  // Version i becomes a reference to version `from`'s, dropping its own (a particle whose update
  // would repeat another's takes that one's result instead).
  void Adopt(size_t i, size_t from, int slot) {
    Root old = roots_[i];
    roots_[i] = Store::Share(roots_[from]);
    store_->Release(old, slot);
  }
  // Every version, to be replaced in place by a store's update of many versions at once (each
  // entry's reference moves to its new root). A dead generation still held is released first
  // (on the calling thread, slot 0).
  std::span<Root> mutable_roots() {
    if (!dead_.empty()) {
      store_->ReleaseMany(dead_, 0);
      DeadReleased();
    }
    return roots_;
  }

  // Every particle's version becomes a reference to `root`, whose reference the set takes over;
  // REQUIRES: every version is empty (a new set).
  void ShareAll(Root root) {
    for (size_t i = 0; i < roots_.size(); ++i) {
      GROVE_DCHECK(roots_[i] == nullptr);
      roots_[i] = i == 0 ? root : Store::Share(root);
    }
  }

  // The next generation: version k becomes a reference to parents[k]'s; the old versions are
  // kept as the dead generation until ReleaseDead(). REQUIRES: the copies of a parent are
  // adjacent in `parents` (as in any nondecreasing list).
  void Gather(std::span<const uint32_t> parents, WorkerPool& workers) {
    GROVE_DCHECK(dead_.empty());
    GatherShared(parents, &roots_, workers, kShare, &spare_);
    TakeGathered();
  }
  // Gather() in parts, for a caller that gathers several things in one loop of chunks of
  // `grain`: GatherBegin(), GatherRange() on each chunk, GatherEnd() after the loop.
  void GatherBegin(size_t n) {
    GROVE_DCHECK(dead_.empty());
    spare_.resize(n);
  }
  void GatherRange(std::span<const uint32_t> parents, size_t b, size_t e) {
    GatherSharedRange(parents, &roots_, kShare, &spare_, b, e);
  }
  void GatherEnd(std::span<const uint32_t> parents, size_t grain) {
    GatherSharedSeams(parents, grain, &roots_);
    TakeGathered();
  }

  // Frees the dead generation's references (what no live version shares), in parallel.
  void ReleaseDead(WorkerPool& workers) {
    workers.ParallelFor(dead_.size(), 1024,
                        [&](int slot, size_t b, size_t e) { ReleaseDeadRange(b, e, slot); });
    DeadReleased();
  }

  // ReleaseDead() in pieces, for a caller that frees the dead generation during the next step's
  // advance: the references of the previous generation's particles [lo, min(hi, its size))
  // from worker slot `slot`. The pieces must not overlap, and together cover the generation
  // before DeadReleased() ends it.
  void ReleaseDeadRange(size_t lo, size_t hi, int slot) {
    hi = std::min(hi, dead_.size());
    if (lo < hi) store_->ReleaseMany(std::span<Root const>(dead_).subspan(lo, hi - lo), slot);
  }
  void DeadReleased() {
    spare_.swap(dead_);  // the released buffer is the next Gather's output
    dead_.clear();
  }

  // Replaces every version by `loaded` (one reference each, as a store's Load() gives them).
  // REQUIRES: loaded.size() == size().
  void Replace(std::vector<Root> loaded) {
    GROVE_CHECK(loaded.size() == roots_.size());
    for (Root r : roots_) store_->Release(r, 0);
    roots_.swap(loaded);
  }

  // The versions of particles `which`, for a store's Save() (the set keeps its references).
  std::vector<Root> Pick(std::span<const uint32_t> which) const {
    std::vector<Root> picked;
    picked.reserve(which.size());
    for (uint32_t i : which) picked.push_back(roots_[i]);
    return picked;
  }

  // Appends versions (one reference each, as a store's Load() gives them): particles that came
  // from elsewhere, for the next Gather() to name. REQUIRES: no dead generation.
  void Append(const std::vector<Root>& loaded) {
    GROVE_DCHECK(dead_.empty());
    roots_.insert(roots_.end(), loaded.begin(), loaded.end());
  }

  // Every root reference the set holds, the dead generation's included: what a store's
  // invariant check must be given.
  std::vector<Root> AllReferences() const {
    std::vector<Root> all(roots_);
    all.insert(all.end(), dead_.begin(), dead_.end());
    return all;
  }

 private:
  // A lambda, not &Store::Share: a function pointer would stay an indirect call per copy.
  static constexpr auto kShare = [](Root r) { return Store::Share(r); };

  // The gathered versions (in spare_) become the live ones, the old ones the dead generation.
  void TakeGathered() {
    dead_.swap(roots_);
    roots_.swap(spare_);
  }

  Store* store_;
  std::vector<Root> roots_;
  std::vector<Root> dead_;
  std::vector<Root> spare_;  // no references: a buffer for the next Gather
};

}  // namespace grove

#endif  // GROVE_ENGINE_PERSISTENT_VERSION_SET_H_

// RefCount: an intrusive atomic reference count (immer's refcount_policy).
//
// Thread safety: all members may be called concurrently. A node's contents are written before
// it is published (by storing its pointer where other threads find it through a happens-before
// edge, e.g. a parallel-for join), so Acquire() needs no ordering of its own.
#ifndef GROVE_CONCURRENCY_REF_COUNT_H_
#define GROVE_CONCURRENCY_REF_COUNT_H_

#include <atomic>
#include <cstdint>

namespace grove {

class RefCount {
 public:
  RefCount() = default;  // starts at 1: the creator's reference
  RefCount(const RefCount&) = delete;
  RefCount& operator=(const RefCount&) = delete;

  // Adds a reference. Relaxed: the caller already holds a reference, so the object cannot die
  // meanwhile, and no data is published by an increment.
  void Acquire() const { count_.fetch_add(1, std::memory_order_relaxed); }

  // Drops a reference; returns true when it was the last one, and the caller must destroy the
  // object. acq_rel: release so this thread's reads and writes of the object happen before its
  // destruction by another thread; acquire so the destroying thread sees every other owner's.
  bool Release() const { return count_.fetch_sub(1, std::memory_order_acq_rel) == 1; }
  // Drops `n` references at once (n >= 1, at most the count); true as Release().
  bool Release(uint32_t n) const { return count_.fetch_sub(n, std::memory_order_acq_rel) == n; }

  // True when the caller holds the only reference and may mutate in place. Acquire pairs with
  // the release in other owners' Release(), so their last reads of the object happen before the
  // caller's writes.
  bool unique() const { return count_.load(std::memory_order_acquire) == 1; }

  // For tests and statistics only: the value may be stale as soon as it is read. Relaxed.
  uint32_t count() const { return count_.load(std::memory_order_relaxed); }

 private:
  mutable std::atomic<uint32_t> count_{1};
};

}  // namespace grove

#endif  // GROVE_CONCURRENCY_REF_COUNT_H_

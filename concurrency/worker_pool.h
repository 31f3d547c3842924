// WorkerPool: a fixed set of worker threads, owned by one engine, that runs loops over particle
// ranges and hands each loop body its worker slot (Ceres' ParallelFor with a thread id).
//
// It owns a tbb::task_arena with an explicit concurrency, so two engines in one process never
// share or resize each other's threads; library code never touches tbb::global_control.
// With one thread every loop runs inline on the caller: a serial executor for tests.
//
// Thread safety: one caller at a time (the engine's driving thread). Inside a loop, a slot is
// held by exactly one thread at a time, so per-slot state (node pools, scratch) needs no locks.
#ifndef GROVE_CONCURRENCY_WORKER_POOL_H_
#define GROVE_CONCURRENCY_WORKER_POOL_H_

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/partitioner.h>
#include <oneapi/tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "alloc/cache_line.h"

namespace grove {

class WorkerPool {
 public:
  // A thread count below 1 is taken as 1 (configurations are validated before this point).
  explicit WorkerPool(int threads);
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Where the loops' time went, since the pool was made: `loop_s`, the driving thread's wall time
  // inside ParallelFor; `busy_s`, the time threads spent running loop bodies (their own and
  // others' chunks), summed over threads. num_threads() * loop_s - busy_s is the time threads
  // waited inside loops: arriving late, or done before the others. (Two clock reads per thread
  // per loop.)
  struct Usage {
    double loop_s = 0;
    double busy_s = 0;
    uint64_t loops = 0;
  };
  Usage usage() const;

  int num_threads() const { return threads_; }
  // Slots are numbered 0 .. num_slots() - 1; the driving thread outside loops uses slot 0.
  int num_slots() const { return threads_; }

  // Calls body(slot, begin, end) over [0, n) in chunks of `grain` items: chunk c is
  // [c * grain, min((c + 1) * grain, n)) (the gathers of generation.h rely on it).
  // Chunks have a home slot: slot k owns the k-th contiguous share of [0, n) and runs it first,
  // in order. So the same particles meet the same worker from one loop to the next, and nodes
  // are mostly freed by the slot whose pool they came from (a local free, not a cross-thread
  // one). A thread then helps with another home only while more than half of it is unclaimed
  // (its owner is late or away): a chunk taken from an owner that is merely a little late moves
  // its particles' state to the helper's core and back again in the next loop, which costs more
  // than the wait where the two cores are far apart (FastSLAM 1.0 on FasterSLAM's webmap, 1,000
  // particles, 2 threads, a virtual machine whose vCPUs had a line round trip of 310-400 ns: 5 to
  // 6 % faster than helping to the end, medians of 30 alternated pairs; where the round trip was
  // about 100 ns, about 2 % slower, 7 pairs). A thread that gets a second task (some slot's
  // thread took none) finishes every home.
  template <typename F>
  void ParallelFor(size_t n, size_t grain, F&& body) {
    if (n == 0) return;
    if (grain == 0) grain = 1;
    const size_t chunks = (n + grain - 1) / grain;
    const int64_t start = Now();
    if (threads_ == 1 || chunks == 1) {
      for (size_t b = 0; b < n; b += grain) body(0, b, b + grain < n ? b + grain : n);
      const int64_t t = Now() - start;
      loop_ns_ += t;
      busy_[0].ns.fetch_add(t, std::memory_order_relaxed);
      ++loops_;
      return;
    }
    const size_t slots = static_cast<size_t>(threads_);
    // Home k holds chunks [k * chunks / slots, (k + 1) * chunks / slots).
    struct alignas(kFalseSharingBytes) Cursor {
      std::atomic<size_t> next;
      bool seen = false;  // slot k's thread has run one of the loop's tasks (only it writes it)
    };
    std::unique_ptr<Cursor[]> cursor(new Cursor[slots]);
    for (size_t k = 0; k < slots; ++k) cursor[k].next.store(k * chunks / slots);
    // Runs home's unclaimed chunks but its last `leave`.
    auto run_home = [&](size_t home, int slot, size_t leave) {
      const size_t end = (home + 1) * chunks / slots;
      std::atomic<size_t>& next = cursor[home].next;
      for (;;) {
        // Relaxed: the counter only hands out distinct chunk indices; the loop's join publishes
        // the results.
        size_t c;
        if (leave == 0) {
          c = next.fetch_add(1, std::memory_order_relaxed);
          if (c >= end) return;
        } else {
          c = next.load(std::memory_order_relaxed);
          do {
            if (c + leave >= end) return;
          } while (!next.compare_exchange_weak(c, c + 1, std::memory_order_relaxed));
        }
        size_t b = c * grain;
        body(slot, b, b + grain < n ? b + grain : n);
      }
    };
    arena_->execute([&] {
      tbb::parallel_for(
          size_t{0}, slots,
          [&](size_t) {
            const int64_t begin = Now();
            const int slot = tbb::this_task_arena::current_thread_index();
            // A thread's first task runs its home, then helps with the others' first halves; a
            // second task on the same thread means some slot's thread took none (and may never
            // come): it finishes every home.
            const bool first = !cursor[slot].seen;
            cursor[slot].seen = true;
            if (first) run_home(static_cast<size_t>(slot), slot, 0);
            for (size_t k = first ? 1 : 0; k < slots; ++k) {
              const size_t home = (slot + k) % slots;
              const size_t size = (home + 1) * chunks / slots - home * chunks / slots;
              run_home(home, slot, first ? (size + 1) / 2 : 0);
            }
            // Relaxed: only this slot adds to its counter; usage() reads between loops.
            busy_[slot].ns.fetch_add(Now() - begin, std::memory_order_relaxed);
          },
          tbb::simple_partitioner());
    });
    loop_ns_ += Now() - start;
    ++loops_;
  }

  // Splits [0, n) into fixed blocks of `block` items, computes f(block_index, begin, end) -> T for
  // each in parallel and returns the results in block order. Combining them in that order gives
  // sums that do not depend on the thread count.
  template <typename T, typename F>
  std::vector<T> MapBlocks(size_t n, size_t block, F&& f) {
    size_t blocks = n == 0 ? 0 : (n + block - 1) / block;
    std::vector<T> out(blocks);
    ParallelFor(blocks, 1, [&](int, size_t b0, size_t b1) {
      for (size_t b = b0; b < b1; ++b) {
        size_t begin = b * block;
        size_t end = begin + block < n ? begin + block : n;
        out[b] = f(b, begin, end);
      }
    });
    return out;
  }

 private:
  static int64_t Now() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }

  struct alignas(kFalseSharingBytes) Busy {
    std::atomic<int64_t> ns{0};
  };

  int threads_;
  std::unique_ptr<tbb::task_arena> arena_;
  std::unique_ptr<Busy[]> busy_;  // per slot
  int64_t loop_ns_ = 0;
  uint64_t loops_ = 0;
};

}  // namespace grove

#endif  // GROVE_CONCURRENCY_WORKER_POOL_H_

#include "concurrency/worker_pool.h"

namespace grove {

WorkerPool::WorkerPool(int threads)
    : threads_(threads < 1 ? 1 : threads), busy_(new Busy[static_cast<size_t>(threads_)]) {
  // One slot is reserved for the driving thread, which joins every loop as slot 0.
  arena_ = std::make_unique<tbb::task_arena>(threads_, 1);
  arena_->initialize();
}

WorkerPool::Usage WorkerPool::usage() const {
  Usage u;
  u.loop_s = static_cast<double>(loop_ns_) * 1e-9;
  for (int k = 0; k < threads_; ++k) {
    u.busy_s += static_cast<double>(busy_[k].ns.load(std::memory_order_relaxed)) * 1e-9;
  }
  u.loops = loops_;
  return u;
}

}  // namespace grove

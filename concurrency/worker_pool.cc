#include "concurrency/worker_pool.h"

namespace grove {

WorkerPool::WorkerPool(int threads) : threads_(threads < 1 ? 1 : threads) {
  // One slot is reserved for the driving thread, which joins every loop as slot 0.
  arena_ = std::make_unique<tbb::task_arena>(threads_, 1);
  arena_->initialize();
}

}  // namespace grove

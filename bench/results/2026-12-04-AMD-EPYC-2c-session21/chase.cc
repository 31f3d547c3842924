// Machine probe (session 21): a latency-bound pointer chase through a random cycle of 64-byte
// nodes (plain loads, or a relaxed atomic increment per node), one copy per process. Run one
// alone and two at once, one per core: `chase MIB ATOMIC`.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <random>
#include <vector>
struct alignas(64) Node {
  Node* next;
  std::atomic<long> count;
  char pad[48];
};
int main(int argc, char** argv) {
  size_t mib = std::atoi(argv[1]);
  int atomic = std::atoi(argv[2]);
  size_t n = mib * 1024 * 1024 / sizeof(Node);
  std::vector<Node> nodes(n);
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin() + 1, order.end(), std::mt19937_64(1));
  for (size_t i = 0; i < n; ++i) nodes[order[i]].next = &nodes[order[(i + 1) % n]];
  size_t steps = 200'000'000 / (mib < 4 ? 1 : 4);
  Node* p = &nodes[0];
  auto t0 = std::chrono::steady_clock::now();
  if (atomic) {
    for (size_t i = 0; i < steps; ++i) {
      p->count.fetch_add(1, std::memory_order_relaxed);
      p = p->next;
    }
  } else {
    for (size_t i = 0; i < steps; ++i) p = p->next;
  }
  double ns =
      std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%zu MiB atomic=%d: %.2f ns/step (%p)\n", mib, atomic, ns / steps, (void*)p);
}

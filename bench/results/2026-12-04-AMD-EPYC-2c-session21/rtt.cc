// Machine probe (session 21): the round trip of one cache line between the two cores (two
// threads pinned to CPUs 0 and 1 take turns incrementing one atomic).
#include <pthread.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <thread>
alignas(64) std::atomic<long> flag{0};
void pin(int c) {
  cpu_set_t cs;
  CPU_ZERO(&cs);
  CPU_SET(c, &cs);
  pthread_setaffinity_np(pthread_self(), sizeof cs, &cs);
}
int main() {
  const long n = 2'000'000;
  std::thread t([&] {
    pin(1);
    for (long i = 0; i < n; ++i) {
      while (flag.load(std::memory_order_acquire) != 2 * i + 1) {
      }
      flag.store(2 * i + 2, std::memory_order_release);
    }
  });
  pin(0);
  auto t0 = std::chrono::steady_clock::now();
  for (long i = 0; i < n; ++i) {
    flag.store(2 * i + 1, std::memory_order_release);
    while (flag.load(std::memory_order_acquire) != 2 * i + 2) {
    }
  }
  double ns =
      std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
  t.join();
  std::printf("round trip %.1f ns\n", ns / n);
}

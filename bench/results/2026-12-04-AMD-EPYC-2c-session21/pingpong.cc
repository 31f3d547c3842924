// Machine probe (session 21): two threads doing relaxed atomic increments on lines chosen at
// random from a set of L lines, shared (both threads use the same set) or private (each its
// own), with W dependent multiply-adds between increments: `pingpong L SHARED THREADS W`.
#include <pthread.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <vector>
struct alignas(64) Line {
  std::atomic<int> c{0};
};
int main(int argc, char** argv) {
  int lines = std::atoi(argv[1]);
  int shared = std::atoi(argv[2]);
  int threads = std::atoi(argv[3]);
  int work = std::atoi(argv[4]);
  std::vector<Line> set(lines * 2);
  const long ops = 20'000'000;
  std::vector<double> ns(threads);
  std::vector<std::thread> ts;
  for (int t = 0; t < threads; ++t)
    ts.emplace_back([&, t] {
      cpu_set_t cs;
      CPU_ZERO(&cs);
      CPU_SET(t, &cs);
      pthread_setaffinity_np(pthread_self(), sizeof cs, &cs);
      Line* base = &set[shared ? 0 : t * lines];
      unsigned x = 12345 + t;
      double acc = 1;
      auto t0 = std::chrono::steady_clock::now();
      for (long i = 0; i < ops; ++i) {
        x = x * 1664525u + 1013904223u;
        base[(x >> 8) % lines].c.fetch_add(1, std::memory_order_relaxed);
        for (int k = 0; k < work; ++k) acc = acc * 1.0000001 + 1e-9;
      }
      ns[t] =
          std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() /
          ops;
      if (acc == 0) std::printf("x");
    });
  for (auto& t : ts) t.join();
  std::printf("lines=%d shared=%d threads=%d work=%d:", lines, shared, threads, work);
  for (double v : ns) std::printf(" %.1f", v);
  std::printf(" ns/op\n");
}

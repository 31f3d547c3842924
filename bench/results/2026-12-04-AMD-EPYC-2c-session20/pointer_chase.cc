#include <algorithm>
#include <chrono>
#include <cstdio>
#include <numeric>
#include <random>
#include <thread>
#include <vector>
// Each thread: 16 independent random pointer chases (as ReleaseMany overlaps 16) in its own array.
double run(size_t mb) {
  size_t n = mb * 1048576 / 64;
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937_64(42));
  struct alignas(64) Line {
    size_t next;
    char pad[56];
  };
  std::vector<Line> a(n);
  for (size_t i = 0; i < n; ++i) a[order[i]].next = order[(i + 1) % n];
  size_t cur[16];
  for (int k = 0; k < 16; ++k) cur[k] = order[k * (n / 16)];
  const long hops = 4000000;
  auto t0 = std::chrono::steady_clock::now();
  for (long h = 0; h < hops; ++h)
    for (int k = 0; k < 16; ++k) cur[k] = a[cur[k]].next;
  double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  size_t x = 0;
  for (int k = 0; k < 16; ++k) x += cur[k];
  if (x == 1) std::puts("");
  return s / (hops * 16) * 1e9;
}
int main(int argc, char** argv) {
  int threads = atoi(argv[1]);
  size_t mb = atol(argv[2]);
  std::vector<std::thread> t;
  std::vector<double> r(threads);
  for (int i = 0; i < threads; ++i) t.emplace_back([&, i] { r[i] = run(mb); });
  for (auto& x : t) x.join();
  for (double v : r) std::printf("%.2f ns per miss (16 in flight)  ", v);
  std::puts("");
}

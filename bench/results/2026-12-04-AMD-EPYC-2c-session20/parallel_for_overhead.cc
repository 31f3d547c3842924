#include <chrono>
#include <cstdio>
#include <vector>

#include "concurrency/worker_pool.h"
int main(int argc, char** argv) {
  int threads = atoi(argv[1]);
  long serial_ns = atol(argv[2]);  // serial work between loops
  grove::WorkerPool pool(threads);
  std::vector<double> v(30000, 1.0), w(30000);
  const int loops = 20000;
  auto spin = [](long ns) {
    auto t = std::chrono::steady_clock::now();
    while (std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t).count() <
           ns) {
    }
  };
  auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < loops; ++k) {
    pool.ParallelFor(v.size(), 4096, [&](int, size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) w[i] = v[i] * 2;
    });
    spin(serial_ns);
  }
  double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("threads %d serial %ld ns: %.2f us per loop (incl serial)\n", threads, serial_ns,
              s / loops * 1e6);
}

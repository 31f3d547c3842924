// Ranks as threads of one process for tests of filters across ranks: OnRanks runs one body per
// rank, joined by InProcessCollective.
#ifndef GROVE_TESTS_API_RANKS_TESTING_H_
#define GROVE_TESTS_API_RANKS_TESTING_H_

#include <cstring>
#include <memory>
#include <thread>
#include <vector>

#include "grove/collective.h"

namespace grove::testing {

// Runs `body(rank, collective)` on each of `ranks` ranks as threads.
template <typename F>
void OnRanks(int ranks, F&& body) {
  std::vector<std::unique_ptr<Collective>> endpoints = InProcessCollective::Create(ranks);
  std::vector<std::thread> threads;
  for (int r = 0; r < ranks; ++r) {
    threads.emplace_back([&, r] { body(r, endpoints[static_cast<size_t>(r)].get()); });
  }
  for (std::thread& t : threads) t.join();
}

inline bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(a)) == 0; }

}  // namespace grove::testing

#endif  // GROVE_TESTS_API_RANKS_TESTING_H_

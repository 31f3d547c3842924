// A wandering test walk for the public-API tests: revisits, a 1 % odometry scale error, kept
// within about `radius_m` (12 m unless given) of the start.
#ifndef GROVE_TESTS_API_TEST_WALK_H_
#define GROVE_TESTS_API_TEST_WALK_H_

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace grove::testing {

struct Step {
  double t, dx, dy;
};

inline std::vector<Step> Walk(int n, uint64_t seed, double radius_m = 12) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> turn(0, 0.35);
  std::vector<Step> steps;
  double x = 0, y = 0, heading = 0;
  for (int k = 0; k < n; ++k) {
    heading += turn(rng);
    if (std::hypot(x, y) > radius_m && std::cos(heading - std::atan2(-y, -x)) < 0) heading += M_PI;
    double dx = 0.7 * std::cos(heading), dy = 0.7 * std::sin(heading);
    x += dx;
    y += dy;
    steps.push_back({0.5 * (k + 1), dx * 1.01, dy * 1.01});
  }
  return steps;
}

}  // namespace grove::testing

#endif  // GROVE_TESTS_API_TEST_WALK_H_

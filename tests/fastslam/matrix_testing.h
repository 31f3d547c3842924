// Random matrices and a relative matrix comparison for the landmark-math and sigma-point tests.
#ifndef GROVE_TESTS_FASTSLAM_MATRIX_TESTING_H_
#define GROVE_TESTS_FASTSLAM_MATRIX_TESTING_H_

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <random>

namespace grove::fastslam {

// A random symmetric positive definite matrix: scale (A A^T + 0.2 I), A standard normal.
template <int N>
inline Eigen::Matrix<double, N, N> RandomSpd(std::mt19937_64& rng, double scale) {
  std::normal_distribution<double> normal(0, 1);
  Eigen::Matrix<double, N, N> a;
  for (int i = 0; i < N; ++i) {
    for (int j = 0; j < N; ++j) a(i, j) = normal(rng);
  }
  return scale * (a * a.transpose() + 0.2 * Eigen::Matrix<double, N, N>::Identity());
}

// A matrix of independent N(0, scale^2) entries.
template <int R, int C>
inline Eigen::Matrix<double, R, C> RandomMatrix(std::mt19937_64& rng, double scale) {
  std::normal_distribution<double> normal(0, scale);
  Eigen::Matrix<double, R, C> a;
  for (int i = 0; i < R; ++i) {
    for (int j = 0; j < C; ++j) a(i, j) = normal(rng);
  }
  return a;
}

// |a - b| <= rel * max(1, |b|) in the Frobenius norm.
template <typename A, typename B>
::testing::AssertionResult MatrixNear(const A& a, const B& b, double rel) {
  const double err = (a - b).norm();
  const double bound = rel * std::max(1.0, b.norm());
  if (err <= bound) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "difference " << err << " > " << bound << "\nactual\n"
                                       << a << "\nexpected\n"
                                       << b;
}

}  // namespace grove::fastslam

#endif  // GROVE_TESTS_FASTSLAM_MATRIX_TESTING_H_

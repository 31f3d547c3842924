// The value of a read-out that returns StatusOr, for tests: a failure is reported, not fatal.
#ifndef GROVE_TESTS_API_STATUS_TESTING_H_
#define GROVE_TESTS_API_STATUS_TESTING_H_

#include <gtest/gtest.h>

#include <utility>

#include "grove/status.h"

namespace grove {

template <typename T>
T ValueOf(StatusOr<T> s) {
  if (!s.ok()) {
    ADD_FAILURE() << s.status().ToString();
    return T{};
  }
  return std::move(s).value();
}

}  // namespace grove

#endif  // GROVE_TESTS_API_STATUS_TESTING_H_

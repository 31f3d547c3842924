/* Checks for the C API's tests (C99): each failure prints the file, line and what failed, and
 * exits; the checks cannot be compiled out. */
#ifndef GROVE_TESTS_API_C_CHECK_H_
#define GROVE_TESTS_API_C_CHECK_H_

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "grove/c_api.h"

#define CHECK(cond)                                                            \
  do {                                                                         \
    if (!(cond)) {                                                             \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
      exit(1);                                                                 \
    }                                                                          \
  } while (0)

/* Checks that `call` returns `expected`; on failure prints both and `message`. */
#define CHECK_STATUS_MSG(call, expected, message)                                             \
  do {                                                                                        \
    grove_status status_ = (call);                                                            \
    if (status_ != (expected)) {                                                              \
      fprintf(stderr, "%s:%d: %s returned %s, expected %s (%s)\n", __FILE__, __LINE__, #call, \
              grove_status_name(status_), grove_status_name(expected), (message));            \
      exit(1);                                                                                \
    }                                                                                         \
  } while (0)
#define CHECK_STATUS(call, expected) CHECK_STATUS_MSG(call, expected, "")

static inline int Contains(const char* text, const char* part) {
  return strstr(text, part) != NULL;
}

#endif /* GROVE_TESTS_API_C_CHECK_H_ */

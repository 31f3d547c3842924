/* CHECK and CHECK_STATUS_MSG for the C API's C tests: checks that cannot be compiled out, and a
 * status check that prints the call, both statuses and a message. Needs stdio.h, stdlib.h and
 * grove/c_api.h (grove_status_name). */
#ifndef GROVE_TESTS_API_C_CHECKS_H_
#define GROVE_TESTS_API_C_CHECKS_H_

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

#endif /* GROVE_TESTS_API_C_CHECKS_H_ */

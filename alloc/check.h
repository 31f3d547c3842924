// Internal invariant checks (mimalloc's three levels). Never used on user input: user input gets a
// Status.
//   GROVE_CHECK(cond)   cheap, always on: a broken invariant aborts with file:line.
//   GROVE_DCHECK(cond)  debug builds only.
//   GROVE_EXPENSIVE_CHECKS  defined in debug builds: whole-structure walks may run.
#ifndef GROVE_ALLOC_CHECK_H_
#define GROVE_ALLOC_CHECK_H_

#include <cstdio>
#include <cstdlib>

#define GROVE_CHECK(cond)                                                                 \
  do {                                                                                    \
    if (!(cond)) [[unlikely]] {                                                           \
      std::fprintf(stderr, "%s:%d: GROVE_CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
      std::abort();                                                                       \
    }                                                                                     \
  } while (0)

#ifdef NDEBUG
#define GROVE_DCHECK(cond) \
  do {                     \
  } while (0)
#else
#define GROVE_DCHECK(cond) GROVE_CHECK(cond)
#define GROVE_EXPENSIVE_CHECKS 1
#endif

#endif  // GROVE_ALLOC_CHECK_H_

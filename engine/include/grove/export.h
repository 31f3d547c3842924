// GROVE_EXPORT marks what the shared library exports: the public facade and the C API. grove is
// compiled with hidden visibility, so everything else (the engine's internals, Eigen, fmt,
// Highway code) stays out of libgrove.so's symbol table.
#ifndef GROVE_EXPORT_H_
#define GROVE_EXPORT_H_

#if defined(__cplusplus) && (defined(__GNUC__) || defined(__clang__))
#define GROVE_EXPORT [[gnu::visibility("default")]]
#elif defined(__GNUC__) || defined(__clang__)
#define GROVE_EXPORT __attribute__((visibility("default")))
#else
#define GROVE_EXPORT
#endif

#endif  // GROVE_EXPORT_H_

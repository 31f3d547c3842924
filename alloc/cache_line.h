// The padding that keeps per-worker state of two threads off one cache line: 128 bytes, two
// 64-byte lines, because adjacent-line prefetchers fetch lines in pairs (oneTBB's max_nfs_size).
// In alloc/, the lowest layer, so that the pools and concurrency/ share the one value.
#ifndef GROVE_ALLOC_CACHE_LINE_H_
#define GROVE_ALLOC_CACHE_LINE_H_

#include <cstddef>

namespace grove {

inline constexpr size_t kFalseSharingBytes = 128;

}  // namespace grove

#endif  // GROVE_ALLOC_CACHE_LINE_H_

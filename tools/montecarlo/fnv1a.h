// FNV-1a (64-bit), the digest `grove fastslam montecarlo` keys finished jobs by: of a scenario,
// of a filter configuration and of a job's CSV. Not cryptographic: it notices changes, not
// forgeries.
#ifndef GROVE_TOOLS_MONTECARLO_FNV1A_H_
#define GROVE_TOOLS_MONTECARLO_FNV1A_H_

#include <fmt/format.h>

#include <cstdint>
#include <string>
#include <string_view>

namespace grove::tools {

inline uint64_t Fnv1a(std::string_view text, uint64_t hash = 0xcbf29ce484222325ULL) {
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

// 16 hex digits.
inline std::string Hex16(uint64_t v) { return fmt::format("{:016x}", v); }

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_FNV1A_H_

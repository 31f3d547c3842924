// The memory budget every command checks its prediction against before it starts any work
// (`grove footslam run`, `fastslam run`, `victoria-park`, `batch`, `fastslam montecarlo`):
// --memory-budget when given, else what this process may still use. A refusal exits with
// kExitMemory (6) and has one wording for every command.
#ifndef GROVE_TOOLS_RUN_MEMORY_BUDGET_H_
#define GROVE_TOOLS_RUN_MEMORY_BUDGET_H_

#include <cstdint>
#include <string>
#include <string_view>

#include "grove/status.h"

namespace grove::tools {

// The fixed part of a grove process (the binary, its libraries, oneTBB's and jemalloc's arenas,
// the engine's pools), which FootSlam::EstimatePeakBytes and FastSlam::EstimatePeakBytes each
// include once: jobs side by side count it once.
inline constexpr int64_t kProcessBaselineBytes = int64_t{48} << 20;

// Peak resident memory of this process, bytes.
int64_t PeakRssBytes();

// Parses a memory size: a number of bytes with an optional binary suffix K, M, G or T
// ("512M", "1.5G", "1073741824"). InvalidArgument naming the text otherwise.
StatusOr<int64_t> ParseMemorySize(const std::string& text);

// The memory this process may still use: the smallest of MemAvailable, the address-space
// limit (RLIMIT_AS) less what is mapped now, and the cgroup's memory.max less its
// memory.current; 0 when none can be read. *source names the limit that won.
int64_t AvailableMemoryBytes(std::string* source = nullptr);

struct MemoryBudget {
  int64_t bytes = 0;                       // 0: not known (nothing is refused)
  std::string source = "--memory-budget";  // what set it, for messages and summary.json

  // `requested_bytes` (--memory-budget; 0: not given), else AvailableMemoryBytes().
  static MemoryBudget Of(int64_t requested_bytes);

  // ResourceExhausted "the run is predicted to need P MiB (WHAT), more than the SOURCE of
  // B MiB; ADVICE" when `predicted_bytes` exceeds the budget; Ok otherwise.
  Status Check(int64_t predicted_bytes, std::string_view what, std::string_view advice) const;
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_RUN_MEMORY_BUDGET_H_

#include "tools/run/memory_budget.h"

#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>

namespace grove::tools {
namespace {

int64_t ReadCgroupValue(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  if (!(in >> text) || text == "max") return -1;
  int64_t v = -1;
  auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  return ec == std::errc() ? v : -1;
}

}  // namespace

int64_t PeakRssBytes() {
  struct rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<int64_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

StatusOr<int64_t> ParseMemorySize(const std::string& text) {
  double value = 0;
  const char* begin = text.data();
  const char* end = begin + text.size();
  auto [ptr, ec] = std::from_chars(begin, end, value);
  double scale = 1;
  if (ec == std::errc() && ptr + 1 == end) {
    switch (*ptr) {
      case 'K':
      case 'k':
        scale = 1024.0;
        break;
      case 'M':
      case 'm':
        scale = 1024.0 * 1024;
        break;
      case 'G':
      case 'g':
        scale = 1024.0 * 1024 * 1024;
        break;
      case 'T':
      case 't':
        scale = 1024.0 * 1024 * 1024 * 1024;
        break;
      default:
        ec = std::errc::invalid_argument;
    }
  } else if (ptr != end) {
    ec = std::errc::invalid_argument;
  }
  double bytes = value * scale;
  if (ec != std::errc() || !std::isfinite(bytes) || bytes < 1 || bytes > 9.0e18) {
    return InvalidArgumentError(
        fmt::format("--memory-budget = {}: must be a size such as 512M, 8G or 1073741824",
                    QuoteForMessage(text)));
  }
  return static_cast<int64_t>(bytes);
}

int64_t AvailableMemoryBytes(std::string* source) {
  int64_t best = 0;
  auto consider = [&](int64_t bytes, const char* what) {
    if (bytes < 0) return;
    if (best == 0 || bytes < best) {
      best = std::max<int64_t>(bytes, 1);
      if (source != nullptr) *source = what;
    }
  };
  {
    std::ifstream meminfo("/proc/meminfo");
    std::string key, unit;
    int64_t kib = 0;
    while (meminfo >> key >> kib >> unit) {
      if (key == "MemAvailable:") consider(kib * 1024, "memory available");
    }
  }
  struct rlimit limit;
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
    std::ifstream statm("/proc/self/statm");
    int64_t pages = 0;
    statm >> pages;
    consider(static_cast<int64_t>(limit.rlim_cur) - pages * sysconf(_SC_PAGESIZE),
             "address-space limit (ulimit -v)");
  }
  {
    // cgroup v2: the process's own group, "0::/path".
    std::ifstream cgroup("/proc/self/cgroup");
    std::string line;
    while (std::getline(cgroup, line)) {
      if (line.rfind("0::", 0) != 0) continue;
      const std::string dir = "/sys/fs/cgroup" + line.substr(3);
      const int64_t max = ReadCgroupValue(dir + "/memory.max");
      const int64_t current = ReadCgroupValue(dir + "/memory.current");
      if (max >= 0 && current >= 0) consider(max - current, "cgroup memory limit");
    }
  }
  return best;
}

MemoryBudget MemoryBudget::Of(int64_t requested_bytes) {
  MemoryBudget b;
  b.bytes = requested_bytes > 0 ? requested_bytes : AvailableMemoryBytes(&b.source);
  return b;
}

Status MemoryBudget::Check(int64_t predicted_bytes, std::string_view what,
                           std::string_view advice) const {
  if (bytes <= 0 || predicted_bytes <= bytes) return Status::Ok();
  return ResourceExhaustedError(
      fmt::format("the run is predicted to need {:.1f} MiB ({}), more than the {} of {:.1f} MiB; "
                  "{}",
                  predicted_bytes / 1048576.0, what, source, bytes / 1048576.0, advice));
}

}  // namespace grove::tools

#include "tools/bench/bench_process.h"

#include <fmt/format.h>

#include <fstream>
#include <thread>

#include "grove/version.h"

namespace grove::tools {

int64_t CurrentRssBytes() {
  std::ifstream statm("/proc/self/statm");
  int64_t size = 0, resident = 0;
  statm >> size >> resident;
  return resident * sysconf(_SC_PAGESIZE);
}

std::string MachineDescription() {
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  }
  long pages = sysconf(_SC_PHYS_PAGES);
  double gib = static_cast<double>(pages) * sysconf(_SC_PAGESIZE) / (1024.0 * 1024 * 1024);
  return fmt::format("{}, {} hardware threads, {:.0f} GiB memory; {}", model,
                     std::thread::hardware_concurrency(), gib, VersionString());
}

std::string CommandLine() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::string line, arg;
  for (bool first = true; std::getline(in, arg, '\0'); first = false) {
    if (first) {
      line = arg.substr(arg.rfind('/') + 1);  // npos + 1 == 0
      continue;
    }
    line += ' ';
    if (!arg.empty() && arg.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                              "0123456789_-+=.,:/@%") == std::string::npos) {
      line += arg;
      continue;
    }
    line += '\'';
    for (char c : arg) {
      if (c == '\'') {
        line += "'\\''";
      } else {
        line += c;
      }
    }
    line += '\'';
  }
  return line;
}

double CpuSeconds(const rusage& usage) {
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

}  // namespace grove::tools

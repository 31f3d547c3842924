// What every `grove bench` command needs of its own process: the machine's description, CPU
// times, the resident set, and a run in a child process whose peak memory is its own.
#ifndef GROVE_TOOLS_BENCH_BENCH_PROCESS_H_
#define GROVE_TOOLS_BENCH_BENCH_PROCESS_H_

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

namespace grove::tools {

// Resident set size now, from /proc/self/statm (pages).
int64_t CurrentRssBytes();

// The CPU model, hardware threads, memory and grove's version, one line.
std::string MachineDescription();

// User plus system CPU time, in seconds.
double CpuSeconds(const rusage& usage);

// This process's command line, as a shell would take it back: the program's file name, then
// each argument (quoted when it needs to be).
std::string CommandLine();

// Runs `body` in a child process so that its memory (peak RSS) is its own; the child writes its
// result to `result_path`. Returns the child's exit status (-1 when a signal ended it);
// *cpu_s (when given) receives the child's CPU time, user and system, summed over its threads,
// and *peak_rss_bytes (when given) its peak resident set.
template <typename F>
int InChild(F&& body, double* cpu_s = nullptr, int64_t* peak_rss_bytes = nullptr) {
  std::fflush(nullptr);
  pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) _exit(body());
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  if (cpu_s != nullptr) *cpu_s = CpuSeconds(usage);
  if (peak_rss_bytes != nullptr) *peak_rss_bytes = int64_t{usage.ru_maxrss} * 1024;  // KiB
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace grove::tools

#endif  // GROVE_TOOLS_BENCH_BENCH_PROCESS_H_

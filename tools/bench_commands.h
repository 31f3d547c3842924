// `grove bench paper` and `grove bench scaling`: the paper's run-time and memory figures
// (Garcia Puyol et al., Figs. 9 and 10) and throughput across cores and particle counts.
#ifndef GROVE_TOOLS_BENCH_COMMANDS_H_
#define GROVE_TOOLS_BENCH_COMMANDS_H_

#include <cstdint>
#include <string>

namespace grove::tools {

struct PaperBenchOptions {
  std::string out_dir;
  int64_t particles = 30000;
  double minutes = 13;         // length of the simulated open-area walk
  int threads = 0;             // 0: all cores
  double naive_limit_s = 180;  // the naive run stops after this much run time
  std::string only;            // run only the configuration with this name (empty: all)
};
int PaperBenchCommand(const PaperBenchOptions& options);

struct ScalingBenchOptions {
  std::string out_dir;
  int64_t steps = 300;  // first steps of the paper walk used for every point
  int64_t max_particles = 1000000;
  int64_t thread_sweep_particles = 30000;
};
int ScalingBenchCommand(const ScalingBenchOptions& options);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_BENCH_COMMANDS_H_

// A benchmark of a filter on the user's own input (`grove bench footslam`, `bench fastslam`):
// every (particles, threads) pair run `repeat` times, each run in a fresh child process, and the
// filter's time of each run (FilterSummary::filter_s(), the filter_time_s of a `run` command's
// summary.json) reported per pair as median, min and max, with throughput and the speed-up
// against the smallest thread count beside the ideal (linear) one.
//
// Why a child process per run: a run of `grove footslam run` is one process, whose node pools
// and allocator start empty; a run in a process that has already run others would reuse their
// memory, so the first run of a pair and the later ones would measure different things. The
// input is read once, before the first fork, and the children share it.
//
// Outputs, written as one set (tools/io/output_set.h) when every run has succeeded:
//   bench.md          the header (machine, grove version, command line, input) and the table
//                     (also printed on stdout)
//   bench.csv         one row per run
//   bench_summary.csv one row per pair: the table's figures, unrounded
//   threads.png       speed-up against threads, a line per particle count and the ideal one
//   particles.png     time per step against particles (when more than one count ran)
//   summary.json      the pairs, the configuration, the machine and the manifest
#ifndef GROVE_TOOLS_BENCH_SWEEP_BENCH_H_
#define GROVE_TOOLS_BENCH_SWEEP_BENCH_H_

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "grove/status.h"
#include "grove/types.h"

namespace grove::tools {

// What the command line asks of the sweep.
struct SweepBenchOptions {
  std::string out_dir;
  std::vector<int64_t> particles;   // each runs at every thread count; not empty
  std::vector<int64_t> threads;     // empty: DefaultThreadCounts()
  int repeat = 3;                   // runs per pair
  int64_t memory_budget_bytes = 0;  // 0: the memory available
};

// 1, 2, 4, ... below the CPUs this process may use (UsableCpus()), then that count.
std::vector<int64_t> DefaultThreadCounts();

// What a model gives the sweep.
struct SweepBenchModel {
  std::string command;  // "footslam": the report's title is "grove bench footslam"
  std::string input;    // what bench.md's header says of the input (Markdown)
  // The configuration of every run but its particles and threads (ConfigToJson), and the
  // model's defaults: bench.md names the fields that differ.
  std::string config_json, defaults_json;
  // The configuration's Validate() for a pair, before anything runs.
  std::function<Status(int64_t particles, int threads)> check;
  // Predicted peak bytes of one run of a pair (the memory budget's check).
  std::function<int64_t(int64_t particles, int threads)> predict_peak_bytes;
  // One run: a new engine of `particles` and `threads` fed the whole input; its summary.
  // Runs in the child process.
  std::function<StatusOr<FilterSummary>(int64_t particles, int threads)> run;
};

// Runs the sweep and writes its outputs. Returns the exit code after printing any error.
int RunSweepBench(const SweepBenchModel& model, const SweepBenchOptions& options);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_BENCH_SWEEP_BENCH_H_

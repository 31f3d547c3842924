// `grove fastslam montecarlo`: Monte Carlo runs of the landmark FastSLAM filters on the seed
// paper's simulations (Ankışhan et al., 2016, Section 4.1-4.3: Simulations I-III), written
// in the shape of its Tables 1 and 2 and Figures 3, 4, 6 and 8.
//
// Each (filter, particle count, run) is one job: run r simulates Bailey's vehicle with seed S + r
// and runs the filter (seed S + r, one thread) on it; after every control and scan it scores the
// weighted-mean pose against the truth, and after every scan it takes the pose NEES from
// FastSlam::PoseCovariance(). Jobs run in parallel (a tbb::task_arena of --threads); every
// result but the CPU time is the same at any thread count. A job writes
// DIR/runs/<filter>_p<particles>/run_<r>.csv and then run_<r>.json (each atomically); a later
// invocation into the same DIR reuses every job whose JSON matches its filter, particle count,
// seed, scenario digest and filter configuration digest and whose CSV has the size and hash the
// JSON records, so a killed command finishes on rerun. When all jobs are done it writes
// DIR/table.md, DIR/table.csv, DIR/summary.json and the charts (PNG and SVG): mse_position,
// mse_heading, boxplot_position, nees and, with more than one particle count, accuracy_vs_cpu.
#ifndef GROVE_TOOLS_MONTECARLO_FASTSLAM_MONTECARLO_H_
#define GROVE_TOOLS_MONTECARLO_FASTSLAM_MONTECARLO_H_

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "tools/montecarlo/monte_carlo_plan.h"
#include "tools/montecarlo/monte_carlo_scenario.h"

namespace grove::tools {

// Bounds of the options.
inline constexpr int64_t kMonteCarloMaxRuns = 100000;
inline constexpr int64_t kMonteCarloMaxParticles = int64_t{1} << 31;
inline constexpr int64_t kMonteCarloMaxThreads = 256;

struct MonteCarloOptions {
  std::string scenario;   // sim1, sim2, sim3 or FILE.json (ParseMonteCarloScenario)
  std::string filters;    // comma list of FastSlamFilterName names, each once
  std::string particles;  // comma list of counts in 1..2^31, each once; empty: PaperParticles
  int64_t runs = 0;       // Monte Carlo runs, 1..kMonteCarloMaxRuns
  std::string out_dir;
  std::string seed = "1";  // S, a non-negative integer: run r uses S + r (S + runs - 1 < 2^64)
  int64_t threads = 0;     // jobs in parallel, 0..kMonteCarloMaxThreads; 0: every hardware thread
  int64_t loops = 0;       // 0: the scenario's; else 1..kMonteCarloMaxLoops
  bool progress = true;    // progress on stderr
  // Refuse (exit 6, before any job) when the jobs run side by side are predicted to need more;
  // 0: the memory available (tools/run/memory_budget.h).
  int64_t memory_budget_bytes = 0;
  bool charts = true;  // not a flag: lets tests skip gnuplot
  // MPI ranks (tools/cli/mpi_world.h): job i runs on rank i % ranks, then rank 0 writes the
  // tables from the files every rank wrote (DIR on a file system they share). all_gather(mine)
  // returns every rank's string in rank order on every rank (collective). Unset: one rank.
  int rank = 0;
  int ranks = 1;
  std::function<std::vector<std::string>(const std::string&)> all_gather;
};

// Runs the command. Returns 0, or prints "grove: error: ..." and returns 2 (a bad option: it is
// named with its value; a bad scenario file's content), 3 (a scenario file or map that cannot be
// read or simulated), 4 (some job's filter failed: its run's status, counted in the tables; a
// rerun runs it again), 5 (the output directory or a file in it cannot be written, or another
// grove run holds DIR), 6 (the jobs that run side by side are predicted to need more memory
// than the budget, before any job; or a job ran out of memory) or 128 + the signal (SIGINT or
// SIGTERM: no further job started, the running ones abandoned, the finished ones kept).
int FastSlamMonteCarloCommand(const MonteCarloOptions& options);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_FASTSLAM_MONTECARLO_H_

// Running the jobs of `grove fastslam montecarlo`: which of them this invocation (and this rank)
// still has to run, and running those side by side, each writing its record
// (tools/montecarlo/job_record.h).
#ifndef GROVE_TOOLS_MONTECARLO_JOB_RUNNER_H_
#define GROVE_TOOLS_MONTECARLO_JOB_RUNNER_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "grove/status.h"
#include "tools/montecarlo/job_progress.h"
#include "tools/montecarlo/monte_carlo_plan.h"
#include "tools/montecarlo/monte_carlo_scenario.h"

namespace grove::tools {

// This rank's jobs (every `ranks`-th from job `rank`) that have no finished record in `dir`, as
// indices into plan.jobs: the costliest first (most particles), so that the last jobs to start
// are short; ties in job order. *own_jobs gets how many jobs are this rank's.
std::vector<size_t> JobsToRun(const std::string& dir, const MonteCarloScenario& scenario,
                              const MonteCarloPlan& plan, size_t rank, int ranks,
                              int64_t* own_jobs);

// Runs the jobs `todo` (indices into plan.jobs) on `threads` threads, each simulating its run
// and running its filter on one thread and writing its record into `dir`; tells `progress` of
// each. Stops at the first record that cannot be written and returns that error; a filter's
// failure is its record's status, not an error. A stop signal (tools/run/signal_policy.h)
// starts no further job and ends the running ones at their next scan, unrecorded.
Status RunMonteCarloJobs(const MonteCarloScenario& scenario, const MonteCarloPlan& plan,
                         const std::vector<size_t>& todo, int threads, const std::string& dir,
                         JobProgress* progress);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_JOB_RUNNER_H_

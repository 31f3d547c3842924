// The files one Monte Carlo job leaves: DIR/runs/<group>/run_<r>.csv (the estimate against the
// truth at every truth time) and then run_<r>.json (the job's figures, the digests it was made
// under and the CSV's size and hash), each written atomically; and reading them back, so that a
// later invocation reuses a finished job and the aggregates come from the files alone.
#ifndef GROVE_TOOLS_MONTECARLO_JOB_RECORD_H_
#define GROVE_TOOLS_MONTECARLO_JOB_RECORD_H_

#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "grove/status.h"
#include "grove/types.h"
#include "tools/montecarlo/monte_carlo_plan.h"
#include "tools/montecarlo/monte_carlo_scenario.h"
#include "tools/sim/fastslam_simulator.h"

namespace grove::tools {

// The filter's weighted-mean pose and pose covariance after the scan at t_s.
struct ScanSample {
  double t_s;
  Pose2 mean;
  Pose2Covariance covariance;
};

// What one job's simulation and filter gave: `status` is the filter's (or the simulator's)
// failure, recorded in the JSON, not an error of the command.
struct JobOutcome {
  Status status;
  std::vector<BaileyPose> truth;
  std::vector<StampedPose> trajectory;  // the weighted-mean pose after each step
  std::vector<ScanSample> scans;
  double cpu_s = std::numeric_limits<double>::quiet_NaN();  // the filter's thread CPU time
  int64_t steps = 0;                                        // filter steps
};

// "DIR/runs/<group>/run_<run>.<ext>".
std::string RunPath(const std::string& dir, const MonteCarloGroup& g, int64_t run, const char* ext);

// Writes the job's CSV, then its JSON (which says the job is complete). Returns the status of
// the writes.
Status WriteJobRecord(const std::string& dir, const MonteCarloScenario& scenario,
                      const MonteCarloGroup& group, const MonteCarloJob& job,
                      const JobOutcome& outcome);

// The job's JSON, when it exists, parses and belongs to this job under this scenario and
// configuration, and its CSV has the recorded size and hash; otherwise an error saying why.
// `csv_text` (may be null) gets the CSV. The job may have failed ("status" is not "ok"; then
// "status_code" names the failure's StatusCode).
StatusOr<nlohmann::json> ReadJobRecord(const std::string& dir, const MonteCarloScenario& scenario,
                                       const MonteCarloGroup& group, const MonteCarloJob& job,
                                       std::string* csv_text = nullptr);

// ReadJobRecord() of a job that succeeded: only those are finished, a later invocation runs a
// failed one again (FailedPrecondition for it).
StatusOr<nlohmann::json> ReadFinishedJob(const std::string& dir, const MonteCarloScenario& scenario,
                                         const MonteCarloGroup& group, const MonteCarloJob& job);

// The columns of a run's CSV that the aggregates need, one entry per truth row.
struct RunSeries {
  std::vector<double> t, e2, h2, nees;  // NaN: no estimate at that row / no NEES
  std::vector<uint8_t> scan;
};
StatusOr<RunSeries> ParseRunSeries(const std::string& path, std::string_view text);

// The number `key` holds in `j`, NaN when absent or not a number.
double JsonNumber(const nlohmann::json& j, const char* key);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_JOB_RECORD_H_

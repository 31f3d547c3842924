// Progress of `grove fastslam montecarlo`: jobs done out of the total, with an ETA from the jobs
// this invocation ran: one redrawn line on a terminal, otherwise a line at each new tenth.
#ifndef GROVE_TOOLS_MONTECARLO_JOB_PROGRESS_H_
#define GROVE_TOOLS_MONTECARLO_JOB_PROGRESS_H_

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <mutex>

namespace grove::tools {

// Thread safety: JobDone() may be called from any thread.
class JobProgress {
 public:
  // `total` jobs of which `reused` are done already; nothing is printed unless `enabled` and
  // some job is left to run.
  JobProgress(int64_t total, int64_t reused, bool enabled);

  void JobDone();
  // Ends a redrawn line.
  void Finish();

 private:
  using Clock = std::chrono::steady_clock;
  double Seconds() const;

  std::mutex mu_;
  const int64_t total_;
  int64_t done_;
  const int64_t reused_;
  const bool enabled_;
  const bool terminal_;
  const Clock::time_point start_;
  int64_t next_tenth_ = 1;
  double last_s_ = 0;
  size_t width_ = 0;
  bool drawn_ = false;
};

}  // namespace grove::tools

#endif  // GROVE_TOOLS_MONTECARLO_JOB_PROGRESS_H_

#include "tools/montecarlo/job_progress.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "tools/run/progress_reporter.h"

namespace grove::tools {

JobProgress::JobProgress(int64_t total, int64_t reused, bool enabled)
    : total_(total),
      done_(reused),
      reused_(reused),
      enabled_(enabled && total > reused),
      terminal_(::isatty(::fileno(stderr)) == 1),
      start_(Clock::now()) {
  if (total_ > 0) next_tenth_ = done_ * 10 / total_ + 1;
}

void JobProgress::JobDone() {
  std::lock_guard<std::mutex> lock(mu_);
  ++done_;
  if (!enabled_) return;
  const double elapsed = Seconds();
  const int64_t ran = done_ - reused_;
  const double eta = static_cast<double>(total_ - done_) * elapsed / static_cast<double>(ran);
  const int64_t percent = done_ * 100 / total_;
  if (terminal_) {
    if (drawn_ && elapsed - last_s_ < 0.1 && done_ < total_) return;
    last_s_ = elapsed;
    drawn_ = true;
    std::string line = fmt::format("montecarlo: jobs {}/{} ({}%)  elapsed {}  ETA {}", done_,
                                   total_, percent, FormatClock(elapsed), FormatClock(eta));
    if (line.size() < width_) line.append(width_ - line.size(), ' ');
    width_ = line.size();
    std::fprintf(stderr, "\r%s", line.c_str());
    std::fflush(stderr);
    return;
  }
  const int64_t tenth = done_ * 10 / total_;
  if (tenth >= next_tenth_) {
    next_tenth_ = tenth + 1;
    std::fprintf(stderr, "montecarlo: jobs %lld/%lld (%lld%%), ETA %s\n",
                 static_cast<long long>(done_), static_cast<long long>(total_),
                 static_cast<long long>(percent), FormatDuration(eta).c_str());
  }
}

void JobProgress::Finish() {
  std::lock_guard<std::mutex> lock(mu_);
  if (drawn_) std::fprintf(stderr, "\n");
  drawn_ = false;
}

double JobProgress::Seconds() const {
  return std::chrono::duration<double>(Clock::now() - start_).count();
}

}  // namespace grove::tools

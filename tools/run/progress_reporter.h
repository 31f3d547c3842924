// Progress of a long filter run, written to a terminal (one line redrawn with '\r') or to a log
// (plain lines, throttled).
#ifndef GROVE_TOOLS_RUN_PROGRESS_REPORTER_H_
#define GROVE_TOOLS_RUN_PROGRESS_REPORTER_H_

#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>

namespace grove::tools {

// Thread safety: none; call Update() and Finish() from one thread.
class ProgressReporter {
 public:
  // `is_terminal` comes from the caller (isatty(fileno(out))). `now_s` returns seconds on a
  // monotonic clock; empty means std::chrono::steady_clock. `out` must outlive the reporter.
  ProgressReporter(int64_t total_steps, int64_t particles, std::FILE* out, bool is_terminal,
                   std::function<double()> now_s = {});

  // Records that `steps_done` steps are complete. Redraws at most every 0.1 s on a terminal; on
  // other outputs prints a line at each new tenth of the run or after 5 s without a line.
  void Update(int64_t steps_done);
  // Prints the totals for the last value given to Update(): steps, particle-steps, time, rate.
  // Later calls do nothing.
  void Finish();

 private:
  double Now() const;
  std::string TerminalLine(double now) const;
  std::string PlainLine(double now) const;
  void Write(const std::string& text);

  int64_t total_steps_;
  int64_t particles_;
  std::FILE* out_;
  bool is_terminal_;
  std::function<double()> now_s_;
  double start_s_;
  int64_t steps_done_ = 0;
  double last_output_s_;
  int64_t next_tenth_ = 1;  // plain output: the next tenth of the run that gets a line
  size_t last_line_chars_ = 0;
  bool drawn_ = false;
  bool finished_ = false;
};

// "950", "12k", "6.8M", "1.2G": two significant digits below 10 of a unit, else whole units.
std::string FormatRate(double per_s);
// "0:03", "12:34", "1:02:03" (minutes:seconds, hours past an hour).
std::string FormatClock(double seconds);
// "12 s", "3 min 20 s", "1 h 02 min".
std::string FormatDuration(double seconds);

}  // namespace grove::tools

#endif  // GROVE_TOOLS_RUN_PROGRESS_REPORTER_H_

// The signal policy of every long command (`grove footslam run`, `fastslam run`,
// `victoria-park`, `batch`, `fastslam montecarlo`), written once: SIGINT and SIGTERM ask the
// command to stop at its next safe point (a step boundary, a job boundary) with what it finished
// kept, and it exits with 128 + the signal; a second one kills at once. SIGHUP (the terminal
// closed) only stops the progress output; SIGPIPE is ignored, so a closed stderr or stdout does
// not kill a command.
#ifndef GROVE_TOOLS_RUN_SIGNAL_POLICY_H_
#define GROVE_TOOLS_RUN_SIGNAL_POLICY_H_

#include <csignal>

namespace grove::tools {

// Installs the policy for the object's lifetime and restores the previous handlers after.
// Construction clears the stop and hangup flags.
class SignalHandlers {
 public:
  SignalHandlers();
  ~SignalHandlers();
  SignalHandlers(const SignalHandlers&) = delete;
  SignalHandlers& operator=(const SignalHandlers&) = delete;

 private:
  struct sigaction old_int_ = {}, old_term_ = {}, old_hup_ = {}, old_pipe_ = {};
};

// True when SIGINT or SIGTERM asked the command to stop; the signal (0: none); whether a
// SIGHUP came. Thread-safe.
bool StopRequested();
int StopSignal();
bool HangupSeen();

}  // namespace grove::tools

#endif  // GROVE_TOOLS_RUN_SIGNAL_POLICY_H_

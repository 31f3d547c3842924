#include "tools/run/signal_policy.h"

#include <atomic>

namespace grove::tools {
namespace {

// The signal that asked the command to stop (0: none), and whether the terminal went away. A
// signal handler may only store to lock-free atomics; the commands read them at their safe points.
std::atomic<int> g_stop_signal{0};
std::atomic<bool> g_hangup{false};
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free);

extern "C" void OnStopSignal(int signal) { g_stop_signal.store(signal, std::memory_order_relaxed); }
extern "C" void OnHangup(int) { g_hangup.store(true, std::memory_order_relaxed); }

}  // namespace

SignalHandlers::SignalHandlers() {
  g_stop_signal.store(0);
  g_hangup.store(false);
  struct sigaction stop = {};
  stop.sa_handler = OnStopSignal;
  sigemptyset(&stop.sa_mask);
  stop.sa_flags = SA_RESETHAND | SA_RESTART;  // interrupted reads and writes resume
  sigaction(SIGINT, &stop, &old_int_);
  sigaction(SIGTERM, &stop, &old_term_);
  struct sigaction hup = {};
  hup.sa_handler = OnHangup;
  sigemptyset(&hup.sa_mask);
  hup.sa_flags = SA_RESTART;
  sigaction(SIGHUP, &hup, &old_hup_);
  struct sigaction pipe = {};
  pipe.sa_handler = SIG_IGN;
  sigemptyset(&pipe.sa_mask);
  sigaction(SIGPIPE, &pipe, &old_pipe_);
}

SignalHandlers::~SignalHandlers() {
  sigaction(SIGINT, &old_int_, nullptr);
  sigaction(SIGTERM, &old_term_, nullptr);
  sigaction(SIGHUP, &old_hup_, nullptr);
  sigaction(SIGPIPE, &old_pipe_, nullptr);
}

bool StopRequested() { return g_stop_signal.load(std::memory_order_relaxed) != 0; }
int StopSignal() { return g_stop_signal.load(std::memory_order_relaxed); }
bool HangupSeen() { return g_hangup.load(std::memory_order_relaxed); }

}  // namespace grove::tools

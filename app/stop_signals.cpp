// SPDX-License-Identifier: BSD-3-Clause
// SIGINT, SIGTERM and SIGHUP during `ukdyn run` and `ukdyn sweep`; SIGPIPE and SIGXFSZ ignored
// (stop_signals.hpp).
#include "stop_signals.hpp"

#include <atomic>
#include <csignal>

#include <signal.h>

namespace ukdyn::cli {
namespace {

// the first signal received (0: none); lock-free, so the handler may write it
std::atomic<int> g_received{0};
static_assert(std::atomic<int>::is_always_lock_free);

// the signals that stop a run, and their dispositions before StopSignals
constexpr int kStopSignals[] = {SIGINT, SIGTERM, SIGHUP};
struct sigaction g_previous[std::size(kStopSignals)];

// the first signal is remembered (the run stops at its next step); a second one takes the
// default action at once: the handler runs with the signal blocked, so it is delivered again,
// now with the default disposition, as the handler returns
extern "C" void on_stop_signal(int sig) {
  int none = 0;
  if (g_received.compare_exchange_strong(none, sig)) return;
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  ::sigaction(sig, &dfl, nullptr);
  ::raise(sig);
}

}  // namespace

void ignore_output_signals() {
  // a console that went away (EPIPE) or a file-size limit (EFBIG) become errors of the write
  // that met them, never the end of the process with its results unwritten
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  ::sigaction(SIGPIPE, &ignore, nullptr);
  ::sigaction(SIGXFSZ, &ignore, nullptr);
}

StopSignals::StopSignals() {
  g_received = 0;
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // interrupted system calls (writes, waitpid) go on
  // a signal ignored when the program started (nohup, a background job of a script) stays so
  for (std::size_t k = 0; k < std::size(kStopSignals); ++k) {
    ::sigaction(kStopSignals[k], nullptr, &g_previous[k]);
    if (g_previous[k].sa_handler != SIG_IGN) ::sigaction(kStopSignals[k], &action, nullptr);
  }
}

StopSignals::~StopSignals() {
  for (std::size_t k = 0; k < std::size(kStopSignals); ++k) {
    ::sigaction(kStopSignals[k], &g_previous[k], nullptr);
  }
}

int StopSignals::received() { return g_received.load(std::memory_order_relaxed); }

const char* StopSignals::name(int sig) {
  switch (sig) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "a signal";
  }
}

}  // namespace ukdyn::cli

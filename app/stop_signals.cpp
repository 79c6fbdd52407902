// SIGINT and SIGTERM during `ukdyn run` (stop_signals.hpp).
#include "stop_signals.hpp"

#include <atomic>
#include <csignal>
#include <utility>

#include <signal.h>

namespace ukdyn::cli {
namespace {

// the first signal received (0: none); lock-free, so the handler may write it
std::atomic<int> g_received{0};
static_assert(std::atomic<int>::is_always_lock_free);

struct sigaction g_previous_int, g_previous_term;

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

StopSignals::StopSignals() {
  g_received = 0;
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // interrupted system calls (writes, waitpid) go on
  // a signal ignored when the program started (nohup, a background job of a script) stays so
  for (auto [sig, previous] : {std::pair{SIGINT, &g_previous_int}, {SIGTERM, &g_previous_term}}) {
    ::sigaction(sig, nullptr, previous);
    if (previous->sa_handler != SIG_IGN) ::sigaction(sig, &action, nullptr);
  }
}

StopSignals::~StopSignals() {
  ::sigaction(SIGINT, &g_previous_int, nullptr);
  ::sigaction(SIGTERM, &g_previous_term, nullptr);
}

int StopSignals::received() { return g_received.load(std::memory_order_relaxed); }

const char* StopSignals::name(int sig) {
  switch (sig) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "a signal";
  }
}

}  // namespace ukdyn::cli

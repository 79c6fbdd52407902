// SIGINT and SIGTERM during `ukdyn run`: the first asks the simulation to stop at its next step
// (SimulationOptions::should_stop), after which everything computed is written; a second one
// ends the program at once (the signal's default action). README.md, "The ukdyn command".
#pragma once

namespace ukdyn::cli {

/// Installs the handlers of SIGINT and SIGTERM for its lifetime (the previous ones come back
/// when it is destroyed). One at a time.
class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  /// The first signal received (SIGINT or SIGTERM), 0 when none. Async-signal-safe to read.
  static int received();
  /// "SIGINT", "SIGTERM" ("a signal" for another).
  static const char* name(int sig);
};

}  // namespace ukdyn::cli

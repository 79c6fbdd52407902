// SPDX-License-Identifier: BSD-3-Clause
// SIGINT, SIGTERM and SIGHUP during `ukdyn run` and `ukdyn sweep`: the first asks the simulation
// to stop at its next step (SimulationOptions::should_stop), after which everything computed is
// written; a second one ends the program at once (the signal's default action). SIGPIPE and
// SIGXFSZ are ignored for the whole program. README.md, "The ukdyn command".
#pragma once

namespace ukdyn::cli {

/// Ignores SIGPIPE and SIGXFSZ for the rest of the program: a console or log reader that went
/// away (`ukdyn run … | head -1`, `| tee log` ended by Ctrl-C) gives EPIPE, and a file-size limit
/// (`ulimit -f`) EFBIG, to the write that met it — the console line is lost, a file's write is
/// the usual "cannot write" error — instead of killing the program before its files are written.
/// Child processes get both back at their defaults (run_program).
void ignore_output_signals();

/// Installs the handlers of SIGINT, SIGTERM and SIGHUP (a closed terminal or ssh session) for
/// its lifetime (the previous ones come back when it is destroyed); a signal ignored when the
/// program started (nohup) stays ignored. One at a time.
class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  /// The first signal received (SIGINT, SIGTERM or SIGHUP), 0 when none. Async-signal-safe to
  /// read.
  static int received();
  /// "SIGINT", "SIGTERM", "SIGHUP" ("a signal" for another).
  static const char* name(int sig);
};

}  // namespace ukdyn::cli

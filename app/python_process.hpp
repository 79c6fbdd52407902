// SPDX-License-Identifier: BSD-3-Clause
// The command's Python helpers (the plots, the viewer's page, the sweep's summary plot) run as
// child processes of Debian's python3: one place that finds the interpreter and runs it.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <sys/types.h>

namespace ukdyn::cli {

/// The interpreter the command runs its Python scripts with: $UKDYN_PYTHON when set and not
/// empty, else /usr/bin/python3 (Debian's, with matplotlib; never the first python3 on PATH).
std::string python_interpreter();

/// Whether `program` exists and is executable.
bool is_executable(const std::string& program);

/// Runs args[0] with the arguments args (posix_spawn, the environment inherited) and waits for
/// it; its exit status, or −1 when it could not start or did not exit normally.
int run_program(std::vector<std::string> args);

/// A program started now and told later whether to go on: args[0] with the arguments args
/// (posix_spawn, the environment inherited), its standard input a pipe that finish() writes a
/// line to and closes; destroyed without finish(), the pipe is closed with nothing written (end
/// of file: the program is to leave without doing its work) and the program waited for. The
/// command starts its plot script so before the simulation, so that the script's imports (about
/// half a second of Python, NumPy and matplotlib) overlap the run instead of following it.
/// SIGINT, SIGTERM and SIGHUP are blocked in the program (a Ctrl-C asks the command's run to
/// stop and have what it computed written, plots included; a second one ends the command, and
/// the program then sees the end of its input, or finishes the plots it was given).
class StartedProgram {
 public:
  explicit StartedProgram(std::vector<std::string> args);
  ~StartedProgram();
  StartedProgram(const StartedProgram&) = delete;
  StartedProgram& operator=(const StartedProgram&) = delete;

  /// Whether the program could be started.
  bool started() const { return pid_ > 0; }
  /// Writes `line` and a newline to the program's input, closes it and waits for the program:
  /// its exit status, or −1 when it was not started or did not exit normally.
  int finish(std::string_view line);

 private:
  int wait();

  pid_t pid_ = -1;  // the program (−1: not started, or waited for)
  int input_ = -1;  // the writing end of its standard input (−1: closed)
};

}  // namespace ukdyn::cli

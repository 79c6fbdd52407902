// SPDX-License-Identifier: BSD-3-Clause
// The command's Python helpers (the plots, the viewer's page, the sweep's summary plot) run as
// child processes of Debian's python3: one place that finds the interpreter and runs it.
#pragma once

#include <string>
#include <vector>

namespace ukdyn::cli {

/// The interpreter the command runs its Python scripts with: $UKDYN_PYTHON when set and not
/// empty, else /usr/bin/python3 (Debian's, with matplotlib; never the first python3 on PATH).
std::string python_interpreter();

/// Whether `program` exists and is executable.
bool is_executable(const std::string& program);

/// Runs args[0] with the arguments args (posix_spawn, the environment inherited) and waits for
/// it; its exit status, or −1 when it could not start or did not exit normally.
int run_program(std::vector<std::string> args);

}  // namespace ukdyn::cli

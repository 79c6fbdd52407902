// SPDX-License-Identifier: BSD-3-Clause
// The command's Python helpers as child processes (app/python_process.hpp).
#include "python_process.hpp"

#include <cerrno>
#include <csignal>
#include <cstdlib>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace ukdyn::cli {

std::string python_interpreter() {
  const char* env = std::getenv("UKDYN_PYTHON");
  return env && *env ? env : "/usr/bin/python3";
}

bool is_executable(const std::string& program) { return ::access(program.c_str(), X_OK) == 0; }

int run_program(std::vector<std::string> args) {
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  // the child gets SIGPIPE and SIGXFSZ at their defaults (the command ignores them; an ignored
  // signal stays ignored across exec)
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t defaults;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGPIPE);
  sigaddset(&defaults, SIGXFSZ);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], nullptr, &attr, argv.data(), environ);
  posix_spawnattr_destroy(&attr);
  if (rc != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace ukdyn::cli

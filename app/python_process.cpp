// SPDX-License-Identifier: BSD-3-Clause
// The command's Python helpers as child processes (app/python_process.hpp).
#include "python_process.hpp"

#include <cerrno>
#include <csignal>
#include <cstdlib>

#include <fcntl.h>

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

namespace {

// Starts args[0] with the arguments args (posix_spawn, the environment inherited), SIGPIPE and
// SIGXFSZ at their defaults in the child (the command ignores them; an ignored signal stays
// ignored across exec) and, with `block_stops`, SIGINT, SIGTERM and SIGHUP blocked; the child's
// pid, or −1 when it could not start.
pid_t spawn(std::vector<std::string>& args, const posix_spawn_file_actions_t* files,
            bool block_stops) {
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t defaults, blocked;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGPIPE);
  sigaddset(&defaults, SIGXFSZ);
  sigemptyset(&blocked);
  sigaddset(&blocked, SIGINT);
  sigaddset(&blocked, SIGTERM);
  sigaddset(&blocked, SIGHUP);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  short flags = POSIX_SPAWN_SETSIGDEF;
  if (block_stops) {
    posix_spawnattr_setsigmask(&attr, &blocked);
    flags |= POSIX_SPAWN_SETSIGMASK;
  }
  posix_spawnattr_setflags(&attr, flags);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], files, &attr, argv.data(), environ);
  posix_spawnattr_destroy(&attr);
  return rc == 0 ? pid : -1;
}

// Waits for the child `pid` (through EINTR): its exit status, or −1 when it did not exit
// normally or could not be waited for.
int wait_exit(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

int run_program(std::vector<std::string> args) {
  const pid_t pid = spawn(args, nullptr, false);
  return pid > 0 ? wait_exit(pid) : -1;
}

StartedProgram::StartedProgram(std::vector<std::string> args) {
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) return;  // (close-on-exec: no other child inherits them)
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_adddup2(&files, ends[0], STDIN_FILENO);  // (dup2 clears cloexec)
  const pid_t pid = spawn(args, &files, true);
  posix_spawn_file_actions_destroy(&files);
  ::close(ends[0]);
  if (pid <= 0) {
    ::close(ends[1]);
    return;
  }
  pid_ = pid;
  input_ = ends[1];
}

StartedProgram::~StartedProgram() {
  if (input_ >= 0) ::close(input_);
  input_ = -1;
  wait();
}

int StartedProgram::finish(std::string_view line) {
  if (!started()) return -1;
  std::string text(line);
  text += '\n';
  // (SIGPIPE is ignored: a program that already left gives EPIPE here, and its status below)
  for (std::size_t at = 0; at < text.size();) {
    const ssize_t n = ::write(input_, text.data() + at, text.size() - at);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    at += std::size_t(n);
  }
  ::close(input_);
  input_ = -1;
  return wait();
}

int StartedProgram::wait() {
  if (pid_ <= 0) return -1;
  const pid_t pid = pid_;
  pid_ = -1;
  return wait_exit(pid);
}

}  // namespace ukdyn::cli

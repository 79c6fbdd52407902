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

StartedProgram::StartedProgram(std::vector<std::string> args) {
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) return;  // (close-on-exec: no other child inherits them)
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_adddup2(&files, ends[0], STDIN_FILENO);  // (dup2 clears cloexec)
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
  posix_spawnattr_setsigmask(&attr, &blocked);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &files, &attr, argv.data(), environ);
  posix_spawnattr_destroy(&attr);
  posix_spawn_file_actions_destroy(&files);
  ::close(ends[0]);
  if (rc != 0) {
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
  int status = 0;
  const pid_t pid = pid_;
  pid_ = -1;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace ukdyn::cli

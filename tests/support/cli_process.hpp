// SPDX-License-Identifier: BSD-3-Clause
// Helpers of the tests that run the `ukdyn` command as a process (simulation/test_interrupt.cpp,
// simulation/test_stream.cpp): a fresh scratch directory, a file's text, and Command, a `ukdyn`
// process with stdout to a file and stderr read through a pipe. The including target defines
// UKDYN_CLI, the path of the built program.
#pragma once

#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#ifndef UKDYN_CLI
#error "define UKDYN_CLI, the path of the ukdyn program, to use cli_process.hpp"
#endif

extern char** environ;

namespace ukdyn::test {

namespace fs = std::filesystem;

/// A fresh, empty directory `<temp>/<prefix><name>.<pid>` for one test (the pid makes it unique:
/// test runs of other trees may share the temp directory).
inline fs::path scratch_directory(const std::string& prefix, const std::string& name) {
  const fs::path dir =
      fs::path(::testing::TempDir()) / (prefix + name + "." + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// The whole content of a file ("" when it cannot be read).
inline std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A `ukdyn run` process: stdout to a file, stderr read through a pipe.
class Command {
  using Clock = std::chrono::steady_clock;

 public:
  explicit Command(const std::vector<std::string>& args, const fs::path& stdout_file) {
    std::vector<std::string> argv_s = {UKDYN_CLI};
    argv_s.insert(argv_s.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : argv_s) argv.push_back(a.data());
    argv.push_back(nullptr);
    // the progress log every 0.05 s (stderr is a pipe, not a terminal)
    std::vector<std::string> env_s = {"UKDYN_PROGRESS_INTERVAL=0.05"};
    for (char** e = environ; *e; ++e) {
      if (std::strncmp(*e, "UKDYN_PROGRESS_INTERVAL=", 24) != 0) env_s.emplace_back(*e);
    }
    std::vector<char*> env;
    for (auto& e : env_s) env.push_back(e.data());
    env.push_back(nullptr);

    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, stdout_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
    // (the child's SIGINT, SIGTERM and SIGHUP at their defaults, whatever the test runner set)
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    sigset_t defaults;
    sigemptyset(&defaults);
    sigaddset(&defaults, SIGINT);
    sigaddset(&defaults, SIGTERM);
    sigaddset(&defaults, SIGHUP);
    posix_spawnattr_setsigdefault(&attr, &defaults);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF);
    const int rc = posix_spawn(&pid_, argv[0], &actions, &attr, argv.data(), env.data());
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attr);
    ::close(fds[1]);
    err_ = fds[0];
    if (rc != 0) throw std::runtime_error(std::string("cannot start ") + UKDYN_CLI);
  }
  ~Command() {
    if (pid_ > 0 && !status_) {
      ::kill(pid_, SIGKILL);
      wait();
    }
    if (err_ >= 0) ::close(err_);
  }

  pid_t pid() const { return pid_; }
  const std::string& stderr_text() const { return stderr_; }

  // reads stderr until `text` appears (true) or the process closes it / the time runs out
  bool wait_for(const std::string& text, double seconds) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
    while (stderr_.find(text) == std::string::npos) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
      if (left.count() <= 0 || !read_some(int(left.count()))) return false;
    }
    return true;
  }

  // waits for the exit: the exit code, or 128 + the signal that ended it
  int wait() {
    while (read_some(-1)) {
    }
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return *status_;
  }

 private:
  // one read of stderr (timeout in ms, −1: none); false at its end
  bool read_some(int timeout_ms) {
    pollfd p{err_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return timeout_ms < 0 ? false : true;
    char buf[4096];
    const ssize_t got = ::read(err_, buf, sizeof buf);
    if (got <= 0) return false;
    stderr_.append(buf, std::size_t(got));
    return true;
  }

  pid_t pid_ = -1;
  int err_ = -1;
  std::string stderr_;
  std::optional<int> status_;
};

}  // namespace ukdyn::test

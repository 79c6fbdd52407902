// The command's Python helpers as child processes (app/python_process.hpp).
#include "python_process.hpp"

#include <cerrno>
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
  pid_t pid = 0;
  if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace ukdyn::cli

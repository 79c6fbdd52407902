// The output directory of `ukdyn run`: created, locked for the run, cleared of a previous run's
// files before this one's are written (output_dir.hpp).
#include "output_dir.hpp"

#include "commands.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <system_error>
#include "ukdyn/core/format.hpp"

namespace ukdyn::cli {
namespace fs = std::filesystem;
namespace {

constexpr const char* kLockFile = ".ukdyn.lock";

// the pid written in the lock file by the run that holds it ("" when unreadable or not yet
// written)
std::string holder_pid(int fd) {
  char text[32] = {};
  const ssize_t got = ::pread(fd, text, sizeof text - 1, 0);
  std::string pid(text, got > 0 ? std::size_t(got) : 0);
  while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
  return pid.find_first_not_of("0123456789") == std::string::npos ? pid : "";
}

}  // namespace

OutputDirectory::OutputDirectory(fs::path dir) : dir_(std::move(dir)) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) {
    throw std::runtime_error("cannot create the directory '" + dir_.string() +
                             "': " + ec.message());
  }
  const fs::path lock = dir_ / kLockFile;
  // (close-on-exec: the plot script must not inherit the lock)
  lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (lock_fd_ < 0) {
    throw std::runtime_error("cannot create the lock file '" + lock.string() +
                             "': " + std::strerror(errno));
  }
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    const std::string pid = err == EWOULDBLOCK ? holder_pid(lock_fd_) : "";
    ::close(lock_fd_);
    lock_fd_ = -1;
    if (err == EWOULDBLOCK) {
      throw DirectoryBusy("the output directory '" + dir_.string() +
                          "' is in use by another ukdyn run (" +
                          (pid.empty() ? std::string("pid unknown") : "pid " + pid) +
                          "); wait until it ends, or choose another directory with -o");
    }
    throw std::runtime_error("cannot lock '" + lock.string() + "': " + std::strerror(err));
  }
  // the holder's pid, for the message of a run refused
  const std::string pid = ukdyn::format_number(::getpid()) + "\n";
  if (::ftruncate(lock_fd_, 0) != 0 || ::pwrite(lock_fd_, pid.data(), pid.size(), 0) < 0) {
    // only the message of a refused run would miss it
  }
}

OutputDirectory::~OutputDirectory() {
  if (lock_fd_ >= 0) ::close(lock_fd_);  // drops the lock
}

void OutputDirectory::remove_previous_outputs() const {
  auto remove = [](const fs::path& file) {
    std::error_code ec;
    fs::remove(file, ec);
    if (ec) throw std::runtime_error("cannot remove '" + file.string() + "': " + ec.message());
  };
  for (const char* name : kRunOutputs) remove(dir_ / name);
  // temporaries of a run killed while writing: .NAME.tmp-…
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir_, ec)) {
    const std::string file = entry.path().filename().string();
    for (const char* name : kRunOutputs) {
      const std::string prefix = std::string(".") + name + ".tmp-";
      if (std::string_view(file).substr(0, prefix.size()) == prefix) remove(entry.path());
    }
  }
}

int hold_output_directory(const std::filesystem::path& dir, std::optional<OutputDirectory>& out) {
  try {
    out.emplace(dir);
  } catch (const DirectoryBusy& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBusy;
  } catch (const std::runtime_error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitRunFailed;
  }
  return 0;
}

}  // namespace ukdyn::cli

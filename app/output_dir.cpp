// SPDX-License-Identifier: BSD-3-Clause
// The output directory of `ukdyn run`: created, locked for the run, cleared of a previous run's
// files before this one's are written (output_dir.hpp).
#include "output_dir.hpp"

#include "commands.hpp"
#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
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

// what a file that is not a regular one is, for the message that refuses it
const char* kind_of(mode_t mode) {
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  return "not a regular file";
}

// "'PATH' is a symbolic link, not a regular file: …" as std::runtime_error
[[noreturn]] void refuse(const fs::path& path, mode_t mode, const char* what) {
  throw std::runtime_error("'" + path.string() + "' is " + kind_of(mode) +
                           ", not a regular file: ukdyn does not write its " + what +
                           " through it; remove it, or choose another directory with -o");
}

}  // namespace

OutputDirectory::OutputDirectory(fs::path dir, std::span<const char* const> outputs)
    : dir_(std::move(dir)), outputs_(outputs) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) {
    throw std::runtime_error("cannot create the directory '" + dir_.string() +
                             "': " + ec.message());
  }
  const fs::path lock = dir_ / kLockFile;
  // (close-on-exec: the plot script must not inherit the lock; no-follow: a symbolic link
  // planted under the lock's name is refused, not followed to a file it would truncate;
  // non-blocking: a FIFO planted there does not hang the open)
  lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0666);
  if (lock_fd_ < 0) {
    const int err = errno;
    struct stat info {};
    if (::lstat(lock.c_str(), &info) == 0 && !S_ISREG(info.st_mode)) {
      refuse(lock, info.st_mode, "lock");
    }
    throw std::runtime_error("cannot create the lock file '" + lock.string() +
                             "': " + std::strerror(err));
  }
  struct stat lock_info {};
  if (::fstat(lock_fd_, &lock_info) != 0 || !S_ISREG(lock_info.st_mode)) {
    ::close(lock_fd_);
    lock_fd_ = -1;
    refuse(lock, lock_info.st_mode, "lock");
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
  // an output name that is not a regular file: refused now, before anything is computed (a
  // FIFO would block the write at the end, a link would have its target replaced)
  for (const char* name : outputs_) {
    struct stat info {};
    if (::lstat((dir_ / name).c_str(), &info) == 0 && !S_ISREG(info.st_mode)) {
      ::close(lock_fd_);
      lock_fd_ = -1;
      refuse(dir_ / name, info.st_mode, "output");
    }
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
  for (const char* name : outputs_) remove(dir_ / name);
  // temporaries of a run killed while writing: .NAME.tmp-…
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir_, ec)) {
    const std::string file = entry.path().filename().string();
    for (const char* name : outputs_) {
      const std::string prefix = std::string(".") + name + ".tmp-";
      if (std::string_view(file).substr(0, prefix.size()) == prefix) remove(entry.path());
    }
  }
}

void write_text_file(const std::string& path, const std::string& text) {
  detail::write_whole_file(path, "ukdyn", text.data(), text.size());
}

int hold_output_directory(const std::filesystem::path& dir, std::span<const char* const> outputs,
                          std::optional<OutputDirectory>& out) {
  try {
    out.emplace(dir, outputs);
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

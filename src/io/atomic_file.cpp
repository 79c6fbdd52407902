// SPDX-License-Identifier: BSD-3-Clause
// Files written whole or not at all: a temporary in the same directory, renamed when complete
// (io/atomic_file.hpp).
#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>
#include "ukdyn/core/format.hpp"

namespace ukdyn::detail {
namespace {

namespace fs = std::filesystem;

// the process's umask, read without changing it (umask(2) would, for every thread): from
// /proc/self/status (Linux 4.7 and later), else the usual 022
mode_t process_umask() {
  mode_t mask = 022;
  if (std::FILE* f = std::fopen("/proc/self/status", "re")) {
    char line[256];
    while (std::fgets(line, sizeof line, f)) {
      unsigned value = 0;
      if (std::sscanf(line, "Umask: %o", &value) == 1) {
        mask = mode_t(value) & 0777;
        break;
      }
    }
    std::fclose(f);
  }
  return mask;
}

}  // namespace

AtomicFile::AtomicFile(std::string path, const char* who)
    : path_(std::move(path)), target_(path_), who_(who) {
  // a symbolic link: replace its target, not the link
  struct stat link_info {};
  if (::lstat(path_.c_str(), &link_info) == 0 && S_ISLNK(link_info.st_mode)) {
    std::error_code ec;
    const fs::path resolved = fs::weakly_canonical(path_, ec);
    if (!ec) target_ = resolved.string();
  }
  // an existing file that is not a regular one (a device, a FIFO, a directory): in place,
  // opened without blocking (a FIFO without a reader fails with ENXIO instead of waiting for
  // one), then blocking again for the writes
  struct stat info {};
  if (::stat(target_.c_str(), &info) == 0 && !S_ISREG(info.st_mode)) {
    in_place_ = true;
    write_path_ = target_;
    fd_ = ::open(write_path_.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC | O_NONBLOCK);
    if (fd_ < 0) fail("open", errno);
    const int flags = ::fcntl(fd_, F_GETFL);
    if (flags >= 0) ::fcntl(fd_, F_SETFL, flags & ~O_NONBLOCK);
    return;
  }
  // the temporary: .NAME.tmp-XXXXXX beside the target (mkostemp: an unpredictable name,
  // O_CREAT | O_EXCL, here also O_NOFOLLOW and close-on-exec)
  const fs::path target(target_);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path();
  write_path_ = (dir / ("." + target.filename().string() + ".tmp-XXXXXX")).string();
  fd_ = ::mkostemp(write_path_.data(), O_CLOEXEC | O_NOFOLLOW);
  if (fd_ < 0) {
    const int err = errno;
    write_path_.clear();
    fail("open", err);
  }
  // mkostemp's mode is 0600: the file gets the mode an ordinary creation would give it
  ::fchmod(fd_, 0666 & ~process_umask());
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!in_place_ && !committed_ && !write_path_.empty()) ::unlink(write_path_.c_str());
}

std::FILE* AtomicFile::open_stdio() {
  errno = 0;
  std::FILE* f = ::fdopen(fd_, "wb");
  if (!f) fail("open", errno);
  fd_ = -1;  // the stream owns it now
  return f;
}

void AtomicFile::release_descriptor() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void AtomicFile::commit() {
  release_descriptor();
  if (in_place_ || committed_) return;
  if (::rename(write_path_.c_str(), target_.c_str()) != 0) fail("replace", errno);
  committed_ = true;
}

void AtomicFile::fail(const char* doing, int err) const { throw_io_error(who_, path_, doing, err); }

void write_whole_file(const std::string& path, const char* who, const char* data,
                      std::size_t size) {
  AtomicFile out(path, who);
  std::unique_ptr<std::FILE, FileCloser> file(out.open_stdio());
  errno = 0;
  if (std::fwrite(data, 1, size, file.get()) != size) throw_io_error(who, path, "write", errno);
  // fclose writes what stdio still holds: its failure (a full disk) is a write error too
  errno = 0;
  if (std::fclose(file.release()) != 0) throw_io_error(who, path, "write", errno);
  out.commit();
}

void throw_io_error(const char* who, const std::string& path, const char* doing, int err) {
  throw std::runtime_error(std::string(who) + ": cannot " + doing + " '" + path +
                           "': " + (err != 0 ? std::strerror(err) : "unknown reason"));
}

}  // namespace ukdyn::detail

// Files written whole or not at all: a temporary in the same directory, renamed when complete
// (io/atomic_file.hpp).
#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include "ukdyn/core/format.hpp"

namespace ukdyn::detail {
namespace {

namespace fs = std::filesystem;

// distinguishes the temporaries of one process (threads may write at once)
std::atomic<unsigned long> g_counter{0};

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
  // an existing file that is not a regular one (a device, a FIFO, a directory): in place
  struct stat info {};
  if (::stat(target_.c_str(), &info) == 0 && !S_ISREG(info.st_mode)) {
    in_place_ = true;
    write_path_ = target_;
    return;
  }
  // the temporary: .NAME.tmp-PID-COUNT beside the target
  const fs::path target(target_);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path();
  for (int attempt = 0; attempt < 100; ++attempt) {
    const std::string name = "." + target.filename().string() + ".tmp-" +
                             format_number(::getpid()) + "-" + format_number(g_counter++);
    write_path_ = (dir / name).string();
    fd_ = ::open(write_path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd_ >= 0) return;
    if (errno != EEXIST) break;
  }
  fail("open", errno);
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!in_place_ && !committed_) ::unlink(write_path_.c_str());
}

std::FILE* AtomicFile::open_stdio() {
  errno = 0;
  if (in_place_) {
    std::FILE* f = std::fopen(write_path_.c_str(), "wb");
    if (!f) fail("open", errno);
    return f;
  }
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

void throw_io_error(const char* who, const std::string& path, const char* doing, int err) {
  throw std::runtime_error(std::string(who) + ": cannot " + doing + " '" + path +
                           "': " + (err != 0 ? std::strerror(err) : "unknown reason"));
}

}  // namespace ukdyn::detail

// SPDX-License-Identifier: BSD-3-Clause
// Internal: files written whole or not at all (the writers of io/trajectory_files.hpp). Not
// installed.
#pragma once

#include <cstdio>
#include <string>

namespace ukdyn::detail {

// A file written under a temporary name in the directory of its final path and renamed over
// that path by commit(), so that the final name never shows a partly written file: a run killed
// while writing leaves the previous file (or none) and a hidden temporary `.NAME.tmp-XXXXXX`,
// which nothing reads. The temporary is made by mkostemp(3): an unpredictable name, created
// with O_EXCL and O_NOFOLLOW (nothing planted under its name is followed or reused), then given
// the mode 0666 less the umask. Destroyed without commit() (an exception), it removes the
// temporary. A path that exists and is not a regular file (/dev/null, /dev/stdout) is opened in
// place — there is nothing to rename — without blocking: a FIFO that no process reads is the
// error "No such device or address", never a hang, and a directory "Is a directory". A symbolic
// link is followed to its target, which is replaced (the command line refuses links among its
// outputs before it runs: app/output_dir.hpp). No fsync: the guarantee is against killed
// processes, not against a power cut.
//
// Errors throw std::runtime_error "WHO: cannot open|write|replace 'PATH': REASON", naming the
// final path.
class AtomicFile {
 public:
  // creates the temporary (mkostemp, mode 0666 less the umask), or opens an in-place path
  AtomicFile(std::string path, const char* who);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // the name to write now: the temporary, or the path itself when written in place
  const std::string& write_path() const { return write_path_; }
  // a stdio stream on write_path() ("wb"), owned by the caller (fclose it before commit())
  std::FILE* open_stdio();
  // closes the descriptor of the temporary so that a library can open write_path() by name
  void release_descriptor();
  // renames the temporary over the final path (nothing when written in place)
  void commit();

  // "cannot DOING 'path': strerror(err)" as std::runtime_error
  [[noreturn]] void fail(const char* doing, int err) const;

 private:
  std::string path_;        // the final path, as given
  std::string target_;      // where the file goes (path_, or the target of a symbolic link)
  std::string write_path_;  // the temporary, or target_ in place
  const char* who_;
  int fd_ = -1;  // the file's descriptor until open_stdio / release_descriptor
  bool in_place_ = false;
  bool committed_ = false;
};

// Closes a stdio stream owned by a std::unique_ptr<std::FILE, FileCloser>.
struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

// Writes size bytes at data to `path` whole or not at all (an AtomicFile), errors as its.
void write_whole_file(const std::string& path, const char* who, const char* data, std::size_t size);

// "WHO: cannot DOING 'path': strerror(err)" as std::runtime_error (AtomicFile::fail's message)
[[noreturn]] void throw_io_error(const char* who, const std::string& path, const char* doing,
                                 int err);

}  // namespace ukdyn::detail

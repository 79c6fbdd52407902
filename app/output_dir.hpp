// SPDX-License-Identifier: BSD-3-Clause
// The output directory of `ukdyn run`: one run at a time, and the files of one run only
// (docs/simulation.md, "Interrupts and outputs").
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

namespace ukdyn::cli {

/// The files `ukdyn run` writes into its directory, in the order it writes them (the plots only
/// those that apply to the model, in the formats of --plot-format; the viewer's page last).
// clang-format off
inline constexpr std::array<const char*, 31> kRunOutputs = {
    "trajectory.csv", "summary.json",
    "coordinates.png", "constraint_forces.png", "violation.png", "contacts.png", "energy.png",
    "control.png", "bodies.png", "joint_reactions.png", "outputs.png",
    "trajectory.h5",
    "coordinates.pdf", "constraint_forces.pdf", "violation.pdf", "contacts.pdf", "energy.pdf",
    "control.pdf", "bodies.pdf", "joint_reactions.pdf", "outputs.pdf",
    "coordinates.svg", "constraint_forces.svg", "violation.svg", "contacts.svg", "energy.svg",
    "control.svg", "bodies.svg", "joint_reactions.svg", "outputs.svg",
    "animation.html"};
// clang-format on

/// The files `ukdyn sweep` writes into its directory.
inline constexpr std::array<const char*, 6> kSweepOutputs = {
    "ensemble.csv", "ensemble.h5", "summary.json", "sweep.png", "sweep.pdf", "sweep.svg"};

/// Another run holds the directory: the message names it and the other run's pid.
class DirectoryBusy : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The output directory, held for a run: created when missing and locked — flock(2) on
/// DIR/.ukdyn.lock, which holds the pid of the run that locked it — until destroyed (or the
/// process ends, however it ends: the kernel drops the lock). A second run into a locked
/// directory is refused at its start, before it computes anything. The lock is opened with
/// O_NOFOLLOW and must be a regular file: a symbolic link (or a FIFO, a directory) planted under
/// its name is refused, never followed. So is any of the run's output names that exists and is
/// not a regular file (a symbolic link, a FIFO, a directory): refused before the run computes
/// anything, with the name and what it is.
class OutputDirectory {
 public:
  /// `outputs`: the names of the files the run writes (kRunOutputs, kSweepOutputs).
  /// @throws DirectoryBusy when another run holds it; std::runtime_error naming the directory
  /// when it cannot be created or locked, or naming an output that is not a regular file.
  OutputDirectory(std::filesystem::path dir, std::span<const char* const> outputs);
  ~OutputDirectory();
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;

  const std::filesystem::path& path() const { return dir_; }

  /// Removes what a previous run wrote here (the outputs, and the temporaries `.NAME.tmp-*` of
  /// a run killed while writing), so that the directory then holds this run's files only; other
  /// files are left alone. @throws std::runtime_error naming a file that cannot be removed.
  void remove_previous_outputs() const;

 private:
  std::filesystem::path dir_;
  std::span<const char* const> outputs_;
  int lock_fd_ = -1;
};

/// Writes `text` to `path` whole or not at all (a temporary made by mkostemp beside it, renamed
/// over it). @throws std::runtime_error "ukdyn: cannot open|write|replace 'PATH': REASON".
void write_text_file(const std::string& path, const std::string& text);

/// Holds `dir` for a run of `ukdyn run` or `ukdyn sweep`: constructs `out`, or prints
/// "error: …" and returns the command's exit status — kExitBusy when another run holds the
/// directory, kExitRunFailed when it cannot be created or locked or one of `outputs` there is not
/// a regular file; 0 when `out` holds it.
int hold_output_directory(const std::filesystem::path& dir, std::span<const char* const> outputs,
                          std::optional<OutputDirectory>& out);

}  // namespace ukdyn::cli

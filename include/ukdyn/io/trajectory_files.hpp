// SPDX-License-Identifier: BSD-3-Clause
/// @file io/trajectory_files.hpp
/// Writers of trajectories: CSV (one row per sample), a JSON run summary, and HDF5 for long runs.
///
/// CSV columns, in this order: `t`; each coordinate `x`; `x_dot`; `x_ddot`; `Qc_ideal.x`;
/// `Qc_nonideal.x`; `lambda.<constraint>` (`lambda.<constraint>.<row>` for several rows);
/// `violation.<constraint>` (position level for holonomic constraints, velocity level for
/// nonholonomic ones, 0 for the acceleration kind); `violation_velocity.<constraint>` for the
/// holonomic ones; `kinetic_energy`, `potential_energy`, `energy`; the energy balance:
/// `work_nonideal`, `work_ideal`, `work_drive`, `work_external`, `work_control`, `work_impact`
/// (only for a system with unilateral contacts), `energy_balance_residual`
/// (simulation/simulate.hpp, Trajectory; docs/simulation.md). Numbers are written by std::to_chars
/// in the shortest form that reads back bit for bit (`0.1`, `1e-300`,
/// `-2.5e+17`; independent of the locale); NaN as `nan`, infinities as `inf` and `-inf`.
///
/// Every writer writes whole files or none: it writes a hidden temporary `.NAME.tmp-PID-N` in
/// the directory of `path` and renames it over `path` when complete, so a process killed while
/// writing leaves the previous file (or none) under `path`, never a truncated one; on an error
/// the temporary is removed. A `path` that exists and is not a regular file (/dev/stdout, a
/// FIFO) is written in place; a symbolic link is followed and its target replaced
/// (docs/simulation.md, "Interrupts and outputs").
#pragma once

#include <string>
#include <vector>

#include "ukdyn/io/provenance.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {

struct ControlStatistics;  // control/control.hpp

/// The CSV header names of a trajectory, in column order.
std::vector<std::string> csv_columns(const Trajectory& traj);

/// Writes the trajectory as CSV. @throws std::runtime_error naming the path if it cannot be
/// written.
void write_csv(const Trajectory& traj, const std::string& path);

/// A further CSV column: its name and one value per sample.
struct CsvColumn {
  std::string name;            ///< header name
  std::vector<double> values;  ///< N values
};

/// The standard columns with their values, in CSV order (what write_csv writes, as numbers).
/// Cost O(N × columns).
std::vector<CsvColumn> csv_table(const Trajectory& traj);

/// The same, with `extra` columns after the standard ones (e.g. a model's output expressions).
/// @throws std::invalid_argument when a column does not have N values; std::runtime_error as
/// above.
void write_csv(const Trajectory& traj, const std::string& path,
               const std::vector<CsvColumn>& extra);

/// trajectory.csv written piece by piece while a run produces its samples (run_model with a
/// chunk callback, `ukdyn run`), with write_csv's columns and numbers, under the same temporary
/// name until commit(): memory O(one piece), whatever the run's length. Destroyed without
/// commit() (an exception, a failure), it removes the temporary.
class CsvWriter {
 public:
  /// Creates the temporary beside `path`; nothing is written yet.
  /// @throws std::runtime_error naming the path.
  explicit CsvWriter(const std::string& path);
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;

  /// Appends one row per sample of traj (its standard columns, then `extra`, each with
  /// traj.samples() values); the first call writes the header (a traj without samples writes
  /// just the header). Later calls must have the same columns. @throws std::invalid_argument
  /// when a column has the wrong length or the columns changed; std::runtime_error naming the
  /// path when it cannot be written. Cost O(samples × columns).
  void append(const Trajectory& traj, const std::vector<CsvColumn>& extra = {});
  /// Rows appended so far.
  Index rows() const { return rows_; }
  /// Writes what is buffered, closes the file and renames it over the path (appends nothing:
  /// call append() once before, if only for the header). @throws std::runtime_error.
  void commit();
  /// After append() or commit() failed to write (a full disk, a file-size limit): closes the
  /// file and renames what reached it over the path — the rows written before the failure, the
  /// last one perhaps cut — so that they are kept under the file's own name rather than lost
  /// with the temporary. Tries nothing more; never throws (true when the file was renamed).
  bool keep_partial() noexcept;

 private:
  struct Impl;
  Impl* impl_;
  Index rows_ = 0;
};

/// Writes a JSON summary: the run statistics (steps, rejected steps, evaluations, wall time,
/// largest violations, energy_balance, energy_exchanged, energy_balance_tolerance, energy drift,
/// status, message), t_start, t_reached, the final state by
/// coordinate name, and the options given. A trajectory that holds only the last sample of a
/// streamed run (traj.stats.samples > traj.samples(), see SimulationOptions::sample_sink) is
/// summarised with samples = stats.samples and t_start = options.t_start.
/// @throws std::runtime_error naming the path.
void write_summary_json(const Trajectory& traj, const SimulationOptions& options,
                        const std::string& path);

/// As above, with what the run was made from under `provenance` (the model's name, file and
/// SHA-256, every parameter with `overridden` marked, the command line, ukdyn's version and
/// commit; io/provenance.hpp) and, for a controlled run, its statistics under `control`
/// (evaluations, not_met, max_residual, first_not_met, not_met_message, max_kappa,
/// bound_exceeded_at, bound_worst_ratio, bound_worst_row; null for none). @throws
/// std::runtime_error naming the path.
void write_summary_json(const Trajectory& traj, const SimulationOptions& options,
                        const std::string& path, const RunProvenance& provenance,
                        const ControlStatistics* control = nullptr);

/// The text write_summary_json writes (pretty-printed JSON, ending in a newline); `provenance`
/// and `control` may be null. Cost O(coordinates + options).
std::string summary_json(const Trajectory& traj, const SimulationOptions& options,
                         const RunProvenance* provenance = nullptr,
                         const ControlStatistics* control = nullptr);

/// Writes the trajectory to an HDF5 file: one dataset per field (`t`, `q`, `q_dot`, `q_ddot`,
/// `Qc_ideal`, `Qc_nonideal`, `lambda`, `position_violation`, `velocity_violation`,
/// `kinetic_energy`, `potential_energy`, `energy`, `work_nonideal`, `work_ideal`, `work_drive`,
/// `work_external`, `work_control`, `work_impact` (with unilateral contacts),
/// `energy_balance_residual`; matrices N × width,
/// chunked and compressed), the names as string attributes (`coordinate_names`,
/// `constraint_names`) and the statistics as attributes of the root group.
/// @throws std::runtime_error naming the path.
void write_hdf5(const Trajectory& traj, const std::string& path);

/// Writes a table of columns (csv_table() and a run's further columns: control, poses,
/// reactions, outputs — every column trajectory.csv has) to HDF5: one 1-D dataset per column,
/// named as in the CSV (a '/' written '|', a name met twice suffixed "#2", …), the names in order
/// as the root attribute `columns`, and, when `summary` (summary_json()'s text) is not empty, the
/// whole text as the attribute `summary` and each of its top-level numbers, booleans and strings
/// as an attribute of its own. Chunked and compressed like write_hdf5.
/// @throws std::invalid_argument when the columns differ in length or the summary is not a JSON
/// object; std::runtime_error naming the path.
void write_table_hdf5(const std::string& path, const std::vector<CsvColumn>& columns,
                      const std::string& summary = "");

/// Reads back a table written by write_table_hdf5: its columns in order, each named as its
/// dataset. @throws std::runtime_error naming the path or the dataset.
std::vector<CsvColumn> read_table_hdf5(const std::string& path);

/// Reads a string attribute of the root group of an HDF5 file (the `summary` of
/// write_table_hdf5). @throws std::runtime_error naming the path or the attribute.
std::string read_hdf5_string_attribute(const std::string& path, const std::string& name);

/// Reads back the sample times and one N × width field of an HDF5 trajectory (for tests and
/// tools). @throws std::runtime_error naming the path or the dataset.
std::vector<double> read_hdf5_field(const std::string& path, const std::string& dataset);

}  // namespace ukdyn

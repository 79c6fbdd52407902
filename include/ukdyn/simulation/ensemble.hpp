// SPDX-License-Identifier: BSD-3-Clause
/// @file simulation/ensemble.hpp
/// Ensembles (docs/ensembles.md): many runs of one model file — a parameter sweep, a Monte Carlo
/// study — on a pool of threads, one row of results per sample. Each sample is the run `ukdyn
/// run MODEL --set …` makes (run_model of modelfile/run.hpp), bit for bit, whatever the number of
/// threads and whichever thread ran it; the Python module runs the same samples on Dask workers
/// (ukdyn.sweep) and gets the same bits.
///
/// Parameters are folded into the compiled expressions when a model file is read (constant
/// folding: modelfile/expression.hpp), so a sample that changes parameters reads the model's text
/// again with its overrides (parse_model); a sample that changes only the initial state or
/// options shares the model read once. parse_model serializes its calls (GiNaC, which it uses, is
/// not thread-safe); the runs are not.
#pragma once

#include <cstddef>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "ukdyn/control/control.hpp"
#include "ukdyn/io/trajectory_files.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/options.hpp"
#include "ukdyn/simulation/sampling.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {

/// What an ensemble runs: a model file's text, read again for each sample that changes its
/// parameters, with settings common to every sample. Shared read-only by the threads.
struct EnsembleModel {
  std::string text;                         ///< the model file's YAML
  std::string file = "<string>";            ///< its name in errors (a path, examples/…)
  std::map<std::string, double> overrides;  ///< parameter overrides of every sample (--set)
  /// options of the table (simulation/options.hpp) for every sample, replacing the file's
  /// simulate: settings, by name
  std::map<std::string, OptionValue> settings;
};

/// One sample: what it changes, each by name. Values of a name in more than one map are
/// refused by run_ensemble.
struct EnsembleSample {
  std::map<std::string, double> parameters;  ///< parameter overrides (the model is read again)
  /// initial state: a coordinate's name sets its q0, `<coordinate>_dot` its q̇0 (as the file's
  /// `initial:` does; projected when the model says `project: true`)
  std::map<std::string, double> initial;
  /// numeric options of the table (simulation/options.hpp: t_end, rtol, …), by name
  std::map<std::string, double> settings;
};

/// Where an ensemble stands: `done` of `total` samples ended (`failed` of them not ok, i.e. a
/// run whose status is neither kOk nor kEnergyBalance, or refused).
struct EnsembleProgress {
  std::size_t done = 0;    ///< samples ended so far (ok or not)
  std::size_t failed = 0;  ///< of those, the ones not ok (or refused)
  std::size_t total = 0;   ///< samples in the ensemble
};

/// How an ensemble runs and what it keeps of each sample.
struct EnsembleOptions {
  /// worker threads (0: std::thread::hardware_concurrency()); each has its own workspaces
  /// (run_model makes them), the model's description is shared. The results do not depend on it.
  unsigned threads = 0;
  /// times at which the state and the outputs are recorded; each is added to the run's
  /// output_at, so a sample falls on it exactly (must lie in every sample's [t_start, t_end]).
  /// Empty: the last sample of each run (at t_reached).
  std::vector<double> at;
  /// the columns of trajectory.csv recorded at `at`, besides every coordinate and its velocity:
  /// any column name (`theta`, `lambda.rod`, `energy`, `error.track`); empty: the model's output
  /// expressions
  std::vector<std::string> outputs;
  /// keep each run's whole trajectory (every column of trajectory.csv); memory grows with it
  bool keep_trajectories = false;
  /// called after each sample ends, with the ensemble's progress (from the worker thread that
  /// ran it, one call at a time); may be empty. An exception it throws stops the ensemble (the
  /// runs under way stop at their next step, the samples not started are not run) and, once
  /// every worker thread has ended, propagates out of run_ensemble — the first one, if several
  /// threads threw. The results computed so far are then lost: a callback that must not end
  /// the ensemble catches its own exceptions.
  std::function<void(const EnsembleProgress&)> progress;
  /// a request to stop (SIGINT): asked before each sample and after every step of the runs
  /// under way (which then end with Status::kInterrupted); samples not started are reported as
  /// not run. Must be thread-safe and cheap; may be empty.
  std::function<bool()> should_stop;
};

/// How a sample ended.
enum class SampleOutcome {
  kRun,      ///< it ran: RunStatistics::status says how it ended (kOk, a failure, kInterrupted)
  kRefused,  ///< it could not start: a model error with its parameters, an inconsistent
             ///< initial state, a setting the run cannot use (SampleResult::message says which)
  kNotRun,   ///< the ensemble was stopped before it started
};

/// The result of one sample.
struct SampleResult {
  SampleOutcome outcome = SampleOutcome::kNotRun;  ///< how it ended
  RunStatistics stats;        ///< the run's statistics (kRun; wall_time is not reproducible)
  bool controlled = false;    ///< run under the model's controller
  ControlStatistics control;  ///< the controller's statistics (controlled runs)
  std::string message;        ///< stats.message (kRun), the refusal's text, or why not run
  /// the recorded values: for each time of EnsembleResult::at (or the last sample), each
  /// column of EnsembleResult::recorded, time-major; NaN for a time the run did not reach
  std::vector<double> values;
  /// every column of trajectory.csv (EnsembleOptions::keep_trajectories; empty otherwise)
  std::vector<CsvColumn> trajectory;
  /// ok: ran to its end with status kOk or kEnergyBalance (a warning)
  bool ok() const {
    return outcome == SampleOutcome::kRun &&
           (stats.status == Status::kOk || stats.status == Status::kEnergyBalance);
  }
};

/// The results of an ensemble, one per sample in the samples' order.
struct EnsembleResult {
  std::vector<std::string> recorded;  ///< the recorded columns: coordinates, velocities, outputs
  std::vector<double> at;             ///< the recording times (empty: the last sample)
  std::vector<SampleResult> samples;  ///< one per sample, in order
  bool interrupted = false;           ///< should_stop asked the ensemble to stop
  /// the model has unilateral contacts or Coulomb friction: the table then has the counts of
  /// their events per sample (ensemble_table)
  bool contacts = false;
  /// samples that failed: not ok (SampleResult::ok), neither interrupted nor not run — a run
  /// that ended in a failure, or a sample refused. Cost O(samples).
  std::size_t failed() const;
  /// samples that ran and were stopped by should_stop (status kInterrupted). Cost O(samples).
  std::size_t interrupted_samples() const;
  /// samples the ensemble was stopped before (SampleOutcome::kNotRun). Cost O(samples).
  std::size_t not_run() const;
  /// samples that are ok (SampleResult::ok); ok + failed + interrupted_samples + not_run is the
  /// number of samples. Cost O(samples).
  std::size_t ok() const;
};

/// Runs every sample of `model` on a pool of options.threads threads (std::thread; a sample is
/// the unit of work, taken in order by whichever thread is free) and returns the results in the
/// samples' order. A sample is run_model() of the model read with model.overrides and its
/// parameters, with the file's settings, model.settings, its settings and `at` added to
/// output_at, from its initial state; the results are those of that run in one thread, bit for
/// bit. A sample that fails (or is refused) is recorded with its status and message and does not
/// stop the others. Stopped by options.should_stop, it keeps every finished sample. An
/// exception thrown by options.progress (or any other that leaves a worker thread) is rethrown
/// here after every thread has been joined — never std::terminate.
/// @throws ModelError when the model (with model.overrides, without any sample's) cannot be
/// read; std::invalid_argument (naming run_ensemble, the sample and the name) for a name of a
/// sample that is not a parameter, coordinate, velocity or option of the model, an option of
/// model.settings out of its range, or a recorded output that is not a column of the model's
/// trajectory.csv. Cost: the runs', over the threads, plus one parse_model per sample that
/// changes parameters (serialized).
EnsembleResult run_ensemble(const EnsembleModel& model, const std::vector<EnsembleSample>& samples,
                            const EnsembleOptions& options);

/// The samples of a design's table: each name of `design` set as a parameter of `model` (when the
/// model has one), else the initial value of a coordinate (`x`) or velocity (`x_dot`), else a
/// numeric option of the table (`t_end`, `rtol`). @throws std::invalid_argument naming a name
/// that is none of these (and listing the model's parameters). Cost O(samples × names).
std::vector<EnsembleSample> samples_of_design(const Model& model, const DesignTable& design);

/// The same for the model of an ensemble (read with model.overrides). @throws ModelError when it
/// cannot be read; std::invalid_argument as above.
std::vector<EnsembleSample> samples_of_design(const EnsembleModel& model,
                                              const DesignTable& design);

/// The ensemble's table: one row per sample. Numeric columns: `sample` (its index), the
/// sample's names (`names`, in order; NaN where a sample does not set one), `status_code`
/// (int(Status) for a run, −1 refused, −2 not run), `ok` (1 or 0), `steps`, `rejected_steps`,
/// `evaluations`, `t_reached`, `max_position_violation`, `max_velocity_violation`,
/// `energy_balance`, `energy_exchanged`, `control_evaluations`, `control_not_met`,
/// `control_max_residual`, `control_max_kappa`; when the model has unilateral contacts or
/// Coulomb friction (EnsembleResult::contacts) the counts of the run's contact events
/// (RunStatistics::contact_events) `impacts` (impacts and rests: a rest is the impact that ends
/// an accumulation), `releases`, `sticks`, `slips` and `rest_time` (the time of its last rest
/// event, NaN when none); then each recorded column at each time (`x@5`, `theta@10`; `x@end`
/// for the last sample). Text columns: `status` (the status's name, "refused" or "not run")
/// and `message`. No wall time: the table is reproducible bit for bit.
struct EnsembleTable {
  std::vector<CsvColumn> numbers;    ///< the numeric columns, in order
  std::vector<std::string> status;   ///< per sample: the status's name
  std::vector<std::string> message;  ///< per sample: the message ("" when ok)
};

/// The table of `result` for `samples` (the ones run_ensemble ran), with the sample columns
/// `names` (empty: every name the samples set, in first-seen order). @throws
/// std::invalid_argument when samples and results differ in number. Cost O(samples × columns).
EnsembleTable ensemble_table(const EnsembleResult& result,
                             const std::vector<EnsembleSample>& samples,
                             std::vector<std::string> names = {});

/// Writes the table as CSV: the numeric columns, then `status` and `message` (quoted as RFC 4180
/// wants), numbers in their shortest round-trip form (as trajectory.csv's). Written whole or not
/// at all. @throws std::runtime_error naming the path.
void write_ensemble_csv(const EnsembleTable& table, const std::string& path);

/// Writes the table as HDF5 (write_table_hdf5 of io/trajectory_files.hpp): the numeric columns as
/// datasets, and a JSON object as the `summary` attribute: `summary` (the caller's object, text;
/// may be empty) with the per-sample `status` and `message` lists added. @throws
/// std::runtime_error naming the path; std::invalid_argument when `summary` is not a JSON object.
void write_ensemble_hdf5(const EnsembleTable& table, const std::string& path,
                         const std::string& summary = "");

}  // namespace ukdyn

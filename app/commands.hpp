// SPDX-License-Identifier: BSD-3-Clause
// The subcommands of the ukdyn program. main.cpp parses the command line and calls these; each
// returns the process exit code. No physics here: everything is a library call.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <ukdyn/io/provenance.hpp>
#include <ukdyn/modelfile/model.hpp>

namespace ukdyn::cli {

/// Exit codes (documented in `ukdyn --help` and README.md).
enum ExitCode : int {
  kExitOk = 0,         ///< success
  kExitRunFailed = 1,  ///< the run failed numerically (what was computed is still written)
  kExitUsage = 2,      ///< bad command line
  kExitModel = 3,      ///< bad model file (ModelError), or a model that cannot be started
  kExitCheck = 4,      ///< `check` found problems
  /// the run reached its end but its energy balance failed (Status::kEnergyBalance): the
  /// trajectory is complete, but energy was gained or lost that no work accounts for
  kExitEnergyBalance = 5,
  /// the output directory is in use by another run (flock on DIR/.ukdyn.lock): nothing was run
  kExitBusy = 6,
  /// the run was interrupted: exit code 128 + the signal's number (130 SIGINT, 143 SIGTERM),
  /// as a shell reports a program the signal ended; the samples up to there are written
  kExitInterruptedBase = 128,
};

/// A mistake on the command line found after parsing (bad --set, unknown example): exit 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The table formats of --format (run and sweep): csv and/or hdf5.
struct TableFormats {
  bool csv = false, hdf5 = false;
};

/// Reads --format's list. @throws UsageError naming a format that is not csv or hdf5, or an
/// empty list — before anything runs, so that a typo costs no work.
TableFormats parse_formats(const std::vector<std::string>& formats);

/// Where a model comes from: a file or a built-in example, with parameter overrides.
struct ModelSource {
  std::string path;              ///< MODEL.yaml, or empty
  std::string example;           ///< --example NAME, or empty
  std::vector<std::string> set;  ///< --set name=value, in order
};

/// Parses "name=value" pairs. @throws UsageError on a missing '=' or a value that is not a number.
std::map<std::string, double> parse_overrides(const std::vector<std::string>& set);

/// Checks --plot-format's list (png, pdf, svg). @throws UsageError naming a format that is none of
/// them, or an empty list — before anything runs.
void check_plot_formats(const std::vector<std::string>& formats);

/// Checks --plot-style (screen, paper). @throws UsageError naming the styles, with a
/// did-you-mean.
void check_plot_style(const std::string& style);

/// Loads the model of `source`. @throws UsageError (neither or both of path and example, an
/// unknown example, --set of a parameter the model does not declare), ModelError (the model
/// file).
Model load_source(const ModelSource& source);

/// A simulation option given on the command line (simulation/options.hpp): its name in the table,
/// the flag as written (`--rtol`, `--no-stiff-switch`) and its text ("false" for `--no-NAME`).
struct FlagSetting {
  std::string name, flag, text;
};

/// Settings of `ukdyn run`.
struct RunArguments {
  ModelSource source;
  std::string out_dir;  ///< -o DIR (empty: ukdyn-<model>)
  /// the option flags given, in the table's order: one flag per option of the table (--t-end,
  /// --integrator, --rtol, --max-steps, --stiff-switch / --no-stiff-switch, …), each replacing
  /// the model's simulate: setting of that name
  std::vector<FlagSetting> settings;
  bool plots = true;  ///< false with --no-plots
  /// --viewer / --no-viewer: write animation.html (unset: for models with bodies or visual:)
  std::optional<bool> viewer;
  /// --plot-format: the plots' file formats, "png", "pdf" and/or "svg" (empty: not given — png,
  /// or pdf for the paper style)
  std::vector<std::string> plot_formats;
  /// --plot-style: "screen" (the default) or "paper" (a journal's column: 3.5 in, 8 pt)
  std::string plot_style = "screen";
  /// --format: the trajectory's files, "csv" (trajectory.csv) and/or "hdf5" (trajectory.h5)
  std::vector<std::string> formats = {"csv"};
  /// --from-summary FILE: the summary.json of an earlier run to make again (its model, parameter
  /// overrides and settings; flags and --set given as well apply on top)
  std::string from_summary;
  std::vector<std::string> arguments;  ///< the command line, for summary.json's provenance
};

/// Fills args from an earlier run's summary.json, or the `summary` attribute of an HDF5 file
/// (args.from_summary): the model file (checked unchanged by its SHA-256) or example, the
/// overridden parameters as --set, every setting as a flag, the run's --format unless
/// args.arguments gives one; what args already has applies after them. @throws UsageError naming
/// the file and what is wrong with it.
void apply_summary(RunArguments& args);

/// The text of the model `source` names (the file's bytes, or the example's text).
/// @throws UsageError when the file cannot be read or the example does not exist.
std::string source_text(const ModelSource& source);

/// What a run of `model` from `source` is made from (summary.json's provenance).
RunProvenance provenance_of(const ModelSource& source, const Model& model,
                            const std::vector<std::string>& arguments);

/// `ukdyn run`: simulate, write trajectory.csv, summary.json and the plots.
int run_command(const RunArguments& args);

/// Settings of `ukdyn sweep` (docs/ensembles.md).
struct SweepArguments {
  ModelSource source;
  std::vector<std::string> grid;    ///< --grid NAME=START:STOP:COUNT or NAME=V1,V2,… (repeatable)
  std::vector<std::string> random;  ///< --random NAME~LAW(A,B) (repeatable)
  std::size_t samples = 0;          ///< --samples N: random draws per grid point
  std::uint64_t seed = 0;           ///< --seed S
  bool lhs = false;                 ///< --lhs: Latin hypercube draws
  std::string at;                   ///< --at T1,T2,…: recording times ("": the run's end)
  std::vector<std::string> outputs;            ///< --record NAME (repeatable): recorded columns
  unsigned jobs = 0;                           ///< --jobs N: threads (0: every core)
  std::string out_dir;                         ///< -o DIR (empty: ukdyn-sweep-<model>)
  std::vector<FlagSetting> settings;           ///< option flags for every sample (as `ukdyn run`'s)
  std::vector<std::string> formats = {"csv"};  ///< --format csv,hdf5
  bool plots = true;                           ///< false with --no-plots
  /// --plot-format: the summary plot's file formats, "png", "pdf" and/or "svg" (sweep.png, …)
  std::vector<std::string> plot_formats = {"png"};
  std::vector<std::string> arguments;  ///< the command line, for summary.json
};

/// `ukdyn sweep`: run_ensemble over a design; write DIR/ensemble.csv (ensemble.h5), summary.json
/// and sweep.png. kExitRunFailed when a sample failed, 128 + signal when interrupted (the
/// finished samples are written).
int sweep_command(const SweepArguments& args);

/// `ukdyn check`: print check_model()'s report; kExitCheck when it found problems.
int check_command(const ModelSource& source);

/// Settings of `ukdyn linearize`.
struct LinearizeArguments {
  ModelSource source;
  std::vector<std::string> at;           ///< --at NAME=VALUE,… (coordinates, NAME_dot, t)
  std::vector<std::string> independent;  ///< --independent: independent positions by name
  std::vector<std::string> independent_velocities;  ///< --independent-velocities
  std::vector<std::string> inputs;    ///< --inputs: coordinates (forces) or parameters
  std::vector<std::string> outputs;   ///< --outputs: coordinates, NAME_dot or output expressions
  std::vector<std::string> states;    ///< --states: keep these states (a subsystem)
  bool along = false;                 ///< --along: along the model's run, at every sample
  bool equilibrium = false;           ///< --equilibrium: find one from the --at state first
  bool project = false;               ///< --project: project the state onto the constraints first
  std::vector<std::string> unknowns;  ///< --unknowns of the equilibrium (default: positions)
  double initial_step = 0.1;          ///< --initial-step: LinearizeOptions::initial_step
  std::string format = "json";        ///< --format json|csv
};

/// `ukdyn linearize`: the linear model (analysis/linearize.hpp) on standard output.
int linearize_command(const LinearizeArguments& args);

/// `ukdyn examples`: list the built-in examples; `ukdyn examples NAME`: print that example's model
/// file (to start one's own from it). @throws UsageError on an unknown NAME (the nearest named).
int examples_command(const std::string& name = "");

}  // namespace ukdyn::cli

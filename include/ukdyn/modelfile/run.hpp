// SPDX-License-Identifier: BSD-3-Clause
/// @file modelfile/run.hpp
/// Running a model as `ukdyn run` does, for every front end (the command, the Python module):
/// the simulation — under its controller when the model file has a `control:` section — and
/// every column of trajectory.csv by name, with its values.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ukdyn/control/control.hpp"
#include "ukdyn/io/provenance.hpp"
#include "ukdyn/io/trajectory_files.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {

/// A model's run: the plant's trajectory and the columns that follow the standard ones.
struct ModelRun {
  /// The plant's motion, as simulate() records it (for a controlled model: its `plant`), but
  /// with each Coulomb friction's stick multipliers (`lambda.stick.<friction>[.i]`) made the
  /// holding force in the model's force unit: × kappa, the unit of the contact's normal rows in
  /// which the stick rows are stated (docs/friction.md §2; 1 for a unit normal in SI units).
  Trajectory trajectory;
  /// Whether the model ran under its controller (a `control:` section).
  bool controlled = false;
  /// The controller over the run (controlled runs only).
  ControlStatistics control;
  /// The columns after the standard ones of io/trajectory_files.hpp, in CSV order: the control's
  /// (control_csv_columns), the bodies' poses (multibody models), then the model's output
  /// expressions.
  std::vector<CsvColumn> extra_columns;

  /// Every column of trajectory.csv, in order: csv_table(trajectory) then extra_columns.
  /// Cost O(N × columns) (copies).
  std::vector<CsvColumn> columns() const;
};

/// Simulates the model with `options` (usually model.options, perhaps with another t_end):
/// simulate(), or simulate_controlled() with the model's controller. A failure during the run
/// is reported in trajectory.stats (status, message) with the samples computed before it, its
/// numbers labelled in the model's units (options.units is set to model.unit_system), its
/// angles' columns weighed as the model's units say (options.angle_coordinates is set from
/// model.coordinate_units, whatever `options` or model.options held: settings copied from
/// another model carry that model's flags).
/// @throws std::invalid_argument when the run cannot start (an inconsistent initial state,
/// bad settings), as simulate() does.
ModelRun run_model(const Model& model, const SimulationOptions& options);

/// run_model with the samples passed on as they are computed instead of kept (`ukdyn run`
/// streams trajectory.csv this way): `chunk` receives, in time order, a ModelRun whose
/// trajectory holds the next samples (at most chunk_samples; names, sizes filled, stats empty)
/// and whose extra_columns hold those samples' values. Returns the run's statistics
/// (trajectory.stats, with stats.samples counting every sample), the names, and the last
/// sample only (trajectory and extra_columns with one value each; none when no sample was
/// recorded). Memory O(chunk_samples × columns) whatever the run's length, and the grid may
/// have up to kMaxStreamedSamples samples; a controlled model (a `control:` section) streams
/// the same way, the control's columns with the plant's (simulate_controlled's streamed
/// overload). An exception thrown by `chunk` stops the run and propagates.
/// @throws std::invalid_argument as run_model.
ModelRun run_model(const Model& model, const SimulationOptions& options,
                   const std::function<void(const ModelRun& chunk)>& chunk,
                   std::size_t chunk_samples = 4096);

/// run_model(model, model.options).
ModelRun run_model(const Model& model);

/// The units of the contact columns that are neither coordinates nor output expressions: the
/// gap columns `gap.<name>` of the contacts: entries of a bodies or robot model, whose gap is a
/// distance (docs/contact.md), in the model's length unit; every unilateral constraint's
/// multipliers `lambda.<name>` and `lambda_total.<name>`, in the force unit when its gap is in
/// the length unit (the torque's when in rad; a generalized model's gap is an output
/// expression, with the unit `units:` or the coordinates it reads give it; none when it has
/// none); then the holding-force columns `lambda.stick.<friction>.i` of the frictions (the force
/// unit at a contact point; on the coordinate path the generalized force of the sliding
/// coordinate: the force unit for a length or a coordinate without a unit, the torque's for
/// rad); (column, unit) in constraint order. The front ends add them to the coordinates' and
/// outputs' units (summary.json, Model.units), so that the plots label a contact's gap in the
/// length unit and its force in the force unit. Cost O(constraints).
std::vector<std::pair<std::string, std::string>> contact_gap_units(const Model& model);

/// What a run of `model` was made from (summary.json's `provenance`, io/provenance.hpp), as
/// `ukdyn run` and Python's Model.simulate record it: the model's name, `model_file` (as given;
/// "" for an example) or `example`, sha256_hex(`model_text`), every parameter with those named
/// in `overridden` marked, `arguments` (the command line; Python: none), and the units of the
/// time, the coordinates, the output expressions and the contacts' gaps, and the unit system.
/// Cost O(text + n + parameters).
RunProvenance model_provenance(const Model& model, const std::string& model_file,
                               const std::string& example, std::string_view model_text,
                               const std::vector<std::string>& overridden,
                               const std::vector<std::string>& arguments);

/// Checks the settings of a run of `model` with `options` (model.options, or a front end's
/// changes of them) as `ukdyn run` runs it: check_settings() of a streamed run (its sample
/// grid held to kMaxStreamedSamples). The model reader calls it on the file's settings, so a
/// model that `ukdyn check` and load_model() accept is one whose settings `ukdyn run` accepts.
/// @throws SettingError naming the setting at fault (its text begins "ukdyn::simulate: ").
void check_run_settings(const Model& model, const SimulationOptions& options);

/// A SettingError of a run of `model` with the file's settings, as a ModelError at the value of
/// the key that gave the setting (Model::positions: `simulate: KEY`, `output: every` / `at`);
/// for a setting the file leaves at its default, at what makes the default unusable
/// (`simulate: t_end` for the sample grid) or the `simulate:` mapping, else the model's start.
/// The message is user_message(e) (no C++ function name).
ModelError locate_run_error(const Model& model, const SettingError& e);

/// An InconsistentInitialState of a run of `model`, as a ModelError: a violated state (not
/// projected, or the projection failed) at `initial:`, or at the first violated constraint without
/// it; contradicting constraints, or a penetrated contact, at the first one's entry. The hint:
/// add `project: true` under `initial:` where projecting may help (Cause::kNotProjected), and
/// for a penetrated contact, which no projection opens, change the initial state.
ModelError locate_run_error(const Model& model, const InconsistentInitialState& e);

/// Whether `e` (of a run of `model`) says that contacts are penetrated at the start (a gap < 0:
/// InconsistentInitialState::Cause::kPenetrated, which simulate() gives them). Projection does
/// not act on a gap, so project_initial cannot help: the front ends say so (the hint above;
/// Python's cause "penetrated"). Cost O(1).
bool contacts_penetrated(const Model& model, const InconsistentInitialState& e);

/// Writes trajectory.csv: the standard columns then run.extra_columns (write_csv of
/// io/trajectory_files.hpp).
/// @throws std::runtime_error naming the path if it cannot be written.
void write_csv(const ModelRun& run, const std::string& path);

}  // namespace ukdyn

/// @file run.hpp
/// Running a model as `ukdyn run` does, for every front end (the command, the Python module):
/// the simulation — under its controller when the model file has a `control:` section — and
/// every column of trajectory.csv by name, with its values.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "ukdyn/control.hpp"
#include "ukdyn/io.hpp"
#include "ukdyn/model.hpp"
#include "ukdyn/simulate.hpp"

namespace ukdyn {

/// A model's run: the plant's trajectory and the columns that follow the standard ones.
struct ModelRun {
  /// The plant's motion, as simulate() records it (for a controlled model: its `plant`).
  Trajectory trajectory;
  /// Whether the model ran under its controller (a `control:` section).
  bool controlled = false;
  /// The controller over the run (controlled runs only).
  ControlStatistics control;
  /// The columns after the standard ones of io.hpp, in CSV order: the control's
  /// (control_csv_columns), the bodies' poses (multibody models), then the model's output
  /// expressions.
  std::vector<CsvColumn> extra_columns;

  /// Every column of trajectory.csv, in order: csv_table(trajectory) then extra_columns.
  /// Cost O(N × columns) (copies).
  std::vector<CsvColumn> columns() const;
};

/// Simulates the model with `options` (usually model.options, perhaps with another t_end):
/// simulate(), or simulate_controlled() with the model's controller. A failure during the run
/// is reported in trajectory.stats (status, message) with the samples computed before it.
/// @throws std::invalid_argument when the run cannot start (an inconsistent initial state,
/// bad settings), as simulate() does.
ModelRun run_model(const Model& model, const SimulationOptions& options);

/// run_model(model, model.options).
ModelRun run_model(const Model& model);

/// Writes trajectory.csv: the standard columns then run.extra_columns (write_csv of io.hpp).
/// @throws std::runtime_error naming the path if it cannot be written.
void write_csv(const ModelRun& run, const std::string& path);

}  // namespace ukdyn

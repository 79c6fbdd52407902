// SPDX-License-Identifier: BSD-3-Clause
/// @file modelfile/model.hpp
/// Model files: a mechanical system written down in YAML with symbolic expressions (see
/// docs/model-format.md), turned into a System, an initial state and simulation settings.
#pragma once

#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/system.hpp"
#include "ukdyn/modelfile/expression.hpp"
#include "ukdyn/modelfile/units.hpp"
#include "ukdyn/modelfile/visual.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {

class Controller;
namespace tree {
class Tree;
}
namespace mb {
struct MultibodyModel;
}

/// An error in a model file: what, where (file:line:column, 1-based) and a hint. what() reads
/// "FILE:LINE:COLUMN: error: MESSAGE (hint: HINT)".
class ModelError : public std::runtime_error {
 public:
  /// The error `message` at `file`:`line`:`column` (1-based; 0: no position) with an optional
  /// `hint`; what() is composed from them as above.
  ModelError(const std::string& file, int line, int column, const std::string& message,
             const std::string& hint = "");
  const std::string& file() const { return file_; }        ///< the file (or "<string>")
  int line() const { return line_; }                       ///< 1-based line
  int column() const { return column_; }                   ///< 1-based column
  const std::string& message() const { return message_; }  ///< what is wrong
  const std::string& hint() const { return hint_; }        ///< how to fix it (may be empty)

 private:
  std::string file_;
  int line_, column_;
  std::string message_, hint_;
};

/// A parameter override (load_model's `overrides`, `ukdyn run --set`) that names no parameter
/// of the model or is not a finite number: a ModelError without a position (line and column 0)
/// whose message starts with "--set NAME:". Front ends treat it as a mistake of their caller.
class OverrideError : public ModelError {
 public:
  /// ModelError's constructor (file, line, column, message, hint).
  using ModelError::ModelError;
};

/// A place in a model file: 1-based line and column (0: unknown, e.g. a default).
struct FilePosition {
  int line = 0;                            ///< 1-based line (0: unknown)
  int column = 0;                          ///< 1-based column (0: unknown)
  bool known() const { return line > 0; }  ///< given in the file
};

/// Where a model file gave what a run can refuse, recorded by the reader so that an error found
/// later (a setting a run cannot use, an inconsistent initial state) is reported at
/// FILE:LINE:COLUMN like the reader's own (locate_run_error in modelfile/run.hpp).
struct ModelPositions {
  FilePosition start;     ///< the model's first key
  FilePosition simulate;  ///< the `simulate:` mapping
  FilePosition initial;   ///< the `initial:` section
  /// the value of each simulation option the file gives, by its name in the options table
  /// (simulation/options.hpp; an alias under its name): `simulate: NAME`, and `output: every`
  /// (output_every), `output: at` (output_at)
  std::map<std::string, FilePosition> settings;
  /// each constraint's entry under `constraints:`, and each joint's under `joints:` (a joint's
  /// constraints are named after it), by name
  std::map<std::string, FilePosition> constraints;
};

/// A model read from a file: the system and everything needed to run it.
struct Model {
  std::string name;                          ///< `name:`
  std::string file;                          ///< where it came from
  std::map<std::string, double> parameters;  ///< `parameters:` after overrides
  System system;                             ///< the description
  VectorXd q0;                               ///< `initial:` coordinates (n; not yet projected)
  VectorXd qd0;                              ///< `initial:` velocities (n; not yet projected)
  bool project_initial = false;              ///< `initial: project:`
  SimulationOptions options;                 ///< `simulate:` and `output:`
  /// `output: expressions:` by name, compiled over (q, q_dot, t): evaluate with
  /// evaluate_output_expressions(). The program's outputs are these, then the `visual:`
  /// points' coordinates (visual.columns); output_column_name() names them all.
  std::vector<std::string> output_names;
  /// The compiled outputs over (q, q_dot, t): output_names' expressions, then the `visual:`
  /// columns (see output_names).
  expr::Program output_program;
  /// Each coordinate's unit (n, in coordinate order): `units:` of the file, else the length
  /// unit (`m`), `rad` and `1` (quaternion components) for the bodies' coordinates of a
  /// multibody model and a robot's joints, else "" (not known). A label, but for one use: the
  /// angles among them (rad, deg: UnitSystem::is_angle) fill
  /// options.angle_coordinates, the columns the run's violation scales weigh by 1.
  std::vector<std::string> coordinate_units;
  /// The base units (`units: {length: mm, mass: g, time: ms}`; SI when not given) and the
  /// labels derived from them: the console's, summary.json's `unit_system`, the plots'. The
  /// model's numbers are in these units, nothing converts them; the time unit sets the defaults
  /// that are times (options.units and options.step; docs/model-format.md, "Units").
  UnitSystem unit_system;
  /// Each output expression's unit (output_names order): `units:` of the file, else "".
  std::vector<std::string> output_units;
  /// `control:` — the controller (with its nominal model) that run_model() applies to the
  /// plant `system`; null when the model has no control section (control/control.hpp).
  std::shared_ptr<const Controller> controller;
  /// `bodies:`, `joints:`, `forces:` — the multibody description that `system` was built from
  /// (its poses and joint reactions are reported); null for a model in generalized coordinates
  /// (multibody/multibody.hpp).
  std::shared_ptr<const mb::MultibodyModel> multibody;
  /// `robot:` (or a .urdf file read alone) — the kinematic tree that `system` was built from
  /// (multibody/tree.hpp); null for other models.
  std::shared_ptr<const tree::Tree> robot;
  /// `robot: torques:` — the joint torques τ(q, q', t) (n) the robot's system applies, for the
  /// run's effort notes (tree::LimitWatch); empty without torques:.
  std::function<void(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                     double t, Eigen::Ref<VectorXd> tau)>
      robot_torques;
  /// `visual:` — how the browser viewer draws the model (modelfile/visual.hpp).
  ModelVisual visual;
  /// Where the file gave the settings, the initial state and the constraints (all unknown for
  /// a model not read from text).
  ModelPositions positions;
};

/// Measured data given by the program that loads a model, rather than written in its file: by
/// table name, the table's columns (name, values) in order. The model file declares each such
/// table under `tables:` (its x:, interpolation:, extrapolation:; file: and data: may be left
/// out), and the data given replace any it has there, as overrides replace parameters
/// (docs/model-format.md, "Tables"; Python's `ukdyn.load(..., tables={...})`).
using TableData = std::vector<std::pair<std::string, std::vector<double>>>;
/// The tables given to load_model: TableData by table name (see TableData).
using GivenTables = std::map<std::string, TableData>;

/// Reads a model from YAML text. `file` names it in errors; `overrides` replace parameter
/// values (as --set name=value does). Thread-safe: calls from several threads are serialized
/// (the symbolic algebra it uses, GiNaC, is not thread-safe); the Models it returns are
/// independent. @throws ModelError with file:line:column and a hint.
Model parse_model(const std::string& text, const std::string& file = "<string>",
                  const std::map<std::string, double>& overrides = {});
/// parse_model with tables given by the caller (GivenTables): a table the file does not declare
/// is a ModelError, as are the given data's errors (too few rows, an abscissa not increasing,
/// columns of different lengths), located at the table's entry.
Model parse_model(const std::string& text, const std::string& file,
                  const std::map<std::string, double>& overrides, const GivenTables& tables);

/// The largest model file load_model() reads: 64 MB (a model file is a few kB; this bounds the
/// memory a wrong path such as /dev/zero can take).
inline constexpr std::size_t kMaxModelFileBytes = std::size_t(64) << 20;

/// Reads a model file. @throws ModelError (including when the file cannot be read, is a
/// directory, is empty, or is larger than kMaxModelFileBytes).
Model load_model(const std::string& path, const std::map<std::string, double>& overrides = {});
/// load_model with tables given by the caller (as parse_model's).
Model load_model(const std::string& path, const std::map<std::string, double>& overrides,
                 const GivenTables& tables);

/// What `ukdyn check` reports about a model at its initial state.
struct CheckReport {
  Index coordinates = 0;         ///< n
  Index constraint_rows = 0;     ///< m (active at t_start)
  Index rank = 0;                ///< rank of A at the initial state
  Index degrees_of_freedom = 0;  ///< n − rank
  /// Constraints whose rows add nothing to the rank of those before them (in declaration
  /// order): removing them leaves the motion unchanged.
  std::vector<std::string> redundant;
  /// Constraints that contradict each other near the initial state: no state satisfies them
  /// together, so projection cannot help (find_constraint_conflict); not listed as redundant.
  std::vector<std::string> contradictory;
  /// One line per constraint the initial state violates (check_initial_conditions).
  std::vector<std::string> initial_violations;
  /// Unilateral contacts penetrated at the initial state beyond the run's tolerance (a gap below
  /// −max(initial_tolerance, 1e-9) of its gap unit): a run refuses to start, projected or not
  /// (`project: true` does not act on a unilateral gap); each is also a problem.
  std::vector<std::string> penetrated;
  /// M(q0, t_start) symmetric positive definite, or positive semi-definite (mass_singular)
  bool mass_positive_definite = false;
  /// M(q0, t_start) singular: positive semi-definite, completed by the constraints when [M; A]
  /// has full column rank (docs/singular-mass.md; otherwise a problem is listed)
  bool mass_singular = false;
  std::vector<std::string> problems;  ///< what makes the model unusable (empty: fine)
  /// True when there are no problems.
  bool ok() const { return problems.empty(); }
};

/// Checks a model at its initial state: sizes, rank and redundancy of the constraints, initial
/// consistency (against initial_tolerance of its options), and M. Cost: a few evaluations.
CheckReport check_model(const Model& model);

/// The name of output k of model.output_program: output_names[k], then visual.columns.
const std::string& output_column_name(const Model& model, std::size_t k);

/// The values of the model's output expressions at every sample of a trajectory: one vector per
/// name, in output_names order.
std::vector<std::vector<double>> evaluate_output_expressions(const Model& model,
                                                             const Trajectory& traj);

}  // namespace ukdyn

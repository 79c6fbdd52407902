// SPDX-License-Identifier: BSD-3-Clause
// run_model: a model's simulation (under its controller when it has one) and its CSV columns,
// shared by `ukdyn run` and the Python module.
#include "ukdyn/modelfile/run.hpp"

#include <algorithm>
#include <optional>

#include "ukdyn/core/format.hpp"
#include "ukdyn/modelfile/table.hpp"
#include "ukdyn/multibody/multibody.hpp"
#include "ukdyn/multibody/tree.hpp"

#include "modelfile/angle_flags.hpp"
#include "modelfile/contact_start.hpp"
#include "modelfile/visual_contacts.hpp"

namespace ukdyn {

std::vector<CsvColumn> ModelRun::columns() const {
  std::vector<CsvColumn> all = csv_table(trajectory);
  all.insert(all.end(), extra_columns.begin(), extra_columns.end());
  return all;
}

namespace {

// the sample fields of a trajectory, in one list
std::vector<std::vector<double>*> fields(Trajectory& t) {
  return {&t.t,
          &t.q,
          &t.qd,
          &t.qdd,
          &t.Qc_ideal,
          &t.Qc_nonideal,
          &t.lambda,
          &t.lambda_total,
          &t.position_violation,
          &t.velocity_violation,
          &t.kinetic_energy,
          &t.potential_energy,
          &t.energy,
          &t.work_nonideal,
          &t.work_ideal,
          &t.work_drive,
          &t.work_external,
          &t.work_control,
          &t.work_impact,
          &t.energy_balance_residual};
}

// the names and sizes of `from` (no samples)
void copy_header(Trajectory& to, const Trajectory& from) {
  to.coordinate_names = from.coordinate_names;
  to.constraint_names = from.constraint_names;
  to.constraint_rows = from.constraint_rows;
  to.constraint_kinds = from.constraint_kinds;
  to.unilateral = from.unilateral;
  to.n = from.n;
  to.m = from.m;
}

// `gap.<name>` of each unilateral constraint whose gap is not an output expression (the
// contacts: of bodies and robot models; a generalized model's gap is its constraint's
// expression, an output): the constraint's violation phi at each sample, which is its gap g
// (docs/contact.md). Cost O(N × one violation per contact).
void add_gap_columns(const Model& model, const Trajectory& traj, std::vector<CsvColumn>& out) {
  const System& sys = model.system;
  const Index N = traj.samples(), n = traj.n;
  VectorXd phi(1), phi_dot(1);
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const Constraint& c = sys.constraint(k);
    if (!c.is_unilateral()) continue;
    const std::string name = "gap." + c.name();
    if (std::find(model.output_names.begin(), model.output_names.end(), name) !=
        model.output_names.end())
      continue;
    const auto scratch = c.model().make_scratch(n);
    CsvColumn col{name, std::vector<double>(std::size_t(N))};
    for (Index i = 0; i < N; ++i) {
      const Eigen::Map<const VectorXd> q(traj.q.data() + i * n, n), qd(traj.qd.data() + i * n, n);
      c.model().violation(q, qd, traj.t[std::size_t(i)], scratch.get(), phi, phi_dot);
      col.values[std::size_t(i)] = phi[0];
    }
    out.push_back(std::move(col));
  }
}

}  // namespace

std::vector<std::pair<std::string, std::string>> contact_gap_units(const Model& model) {
  std::vector<std::pair<std::string, std::string>> out;
  const System& sys = model.system;
  const UnitSystem& u = model.unit_system;
  const bool built = model.multibody || model.robot;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const Constraint& c = sys.constraint(k);
    if (!c.is_unilateral()) continue;
    const std::string name = "gap." + c.name();
    const auto output = std::find(model.output_names.begin(), model.output_names.end(), name);
    // the gap's unit: a contacts: entry's is a distance; a generalized model's gap is an output
    // expression, with the unit units: or its coordinates give it (Reader::label_gaps)
    std::string gap;
    if (output == model.output_names.end()) {
      if (built) out.emplace_back(name, gap = u.length);
    } else if (const auto i = std::size_t(output - model.output_names.begin());
               i < model.output_units.size()) {
      gap = model.output_units[i];
    }
    // its multipliers lambda.<c>, lambda_total.<c>: the force along a gap in the length unit,
    // the torque along one in rad (energy per gap unit)
    const std::string force = gap == u.length ? u.force() : gap == "rad" ? u.torque() : "";
    if (force.empty()) continue;
    for (Index r = 0; r < c.rows(); ++r)
      out.emplace_back("lambda." + c.name() + (c.rows() == 1 ? "" : "." + format_number(r)), force);
    out.emplace_back("lambda_total." + c.name(), force);
  }
  // the holding forces lambda.stick.<friction>[.i] (run_model scales them to forces)
  for (const FrictionContact& f : sys.friction_contacts()) {
    if (f.stick_constraint < 0) continue;
    const Constraint& stick = sys.constraint(f.stick_constraint);
    for (Index r = 0; r < stick.rows(); ++r) {
      std::string unit = u.force();
      if (!f.kinematics) {
        // the generalized force of sliding coordinate r: a force on a length, a torque on rad,
        // none on a coordinate without a unit (never a guessed label)
        const Index j = r < Index(f.coordinates.size()) ? f.coordinates[std::size_t(r)] : r;
        const std::string& of = std::size_t(j) < model.coordinate_units.size()
                                    ? model.coordinate_units[std::size_t(j)]
                                    : std::string();
        unit = of == u.length ? u.force() : of == "rad" ? u.torque() : std::string();
      }
      if (unit.empty()) continue;
      out.emplace_back(
          "lambda." + stick.name() + (stick.rows() == 1 ? std::string() : "." + format_number(r)),
          unit);
    }
  }
  return out;
}

namespace {

// the model's columns after the standard ones, for the samples of traj: the bodies' poses
// (multibody models), the contacts' gaps, the output expressions (not the control's), then the
// points and normals of the contacts: entries drawn (modelfile/visual_contacts.hpp)
void add_model_columns(const Model& model, const Trajectory& traj, std::vector<CsvColumn>& out) {
  if (model.multibody) {
    for (auto& col : mb::report_csv_columns(*model.multibody, traj)) out.push_back(std::move(col));
  }
  add_gap_columns(model, traj, out);
  const auto values = evaluate_output_expressions(model, traj);
  for (std::size_t k = 0; k < values.size(); ++k) {
    out.push_back(CsvColumn{output_column_name(model, k), values[k]});
  }
  detail::add_contact_columns(model, traj, out);
}

// the efforts on a robot's joints at samples (t, q, q'): its torques: τ(q, q', t) plus the
// control's Qc_control (each may be absent; both absent: empty, efforts not checked)
std::vector<double> robot_efforts(const Model& model, const std::vector<double>& t,
                                  const std::vector<double>& q, const std::vector<double>& qd,
                                  const std::vector<double>& Qc_control) {
  if (!model.robot_torques || !model.robot || qd.size() != q.size()) return Qc_control;
  const Index n = model.robot->coordinate_count();
  std::vector<double> tau(t.size() * std::size_t(n), 0.0);
  for (std::size_t s = 0; s < t.size(); ++s) {
    const std::size_t at = s * std::size_t(n);
    Eigen::Map<VectorXd> out(tau.data() + at, n);
    model.robot_torques(Eigen::Map<const VectorXd>(q.data() + at, n),
                        Eigen::Map<const VectorXd>(qd.data() + at, n), t[s], out);
    if (!Qc_control.empty()) out += Eigen::Map<const VectorXd>(Qc_control.data() + at, n);
  }
  return tau;
}

// the velocities to watch: q' of every sample (none when the run kept no velocities)
const std::vector<double>& watched_velocities(const std::vector<double>& q,
                                              const std::vector<double>& qd) {
  static const std::vector<double> none;
  return qd.size() == q.size() ? qd : none;
}

// a robot's joint and effort limits that the run left, as notes (tree::LimitWatch)
void note_limits(const std::optional<tree::LimitWatch>& watch, const UnitSystem& units,
                 RunStatistics& stats) {
  if (!watch) return;
  for (const tree::LimitExcess& e : watch->excesses())
    stats.notes.push_back(tree::describe(e, units));
}

// A failed run whose model met a table column outside its range (the value NaN there,
// expr::table_range_error): the table's message first
void note_table_range(RunStatistics& stats) {
  const std::string& error = expr::table_range_error();
  if (error.empty() || stats.status == Status::kOk || stats.status == Status::kEnergyBalance ||
      stats.status == Status::kInterrupted)
    return;
  stats.message = error + "; " + stats.message;
}

}  // namespace

ModelRun run_model(const Model& model, const SimulationOptions& options_in,
                   const std::function<void(const ModelRun& chunk)>& chunk,
                   std::size_t chunk_samples) {
  expr::clear_table_range_error();
  // (the run's messages in the model's units)
  SimulationOptions options = options_in;
  options.units = model.unit_system;
  // (the columns of its angles, from its units, as its units: options copied from another
  // model carry that model's flags)
  options.angle_coordinates = detail::model_angle_coordinates(model);
  // the samples gather in `gathered` (plant and control; its capacity kept), passed on as a
  // ModelRun every chunk_samples; `last` holds the last sample
  const bool controlled = bool(model.controller);
  ControlledTrajectory gathered, last;
  ModelRun piece;
  const std::size_t size = std::max<std::size_t>(chunk_samples, 1);
  // the columns of the samples in `from`: the control's, the bodies', the output expressions'
  auto columns_of = [&](const ControlledTrajectory& from) {
    std::vector<CsvColumn> cols;
    if (controlled) cols = control_csv_columns(from);
    add_model_columns(model, from.plant, cols);
    return cols;
  };
  std::optional<tree::LimitWatch> watch;
  if (model.robot) watch.emplace(*model.robot);
  auto pass_on = [&] {
    if (gathered.samples() == 0) return;
    if (watch) {
      watch->observe(gathered.plant.t, gathered.plant.q,
                     robot_efforts(model, gathered.plant.t, gathered.plant.q, gathered.plant.qd,
                                   gathered.Qc_control),
                     watched_velocities(gathered.plant.q, gathered.plant.qd));
    }
    detail::scale_stick_multipliers(model, gathered.plant);
    piece.extra_columns = columns_of(gathered);
    std::swap(piece.trajectory, gathered.plant);
    chunk(piece);
    std::swap(piece.trajectory, gathered.plant);
    for (auto* f : sample_fields(gathered)) f->clear();
  };
  // a sample: the plant's, and the control's values when `control` is not null
  auto take = [&](const Trajectory& plant, const ControlledTrajectory* control) {
    if (last.plant.coordinate_names.empty()) {
      for (ControlledTrajectory* to : {&gathered, &last}) {
        copy_header(to->plant, plant);
        if (control) {
          to->row_names = control->row_names;
          to->robust = control->robust;
        }
      }
    }
    auto to = sample_fields(gathered), one = sample_fields(last);
    auto from = fields(const_cast<Trajectory&>(plant));
    if (control) {
      const auto all = sample_fields(const_cast<ControlledTrajectory&>(*control));
      from.insert(from.end(), all.begin() + std::ptrdiff_t(from.size()), all.end());
    }
    for (std::size_t f = 0; f < from.size(); ++f) {
      to[f]->insert(to[f]->end(), from[f]->begin(), from[f]->end());
      *one[f] = *from[f];
    }
    if (std::size_t(gathered.samples()) >= size) pass_on();
  };
  ModelRun run;
  if (controlled) {
    ControlledTrajectory c = simulate_controlled(
        *model.controller, model.system, model.q0, model.qd0, options,
        [&](const ControlledTrajectory& sample) { take(sample.plant, &sample); });
    run.trajectory = std::move(c.plant);
    run.control = std::move(c.control);
    run.controlled = true;
  } else {
    SimulationOptions o = options;
    o.sample_sink = [&](const Trajectory& sample) { take(sample, nullptr); };
    run.trajectory = simulate(model.system, model.q0, model.qd0, o);
  }
  pass_on();
  note_limits(watch, model.unit_system, run.trajectory.stats);
  note_table_range(run.trajectory.stats);

  // the statistics, the names and the last sample with its columns
  if (last.samples() > 0) {
    auto to = fields(run.trajectory), from = fields(last.plant);
    for (std::size_t f = 0; f < to.size(); ++f) *to[f] = *from[f];
    detail::scale_stick_multipliers(model, run.trajectory);
  }
  // (the names of the columns also when no sample was recorded: a header-only CSV)
  last.plant = run.trajectory;
  if (controlled) {
    last.row_names = model.controller->row_names();
    last.robust = model.controller->robust().has_value();
  }
  run.extra_columns = columns_of(last);
  return run;
}

ModelRun run_model(const Model& model, const SimulationOptions& options_in) {
  expr::clear_table_range_error();
  SimulationOptions options = options_in;
  options.units = model.unit_system;  // (the run's messages in the model's units)
  // (the columns of its angles, from its units, as its units: options copied from another
  // model carry that model's flags)
  options.angle_coordinates = detail::model_angle_coordinates(model);
  ModelRun run;
  std::optional<tree::LimitWatch> watch;
  if (model.robot) watch.emplace(*model.robot);
  if (model.controller) {
    ControlledTrajectory c =
        simulate_controlled(*model.controller, model.system, model.q0, model.qd0, options);
    if (watch) {
      watch->observe(c.plant.t, c.plant.q,
                     robot_efforts(model, c.plant.t, c.plant.q, c.plant.qd, c.Qc_control),
                     watched_velocities(c.plant.q, c.plant.qd));
    }
    run.extra_columns = control_csv_columns(c);
    run.trajectory = std::move(c.plant);
    run.control = std::move(c.control);
    run.controlled = true;
  } else {
    run.trajectory = simulate(model.system, model.q0, model.qd0, options);
    if (watch) {
      const Trajectory& tr = run.trajectory;
      watch->observe(tr.t, tr.q, robot_efforts(model, tr.t, tr.q, tr.qd, {}),
                     watched_velocities(tr.q, tr.qd));
    }
  }
  note_limits(watch, model.unit_system, run.trajectory.stats);
  note_table_range(run.trajectory.stats);
  detail::scale_stick_multipliers(model, run.trajectory);
  add_model_columns(model, run.trajectory, run.extra_columns);
  return run;
}

ModelRun run_model(const Model& model) { return run_model(model, model.options); }

void check_run_settings(const Model& model, const SimulationOptions& options) {
  // as `ukdyn run` runs it: streamed (run_model with a chunk sets a sample_sink)
  SimulationOptions streamed = options;
  streamed.sample_sink = [](const Trajectory&) {};
  check_settings(model.system, streamed);
}

namespace {

// the ModelError of `model`'s file at `at` (the model's start when unknown)
ModelError error_at(const Model& model, FilePosition at, const std::string& message,
                    const std::string& hint = "") {
  if (!at.known()) at = model.positions.start;
  if (!at.known()) at = {1, 1};
  return ModelError(model.file, at.line, at.column, message, hint);
}

// the entry of constraint `name`: its own, or that of the joint it is named after (a joint's
// constraints are named "<joint>" or "<joint>.<part>" / "<joint>_<part>")
FilePosition constraint_position(const Model& model, const std::string& name) {
  const auto& all = model.positions.constraints;
  if (const auto it = all.find(name); it != all.end()) return it->second;
  FilePosition best;
  std::size_t longest = 0;
  for (const auto& [declared, at] : all) {
    if (declared.size() > longest && name.size() > declared.size() &&
        name.compare(0, declared.size(), declared) == 0 &&
        (name[declared.size()] == '.' || name[declared.size()] == '_')) {
      best = at;
      longest = declared.size();
    }
  }
  return best;
}

}  // namespace

ModelError locate_run_error(const Model& model, const SettingError& e) {
  const ModelPositions& p = model.positions;
  const auto given = [&](const std::string& name) {
    const auto it = p.settings.find(name);
    return it == p.settings.end() ? FilePosition{} : it->second;
  };
  FilePosition at = given(e.setting());
  // the sample grid of a default spacing: too many samples for the file's t_end
  if (!at.known() && (e.setting() == "output_every" || e.setting() == "output_at")) {
    at = given("t_end");
  }
  if (!at.known()) at = p.simulate;
  return error_at(model, at, user_message(e));
}

bool contacts_penetrated(const Model& model, const InconsistentInitialState& e) {
  (void)model;  // (the cause says it: simulate names the penetrated contacts)
  return e.cause() == InconsistentInitialState::Cause::kPenetrated;
}

ModelError locate_run_error(const Model& model, const InconsistentInitialState& e) {
  using Cause = InconsistentInitialState::Cause;
  const FilePosition constraint =
      e.constraints().empty() ? FilePosition{} : constraint_position(model, e.constraints()[0]);
  // penetrated contacts (unilateral constraints with a gap < 0 at the start): projection does
  // not act on a unilateral gap, so the hint is to move the state, at the first contact's entry
  const bool penetrated = e.cause() == Cause::kPenetrated;
  FilePosition at;
  if (e.cause() == Cause::kContradictory || penetrated) {
    at = constraint.known() ? constraint : model.positions.initial;
  } else {
    at = model.positions.initial.known() ? model.positions.initial : constraint;
  }
  std::string hint;
  if (penetrated) {
    hint =
        "start with the contact open or touching: change the initial q so that its gap is >= 0 "
        "(`project: true` does not act on a unilateral gap)";
  } else if (e.cause() == Cause::kNotProjected) {
    hint = "add `project: true` under `initial:` in the model file";
  }
  return error_at(model, at, user_message(e), hint);
}

ModelError detail::locate_contact_start(const Model& model, const ContactStartError& e) {
  const System& sys = model.system;
  FilePosition at;
  for (const std::string& name : e.contacts()) {
    // the friction's entry on the contact (its stick constraint's, Reader::read_nonideal)
    const Index k = sys.constraint_index(name);
    for (const FrictionContact& f : sys.friction_contacts()) {
      if (f.normal_constraint != k || f.stick_constraint < 0) continue;
      const auto& all = model.positions.constraints;
      if (const auto it = all.find(sys.constraint(f.stick_constraint).name()); it != all.end())
        at = it->second;
    }
    if (!at.known()) at = constraint_position(model, name);
    if (at.known()) break;
  }
  return error_at(model, at, user_message(e));
}

void write_csv(const ModelRun& run, const std::string& path) {
  write_csv(run.trajectory, path, run.extra_columns);
}

RunProvenance model_provenance(const Model& model, const std::string& model_file,
                               const std::string& example, std::string_view model_text,
                               const std::vector<std::string>& overridden,
                               const std::vector<std::string>& arguments) {
  RunProvenance p;
  p.model_name = model.name;
  p.model_file = model_file;
  p.example = example;
  p.model_sha256 = sha256_hex(model_text);
  for (const auto& [name, value] : model.parameters) {
    const bool given = std::find(overridden.begin(), overridden.end(), name) != overridden.end();
    p.parameters.push_back({name, value, given});
  }
  p.arguments = arguments;
  const auto& names = model.system.coordinate_names();
  // the time's (column t), then the coordinates'
  p.units.emplace_back("t", model.unit_system.time);
  for (std::size_t i = 0; i < names.size() && i < model.coordinate_units.size(); ++i) {
    p.units.emplace_back(names[i], model.coordinate_units[i]);
  }
  // the output expressions' (one named like a coordinate keeps the coordinate's)
  for (std::size_t i = 0; i < model.output_names.size() && i < model.output_units.size(); ++i) {
    if (std::find(names.begin(), names.end(), model.output_names[i]) == names.end()) {
      p.units.emplace_back(model.output_names[i], model.output_units[i]);
    }
  }
  // the gaps of the contacts: entries (a distance: the length unit; contact_gap_units)
  for (auto& gap : contact_gap_units(model)) p.units.push_back(std::move(gap));
  // a requirement row's error (error.<row>) in the unit of its desired value (desired_<row>,
  // an output expression: `units: {desired_tip_0: m}`), when the file gives it
  if (model.controller) {
    for (const std::string& row : model.controller->row_names()) {
      std::string desired = "desired_" + row;
      std::replace(desired.begin(), desired.end(), '.', '_');
      for (std::size_t i = 0; i < model.output_names.size() && i < model.output_units.size(); ++i) {
        if (model.output_names[i] == desired && !model.output_units[i].empty()) {
          p.units.emplace_back("error." + row, model.output_units[i]);
        }
      }
    }
  }
  const UnitSystem& u = model.unit_system;
  p.unit_system = {{"length", u.length},       {"mass", u.mass},     {"time", u.time},
                   {"velocity", u.velocity()}, {"force", u.force()}, {"energy", u.energy()},
                   {"power", u.power()}};
  return p;
}

}  // namespace ukdyn

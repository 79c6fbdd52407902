// run_model: a model's simulation (under its controller when it has one) and its CSV columns,
// shared by `ukdyn run` and the Python module.
#include "ukdyn/run.hpp"

#include <algorithm>

#include "ukdyn/multibody.hpp"

namespace ukdyn {

std::vector<CsvColumn> ModelRun::columns() const {
  std::vector<CsvColumn> all = csv_table(trajectory);
  all.insert(all.end(), extra_columns.begin(), extra_columns.end());
  return all;
}

namespace {

// the sample fields of a trajectory, in one list
std::vector<std::vector<double>*> fields(Trajectory& t) {
  return {&t.t, &t.q, &t.qd, &t.qdd, &t.Qc_ideal, &t.Qc_nonideal, &t.lambda,
          &t.position_violation, &t.velocity_violation, &t.kinetic_energy, &t.potential_energy,
          &t.energy, &t.work_nonideal, &t.work_ideal, &t.work_drive, &t.work_external,
          &t.work_control, &t.energy_balance_residual};
}

// the names and sizes of `from` (no samples)
void copy_header(Trajectory& to, const Trajectory& from) {
  to.coordinate_names = from.coordinate_names;
  to.constraint_names = from.constraint_names;
  to.constraint_rows = from.constraint_rows;
  to.constraint_kinds = from.constraint_kinds;
  to.n = from.n;
  to.m = from.m;
}

// the model's columns after the standard ones, for the samples of traj: the bodies' poses
// (multibody models), then the output expressions (not the control's)
void add_model_columns(const Model& model, const Trajectory& traj, std::vector<CsvColumn>& out) {
  if (model.multibody) {
    for (auto& col : mb::report_csv_columns(*model.multibody, traj)) out.push_back(std::move(col));
  }
  const auto values = evaluate_output_expressions(model, traj);
  for (std::size_t k = 0; k < values.size(); ++k) {
    out.push_back(CsvColumn{model.output_names[k], values[k]});
  }
}

}  // namespace

ModelRun run_model(const Model& model, const SimulationOptions& options,
                   const std::function<void(const ModelRun& chunk)>& chunk,
                   std::size_t chunk_samples) {
  if (model.controller) {
    ModelRun run = run_model(model, options);
    if (run.trajectory.samples() > 0) chunk(run);
    return run;
  }
  // the samples gather in `piece` (its capacity kept), passed on every chunk_samples
  ModelRun piece;
  Trajectory last;  // the last sample
  const std::size_t size = std::max<std::size_t>(chunk_samples, 1);
  auto pass_on = [&] {
    if (piece.trajectory.samples() == 0) return;
    piece.extra_columns.clear();
    add_model_columns(model, piece.trajectory, piece.extra_columns);
    chunk(piece);
    for (auto* f : fields(piece.trajectory)) f->clear();
  };
  SimulationOptions o = options;
  o.sample_sink = [&](const Trajectory& sample) {
    if (last.coordinate_names.empty() && piece.trajectory.coordinate_names.empty()) {
      copy_header(piece.trajectory, sample);
      copy_header(last, sample);
    }
    auto to = fields(piece.trajectory), one = fields(last);
    auto from = fields(const_cast<Trajectory&>(sample));
    for (std::size_t f = 0; f < to.size(); ++f) {
      to[f]->insert(to[f]->end(), from[f]->begin(), from[f]->end());
      *one[f] = *from[f];
    }
    if (std::size_t(piece.trajectory.samples()) >= size) pass_on();
  };
  Trajectory result = simulate(model.system, model.q0, model.qd0, o);
  pass_on();

  // the statistics, the names and the last sample
  ModelRun run;
  run.trajectory = std::move(result);
  if (last.samples() > 0) {
    auto to = fields(run.trajectory), from = fields(last);
    for (std::size_t f = 0; f < to.size(); ++f) *to[f] = *from[f];
  }
  add_model_columns(model, run.trajectory, run.extra_columns);
  return run;
}

ModelRun run_model(const Model& model, const SimulationOptions& options) {
  ModelRun run;
  if (model.controller) {
    ControlledTrajectory c =
        simulate_controlled(*model.controller, model.system, model.q0, model.qd0, options);
    run.extra_columns = control_csv_columns(c);
    run.trajectory = std::move(c.plant);
    run.control = std::move(c.control);
    run.controlled = true;
  } else {
    run.trajectory = simulate(model.system, model.q0, model.qd0, options);
  }
  if (model.multibody) {
    for (auto& col : mb::report_csv_columns(*model.multibody, run.trajectory)) {
      run.extra_columns.push_back(std::move(col));
    }
  }
  const auto values = evaluate_output_expressions(model, run.trajectory);
  for (std::size_t k = 0; k < values.size(); ++k) {
    run.extra_columns.push_back(CsvColumn{model.output_names[k], values[k]});
  }
  return run;
}

ModelRun run_model(const Model& model) { return run_model(model, model.options); }

void write_csv(const ModelRun& run, const std::string& path) {
  write_csv(run.trajectory, path, run.extra_columns);
}

}  // namespace ukdyn

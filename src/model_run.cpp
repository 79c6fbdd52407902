// run_model: a model's simulation (under its controller when it has one) and its CSV columns,
// shared by `ukdyn run` and the Python module.
#include "ukdyn/run.hpp"

#include "ukdyn/multibody.hpp"

namespace ukdyn {

std::vector<CsvColumn> ModelRun::columns() const {
  std::vector<CsvColumn> all = csv_table(trajectory);
  all.insert(all.end(), extra_columns.begin(), extra_columns.end());
  return all;
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

// SPDX-License-Identifier: BSD-3-Clause
// `ukdyn linearize`: the linear model of a model file about a state (or an equilibrium found
// from it), as JSON or CSV on standard output. The physics is linearize() and
// find_equilibrium() of the library (analysis/linearize.hpp; docs/linearize.md).
#include <cstdio>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <ukdyn/analysis/linearize.hpp>
#include <ukdyn/analysis/model_linearize.hpp>
#include <ukdyn/core/status.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>

#include "commands.hpp"

namespace ukdyn::cli {
namespace {

// "a=1,b_dot=2" → the operating point: positions by name, rates by NAME_dot, and t
OperatingPoint operating_point(const Model& model, const std::vector<std::string>& at) {
  const System& sys = model.system;
  OperatingPoint op{model.q0, model.qd0, model.options.t_start};
  for (const std::string& item : at) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0)
      throw UsageError("--at " + item + ": expected NAME=VALUE (a coordinate, NAME_dot or t)");
    const std::string name = item.substr(0, eq), text = item.substr(eq + 1);
    double value = 0;
    try {
      std::size_t used = 0;
      value = std::stod(text, &used);
      if (used != text.size()) throw std::invalid_argument(text);
    } catch (const std::exception&) {
      throw UsageError("--at " + item + ": '" + text + "' is not a number");
    }
    if (name == "t") {
      op.t = value;
      continue;
    }
    try {
      const LinearOutput which = coordinate_output(sys, name);
      (which.rate ? op.qd : op.q)(which.coordinate) = value;
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--at: ") + e.what());
    }
  }
  return op;
}

nlohmann::json matrix_json(const MatrixXd& M) {
  nlohmann::json rows = nlohmann::json::array();
  for (Index i = 0; i < M.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (Index j = 0; j < M.cols(); ++j) row.push_back(M(i, j));
    rows.push_back(row);
  }
  return rows;
}

void print_csv_matrix(const char* title, const MatrixXd& M, const std::vector<std::string>& rows,
                      const std::vector<std::string>& cols) {
  std::printf("# %s\n", title);
  for (const auto& c : cols) std::printf(",%s", c.c_str());
  std::printf("\n");
  for (Index i = 0; i < M.rows(); ++i) {
    std::printf("%s", rows[std::size_t(i)].c_str());
    for (Index j = 0; j < M.cols(); ++j) std::printf(",%.17g", M(i, j));
    std::printf("\n");
  }
}

// the linear model as JSON (the callers add the operating point)
nlohmann::json model_json(const LinearModel& lm) {
  nlohmann::json j;
  j["states"] = lm.state_names;
  j["inputs"] = lm.input_names;
  j["outputs"] = lm.output_names;
  j["x0"] = std::vector<double>(lm.x0.data(), lm.x0.data() + lm.x0.size());
  j["f0"] = std::vector<double>(lm.f0.data(), lm.f0.data() + lm.f0.size());
  j["A"] = matrix_json(lm.A);
  j["B"] = matrix_json(lm.B);
  j["C"] = matrix_json(lm.C);
  j["D"] = matrix_json(lm.D);
  j["A_error"] = matrix_json(lm.A_error);
  j["B_error"] = matrix_json(lm.B_error);
  j["C_error"] = matrix_json(lm.C_error);
  j["D_error"] = matrix_json(lm.D_error);
  j["chart_condition"] = lm.chart_condition;
  j["open_contacts"] = lm.open_contacts;
  nlohmann::json modes = nlohmann::json::array();
  for (Index k = 0; k < lm.eigenvalues.size(); ++k) {
    nlohmann::json mode;
    mode["eigenvalue"] = {lm.eigenvalues(k).real(), lm.eigenvalues(k).imag()};
    nlohmann::json shape;
    for (Index i = 0; i < lm.eigenvectors.rows(); ++i)
      shape[lm.state_names[std::size_t(i)]] = {lm.eigenvectors(i, k).real(),
                                               lm.eigenvectors(i, k).imag()};
    mode["shape"] = shape;
    modes.push_back(mode);
  }
  j["modes"] = modes;
  return j;
}

// --along: the model run with its own settings, linearized at every sample, as JSON
int linearize_along_command(const Model& model, const LinearizeArguments& args,
                            const ModelLinearizeRequest& request) {
  if (args.equilibrium || args.project || !args.at.empty())
    throw UsageError(
        "--along linearizes along the model's own run: it takes no --at, --project "
        "or --equilibrium");
  if (args.format != "json") throw UsageError("--along writes JSON only (--format json)");
  const ModelRun run = run_model(model);
  if (run.trajectory.stats.status != Status::kOk)
    throw UsageError("--along: the run failed: " + run.trajectory.stats.message);
  const std::vector<OperatingPoint> path = trajectory_points(run.trajectory);
  const auto models = linearize_model_along(
      model, path, request, [&] { return source_text(args.source); }, "--along");
  nlohmann::json j;
  j["model"] = model.name;
  j["coordinates"] = model.system.coordinate_names();
  nlohmann::json points = nlohmann::json::array();
  for (std::size_t k = 0; k < models.size(); ++k) {
    nlohmann::json p = model_json(models[k]);
    p["t"] = path[k].t;
    points.push_back(p);
  }
  j["points"] = points;
  std::printf("%s\n", j.dump(2).c_str());
  return kExitOk;
}

}  // namespace

int linearize_command(const LinearizeArguments& args) {
  if (args.format != "json" && args.format != "csv")
    throw UsageError("--format " + args.format + ": must be json or csv");
  const Model model = load_source(args.source);
  ModelLinearizeRequest request;
  request.inputs = args.inputs;
  request.outputs = args.outputs;
  request.options.independent_positions = args.independent;
  request.options.independent_velocities = args.independent_velocities;
  request.options.states = args.states;
  request.options.initial_step = args.initial_step;
  request.equilibrium = args.equilibrium;
  request.unknowns = args.unknowns;
  request.project = args.project || (model.project_initial && args.at.empty());
  if (args.along) {
    try {
      return linearize_along_command(model, args, request);
    } catch (const LinearizeNameError& e) {
      throw UsageError(e.what());
    }
  }
  ModelLinearization result;
  try {
    result = linearize_model(
        model, operating_point(model, args.at), request, [&] { return source_text(args.source); },
        "ukdyn linearize");
  } catch (const LinearizeNameError& e) {
    throw UsageError(e.what());
  } catch (const std::invalid_argument& e) {
    // (a point off the constraints: the command's own remedy, not the C++ functions' names)
    const std::string what = e.what(), cpp = "project the state first (ukdyn::project_positions";
    const std::size_t at = what.find(cpp);
    if (at == std::string::npos || args.project) throw;
    throw UsageError(what.substr(0, at) +
                     "add --project to project the point onto the constraints first (its "
                     "positions, then its velocities)");
  }
  const OperatingPoint& op = result.point;
  const LinearModel& lm = result.linear;
  const System& sys = model.system;
  std::vector<std::string> derivative_names;
  for (const auto& s : lm.state_names) derivative_names.push_back(s + "'");

  // (a model with control: the linear model is the plant's, open loop: said, u19 05)
  if (model.controller)
    std::fprintf(stderr,
                 "note: the model's control: section is left out: this is the plant's open-loop "
                 "linear model, without the tracking control (docs/linearize.md, \"Control\")\n");
  // (said on stderr too: the model is that of the point's contact mode)
  for (const auto& c : lm.open_contacts)
    std::fprintf(stderr,
                 "note: contact '%s' is open at the point: it is left out of the linear model "
                 "(docs/linearize.md, \"Contacts\")\n",
                 c.c_str());
  if (args.format == "csv") {
    print_csv_matrix("A", lm.A, derivative_names, lm.state_names);
    print_csv_matrix("B", lm.B, derivative_names, lm.input_names);
    print_csv_matrix("C", lm.C, lm.output_names, lm.state_names);
    print_csv_matrix("D", lm.D, lm.output_names, lm.input_names);
    print_csv_matrix("A_error", lm.A_error, derivative_names, lm.state_names);
    std::printf("# eigenvalues\nre,im\n");
    for (Index k = 0; k < lm.eigenvalues.size(); ++k)
      std::printf("%.17g,%.17g\n", lm.eigenvalues(k).real(), lm.eigenvalues(k).imag());
    if (!lm.open_contacts.empty()) {
      std::printf("# open contacts (left out)\n");
      for (const auto& c : lm.open_contacts) std::printf("%s\n", c.c_str());
    }
    return kExitOk;
  }
  nlohmann::json j = model_json(lm);
  j["model"] = model.name;
  j["t"] = op.t;
  j["q"] = std::vector<double>(op.q.data(), op.q.data() + op.q.size());
  j["qd"] = std::vector<double>(op.qd.data(), op.qd.data() + op.qd.size());
  j["coordinates"] = sys.coordinate_names();
  std::printf("%s\n", j.dump(2).c_str());
  return kExitOk;
}

}  // namespace ukdyn::cli

// SPDX-License-Identifier: BSD-3-Clause
// `ukdyn linearize`: the linear model of a model file about a state (or an equilibrium found
// from it), as JSON or CSV on standard output. The physics is linearize() and
// find_equilibrium() of the library (analysis/linearize.hpp; docs/linearize.md).
#include <cstdio>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <ukdyn/analysis/linearize.hpp>
#include <ukdyn/modelfile/model.hpp>

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

}  // namespace

int linearize_command(const LinearizeArguments& args) {
  if (args.format != "json" && args.format != "csv")
    throw UsageError("--format " + args.format + ": must be json or csv");
  const Model model = load_source(args.source);
  const System& sys = model.system;
  OperatingPoint op = operating_point(model, args.at);
  if (args.project || (model.project_initial && args.at.empty()))
    op = project_onto_manifold(sys, op);

  LinearizeOptions options;
  options.independent_positions = args.independent;
  options.independent_velocities = args.independent_velocities;
  if (args.equilibrium) {
    EquilibriumOptions eo;
    eo.unknowns = args.unknowns;
    eo.linearize = options;
    op = find_equilibrium(sys, op, eo).point;
  }

  // inputs: a coordinate's name is a generalized force along it, a parameter's name the parameter
  std::vector<LinearInput> inputs;
  try {
    inputs = model_inputs(model, args.inputs.empty() ? std::string() : source_text(args.source),
                          args.inputs, "--inputs");
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  std::vector<LinearOutput> outputs;
  for (const std::string& name : args.outputs) {
    try {
      outputs.push_back(coordinate_output(sys, name));
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--outputs: ") + e.what());
    }
  }

  const LinearModel lm = linearize(sys, op, inputs, outputs, options);
  std::vector<std::string> derivative_names;
  for (const auto& s : lm.state_names) derivative_names.push_back(s + "'");

  if (args.format == "csv") {
    print_csv_matrix("A", lm.A, derivative_names, lm.state_names);
    print_csv_matrix("B", lm.B, derivative_names, lm.input_names);
    print_csv_matrix("C", lm.C, lm.output_names, lm.state_names);
    print_csv_matrix("D", lm.D, lm.output_names, lm.input_names);
    print_csv_matrix("A_error", lm.A_error, derivative_names, lm.state_names);
    std::printf("# eigenvalues\nre,im\n");
    for (Index k = 0; k < lm.eigenvalues.size(); ++k)
      std::printf("%.17g,%.17g\n", lm.eigenvalues(k).real(), lm.eigenvalues(k).imag());
    return kExitOk;
  }
  nlohmann::json j;
  j["model"] = model.name;
  j["t"] = op.t;
  j["q"] = std::vector<double>(op.q.data(), op.q.data() + op.q.size());
  j["qd"] = std::vector<double>(op.qd.data(), op.qd.data() + op.qd.size());
  j["coordinates"] = sys.coordinate_names();
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
  std::printf("%s\n", j.dump(2).c_str());
  return kExitOk;
}

}  // namespace ukdyn::cli

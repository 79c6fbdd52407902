// SPDX-License-Identifier: BSD-3-Clause
// ukdyn._linearize and ukdyn._equilibrium: Model.linearize() and Model.equilibrium() of the
// package (python/ukdyn/linear.py); the physics is analysis/linearize.hpp.
#include <algorithm>
#include <complex>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include <pybind11/complex.h>

#include "common.hpp"
#include "embedded.hpp"  // app/embedded.hpp: the example models, embedded at build time
#include "ukdyn/analysis/linearize.hpp"

namespace ukdyn::python {
namespace {

// the state given from Python: the model's initial state where q or q_dot is None
OperatingPoint point_of(const Model& model, py::object q, py::object qd, py::object t,
                        const char* who) {
  OperatingPoint op{model.q0, model.qd0, model.options.t_start};
  const Index n = model.system.coordinate_count();
  if (!q.is_none()) read_vector(q, n, who, "q", op.q);
  if (!qd.is_none()) read_vector(qd, n, who, "q_dot", op.qd);
  if (!t.is_none()) op.t = t.cast<double>();
  return op;
}

// the text of the model, for parameter inputs: its file, or the embedded example
std::string model_text(const Model& model) {
  std::ifstream in(model.file, std::ios::binary);
  if (in) return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  const std::string stem = std::filesystem::path(model.file).stem().string();
  for (const auto& f : cli::example_models())
    if (stem == f.name && model.file.find("examples/models/") != std::string::npos) return f.text;
  throw std::invalid_argument("Model.linearize: a parameter input needs the model's text, and '" +
                              model.file + "' cannot be read (load the model from a file)");
}

py::dict linearize_model(const Model& model, py::object q, py::object qd, py::object t,
                         const std::vector<std::string>& inputs,
                         const std::vector<std::string>& outputs,
                         const std::vector<std::string>& independent,
                         const std::vector<std::string>& independent_velocities, bool equilibrium,
                         const std::vector<std::string>& unknowns, bool project) {
  const System& sys = model.system;
  OperatingPoint op = point_of(model, q, qd, t, "Model.linearize");
  if (project) op = project_onto_manifold(sys, op);
  LinearizeOptions options;
  options.independent_positions = independent;
  options.independent_velocities = independent_velocities;
  if (equilibrium) {
    EquilibriumOptions eo;
    eo.unknowns = unknowns;
    eo.linearize = options;
    op = find_equilibrium(sys, op, eo).point;
  }
  // a coordinate's name is a generalized force along it, a parameter's name the parameter
  bool parameters = false;
  for (const auto& name : inputs) parameters = parameters || model.parameters.count(name) > 0;
  const std::vector<LinearInput> in = model_inputs(
      model, parameters ? model_text(model) : std::string(), inputs, "Model.linearize: input");
  std::vector<LinearOutput> out;
  for (const auto& name : outputs) out.push_back(coordinate_output(sys, name));
  const LinearModel lm = linearize(sys, op, in, out, options);

  py::dict d;
  d["A"] = copy_matrix(lm.A);
  d["B"] = copy_matrix(lm.B);
  d["C"] = copy_matrix(lm.C);
  d["D"] = copy_matrix(lm.D);
  d["A_error"] = copy_matrix(lm.A_error);
  d["B_error"] = copy_matrix(lm.B_error);
  d["C_error"] = copy_matrix(lm.C_error);
  d["D_error"] = copy_matrix(lm.D_error);
  d["states"] = lm.state_names;
  d["inputs"] = lm.input_names;
  d["outputs"] = lm.output_names;
  d["x0"] = copy_vector(lm.x0);
  d["f0"] = copy_vector(lm.f0);
  d["q"] = copy_vector(op.q);
  d["q_dot"] = copy_vector(op.qd);
  d["t"] = op.t;
  d["chart_condition"] = lm.chart_condition;
  // eigenvalues (s) and eigenvectors (s × s) as complex arrays
  const Index s = lm.eigenvalues.size();
  py::array_t<std::complex<double>> ev(s);
  py::array_t<std::complex<double>, py::array::f_style> vec({s, s});
  for (Index k = 0; k < s; ++k) {
    ev.mutable_at(k) = lm.eigenvalues(k);
    for (Index i = 0; i < s; ++i) vec.mutable_at(i, k) = lm.eigenvectors(i, k);
  }
  d["eigenvalues"] = ev;
  d["eigenvectors"] = vec;
  return d;
}

py::tuple equilibrium_of(const Model& model, py::object q, py::object qd, py::object t,
                         const std::vector<std::string>& unknowns, double tolerance,
                         const std::vector<std::string>& independent) {
  EquilibriumOptions eo;
  eo.unknowns = unknowns;
  eo.tolerance = tolerance;
  eo.linearize.independent_positions = independent;
  const Equilibrium eq =
      find_equilibrium(model.system, point_of(model, q, qd, t, "Model.equilibrium"), eo);
  return py::make_tuple(copy_vector(eq.point.q), copy_vector(eq.point.qd), eq.residual,
                        eq.iterations);
}

}  // namespace

void bind_linearize(py::module_& m) {
  m.def("_linearize", &linearize_model, py::arg("model"), py::arg("q"), py::arg("q_dot"),
        py::arg("t"), py::arg("inputs"), py::arg("outputs"), py::arg("independent"),
        py::arg("independent_velocities"), py::arg("equilibrium"), py::arg("unknowns"),
        py::arg("project"),
        "The linear model of a Model as a dict of NumPy arrays and names (Model.linearize).");
  m.def("_equilibrium", &equilibrium_of, py::arg("model"), py::arg("q"), py::arg("q_dot"),
        py::arg("t"), py::arg("unknowns"), py::arg("tolerance"), py::arg("independent"),
        "(q, q_dot, residual, iterations) of an equilibrium found from a guess "
        "(Model.equilibrium).");
}

}  // namespace ukdyn::python

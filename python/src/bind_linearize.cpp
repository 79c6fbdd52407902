// SPDX-License-Identifier: BSD-3-Clause
// ukdyn._linearize and ukdyn._equilibrium: Model.linearize() and Model.equilibrium() of the
// package (python/ukdyn/linear.py); the physics is analysis/linearize.hpp.
#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <pybind11/complex.h>

#include "common.hpp"
#include "embedded.hpp"  // app/embedded.hpp: the example models, embedded at build time
#include "ukdyn/analysis/linearize.hpp"
#include "ukdyn/analysis/model_linearize.hpp"

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

// the linear model as a dict of NumPy arrays and names (LinearModel of linear.py, without the
// operating point)
py::dict model_dict(const LinearModel& lm) {
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
  d["chart_condition"] = lm.chart_condition;
  d["open_contacts"] = lm.open_contacts;
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

// the request of Model.linearize / Model.linearize_along
ModelLinearizeRequest request_of(const std::vector<std::string>& inputs,
                                 const std::vector<std::string>& outputs,
                                 const std::vector<std::string>& independent,
                                 const std::vector<std::string>& independent_velocities,
                                 const std::vector<std::string>& states, double initial_step) {
  ModelLinearizeRequest r;
  if (!(initial_step > 0) || !std::isfinite(initial_step))
    throw std::invalid_argument("Model.linearize: initial_step = " + std::to_string(initial_step) +
                                " must be > 0 (Ridders' first step relative to each variable's "
                                "scale; default 0.1)");
  r.options.initial_step = initial_step;
  r.inputs = inputs;
  r.outputs = outputs;
  r.options.independent_positions = independent;
  r.options.independent_velocities = independent_velocities;
  r.options.states = states;
  return r;
}

py::dict linearize_model_py(const Model& model, py::object q, py::object qd, py::object t,
                            const std::vector<std::string>& inputs,
                            const std::vector<std::string>& outputs,
                            const std::vector<std::string>& independent,
                            const std::vector<std::string>& independent_velocities,
                            const std::vector<std::string>& states, bool equilibrium,
                            const std::vector<std::string>& unknowns, bool project,
                            double initial_step) {
  ModelLinearizeRequest r =
      request_of(inputs, outputs, independent, independent_velocities, states, initial_step);
  r.equilibrium = equilibrium;
  r.unknowns = unknowns;
  r.project = project;
  const ModelLinearization result = linearize_model(
      model, point_of(model, q, qd, t, "Model.linearize"), r, [&] { return model_text(model); },
      "Model.linearize");
  py::dict d = model_dict(result.linear);
  d["q"] = copy_vector(result.point.q);
  d["q_dot"] = copy_vector(result.point.qd);
  d["t"] = result.point.t;
  return d;
}

// the points (t: N, q and q_dot: N × n) of a motion, linearized in one chart
py::list linearize_along_py(const Model& model, py::object t, py::object q, py::object qd,
                            const std::vector<std::string>& inputs,
                            const std::vector<std::string>& outputs,
                            const std::vector<std::string>& independent,
                            const std::vector<std::string>& independent_velocities,
                            const std::vector<std::string>& states, double initial_step) {
  const char* who = "Model.linearize_along";
  const Index n = model.system.coordinate_count();
  const auto ts = t.cast<std::vector<double>>();
  const auto qs = q.cast<std::vector<std::vector<double>>>();
  const auto qds = qd.cast<std::vector<std::vector<double>>>();
  if (qs.size() != ts.size() || qds.size() != ts.size())
    throw std::invalid_argument(std::string(who) + ": t has " + std::to_string(ts.size()) +
                                " samples, q " + std::to_string(qs.size()) + " and q_dot " +
                                std::to_string(qds.size()) + " rows; they must agree");
  std::vector<OperatingPoint> path;
  for (std::size_t k = 0; k < ts.size(); ++k) {
    if (Index(qs[k].size()) != n || Index(qds[k].size()) != n)
      throw std::invalid_argument(std::string(who) + ": row " + std::to_string(k) +
                                  " of q or q_dot has " + std::to_string(qs[k].size()) + " / " +
                                  std::to_string(qds[k].size()) + " entries, expected " +
                                  std::to_string(n) + " (the coordinates)");
    path.push_back({Eigen::Map<const VectorXd>(qs[k].data(), n),
                    Eigen::Map<const VectorXd>(qds[k].data(), n), ts[k]});
  }
  const auto models = linearize_model_along(
      model, path,
      request_of(inputs, outputs, independent, independent_velocities, states, initial_step),
      [&] { return model_text(model); }, who);
  py::list out;
  for (std::size_t k = 0; k < models.size(); ++k) {
    py::dict d = model_dict(models[k]);
    d["q"] = copy_vector(path[k].q);
    d["q_dot"] = copy_vector(path[k].qd);
    d["t"] = path[k].t;
    out.append(d);
  }
  return out;
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
  m.def("_linearize", &linearize_model_py, py::arg("model"), py::arg("q"), py::arg("q_dot"),
        py::arg("t"), py::arg("inputs"), py::arg("outputs"), py::arg("independent"),
        py::arg("independent_velocities"), py::arg("states"), py::arg("equilibrium"),
        py::arg("unknowns"), py::arg("project"), py::arg("initial_step") = 0.1,
        "The linear model of a Model as a dict of NumPy arrays and names (Model.linearize).");
  m.def("_linearize_along", &linearize_along_py, py::arg("model"), py::arg("t"), py::arg("q"),
        py::arg("q_dot"), py::arg("inputs"), py::arg("outputs"), py::arg("independent"),
        py::arg("independent_velocities"), py::arg("states"), py::arg("initial_step") = 0.1,
        "The linear models along a motion, one dict per point (Model.linearize_along).");
  m.def("_equilibrium", &equilibrium_of, py::arg("model"), py::arg("q"), py::arg("q_dot"),
        py::arg("t"), py::arg("unknowns"), py::arg("tolerance"), py::arg("independent"),
        "(q, q_dot, residual, iterations) of an equilibrium found from a guess "
        "(Model.equilibrium).");
}

}  // namespace ukdyn::python

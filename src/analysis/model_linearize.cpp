// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/model_linearize.cpp
/// linearize() of a model file by names, for the command line and Python
/// (include/ukdyn/analysis/model_linearize.hpp).
#include "ukdyn/analysis/model_linearize.hpp"

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "analysis/internal.hpp"

namespace ukdyn {
namespace {

// inputs by name, name errors as LinearizeNameError
std::vector<LinearInput> inputs_of(const Model& model, const ModelLinearizeRequest& request,
                                   const std::function<std::string()>& text, const char* who) {
  bool parameters = false;
  for (const auto& name : request.inputs)
    parameters = parameters || model.parameters.count(name) > 0;
  const std::string input_who = std::string(who) + ": input";
  try {
    return model_inputs(model, parameters ? text() : std::string(), request.inputs,
                        input_who.c_str());
  } catch (const LinearizeNameError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    throw LinearizeNameError(e.what());
  }
}

}  // namespace

std::vector<LinearOutput> model_outputs(const Model& model, const std::vector<std::string>& names,
                                        const char* who) {
  std::vector<LinearOutput> outputs;
  for (const std::string& name : names) {
    const auto& exprs = model.output_names;
    if (const auto it = std::find(exprs.begin(), exprs.end(), name); it != exprs.end()) {
      // an output expression: the model's program over [q; q'; t], its output k
      struct Evaluator {
        expr::Program program;
        std::vector<double> in, out, scratch;
      };
      auto ev = std::make_shared<Evaluator>();
      ev->program = model.output_program;
      ev->in.assign(std::size_t(ev->program.inputs()), 0.0);
      ev->out.assign(std::size_t(ev->program.outputs()), 0.0);
      ev->scratch.assign(std::size_t(ev->program.scratch_size()), 0.0);
      const std::size_t k = std::size_t(it - exprs.begin());
      LinearOutput y;
      y.name = name;
      y.expression = [ev, k](const VectorXd& q, const VectorXd& qd, double t) {
        const Index n = q.size();
        std::copy_n(q.data(), n, ev->in.begin());
        std::copy_n(qd.data(), n, ev->in.begin() + n);
        ev->in[std::size_t(2 * n)] = t;
        ev->program.evaluate(ev->in.data(), ev->out.data(), ev->scratch.data());
        return ev->out[k];
      };
      outputs.push_back(std::move(y));
      continue;
    }
    try {
      outputs.push_back(coordinate_output(model.system, name));
    } catch (const std::invalid_argument& e) {
      std::string list;
      for (const auto& o : exprs) list += (list.empty() ? "" : ", ") + o;
      throw LinearizeNameError(std::string(who) + ": output " + name +
                               ": neither a coordinate, NAME_dot, nor an output expression (" +
                               (list.empty() ? "the model has none" : list) + "): " + e.what());
    }
  }
  return outputs;
}

ModelLinearization linearize_model(const Model& model, OperatingPoint at,
                                   const ModelLinearizeRequest& request,
                                   const std::function<std::string()>& text, const char* who) {
  const System& sys = model.system;
  // the names first: a misspelt one is reported before any work
  const std::vector<LinearInput> inputs = inputs_of(model, request, text, who);
  const std::vector<LinearOutput> outputs = model_outputs(model, request.outputs, who);
  // the point: projected, then an equilibrium found from it, as asked
  if (request.project) at = project_onto_manifold(sys, at);
  if (request.equilibrium) {
    EquilibriumOptions eo;
    eo.unknowns = request.unknowns;
    eo.linearize = request.options;
    eo.linearize.states.clear();  // the search works on the whole state
    at = find_equilibrium(sys, at, eo).point;
  }
  return {at, linearize(sys, at, inputs, outputs, request.options)};
}

std::vector<LinearModel> linearize_model_along(const Model& model,
                                               const std::vector<OperatingPoint>& path,
                                               const ModelLinearizeRequest& request,
                                               const std::function<std::string()>& text,
                                               const char* who) {
  const std::vector<LinearInput> inputs = inputs_of(model, request, text, who);
  const std::vector<LinearOutput> outputs = model_outputs(model, request.outputs, who);
  return linearize_along(model.system, path, inputs, outputs, request.options);
}

std::vector<OperatingPoint> trajectory_points(const Trajectory& trajectory) {
  const Index n = trajectory.n;
  std::vector<OperatingPoint> path;
  path.reserve(std::size_t(trajectory.samples()));
  for (Index i = 0; i < trajectory.samples(); ++i) {
    OperatingPoint p;
    p.q = Eigen::Map<const VectorXd>(trajectory.q.data() + i * n, n);
    p.qd = Eigen::Map<const VectorXd>(trajectory.qd.data() + i * n, n);
    p.t = trajectory.t[std::size_t(i)];
    path.push_back(std::move(p));
  }
  return path;
}

}  // namespace ukdyn

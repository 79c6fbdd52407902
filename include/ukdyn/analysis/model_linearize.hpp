// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/model_linearize.hpp
/// linearize() of a model file by names, as the command line (`ukdyn linearize`) and Python
/// (`Model.linearize`, `Model.linearize_along`) ask for it: the one place where a request's
/// names become inputs, outputs and options, and where the operating point is projected or
/// an equilibrium found first (docs/linearize.md).
#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ukdyn/analysis/linearize.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {

/// A name of a request that names nothing of the model (an input, an output): the command
/// line reports it as a usage error.
class LinearizeNameError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// What to linearize, by names.
struct ModelLinearizeRequest {
  std::vector<std::string> inputs;   ///< coordinates (a force along one) or parameters
  std::vector<std::string> outputs;  ///< coordinates, NAME_dot, or `output: expressions:` names
  /// independent coordinates (independent_positions, independent_velocities) and the kept
  /// states (states), as LinearizeOptions
  LinearizeOptions options;
  bool project = false;      ///< project the point onto the manifold first
  bool equilibrium = false;  ///< find an equilibrium (or steady motion) from the point first
  std::vector<std::string> unknowns;  ///< the equilibrium's unknowns (empty: the positions)
};

/// The outputs called `names`: a coordinate (its position), NAME_dot (its rate), or one of the
/// model's output expressions (`output: expressions:`, evaluated at the completed state).
/// @throws LinearizeNameError naming `who`, the name and what the names may be. Cost O(n) each.
std::vector<LinearOutput> model_outputs(const Model& model, const std::vector<std::string>& names,
                                        const char* who);

/// The result of linearize_model: the operating point used (after projection or the
/// equilibrium search) and the linear model there.
struct ModelLinearization {
  OperatingPoint point;  ///< the operating point (q, q', t) the model was linearized at
  LinearModel linear;    ///< the linear model at that point
};

/// The request carried out at `at`: projection (request.project), the equilibrium search
/// (request.equilibrium), the inputs (model_inputs; `text` gives the model's text, called only
/// when a parameter is an input) and outputs (model_outputs), then linearize().
/// @throws LinearizeNameError on a bad input or output name (prefixed `who`); otherwise as
/// project_onto_manifold, find_equilibrium and linearize. Cost: theirs.
ModelLinearization linearize_model(const Model& model, OperatingPoint at,
                                   const ModelLinearizeRequest& request,
                                   const std::function<std::string()>& text, const char* who);

/// linearize_along() of the model at the points of `path` (e.g. the samples of a run), with
/// the request's inputs, outputs and options (project, equilibrium and unknowns unused).
/// @throws as linearize_model and linearize_along. Cost: linearize() per point.
std::vector<LinearModel> linearize_model_along(const Model& model,
                                               const std::vector<OperatingPoint>& path,
                                               const ModelLinearizeRequest& request,
                                               const std::function<std::string()>& text,
                                               const char* who);

/// The samples of a trajectory as operating points (t, q, q' of each).
/// Cost O(N n).
std::vector<OperatingPoint> trajectory_points(const Trajectory& trajectory);

}  // namespace ukdyn

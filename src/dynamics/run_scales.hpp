// SPDX-License-Identifier: BSD-3-Clause
// The run's length and speed (not installed): the raw scales behind set_run_scales
// (dynamics/projection.hpp) that linearize's steps also take (analysis/reduced_dynamics.cpp;
// docs/simulation.md, "Scales and tolerances"; docs/linearize.md, "Derivatives and their error").
#pragma once

#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/workspace.hpp"

namespace ukdyn::detail {

/// The scales a state gives a run, before their classes are taken.
struct RunLengthSpeed {
  double length = 1.0;      ///< ℓ = ‖q‖∞, 1 when every coordinate is 0 (has_length false)
  bool has_length = false;  ///< ‖q‖∞ > 0 and finite
  double energy = 0.0;      ///< E = max(T + |V|, ‖Q‖∞ ℓ) at the state (0 when not finite)
  double speed = 1.0;       ///< v (see run_length_speed), > 0
};

/// ℓ, E and v = the largest of ‖q'‖∞, √(2E / m) (m = 1ᵀ M 1 / n, a Rayleigh quotient of M) and
/// ℓ / duration (no such term for duration <= 0), ℓ when none of them is > 0. With `angles`
/// (n flags, SimulationOptions::angle_coordinates) the lengths' own: ‖q‖∞, ‖Q‖∞, ‖q'‖∞ and m =
/// 1_Lᵀ M 1_L / n_L over the coordinates not flagged (1_L their indicator, n_L their number), so
/// that ℓ, E and v move with the unit of length alone (T + |V| is the whole system's). Evaluates
/// M and Q at (q, q', t) in ws (ws.status is left kOk). Cost: one unconstrained evaluation, O(n³).
RunLengthSpeed run_length_speed(const System& sys, Workspace& ws,
                                const Eigen::Ref<const VectorXd>& q,
                                const Eigen::Ref<const VectorXd>& qd, double t, double duration,
                                const std::vector<bool>* angles = nullptr);

}  // namespace ukdyn::detail

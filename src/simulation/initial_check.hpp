// SPDX-License-Identifier: BSD-3-Clause
// The initial state's consistency in the run's own scales: what simulate checks at t_start and
// what `ukdyn check` reports, from one function, so that the two never disagree.
#pragma once

#include <string>
#include <vector>

#include "ukdyn/core/system.hpp"

namespace ukdyn::detail {

/// One line per constraint that (q, q', t) violates beyond `tolerance` times the row's scale of a
/// run of length `duration` from this state (set_run_scales: ‖a_i‖ ℓ for positions, ‖a_i‖ v for
/// velocities; duration <= 0 takes the speed scale from the state alone; `angle_coordinates`
/// weighs the columns as SimulationOptions::angle_coordinates). Cost: one Workspace, one
/// evaluation of every constraint's rows. `names`, when given, receives the violated
/// constraints' names, one per line.
std::vector<std::string> check_initial_conditions(const System& sys,
                                                  const Eigen::Ref<const VectorXd>& q,
                                                  const Eigen::Ref<const VectorXd>& qd, double t,
                                                  double tolerance, double duration,
                                                  std::vector<std::string>* names = nullptr,
                                                  const std::vector<bool>& angle_coordinates = {});

}  // namespace ukdyn::detail

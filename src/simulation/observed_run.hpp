// SPDX-License-Identifier: BSD-3-Clause
// detail::simulate_observed (dynamics/internal.hpp) with a second observer, `started`, called
// with the run's workspace once it is made, before the first evaluation, and with each workspace
// the run makes later (the branch check's, Run::branch_workspace): the controlled plant's scratch
// of each then points at that workspace's contact modes (ws.activity_override; the branch
// check's copies the run's), which its controller's model mirrors
// (control/simulate_controlled.cpp, docs/contact.md "Contacts under control"). rate_unit > 0
// replaces the rate decade that set_run_scales finds (Workspace::rate_unit): a controlled plant's
// own, which the augmented system's auxiliary coordinates (unit masses, integrands as forces)
// would blur.
#pragma once

#include <functional>

#include "dynamics/internal.hpp"

namespace ukdyn::detail {

Trajectory simulate_observed(const System& sys, const Eigen::Ref<const VectorXd>& q0,
                             const Eigen::Ref<const VectorXd>& qd0,
                             const SimulationOptions& options,
                             const std::function<void(const Workspace&)>& finished,
                             const std::function<void(Workspace&)>& started,
                             double rate_unit = 0.0);

}  // namespace ukdyn::detail

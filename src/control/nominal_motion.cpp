// SPDX-License-Identifier: BSD-3-Clause
// Stage 1 of the control pipeline: the nominal model's physically constrained motion without
// control, a_p = a + L⁻ᵀ W_p⁺ (b_p − A_p a) (+ its non-ideal part), eq. (9) — the "unconstrained"
// acceleration that the requirements are then imposed on.
#include "control/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn {

ControlStatus evaluate_model(const Controller& ctrl, ControlWorkspace& ws,
                             const Eigen::Ref<const VectorXd>& q,
                             const Eigen::Ref<const VectorXd>& qd, double t) {
  control_detail::require_same_controller(ctrl, ws, "ukdyn::evaluate_model");
  // M, L, a, A_p, W_p, a_p = model.qdd, physical reaction model.Qc
  if (forward_dynamics(ctrl.model(), ws.model, q, qd, t) != Status::kOk) {
    return control_detail::fail(ws, ControlStatus::kModelFailed, "model", -1, t);
  }
  return ControlStatus::kOk;
}

}  // namespace ukdyn

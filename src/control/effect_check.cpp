// SPDX-License-Identifier: BSD-3-Clause
// Stage 5 of the control pipeline: the control force and its effect on the nominal model.
//   Qc_control = Qc_nominal + Qc_robust
//   q''        = a_p + P Qc_control,          P = L⁻ᵀ (I − W_p⁺ W_p) L⁻¹
//   Qc_physical = model.Qc + (M P − I) Qc_control   (the physical reaction under the control)
//   power      = Qc_controlᵀ q'
#include "control/internal.hpp"

namespace ukdyn {

ControlStatus check_control(const Controller& ctrl, ControlWorkspace& ws,
                            const Eigen::Ref<const VectorXd>& qd) {
  control_detail::require_same_controller(ctrl, ws, "ukdyn::check_control");
  return control_detail::check_control_on(ctrl, ws, qd, ws.model.decomposition);
}

ControlStatus control_detail::check_control_on(const Controller&, ControlWorkspace& ws,
                                               const Eigen::Ref<const VectorXd>& qd,
                                               FundamentalDecomposition& dp) {
  // Qc_control = Qc_nominal + Qc_robust
  ws.Qc_control = ws.Qc_nominal + ws.Qc_robust;
  if (ws.model.active_rows > 0) {
    // P F and M P F by the non-ideal projection of F
    dp.project_nonideal(ws.Qc_control, ws.tmp_n, ws.tmp_n2, ws.lambda_p);
    ws.qdd = ws.model.qdd + ws.tmp_n;
    ws.Qc_physical = ws.model.Qc + ws.tmp_n2 - ws.Qc_control;
  } else {
    // P = M⁻¹
    dp.solve_mass(ws.Qc_control, ws.tmp_n);
    ws.qdd = ws.model.qdd + ws.tmp_n;
    ws.Qc_physical = ws.model.Qc;
  }
  ws.power = ws.Qc_control.dot(qd);
  if (!ws.Qc_control.allFinite() || !ws.qdd.allFinite()) {
    return control_detail::fail(ws, ControlStatus::kNonFiniteResult, "Qc_control", -1,
                                ws.failed_time);
  }
  return ws.status;
}

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// compute_control: the stages of the control pipeline (control/control.hpp) in order.
#include <stdexcept>
#include <string>

#include "control/internal.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn {

namespace {
void require_size(const Eigen::Ref<const VectorXd>& v, Index n, const char* what) {
  if (v.size() != n) {
    throw std::invalid_argument(std::string("ukdyn::compute_control: ") + what + " has " +
                                format_number(v.size()) +
                                " entries, expected n = " + format_number(n));
  }
}
}  // namespace

ControlStatus compute_control(const Controller& ctrl, ControlWorkspace& ws,
                              const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t) {
  return control_detail::compute_control_in(ctrl, ws, q, qd, t, nullptr);
}

ControlStatus control_detail::compute_control_in(const Controller& ctrl, ControlWorkspace& ws,
                                                 const Eigen::Ref<const VectorXd>& q,
                                                 const Eigen::Ref<const VectorXd>& qd, double t,
                                                 const Workspace* plant) {
  control_detail::require_same_controller(ctrl, ws, "ukdyn::compute_control");
  require_size(q, ctrl.coordinate_count(), "q");
  require_size(qd, ctrl.coordinate_count(), "q_dot");
  ++ws.counters.evaluations;
  ws.status = ControlStatus::kOk;
  ws.failed_quantity = "";
  ws.failed_index = -1;
  ws.failed_time = t;
  // a_p → A_r, b_r, e → law → robust term → control force, q'', physical reaction
  // (stage 1 and the law's factorization of M fused where they factorize the same M)
  const bool fused = control_detail::evaluate_model_fused(ctrl, ws, q, qd, t, plant);
  ControlStatus s = fused ? ControlStatus::kOk : evaluate_model(ctrl, ws, q, qd, t);
  if (s != ControlStatus::kOk) return s;
  s = assemble_requirements(ctrl, ws, q, qd, t);
  if (s != ControlStatus::kOk) return s;
  s = control_detail::solve_law_on(ctrl, ws, q, qd, t, fused);
  const bool not_met = s == ControlStatus::kRequirementsNotMet;
  if (s != ControlStatus::kOk && !not_met) return s;
  s = apply_robust(ctrl, ws);
  if (s != ControlStatus::kOk && s != ControlStatus::kRequirementsNotMet) return s;
  s = control_detail::check_control_on(ctrl, ws, qd,
                                       fused ? ws.decomposition : ws.model.decomposition);
  if (s != ControlStatus::kOk && s != ControlStatus::kRequirementsNotMet) return s;
  if (not_met) {
    // a valid least-squares force; the rows missed are in ws.met and ws.residual
    ws.status = ControlStatus::kRequirementsNotMet;
    ws.failed_quantity = "requirements";
    ++ws.counters.not_met;
  }
  return ws.status;
}

}  // namespace ukdyn

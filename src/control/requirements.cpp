// SPDX-License-Identifier: BSD-3-Clause
// Requirements: constraints read as trajectory requirements, with their error dynamics (the
// Baumgarte gains of Constraint::stabilize), and stage 2 of the control pipeline:
//   A_r q'' = b_r (b_r with the error dynamics),   e = b_r − A_r a_p.
#include <cmath>
#include <stdexcept>
#include <string>

#include "control/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn {

using control_detail::format;

ErrorDynamics ErrorDynamics::second_order(double omega, double zeta) {
  if (!(omega > 0.0) || !std::isfinite(omega) || !(zeta > 0.0) || !std::isfinite(zeta)) {
    throw std::invalid_argument(
        "ukdyn::ErrorDynamics::second_order: omega and zeta must be > 0, "
        "got omega = " +
        format(omega) + ", zeta = " + format(zeta) +
        " (for no error dynamics use ErrorDynamics::none())");
  }
  return {Order::kSecond, zeta * omega, omega};
}

ErrorDynamics ErrorDynamics::gains(double alpha, double beta) {
  if (!(alpha >= 0.0) || !(beta >= 0.0) || !std::isfinite(alpha) || !std::isfinite(beta)) {
    throw std::invalid_argument(
        "ukdyn::ErrorDynamics::gains: alpha and beta must be >= 0, got "
        "alpha = " +
        format(alpha) + ", beta = " + format(beta));
  }
  return {Order::kSecond, alpha, beta};
}

ErrorDynamics ErrorDynamics::first_order(double rate) {
  if (!(rate > 0.0) || !std::isfinite(rate)) {
    throw std::invalid_argument("ukdyn::ErrorDynamics::first_order: the rate must be > 0, got " +
                                format(rate) +
                                " (for no error dynamics use "
                                "ErrorDynamics::none())");
  }
  return {Order::kFirst, rate, 0.0};
}

Constraint requirement(Constraint c, const ErrorDynamics& d) {
  using Order = ErrorDynamics::Order;
  const std::string who = "ukdyn::requirement '" + c.name() + "'";
  switch (c.kind()) {
    case ConstraintKind::kHolonomic:
      if (d.order == Order::kFirst) {
        throw std::invalid_argument(
            who +
            ": a holonomic requirement phi(q, t) = 0 takes second-order error dynamics "
            "(ErrorDynamics::second_order(omega, zeta) or gains(alpha, beta)); for "
            "e' + k e = 0 write it as a nonholonomic requirement psi = d/dt phi");
      }
      break;
    case ConstraintKind::kNonholonomic:
      if (d.order == Order::kSecond) {
        throw std::invalid_argument(
            who +
            ": a nonholonomic requirement psi(q, q', t) = 0 is differentiated once, so its "
            "error obeys first-order dynamics e' + k e = 0: use "
            "ErrorDynamics::first_order(k)");
      }
      break;
    case ConstraintKind::kAcceleration:
      if (d.order != Order::kNone) {
        throw std::invalid_argument(
            who +
            ": a requirement given in acceleration form has no error to correct; give "
            "ErrorDynamics::none() or write it as a holonomic or nonholonomic requirement");
      }
      return c;
  }
  if (d.order == Order::kNone) return c.stabilize(0.0, 0.0);
  return c.stabilize(d.alpha, d.order == Order::kSecond ? d.beta : 0.0);
}

ControlStatus assemble_requirements(const Controller& ctrl, ControlWorkspace& ws,
                                    const Eigen::Ref<const VectorXd>& q,
                                    const Eigen::Ref<const VectorXd>& qd, double t) {
  control_detail::require_same_controller(ctrl, ws, "ukdyn::assemble_requirements");
  // A_r, b_r of the active requirements, b_r ← b_r − 2α phi' − β² phi (resp. − α psi)
  if (assemble_constraints(ctrl.requirements(), ws.req, q, qd, t) != Status::kOk) {
    return control_detail::fail(ws, ControlStatus::kNonFiniteInput, ws.req.failed_quantity,
                                ws.req.failed_index, t);
  }
  // e = b_r − A_r a_p
  ws.e = ws.req.b;
  ws.e.noalias() -= ws.req.A * ws.model.qdd;
  return ControlStatus::kOk;
}

}  // namespace ukdyn

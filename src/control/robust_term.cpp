// SPDX-License-Identifier: BSD-3-Clause
// Stage 4 of the control pipeline: the robust term for a plant that differs from the nominal
// model (docs/control.md, "Uncertain systems"). Per requirement row i, with the prescribed error
// dynamics e'' + 2α e' + β² e = r (holonomic; r = 0 on the nominal model) or e' + α e = r:
//   sliding variable   s_i = e_i' + α e_i   (holonomic),   s_i = e_i   (nonholonomic)
//   uncertainty        rho_i = bound + relative_bound |b_r,i|,  delta = gain_uncertainty
//   gain               kappa_i = rho_i + delta max_j rho_j / (1 − delta)
//   requirement accel. v_i = −kappa_i sat(s_i / epsilon)
// and Qc_robust = the law's force for v (the same decomposition as the nominal force). The
// Lyapunov function V = (β² + 2α²) e² + 2α e e' + e'² has V' = −2α(β² e² + e'²) + 2 s r, and
// 2 s r <= kappa epsilon / 2, whence the bound of RobustControl.
#include <algorithm>
#include <cmath>

#include "control/internal.hpp"

namespace ukdyn {

ControlStatus apply_robust(const Controller& ctrl, ControlWorkspace& ws) {
  control_detail::require_same_controller(ctrl, ws, "ukdyn::apply_robust");
  if (!ctrl.robust()) {
    ws.s.setZero();
    ws.kappa.setZero();
    ws.v.setZero();
    ws.u_robust.setZero();
    ws.Qc_robust.setZero();
    return ws.status;
  }
  const RobustControl& r = *ctrl.robust();
  const System& reqs = ctrl.requirements();
  // s_i and rho_i (kept in kappa) of the active rows
  double rho_max = 0.0;
  for (Index k = 0; k < reqs.constraint_count(); ++k) {
    const Index r0 = reqs.row_offset(k), rows = reqs.constraint(k).rows();
    const bool active = ws.req.active[std::size_t(k)] != 0;
    const bool holonomic = reqs.constraint(k).kind() == ConstraintKind::kHolonomic;
    const double alpha = ws.req.stabilization[std::size_t(k)].alpha;
    for (Index i = r0; i < r0 + rows; ++i) {
      if (!active) {
        ws.s[i] = 0.0;
        ws.kappa[i] = 0.0;
        continue;
      }
      // s = e' + α e  (phi, phi' from the stabilized assembly), or s = psi
      ws.s[i] = holonomic ? ws.req.phi_dot[i] + alpha * ws.req.phi[i] : ws.req.phi_dot[i];
      ws.kappa[i] = r.bound + r.relative_bound * std::abs(ws.req.b[i]);
      rho_max = std::max(rho_max, ws.kappa[i]);
    }
  }
  // kappa_i = rho_i + δ rho_max / (1 − δ);  v_i = −kappa_i sat(s_i / ε)
  const double delta = r.gain_uncertainty, extra = delta * rho_max / (1.0 - delta);
  for (Index k = 0; k < reqs.constraint_count(); ++k) {
    const Index r0 = reqs.row_offset(k), rows = reqs.constraint(k).rows();
    const bool active = ws.req.active[std::size_t(k)] != 0;
    for (Index i = r0; i < r0 + rows; ++i) {
      if (!active) {
        ws.v[i] = 0.0;
        continue;
      }
      ws.kappa[i] += extra;
      ws.v[i] = -ws.kappa[i] * std::clamp(ws.s[i] / r.boundary_layer, -1.0, 1.0);
    }
  }
  // Qc_robust = the law's force for v
  control_detail::apply_law(ctrl, ws, ws.v, ws.u_robust, ws.Qc_robust, ws.tmp_n);
  return ws.status;
}

namespace control_detail {

BoundWatch::BoundWatch(const Controller& ctrl, double t_start) : ctrl_(&ctrl), t_start_(t_start) {}

void BoundWatch::add(double t, Index i, double e, double bound) {
  const Constraint& c = ctrl_->requirement(ctrl_->row_requirement(i));
  if (!c.is_active(t_start_) || !c.is_active(t)) return;
  largest_ = std::max(largest_, bound);
  ++checked_;
  // |e| > (1 + margin) bound + 1e-9 of the largest bound (a bound of 0 with an error of 0 holds)
  const double a = std::abs(e);
  if (!(a > (1.0 + ControlStatistics::kBoundMargin) * bound + 1e-9 * largest_)) return;
  ++exceeded_;
  if (first_row_ < 0) {
    first_ = t;
    first_row_ = i;
  }
  const double ratio = bound > 0.0 ? a / bound : std::numeric_limits<double>::infinity();
  if (ratio > worst_) {
    worst_ = ratio;
    worst_time_ = t;
    worst_row_ = i;
  }
}

void BoundWatch::finish(ControlStatistics& stats, RunStatistics& run,
                        const std::string& time_unit) const {
  if (first_row_ < 0) return;
  const auto& rows = ctrl_->row_names();
  stats.bound_exceeded_at = first_;
  stats.bound_worst_ratio = worst_;
  stats.bound_worst_row = rows[std::size_t(worst_row_)];
  stats.bound_worst_time = worst_time_;
  // the note says when, by how much, and what does not hold
  run.notes.push_back(
      "t = " + format(first_) + " " + time_unit + ": the error of requirement row '" +
      rows[std::size_t(first_row_)] + "' left its guaranteed bound (error_bound." +
      rows[std::size_t(first_row_)] + "), at " + format_number(exceeded_) + " of " +
      format_number(checked_) + " checked samples and rows, by up to " + format_number(worst_, 3) +
      " times the bound (row '" + stats.bound_worst_row + "', t = " + format(worst_time_) + " " +
      time_unit +
      "): the plant lies outside the controller's uncertainty model (robust: bound, "
      "relative_bound, gain_uncertainty), or the actuators cannot produce the robust term, so "
      "the bound guarantees nothing here. Widen the uncertainty model to cover the plant "
      "(docs/control.md, section 4)");
}

}  // namespace control_detail

}  // namespace ukdyn

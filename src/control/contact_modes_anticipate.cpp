// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts under control, the event's LCP anticipated: where the run's modes release
// contacts it held (its LCP of the accelerations), the control answers their forces — the LCP of
// those contacts with the requirements as equalities, F₀ − K A_r P A_cᵀ λ — and a free λ_j takes
// its multiplier held (held_reactions) (control/contact_modes.hpp; docs/contact.md, "In a run").
#include "control/contact_modes.hpp"

#include <algorithm>
#include <cmath>

#include "control/internal.hpp"

namespace ukdyn::control_detail {

void ContactModes::anticipate(const Controller& ctrl, ControlWorkspace& cws,
                              const std::vector<signed char>* run_modes,
                              const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t, ControlStatus& s) {
  if (run_modes == nullptr) return;
  // the contacts the run held at the previous evaluation (1, or −1: its time interval's, as
  // before the run's first modes) and releases in this one; first_ marks those seen open for the
  // first time (the start's LCP: they count when they touch, below)
  closed_.clear();
  for (std::size_t i = 0; i < contacts_.size(); ++i) {
    const signed char now = (*run_modes)[std::size_t(contacts_[i])];
    if (last_[i] != 0 && now == 0) closed_.push_back(Index(i));
    first_[i] = last_[i] == -1 ? 1 : 0;
    last_[i] = now;
  }
  decided_.clear();
  if (closed_.empty() || (s != ControlStatus::kOk && s != ControlStatus::kRequirementsNotMet)) {
    return;
  }
  for (Index i : closed_) {
    // (the model has them open: the run's modes are mirrored)
    if (cws.model.active[std::size_t(contacts_[std::size_t(i)])]) return;
  }
  contact_rows(ctrl, cws, q, qd, t);
  // only those that stay touching, g' <= 1e-9 (‖A_i‖ ‖q'‖ + |∂g/∂t|), as the run's LCP takes
  // them (a contact that an impact sends off with g' > 0 is not in it)
  Index k = 0;
  for (std::size_t j = 0; j < closed_.size(); ++j) {
    const Index c = contacts_[std::size_t(closed_[j])];
    Eigen::Matrix<double, 1, 1> g, gd;
    ctrl.model().constraint(c).model().violation(q, qd, t, cws.model.scratch[std::size_t(c)].get(),
                                                 g, gd);
    const double Aqd = A_c_.row(Index(j)).dot(qd);
    if (gd[0] > kSignificant * (A_c_.row(Index(j)).norm() * qd.norm() + std::abs(gd[0] - Aqd))) {
      continue;
    }
    // (at the start: only a closed gap, g <= 1e-9 ‖A_i‖ max(1, ‖q‖))
    if (first_[std::size_t(closed_[j])] &&
        g[0] > kSignificant * A_c_.row(Index(j)).norm() * std::max(1.0, q.norm())) {
      continue;
    }
    closed_[std::size_t(k)] = closed_[j];
    A_c_.row(k) = A_c_.row(Index(j));
    b_c_[k] = b_c_[Index(j)];
    ++k;
  }
  closed_.resize(std::size_t(k));
  if (k == 0) return;
  if (s == ControlStatus::kRequirementsNotMet) {
    probe_held(ctrl, cws, q, qd, t, s);
    return;
  }
  controlled_delassus(ctrl, cws);
  for (Index i : closed_) decided_.push_back(contacts_[std::size_t(i)]);
  if (!lcp_.solve(W_.topLeftCorner(k, k), r_.head(k), kLcpTolerance)) {
    lambda_.head(k).setZero();
    return;
  }
  lambda_.head(k) = lcp_.z();
  held_reactions(ctrl, cws, q, qd, t, k);
  if (!(lambda_.head(k).maxCoeff() > 0.0)) return;
  // ΔF = −K A_r P A_cᵀ λ: the control's answer to the contact forces A_cᵀ λ
  Kf_.noalias() = A_c_.topRows(k).transpose() * lambda_.head(k);
  if (cws.model.active_rows > 0) {
    cws.model.decomposition.project_nonideal(Kf_, scratch_n_, cws.tmp_n2, cws.lambda_p);
  } else {
    cws.model.decomposition.solve_mass(Kf_, scratch_n_);
  }
  req_.noalias() = cws.req.A * scratch_n_;
  apply_law(ctrl, cws, req_, u_, Kf_, minv_Kf_);
  cws.Qc_nominal -= Kf_;
  cws.Qc_control -= Kf_;
  cws.u -= u_;
  // the model's acceleration under it (contacts open), the physical reaction
  // model.Qc + (M P − I) F, and the power
  if (cws.model.active_rows > 0) {
    cws.model.decomposition.project_nonideal(Kf_, scratch_n_, cws.tmp_n2, cws.lambda_p);
    cws.Qc_physical -= cws.tmp_n2 - Kf_;
  } else {
    cws.model.decomposition.solve_mass(Kf_, scratch_n_);
  }
  cws.qdd -= scratch_n_;
  cws.power = cws.Qc_control.dot(qd);
}

void ContactModes::held_reactions(const Controller& ctrl, ControlWorkspace& cws,
                                  const Eigen::Ref<const VectorXd>& q,
                                  const Eigen::Ref<const VectorXd>& qd, double t, Index k) {
  // the contacts whose force the requirements decide nothing of: W̃'s row and column zero (the
  // requirements remove their direction: a requirement row that duplicates the contact's) and
  // r̃ at roundoff of its terms, so that any λ_j >= 0 solves the LCP
  std::vector<signed char>& modes = cws.model.activity_override;
  bool any = false;
  for (Index j = 0; j < k; ++j) {
    const double scale =
        A_c_.row(j).norm() * (cws.model.a.norm() + cws.qdd.norm()) + std::abs(b_c_[j]);
    const bool free = W_.row(j).head(k).isZero(0.0) && W_.col(j).head(k).isZero(0.0) &&
                      std::abs(r_[j]) <= kSignificant * scale;
    const std::size_t i = std::size_t(closed_[std::size_t(j)]);
    saved_[i] = modes[std::size_t(contacts_[i])];
    if (free) modes[std::size_t(contacts_[i])] = 1;
    any = any || free;
  }
  if (!any) return;
  // they carry what they carry held under the control computed with them held: what the
  // uncontrolled constrained system carries (the Gauss law loads no held contact; docs/contact.md,
  // "Contacts under control"); the control with them open is then computed again
  if (compute_control(ctrl, cws, q, qd, t) == ControlStatus::kOk) {
    for (Index j = 0; j < k; ++j) {
      const std::size_t i = std::size_t(closed_[std::size_t(j)]);
      if (modes[std::size_t(contacts_[i])] == saved_[i]) continue;
      const Index row = ctrl.model().row_offset(contacts_[i]);
      lambda_[j] = std::max(0.0, cws.model.lambda[row] + cws.model.lambda_nonideal[row]);
    }
  }
  for (Index j = 0; j < k; ++j) {
    const std::size_t i = std::size_t(closed_[std::size_t(j)]);
    modes[std::size_t(contacts_[i])] = saved_[i];
  }
  compute_control(ctrl, cws, q, qd, t);
}

}  // namespace ukdyn::control_detail

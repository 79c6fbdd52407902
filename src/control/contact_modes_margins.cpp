// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts under control: whether the Coulomb contacts stuck in the controller's model
// hold under a control — the model's multipliers under a force (reaction_under), each contact's
// margin mu_static N − |H| split as the run's stick margin splits it (stick_margin), and, with
// several stuck, some split of their holding forces inside every cone (hold_by_split, the run's
// test) (control/contact_modes.hpp; docs/friction.md, "Several contacts").
#include "control/contact_modes.hpp"

#include <limits>

#include "dynamics/internal.hpp"
#include "simulation/split_margin.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn::control_detail {

bool ContactModes::stuck_hold(const Controller& ctrl, ControlWorkspace& cws,
                              const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t) {
  Workspace& model = cws.model;
  stuck_.clear();
  for (std::size_t j = 0; j < frictions_.size(); ++j) {
    if (model.activity_override[std::size_t(frictions_[j].stick_constraint)] > 0) {
      stuck_.push_back(j);
    }
  }
  if (stuck_.empty()) return true;
  // the model's reaction under the control
  F_s_ = cws.Qc_control;
  const bool evaluated = reaction_under(ctrl, cws, F_s_, q, qd, t);
  if (!stuck_margins(ctrl, cws, q, qd, t)) return false;
  // (held: the control evaluated again, where reaction_under evaluated the model under it)
  if (evaluated) compute_control(ctrl, cws, q, qd, t);
  return true;
}

bool ContactModes::reaction_under(const Controller& ctrl, ControlWorkspace& cws,
                                  const Eigen::Ref<const VectorXd>& F,
                                  const Eigen::Ref<const VectorXd>& q,
                                  const Eigen::Ref<const VectorXd>& qd, double t) {
  Workspace& model = cws.model;
  // a Coulomb contact sliding in the model (its friction on)?
  bool sliding = false;
  for (const FrictionContact& c : frictions_) {
    sliding = sliding || model.nonideal_enabled[std::size_t(c.force)] != 0;
  }
  if (!sliding) {
    // λ + λ_nonideal − G_p⁺ A_p M⁻¹ F (the model's evaluation left as it is)
    model.decomposition.project_nonideal(F, cws.tmp_n, cws.tmp_n2, lam_);
    lam_ += model.lambda + model.lambda_nonideal;
    return false;
  }
  // the sliding contacts' friction mu N follows the N that F changes (a corner sliding beside
  // a stuck one: its friction is mu N of the N under F, not of the model's without it), so
  // stages 3 and 4 again with F among the forces: Q += F, a += M⁻¹ F (its factor as it is)
  model.Q += F;
  model.decomposition.solve_mass(F, cws.tmp_n);
  model.a += cws.tmp_n;
  if (solve_ideal(ctrl.model(), model) == Status::kOk) {
    apply_nonideal(ctrl.model(), model, q, qd, t);
  }
  lam_ = model.lambda + model.lambda_nonideal;
  return true;
}

bool ContactModes::stuck_margins(const Controller& ctrl, ControlWorkspace& cws,
                                 const Eigen::Ref<const VectorXd>& q,
                                 const Eigen::Ref<const VectorXd>& qd, double t) {
  // each contact's margin mu_static N − |H| (split as the run's stick margin splits it): the
  // stick breaks where one is < 0
  note_margin_ = std::numeric_limits<double>::infinity();
  note_split_ = false;
  released_.clear();
  for (std::size_t j : stuck_) {
    const double margin = stick_margin(ctrl, cws, j, q, qd, t);
    if (margin < 0.0) released_.push_back(j);
    if (margin < note_margin_) {
      note_margin_ = margin;
      note_N_ = normal_force_;
      note_H_ = holding_force_;
    }
  }
  // several stuck: held when some split of their holding forces lies inside every cone, as in the
  // run (Run::holding_split), not only the minimum-norm one
  if (!released_.empty() && stuck_.size() >= 2) hold_by_split(ctrl, cws, q, qd, t);
  return released_.empty();
}

double ContactModes::stick_margin(const Controller& ctrl, ControlWorkspace& cws, std::size_t j,
                                  const Eigen::Ref<const VectorXd>& q,
                                  const Eigen::Ref<const VectorXd>& qd, double t) {
  const System& sys = ctrl.model();
  Workspace& model = cws.model;
  const FrictionContact& c = frictions_[j];
  const Index k = c.normal_constraint, rows = sys.constraint(k).rows();
  if (normals_.rows() != rows) normals_.resize(rows, sys.coordinate_count());  // (once a size)
  detail::copy_constraint_rows(sys, model, k, normals_);
  // the normal constraint's reaction R_n = A_nᵀ lam_n
  detail::constraint_share(sys, model, k, lam_, reaction_);
  if (const ContactKinematics& kin = c.kinematics) {
    // contact point: N from R_n along the contact normal, H = kappa lam_stick (its rows are
    // kappa T)
    detail::sliding_velocity(sys, model, Index(j), q, qd, t, false);
    normal_force_ = detail::contact_normal_force(sys, model, Index(j), reaction_);
    const double kappa = detail::normal_row_unit(normals_, rows, part_);
    holding_force_ = kappa * lam_.segment(sys.row_offset(c.stick_constraint), kin.tangents).norm();
    return c.mu_static * normal_force_ - holding_force_;
  }
  // coordinates: R = A_nᵀ lam_n + A_sᵀ lam_s, N its projection onto the normal rows, H the rest
  detail::constraint_share(sys, model, c.stick_constraint, lam_, part_);
  reaction_ += part_;
  detail::normal_part(normals_, reaction_, part_);
  normal_force_ = detail::coordinate_normal_force(c, part_);  // |R_N,p|
  holding_force_ = (reaction_ - part_).norm();
  return c.mu_static * normal_force_ - holding_force_;
}

void ContactModes::hold_by_split(const Controller& ctrl, ControlWorkspace& cws,
                                 const Eigen::Ref<const VectorXd>& q,
                                 const Eigen::Ref<const VectorXd>& qd, double t) {
  const System& sys = ctrl.model();
  Workspace& model = cws.model;
  // the closed contacts sliding keep their N (their friction is mu N of it), as in the run
  sliding_.clear();
  for (std::size_t j = 0; j < frictions_.size(); ++j) {
    const FrictionContact& c = frictions_[j];
    const auto k = std::size_t(c.normal_constraint);
    const bool separated = sys.constraint(Index(k)).is_unilateral() && !model.active[k];
    if (model.activity_override[std::size_t(c.stick_constraint)] <= 0 && !separated &&
        c.mu_static != 0.0) {
      sliding_.push_back(j);
    }
  }
  // (N along Λ, not along a unilateral contact's push: under control a stuck contact that pulls
  // is released by the contact modes' own LCP — a cube tipped about its front edge lifts its
  // back corners, ControlRigid.CubeFullyActuated…; with N along the push no split held and a
  // corner slid)
  if (!detail::split_space(sys, model, lam_, stuck_, sliding_, q, qd, t, space_)) return;
  const double margin = detail::max_split_margin(space_, &split_y_, true);
  if (!(margin > -detail::kSplitTolerance)) return;
  released_.clear();
  // (the note's numbers, at the split of largest margin, when the note is asked for)
  note_split_ = true;
}

void ContactModes::split_note_numbers() {
  note_split_ = false;
  if (!(detail::max_split_margin(space_, &split_y_, false, true) > -detail::kSplitTolerance)) {
    return;
  }
  // the contact least held at the split of largest margin (the lower N of a tie: the one
  // nearer to letting go)
  note_margin_ = std::numeric_limits<double>::infinity();
  for (const detail::SplitCone& cone : space_.cones) {
    const double N = cone.N0 + cone.g.dot(split_y_);
    const double H = (cone.f0 + cone.F * split_y_).norm();
    const double m = cone.mu * N - H;
    if (m < note_margin_ - 1e-12 * space_.scale ||
        (m <= note_margin_ + 1e-12 * space_.scale && N < note_N_)) {
      note_margin_ = m;
      note_N_ = N;
      note_H_ = H;
    }
  }
}

}  // namespace ukdyn::control_detail

// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts under control, the stick/slip trial: a requirement that needs a stuck
// Coulomb contact to slide breaks its stick when the control that meets it with the contact
// sliding (friction mu N against the relative acceleration it imposes) would need more than
// static friction holding it (slip, and stick_note saying why) (control/contact_modes.hpp;
// docs/contact.md, "Contacts under control").
#include "control/contact_modes.hpp"

#include <cmath>
#include <string>

#include "control/internal.hpp"
#include "dynamics/internal.hpp"

namespace ukdyn::control_detail {

void ContactModes::slip(const Controller& ctrl, ControlWorkspace& cws,
                        const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                        double t, ControlStatus& s) {
  if (frictions_.empty() || s != ControlStatus::kRequirementsNotMet) return;
  Workspace& model = cws.model;
  // the contacts that stick in the model (the run's stuck ones, mirrored)
  stuck_.clear();
  for (std::size_t j = 0; j < frictions_.size(); ++j) {
    if (model.activity_override[std::size_t(frictions_[j].stick_constraint)] > 0) {
      stuck_.push_back(j);
    }
  }
  if (stuck_.empty()) return;
  if (hints_.rows() != model.slip_hint.rows()) {  // (once: the workspace's hint size)
    hints_.setZero(model.slip_hint.rows(), Index(frictions_.size()));
    held_hints_.setZero(model.slip_hint.rows(), Index(frictions_.size()));
  }
  // the closed ones that slide at rest (|v_rel| <= eps: the run released them, their friction
  // along the run's hint, the holding force's direction they let go with) take their friction
  // against the motion the requirements impose too: a box on four corners of which the run
  // released one, whose friction along its hint pushed the frictionless motion of the three
  // still stuck sideways, their hints then mostly along that push, and F_s 0.64 of the torque
  // Coulomb's sliding needs (u22 02)
  resting_.clear();
  const System& sys = ctrl.model();
  for (std::size_t j = 0; j < frictions_.size(); ++j) {
    const FrictionContact& c = frictions_[j];
    const auto k = std::size_t(c.normal_constraint);
    const bool separated = sys.constraint(Index(k)).is_unilateral() && !model.active[k];
    if (model.activity_override[std::size_t(c.stick_constraint)] > 0 || separated) continue;
    detail::sliding_velocity(sys, model, Index(j), q, qd, t, false);
    if (!(model.sliding.col(Index(j)).head(c.size()).norm() <= c.eps)) continue;
    resting_.push_back(j);
    resting_enabled_[j] = model.nonideal_enabled[std::size_t(c.force)];
  }
  for (std::size_t j : stuck_) {
    const FrictionContact& c = frictions_[j];
    held_[j] = model.slip_hint_held[std::size_t(c.force)];
    held_hints_.col(Index(j)) = model.slip_hint.col(c.force);
  }
  for (std::size_t j : resting_) {
    const FrictionContact& c = frictions_[j];
    held_[j] = model.slip_hint_held[std::size_t(c.force)];
    held_hints_.col(Index(j)) = model.slip_hint.col(c.force);
  }
  // the first requirement row not met with them stuck (the note's)
  Index row = 0;
  while (row + 1 < Index(cws.met.size()) && cws.met[std::size_t(row)]) ++row;
  // q''₀: the control with them sliding without friction; not met either: not theirs
  slide_stuck(model, false);
  if (compute_control(ctrl, cws, q, qd, t) != ControlStatus::kOk) {
    hold_stuck(model);
    s = compute_control(ctrl, cws, q, qd, t);
    return;
  }
  // the friction against the relative acceleration it imposes (none where it is roundoff of
  // its terms: no direction to slide in), and F_s, the control with that friction
  auto hint_against = [&](std::size_t j) {
    double scale = 0.0;
    const Index k = relative_acceleration(ctrl, cws, j, q, qd, t, scale);
    auto hint = hints_.col(Index(j));
    hint.setZero();
    if (!(accel_.head(k).norm() > kSignificant * scale)) return;
    const FrictionContact& c = frictions_[j];
    if (c.kinematics) {
      hint.head(k) = -accel_.head(k).normalized();
    } else {
      const double a = accel_.head(k).norm();
      for (Index r = 0; r < k; ++r) hint[c.coordinates[std::size_t(r)]] = -accel_[r] / a;
    }
  };
  for (std::size_t j : stuck_) hint_against(j);
  for (std::size_t j : resting_) hint_against(j);
  slide_stuck(model, true);
  const bool met = compute_control(ctrl, cws, q, qd, t) == ControlStatus::kOk;
  F_s_ = cws.Qc_control;
  // the control with them stuck again: the held one, and the stuck model's reaction under F_s,
  // λ + λ_nonideal − G_p⁺ A_p M⁻¹ F_s
  hold_stuck(model);
  s = compute_control(ctrl, cws, q, qd, t);
  if (!met || s != ControlStatus::kRequirementsNotMet) return;
  const bool evaluated = reaction_under(ctrl, cws, F_s_, q, qd, t);
  // held when each margin, or some split of several contacts' holding forces, is inside its cone
  note_t_ = t;
  note_row_ = row;
  if (stuck_margins(ctrl, cws, q, qd, t)) {
    // static friction holds them: the held control stands, not met (evaluated again where
    // reaction_under evaluated the model under F_s)
    slipped_ = -1;
    if (evaluated) s = compute_control(ctrl, cws, q, qd, t);
    return;
  }
  // F_s: the plant's stick then needs more than mu_static N, and the run releases it
  slide_stuck(model, true);
  s = compute_control(ctrl, cws, q, qd, t);
  hold_stuck(model);
  slipped_ = 1;
}

void ContactModes::slide_stuck(Workspace& model, bool friction) {
  for (std::size_t j : stuck_) {
    const FrictionContact& c = frictions_[j];
    model.activity_override[std::size_t(c.stick_constraint)] = 0;
    model.nonideal_enabled[std::size_t(c.force)] = friction ? 1 : 0;
    model.slip_hint.col(c.force) = hints_.col(Index(j));
    model.slip_hint_held[std::size_t(c.force)] = 0;
  }
  for (std::size_t j : resting_) {
    const FrictionContact& c = frictions_[j];
    model.nonideal_enabled[std::size_t(c.force)] = friction ? 1 : 0;
    model.slip_hint.col(c.force) = hints_.col(Index(j));
    model.slip_hint_held[std::size_t(c.force)] = 0;
  }
}

void ContactModes::hold_stuck(Workspace& model) const {
  for (std::size_t j : stuck_) {
    const FrictionContact& c = frictions_[j];
    model.activity_override[std::size_t(c.stick_constraint)] = 1;
    model.nonideal_enabled[std::size_t(c.force)] = 0;
    model.slip_hint.col(c.force) = held_hints_.col(Index(j));
    model.slip_hint_held[std::size_t(c.force)] = held_[j];
  }
  for (std::size_t j : resting_) {
    const FrictionContact& c = frictions_[j];
    model.nonideal_enabled[std::size_t(c.force)] = resting_enabled_[j];
    model.slip_hint.col(c.force) = held_hints_.col(Index(j));
    model.slip_hint_held[std::size_t(c.force)] = held_[j];
  }
}

Index ContactModes::relative_acceleration(const Controller& ctrl, ControlWorkspace& cws,
                                          std::size_t j, const Eigen::Ref<const VectorXd>& q,
                                          const Eigen::Ref<const VectorXd>& qd, double t,
                                          double& scale) {
  const System& sys = ctrl.model();
  Workspace& model = cws.model;
  const FrictionContact& c = frictions_[j];
  const Index basis = detail::sliding_velocity(sys, model, Index(j), q, qd, t, false);
  if (const ContactKinematics& kin = c.kinematics) {
    // a_rel = T q'' + T' q'
    const Index d = kin.tangents;
    const auto& J = model.contact_jacobian[j];
    accel_.head(d) = model.contact_bias.col(Index(j)).segment(1, d);
    scale = accel_.head(d).norm();
    for (std::size_t i = 0; i < kin.columns.size(); ++i) {
      const double qdd = cws.qdd[kin.columns[i]];
      accel_.head(d) += J.col(Index(i)).tail(d) * qdd;
      scale += J.col(Index(i)).tail(d).norm() * (std::abs(qdd) + std::abs(model.a[kin.columns[i]]));
    }
    return d;
  }
  // a_rel = P (q''_c − u')
  const Index k = Index(c.coordinates.size());
  // (the scale of its terms: q''_c is what the forces leave of a = M⁻¹ Q — a particle pushed and
  // held at rest has q''_c at roundoff of F/m, no direction to slide in; u16 02)
  scale = 0.0;
  for (Index r = 0; r < k; ++r) {
    const Index i = c.coordinates[std::size_t(r)];
    accel_[r] = cws.qdd[i];
    scale += std::abs(cws.qdd[i]) + std::abs(model.a[i]);
  }
  if (c.surface_velocity) {
    accel_.head(k) -= model.surface_u_dot.head(k);
    scale += model.surface_u_dot.head(k).norm();
  }
  detail::remove_normals(model, basis, accel_.head(k));
  return k;
}

std::string ContactModes::stick_note(const Controller& ctrl) {
  if (slipped_ == 0) return "";
  if (slipped_ < 0 && note_split_) split_note_numbers();
  const std::string f = " " + units_.force();
  const std::string numbers = format(note_H_) + f + (slipped_ > 0 ? " > " : " <= ") +
                              "mu_static N = " + format(note_H_ + note_margin_) + f +
                              " (N = " + format(note_N_) + f + ")";
  const std::string row = "the requirement row '" + ctrl.row_names()[std::size_t(note_row_)] + "'";
  if (slipped_ < 0) {
    return row +
           " needs a stuck contact to slide, but static friction holds it: the control "
           "that meets it with the contact sliding would need a holding force of only " +
           numbers + " with it stuck (docs/contact.md, \"Contacts under control\")";
  }
  std::string names;
  for (std::size_t j : released_) {
    names += (names.empty() ? "'" : ", '") + ctrl.model().nonideal_name(frictions_[j].force) + "'";
  }
  return "t = " + format(note_t_) + " " + units_.time + ": " + row + " needs the stuck contact " +
         names +
         " to slide: the control that meets it with the contact sliding (friction mu N against "
         "the motion it imposes) would need a holding force of " +
         numbers + " to keep it stuck, so it slips (docs/contact.md, \"Contacts under control\")";
}

}  // namespace ukdyn::control_detail

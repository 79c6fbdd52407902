// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts under control, the held-contact trials: a requirement that the actuators
// reach only through a Coulomb contact held (a wheel driven by its axle torque): the control
// computed with sliding contacts held (hold_sliding, and held_note saying why it is not met), and
// with touching contacts the run releases at an event held (probe_held, anticipate's)
// (control/contact_modes.hpp; docs/contact.md, "Contacts under control").
#include "control/contact_modes.hpp"

#include <algorithm>
#include <string>

#include "control/internal.hpp"
#include "dynamics/internal.hpp"

namespace ukdyn::control_detail {

void ContactModes::hold_sliding(const Controller& ctrl, ControlWorkspace& cws,
                                const Eigen::Ref<const VectorXd>& q,
                                const Eigen::Ref<const VectorXd>& qd, double t, ControlStatus& s) {
  held_sliding_ = false;
  if (frictions_.empty() || s != ControlStatus::kRequirementsNotMet || slipped_ != 0) return;
  const System& sys = ctrl.model();
  Workspace& model = cws.model;
  // the Coulomb contacts that slide in the model on a closed contact (a frictionless one
  // transmits nothing held or sliding)
  stuck_.clear();
  for (std::size_t j = 0; j < frictions_.size(); ++j) {
    const FrictionContact& c = frictions_[j];
    const auto k = std::size_t(c.normal_constraint);
    const bool separated = sys.constraint(Index(k)).is_unilateral() && !model.active[k];
    if (model.activity_override[std::size_t(c.stick_constraint)] > 0 || separated ||
        c.mu_static == 0.0) {
      continue;
    }
    stuck_.push_back(j);
  }
  if (stuck_.empty()) return;
  // the sliding evaluation's verdict: the plant's while they slide (the note's row)
  Index row = 0;
  while (row + 1 < Index(cws.met.size()) && cws.met[std::size_t(row)]) ++row;
  slide_residual_ = cws.residual;
  std::copy(cws.met.begin(), cws.met.end(), slide_met_.begin());
  slide_not_met_ = cws.rows_not_met;
  // F_h: the control with them held (their stick constraints on, their friction off; the
  // mirrored modes saved); not met either: not theirs, the sliding control stands
  held_sticks_.which.clear();
  for (std::size_t j : stuck_) held_sticks_.override_stick(model, j, frictions_[j], 1);
  if (compute_control(ctrl, cws, q, qd, t) != ControlStatus::kOk) {
    held_sticks_.restore(model, frictions_);
    s = compute_control(ctrl, cws, q, qd, t);
    return;
  }
  // the held model's reaction under F_h, each contact's margin mu_static N − |H|, and its
  // sliding speed
  F_s_ = cws.Qc_control;
  const bool evaluated = reaction_under(ctrl, cws, F_s_, q, qd, t);
  note_t_ = t;
  note_row_ = row;
  const bool hold = stuck_margins(ctrl, cws, q, qd, t);
  bool rest = true;
  held_speed_ = 0.0;
  for (std::size_t j : stuck_) {
    detail::sliding_velocity(sys, model, Index(j), q, qd, t, false);
    const double v = model.sliding.col(Index(j)).head(frictions_[j].size()).norm();
    rest = rest && v <= frictions_[j].eps;
    held_speed_ = std::max(held_speed_, v);
  }
  // (the held model's evaluation under F_h again, where reaction_under evaluated it with F_h
  // among its forces)
  if (evaluated) compute_control(ctrl, cws, q, qd, t);
  held_sticks_.restore(model, frictions_);
  if (hold && rest) {
    // at rest and held by static friction: the run sticks them, and F_h meets the requirements
    s = ControlStatus::kOk;
    return;
  }
  // the plant slides on under F_h: the requirements not met, as the sliding evaluation says
  if (hold) released_.assign(stuck_.begin(), stuck_.end());
  s = ControlStatus::kRequirementsNotMet;
  cws.status = s;
  cws.residual = slide_residual_;
  std::copy(slide_met_.begin(), slide_met_.end(), cws.met.begin());
  cws.rows_not_met = slide_not_met_;
  held_sliding_ = true;
}

std::string ContactModes::held_note(const Controller& ctrl) {
  if (!held_sliding_) return "";
  if (note_split_) split_note_numbers();
  const std::string f = " " + units_.force();
  std::string names;
  for (std::size_t j : released_) {
    names += (names.empty() ? "'" : ", '") + ctrl.model().nonideal_name(frictions_[j].force) + "'";
  }
  const bool beyond = note_margin_ < 0.0;
  const std::string numbers = format(note_H_) + f + (beyond ? " > " : " <= ") +
                              "mu_static N = " + format(note_H_ + note_margin_) + f +
                              " (N = " + format(note_N_) + f + ")";
  const std::string head =
      "t = " + format(note_t_) + " " + units_.time + ": the requirement row '" +
      ctrl.row_names()[std::size_t(note_row_)] + "' can be met only with the contact " + names +
      " held (stuck): with it sliding the actuated coordinates do not meet it, and the control "
      "that meets it with it held needs a holding force of " +
      numbers;
  if (beyond) {
    return head +
           ", more than static friction gives: the control applies that force, the contact "
           "slides under it with the friction mu N, and the requirement is not met "
           "(docs/contact.md, \"Contacts under control\")";
  }
  return head + ", but the contact slides (|v_rel| = " + format(held_speed_) + " " +
         units_.velocity() +
         "): the control applies that force until it sticks, the requirement not met meanwhile "
         "(docs/contact.md, \"Contacts under control\")";
}

void ContactModes::probe_held(const Controller& ctrl, ControlWorkspace& cws,
                              const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t, ControlStatus& s) {
  const System& sys = ctrl.model();
  Workspace& model = cws.model;
  std::vector<signed char>& modes = model.activity_override;
  // the touching contacts closed_ held, and the sticks of their Coulomb contacts at rest
  for (Index i : closed_) {
    saved_[std::size_t(i)] = modes[std::size_t(contacts_[std::size_t(i)])];
    modes[std::size_t(contacts_[std::size_t(i)])] = 1;
  }
  lifted_.which.clear();
  for (std::size_t f = 0; f < frictions_.size(); ++f) {
    const FrictionContact& c = frictions_[f];
    if (c.mu_static == 0.0 || std::none_of(closed_.begin(), closed_.end(), [&](Index i) {
          return contacts_[std::size_t(i)] == c.normal_constraint;
        })) {
      continue;
    }
    detail::sliding_velocity(sys, model, Index(f), q, qd, t, false);
    if (!(model.sliding.col(Index(f)).head(c.size()).norm() <= c.eps)) continue;
    lifted_.override_stick(model, f, c, 1);
  }
  const ControlStatus held = compute_control(ctrl, cws, q, qd, t);
  lifted_.restore(model, frictions_);
  for (Index i : closed_) {
    modes[std::size_t(contacts_[std::size_t(i)])] = saved_[std::size_t(i)];
  }
  if (held == ControlStatus::kOk) {
    s = held;
    return;
  }
  // (not met held either: the control with them open stands)
  compute_control(ctrl, cws, q, qd, t);
}

}  // namespace ukdyn::control_detail

// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts under control: the controller's model holds the run's closed contacts, and
// a requirement that lifts a contact off opens it, one that would need it to pull is reported
// (control/contact_modes.hpp; docs/contact.md, "Contacts under control").
#include "control/contact_modes.hpp"

#include <cmath>

#include "control/internal.hpp"

namespace ukdyn::control_detail {

ContactModes::ContactModes(const Controller& ctrl) {
  const System& model = ctrl.model();
  for (Index k = 0; k < model.constraint_count(); ++k) {
    if (model.constraint(k).is_unilateral()) contacts_.push_back(k);
  }
  saved_.assign(contacts_.size(), -1);
  open_.assign(contacts_.size(), 0);
  pulls_.assign(contacts_.size(), 0);
  row_A_ = MatrixXd::Zero(1, model.coordinate_count());
  row_b_ = VectorXd::Zero(1);
}

void ContactModes::mirror(const std::vector<signed char>* run_modes, ControlWorkspace& cws) const {
  if (run_modes == nullptr) return;
  for (Index k : contacts_) {
    cws.model.activity_override[std::size_t(k)] = (*run_modes)[std::size_t(k)];
  }
}

double ContactModes::gap_acceleration(const Controller& ctrl, ControlWorkspace& cws, std::size_t i,
                                      const Eigen::Ref<const VectorXd>& q,
                                      const Eigen::Ref<const VectorXd>& qd, double t,
                                      double& scale) {
  const Index k = contacts_[i];
  ctrl.model().constraint(k).model().acceleration_form(
      q, qd, t, cws.model.scratch[std::size_t(k)].get(), row_A_, row_b_);
  // the class of the accelerations involved: the free one, the controlled one and b
  scale = row_A_.row(0).norm() * (cws.model.a.norm() + cws.qdd.norm()) + std::abs(row_b_[0]);
  return row_A_.row(0).dot(cws.qdd) - row_b_[0];
}

bool ContactModes::settle(const Controller& ctrl, ControlWorkspace& cws,
                          const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                          double t, ControlStatus& s, std::string& failure) {
  // a g'' within this fraction of its scale is zero (the requirement neither lifts nor presses)
  constexpr double kSignificant = 1e-9;
  if (contacts_.empty() || s != ControlStatus::kRequirementsNotMet) return true;
  // the closed contacts, and the first requirement row not met with them held
  std::vector<signed char>& modes = cws.model.activity_override;
  bool any_closed = false;
  for (std::size_t i = 0; i < contacts_.size(); ++i) {
    const Index k = contacts_[i];
    saved_[i] = modes[std::size_t(k)];
    open_[i] = cws.model.active[std::size_t(k)];
    pulls_[i] = 0;
    any_closed = any_closed || open_[i] != 0;
  }
  if (!any_closed) return true;
  Index row = 0;
  while (row + 1 < Index(cws.met.size()) && cws.met[std::size_t(row)]) ++row;
  const double held_residual = cws.residual[row];
  auto restore = [&] {
    for (std::size_t i = 0; i < contacts_.size(); ++i) modes[std::size_t(contacts_[i])] = saved_[i];
  };
  // open the closed contacts; hold again those the requirements drive shut, until none is
  bool pulled = false;
  for (std::size_t round = 0; round <= contacts_.size(); ++round) {
    for (std::size_t i = 0; i < contacts_.size(); ++i) {
      if (open_[i]) modes[std::size_t(contacts_[i])] = 0;
    }
    const ControlStatus trial = compute_control(ctrl, cws, q, qd, t);
    if (trial != ControlStatus::kOk) break;  // not met with them open either: not theirs
    bool shut = false;
    for (std::size_t i = 0; i < contacts_.size(); ++i) {
      if (!open_[i]) continue;
      double scale = 0.0;
      if (gap_acceleration(ctrl, cws, i, q, qd, t, scale) < -kSignificant * scale) {
        open_[i] = 0;
        modes[std::size_t(contacts_[i])] = saved_[i];
        pulls_[i] = 1;
        shut = true;
      }
    }
    if (!shut) {
      // met, and no gap driven shut: the plant releases the contacts the control lifts off
      // (their multiplier under this control pulls); the model keeps them open for this
      // evaluation only
      restore();
      s = ControlStatus::kOk;
      return true;
    }
    pulled = true;
    bool any_open = false;
    for (unsigned char o : open_) any_open = any_open || o != 0;
    if (!any_open) break;
  }
  restore();
  if (pulled) {
    std::string names;
    for (std::size_t i = 0; i < contacts_.size(); ++i) {
      if (pulls_[i]) {
        names += (names.empty() ? "'" : ", '") + ctrl.model().constraint(contacts_[i]).name() + "'";
      }
    }
    failure = "at t = " + format(t) + " the requirement row '" +
              ctrl.row_names()[std::size_t(row)] + "' can be met only if the contact " + names +
              " pulls: with the contact open the control that meets it drives the gap shut "
              "(g'' < 0), and with it closed the requirement is missed by " +
              format(std::abs(held_residual)) +
              " (docs/contact.md, \"Contacts under control\"). Try: a requirement that stays on "
              "the open side of the contact, or the contact written as a two-sided constraint";
    return false;
  }
  // the requirements are not met with the contacts open either: the held control stands
  s = compute_control(ctrl, cws, q, qd, t);
  return true;
}

}  // namespace ukdyn::control_detail

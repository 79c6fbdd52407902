// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts under control, the first stage: the controller's model holds the run's
// closed contacts (mirror); when the requirements are not met with them held, settle() runs the
// trials in order — the LCP of the closed contacts with the requirement rows as equalities
// (here: which stay held, and one that has no solution, a requirement that needs a contact to
// pull, reported), then the stick/slip trial (contact_modes_slip.cpp) and the held-contact trial
// (contact_modes_held.cpp). Whether stuck contacts hold is contact_modes_margins.cpp's; the
// event's LCP anticipated, contact_modes_anticipate.cpp's (control/contact_modes.hpp;
// docs/contact.md, "Contacts under control").
#include "control/contact_modes.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "control/internal.hpp"

namespace ukdyn::control_detail {

namespace {
// an entry of W̃ within this fraction of the largest W_ii = A_i P A_iᵀ is roundoff of a
// direction the requirements remove (W̃ = 0 there: a block whose height is required)
constexpr double kRoundoff = 1e-10;
}  // namespace

ContactModes::ContactModes(const Controller& ctrl) : lcp_(0) {
  const System& model = ctrl.model();
  for (Index k = 0; k < model.constraint_count(); ++k) {
    if (model.constraint(k).is_unilateral()) contacts_.push_back(k);
  }
  frictions_ = model.friction_contacts();
  const Index n = model.coordinate_count(), K = Index(contacts_.size());
  saved_.assign(contacts_.size(), -1);
  last_.assign(contacts_.size(), -1);
  first_.assign(contacts_.size(), 0);
  closed_.reserve(contacts_.size());
  decided_.reserve(contacts_.size());
  row_A_ = MatrixXd::Zero(1, n);
  row_b_ = VectorXd::Zero(1);
  A_c_ = MatrixXd::Zero(K, n);
  b_c_ = VectorXd::Zero(K);
  PAt_ = MatrixXd::Zero(n, K);
  W_ = MatrixXd::Zero(K, K);
  r_ = VectorXd::Zero(K);
  lambda_ = VectorXd::Zero(K);
  req_ = VectorXd::Zero(ctrl.requirement_rows());
  Kf_ = VectorXd::Zero(n);
  minv_Kf_ = VectorXd::Zero(n);
  scratch_n_ = VectorXd::Zero(n);
  lcp_ = ContactLcp(K);
  stuck_.reserve(frictions_.size());
  sliding_.reserve(frictions_.size());
  resting_.reserve(frictions_.size());
  resting_enabled_.assign(frictions_.size(), 0);
  lifted_.reserve(frictions_.size());
  released_.reserve(frictions_.size());
  held_.assign(frictions_.size(), 0);
  held_sticks_.reserve(frictions_.size());
  slide_residual_ = VectorXd::Zero(ctrl.requirement_rows());
  slide_met_.assign(std::size_t(ctrl.requirement_rows()), 0);
  F_s_ = VectorXd::Zero(n);
  lam_ = VectorXd::Zero(model.constraint_rows());
  accel_ = VectorXd::Zero(std::max<Index>(n, 2));
  reaction_ = VectorXd::Zero(n);
  part_ = VectorXd::Zero(n);
}

void ContactModes::SavedSticks::reserve(std::size_t count) {
  which.reserve(count);
  modes.assign(count, 0);
  enabled.assign(count, 0);
}

void ContactModes::SavedSticks::override_stick(Workspace& model, std::size_t f,
                                               const FrictionContact& c, signed char stick) {
  const auto k = std::size_t(c.stick_constraint), force = std::size_t(c.force);
  which.push_back(f);
  modes[f] = model.activity_override[k];
  enabled[f] = model.nonideal_enabled[force];
  model.activity_override[k] = stick;
  model.nonideal_enabled[force] = 0;
}

void ContactModes::SavedSticks::restore(Workspace& model,
                                        const std::vector<FrictionContact>& frictions) const {
  for (std::size_t f : which) {
    const FrictionContact& c = frictions[f];
    model.activity_override[std::size_t(c.stick_constraint)] = modes[f];
    model.nonideal_enabled[std::size_t(c.force)] = enabled[f];
  }
}

void ContactModes::mirror(const std::vector<signed char>* run_modes, ControlWorkspace& cws) const {
  if (run_modes == nullptr) return;
  for (Index k : contacts_) {
    cws.model.activity_override[std::size_t(k)] = (*run_modes)[std::size_t(k)];
  }
}

void ContactModes::mirror(const Workspace* run, ControlWorkspace& cws) const {
  if (run == nullptr) return;
  Workspace& model = cws.model;
  mirror(&run->activity_override, cws);
  // each Coulomb contact sticks (its stick constraint held, its friction off) or slides (with
  // the run's slip hint) in the model as in the run
  for (const FrictionContact& c : frictions_) {
    const auto k = std::size_t(c.stick_constraint), i = std::size_t(c.force);
    model.activity_override[k] = run->activity_override[k];
    model.nonideal_enabled[i] = run->nonideal_enabled[i];
    model.slip_hint.col(c.force) = run->slip_hint.col(c.force);
    model.slip_hint_held[i] = run->slip_hint_held[i];
  }
}

void ContactModes::contact_rows(const Controller& ctrl, ControlWorkspace& cws,
                                const Eigen::Ref<const VectorXd>& q,
                                const Eigen::Ref<const VectorXd>& qd, double t) {
  for (std::size_t j = 0; j < closed_.size(); ++j) {
    const Index k = contacts_[std::size_t(closed_[j])];
    ctrl.model().constraint(k).model().acceleration_form(
        q, qd, t, cws.model.scratch[std::size_t(k)].get(), row_A_, row_b_);
    A_c_.row(Index(j)) = row_A_.row(0);
    b_c_[Index(j)] = row_b_[0];
  }
}

void ContactModes::controlled_delassus(const Controller& ctrl, ControlWorkspace& cws) {
  const Index k = Index(closed_.size());
  FundamentalDecomposition& dp = cws.model.decomposition;  // the model with the contacts open
  const bool physical = cws.model.active_rows > 0;
  // x = P f (the model's compliance: its bilateral constraints held, the contacts open)
  auto apply_p = [&](const Eigen::Ref<const VectorXd>& f, Eigen::Ref<VectorXd> x) {
    if (physical) {
      dp.project_nonideal(f, x, cws.tmp_n2, cws.lambda_p);
    } else {
      dp.solve_mass(f, x);
    }
  };
  if (u_.size() != cws.u.size()) u_.setZero(cws.u.size());  // (once: the actuator count)
  double diag = 0.0;
  for (Index j = 0; j < k; ++j) {
    // P A_jᵀ: the contact force's effect without control
    scratch_n_ = A_c_.row(j).transpose();
    apply_p(scratch_n_, PAt_.col(j));
    diag = std::max(diag, A_c_.row(j).dot(PAt_.col(j)));
    // the control's answer to it: K (−A_r P A_jᵀ), whose effect P K … is taken off
    req_.noalias() = cws.req.A * PAt_.col(j);
    apply_law(ctrl, cws, req_, u_, Kf_, minv_Kf_);
    apply_p(Kf_, scratch_n_);
    PAt_.col(j) -= scratch_n_;
  }
  // W̃ = A_c P (I − K A_r P) A_cᵀ, its roundoff removed
  auto W = W_.topLeftCorner(k, k);
  W.noalias() = A_c_.topRows(k) * PAt_.leftCols(k);
  W = W.unaryExpr([&](double v) { return std::abs(v) <= kRoundoff * diag ? 0.0 : v; });
  // r̃ = A_c q''₀ − b_c (q''₀: cws.qdd, the control with the contacts open)
  r_.head(k).noalias() = A_c_.topRows(k) * cws.qdd;
  r_.head(k) -= b_c_.head(k);
}

bool ContactModes::settle(const Controller& ctrl, ControlWorkspace& cws,
                          const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                          double t, ControlStatus& s, std::string& failure) {
  slipped_ = 0;
  held_sliding_ = false;
  if (s != ControlStatus::kRequirementsNotMet) return true;
  // the unilateral contacts' LCP, then the stuck Coulomb contacts, then the sliding ones
  if (!settle_contacts(ctrl, cws, q, qd, t, s, failure)) return false;
  slip(ctrl, cws, q, qd, t, s);
  hold_sliding(ctrl, cws, q, qd, t, s);
  return true;
}

bool ContactModes::settle_contacts(const Controller& ctrl, ControlWorkspace& cws,
                                   const Eigen::Ref<const VectorXd>& q,
                                   const Eigen::Ref<const VectorXd>& qd, double t, ControlStatus& s,
                                   std::string& failure) {
  if (contacts_.empty()) return true;
  decided_.clear();
  // the closed contacts, and the first requirement row not met with them held
  std::vector<signed char>& modes = cws.model.activity_override;
  closed_.clear();
  for (std::size_t i = 0; i < contacts_.size(); ++i) {
    const Index k = contacts_[i];
    saved_[i] = modes[std::size_t(k)];
    if (cws.model.active[std::size_t(k)]) closed_.push_back(Index(i));
  }
  if (closed_.empty()) return true;
  Index row = 0;
  while (row + 1 < Index(cws.met.size()) && cws.met[std::size_t(row)]) ++row;
  const double held_residual = cws.residual[row];
  auto restore = [&] {
    for (std::size_t i = 0; i < contacts_.size(); ++i) modes[std::size_t(contacts_[i])] = saved_[i];
  };
  // q''₀: the control with the closed contacts open
  for (Index i : closed_) modes[std::size_t(contacts_[std::size_t(i)])] = 0;
  if (compute_control(ctrl, cws, q, qd, t) != ControlStatus::kOk) {
    // not met with them open either: not theirs, the held control stands
    restore();
    s = compute_control(ctrl, cws, q, qd, t);
    return true;
  }
  const Index k = Index(closed_.size());
  contact_rows(ctrl, cws, q, qd, t);
  // no gap driven shut (g'' >= −1e-9 of its scale ‖A_i‖ (‖a‖ + ‖q''‖) + |b_i|): λ = 0, every
  // closed contact opens, and the control with them open is the one (nothing more to solve)
  bool shut = false;
  for (Index j = 0; j < k; ++j) {
    const double g2 = A_c_.row(j).dot(cws.qdd) - b_c_[j];
    const double scale =
        A_c_.row(j).norm() * (cws.model.a.norm() + cws.qdd.norm()) + std::abs(b_c_[j]);
    shut = shut || g2 < -kSignificant * scale;
  }
  if (!shut) {
    // the plant releases the contacts the control lifts off (their multiplier under this control
    // pulls); the model keeps them open for this evaluation only
    restore();
    s = ControlStatus::kOk;
    return true;
  }
  // the LCP w = W̃ λ + r̃ of the closed contacts with the requirements as equalities
  controlled_delassus(ctrl, cws);
  for (Index i : closed_) decided_.push_back(contacts_[std::size_t(i)]);
  if (!lcp_.solve(W_.topLeftCorner(k, k), r_.head(k), kLcpTolerance)) {
    // no λ >= 0 meets the requirements with every gap g'' >= 0: a contact would have to pull
    lambda_.head(k).setZero();
    restore();
    failure = pull_message(ctrl, t, row, std::abs(held_residual));
    return false;
  }
  lambda_.head(k) = lcp_.z();
  // hold the contacts that push (λ > 0), open the others (and the stick of a stuck Coulomb
  // contact whose normal opens: a contact that lifts off does not stick), and compute that
  // control
  for (Index j = 0; j < k; ++j) {
    const std::size_t i = std::size_t(closed_[std::size_t(j)]);
    modes[std::size_t(contacts_[i])] = lambda_[j] > 0.0 ? saved_[i] : 0;
  }
  open_lifted_sticks(cws.model, k);
  s = compute_control(ctrl, cws, q, qd, t);
  // the Coulomb contacts still stuck must hold under it (some split of their holding forces
  // inside every cone): a control that tips a box onto a corner that cannot hold it is no
  // control of the plant, which slides instead (the box on two corners; docs/contact.md,
  // "Contacts under control"). Then the held control stands, and slip() decides
  if (s == ControlStatus::kOk && !stuck_hold(ctrl, cws, q, qd, t)) {
    s = ControlStatus::kRequirementsNotMet;
  }
  restore();
  lifted_.restore(cws.model, frictions_);
  if (s != ControlStatus::kOk) {
    // (a law whose answer to the contact forces is not the requirements' exact elimination —
    // never the Gauss law — or stuck contacts that would slip): the held control stands
    s = compute_control(ctrl, cws, q, qd, t);
  }
  return true;
}

void ContactModes::open_lifted_sticks(Workspace& model, Index k) {
  lifted_.which.clear();
  for (Index j = 0; j < k; ++j) {
    if (lambda_[j] > 0.0) continue;
    const Index normal = contacts_[std::size_t(closed_[std::size_t(j)])];
    for (std::size_t f = 0; f < frictions_.size(); ++f) {
      const FrictionContact& c = frictions_[f];
      const auto stick = std::size_t(c.stick_constraint);
      if (c.normal_constraint != normal || model.activity_override[stick] <= 0) continue;
      // (its friction off: mu N of a zero N)
      lifted_.override_stick(model, f, c, 0);
    }
  }
}

std::string ContactModes::pull_message(const Controller& ctrl, double t, Index row,
                                       double missed) const {
  // the contacts the control with them open drives shut (r̃_i < 0)
  std::string names;
  for (std::size_t j = 0; j < closed_.size(); ++j) {
    if (!(r_[Index(j)] < 0.0)) continue;
    const Index k = contacts_[std::size_t(closed_[j])];
    names += (names.empty() ? "'" : ", '") + ctrl.model().constraint(k).name() + "'";
  }
  return "at t = " + format(t) + " " + units_.time + " the requirement row '" +
         ctrl.row_names()[std::size_t(row)] + "' can be met only if the contact " + names +
         " pulls: with the contact open the control that meets it drives the gap shut "
         "(g'' < 0), no pushing contact force lets it be met (the LCP of the closed contacts "
         "with the requirements as equalities has no solution), and with the contacts closed the "
         "requirement's acceleration is missed by " +
         format(missed) + " (" + units_.rate(units_.length, 2) + " for a position row, rad/" +
         units_.time + "² for an angle)" +
         " (docs/contact.md, \"Contacts under control\"). Try: a requirement that stays on "
         "the open side of the contact, or the contact written as a two-sided constraint";
}

}  // namespace ukdyn::control_detail

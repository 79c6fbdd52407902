// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts under control: the controller's model holds the run's closed contacts;
// when the requirements are not met with them held, the LCP of the closed contacts with the
// requirement rows as equalities decides which stay held, and one that has no solution (a
// requirement that needs a contact to pull) is reported (control/contact_modes.hpp;
// docs/contact.md, "Contacts under control").
#include "control/contact_modes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "control/internal.hpp"
#include "dynamics/internal.hpp"
#include "simulation/split_margin.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn::control_detail {

namespace {
// a g'' within this fraction of its scale is zero (the requirement neither lifts nor presses)
constexpr double kSignificant = 1e-9;
// an entry of W̃ within this fraction of the largest W_ii = A_i P A_iᵀ is roundoff of a
// direction the requirements remove (W̃ = 0 there: a block whose height is required)
constexpr double kRoundoff = 1e-10;
// the LCP's solution is checked to this fraction of its scale (ContactLcp::solve)
constexpr double kLcpTolerance = 1e-9;
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
  lifted_modes_.assign(frictions_.size(), 0);
  lifted_enabled_.assign(frictions_.size(), 0);
  released_.reserve(frictions_.size());
  held_.assign(frictions_.size(), 0);
  slide_modes_.assign(frictions_.size(), 0);
  slide_enabled_.assign(frictions_.size(), 0);
  slide_residual_ = VectorXd::Zero(ctrl.requirement_rows());
  slide_met_.assign(std::size_t(ctrl.requirement_rows()), 0);
  F_s_ = VectorXd::Zero(n);
  lam_ = VectorXd::Zero(model.constraint_rows());
  accel_ = VectorXd::Zero(std::max<Index>(n, 2));
  reaction_ = VectorXd::Zero(n);
  part_ = VectorXd::Zero(n);
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
  close_lifted_sticks(cws.model);
  if (s != ControlStatus::kOk) {
    // (a law whose answer to the contact forces is not the requirements' exact elimination —
    // never the Gauss law — or stuck contacts that would slip): the held control stands
    s = compute_control(ctrl, cws, q, qd, t);
  }
  return true;
}

void ContactModes::open_lifted_sticks(Workspace& model, Index k) {
  lifted_.clear();
  for (Index j = 0; j < k; ++j) {
    if (lambda_[j] > 0.0) continue;
    const Index normal = contacts_[std::size_t(closed_[std::size_t(j)])];
    for (std::size_t f = 0; f < frictions_.size(); ++f) {
      const FrictionContact& c = frictions_[f];
      const auto stick = std::size_t(c.stick_constraint), force = std::size_t(c.force);
      if (c.normal_constraint != normal || model.activity_override[stick] <= 0) continue;
      lifted_.push_back(f);
      lifted_modes_[f] = model.activity_override[stick];
      lifted_enabled_[f] = model.nonideal_enabled[force];
      // (its friction off: mu N of a zero N)
      model.activity_override[stick] = 0;
      model.nonideal_enabled[force] = 0;
    }
  }
}

void ContactModes::close_lifted_sticks(Workspace& model) const {
  for (std::size_t f : lifted_) {
    const FrictionContact& c = frictions_[f];
    model.activity_override[std::size_t(c.stick_constraint)] = lifted_modes_[f];
    model.nonideal_enabled[std::size_t(c.force)] = lifted_enabled_[f];
  }
}

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
  lifted_.clear();
  for (std::size_t f = 0; f < frictions_.size(); ++f) {
    const FrictionContact& c = frictions_[f];
    if (c.mu_static == 0.0 || std::none_of(closed_.begin(), closed_.end(), [&](Index i) {
          return contacts_[std::size_t(i)] == c.normal_constraint;
        })) {
      continue;
    }
    detail::sliding_velocity(sys, model, Index(f), q, qd, t, false);
    if (!(model.sliding.col(Index(f)).head(c.size()).norm() <= c.eps)) continue;
    const auto stick = std::size_t(c.stick_constraint), force = std::size_t(c.force);
    lifted_.push_back(f);
    lifted_modes_[f] = modes[stick];
    lifted_enabled_[f] = model.nonideal_enabled[force];
    modes[stick] = 1;
    model.nonideal_enabled[force] = 0;
  }
  const ControlStatus held = compute_control(ctrl, cws, q, qd, t);
  close_lifted_sticks(model);
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
  // F_h: the control with them held; not met either: not theirs, the sliding control stands
  hold_sliding_contacts(model);
  if (compute_control(ctrl, cws, q, qd, t) != ControlStatus::kOk) {
    release_sliding_contacts(model);
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
  release_sliding_contacts(model);
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

void ContactModes::hold_sliding_contacts(Workspace& model) {
  for (std::size_t j : stuck_) {
    const FrictionContact& c = frictions_[j];
    const auto stick = std::size_t(c.stick_constraint), force = std::size_t(c.force);
    slide_modes_[j] = model.activity_override[stick];
    slide_enabled_[j] = model.nonideal_enabled[force];
    model.activity_override[stick] = 1;
    model.nonideal_enabled[force] = 0;
  }
}

void ContactModes::release_sliding_contacts(Workspace& model) const {
  for (std::size_t j : stuck_) {
    const FrictionContact& c = frictions_[j];
    model.activity_override[std::size_t(c.stick_constraint)] = slide_modes_[j];
    model.nonideal_enabled[std::size_t(c.force)] = slide_enabled_[j];
  }
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

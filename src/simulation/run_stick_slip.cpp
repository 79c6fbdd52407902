// SPDX-License-Identifier: BSD-3-Clause
// Coulomb contacts: stick, slide, or slide through v_rel = 0 (docs/friction.md, "Stick and slip,
// as events"). Each contact's mode (sliding: its friction force acts; sticking: its stick
// constraint acts; passing: it slides through a zero of v_rel at which it could not stick), the
// tests that decide a stick, the release at mu_static N, and the carrying of a sliding contact
// through a dead centre. The events themselves are located in run_events.cpp. The class:
// simulation/run.hpp.
#include <Eigen/QR>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "simulation/run.hpp"
#include "ukdyn/dynamics/contact.hpp"

namespace ukdyn::detail {

// the friction force while sliding, the stick constraint while sticking
void Run::apply_contact_modes() {
  const auto& contacts = sys_.friction_contacts();
  group_t_ = std::numeric_limits<double>::quiet_NaN();  // (group_margin's answer is stale)
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    const bool sticks = mode_[c] == ContactMode::kSticking;
    ws_.nonideal_enabled[std::size_t(contacts[c].force)] = sticks ? 0 : 1;
    ws_.activity_override[std::size_t(contacts[c].stick_constraint)] = sticks ? 1 : 0;
  }
}

// initial modes: a contact at rest (|v_rel| <= eps) sticks when sticking is admissible, else it
// starts to slide with friction against its impending motion
void Run::initial_contact_modes(double t, double* x) {
  const auto& contacts = sys_.friction_contacts();
  mode_.assign(contacts.size(), ContactMode::kSliding);
  apply_contact_modes();
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    if (frictionless(c) || separated(c)) continue;
    const Index k = relative_velocity(c, t, x, velocity_);
    if (velocity_.head(k).norm() <= contacts[c].eps && !try_stick(c, t, x)) {
      start_sliding(c, t, x);
    }
  }
  apply_contact_modes();
  separated_before_.assign(contacts.size(), 0);
  for (std::size_t c = 0; c < contacts.size(); ++c) separated_before_[c] = separated(c) ? 1 : 0;
}

// after an impact or release of unilateral contacts at (t, x): a Coulomb contact whose contact
// is open slides (its friction is zero while open: a stick constraint would hold it in the
// air); a closed one that an impact set sliding (|v_rel| > eps while it stuck) slides against
// its motion; a closed one at rest (|v_rel| <= eps: it closed, or an impact's friction stopped
// it) sticks when that is admissible, else starts to slide against its impending motion, as at
// the start of a run
void Run::contacts_changed(double t, double* x) {
  const auto& contacts = sys_.friction_contacts();
  separated_before_.resize(contacts.size(), 0);
  const std::vector<unsigned char> was_open = separated_before_;
  // the open ones first: a stick constraint left on an open contact would make the others'
  // stick rows inconsistent (a rocking block's corner that leaves holds its x while the
  // landing one tries to stick)
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    if (!sys_.constraint(contacts[c].normal_constraint).is_unilateral()) continue;
    separated_before_[c] = separated(c) ? 1 : 0;
    if (!separated(c) && !frictionless(c)) continue;
    if (mode_[c] != ContactMode::kSliding) ++traj_.stats.events;
    mode_[c] = ContactMode::kSliding;
    set_slip_hint(c, VectorXd());
    ws_.slip_hint_held[std::size_t(contacts[c].force)] = 0;
  }
  apply_contact_modes();
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    if (!sys_.constraint(contacts[c].normal_constraint).is_unilateral() || separated(c) ||
        frictionless(c))
      continue;
    const Index k = relative_velocity(c, t, x, velocity_);
    const bool at_rest = velocity_.head(k).norm() <= contacts[c].eps;
    if (mode_[c] == ContactMode::kSticking) {
      if (at_rest) continue;
      ++traj_.stats.events;
      mode_[c] = ContactMode::kSliding;
      set_slip_hint(c, VectorXd());
      apply_contact_modes();
      continue;
    }
    if (at_rest && (was_open[c] || mode_[c] == ContactMode::kSliding) && !try_stick(c, t, x)) {
      start_sliding(c, t, x);
    }
  }
  apply_contact_modes();
}

// switches the contact found by the last find_event at (t, x)
Status Run::switch_contact(double t, double* x) {
  const std::size_t c = std::size_t(switching_);
  ++traj_.stats.events;
  switch (mode_[c]) {
    case ContactMode::kSticking: {
      // release: friction from its full magnitude along the force that held the contact
      stick_margin(c, t, x);
      mode_[c] = ContactMode::kSliding;
      set_slip_hint(c, holding_);
      apply_contact_modes();
      // (the contacts still sticking that no split of the holding forces can hold slip too)
      if (sticking_contacts() > 0) release_unheld(t, x);
      bool changed = false;
      ProjectionOptions all = o_.projection;
      return project(t, x, all, changed);
    }
    case ContactMode::kSliding: {
      // the contact stops, or would have to: it sticks (with the contacts stopped with it) when
      // that is admissible, else it slides on through v_rel = 0, the next event of this contact
      if (try_stick_together(c, t, x)) return Status::kOk;
      const Index k = relative_velocity(c, t, x, velocity_);
      const double speed = velocity_.head(k).norm();
      passing_.col(Index(c)).head(k) = velocity_.head(k) / (speed > 0.0 ? speed : 1.0);
      mode_[c] = ContactMode::kPassing;
      return Status::kOk;
    }
    case ContactMode::kPassing:
      // carried through a dead centre and past it: the friction turns against the new motion
      // (at its full magnitude while |v_rel| <= 100 eps, then by the law)
      if (held(c)) {
        ws_.slip_hint_held[std::size_t(sys_.friction_contacts()[c].force)] = 0;
        const Index k = relative_velocity(c, t, x, velocity_);
        mode_[c] = ContactMode::kSliding;
        if (velocity_.head(k).dot(passing_.col(Index(c)).head(k)) > 0.0) {
          set_slip_hint(c, VectorXd());  // left the neighbourhood before the zero
          return Status::kOk;
        }
        if (try_stick_together(c, t, x, false)) return Status::kOk;
        set_slip_hint(c, carried_direction(c, 1.0));
        return Status::kOk;
      }
      // v_rel = 0: it sticks now if it can (a stop located early, where the velocity jump
      // was not yet tolerance-level); else the friction turns against the new motion, at
      // its full magnitude
      if (try_stick_together(c, t, x, false)) return Status::kOk;
      if (!start_sliding(c, t, x)) {
        // friction could hold the contact, but it cannot stick: the regularized law would
        // only creep towards rest (stiff, millions of steps); stop with the reason instead
        failure_ = "t = " + format(t) + ": contact '" +
                   sys_.nonideal_name(sys_.friction_contacts()[c].force) +
                   "' comes to rest where friction could hold it, but it cannot stick (" +
                   (refusal_.empty() ? std::string("its stick was refused") : refusal_) +
                   "); the run stops here rather than creep under the regularized law "
                   "(docs/friction.md, Limits)";
        apply_contact_modes();
        return Status::kIntegratorFailure;
      }
      apply_contact_modes();
      return Status::kOk;
  }
  return Status::kOk;
}

// mu_static N − |holding force|, with the contact sticking, at (t, x); NaN when the
// constraints with the stick rows have no solution there. The stick rows make the normal
// constraint's rows redundant, so their minimum-norm shares split the reaction arbitrarily;
// the reaction R = share(normal) + share(stick) is unique, and is split here into its part
// along the normal constraint's rows (N) and the rest (the friction that holds).
double Run::stick_margin(std::size_t c, double t, const double* x) {
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  if (forward_dynamics(sys_, ws_, q_, qd_, t) != Status::kOk) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return stick_margin_here(c, t);
}

// stick_margin from the evaluation just made (at q_, qd_, t)
double Run::stick_margin_here(std::size_t c, double t) {
  const FrictionContact& contact = sys_.friction_contacts()[c];
  // R = the two constraints' shares of the ideal force and of the other contacts' friction
  reaction_ = ws_.shares.col(contact.normal_constraint) + ws_.shares.col(contact.stick_constraint);
  for (Index k : {contact.normal_constraint, contact.stick_constraint}) {
    detail::constraint_share(sys_, ws_, k, ws_.lambda_nonideal, reaction_part_);
    reaction_ += reaction_part_;
  }
  if (contact.kinematics) return point_stick_margin(c, contact, t);
  const Index k = contact.normal_constraint, rows = sys_.constraint(k).rows();
  if (normals_.rows() != rows) normals_.resize(rows, n_);  // (once per contact size)
  detail::copy_constraint_rows(sys_, ws_, k, normals_);
  const auto& normals = normals_;
  // R_N = projection of R onto the normal rows: a (a·R)/(a·a) for one row
  if (rows == 1) {
    const double aa = normals.row(0).squaredNorm();
    normal_ = normals.row(0).transpose() * (aa > 0.0 ? normals.row(0).dot(reaction_) / aa : 0.0);
  } else {
    const MatrixXd Nt = normals.transpose();
    normal_ = Nt * Nt.completeOrthogonalDecomposition().solve(reaction_);
  }
  holding_ = reaction_ - normal_;
  return contact.mu_static * normal_.norm() - holding_.norm();
}

// stick_margin on the contact-point path, after the evaluation with the contact sticking:
// N from the normal constraint's whole reaction (contact_normal_force), the holding force
// f_t = kappa (lambda_stick + lambda_nonideal,stick) in the tangent basis (the stick rows are
// kappa T, so their share is Tᵀ f_t), into holding_.head(d)
double Run::point_stick_margin(std::size_t c, const FrictionContact& contact, double t) {
  reaction_ = ws_.shares.col(contact.normal_constraint);
  detail::constraint_share(sys_, ws_, contact.normal_constraint, ws_.lambda_nonideal,
                           reaction_part_);
  reaction_ += reaction_part_;
  // (the contact's Jacobian rows at this state, for N)
  detail::sliding_velocity(sys_, ws_, Index(c), q_, qd_, t, false);
  const double N = detail::contact_normal_force(sys_, ws_, Index(c), reaction_);
  // kappa: the unit of the normal rows as assembled (that of the stick rows, PointStickModel)
  const Index d = contact.kinematics.tangents, s = contact.stick_constraint;
  const Index k = contact.normal_constraint, rows = sys_.constraint(k).rows();
  if (normals_.rows() != rows) normals_.resize(rows, n_);  // (once per contact size)
  detail::copy_constraint_rows(sys_, ws_, k, normals_);
  const double kappa = detail::normal_row_unit(normals_, rows, reaction_part_);
  holding_.setZero(std::max(n_, d));
  holding_.head(d) =
      kappa * (ws_.lambda_of(sys_, s) + ws_.lambda_nonideal.segment(sys_.row_offset(s), d));
  return contact.mu_static * N - holding_.head(d).norm();
}

// Sticks contact c at (t, x) when sticking is admissible, projecting the velocities of x onto
// the stick rows; else leaves x and the mode as they were and returns false. Admissible:
// (1) the projection removes at most rtol · (largest kinetic energy of the run) — a zero of
// v_rel that the mechanism passes through kinematically (a dead centre) would need a velocity
// jump; (2) the constraints with the stick rows have a solution there; (3) the force that
// holds the contact lies within mu_static N.
// `report`: a refusal for reasons 1 or 2 is counted and noted.
bool Run::try_stick(std::size_t c, double t, double* x, bool report) {
  // (1) the velocities with the stick rows (into qd_), and the kinetic energy that takes
  ProjectionResult rv;
  double T_before = 0.0;
  const double removed = stick_energy_loss(c, t, x, rv, T_before);
  mode_[c] = ContactMode::kSticking;
  apply_contact_modes();
  auto refuse = [&](const std::string& why) {
    refusal_ = why;
    mode_[c] = ContactMode::kSliding;
    apply_contact_modes();
    if (report && !why.empty()) {
      ++traj_.stats.stick_refusals;
      if (traj_.stats.notes.size() < kMaxNotes) {
        traj_.stats.notes.push_back("t = " + format(t) + ": contact '" +
                                    sys_.nonideal_name(sys_.friction_contacts()[c].force) +
                                    "' did not stick: " + why + "; it slides on through v = 0");
      }
    }
    return false;
  };
  if (std::isnan(removed)) {
    return refuse(
        "the velocities cannot be projected onto the stick rows (its tangential motion is "
        "fixed by the other constraints?)");
  }
  if (removed > stick_allowance(c, T_before)) {
    return refuse("sticking would remove " + format(removed) +
                  " of kinetic energy (a zero of the sliding velocity that the mechanism passes "
                  "through)");
  }
  std::copy(x, x + sample_.size(), trial_.begin());
  Eigen::Map<VectorXd>(trial_.data() + n_, n_) = qd_;
  // (2), (3)
  const double margin = stick_margin(c, t, trial_.data());
  if (std::isnan(margin)) return refuse("the constraints with the stick rows have no solution");
  if (margin < 0.0) return refuse("");  // it reverses: friction cannot hold it
  if (rv.iterations > 0) ++traj_.stats.projections;
  note_violation(0.0, rv.violation);
  std::copy(trial_.begin(), trial_.end(), x);
  set_slip_hint(c, VectorXd());
  return true;
}

// The kinetic energy that projecting the velocities of x onto contact c's stick rows (least
// M-norm, with every other constraint) removes; the projected velocities into qd_, the
// projection's result into rv, the kinetic energy before into T_before. NaN when the state
// cannot be evaluated or the projection fails. Leaves the contact's mode as it was.
double Run::stick_energy_loss(std::size_t c, double t, const double* x, ProjectionResult& rv,
                              double& T_before) {
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  const bool evaluated = forward_dynamics(sys_, ws_, q_, qd_, t) == Status::kOk;
  T_before = detail::kinetic_energy(ws_, qd_);
  const ContactMode was = mode_[c];
  mode_[c] = ContactMode::kSticking;
  apply_contact_modes();
  ProjectionOptions all = o_.projection;
  rv = project_velocities(sys_, ws_, q_, qd_, t, all);
  mode_[c] = was;
  apply_contact_modes();
  if (!evaluated || rv.status != Status::kOk || !rv.converged) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return T_before - detail::kinetic_energy(ws_, qd_);
}

// True when contact c's stop located at te (dense: the step's state there) is a passage of
// v_rel = 0 that the mechanism makes kinematically (a stick would remove kinetic energy) at a
// configuration where the constraints nearly lose rank (Workspace::rank_margin below
// kSingularMargin: a dead centre where two rows coincide). A restart there would start from
// a state whose velocities the near-dependent rows fix only to (position error) / (distance
// to the pose) — 1e-3 relative at the twin arms' dead centre, enough to take one arm onto the
// mirror branch. No stick is possible there, and the friction turns within the step by its
// regularized law, so the run goes on without restarting (docs/friction.md, "Dead centres").
bool Run::passes_at_rank_drop(std::size_t c, double te, const detail::SegmentHooks::Dense& dense) {
  dense(te, event_x_.data());
  q_ = Eigen::Map<const VectorXd>(event_x_.data(), n_);
  qd_ = Eigen::Map<const VectorXd>(event_x_.data() + n_, n_);
  if (forward_dynamics(sys_, ws_, q_, qd_, te) != Status::kOk) return false;
  if (!(ws_.rank_margin < detail::kSingularMargin)) return false;  // (NaN: unknown)
  ProjectionResult rv;
  double T_before = 0.0;
  const double removed = stick_energy_loss(c, te, event_x_.data(), rv, T_before);
  return std::isnan(removed) || removed > stick_allowance(c, T_before);
}

// Contact c, sliding along direction_ (length k) near a rank drop (the step's rank margin
// below kSingularMargin), is carried through the dead centre when it still slides clearly
// along that direction at t1 (faster than v_stop): its friction keeps that direction, at every
// speed (Workspace::slip_hint_held: at t1 the same force as the law's), until the end of the
// step in which v_rel crosses zero, where it turns (switch_contact), or until the margin is
// back above twice kSingularMargin. At a kinematic passage (a dead centre, where the sliding
// coordinate is stationary) the friction's jump at v_rel = 0 is normal to the constraints and
// its effect on the motion vanishes with the distance to the pose: a kink. Located or
// resolved by the step-size control, that kink draws the steps into the neighbourhood where
// the near-dependent rows fix the velocities only to (position tolerance) / (distance to the
// pose), and there the run left its branch (one of the twin arms onto the mirror branch, with
// status ok). Carried, the friction is smooth along every step, and the step that crosses
// keeps the force of the side it started on: an error of O(mu N h²) times the rate at which
// the sliding coordinate's speed grows past the pose, measured in the energy balance like
// any force. Returns whether the contact is carried.
bool Run::carry_through(std::size_t c, Index k, double t1, const double* x1, double v_stop) {
  relative_velocity(c, t1, x1, velocity_);
  if (!(velocity_.head(k).dot(direction_.head(k)) > v_stop)) return false;
  mode_[c] = ContactMode::kPassing;
  passing_.col(Index(c)).head(k) = velocity_.head(k).normalized();
  set_slip_hint(c, carried_direction(c, -1.0));
  ws_.slip_hint_held[std::size_t(sys_.friction_contacts()[c].force)] = 1;
  return true;
}

// The restart after a carried contact's zero of v_rel at tz, inside the step to (t1, x1): the
// first time past tz where the rank margin is back to kCarriedMargin, or t1. The friction
// keeps its old side only that far past the pose (an error of O(mu N) times the sliding
// coordinate's rate squared over that stretch), and the restart lies outside the pose's
// neighbourhood.
double Run::carried_past(double tz, double t1, const double* x1,
                         const detail::SegmentHooks::Dense& dense) {
  const double te = locate(tz, t1, x1, dense, [&](double t, const double* x) {
    q_ = Eigen::Map<const VectorXd>(x, n_);
    qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
    if (forward_dynamics(sys_, ws_, q_, qd_, t) != Status::kOk) return 1.0;
    return ws_.rank_margin < kCarriedMargin ? 1.0 : -1.0;
  });
  return std::isnan(te) ? t1 : te;
}

// sign × contact c's passing direction on its sliding coordinates, into holding_ (n)
const VectorXd& Run::carried_direction(std::size_t c, double sign) {
  const FrictionContact& contact = sys_.friction_contacts()[c];
  if (contact.kinematics) {
    const Index d = contact.kinematics.tangents;
    holding_.setZero(std::max(n_, d));
    holding_.head(d) = sign * passing_.col(Index(c)).head(d);
    return holding_;
  }
  const auto& coords = contact.coordinates;
  holding_.setZero();
  for (std::size_t r = 0; r < coords.size(); ++r)
    holding_[coords[r]] = sign * passing_(Index(r), Index(c));
  return holding_;
}

// contact c slides from v_rel = 0 (passing, or at the start): friction at its full magnitude
// against the impending motion, the acceleration of v_rel without this friction. Returns
// false when that friction would turn the motion back (it could hold the contact): then the
// regularized law acts instead, with no hint.
bool Run::start_sliding(std::size_t c, double t, const double* x) {
  const FrictionContact& contact = sys_.friction_contacts()[c];
  mode_[c] = ContactMode::kSliding;
  set_slip_hint(c, VectorXd());
  apply_contact_modes();
  ws_.nonideal_enabled[std::size_t(contact.force)] = 0;
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  const bool evaluated = forward_dynamics(sys_, ws_, q_, qd_, t) == Status::kOk;
  apply_contact_modes();
  if (!evaluated) return true;  // (the regularized law then decides)
  // a_rel = P (q''_c − u') without this friction: the impending motion
  relative_acceleration(c, t);
  const Index k = contact.size();
  if (contact.kinematics) {
    holding_.setZero(std::max(n_, k));
    holding_.head(k) = -velocity_.head(k);
  } else {
    holding_.setZero();
    const auto& coords = contact.coordinates;
    for (std::size_t r = 0; r < coords.size(); ++r) holding_[coords[r]] = -velocity_[Index(r)];
  }
  set_slip_hint(c, holding_);
  // with the friction at its full magnitude against it, does the contact still move that way?
  // If not, friction could hold it although the stick was not admissible (a stick constraint
  // that the model cannot express): no hint then, the regularized law holds it near rest
  direction_.head(k) = velocity_.head(k);
  if (forward_dynamics(sys_, ws_, q_, qd_, t) != Status::kOk) return true;
  relative_acceleration(c, t);
  if (velocity_.head(k).dot(direction_.head(k)) > 0.0) return true;
  set_slip_hint(c, VectorXd());
  return false;
}

// a_rel = P (q''_c − u') of contact c from the last evaluation (at q_, qd_, t) into the head of
// velocity_, P the tangential projector of sliding_velocity
void Run::relative_acceleration(std::size_t c, double t) {
  const FrictionContact& contact = sys_.friction_contacts()[c];
  if (const ContactKinematics& kin = contact.kinematics) {
    // a_rel = T q'' + T' q'
    detail::sliding_velocity(sys_, ws_, Index(c), q_, qd_, t, false);
    const Index d = kin.tangents;
    const auto& J = ws_.contact_jacobian[c];
    velocity_.head(d) = ws_.contact_bias.col(Index(c)).segment(1, d);
    for (std::size_t j = 0; j < kin.columns.size(); ++j)
      velocity_.head(d) += J.col(Index(j)).tail(d) * ws_.qdd[kin.columns[j]];
    return;
  }
  const Index k = Index(contact.coordinates.size());
  for (Index r = 0; r < k; ++r) velocity_[r] = ws_.qdd[contact.coordinates[std::size_t(r)]];
  const Index basis = detail::sliding_velocity(sys_, ws_, Index(c), q_, qd_, t, false);
  if (contact.surface_velocity) velocity_.head(k) -= ws_.surface_u_dot.head(k);
  detail::remove_normals(ws_, basis, velocity_.head(k));
}

// the direction of the friction at |v_rel| <= eps: along `along` (n) on the contact's
// sliding coordinates, normalized; none when `along` is empty or zero (see CoulombFriction)
void Run::set_slip_hint(std::size_t c, const Eigen::Ref<const VectorXd>& along) {
  const FrictionContact& contact = sys_.friction_contacts()[c];
  auto hint = ws_.slip_hint.col(contact.force);
  hint.setZero();
  if (along.size() == 0) return;
  if (contact.kinematics) {
    hint.head(contact.kinematics.tangents) = along.head(contact.kinematics.tangents);
  } else {
    for (Index i : contact.coordinates) hint[i] = along[i];
  }
  if (hint.norm() > 0.0) hint.normalize();
}

// ---- Several contacts (docs/friction.md, "Several contacts") ----------------------------------

// the sticking contacts (closed, with friction) into stuck_; returns their count
std::size_t Run::sticking_contacts() {
  stuck_.clear();
  for (std::size_t c = 0; c < mode_.size(); ++c) {
    if (mode_[c] == ContactMode::kSticking && !separated(c) && !frictionless(c))
      stuck_.push_back(c);
  }
  return stuck_.size();
}

// Contact c stops at (t, x) (its sliding speed fell to v_stop): every other closed contact whose
// sliding speed there is within 2 v_stop of rest (a contact of the same body, whose stick rows
// are redundant with c's, slides at c's speed and has no stop event of its own) sticks with it
// when that is admissible jointly, by try_stick's three rules on all of them: the velocity
// projection onto all their stick rows removes at most the largest of their allowances, the
// constraints with all the stick rows have a solution, and some split of the holding forces
// lies inside every sticking contact's cone (holding_split). Else, or when none stopped with
// it, try_stick(c) alone. Cost: one projection and two evaluations, and holding_split's.
bool Run::try_stick_together(std::size_t c, double t, double* x, bool report) {
  const auto& contacts = sys_.friction_contacts();
  modes_before_ = mode_;
  bool others = false;
  for (std::size_t o = 0; o < contacts.size(); ++o) {
    if (o == c || mode_[o] == ContactMode::kSticking || frictionless(o) || separated(o)) continue;
    const Index k = relative_velocity(o, t, x, velocity_);
    if (velocity_.head(k).norm() <= 2.0 * 100.0 * contacts[o].eps) {
      mode_[o] = ContactMode::kSticking;
      others = true;
    }
  }
  if (!others) return try_stick(c, t, x, report);
  mode_[c] = ContactMode::kSticking;
  // the kinetic energy the projection onto all the stick rows removes (rule 1)
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  std::swap(mode_, modes_before_);
  apply_contact_modes();
  bool admissible = forward_dynamics(sys_, ws_, q_, qd_, t) == Status::kOk;
  const double T_before = detail::kinetic_energy(ws_, qd_);
  double allowance = 0.0;
  for (std::size_t o = 0; o < contacts.size(); ++o) {
    if (modes_before_[o] == ContactMode::kSticking && mode_[o] != ContactMode::kSticking)
      allowance = std::max(allowance, stick_allowance(o, T_before));
  }
  std::swap(mode_, modes_before_);  // (the joint modes)
  apply_contact_modes();
  ProjectionOptions all = o_.projection;
  const ProjectionResult rv = project_velocities(sys_, ws_, q_, qd_, t, all);
  admissible = admissible && rv.status == Status::kOk && rv.converged &&
               T_before - detail::kinetic_energy(ws_, qd_) <= allowance;
  // (2), (3) at the projected state
  if (admissible) {
    std::copy(x, x + sample_.size(), trial_.begin());
    Eigen::Map<VectorXd>(trial_.data() + n_, n_) = qd_;
    q_ = Eigen::Map<const VectorXd>(trial_.data(), n_);
    admissible = forward_dynamics(sys_, ws_, q_, qd_, t) == Status::kOk &&
                 sticking_contacts() > 0 && holding_split(t) >= 0;
  }
  if (!admissible) {
    mode_ = modes_before_;
    apply_contact_modes();
    return try_stick(c, t, x, report);
  }
  if (rv.iterations > 0) ++traj_.stats.projections;
  note_violation(0.0, rv.violation);
  std::copy(trial_.begin(), trial_.end(), x);
  for (std::size_t o = 0; o < contacts.size(); ++o) {
    if (mode_[o] != ContactMode::kSticking || modes_before_[o] == ContactMode::kSticking) continue;
    set_slip_hint(o, VectorXd());
    ws_.slip_hint_held[std::size_t(contacts[o].force)] = 0;
  }
  return true;
}

// The release test of sticking contact c (find_event): alone, its stick_margin; with others
// sticking, its stick_margin while every minimum-norm margin is >= 0 (the old test, unchanged
// where the minimum-norm split holds), else |lowest margin| while some split of the holding
// forces lies inside every cone and the lowest margin (< 0) when none does: the release of a
// rigid body on several contacts is the instant no split holds it, whatever the minimum-norm
// multipliers say (they split the force of redundant stick rows equally). Its sign is what the
// bisection reads. Cost: one evaluation, and holding_split's.
double Run::group_margin(std::size_t c, double t, const double* x) {
  if (sticking_contacts() < 2) return stick_margin(c, t, x);
  // (the same state as the last split search's, for another contact: its answer)
  if (t == group_t_ && std::equal(x, x + 2 * n_, group_x_.begin())) return group_margin_;
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  if (forward_dynamics(sys_, ws_, q_, qd_, t) != Status::kOk) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  const int split = holding_split(t);
  if (split > 0) return stick_margin_here(c, t);
  const double lowest = std::abs(split_lowest_);
  group_t_ = t;
  group_x_.assign(x, x + 2 * n_);
  group_margin_ = split == 0 ? std::max(lowest, std::numeric_limits<double>::min()) : -lowest;
  return group_margin_;
}

// After contact c's release at (t, x): while the contacts still sticking cannot be held by any
// split of their holding forces (with the released ones' friction now acting), the one with the
// lowest minimum-norm margin slips too, along its holding force (as a release).
void Run::release_unheld(double t, double* x) {
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  while (sticking_contacts() > 0) {
    if (forward_dynamics(sys_, ws_, q_, qd_, t) != Status::kOk) return;
    std::size_t worst = 0;
    if (holding_split(t, &worst) >= 0) return;
    stick_margin_here(worst, t);
    ++traj_.stats.events;
    mode_[worst] = ContactMode::kSliding;
    set_slip_hint(worst, holding_);
    apply_contact_modes();
  }
}

// Whether the sticking contacts stuck_ (at the evaluation just made, at q_, qd_, t) can hold.
// The multipliers Λ = lambda + lambda_nonideal of the active rows are unique only up to the null
// space Z of Aᵀ (redundant rows: the stick rows of contacts on one rigid body); Λ + Z y leaves
// Qc and the motion unchanged. Each sticking contact's holding force f_i and normal force N_i
// are linear in Λ (as stick_margin splits them); the split sought is the y of least norm with
// |f_i| <= mu_static N_i for all i: a small second-order cone programme, solved by outer
// cutting planes — for one tangent the two faces ±f_i <= mu_s N_i (exact), for two the tangent
// planes u·f_i <= mu_s N_i at the directions u of the violating f_i, added until every cone
// holds to 1e-7 of the forces (at most kSplitRounds rounds) — each a quadratic programme
// min ½|y|², G y <= h, solved as the LCP w = (G Gᵀ + δ I) z + h (y = −Gᵀ z) by Siconos
// Numerics (ContactLcp) and polished on its active planes; a plane still violated then means
// an empty polyhedron (no split exists: the outer planes contain the cones). The sliding
// contacts' normal forces stay as evaluated (their friction is mu N of those). Returns 1 when the
// minimum-norm split holds (y = 0), 0 when another does (its change of the multipliers into split_,
// m), −1 when none does (and when a sticking contact on the coordinate path has a normal constraint
// of several rows, whose N is not linear in Λ: the minimum-norm test then). The lowest minimum-norm
// margin into split_lowest_, its contact into *worst. Cost: an SVD of the active rows (m_a × n) and
// a few LCPs of 2 to 3 rows per contact; allocates (at stops, releases and the samples of runs with
// several contacts sticking where the minimum-norm split fails).
int Run::holding_split(double t, std::size_t* worst) {
  const auto& contacts = sys_.friction_contacts();
  split_lowest_ = std::numeric_limits<double>::infinity();
  for (std::size_t c : stuck_) {
    const double margin = stick_margin_here(c, t);
    if (!(margin >= split_lowest_)) {
      split_lowest_ = margin;
      if (worst) *worst = c;
    }
  }
  const Index m = ws_.lambda.size();
  split_.setZero(m);
  if (split_lowest_ >= 0.0) return 1;
  if (stuck_.size() < 2 || std::isnan(split_lowest_)) return -1;
  // the active rows, compact: their rows of A, and Λ there
  std::vector<Index> row_of, compact(std::size_t(m), -1);
  for (Index k = 0; k < sys_.constraint_count(); ++k) {
    if (!ws_.active[std::size_t(k)]) continue;
    for (Index r = 0; r < sys_.constraint(k).rows(); ++r) {
      compact[std::size_t(sys_.row_offset(k) + r)] = Index(row_of.size());
      row_of.push_back(sys_.row_offset(k) + r);
    }
  }
  const Index ma = Index(row_of.size());
  split_rows_.setZero(ma, n_);
  for (Index k = 0; k < sys_.constraint_count(); ++k) {
    if (!ws_.active[std::size_t(k)] || sys_.constraint(k).rows() == 0) continue;
    detail::copy_constraint_rows(sys_, ws_, k,
                                 split_rows_.middleRows(compact[std::size_t(sys_.row_offset(k))],
                                                        sys_.constraint(k).rows()));
  }
  VectorXd lambda0(ma);
  const bool nonideal = ws_.lambda_nonideal.size() == m;
  for (Index i = 0; i < ma; ++i) {
    const Index r = row_of[std::size_t(i)];
    lambda0[i] = ws_.lambda[r] + (nonideal ? ws_.lambda_nonideal[r] : 0.0);
  }
  // Z: the left null space of the active rows
  const Eigen::JacobiSVD<MatrixXd> svd(split_rows_, Eigen::ComputeFullU);
  const auto& sigma = svd.singularValues();
  Index rank = 0;
  while (rank < sigma.size() && sigma[rank] > 1e-10 * sigma[0]) ++rank;
  if (rank == ma) return -1;
  split_null_ = svd.matrixU().rightCols(ma - rank);
  // N_i = g·Λ of contact c (the sign of Λ at the evaluation: N is |·|) into g; false where N is
  // not linear in Λ (a coordinate-path normal constraint of several rows)
  auto normal_form = [&](std::size_t c, VectorXd& g) {
    const FrictionContact& contact = contacts[c];
    const Index k = contact.normal_constraint, s = contact.stick_constraint;
    const Index rows_k = sys_.constraint(k).rows(), rows_s = sys_.constraint(s).rows();
    const Index ok = compact[std::size_t(sys_.row_offset(k))];
    g.setZero(ma);
    if (const ContactKinematics& kin = contact.kinematics) {
      // N = |w·A_kᵀ Λ_k| / |w|², w = J_Pᵀ n_W (contact_normal_force)
      detail::sliding_velocity(sys_, ws_, Index(c), q_, qd_, t, false);
      const auto& J = ws_.contact_jacobian[c];
      const double ww = J.row(0).squaredNorm();
      for (Index r = 0; r < rows_k && ww > 0.0; ++r) {
        double wa = 0.0;
        for (std::size_t j = 0; j < kin.columns.size(); ++j)
          wa += J(0, Index(j)) * split_rows_(ok + r, kin.columns[j]);
        g[ok + r] = wa / ww;
      }
    } else {
      // R = A_kᵀ Λ_k + A_sᵀ Λ_s (its rows while it sticks); N = |a·R| / |a| (one normal row)
      if (rows_k != 1) return false;
      const double aa = split_rows_.row(ok).squaredNorm();
      if (!(aa > 0.0)) return false;
      const Index os = compact[std::size_t(sys_.row_offset(s))];
      const bool sticks = os >= 0 && ws_.active[std::size_t(s)];
      for (Index r = 0; r < rows_k + (sticks ? rows_s : 0); ++r) {
        const Index i = r < rows_k ? ok + r : os + r - rows_k;
        g[i] = split_rows_.row(ok).dot(split_rows_.row(i)) / std::sqrt(aa);
      }
    }
    if (g.dot(lambda0) < 0.0) g = -g;
    return true;
  };
  // the sliding contacts' normal forces stay (their friction is μ N at the evaluation's N): Z
  // restricted to the y that leave each one's N unchanged
  {
    std::vector<VectorXd> fixed;
    VectorXd g;
    for (std::size_t c = 0; c < contacts.size(); ++c) {
      if (mode_[c] == ContactMode::kSticking || separated(c) || frictionless(c)) continue;
      if (compact[std::size_t(sys_.row_offset(contacts[c].normal_constraint))] < 0) continue;
      if (!normal_form(c, g)) return -1;
      fixed.push_back(split_null_.transpose() * g);
    }
    if (!fixed.empty()) {
      MatrixXd E(Index(fixed.size()), split_null_.cols());
      for (std::size_t i = 0; i < fixed.size(); ++i) E.row(Index(i)) = fixed[i].transpose();
      const Eigen::JacobiSVD<MatrixXd> keep(E, Eigen::ComputeFullV);
      const auto& sv = keep.singularValues();
      const double top = sv.size() > 0 ? sv[0] : 0.0;
      Index used = 0;
      while (used < sv.size() && sv[used] > 1e-10 * std::max(top, 1e-300)) ++used;
      if (used == E.cols()) return -1;
      split_null_ = (split_null_ * keep.matrixV().rightCols(E.cols() - used)).eval();
    }
  }
  const Index nz = split_null_.cols();
  // each contact's f_i = F_i Λ (d_i) and N_i = g_i·Λ on the compact rows, then on y
  struct Cone {
    MatrixXd F;  // (d × nz) F_i Z
    VectorXd g;  // (nz) Zᵀ g_i
    VectorXd f0;
    double N0 = 0.0, mu = 0.0;
  };
  std::vector<Cone> cones;
  double scale = 0.0;
  for (std::size_t c : stuck_) {
    const FrictionContact& contact = contacts[c];
    const Index k = contact.normal_constraint, s = contact.stick_constraint;
    const Index rows_k = sys_.constraint(k).rows(), rows_s = sys_.constraint(s).rows();
    const Index ok = compact[std::size_t(sys_.row_offset(k))];
    const Index os = compact[std::size_t(sys_.row_offset(s))];
    MatrixXd F = MatrixXd::Zero(0, ma);
    VectorXd g;
    if (!normal_form(c, g)) return -1;
    if (const ContactKinematics& kin = contact.kinematics) {
      // f = kappa Λ_s
      if (normals_.rows() != rows_k) normals_.resize(rows_k, n_);
      detail::copy_constraint_rows(sys_, ws_, k, normals_);
      const double kappa = detail::normal_row_unit(normals_, rows_k, reaction_part_);
      F.setZero(kin.tangents, ma);
      for (Index j = 0; j < kin.tangents; ++j) F(j, os + j) = kappa;
    } else {
      // f = P R in an orthonormal basis of its range, P = I − a aᵀ / |a|²
      const VectorXd a = split_rows_.row(ok).transpose();
      MatrixXd H = split_rows_.middleRows(os, rows_s).transpose();  // (n × rows_s)
      H -= a * (a.transpose() * H) / a.squaredNorm();
      const Eigen::JacobiSVD<MatrixXd> range(H, Eigen::ComputeThinU);
      Index d = 0;
      const double top = range.singularValues().size() ? range.singularValues()[0] : 0.0;
      while (d < range.singularValues().size() && range.singularValues()[d] > 1e-10 * top) ++d;
      F.setZero(d, ma);
      F.middleCols(os, rows_s) = range.matrixU().leftCols(d).transpose() * H;
    }
    Cone cone;
    cone.N0 = g.dot(lambda0);
    cone.f0 = F * lambda0;
    cone.F = F * split_null_;
    cone.g = split_null_.transpose() * g;
    cone.mu = contact.mu_static;
    scale = std::max({scale, cone.mu * cone.N0, cone.f0.norm()});
    cones.push_back(std::move(cone));
  }
  // the planes G y <= h: N_i >= 0, and faces or tangent planes of the cones
  std::vector<VectorXd> planes;
  std::vector<double> offsets;
  auto add_face = [&](const Cone& cone, const VectorXd& u) {
    planes.push_back(cone.F.transpose() * u - cone.mu * cone.g);
    offsets.push_back(cone.mu * cone.N0 - u.dot(cone.f0));
  };
  for (const Cone& cone : cones) {
    planes.push_back(-cone.g);
    offsets.push_back(cone.N0);
    const Index d = cone.f0.size();
    if (d == 0) continue;
    if (d == 1) {
      add_face(cone, VectorXd::Constant(1, 1.0));
      add_face(cone, VectorXd::Constant(1, -1.0));
      continue;
    }
    VectorXd u = VectorXd::Zero(d);
    if (cone.f0.norm() > 0.0)
      u = cone.f0.normalized();
    else
      u[0] = 1.0;
    add_face(cone, u);
  }
  const double tolerance = 1e-7 * scale;
  VectorXd y = VectorXd::Zero(nz);
  for (int round = 0; round < kSplitRounds; ++round) {
    const Index rows = Index(planes.size());
    split_G_.resize(rows, nz);
    split_h_.resize(rows);
    for (Index i = 0; i < rows; ++i) {
      split_G_.row(i) = planes[std::size_t(i)].transpose();
      split_h_[i] = offsets[std::size_t(i)];
    }
    // (W = G Gᵀ is singular where the planes outnumber y: Lemke then failed on feasible sets;
    // W + δ I, δ = 1e-12 of its diagonal, is positive definite, and G y <= h + δ z: a plane
    // violated by more than the tolerance means an empty polyhedron)
    ContactLcp lcp(rows);
    MatrixXd W = split_G_ * split_G_.transpose();
    W.diagonal().array() += 1e-8 * W.diagonal().maxCoeff();
    if (!lcp.solve(W, split_h_, 1e-9)) return -1;
    y = -split_G_.transpose() * lcp.z();
    // (polished on its active planes: the least-norm y with G_a y = h_a, free of δ)
    {
      std::vector<Index> on;
      for (Index i = 0; i < rows; ++i)
        if (lcp.z()[i] > 0.0) on.push_back(i);
      if (!on.empty()) {
        MatrixXd Ga(Index(on.size()), nz);
        VectorXd ha(Index(on.size()));
        for (std::size_t i = 0; i < on.size(); ++i) {
          Ga.row(Index(i)) = split_G_.row(on[i]);
          ha[Index(i)] = split_h_[on[i]];
        }
        const VectorXd polished = Ga.completeOrthogonalDecomposition().solve(ha);
        if ((split_G_ * polished - split_h_).maxCoeff() <= tolerance) y = polished;
      }
    }
    if ((split_G_ * y - split_h_).maxCoeff() > 1e-6 * scale) return -1;
    bool held = true;
    for (const Cone& cone : cones) {
      const VectorXd f = cone.f0 + cone.F * y;
      const double N = cone.N0 + cone.g.dot(y);
      if (f.norm() <= cone.mu * N + tolerance) continue;
      held = false;
      if (f.size() > 1) add_face(cone, f.normalized());
    }
    if (held) {
      const VectorXd change = split_null_ * y;
      for (Index i = 0; i < ma; ++i) split_[row_of[std::size_t(i)]] = change[i];
      return 0;
    }
  }
  return -1;
}

}  // namespace ukdyn::detail

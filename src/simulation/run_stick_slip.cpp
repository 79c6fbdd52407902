// SPDX-License-Identifier: BSD-3-Clause
// Coulomb contacts: stick, slide, or slide through v_rel = 0 (docs/friction.md, "Stick and slip,
// as events"). Each contact's mode (sliding: its friction force acts; sticking: its stick
// constraint acts; passing: it slides through a zero of v_rel at which it could not stick), the
// tests that decide a stick, the release at mu_static N, and the carrying of a sliding contact
// through a dead centre. The events themselves are located in run_events.cpp. The class:
// simulation/run.hpp.
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

// initial modes: the contacts at rest (|v_rel| <= eps) stick together, less those no split of
// the holding forces holds (stick_at_rest); the others slide
void Run::initial_contact_modes(double t, double* x) {
  const auto& contacts = sys_.friction_contacts();
  mode_.assign(contacts.size(), ContactMode::kSliding);
  apply_contact_modes();
  rest_.clear();
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    if (frictionless(c) || separated(c)) continue;
    const Index k = relative_velocity(c, t, x, velocity_);
    if (velocity_.head(k).norm() <= contacts[c].eps) rest_.push_back(c);
  }
  stick_at_rest(t, x, rest_);
  apply_contact_modes();
  separated_before_.assign(contacts.size(), 0);
  for (std::size_t c = 0; c < contacts.size(); ++c) separated_before_[c] = separated(c) ? 1 : 0;
}

// after an impact or release of unilateral contacts at (t, x): a Coulomb contact whose contact
// is open slides (its friction is zero while open: a stick constraint would hold it in the
// air); a closed one that an impact set sliding (|v_rel| > eps while it stuck) slides against
// its motion; the closed ones at rest (|v_rel| <= eps: they closed, or an impact's friction
// stopped them) are decided together with those still sticking, as at the start of a run
// (stick_at_rest)
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
  rest_.clear();
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
    if (at_rest && (was_open[c] || mode_[c] == ContactMode::kSliding)) rest_.push_back(c);
  }
  if (!rest_.empty()) stick_at_rest(t, x, rest_);
  apply_contact_modes();
}

// switches the contact found by the last find_event at (t, x)
Status Run::switch_contact(double t, double* x) {
  const std::size_t c = std::size_t(switching_);
  ++traj_.stats.events;
  switch (mode_[c]) {
    case ContactMode::kSticking: {
      // with others sticking: the contacts that no split of the holding forces holds slip, the
      // least held first (release_unheld, which counts them), whichever found the event
      if (sticking_contacts() >= 2) {
        --traj_.stats.events;
        release_unheld(t, x, true);
        if (!released_.empty()) {
          bool changed = false;
          ProjectionOptions all = o_.projection;
          return project(t, x, all, changed);
        }
        ++traj_.stats.events;
      }
      // release: friction from its full magnitude along the force that held the contact
      note_slip(c, stick_margin(c, t, x));
      mode_[c] = ContactMode::kSliding;
      set_slip_hint(c, holding_);
      apply_contact_modes();
      // (the contacts still sticking that no split of the holding forces can hold slip too)
      if (sticking_contacts() > 0) release_unheld(t, x, true, c);
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
  detail::normal_part(normals_, reaction_, normal_);  // R_N
  holding_ = reaction_ - normal_;
  return contact.mu_static * detail::coordinate_normal_force(contact, normal_) - holding_.norm();
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
        traj_.stats.notes.push_back("t = " + format(t) + " " + o_.units.time + ": contact '" +
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
    return refuse("sticking would remove " + format(removed) + " " + o_.units.energy() +
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
  if (!(velocity_.head(k).norm() > kStillAcceleration * acceleration_scale())) {
    // none (to roundoff of the run's acceleration class): a control that holds the body where
    // it is cancels the motion that friction could not hold (u16 02: a particle pushed by
    // F > mu_static N and required to stay put). The friction then takes the holding force's
    // direction at its full magnitude, as at a release (switch_contact), and the control pays
    // the rest: the same in any units, not a roundoff direction
    mode_[c] = ContactMode::kSticking;
    apply_contact_modes();
    const double margin = stick_margin(c, t, x);
    mode_[c] = ContactMode::kSliding;
    apply_contact_modes();
    if (margin < 0.0) {
      set_slip_hint(c, holding_);
      // (unless that friction moves the contact along itself: the control holds a point that
      // is not the contact's — a body held at its centre, its contact below it, turns under the
      // friction, and sticks with no holding force instead; u17 02)
      if (forward_dynamics(sys_, ws_, q_, qd_, t) != Status::kOk) return true;
      relative_acceleration(c, t);
      const auto hint = ws_.slip_hint.col(contact.force);
      double along = 0.0;
      if (contact.kinematics) {
        along = velocity_.head(k).dot(hint.head(k));
      } else {
        for (Index r = 0; r < k; ++r)
          along += velocity_[r] * hint[contact.coordinates[std::size_t(r)]];
      }
      if (!(along > kStillAcceleration * acceleration_scale())) return true;
      set_slip_hint(c, VectorXd());
      return false;
    }
    // (friction could hold it: the regularized law, below)
  }
  hint_against_acceleration(c);
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

// the run's class of accelerations, v² / ℓ from set_run_scales (0 before them: every a_rel
// counts)
double Run::acceleration_scale() const {
  return ws_.length_scale > 0.0 ? ws_.speed_scale * ws_.speed_scale / ws_.length_scale : 0.0;
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

// contact c's slip hint against a_rel (the head of velocity_, from relative_acceleration),
// through holding_
void Run::hint_against_acceleration(std::size_t c) {
  const FrictionContact& contact = sys_.friction_contacts()[c];
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

}  // namespace ukdyn::detail

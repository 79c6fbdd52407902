// SPDX-License-Identifier: BSD-3-Clause
// Several Coulomb contacts of one body that stop, hold and break away together (docs/friction.md,
// "Several contacts"): the joint stick at a located stop, the split of the holding forces that
// fits every contact's cone when the minimum-norm one does not (cutting planes, each round a
// small QP solved as an LCP), and the release of the contacts no split holds. The single
// contact's stick and slip: run_stick_slip.cpp. The class: simulation/run.hpp.
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "simulation/run.hpp"
#include "simulation/split_margin.hpp"
#include "ukdyn/dynamics/contact.hpp"

namespace ukdyn::detail {

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
// when that is admissible jointly (stick_jointly, with a split inside every cone required).
// Where no split holds them all, they are decided together as at rest: the least held slips
// while no split holds the rest (stick_jointly without the split, release_unheld), true then
// whether c sticks or slides. Else (rules 1, 2 refused it), or when none stopped with it,
// try_stick(c) alone. Cost: stick_jointly's, twice.
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
  const std::vector<ContactMode> together = mode_;  // (at a stop: allocates, as the split does)
  if (stick_jointly(t, x, true)) return true;
  // no split holds them all: the stop is decided for all of them at once, as at rest
  // (stick_at_rest: they stick, and the least held slips while no split holds the rest), not by
  // c alone, which held a cube stopping on its four corners alone while it turned about it
  // under a control computed with it stuck (u21 01). (true: the stop is resolved, whether c
  // sticks or slides from rest with the others)
  mode_ = together;
  if (stick_jointly(t, x, false)) return true;
  return try_stick(c, t, x, report);
}

// The contacts `rest` at (t, x), closed, rough and at rest (|v_rel| <= eps: at the start of a
// run, or after an impact or release), decided together with the contacts sticking already:
// all of them stick (stick_jointly), and while no split of the holding forces lies inside
// every cone, the one with the lowest minimum-norm margin slips, along its holding force
// (release_unheld) — the largest set that holds, found as a release finds it: a box on two
// corners on a belt accelerating at mu g < A < mu_s g rides with it, though neither corner
// alone holds m A. With fewer than two contacts sticking, or where the joint stick is not
// admissible (try_stick's rules 1, 2), each contact of `rest` in turn sticks when it can alone
// (try_stick), else starts to slide against its impending motion (start_sliding). Cost:
// stick_jointly's, and holding_split's once per contact released.
void Run::stick_at_rest(double t, double* x, const std::vector<std::size_t>& rest) {
  modes_before_ = mode_;
  for (std::size_t c : rest) mode_[c] = ContactMode::kSticking;
  if (sticking_contacts() >= 2 && stick_jointly(t, x, false)) return;
  mode_ = modes_before_;
  apply_contact_modes();
  for (std::size_t c : rest) {
    if (!try_stick(c, t, x)) start_sliding(c, t, x);
  }
}

// The contacts sticking in mode_ and not in modes_before_ stick at (t, x) together with those
// sticking already, when try_stick's rules hold for all of them jointly: the velocity
// projection onto all their stick rows removes at most the largest of their allowances (1),
// and the constraints with all the stick rows have a solution (2); then, with `split`, some
// split of the holding forces lies inside every sticking contact's cone (holding_split, (3));
// without, the contacts that no split holds slip (release_unheld). x then takes the projected
// velocities; else mode_ is modes_before_ again, x unchanged, and false. Cost: one projection
// and two evaluations, and holding_split's.
bool Run::stick_jointly(double t, double* x, bool split) {
  const auto& contacts = sys_.friction_contacts();
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
                 sticking_contacts() > 0 && (!split || holding_split(t) >= 0);
  }
  if (!admissible) {
    mode_ = modes_before_;
    apply_contact_modes();
    return false;
  }
  if (rv.iterations > 0) ++traj_.stats.projections;
  note_violation(0.0, rv.violation);
  std::copy(trial_.begin(), trial_.end(), x);
  for (std::size_t o = 0; o < contacts.size(); ++o) {
    if (mode_[o] != ContactMode::kSticking || modes_before_[o] == ContactMode::kSticking) continue;
    set_slip_hint(o, VectorXd());
    ws_.slip_hint_held[std::size_t(contacts[o].force)] = 0;
  }
  if (!split) release_unheld(t, x, false);
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
  // (whether a split holds is all the sign needs: no search for the least change)
  const int split = holding_split(t, nullptr, false);
  if (split > 0) return stick_margin_here(c, t);
  const double lowest = std::max(std::abs(split_lowest_), std::numeric_limits<double>::min());
  group_t_ = t;
  group_x_.assign(x, x + 2 * n_);
  group_margin_ = split == 0 ? lowest : -lowest;
  return group_margin_;
}

// A unilateral contact of a rigid body held on several rough contacts is statically
// indeterminate: the minimum-norm split of the holding forces, the evaluation's multipliers,
// depends on how the rows are written and on the units (a ladder stopped on a rough wall and
// floor: its wall pushed with 31 N in SI and pulled with −22.8 N in mm, g, ms, was released
// there and bounced 158 times). Its release is the friction's: the instant no split holds.
bool Run::holds_pushing(Index k, double t, const double* x) {
  if (sticking_contacts() < 2) return false;
  const auto& contacts = sys_.friction_contacts();
  const auto stuck_on_k = [&](std::size_t c) {
    return contacts[c].normal_constraint == k && mode_[c] == ContactMode::kSticking;
  };
  std::size_t c = 0;
  while (c < contacts.size() && !stuck_on_k(c)) ++c;
  if (c == contacts.size()) return false;
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  if (forward_dynamics(sys_, ws_, q_, qd_, t) != Status::kOk) return false;
  split_push_only_ = true;
  const int split = holding_split(t, nullptr, false);
  split_push_only_ = false;
  group_t_ = std::numeric_limits<double>::quiet_NaN();  // (group_margin's answer is stale)
  return split >= 0;
}

// After a release at (t, x) (of contact `first`, or none): while the contacts still sticking
// cannot be held by any split of their holding forces (with the released ones' friction now
// acting), the one with the lowest minimum-norm margin slips too, along its holding force (as a
// release; counted as an event when `events`). When two or more were released and none sticks
// any more (a body breaking away from all its contacts), their friction turns against the
// motion they take together (slide_together).
void Run::release_unheld(double t, double* x, bool events, std::size_t first) {
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  released_.clear();
  if (first < mode_.size()) released_.push_back(first);
  while (sticking_contacts() > 0) {
    if (forward_dynamics(sys_, ws_, q_, qd_, t) != Status::kOk) return;
    std::size_t worst = 0;
    if (holding_split(t, &worst) >= 0) return;
    // (along its holding force at the split of largest margin, which the units do not change;
    // the minimum-norm split's where that was not solved; listed with mu_s N of the latter)
    const double margin = stick_margin_here(worst, t);
    const double limit = margin + holding_.norm();
    if (split_exact_) split_holding(split_worst_);
    note_slip(worst, limit - holding_.norm());
    if (events) ++traj_.stats.events;
    mode_[worst] = ContactMode::kSliding;
    set_slip_hint(worst, holding_);
    apply_contact_modes();
    released_.push_back(worst);
  }
  if (released_.size() >= 2) slide_together(t);
}

// the holding force f = f0 + F y* of sticking contact stuck_[i] at the split of largest margin
// (holding_split's y*), mapped by its cone's basis into holding_: the tangent-basis components
// at a contact point (d), the generalized force on the coordinate path (n)
const VectorXd& Run::split_holding(std::size_t i) {
  const SplitCone& cone = split_cones_[i];
  holding_.setZero(std::max(n_, cone.basis.rows()));
  holding_.head(cone.basis.rows()) = cone.basis * (cone.f0 + cone.F * split_y_);
  return holding_;
}

// The contacts released_ slide from rest together at (q_, qd_, t): each one's friction, at its
// full magnitude, against its relative acceleration a_rel without their friction (their
// impending motion, start_sliding's rule taken for all of them at once), not along their
// holding forces: those of the minimum-norm multipliers, whose split depends on how the rows are
// scaled (the units), and along which the table broken away from its legs in mm, g, ms set off
// sideways. (Not iterated to a fixed point hint = −a_rel/|a_rel| with the friction on: on the
// table that iteration oscillates, the friction's sideways part outweighing the push's surplus.)
// Cost: one evaluation.
void Run::slide_together(double t) {
  const auto& contacts = sys_.friction_contacts();
  for (std::size_t c : released_) ws_.nonideal_enabled[std::size_t(contacts[c].force)] = 0;
  const bool evaluated = forward_dynamics(sys_, ws_, q_, qd_, t) == Status::kOk;
  apply_contact_modes();
  if (!evaluated) return;
  for (std::size_t c : released_) {
    relative_acceleration(c, t);
    // (none, to roundoff of the run's accelerations: a control that holds the body cancels the
    // motion; the holding force's direction that release_unheld gave it stays, as for one
    // contact in start_sliding — u17 02, a box on two corners held in place in mm, g, ms)
    if (velocity_.head(contacts[c].size()).norm() > kStillAcceleration * acceleration_scale())
      hint_against_acceleration(c);
  }
}

// Whether the sticking contacts stuck_ (at the evaluation just made, at q_, qd_, t) can hold,
// decided by the largest margin s* of a split inside every cone (max_split_margin, to 1e-12 of
// the forces, on the split space of detail::split_space), and which split then.
// The multipliers Λ = lambda + lambda_nonideal of the active rows are unique only up to the null
// space Z of Aᵀ (redundant rows: the stick rows of contacts on one rigid body); Λ + Z y leaves
// Qc and the motion unchanged. Each sticking contact's holding force f_i and normal force N_i
// are linear in Λ (as stick_margin splits them); the split sought is the y whose change of the
// contact forces (f_i, N_i) has least norm (the metric of the multipliers depends on the units)
// with |f_i| <= mu_static N_i for all i: a small second-order cone programme, solved by outer
// cutting planes — for one tangent the two faces ±f_i <= mu_s N_i (exact), for two the tangent
// planes u·f_i <= mu_s N_i at the directions u of the violating f_i, added until every cone
// holds to 1e-7 of the forces (at most kSplitRounds rounds) — each a quadratic programme
// min ½|y|², G y <= h, solved as the LCP w = (G Gᵀ + δ I) z + h (y = −Gᵀ z) by Siconos
// Numerics (ContactLcp) and polished on its active planes; a plane still violated then means
// an empty polyhedron (no split exists: the outer planes contain the cones); where they find
// none although s* says one exists, the split of largest margin is taken. The sliding
// contacts' normal forces stay as evaluated (their friction is mu N of those). Returns 1 when the
// minimum-norm split holds (y = 0), 0 when another does (its change of the multipliers into split_,
// m), −1 when none does (and when a sticking contact on the coordinate path has a normal constraint
// of several rows, whose N is not linear in Λ: the minimum-norm test then). The lowest minimum-norm
// margin into split_lowest_, its contact into *worst (where s* decided none: the contact least
// held at its maximizer, into split_worst_ too). Without `search`, 0 only says that a split
// exists (split_ stays zero). Cost: the barrier method's Newton steps, an SVD of the active rows
// (m_a × n), one of the contact forces' map, and a few LCPs of 2 to 3 rows per contact; allocates
// (at stops, releases and the samples of runs with several contacts sticking where the minimum-norm
// split fails).
int Run::holding_split(double t, std::size_t* worst, bool search) {
  const auto& contacts = sys_.friction_contacts();
  split_exact_ = false;
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
  // Λ = λ + λ_nonideal; the contacts sliding closed keep their N (their friction is μ N of it)
  lambda_total_ = ws_.lambda;
  if (ws_.lambda_nonideal.size() == m) lambda_total_ += ws_.lambda_nonideal;
  sliding_.clear();
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    if (mode_[c] != ContactMode::kSticking && !separated(c) && !frictionless(c))
      sliding_.push_back(c);
  }
  // whether any split holds: the largest margin s* of a split inside every cone, to roundoff
  // (max_split_margin), with a unilateral contact's N along its push, whatever its minimum-norm
  // sign; where none holds so, with N along Λ (split_space): a stuck contact that pulls in every
  // split is released by its own event, not slid (a cube tipped under control lifts its back
  // corners) — unless only the pushing answer is asked for (holds_pushing). Where none holds,
  // the contact least held at its maximizer y* is the worst (every margin there is >= s*; the
  // contacts bound to s* are those no split can relieve) (the sign only where nothing else is
  // read: no search, no worst contact)
  for (const bool push : {true, false}) {
    if (!split_space(sys_, ws_, lambda_total_, stuck_, sliding_, q_, qd_, t, space_, push))
      return -1;
    split_margin_ = max_split_margin(space_, &split_y_, !search && worst == nullptr);
    if (split_push_only_ || !(split_margin_ <= -kSplitTolerance)) break;
  }
  std::vector<SplitCone>& cones = space_.cones;
  const std::vector<Index>& row_of = space_.row_of;
  const Index ma = Index(row_of.size()), nz = space_.nz;
  const double scale = space_.scale;
  split_null_ = space_.null;
  if (!std::isnan(split_margin_)) {
    split_exact_ = true;
    if (split_margin_ <= -kSplitTolerance) {
      double lowest = std::numeric_limits<double>::infinity();
      for (std::size_t i = 0; i < cones.size(); ++i) {
        const SplitCone& cone = cones[i];
        const double margin =
            cone.mu * (cone.N0 + cone.g.dot(split_y_)) - (cone.f0 + cone.F * split_y_).norm();
        if (margin < lowest) {
          lowest = margin;
          split_worst_ = i;
          if (worst) *worst = stuck_[i];
        }
      }
      return -1;
    }
    if (!search) return 0;
  }
  // the planes G y <= h: N_i >= 0, and faces or tangent planes of the cones
  std::vector<VectorXd> planes;
  std::vector<double> offsets;
  auto add_face = [&](const SplitCone& cone, const VectorXd& u) {
    planes.push_back(cone.F.transpose() * u - cone.mu * cone.g);
    offsets.push_back(cone.mu * cone.N0 - u.dot(cone.f0));
  };
  for (const SplitCone& cone : cones) {
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
    // W + δ I, δ = 1e-8 of its largest diagonal, is positive definite, and G y <= h + δ z: a plane
    // violated by more than the tolerance means an empty polyhedron)
    ContactLcp lcp(rows);
    MatrixXd W = split_G_ * split_G_.transpose();
    W.diagonal().array() += 1e-8 * W.diagonal().maxCoeff();
    if (!lcp.solve(W, split_h_, 1e-9)) break;
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
    if ((split_G_ * y - split_h_).maxCoeff() > 1e-6 * scale) break;
    bool held = true;
    for (const SplitCone& cone : cones) {
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
  // (no least change found, where a split holds: the one of largest margin)
  if (!split_exact_) return -1;
  const VectorXd change = split_null_ * split_y_;
  for (Index i = 0; i < ma; ++i) split_[row_of[std::size_t(i)]] = change[i];
  return 0;
}

}  // namespace ukdyn::detail

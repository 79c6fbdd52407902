// SPDX-License-Identifier: BSD-3-Clause
// The Run's construction and drift control (docs/simulation.md, "Drift control"): each
// constraint's setting (projection or Baumgarte), the projection after every accepted step and of
// the stages, and the checks after a step that stop a run which diverges or leaves its branch at
// a singular configuration (docs/simulation.md, "A run that diverges", "Singular
// configurations"). The class: simulation/run.hpp.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "simulation/run.hpp"

namespace ukdyn::detail {

namespace {

// The solver settings of the integration: the Gauss and virtual-work residuals are not part of a
// trajectory, so they are not computed at every evaluation (the consistency test still is).
SolverOptions integration_options(SolverOptions o) {
  o.compute_residuals = false;
  return o;
}

}  // namespace

// "the constraints … contradict each other …" / "… the mechanism locks up …" (run messages)
std::string describe_conflict(const ConstraintConflict& c, double t) {
  std::string names;
  for (const auto& s : c.names) names += (names.empty() ? "'" : ", '") + s + "'";
  if (c.velocity_level) {
    return "the constraints have no solution near t = " + format(t) +
           ": the mechanism locks up (constraint rows that cannot be satisfied: " + names +
           (c.singular_ratio > 0.0
                ? "; the constraint Jacobian is nearly singular there (sigma_min/sigma_max = " +
                      format(c.singular_ratio) +
                      ") and the velocities it asks for grow without bound)"
                : "; the motion they ask for leaves the directions the constraints allow, "
                  "residual " +
                      format(c.residual) + ")");
  }
  if (c.names.size() == 1) {
    return "the constraint " + names + " cannot be satisfied near t = " + format(t) +
           ": no state satisfies it (the least violation is " + format(c.residual) +
           "; projecting the initial state cannot help: correct or remove it)";
  }
  return "the constraints " + names + " contradict each other near t = " + format(t) +
         ": no state satisfies them together (the least violation is " + format(c.residual) +
         "; projecting the initial state cannot help: correct or remove one of them)";
}

// `finished`: called with the workspace when the run ends (detail::simulate_observed)
Run::Run(const System& sys, const SimulationOptions& o, Trajectory& traj,
         std::function<void(const Workspace&)> finished, Quadratures* quad)
    : finished_(std::move(finished)),
      sys_(sys),
      o_(o),
      ws_(sys, integration_options(o.solver)),
      traj_(traj),
      n_(sys.coordinate_count()),
      q_(n_),
      qd_(n_),
      quad_(quad) {
  // a streamed run records each sample into one_, which the sink receives
  if (o.sample_sink) {
    one_.coordinate_names = traj.coordinate_names;
    one_.constraint_names = traj.constraint_names;
    one_.constraint_rows = traj.constraint_rows;
    one_.constraint_kinds = traj.constraint_kinds;
    one_.unilateral = traj.unilateral;
    one_.n = traj.n;
    one_.m = traj.m;
  }
  // drift control of each constraint
  const Index K = sys.constraint_count();
  projection_ = o.projection;
  projection_.mask.assign(std::size_t(K), 0);
  for (Index k = 0; k < K; ++k) {
    ConstraintDrift d{o.drift, 0.0, 0.0};
    if (auto it = o.drift_per_constraint.find(sys.constraint(k).name());
        it != o.drift_per_constraint.end()) {
      d = it->second;
    }
    if (d.method == DriftControl::kProjection) {
      projection_.mask[std::size_t(k)] = 1;
      projecting_ = projecting_ || sys.constraint(k).kind() != ConstraintKind::kAcceleration;
    } else if (d.method == DriftControl::kBaumgarte) {
      ws_.stabilization[std::size_t(k)] = Stabilization{d.alpha > 0 ? d.alpha : o.baumgarte_alpha,
                                                        d.beta > 0 ? d.beta : o.baumgarte_beta};
    }
  }
}

// projects x = [q; q'; W] in place with the given mask; false when it did not converge
// q_, q'_ ← x projected onto the constraints of p: positions, then velocities (stops at the
// first evaluation that fails: its status)
Status Run::project_into(double t, const double* x, const ProjectionOptions& p,
                         ProjectionResult& rp, ProjectionResult& rv) {
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  rp = project_positions(sys_, ws_, q_, t, p);
  if (rp.status != Status::kOk) return rp.status;
  rv = project_velocities(sys_, ws_, q_, qd_, t, p);
  return rv.status;
}

Status Run::project(double t, double* x, const ProjectionOptions& p, bool& changed) {
  // the cheap test first: each constraint's violation once; within the tolerance (most steps)
  // the projections would measure the same and change nothing. After a step that needed a
  // projection the next one likely does too: then straight to the projections.
  if (!projected_last_) {
    q_ = Eigen::Map<const VectorXd>(x, n_);
    qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
    if (const Violations v = measure_violations(sys_, ws_, q_, qd_, t, p);
        v.finite && v.within_tolerance) {
      note_violation(std::max(v.position, 0.0), std::max(v.velocity, 0.0));
      changed = false;
      return Status::kOk;
    }
  }
  ProjectionResult rp, rv;
  if (const Status s = project_into(t, x, p, rp, rv); s != Status::kOk) return s;
  note_violation(rp.violation, rv.violation);
  changed = rp.iterations > 0 || rv.iterations > 0;
  projected_last_ = changed;
  if (changed) {
    ++traj_.stats.projections;
    Eigen::Map<VectorXd>(x, n_) = q_;
    Eigen::Map<VectorXd>(x + n_, n_) = qd_;
  }
  if (!rp.converged || !rv.converged) {
    failure_ =
        "drift control: the projection onto the constraints did not converge at t = " + format(t) +
        " (position violation " + format(rp.violation) + ", velocity violation " +
        format(rv.violation) + " after " + format_number(rp.iterations) + " and " +
        format_number(rv.iterations) + " iterations)";
    // the cause, when it is that no state near satisfies the constraints (lock-up)
    const ConstraintConflict c = find_constraint_conflict(sys_, ws_, q_, qd_, t, p.tolerance);
    if (c.found) failure_ = describe_conflict(c, t) + "; " + failure_;
    return Status::kProjectionFailed;
  }
  return Status::kOk;
}

// removes from a step's error estimate err the components normal to the projected
// constraints at the state x the step reached: what project() after the step removes
bool Run::project_error(double t, const double* x, double* err) {
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  Eigen::Map<VectorXd> dq(err, n_), dqd(err + n_, n_);
  return remove_normal_components(sys_, ws_, q_, qd_, t, projection_, dq, dqd) == Status::kOk;
}

// projects a stage state x in place onto the projected constraints; false when it failed
bool Run::project_stage(double t, double* x) {
  ProjectionResult rp, rv;
  if (project_into(t, x, projection_, rp, rv) != Status::kOk || !rp.converged || !rv.converged) {
    return false;
  }
  Eigen::Map<VectorXd>(x, n_) = q_;
  Eigen::Map<VectorXd>(x + n_, n_) = qd_;
  return true;
}

// drift control after an accepted step; then a requested stop (see stop_requested)
Status Run::after_step(double t, double* x, bool& changed) {
  changed = false;
  if (o_.progress) report_progress(t);
  if (projecting_) {
    if (const Status s = project(t, x, projection_, changed); s != Status::kOk) return s;
  }
  if (diverges(t, x) || leaves_branch(t, x)) return Status::kIntegratorFailure;
  if (!stop_requested()) return Status::kOk;
  // a sample inside the step just taken that is not recorded yet (the fixed-step methods and
  // BDF emit the samples of a step after this call): the run stops there, in record(), so that
  // every sample before the stop is the uninterrupted run's. Otherwise it stops here and the
  // driver records the state at t. (The count bounds the wait, should a sample never come.)
  if (sample_due(t) && ++stop_wait_ < kMaxStopWait) return Status::kOk;
  return Status::kInterrupted;
}

// The motion grows without bound when the kinetic energy T at (t, x) exceeds kDivergence
// times the model's energy scale (T + |V| at the first sample, or at the first one after it
// with energy when it has none). Then `why` says so (with the fastest coordinate) and this
// returns true. Cost: one evaluation.
bool Run::diverged(double t, const double* x, std::string& why) {
  if (!(energy_scale_ > 0.0)) return false;
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  const Status s = forward_dynamics(sys_, ws_, q_, qd_, t);
  if (s == Status::kNonFiniteInput || s == Status::kMassNotSymmetric ||
      s == Status::kMassNotPositiveDefinite) {
    return false;
  }
  // (speeds that grow as the constraints lose rank — a driven mechanism locking up, a dead
  // centre — are a singular configuration's, for the collapse diagnosis to name; NaN, the
  // sparse engine's, is no sign either way)
  if (ws_.rank_margin < kDivergenceRankMargin) return false;
  // (a controlled run's auxiliary integrals, "ukdyn.control.*", are no coordinates of the
  // model: their rates, the control's power and effort, are left out)
  Index fastest = 0;
  for (Index i = 0; i < n_; ++i) {
    if (sys_.coordinate_names()[std::size_t(i)].rfind("ukdyn.", 0) == 0) {
      qd_[i] = 0.0;
    } else if (std::abs(qd_[i]) > std::abs(qd_[fastest])) {
      fastest = i;
    }
  }
  const double T = detail::kinetic_energy(ws_, qd_);
  if (!(T > kDivergence * energy_scale_)) return false;
  why = "the motion grows without bound: at t = " + format(t) + " the kinetic energy is " +
        format(T) + ", " + format(T / energy_scale_) + " times the model's energy scale (" +
        format(energy_scale_) + ", T + |V| at the start), and '" +
        sys_.coordinate_names()[std::size_t(fastest)] + "' moves at " + format(qd_[fastest]) +
        " per unit time: the model's motion diverges (an unstable feedback or control "
        "law, a force that feeds energy in)";
  return true;
}

// After an accepted step to (t, x): true when the run diverges (see diverged) while its steps
// are so short that the rest of the run would take more than max_steps of them — a crawl
// that would otherwise go on for hours. The energy is evaluated only at such steps.
bool Run::diverges(double t, const double* x) {
  const double h = t - last_step_end_;
  last_step_end_ = t;
  if (!(h > 0.0) || !((o_.t_end - t) / h > double(o_.max_steps))) {
    crawling_steps_ = 0;
    return false;
  }
  std::string why;
  if (!diverged(t, x, why)) {
    crawling_steps_ = 0;
    return false;
  }
  if (++crawling_steps_ < kDivergentSteps) return false;
  failure_ = why + "; its steps (" + format(h) +
             ") are too short for the rest of the run to fit "
             "in max_steps = " +
             format_number(o_.max_steps) + ", so the run stops here rather than crawl on";
  return true;
}

// After an accepted step to (t, x): true (with failure_ set) when the motion has left its
// branch at a singular configuration it is passing. A passage runs from the first step end
// whose last evaluation had a rank margin below kSingularMargin to the first one back above
// twice that. Across it q' changes by at most its duration times the accelerations, which are
// smooth along a branch: a change of q' (in the M-norm) beyond kBranchFactor times the duration
// times the larger M-norm of q'' at its two ends — and beyond 1e-3 of |q'| — is a jump onto
// another branch (one of the twin arms reversed: the mirror branch), which no status ok may
// hide. A slow passage may never end (the twin arms swinging 0.005 rad about their dead
// centre): under the adaptive methods, whose steps can close in on the pose, each step is also
// judged once the margin has fallen an order below its entry's — against the accelerations at
// the entry (the ones inside are a roundoff off the branch times the inverse margin), times
// kStepFactor, on the part of the change that turns q' rather than stretches it (the speeds of
// a driven mechanism that locks up grow along their direction; a jump onto the mirror branch
// reverses an arm at the same speed). Costs an evaluation at a passage's two ends (in a
// workspace of its own, so that the run's is left as the integrator left it) and two M-norms
// for each step judged inside; nothing elsewhere (Algorithm::kTextbook, whose margin is NaN, is
// not checked).
bool Run::leaves_branch(double t, const double* x) {
  const double margin = ws_.rank_margin;
  if (!in_pose_ && !(margin < detail::kSingularMargin)) return false;
  const Eigen::Map<const VectorXd> qd(x + n_, n_);
  const bool leaving = in_pose_ && margin >= 2.0 * detail::kSingularMargin;
  double t_from = step_t_, change = 0.0, bound = 0.0, speed = 0.0;
  // the change of q' from v0 (M-norm), and q's speed at v0
  const auto changed = [&](const Workspace& w, const VectorXd& v0) {
    speed = std::sqrt(2.0 * detail::kinetic_energy(w, v0));
    change_ = v0 - qd;
    change = std::sqrt(2.0 * detail::kinetic_energy(w, change_));
  };
  if (in_pose_ && !leaving) {
    // a step inside the passage: judged (without an evaluation: the norms in the run's
    // workspace, its last evaluation within this step) where the margin is an order below the
    // entry's, under an adaptive method; (BDF reports converged attempts: after a rejected one,
    // t can go back; not judged then)
    const Integrator method = progress_.integrator;
    const bool adaptive =
        method == Integrator::kDopri5 || method == Integrator::kRKF78 || method == Integrator::kBDF;
    if (!adaptive || !(margin < 0.1 * pose_margin_)) return false;
    if (!(t > step_t_)) {
      step_t_ = t;
      step_velocity_ = qd;
      return false;
    }
    changed(ws_, step_velocity_);
    change_ = qd;
    const double stretch = std::sqrt(2.0 * detail::kinetic_energy(ws_, change_)) - speed;
    change = std::sqrt(std::max(0.0, change * change - stretch * stretch));
    bound = kStepFactor * pose_acceleration_ * (t - step_t_);
    step_t_ = t;
    step_velocity_ = qd;
  } else {
    // a passage's entry or exit: the accelerations there, in the branch check's workspace
    q_ = Eigen::Map<const VectorXd>(x, n_);
    qd_ = qd;
    Workspace& w = branch_workspace();
    if (forward_dynamics(sys_, w, q_, qd_, t) != Status::kOk) return false;
    const double acceleration = std::sqrt(2.0 * detail::kinetic_energy(w, w.qdd));
    if (!in_pose_) {
      in_pose_ = true;
      pose_t_ = step_t_ = t;
      pose_margin_ = margin;
      pose_acceleration_ = acceleration;
      pose_velocity_ = step_velocity_ = qd_;
      return false;
    }
    in_pose_ = false;
    if (!(t > pose_t_)) return false;
    t_from = pose_t_;
    changed(w, pose_velocity_);
    bound = kBranchFactor * (t - pose_t_) * std::max(acceleration, pose_acceleration_);
  }
  if (!(change > bound && change > 1e-3 * speed)) return false;
  failure_ = "the motion left its branch at the singular configuration passed between t = " +
             format(t_from) + " and " + format(t) +
             " (the constraints nearly lose rank there: a dead centre or a branch point): "
             "the velocity changed by " +
             format(change) + " (in the M-norm; " + format(change / speed) +
             " of the speed) where the accelerations allow " + format(bound) +
             ", a jump onto another branch of the mechanism. Try: a tighter rtol, another "
             "integrator, or a fixed step (integrator: rk4, step: 1e-4) across the pose";
  return true;
}

// the branch check's own workspace, in the run's modes (contacts held open or closed, stick or
// slip, drift control, scales): its evaluations at step ends leave the run's workspace as the
// integrator and the events left it. Copies of equal sizes: no allocation. Made at its first
// use, and then handed to `started_` (a controlled plant's control mirrors its modes).
Workspace& Run::branch_workspace() {
  if (!branch_ws_) {
    branch_ws_ = std::make_unique<Workspace>(sys_, ws_.options());
    if (started_) started_(*branch_ws_);
  }
  Workspace& w = *branch_ws_;
  w.activity_override = ws_.activity_override;
  w.stabilization = ws_.stabilization;
  w.nonideal_enabled = ws_.nonideal_enabled;
  w.slip_hint = ws_.slip_hint;
  w.slip_hint_held = ws_.slip_hint_held;
  w.sliding = ws_.sliding;
  w.phi_scale = ws_.phi_scale;
  w.phi_dot_scale = ws_.phi_dot_scale;
  w.length_scale = ws_.length_scale;
  w.speed_scale = ws_.speed_scale;
  w.rate_unit = ws_.rate_unit;
  w.energy_unit = ws_.energy_unit;
  return w;
}

}  // namespace ukdyn::detail

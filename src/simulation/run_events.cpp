// SPDX-License-Identifier: BSD-3-Clause
// Event location inside a step (SegmentHooks::find_event): the first stop, release or passage of
// a Coulomb contact (its modes: run_stick_slip.cpp), or the first switch of a non-smooth function
// (System::switch_count), located by bisection on the step's dense output; the sides of the
// switching functions, and the chattering test at a switch (docs/simulation.md, "Switch events").
// The class: simulation/run.hpp.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "simulation/run.hpp"

namespace ukdyn::detail {

void Run::screen_sticking(double t, const double* x) {
  const auto& contacts = sys_.friction_contacts();
  if (mode_.size() != contacts.size()) return;  // (before the initial modes)
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    if (mode_[c] != ContactMode::kSticking || frictionless(c) || separated(c)) continue;
    // (stick_margin_here reads the evaluation just made, and the stage's q, q')
    q_ = Eigen::Map<const VectorXd>(x, n_);
    qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
    if (stick_margin_here(c, t) < 0.0 && !(stick_screened_[c] <= t)) stick_screened_[c] = t;
  }
}

double Run::screened_slip(std::size_t c, double t0, const double* x0, double t1,
                          const detail::SegmentHooks::Dense& dense) {
  // a stage of the step saw the holding force leave the cone (a force pulse within one long
  // step of a body at rest, which the state and so the step size does not see): confirmed at
  // its time on the dense output (a stage state is not the solution), with every contact
  // sticking together (group_margin), and located from t0
  const double ts = stick_screened_[c];
  if (!(ts >= t0 && ts <= t1)) return std::numeric_limits<double>::quiet_NaN();
  auto margin = [&](double t, const double* x) { return group_margin(c, t, x); };
  dense(ts, trial_.data());
  if (margin(ts, trial_.data()) > 0.0) return std::numeric_limits<double>::quiet_NaN();
  return margin(t0, x0) > 0.0 ? locate(t0, ts, trial_.data(), dense, margin) : t0;
}

void Run::arm_stops(double t, const double* x) {
  const auto& contacts = sys_.friction_contacts();
  if (mode_.size() != contacts.size()) return;  // (before the initial modes)
  std::fill(stop_armed_.begin(), stop_armed_.end(), 0);
  if (!screens_stops_) return;
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    if (mode_[c] != ContactMode::kSliding || frictionless(c) || separated(c)) continue;
    arm_stop(c, t, x, 100.0 * contacts[c].eps);
  }
}

void Run::arm_stop(std::size_t c, double t, const double* x, double v_stop) {
  stop_armed_[c] = 0;
  stop_seen_[c] = 0;
  const Index k = relative_velocity(c, t, x, velocity_);
  const double speed = velocity_.head(k).norm();
  if (!(speed > v_stop)) return;
  stop_direction_.col(Index(c)).head(k) = velocity_.head(k) / speed;
  stop_armed_[c] = 1;
}

double Run::locate_stop(std::size_t c, Index k, double t0, double t1, const double* x1,
                        const detail::SegmentHooks::Dense& dense, double v_stop) {
  // (a stage of the step, or of an attempt from t0 that was rejected, at the stop; then the
  // bisection's steps screened along the step's start direction, the one its test reads)
  const bool seen = stop_armed_[c] && stop_seen_[c];
  stop_direction_.col(Index(c)).head(k) = direction_.head(k);
  stop_armed_[c] = 1;
  stop_seen_[c] = 0;
  // the speed along the direction less v_stop at x, and at most 0 when a stage of the step to t
  // (the dense output: a step of the method) had that speed at or below v_stop: a stage past
  // the stop sees the friction reversed, and the step's end can lie before the stop again
  auto ahead = [&](double t, const double* x) {
    relative_velocity(c, t, x, velocity_);
    const double g = velocity_.head(k).dot(direction_.head(k)) - v_stop;
    const bool stage = stop_seen_[c] != 0;
    stop_seen_[c] = 0;
    return stage ? std::min(g, 0.0) : g;
  };
  double te = std::numeric_limits<double>::quiet_NaN();
  if (!(ahead(t1, x1) > 0.0)) {
    te = locate(t0, t1, nullptr, dense, ahead);
  } else if (seen) {
    // the end before the stop, a stage past it: confirmed by the step to t1 again (a rejected
    // attempt's stage is not this step's), its stages screened
    dense(t1, event_x_.data());
    if (!(ahead(t1, event_x_.data()) > 0.0)) te = locate(t0, t1, nullptr, dense, ahead);
  }
  // no stop: the next step's stages are screened along the direction at its start
  if (std::isnan(te)) arm_stop(c, t1, x1, v_stop);
  return te;
}

// the first switch of a contact inside [t0, t1] (see SegmentHooks::find_event)
double Run::find_event(double t0, const double* x0, double t1, const double* x1,
                       const detail::SegmentHooks::Dense& dense) {
  const auto& contacts = sys_.friction_contacts();
  double first = std::numeric_limits<double>::quiet_NaN();
  switching_ = -1;
  entered_ = false;
  Index handover = -1;  // the contact whose passage rkf78 hands to dopri5 (see hands_over)
  // the rank margin at (or within the step's last stages before) t1: the step's last evaluation
  const double margin = ws_.rank_margin;
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    if (frictionless(c) || separated(c)) continue;
    double te = std::numeric_limits<double>::quiet_NaN();
    switch (mode_[c]) {
      case ContactMode::kSticking:
        // the holding force reaches mu_static N: mu_static N − |holding force| falls to zero
        // (with other contacts sticking: no split of the holding forces fits every cone)
        // (at the step's end as before; else what the stages saw: screened_slip)
        te = locate(t0, t1, x1, dense,
                    [&](double t, const double* x) { return group_margin(c, t, x); });
        if (std::isnan(te)) te = screened_slip(c, t0, x0, t1, dense);
        break;
      case ContactMode::kSliding: {
        // the sliding speed along the step's initial direction falls to v_stop = 100 eps: the
        // contact stops, or would have to, whether its velocity would reverse or decay to
        // rest (where the regularized law would only creep); the stop is then early by
        // v_stop / deceleration, the position off by v_stop² / (2 deceleration)
        const double v_stop = 100.0 * contacts[c].eps;
        const Index k = relative_velocity(c, t0, x0, direction_);
        const double speed = direction_.head(k).norm();
        if (speed <= v_stop) continue;
        // sliding clearly: the start direction of a release or passage has served (on a
        // curved path it would no longer oppose the motion when the contact next slows down)
        if (ws_.slip_hint.col(contacts[c].force).squaredNorm() > 0.0) set_slip_hint(c, VectorXd());
        direction_.head(k) /= speed;
        // near a rank drop: rkf78 hands the run to dopri5 before the step (see hands_over);
        // still sliding clearly at t1: carried through (see carry_through)
        if (margin < detail::kSingularMargin && progress_.integrator == Integrator::kRKF78) {
          te = t0;
          handover = Index(c);
          break;
        }
        if (margin < detail::kSingularMargin && carry_through(c, k, t1, x1, v_stop)) {
          continue;
        }
        te = screens_stops_ ? locate_stop(c, k, t0, t1, x1, dense, v_stop)
                            : locate(t0, t1, x1, dense, [&](double t, const double* x) {
                                relative_velocity(c, t, x, velocity_);
                                return velocity_.head(k).dot(direction_.head(k)) - v_stop;
                              });
        // (a kinematic passage at a rank drop: no restart there)
        if (!std::isnan(te) && passes_at_rank_drop(c, te, dense)) {
          if (progress_.integrator == Integrator::kRKF78) {
            te = t0;
            handover = Index(c);
            break;
          }
          te = std::numeric_limits<double>::quiet_NaN();
          ++traj_.stats.stick_refusals;
        }
        break;
      }
      case ContactMode::kPassing: {
        // a contact that could not stick: the zero of v_rel along its direction then
        const Index k = contacts[c].size();
        auto along = [&](double t, const double* x) {
          relative_velocity(c, t, x, velocity_);
          return velocity_.head(k).dot(passing_.col(Index(c)).head(k));
        };
        // carried through a dead centre: the friction turns at the end of the step that
        // crossed v_rel = 0 (switch_contact), outside the dead centre's neighbourhood
        // (or out of the neighbourhood again, where the law takes over)
        if (held(c)) {
          if (along(t1, x1) <= 0.0) {
            te = carried_past(locate(t0, t1, x1, dense, along), t1, x1, dense);
          } else if (margin >= 2.0 * detail::kSingularMargin) {
            te = t1;
          }
          break;
        }
        if (along(t0, x0) <= 0.0) {
          mode_[c] = ContactMode::kSliding;  // passed already (within rounding of the start)
          continue;
        }
        te = locate(t0, t1, x1, dense, along);
        break;
      }
    }
    if (!std::isnan(te) && (std::isnan(first) || te < first)) {
      first = te;
      switching_ = Index(c);
    }
  }
  // (the stages up to t1 are screened; a later one — of a rejected longer step — waits)
  for (double& s : stick_screened_) {
    if (!(s > t1)) s = std::numeric_limits<double>::quiet_NaN();
  }
  hands_over_ = handover >= 0 && switching_ == handover;
  // the first sign change of a switching function, when it comes before the contacts' event
  switch_event_ = false;
  // (no event: the step may end inside a dead centre's neighbourhood, see entered_dead_centre)
  // (a step near a rank drop that jumped onto another branch: bridged from its start instead,
  // see entered_dead_centre)
  const bool near = near_dead_centre();
  if (near && jumps_branch(t0, x0, t1, x1)) {
    entered_ = true;
    hands_over_ = false;
    return t0;
  }
  if (!locates_switches()) {
    if (std::isnan(first) && near) {
      const double te = enters_dead_centre(t0, x0, t1, x1, dense);
      if ((entered_ = !std::isnan(te))) return te;
    }
    return first;
  }
  // a crawl after a switch: kSwitchBurst accepted steps — those into a switch and at one
  // included — since the switch that opened the window, within kSwitchBurstSpan of the run (a
  // sliding mode: every step crosses the switch again, or the step size control rejects it;
  // counting only the steps between switches missed a sliding mode entered from rest, which
  // switched every few steps and crawled for 10⁷ steps)
  if (!std::isnan(window_start_) && ++steps_since_switch_ >= kSwitchBurst) {
    if (t1 - window_start_ <= kSwitchBurstSpan * (o_.t_end - o_.t_start)) {
      crawl_ = true;
      switch_event_ = true;
      return t1;
    }
    window_start_ = std::numeric_limits<double>::quiet_NaN();
    steps_since_switch_ = 0;
  }
  double hi = t1;
  double ts = find_switch(t0, x0, t1, x1, dense, hi);
  approach_ = false;
  if (!std::isnan(ts) && (std::isnan(first) || ts < first)) {
    switch_event_ = true;
    hands_over_ = false;
    // the approach: the restart state at ts comes from one step [t0, ts] whose last stages
    // lie at ts, within their own error of the switch, on either side (rkf78's end-node
    // stages are not exact even for a quadratic motion: an error h·b·jump). So the run first
    // restarts 3/4 of the way, where every stage is clearly on the old side, and finds the
    // switch again from there, until the step to it is below kSwitchApproach (|t| ≥ 1)
    // (not at a dead centre, where the constraints nearly lose rank: restarts closing in on
    // the pose can take the mirror branch; the restart at ts is bridged past the pose
    // instead, see bridge_dead_centre)
    bool at_rank_drop = false;
    if (ts - t0 > kSwitchApproach * std::max(1.0, std::abs(ts))) {
      dense(ts, event_x_.data());
      const double margin_ts = rank_margin_at(ts, event_x_.data());
      at_rank_drop = margin_ts < kCarriedMargin;
      // (near a dead centre under dopri5, rkf78 or BDF: the restart just before the switch is
      // bridged past the pose, see entered_dead_centre; the approach's restarts and the nudge past
      // the switch there took the mirror branch; once from a step's start)
      if (!at_rank_drop && margin_ts < kBridgedSwitchMargin && near && t0 != entry_failed_) {
        entry_failed_ = ts;
        entered_ = true;
        switch_event_ = false;
        return ts;
      }
      if (!at_rank_drop) {
        approach_ = true;
        return ts - 0.25 * (ts - t0);
      }
      // (a switch at the pose in a step that ends inside its neighbourhood, under an adaptive
      // method: the run restarts at the step's start, outside it, bridged past the pose — a
      // restart at the pose took the mirror branch; once from there)
      if (at_rank_drop && near && t0 != entry_failed_ && rank_margin_at(t1, x1) < kCarriedMargin) {
        const double m0 = rank_margin_at(t0, x0);
        if (m0 >= kCarriedMargin && m0 < detail::kSingularMargin) {
          entry_failed_ = t0;
          entered_ = true;
          switch_event_ = false;
          return t0;
        }
      }
      // the step crossed the pose to where the margin is back: the switch takes effect at its
      // end (the step's stages on both sides, its error accepted: at a dead centre the
      // switch's lever on the motion vanishes), no restart inside the pose's neighbourhood
      if (rank_margin_at(t1, x1) >= kCarriedMargin) ts = hi = t1;
    }
    switch_width_ = hi - ts;
    // (a switch opens the crawl test's window, or keeps the one a burst opened within the span)
    if (!(ts - window_start_ <= kSwitchBurstSpan * (o_.t_end - o_.t_start))) {
      window_start_ = ts;
      steps_since_switch_ = 0;
    }
    // the functions across their side just past the switch take their new side (the run
    // restarts just before it, at ts: every stage of the step to ts on the old side)
    dense(hi, event_x_.data());
    evaluate_switches(hi, event_x_.data());
    double furthest = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < crossing_count_; ++k) {
      const std::size_t i = crossing_[k];
      const double m = double(side_[i]) * g_[Index(i)];
      if (m < furthest) {
        furthest = m;
        switch_fired_ = i;
      }
      const bool flip = m <= 0.0 || landed_ || (at_rank_drop && hi == t1);
      flipped_[i] = flip ? 1 : 0;
      if (flip) side_[i] = static_cast<signed char>(-side_[i]);
    }
    return ts;
  }
  if (std::isnan(first)) {
    // no event: a function that was 0 takes the side where the step leaves it
    for (Index i = 0; i < g1_.size(); ++i) {
      if (side_[std::size_t(i)] == 0 && g1_[i] != 0.0) side_[std::size_t(i)] = g1_[i] > 0 ? 1 : -1;
    }
    if (near) {
      const double te = enters_dead_centre(t0, x0, t1, x1, dense);
      if ((entered_ = !std::isnan(te))) return te;
    }
  }
  return first;
}

// find_event: the step from (t0, x0) to (t1, x1) is near a rank drop — the last evaluation's
// rank margin, or the last step end's, below kSingularMargin, or a rank dropped — under dopri5,
// rkf78 or BDF in a run that bridges entries (see run.hpp)
bool Run::near_dead_centre() {
  const Integrator method = progress_.integrator;
  if (!bridging_entries_ ||
      (method != Integrator::kDopri5 && method != Integrator::kRKF78 &&
       method != Integrator::kBDF) ||
      std::isnan(ws_.rank_margin)) {
    return false;
  }
  if (ws_.rank_margin >= detail::kSingularMargin && ws_.rank == ws_.active_rows &&
      !(entry_margin_ < detail::kSingularMargin)) {
    entry_armed_ = true;
    return false;
  }
  return true;
}

// find_event: the step from (t0, x0) to (t1, x1), near a rank drop, crossed the pose onto
// another branch: its change of q' that turns it (a jump onto the mirror branch reverses an
// arm) beyond kStepFactor times the accelerations at its start (the test of leaves_branch),
// where the rank margin is below kSingularMargin; the run is bridged from t0, once from there
// (a step that jumps again from the bridge's start is left to leaves_branch). Costs one
// evaluation.
bool Run::jumps_branch(double t0, const double* x0, double t1, const double* x1) {
  if (t0 == entry_failed_) return false;
  q_ = Eigen::Map<const VectorXd>(x0, n_);
  qd_ = Eigen::Map<const VectorXd>(x0 + n_, n_);
  Workspace& w = branch_workspace();
  if (forward_dynamics(sys_, w, q_, qd_, t0) != Status::kOk ||
      !(w.rank_margin < detail::kSingularMargin) || w.rank < w.active_rows) {
    return false;
  }
  const double acceleration = std::sqrt(2.0 * detail::kinetic_energy(w, w.qdd));
  const double speed = std::sqrt(2.0 * detail::kinetic_energy(w, qd_));
  change_ = Eigen::Map<const VectorXd>(x1 + n_, n_) - qd_;
  double change = std::sqrt(2.0 * detail::kinetic_energy(w, change_));
  // (the part that turns q' rather than stretches it: the speeds of a driven mechanism that
  // locks up grow along their direction, as in leaves_branch)
  change_ = Eigen::Map<const VectorXd>(x1 + n_, n_);
  const double stretch = std::sqrt(2.0 * detail::kinetic_energy(w, change_)) - speed;
  change = std::sqrt(std::max(0.0, change * change - stretch * stretch));
  if (!(change > kStepFactor * acceleration * (t1 - t0) && change > 1e-3 * speed)) return false;
  entry_failed_ = t0;
  return true;
}

// find_event: the step from (t0, x0) to (t1, x1), near a rank drop, enters a dead centre's
// neighbourhood (the rank margin below kCarriedMargin) from outside it. Under dopri5 and BDF: a
// step that ends inside it, bridged from t1 (returned). Under rkf78 also a step that passes
// through it and ends outside (the margin at kCrossingSamples − 1 points of the dense output
// below kCarriedMargin, or dipping there below kCrossingRestartMargin and half the ends'):
// either is bridged from outside — from the last point checked whose margin is at least
// kCrossingRestartMargin, else from t0 (returned), once from there. rkf78's steps cross the
// pose whole, their 13 stages on both sides (+7.9e-9 J at one passage of the twin arms' slow
// swing), or end inside, where the state is fixed only to the position tolerance over the
// margin squared (a bridge from θ = 1.6e-5 rad took −6.6e-9 J). NaN: no entry. Costs one
// evaluation; under rkf78 kCrossingSamples more, and its dense output at kCrossingSamples − 1
// points (a step of the method each).
double Run::enters_dead_centre(double t0, const double* x0, double t1, const double* x1,
                               const detail::SegmentHooks::Dense& dense) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double margin = entry_margin_ = rank_margin_at(t1, x1);
  if (progress_.integrator == Integrator::kRKF78 && t0 != entry_failed_ && !std::isnan(margin)) {
    // (inside at a point checked, or a dip between the step's ends to below the restart's
    // margin: the pose passed between two points)
    const double m0 = rank_margin_at(t0, x0);
    double outside = t0;  // the last point checked with the margin of a restart
    double lowest = std::numeric_limits<double>::infinity();
    for (int k = 1; lowest >= kCarriedMargin && k < kCrossingSamples; ++k) {
      const double s = t0 + (t1 - t0) * double(k) / double(kCrossingSamples);
      dense(s, event_x_.data());
      const double ms = rank_margin_at(s, event_x_.data());
      lowest = std::min(lowest, ms);
      if (ms >= kCrossingRestartMargin && lowest >= kCrossingRestartMargin) outside = s;
    }
    const bool inside = lowest < kCarriedMargin || margin < kCarriedMargin ||
                        (lowest < kCrossingRestartMargin && lowest < 0.5 * std::min(m0, margin));
    if (inside && (outside > t0 || m0 >= kCarriedMargin)) {
      entry_failed_ = outside;
      return outside;
    }
  }
  if (!(margin < kCarriedMargin)) {
    if (!std::isnan(margin)) entry_armed_ = true;
    return nan;
  }
  if (!entry_armed_) return nan;
  entry_armed_ = false;
  // (its q'' from the step's start, see bridge_dead_centre)
  entry_t0_ = t0;
  std::copy(x0, x0 + entry_x0_.size(), entry_x0_.begin());
  return t1;
}

// after a bridge to (t, x): the functions across their side take the new one (see run.hpp)
std::size_t Run::sides_after_bridge(double t, const double* x) {
  if (!locates_switches()) return 0;
  evaluate_switches(t, x);
  std::size_t flips = 0;
  for (Index i = 0; i < g_.size(); ++i) {
    signed char& side = side_[std::size_t(i)];
    if (double(side) * g_[i] < 0.0) {
      side = static_cast<signed char>(-side);
      ++flips;
    } else if (side == 0 && g_[i] != 0.0) {
      side = g_[i] > 0.0 ? 1 : -1;
    }
  }
  return flips;
}

// true when every function that switched at the last switch event is on its new side at
// (t, x): side_i g_i > 0
bool Run::switch_settled(double t, const double* x) {
  evaluate_switches(t, x);
  for (std::size_t k = 0; k < crossing_count_; ++k) {
    const std::size_t i = crossing_[k];
    if (side_[i] != 0 && double(side_[i]) * g_[Index(i)] <= 0.0 && flipped(i)) return false;
  }
  return true;
}

// each function's side: the sign of g at (t, x) (0: at its switch)
void Run::initial_switch_sides(double t, const double* x) {
  if (!locates_switches()) return;
  evaluate_switches(t, x);
  for (Index i = 0; i < g_.size(); ++i) {
    side_[std::size_t(i)] = static_cast<signed char>(g_[i] > 0.0 ? 1 : g_[i] < 0.0 ? -1 : 0);
    // a function at its switch at the start is as if it had just switched: the crawl test's
    // window opens (a sliding mode entered from rest, x'' = −sign(x') − 0.5 from x' = 0,
    // ends every step on its start side, the crossings in between unseen, and crawls)
    if (side_[std::size_t(i)] == 0 && std::isnan(window_start_)) {
      window_start_ = t;
      switch_fired_ = std::size_t(i);
    }
  }
}

// The time just before the first switch in (t0, t1], or NaN: the functions whose value at t1
// lies across their side (side_i g_i(t1) < 0) are the crossing ones, and the switch is
// located by bisection on min over them of side_i g_i on the dense output: the bracket
// [s, hi] of width 1e-14 |t|, s on the old side (returned: a restart there takes every stage
// on the old side; from hi the last stage of rk4 would see the new one), hi past it. A step
// that starts across the side already (a restart that the dynamics turns straight back: a
// sliding mode) switches back at t0. (A function that leaves its side and comes back within
// one step is not seen.)
double Run::find_switch(double t0, const double* x0, double t1, const double* x1,
                        const detail::SegmentHooks::Dense& dense, double& hi) {
  evaluate_switches(t1, x1);
  g1_ = g_;
  crossing_count_ = 0;
  landed_ = false;
  for (Index i = 0; i < g_.size(); ++i) {
    if (double(side_[std::size_t(i)]) * g_[i] < 0.0) crossing_[crossing_count_++] = std::size_t(i);
  }
  if (crossing_count_ == 0) {
    // a step that lands on a switch (an output time there: g(t1) within 1e-12 of g(t0) of 0,
    // on the old side) took its last stages at the tie, on either side: a switch at t1
    evaluate_switches(t0, x0);
    for (Index i = 0; i < g_.size(); ++i) {
      const double s0 = double(side_[std::size_t(i)]) * g_[i],
                   s1 = double(side_[std::size_t(i)]) * g1_[i];
      if (s0 > 0.0 && s1 >= 0.0 && s1 <= 1e-12 * s0) crossing_[crossing_count_++] = std::size_t(i);
    }
    if (crossing_count_ == 0) return std::numeric_limits<double>::quiet_NaN();
    landed_ = true;
    hi = t1;
    return t1;
  }
  auto margin = [&](double t, const double* x) {
    evaluate_switches(t, x);
    double m = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < crossing_count_; ++k) {
      const std::size_t i = crossing_[k];
      m = std::min(m, double(side_[i]) * g_[Index(i)]);
    }
    return m;
  };
  if (margin(t0, x0) <= 0.0) {
    hi = t0;
    return t0;
  }
  double lo = t0;
  hi = locate(t0, t1, x1, dense, margin, &lo);
  return lo;
}

// After a switch event at t (or the crawl find_event reports): true when the run chatters —
// the last kSwitchBurst switch events fell within kSwitchBurstSpan of the run's time span, or
// the steps after one crawled (a sliding mode: the dynamics turns the motion back at the switch
// from either side, and no step crosses it); `message` then says so.
bool Run::switch_chatters(double t, std::string& message) {
  const double span = kSwitchBurstSpan * (o_.t_end - o_.t_start);
  const std::string& fired = sys_.switch_names()[switch_fired_];
  const std::string name = "'" + fired + "'";
  const std::string advice =
      " (chattering: a sliding mode, where the dynamics turns the motion back at the switch "
      "from either side, and no step can cross it). Regularize the switch (tanh(v/eps) for "
      "sign(v)), or set switch_events to false to step across it unlocated";
  // a switch of a constraint (a model file names it "g in the constraint 'NAME'") is a kink of
  // it, where the velocity would have to jump: said so, not a sliding mode
  const std::string marker = " in the constraint '";
  const std::size_t at = fired.rfind(marker);
  auto kink = [&](double t_kink) {
    return "the constraint '" + fired.substr(at + marker.size()) +
           " has a kink at t = " + format(t_kink) + " (where " + fired.substr(0, at) +
           " changes sign): the motion cannot continue across it without an impact (ukdyn does "
           "not model impacts); smooth the constraint or stop the run before it";
  };
  const bool of_constraint = at != std::string::npos && fired.back() == '\'';
  if (crawl_) {
    message = of_constraint
                  ? kink(window_start_)
                  : "switch events: " + format_number(long(kSwitchBurst)) +
                        " steps after the switch of " + name + " at t = " + format(window_start_) +
                        " advanced only to t = " + format(t) + advice;
    return true;
  }
  burst_[burst_next_ % kSwitchBurst] = t;
  ++burst_next_;
  if (burst_next_ < kSwitchBurst) return false;
  const double oldest = burst_[burst_next_ % kSwitchBurst];
  if (!(t - oldest <= span)) return false;
  message = of_constraint ? kink(oldest)
                          : "switch events: " + format_number(long(kSwitchBurst)) +
                                " sign changes (the last of " + name +
                                ") between t = " + format(oldest) + " and " + format(t) + advice;
  return true;
}

// the rank margin of the constraints active now at (t, x) (see run.hpp)
double Run::rank_margin_at(double t, const double* x) {
  q_ = Eigen::Map<const VectorXd>(x, n_);
  qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
  Workspace& w = branch_workspace();
  forward_dynamics(sys_, w, q_, qd_, t);  // (the margin is that of A, whatever the status)
  // (a rank already dropped: the margin is that of the rows kept, as if none were about to go)
  return w.rank < w.active_rows ? 0.0 : w.rank_margin;
}

// A restart at a dead centre, bridged past the pose (see run.hpp)
double Run::bridge_dead_centre(double t, double b, double h_max, double* x, ConstrainedOde& ode,
                               Status& status, bool ahead, double after) {
  status = Status::kOk;
  const double m0 = rank_margin_at(t, x);
  // (a pose ahead: from outside its neighbourhood, to where the margin is back to m0's)
  if (!(m0 < kCarriedMargin) && !(ahead && m0 < detail::kSingularMargin)) return t;
  const double target = std::max(m0, kCarriedMargin);
  const Index size = ode.size();
  bridge_x_.assign(x, x + size);
  bridge_rate_.resize(std::size_t(size));
  bridge_rate0_.resize(std::size_t(size));
  trial_.resize(std::size_t(size));
  const Eigen::Map<const VectorXd> q0(bridge_x_.data(), n_), qd0(bridge_x_.data() + n_, n_);
  ProjectionOptions all = o_.projection;
  // the landing: the first h (doubled) where q + h q', projected, has the margin back to
  // the target (from outside: after it fell below half the start's, past the pose)
  h_max = std::min(h_max, 0.5 * (b - t));
  double h = 1e-12 * std::max(1.0, std::abs(t));
  bool dipped = m0 < kCarriedMargin;
  for (; h <= h_max; h *= 2.0) {
    std::copy(bridge_x_.begin(), bridge_x_.end(), trial_.begin());
    q_ = q0 + h * qd0;
    // (the margin on the constraints: off them, the rows of a dead centre need not coincide)
    if (project_positions(sys_, ws_, q_, t + h, all).status != Status::kOk) continue;
    Eigen::Map<VectorXd>(trial_.data(), n_) = q_;
    const double m = rank_margin_at(t + h, trial_.data());
    if (dipped && m >= target && t + h > after) break;
    if (m < 0.5 * m0) dipped = true;
  }
  if (!(h <= h_max)) return t;
  // (from outside: the landing refined to where the margin is back to the start's, within
  // 1/64 of the bridge: its length nearly the passage's own)
  if (!(m0 < kCarriedMargin)) {
    double lo = std::max(0.5 * h, after - t);
    for (int k = 0; k < 6; ++k) {
      const double mid = 0.5 * (lo + h);
      q_ = q0 + mid * qd0;
      if (project_positions(sys_, ws_, q_, t + mid, all).status != Status::kOk) break;
      std::copy(bridge_x_.begin(), bridge_x_.end(), trial_.begin());
      Eigen::Map<VectorXd>(trial_.data(), n_) = q_;
      (rank_margin_at(t + mid, trial_.data()) >= target ? h : lo) = mid;
    }
    std::copy(bridge_x_.begin(), bridge_x_.end(), trial_.begin());
    q_ = q0 + h * qd0;
    if (project_positions(sys_, ws_, q_, t + h, all).status != Status::kOk) return t;
    Eigen::Map<VectorXd>(trial_.data(), n_) = q_;
  }
  // q'' at the landing, on the constraints there
  bool changed = false;
  if ((status = project(t + h, trial_.data(), all, changed)) != Status::kOk) return t;
  if (!ode(trial_.data(), bridge_rate_.data(), t + h)) {
    ode.clear_failure();
    return t;
  }
  // and at the start, where the rank margin is clear of the pose's (inside its neighbourhood
  // q'' there is a roundoff off the branch times the inverse margin: the landing's serves)
  bridge_rate0_ = bridge_rate_;
  if (m0 >= kCarriedMargin && !ode(bridge_x_.data(), bridge_rate0_.data(), t)) {
    ode.clear_failure();
    bridge_rate0_ = bridge_rate_;
  }
  // (an entry's end inside: q'' there on the line through the entering step's start, outside,
  // and the landing — exact for q'' linear in t, as the landing's alone is not for a passage
  // whose q'' turns with the pose: the twin arms' slow passage lost 1e-5 of its energy)
  if (ahead && m0 < kCarriedMargin && entry_t0_ < t) {
    if (ode(entry_x0_.data(), trial_.data(), entry_t0_)) {
      const double f = (t - entry_t0_) / (t + h - entry_t0_);
      for (std::size_t i = 0; i < bridge_rate0_.size(); ++i) {
        bridge_rate0_[i] = trial_[i] + (bridge_rate_[i] - trial_[i]) * f;
      }
    } else {
      ode.clear_failure();
    }
  }
  entry_t0_ = std::numeric_limits<double>::quiet_NaN();
  // the bridge: q' kept, q'' linear between the two ends
  bridge_t_ = t;
  bridge_h_ = h;
  bridged_state(t + h, x);
  if ((status = project(t + h, x, all, changed)) != Status::kOk) return t;
  return t + h;
}

// the state of the last bridge at s (see run.hpp)
void Run::bridged_state(double s, double* out) const {
  const double tau = s - bridge_t_, slope = tau / bridge_h_;
  const std::size_t n = std::size_t(n_);
  for (std::size_t i = 0; i < n; ++i) {
    const double a0 = bridge_rate0_[n + i], a1 = bridge_rate_[n + i];
    out[i] =
        bridge_x_[i] + tau * bridge_x_[n + i] + tau * tau * (0.5 * a0 + (a1 - a0) * slope / 6.0);
  }
  for (std::size_t i = n; i < bridge_x_.size(); ++i) {
    const double r0 = bridge_rate0_[i], r1 = bridge_rate_[i];
    out[i] = bridge_x_[i] + tau * (r0 + 0.5 * (r1 - r0) * slope);
  }
}

// ---- The sticks and slips listed (RunStatistics::contact_events) ------------------------------

void Run::before_mode_change(const double* x) {
  listed_modes_ = mode_;
  listed_x_.assign(x, x + 2 * n_);
  slip_holding_.assign(mode_.size(), std::numeric_limits<double>::quiet_NaN());
  slip_limit_.assign(mode_.size(), std::numeric_limits<double>::quiet_NaN());
}

void Run::list_mode_changes(double t, const double* x) {
  const auto& contacts = sys_.friction_contacts();
  if (listed_modes_.size() != mode_.size()) return;
  for (std::size_t c = 0; c < mode_.size(); ++c) {
    // stick: into sticking from sliding or passing; slip: out of sticking
    const bool was = listed_modes_[c] == ContactMode::kSticking;
    const bool now = mode_[c] == ContactMode::kSticking;
    if (was == now) continue;
    ContactEvent ev;
    ev.t = t;
    ev.constraint = contacts[c].normal_constraint;
    ev.kind = now ? ContactEvent::Kind::kStick : ContactEvent::Kind::kSlip;
    ev.friction = sys_.nonideal_name(contacts[c].force);
    // |v_rel| before (the state handed to the event) and after
    Index k = relative_velocity(c, t, listed_x_.data(), velocity_);
    ev.speed_before = velocity_.head(k).norm();
    k = relative_velocity(c, t, x, velocity_);
    ev.speed_after = velocity_.head(k).norm();
    if (!now) {
      ev.holding_force = slip_holding_[c];
      ev.friction_limit = slip_limit_[c];
    }
    traj_.stats.contact_events.push_back(std::move(ev));
  }
}

}  // namespace ukdyn::detail

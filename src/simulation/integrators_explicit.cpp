// SPDX-License-Identifier: BSD-3-Clause
// The explicit integrators, from Boost.Odeint: classical RK4 and Dormand–Prince's 5th-order
// formula (fixed step, cubic Hermite output), Dormand–Prince 5(4) (adaptive, its own dense
// output) and Runge–Kutta–Fehlberg 7(8) (adaptive, landing exactly on output times). Step-size
// control is Odeint's; this file only walks the steps so that the driver can project after each
// accepted one and count what happened.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <boost/numeric/odeint.hpp>

#include "simulation/integrator.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn::detail {

namespace {
namespace odeint = boost::numeric::odeint;
using State = std::vector<double>;

// The last two evaluations (x, f(x)), for StiffnessTest: after an accepted dopri5 step they are
// the 6th stage and the 7th (FSAL) one, both at t + h. Two copies of 2n + 1 numbers per
// evaluation, nothing else: the trajectory is unchanged.
struct StageProbe {
  State x_prev, f_prev, x_last, f_last;  // (2n + 1) each
  void record(const State& x, const State& f) {
    std::swap(x_prev, x_last);
    std::swap(f_prev, f_last);
    x_last = x;
    f_last = f;
  }
  // h·ρ ≈ h ‖f7 − f6‖ / ‖y7 − y6‖ (0 when the two stages coincide), over [q; q'] only: W is
  // a quadrature (W' = q'ᵀ Qc_nonideal, no component depends on W, its Jacobian column is
  // zero) that adds no stiffness, but its smooth change can swamp y7 − y6 (a damper written
  // as a non-ideal force C: W' = −c q'² is large while the stiff part of y7 − y6 is tiny).
  // (In fact over every component but the last work channel, `skip`; a caller's quadratures,
  // after it, count as the coordinates they were once, a controlled run's integrals, each in
  // its unit (WorkLayout::quadrature_units): in its model's units the control's effort, 10⁹
  // times its SI number in g, mm, ms, would make h·ρ that of the effort's jumps alone)
  double h_rho(double h) const {
    double num = 0.0, den = 0.0;
    for (std::size_t i = 0; i < x_last.size(); ++i) {
      if (i == skip) continue;
      const double w = i < quadrature ? 1.0 : 1.0 / units[i - quadrature];
      const double df = (f_last[i] - f_prev[i]) * w, dx = (x_last[i] - x_prev[i]) * w;
      num += df * df;
      den += dx * dx;
    }
    return den > 0.0 ? std::abs(h) * std::sqrt(num / den) : 0.0;
  }
  std::size_t skip = 0;  // the last work channel's index in x
  // the first quadrature's index in x (x.size() without) and the quadratures' units
  std::size_t quadrature = 0;
  std::vector<double> units;
};

// Projected stages near a singular configuration. Off the constraints, q'' carries a stage
// state's violation δ along the normal of the smallest singular value σ_r of A M^{-1/2} as δ/σ_r;
// the Runge–Kutta stages (violated by O(h²)) then leave the constraints by δ/σ_r, and near a
// singular pose of a closed loop (σ_r → 0) the step either collapses onto the pose or crosses
// it onto another branch. While `on`, each state f is evaluated at is first projected onto the
// constraints (hooks.project_stage), so that f is evaluated on the constraint manifold, where
// the motion is smooth through the pose: the method integrates x' = f(π(x)), whose solution
// from a consistent state is the same. It is on for a step when Workspace::rank_margin (σ_r/σ_1
// estimated by the decomposition) at the step's start, or extrapolated to its end from the
// last two steps, is below kMargin; where the margin is unknown (NaN: Algorithm::kTextbook),
// for the retry of a rejected step and the kAfterRejection steps after it.
struct StageProjection {
  static constexpr double kMargin = kSingularMargin;
  static constexpr int kAfterRejection = 3;
  SegmentHooks* hooks = nullptr;
  bool on = false;
  State y;                                 // (size of x) the projected copy
  double margin = 1.0, margin_prev = 1.0;  // at the last two accepted states
  double step_prev = 0.0;                  // between them
  int pending = 0;  // (unknown margin) steps still to project after a rejection

  StageProjection(SegmentHooks& h, std::size_t size) : hooks(&h), y(size) {}
  // after the evaluation at the accepted state (t, x) left `m` in the workspace
  void accepted(double m, double step) {
    margin_prev = margin;
    margin = m;
    step_prev = step;
    if (pending > 0) --pending;
  }
  void rejected() { pending = kAfterRejection + 1; }
  // whether the attempt of size dt from the last accepted state projects its stages
  bool decide(double dt) {
    if (!hooks->project_stage) return on = false;
    if (std::isnan(margin)) return on = pending > 0;
    double predicted = margin;
    if (step_prev > 0.0 && margin_prev > margin) {
      predicted = margin - (margin_prev - margin) * std::abs(dt / step_prev);
    }
    return on = std::min(margin, predicted) < kMargin;
  }
};

// Odeint's view of the ODE (Odeint copies it: state lives behind the pointers)
struct OdeFn {
  ConstrainedOde* ode;
  StageProbe* probe = nullptr;
  StageProjection* projection = nullptr;
  void operator()(const State& x, State& dxdt, double t) const {
    if (projection && projection->on) {
      projection->y = x;
      if (projection->hooks->project_stage(t, projection->y.data())) {
        (*ode)(projection->y.data(), dxdt.data(), t);
        if (probe) probe->record(x, dxdt);
        return;
      }
    }
    (*ode)(x.data(), dxdt.data(), t);
    if (probe) probe->record(x, dxdt);
  }
};

// after a failed evaluation: the result that reports it
SegmentResult failed(const ConstrainedOde& ode, SegmentResult r, double t) {
  r.status = ode.failure();
  r.message = ode.failure_message();
  r.t_reached = t;
  return r;
}

// When hooks.find_event reports a switch inside the step just taken: emit the samples up to it,
// leave the state there in x and return true (the integrator then returns r with r.event).
// `dense` locates the event and gives the samples; `restart(te, x)` gives the state the run
// restarts from: one step of the method from (t0, x0) to te, as accurate as any step (an
// interpolant, a cubic Hermite in particular, is less so, and its error would enter the run at
// every event).
bool stop_at_event(SegmentHooks& hooks, double t0, const State& x0, double t1, const State& x1,
                   const SegmentHooks::Dense& dense, const SegmentHooks::Dense& restart,
                   const SampleTimes& outputs, std::size_t& next, State& x, SegmentResult& r) {
  if (!hooks.find_event) return false;
  const double te = hooks.find_event(t0, x0.data(), t1, x1.data(), dense);
  if (std::isnan(te)) return false;
  State out(x0.size());
  for (; next < outputs.size() && outputs[next] <= te; ++next) {
    dense(outputs[next], out.data());
    if (const Status s = hooks.output(outputs[next], out.data()); s != Status::kOk) {
      r.status = s;
      r.t_reached = outputs[next];
      return true;
    }
  }
  restart(te, x.data());
  r.t_reached = te;
  r.event = true;
  return true;
}

// ends a segment at t with status s
SegmentResult& stop(SegmentResult& r, Status s, double t, std::string message = {}) {
  r.status = s;
  r.t_reached = t;
  r.message = std::move(message);
  return r;
}

// Odeint's step-size control (controlled_runge_kutta::try_step, with its error checker and
// step adjuster, so that steps and step sizes are Odeint's), with one addition: a step whose
// error estimate fails is measured again with the estimate's components normal to the
// constraints taken out (hooks.project_error), since the projection after the step removes
// them. Near a singular configuration (a closed loop whose constraints lose rank) the stage
// states' violation δ enters q'' along the normal of the vanishing singular value σ as δ/σ: the
// normal components of the estimate grow like 1/σ and shrink the step onto the singular pose,
// while the motion along the constraints — what the projected solution keeps — is smooth
// there (docs/simulation.md, "Singular configurations").
class StepControl {
 public:
  // x = [q; q'; W; z] with n coordinates; rate: the run's rate decade (Workspace::rate_unit),
  // the atol on q' being o.atol · rate, and on the quadrature z_i o.atol · unit_i
  // (WorkLayout::quadrature_units; docs/simulation.md, "Scales and tolerances")
  StepControl(const SimulationOptions& o, SegmentHooks& hooks, std::size_t size, Index n,
              double rate, const WorkLayout& works)
      : rtol_(o.rtol),
        atol_(size, o.atol),
        adjuster_(o.max_step > 0 ? o.max_step : 0.0),
        hooks_(hooks),
        err_(size),
        err_normal_(size) {
    for (Index i = n; i < 2 * n; ++i) atol_[std::size_t(i)] = o.atol * rate;
    if (works.quadrature >= 0) {
      const std::size_t z = std::size_t(2 * n + works.quadrature);
      for (std::size_t i = 0; i < works.quadrature_units.size(); ++i) {
        atol_[z + i] = o.atol * works.quadrature_units[i];
      }
    }
  }

  // the local error estimate the next attempt writes
  State& error() { return err_; }
  // false (and dt = the largest step) when dt exceeds the largest step, as Odeint does
  bool admissible(double& dt) {
    if (adjuster_.check_step_size_limit(dt)) return true;
    dt = adjuster_.get_max_dt();
    return false;
  }
  // after an attempt from (t, in, dxdt_in) of size dt that reached `out` with error(): accept
  // (t += dt, dt the next step) or reject (dt the step to try again)
  // (tangential: the attempt projected its stages, near a singular configuration; elsewhere the
  // whole estimate counts, as in Odeint)
  template <int ErrorOrder, int StepperOrder>
  bool judge(const State& in, const State& dxdt_in, const State& out, double& t, double& dt,
             bool tangential_control, long& tangential) {
    const bool retry = tangential_control && hooks_.project_error;
    if (retry) err_normal_ = err_;
    double e = error(in, dxdt_in, err_, dt);
    if (e > 1.0 && retry && hooks_.project_error(t + dt, out.data(), err_normal_.data())) {
      const double e_tangential = error(in, dxdt_in, err_normal_, dt);
      if (e_tangential <= 1.0) ++tangential;
      e = std::min(e, e_tangential);
    }
    if (e > 1.0) {
      dt = adjuster_.decrease_step(dt, e, ErrorOrder);
      return false;
    }
    t += dt;
    dt = adjuster_.increase_step(dt, e, StepperOrder);
    return true;
  }

 private:
  // Odeint's default_error_checker with an atol per component: max_i |err_i| /
  // (atol_i + rtol (|x_i| + |dt| |x'_i|)), bit for bit Odeint's where every atol_i is atol
  double error(const State& x, const State& dxdt, State& err, double dt) const {
    const double h = std::abs(dt);
    double e = 0.0;
    for (std::size_t i = 0; i < err.size(); ++i) {
      err[i] = std::abs(err[i]) / (atol_[i] + rtol_ * (std::abs(x[i]) + h * std::abs(dxdt[i])));
      e = std::max(e, err[i]);
    }
    return e;
  }
  double rtol_;
  State atol_;  // per component of x
  odeint::default_step_adjuster<double, double> adjuster_;
  SegmentHooks& hooks_;
  State err_, err_normal_;  // the estimate; its copy for project_error
};

// consecutive rejected steps after which an adaptive method gives up
constexpr int kMaxRejections = 200;

// Accepted steps that t can hardly resolve: below 64 ε max(|t|, |t_end|) ("slivers"), a run of
// kMaxSlivers of them is a step size underflow too — the error test accepting steps of a few
// units of t's roundoff, forever, where the dynamics blow up without turning non-finite (a
// ball's tangents near their singular axis took 2.6 million steps of 2.8e-17 s in 120 s at
// t = 0.244, u22 04). sliver(...) counts them; true when the run must stop.
constexpr int kMaxSlivers = 1000;
bool sliver(double step, double t, double t_end, int& slivers) {
  const double roundoff =
      64.0 * std::numeric_limits<double>::epsilon() * std::max(std::abs(t), std::abs(t_end));
  slivers = step < roundoff ? slivers + 1 : 0;
  return slivers > kMaxSlivers;
}

// The step dt towards the next stop `rest` ahead held to max_step (> 0; 0: unlimited). A
// landing step (dt = rest) above max_step by the sliver the landing adds — or by the roundoff
// that t gathers over T / max_step steps, which leaves it a few units short of T — is split in
// two halves (landing with the second) instead of being refused as too large (which ended runs
// at max_step = 1e-4 in "step size underflow" one step before t_end); any other step above
// max_step is max_step.
double within_max_step(double dt, double rest, double max_step) {
  if (!(max_step > 0.0) || dt <= max_step) return dt;
  return dt == rest && dt <= 2.0 * max_step ? 0.5 * dt : max_step;
}

// x(s) on [t0, t1] from the values and derivatives at both ends (cubic Hermite)
void hermite(double s, double t0, double t1, const State& x0, const State& d0, const State& x1,
             const State& d1, State& out) {
  const double h = t1 - t0, u = (s - t0) / h, u2 = u * u, u3 = u2 * u;
  const double h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2,
               h11 = u3 - u2;
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = h00 * x0[i] + h10 * h * d0[i] + h01 * x1[i] + h11 * h * d1[i];
  }
}

// Dormand–Prince's tableau (Dormand & Prince 1980, Hairer–Nørsett–Wanner I, table II.5.2)
// without its 7th (first-same-as-last) stage, which only the error estimate needs: the 6-stage,
// 5th-order formula that dopri5 propagates, as an Odeint generic Runge–Kutta stepper
using Dopri5Fixed = odeint::explicit_generic_rk<6, 5, State, double, State, double>;

Dopri5Fixed dopri5_fixed() {
  const boost::array<double, 1> a1 = {1.0 / 5};
  const boost::array<double, 2> a2 = {3.0 / 40, 9.0 / 40};
  const boost::array<double, 3> a3 = {44.0 / 45, -56.0 / 15, 32.0 / 9};
  const boost::array<double, 4> a4 = {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561,
                                      -212.0 / 729};
  const boost::array<double, 5> a5 = {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176,
                                      -5103.0 / 18656};
  const boost::array<double, 6> b = {35.0 / 384,     0.0,      500.0 / 1113, 125.0 / 192,
                                     -2187.0 / 6784, 11.0 / 84};
  const boost::array<double, 6> c = {0.0, 1.0 / 5, 3.0 / 10, 4.0 / 5, 8.0 / 9, 1.0};
  return Dopri5Fixed(boost::fusion::make_vector(a1, a2, a3, a4, a5), b, c);
}

// a fixed-step Runge–Kutta method (RK4 or the 5th-order Dormand–Prince formula) with the step
// (t1 − t0) / N closest to `step` from below; k1 of each step is the derivative at the state
// after drift control, so a step costs (stages − 1) + 1 evaluations
template <class Stepper>
SegmentResult fixed_step(Stepper stepper, ConstrainedOde& ode, State& x, double t0, double t1,
                         const SampleTimes& outputs, SegmentHooks& hooks, double step,
                         long max_steps) {
  SegmentResult r;
  const OdeFn fn{&ode};
  // N steps (counted in double first: (t1 − t0) / step may exceed any integer)
  const double count = std::max(1.0, std::ceil((t1 - t0) / step * (1.0 - 1e-12)));
  if (!(count <= double(max_steps))) {
    return stop(r, Status::kIntegratorFailure, t0,
                "step limit: the segment [" + format_short(t0) + ", " + format_short(t1) +
                    "] needs " + format_short(count) + " steps of " + format_short(step) +
                    ", more than the " + format_number(max_steps) + " the run has left");
  }
  const long N = long(count);
  const double h = (t1 - t0) / double(N);
  State dxdt(x.size()), x_new(x.size()), dxdt_new(x.size()), out(x.size());
  // k1 of the first step
  fn(x, dxdt, t0);
  if (ode.failed()) return failed(ode, r, t0);
  std::size_t next = 0;
  double t = t0;
  // a switch of the dynamics inside a step (from t, at x with derivative dxdt, to t_new): the
  // state at s inside the step is one step of the method from t to s (a cubic Hermite of a step
  // across a jump of the forces would misplace the event by O(h · jump)). Made once: it reads
  // x, dxdt and t by reference (a std::function made in the loop would allocate every step).
  const SegmentHooks::Dense state_at = [&](double s, double* xs) {
    State tmp = x, d = dxdt;
    stepper.do_step(fn, tmp, d, t, s - t);
    std::copy(tmp.begin(), tmp.end(), xs);
  };
  for (long k = 1; k <= N; ++k) {
    // one step; t_k from k, not by accumulation
    const double t_new = k == N ? t1 : t0 + double(k) * h;
    x_new = x;
    stepper.do_step(fn, x_new, dxdt, t, t_new - t);
    if (ode.failed()) return failed(ode, r, t);
    ++r.steps;
    // drift control, then the derivative at the new state (k1 of the next step)
    bool changed = false;
    if (hooks.after_step) {
      const Status s = hooks.after_step(t_new, x_new.data(), changed);
      if (s != Status::kOk) {
        r.status = s;
        r.t_reached = t_new;
        x = x_new;
        return r;
      }
    }
    fn(x_new, dxdt_new, t_new);
    if (ode.failed()) return failed(ode, r, t_new);
    // a switch of the dynamics inside the step: stop there
    if (stop_at_event(hooks, t, x, t_new, x_new, state_at, state_at, outputs, next, x, r)) {
      return r;
    }
    // samples inside (t, t_new] by cubic Hermite interpolation
    for (; next < outputs.size() && outputs[next] <= t_new; ++next) {
      hermite(outputs[next], t, t_new, x, dxdt, x_new, dxdt_new, out);
      if (const Status s = hooks.output(outputs[next], out.data()); s != Status::kOk) {
        return stop(r, s, outputs[next]);
      }
    }
    std::swap(x, x_new);
    std::swap(dxdt, dxdt_new);
    t = t_new;
  }
  r.t_reached = t1;
  r.last_step = h;
  return r;
}

// Dormand–Prince 5(4): Odeint's controller, its dense output between accepted steps
SegmentResult dopri5(ConstrainedOde& ode, State& x, double t0, double t1,
                     const SampleTimes& outputs, const SimulationOptions& o, SegmentHooks& hooks,
                     double dt, long max_steps) {
  SegmentResult r;
  // the stiffness test reads the last two stages of each step (for the switch, and for the
  // diagnosis of a collapsed step size when the switch is off)
  StageProbe probe;
  {
    const WorkLayout& w = ode.works();
    probe.skip =
        std::size_t(2 * ode.coordinate_count() + (w.quadrature >= 0 ? w.quadrature : w.count) - 1);
    probe.quadrature = w.quadrature >= 0 ? probe.skip + 1 : x.size();
    probe.units = w.quadrature_units;
  }
  StiffnessTest stiffness;
  StageProjection projection(hooks, x.size());
  const OdeFn fn{&ode, &probe, &projection};
  using Stepper = odeint::runge_kutta_dopri5<State>;
  Stepper stepper;
  StepControl control(o, hooks, x.size(), ode.coordinate_count(), ode.workspace().rate_unit,
                      ode.works());
  State dxdt(x.size()), x_old(x.size()), dxdt_old(x.size()), out(x.size());
  fn(x, dxdt, t0);
  if (ode.failed()) return failed(ode, r, t0);
  projection.accepted(ode.workspace().rank_margin, 0.0);
  bool low_margin = projection.margin < kSingularMargin;  // (crossing) seen below kSingularMargin
  std::size_t next = 0;
  double t = t0;
  int rejections = 0, slivers = 0;
  std::string outside_description;  // of the last trial state outside the model's domain
  while (t < t1) {
    // land on the segment's end; a landing step above max_step (by the sliver the landing
    // adds, or the roundoff t has gathered over many steps) is split in two halves instead
    if (t + dt >= t1 || t1 - (t + dt) < 1e-12 * std::max(1.0, std::abs(t1))) dt = t1 - t;
    dt = within_max_step(dt, t1 - t, o.max_step);
    projection.decide(dt);
    std::swap(x_old, x);
    std::swap(dxdt_old, dxdt);
    const double t_old = t;
    bool accepted = false;
    Status outside = Status::kOk;  // a trial state outside the model's domain
    if (control.admissible(dt)) {
      stepper.do_step(fn, x_old, dxdt_old, t, x, dxdt, dt, control.error());
      if (ode.failed()) {
        // rejected: half the step, from the same state
        outside = ode.take_failure(outside_description);
        dt *= 0.5;
      } else {
        accepted = control.judge<Stepper::error_order_value, Stepper::stepper_order_value>(
            x_old, dxdt_old, x, t, dt, projection.on, r.tangential_steps);
      }
    }
    if (!accepted) {
      std::swap(x_old, x);
      std::swap(dxdt_old, dxdt);
      projection.rejected();
      ++r.rejected;
      if (++rejections > kMaxRejections || t + dt == t) {
        if (outside != Status::kOk) {
          return stop(r, outside, t, left_domain("dopri5", t, dt, outside_description));
        }
        r.collapsed = true;
        r.stiffness = stiffness.recent();
        return stop(r, Status::kIntegratorFailure, t,
                    "dopri5: step size underflow at t = " + format_number(t));
      }
      continue;
    }
    rejections = 0;
    if (t1 - t < 1e-14 * std::max(1.0, std::abs(t1))) t = t1;
    ++r.steps;
    r.last_step = t - t_old;
    if (sliver(r.last_step, t, t1, slivers)) {
      r.collapsed = true;
      r.stiffness = stiffness.recent();
      return stop(r, Status::kIntegratorFailure, t,
                  "dopri5: step size underflow at t = " + format_number(t) + " (" +
                      format_number(kMaxSlivers) + " steps in a row below 64 ulp of t)");
    }
    if (projection.on) ++r.projected_stage_steps;
    // the margin at the new state (its FSAL evaluation, or the one after drift control below)
    double margin = ode.workspace().rank_margin;
    // h·ρ from the 6th and 7th stages, before anything else evaluates f
    const bool stiff =
        stiffness.accepted(probe.h_rho(r.last_step)) && o.stiff_switch && !hooks.cross_singular;
    // a switch of the dynamics inside the step: stop there
    {
      const State x_new = x, dxdt_new = dxdt;
      const double t_new = t;
      const SegmentHooks::Dense dense = [&](double s, double* xs) {
        State tmp(x.size());
        stepper.calc_state(s, tmp, x_old, dxdt_old, t_old, x_new, dxdt_new, t_new);
        std::copy(tmp.begin(), tmp.end(), xs);
      };
      const SegmentHooks::Dense restart = [&](double s, double* xs) {
        State tmp = x_old, d = dxdt_old;
        odeint::runge_kutta_dopri5<State>().do_step(fn, tmp, d, t_old, s - t_old);
        std::copy(tmp.begin(), tmp.end(), xs);
      };
      if (hooks.find_event &&
          stop_at_event(hooks, t_old, x_old, t_new, x_new, dense, restart, outputs, next, x, r)) {
        return r;
      }
    }
    // samples inside (t_old, t] from the method's dense output
    for (; next < outputs.size() && outputs[next] <= t; ++next) {
      stepper.calc_state(outputs[next], out, x_old, dxdt_old, t_old, x, dxdt, t);
      if (const Status s = hooks.output(outputs[next], out.data()); s != Status::kOk) {
        return stop(r, s, outputs[next]);
      }
    }
    // drift control; a corrected state needs its derivative again (first stage of the next)
    if (hooks.after_step) {
      bool changed = false;
      const Status s = hooks.after_step(t, x.data(), changed);
      if (s != Status::kOk) {
        return stop(r, s, t);
      }
      if (changed) {
        fn(x, dxdt, t);
        if (ode.failed()) return failed(ode, r, t);
        margin = ode.workspace().rank_margin;
      }
    }
    projection.accepted(margin, r.last_step);
    r.stiffness = stiffness.recent();
    // crossing for BDF: past the singular configuration, BDF goes on from here
    if (hooks.cross_singular) {
      low_margin = low_margin || margin < kSingularMargin;
      if (low_margin && margin >= 2.0 * kSingularMargin && t < t1) {
        r.crossed = true;
        r.t_reached = t;
        return r;
      }
    }
    // stiff: the driver goes on with BDF from here (x is the state after drift control)
    if (stiff && t < t1) {
      r.stiff = true;
      r.t_reached = t;
      return r;
    }
    if (r.steps >= max_steps) {
      r.collapsed = true;
      return stop(r, Status::kIntegratorFailure, t,
                  "dopri5: step limit reached at t = " + format_number(t));
    }
  }
  r.t_reached = t1;
  return r;
}

// Runge–Kutta–Fehlberg 7(8): Odeint's controller, steps shortened to land on output times
SegmentResult rkf78(ConstrainedOde& ode, State& x, double t0, double t1, const SampleTimes& outputs,
                    const SimulationOptions& o, SegmentHooks& hooks, double dt, long max_steps) {
  SegmentResult r;
  StageProjection projection(hooks, x.size());
  const OdeFn fn{&ode, nullptr, &projection};
  using Stepper = odeint::runge_kutta_fehlberg78<State>;
  Stepper stepper;
  StepControl control(o, hooks, x.size(), ode.coordinate_count(), ode.workspace().rate_unit,
                      ode.works());
  std::size_t next = 0;
  double t = t0;
  int rejections = 0, slivers = 0;
  std::string outside_description;    // of the last trial state outside the model's domain
  Status outside_last = Status::kOk;  // the last attempt's, when it was outside the domain
  State x_old(x.size()), dxdt(x.size()), x_out(x.size());
  // the derivative at x, evaluated again only when x changes
  bool dxdt_current = false;
  while (t < t1) {
    // the next stop: an output time or the segment's end
    const double target = next < outputs.size() ? std::min(outputs[next], t1) : t1;
    // (after an attempt outside the model's domain, the halved step is not stretched to land)
    bool landing =
        t + dt >= target || (outside_last == Status::kOk &&
                             target - (t + dt) < 1e-12 * std::max(1.0, std::abs(target)));
    double step = landing ? target - t : dt;
    // (a landing step above max_step: half of it, landing with the next)
    if (o.max_step > 0.0 && step > o.max_step) {
      step = within_max_step(step, target - t, o.max_step);
      landing = false;
    }
    const double t_old = t;
    if (hooks.find_event) x_old = x;
    bool accepted = false;
    Status outside = Status::kOk;  // a trial state outside the model's domain
    outside_last = Status::kOk;
    if (control.admissible(step)) {
      if (!dxdt_current) {
        // (x is consistent: the evaluation at x is not projected)
        projection.on = false;
        fn(x, dxdt, t);
        if (ode.failed()) return failed(ode, r, t_old);
        dxdt_current = true;
        projection.accepted(ode.workspace().rank_margin, r.last_step);
      }
      projection.decide(step);
      stepper.do_step(fn, x, dxdt, t, x_out, step, control.error());
      if (ode.failed()) {
        // a trial state outside the model's domain: rejected, half the step
        outside = outside_last = ode.take_failure(outside_description);
        step *= 0.5;
      } else {
        accepted = control.judge<Stepper::error_order_value, Stepper::stepper_order_value>(
            x, dxdt, x_out, t, step, projection.on, r.tangential_steps);
      }
    }
    if (accepted) {
      std::swap(x, x_out);
      dxdt_current = false;
      if (projection.on) ++r.projected_stage_steps;
    } else {
      projection.rejected();
      ++r.rejected;
      dt = step;
      if (++rejections > kMaxRejections || t + dt == t) {
        if (outside != Status::kOk) {
          return stop(r, outside, t, left_domain("rkf78", t, dt, outside_description));
        }
        r.collapsed = true;
        return stop(r, Status::kIntegratorFailure, t,
                    "rkf78: step size underflow at t = " + format_number(t));
      }
      continue;
    }
    rejections = 0;
    ++r.steps;
    r.last_step = t - t_old;
    if (sliver(r.last_step, t, t1, slivers)) {
      r.collapsed = true;
      return stop(r, Status::kIntegratorFailure, t,
                  "rkf78: step size underflow at t = " + format_number(t) + " (" +
                      format_number(kMaxSlivers) + " steps in a row below 64 ulp of t)");
    }
    // a shortened step leaves the suggestion for the full one
    if (!landing) dt = step;
    if (landing) t = target;
    // a switch of the dynamics inside the step: stop there. The state at s inside the step is
    // one Fehlberg step from t_old to s (as accurate as any step; a cubic Hermite is not)
    if (hooks.find_event) {
      const State x_new = x;
      const double t_new = t;
      const SegmentHooks::Dense state_at = [&](double s, double* xs) {
        State tmp = x_old;
        odeint::runge_kutta_fehlberg78<State>().do_step(fn, tmp, t_old, s - t_old);
        std::copy(tmp.begin(), tmp.end(), xs);
      };
      if (stop_at_event(hooks, t_old, x_old, t_new, x_new, state_at, state_at, outputs, next, x,
                        r)) {
        return r;
      }
    }
    if (next < outputs.size() && t == outputs[next]) {
      if (const Status s = hooks.output(t, x.data()); s != Status::kOk) {
        return stop(r, s, t);
      }
      ++next;
    }
    if (hooks.after_step) {
      bool changed = false;
      if (const Status s = hooks.after_step(t, x.data(), changed); s != Status::kOk) {
        return stop(r, s, t);
      }
    }
    if (r.steps >= max_steps) {
      r.collapsed = true;
      return stop(r, Status::kIntegratorFailure, t,
                  "rkf78: step limit reached at t = " + format_number(t));
    }
  }
  r.t_reached = t1;
  return r;
}
}  // namespace

SegmentResult integrate_explicit(Integrator method, ConstrainedOde& ode, std::vector<double>& x,
                                 double t0, double t1, const SampleTimes& outputs,
                                 const SimulationOptions& options, SegmentHooks& hooks,
                                 double first_step) {
  const long max_steps = std::min(options.max_steps, hooks.max_steps);
  switch (method) {
    case Integrator::kRK4:
      return fixed_step(odeint::runge_kutta4<State>(), ode, x, t0, t1, outputs, hooks, first_step,
                        max_steps);
    case Integrator::kRK5:
      return fixed_step(dopri5_fixed(), ode, x, t0, t1, outputs, hooks, first_step, max_steps);
    case Integrator::kDopri5:
      return dopri5(ode, x, t0, t1, outputs, options, hooks, first_step, max_steps);
    case Integrator::kRKF78:
      return rkf78(ode, x, t0, t1, outputs, options, hooks, first_step, max_steps);
    case Integrator::kBDF:
      break;
  }
  SegmentResult r;
  r.status = Status::kIntegratorFailure;
  r.message = "integrate_explicit: not an explicit method";
  return r;
}

}  // namespace ukdyn::detail

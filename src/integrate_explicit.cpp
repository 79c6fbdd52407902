// The explicit integrators, from Boost.Odeint: classical RK4 and Dormand–Prince's 5th-order
// formula (fixed step, cubic Hermite output), Dormand–Prince 5(4) (adaptive, its own dense
// output) and Runge–Kutta–Fehlberg 7(8) (adaptive, landing exactly on output times). Step-size
// control is Odeint's; this file only walks the steps so that the driver can project after each
// accepted one and count what happened.
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include <boost/numeric/odeint.hpp>

#include "integrator.hpp"

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
  // as a non-ideal force C: W' = −c q'² is large while the stiff part of y7 − y6 is tiny)
  double h_rho(double h) const {
    double num = 0.0, den = 0.0;
    for (std::size_t i = 0; i + 1 < x_last.size(); ++i) {
      num += (f_last[i] - f_prev[i]) * (f_last[i] - f_prev[i]);
      den += (x_last[i] - x_prev[i]) * (x_last[i] - x_prev[i]);
    }
    return den > 0.0 ? std::abs(h) * std::sqrt(num / den) : 0.0;
  }
};

// Odeint's view of the ODE (Odeint copies it: state lives behind the pointers)
struct OdeFn {
  ConstrainedOde* ode;
  StageProbe* probe = nullptr;
  void operator()(const State& x, State& dxdt, double t) const {
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
                   const std::vector<double>& outputs, std::size_t& next, State& x,
                   SegmentResult& r) {
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

// Odeint's controlled stepper with the run's tolerances (and largest step, when given)
template <class Stepper>
auto controlled(const SimulationOptions& o, Stepper stepper) {
  using Controlled = decltype(odeint::make_controlled(o.atol, o.rtol, stepper));
  return o.max_step > 0 ? Controlled(odeint::make_controlled(o.atol, o.rtol, o.max_step, stepper))
                        : odeint::make_controlled(o.atol, o.rtol, stepper);
}

// consecutive rejected steps after which an adaptive method gives up
constexpr int kMaxRejections = 200;

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
                         const std::vector<double>& outputs, SegmentHooks& hooks, double step) {
  SegmentResult r;
  const OdeFn fn{&ode};
  const long N = std::max(1L, long(std::ceil((t1 - t0) / step * (1.0 - 1e-12))));
  const double h = (t1 - t0) / double(N);
  State dxdt(x.size()), x_new(x.size()), dxdt_new(x.size()), out(x.size());
  // k1 of the first step
  fn(x, dxdt, t0);
  if (ode.failed()) return failed(ode, r, t0);
  std::size_t next = 0;
  double t = t0;
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
    // a switch of the dynamics inside the step: stop there. The state at s inside the step is
    // one step of the method from t to s (a cubic Hermite of a step across a jump of the forces
    // would misplace the event by O(h · jump))
    const SegmentHooks::Dense state_at = [&](double s, double* xs) {
      State tmp = x, d = dxdt;
      stepper.do_step(fn, tmp, d, t, s - t);
      std::copy(tmp.begin(), tmp.end(), xs);
    };
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
                     const std::vector<double>& outputs, const SimulationOptions& o,
                     SegmentHooks& hooks, double dt, long max_steps) {
  SegmentResult r;
  // the stiffness test reads the last two stages of each step (for the switch, and for the
  // diagnosis of a collapsed step size when the switch is off)
  StageProbe probe;
  StiffnessTest stiffness;
  const OdeFn fn{&ode, &probe};
  auto stepper = controlled(o, odeint::runge_kutta_dopri5<State>());
  State dxdt(x.size()), x_old(x.size()), dxdt_old(x.size()), out(x.size());
  fn(x, dxdt, t0);
  if (ode.failed()) return failed(ode, r, t0);
  std::size_t next = 0;
  double t = t0;
  int rejections = 0;
  while (t < t1) {
    // land on the segment's end
    if (t + dt >= t1 || t1 - (t + dt) < 1e-12 * std::max(1.0, std::abs(t1))) dt = t1 - t;
    x_old = x;
    dxdt_old = dxdt;
    const double t_old = t;
    const auto result = stepper.try_step(fn, x, dxdt, t, dt);
    if (ode.failed()) return failed(ode, r, t_old);
    if (result == odeint::fail) {
      ++r.rejected;
      if (++rejections > kMaxRejections || t + dt == t) {
        r.collapsed = true;
        r.stiffness = stiffness.recent();
        return stop(r, Status::kIntegratorFailure, t,
                    "dopri5: step size underflow at t = " + std::to_string(t));
      }
      continue;
    }
    rejections = 0;
    if (t1 - t < 1e-14 * std::max(1.0, std::abs(t1))) t = t1;
    ++r.steps;
    r.last_step = t - t_old;
    // h·ρ from the 6th and 7th stages, before anything else evaluates f
    const bool stiff = stiffness.accepted(probe.h_rho(r.last_step)) && o.stiff_switch;
    // a switch of the dynamics inside the step: stop there
    {
      const State x_new = x, dxdt_new = dxdt;
      const double t_new = t;
      const SegmentHooks::Dense dense = [&](double s, double* xs) {
        State tmp(x.size());
        stepper.stepper().calc_state(s, tmp, x_old, dxdt_old, t_old, x_new, dxdt_new, t_new);
        std::copy(tmp.begin(), tmp.end(), xs);
      };
      const SegmentHooks::Dense restart = [&](double s, double* xs) {
        State tmp = x_old, d = dxdt_old;
        odeint::runge_kutta_dopri5<State>().do_step(fn, tmp, d, t_old, s - t_old);
        std::copy(tmp.begin(), tmp.end(), xs);
      };
      if (hooks.find_event && stop_at_event(hooks, t_old, x_old, t_new, x_new, dense, restart,
                                            outputs, next, x, r)) {
        return r;
      }
    }
    // samples inside (t_old, t] from the method's dense output
    for (; next < outputs.size() && outputs[next] <= t; ++next) {
      stepper.stepper().calc_state(outputs[next], out, x_old, dxdt_old, t_old, x, dxdt, t);
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
      }
    }
    r.stiffness = stiffness.recent();
    // stiff: the driver goes on with BDF from here (x is the state after drift control)
    if (stiff && t < t1) {
      r.stiff = true;
      r.t_reached = t;
      return r;
    }
    if (r.steps >= max_steps) {
      r.collapsed = true;
      return stop(r, Status::kIntegratorFailure, t,
                  "dopri5: step limit reached at t = " + std::to_string(t));
    }
  }
  r.t_reached = t1;
  return r;
}

// Runge–Kutta–Fehlberg 7(8): Odeint's controller, steps shortened to land on output times
SegmentResult rkf78(ConstrainedOde& ode, State& x, double t0, double t1,
                    const std::vector<double>& outputs, const SimulationOptions& o,
                    SegmentHooks& hooks, double dt, long max_steps) {
  SegmentResult r;
  const OdeFn fn{&ode};
  auto stepper = controlled(o, odeint::runge_kutta_fehlberg78<State>());
  std::size_t next = 0;
  double t = t0;
  int rejections = 0;
  State x_old(x.size());
  while (t < t1) {
    // the next stop: an output time or the segment's end
    const double target = next < outputs.size() ? std::min(outputs[next], t1) : t1;
    const bool landing =
        t + dt >= target || target - (t + dt) < 1e-12 * std::max(1.0, std::abs(target));
    double step = landing ? target - t : dt;
    const double t_old = t;
    if (hooks.find_event) x_old = x;
    const auto result = stepper.try_step(fn, x, t, step);
    if (ode.failed()) return failed(ode, r, t_old);
    if (result == odeint::fail) {
      ++r.rejected;
      dt = step;
      if (++rejections > kMaxRejections || t + dt == t) {
        r.collapsed = true;
        return stop(r, Status::kIntegratorFailure, t,
                    "rkf78: step size underflow at t = " + std::to_string(t));
      }
      continue;
    }
    rejections = 0;
    ++r.steps;
    r.last_step = t - t_old;
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
                  "rkf78: step limit reached at t = " + std::to_string(t));
    }
  }
  r.t_reached = t1;
  return r;
}
}  // namespace

SegmentResult integrate_explicit(Integrator method, ConstrainedOde& ode, std::vector<double>& x,
                                 double t0, double t1, const std::vector<double>& outputs,
                                 const SimulationOptions& options, SegmentHooks& hooks,
                                 double first_step) {
  switch (method) {
    case Integrator::kRK4:
      return fixed_step(odeint::runge_kutta4<State>(), ode, x, t0, t1, outputs, hooks, first_step);
    case Integrator::kRK5:
      return fixed_step(dopri5_fixed(), ode, x, t0, t1, outputs, hooks, first_step);
    case Integrator::kDopri5:
      return dopri5(ode, x, t0, t1, outputs, options, hooks, first_step, options.max_steps);
    case Integrator::kRKF78:
      return rkf78(ode, x, t0, t1, outputs, options, hooks, first_step, options.max_steps);
    case Integrator::kBDF:
      break;
  }
  SegmentResult r;
  r.status = Status::kIntegratorFailure;
  r.message = "integrate_explicit: not an explicit method";
  return r;
}

}  // namespace ukdyn::detail

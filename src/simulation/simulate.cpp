// SPDX-License-Identifier: BSD-3-Clause
// simulate(): the driver of a run. Splits [t_start, t_end] at breakpoints (the ends of
// constraint intervals and those the user gives), integrates each segment with the chosen method,
// applies drift control after every accepted step, and records samples.
// The Run (simulation/run.hpp) holds what the integrator's callbacks share, one job per file:
// drift control (run_drift.cpp), events and switches (run_events.cpp), stick/slip of Coulomb
// contacts (run_stick_slip.cpp), samples (run_output.cpp); the settings are checked in
// settings_check.cpp.
#include "ukdyn/simulation/simulate.hpp"

#include "ukdyn/simulation/options.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>

#include "dynamics/internal.hpp"
#include "simulation/contact_events.hpp"
#include "simulation/energy_balance.hpp"
#include "simulation/initial_check.hpp"
#include "simulation/integrator.hpp"
#include "simulation/observed_run.hpp"
#include "simulation/run.hpp"
#include "simulation/sample_grid.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"

namespace ukdyn {

namespace detail {
namespace {

// stick/slip transitions after which a run is declared chattering
constexpr long kMaxEvents = 100000;
// characters of BDF's failure quoted in the note of a fallback
constexpr std::size_t kFallbackQuote = 160;

// Whether a run goes on with an explicit method after BDF failed with r (x the state BDF left,
// its last accepted one): its Newton iteration left the model's domain, or its steps collapsed
// (CVODE's error test or convergence failures), at a finite state. Not after a stop on request,
// at the run's step limit (`exhausted`), or when a hook (drift control, the sample sink) failed.
bool bdf_fallback(const detail::SegmentResult& r, const std::vector<double>& x, bool exhausted) {
  if (exhausted || r.status == Status::kInterrupted || r.message.empty()) return false;
  if (r.message.find("step limit") != std::string::npos) return false;
  return std::all_of(x.begin(), x.end(), [](double v) { return std::isfinite(v); });
}

// the explicit method after a BDF failure: the run's own method when BDF came from the
// stiffness switch; for a run asked of BDF, rkf78 at tight tolerances (rtol < 1e-7), where its
// 8th order takes far fewer steps, dopri5 otherwise
Integrator fallback_method(const SimulationOptions& o) {
  if (o.integrator != Integrator::kBDF) return o.integrator;
  return o.rtol < 1e-7 ? Integrator::kRKF78 : Integrator::kDopri5;
}

// the conflict of the initial state's constraints: at the state the position projection reaches
// from (q, q') (the least violation, Gauss–Newton), when that projection does not converge
ConstraintConflict initial_conflict(const System& sys, Workspace& ws,
                                    const Eigen::Ref<const VectorXd>& q,
                                    const Eigen::Ref<const VectorXd>& qd,
                                    const SimulationOptions& o) {
  VectorXd qp = q;
  const ProjectionResult rp = project_positions(sys, ws, qp, o.t_start, o.projection);
  if (rp.status != Status::kOk) return {};
  VectorXd qdp = qd;
  const ProjectionResult rv = project_velocities(sys, ws, qp, qdp, o.t_start, o.projection);
  if (rp.converged && rv.converged) return {};
  return find_constraint_conflict(sys, ws, qp, rp.converged ? Eigen::Ref<const VectorXd>(qdp) : qd,
                                  o.t_start, o.projection.tolerance);
}

// one line per constraint whose violation exceeds tol (after evaluate_violations); their names
// in `names` when given
std::vector<std::string> violated(const System& sys, const Workspace& ws, double tol,
                                  std::vector<std::string>* names = nullptr) {
  std::vector<std::string> lines;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const double p = position_violation(sys, ws, k), v = velocity_violation(sys, ws, k);
    // each row against the tolerance times its scale (Workspace::phi_scale)
    bool bad = false;
    for (Index i = sys.row_offset(k); i < sys.row_offset(k) + sys.constraint(k).rows(); ++i) {
      bad = bad || std::abs(ws.phi[i]) > tol * ws.phi_scale[i] ||
            std::abs(ws.phi_dot[i]) > tol * ws.phi_dot_scale[i];
    }
    if (bad) {
      if (names) names->push_back(sys.constraint(k).name());
      lines.push_back("constraint '" + sys.constraint(k).name() + "' (" +
                      to_string(sys.constraint(k).kind()) + "): position violation " + format(p) +
                      ", velocity violation " + format(v));
    }
  }
  return lines;
}

std::string join_lines(const std::vector<std::string>& lines) { return join(lines, "; "); }

}  // namespace
}  // namespace detail

std::string user_message(const std::exception& e) {
  std::string message = e.what();
  const std::string prefix = "ukdyn::simulate: ";
  if (message.rfind(prefix, 0) == 0) message.erase(0, prefix.size());
  return message;
}

std::vector<std::string> detail::check_initial_conditions(
    const System& sys, const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
    double t, double tolerance, double duration, std::vector<std::string>* names,
    const std::vector<bool>& angle_coordinates) {
  Workspace ws(sys);
  // the scales a run from this state takes (simulate's own check compares against the same)
  set_run_scales(sys, ws, q, qd, t, duration, angle_coordinates);
  detail::release_open_contacts(sys, ws, q, qd, t);  // (an open gap is no violation)
  evaluate_violations(sys, ws, q, qd, t);
  return detail::violated(sys, ws, tolerance, names);
}

std::vector<std::string> check_initial_conditions(const System& sys,
                                                  const Eigen::Ref<const VectorXd>& q,
                                                  const Eigen::Ref<const VectorXd>& qd, double t,
                                                  double tolerance) {
  return detail::check_initial_conditions(sys, q, qd, t, tolerance, 0.0);
}

Trajectory simulate(const System& sys, const Eigen::Ref<const VectorXd>& q0,
                    const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& given) {
  return detail::simulate_observed(sys, q0, qd0, given, {});
}

Trajectory detail::simulate_observed(const System& sys, const Eigen::Ref<const VectorXd>& q0,
                                     const Eigen::Ref<const VectorXd>& qd0,
                                     const SimulationOptions& given,
                                     const std::function<void(const Workspace&)>& finished) {
  return simulate_observed(sys, q0, qd0, given, finished, {});
}

Trajectory detail::simulate_observed(const System& sys, const Eigen::Ref<const VectorXd>& q0,
                                     const Eigen::Ref<const VectorXd>& qd0,
                                     const SimulationOptions& given,
                                     const std::function<void(const Workspace&)>& finished,
                                     const std::function<void(Workspace&)>& started,
                                     double rate_unit, Quadratures* quad) {
  validate(sys, q0, qd0, given);
  check_settings(sys, given);
  // an rtol below roundoff is raised to the smallest one that means anything (with a note)
  SimulationOptions o = given;
  std::string rtol_note;
  if (o.rtol < kMinimumRtol) {
    rtol_note = "rtol = " + format(given.rtol) +
                " is below the roundoff of double: the run uses "
                "rtol = " +
                format(kMinimumRtol) + " (kMinimumRtol, 100 eps)";
    o.rtol = kMinimumRtol;
  }
  // the sample times, refused now if too many
  const detail::SampleGrid samples = sample_grid(sys, o);
  const auto wall_start = std::chrono::steady_clock::now();
  Trajectory traj;
  traj.coordinate_names = sys.coordinate_names();
  for (const auto& c : sys.constraints()) {
    if (c.is_unilateral()) traj.unilateral.push_back(Index(traj.constraint_names.size()));
    traj.constraint_names.push_back(c.name());
    traj.constraint_rows.push_back(c.rows());
    traj.constraint_kinds.push_back(c.kind());
  }
  traj.n = sys.coordinate_count();
  traj.m = sys.constraint_rows();
  if (!rtol_note.empty()) traj.stats.notes.push_back(rtol_note);
  if (quad != nullptr) quad->sample.assign(std::size_t(quad->count), 0.0);
  Run run(sys, o, traj, finished, quad);
  Workspace& ws = run.workspace();
  if (started) {
    started(ws);
    run.set_started(started);  // (and the workspaces the run makes later)
  }
  const Index n = sys.coordinate_count();

  // initial conditions: consistent, or projected on request (constraints that contradict each
  // other are named: no projection helps); the unilateral contacts open or closed first
  VectorXd q = q0, qd = qd0;
  // the scales of the tolerances on the constraints' violations and of the work channels
  // (relative, unit-free)
  set_run_scales(sys, ws, q, qd, o.t_start, o.t_end - o.t_start, o.angle_coordinates);
  if (rate_unit > 0.0) {
    ws.rate_unit = rate_unit;  // (a controlled plant's: observed_run.hpp)
  } else if (q.size() == 0 || !(q.cwiseAbs().maxCoeff() > 0.0)) {
    // a state without length (a robot at its neutral pose): the rate unit of the model's time
    // unit, 1/s, in it (at most 1: 1e-3 per ms), so that the same model in ms runs the steps it
    // runs in s (docs/simulation.md, "The integrators' atol")
    ws.rate_unit = std::min(1.0, o.units.seconds());
  }
  // (x = [q; q'; W; z], WorkLayout)
  const detail::WorkLayout layout(sys, true, quad);
  detail::ContactEvents contacts(sys, ws, std::size_t(2 * n + layout.count), o.t_end - o.t_start);
  contacts.set_units(o.units);
  if (o.integrator == Integrator::kBDF) contacts.set_flight_tolerance(o.rtol);
  // (false: a gap not finite at the start, reported below as the run's status)
  bool contacts_started = true;
  if (contacts.any()) {
    contacts_started = contacts.start(o.t_start, q, qd, o.initial_tolerance, traj.stats);
    run.set_contacts(&contacts);
    contacts.set_held(
        [&run](Index k, double t, const double* x) { return run.holds_pushing(k, t, x); });
  }
  evaluate_violations(sys, ws, q, qd, o.t_start);
  std::vector<std::string> bad_names;
  if (auto bad = violated(sys, ws, o.initial_tolerance, &bad_names); !bad.empty()) {
    if (const auto c = initial_conflict(sys, ws, q, qd, o); c.found) {
      throw InconsistentInitialState(InconsistentInitialState::Cause::kContradictory,
                                     "ukdyn::simulate: " + describe_conflict(c, o.t_start),
                                     c.names);
    }
    if (!o.project_initial) {
      throw InconsistentInitialState(
          InconsistentInitialState::Cause::kNotProjected,
          "ukdyn::simulate: inconsistent initial conditions at t = " + format(o.t_start) + ": " +
              join_lines(bad) + " (set project_initial to project them onto the constraints)",
          bad_names);
    }
    ProjectionOptions all = o.projection;
    const auto rp = project_positions(sys, ws, q, o.t_start, all);
    const auto rv = project_velocities(sys, ws, q, qd, o.t_start, all);
    evaluate_violations(sys, ws, q, qd, o.t_start);
    bad_names.clear();
    bad = violated(sys, ws, o.initial_tolerance, &bad_names);
    if (!rp.converged || !rv.converged || !bad.empty()) {
      throw InconsistentInitialState(
          InconsistentInitialState::Cause::kProjectionFailed,
          "ukdyn::simulate: no consistent initial state near the one given: after projection " +
              (bad.empty() ? std::string("the iteration did not converge") : join_lines(bad)),
          bad_names);
    }
  }

  // x = [q; q'; W; z] (the work channels start at 0, the quadratures at theirs)
  std::vector<double> x(std::size_t(2 * n + layout.count), 0.0);
  Eigen::Map<VectorXd>(x.data(), n) = q;
  Eigen::Map<VectorXd>(x.data() + n, n) = qd;
  if (layout.quadrature >= 0) {
    std::copy(quad->z0.begin(), quad->z0.end(), x.begin() + 2 * n + layout.quadrature);
  }

  // (quiet work channels for the explicit integrators; stage states violated beyond the
  // projection tolerance may take the least-squares q'')
  detail::ConstrainedOde ode(sys, ws, o.integrator != Integrator::kBDF, o.projection.tolerance,
                             quad);
  // the contacts' release and slip screening at every stage (docs/contact.md, "In a run")
  if (contacts.any()) ode.watch_releases(&contacts);
  if (std::any_of(sys.friction_contacts().begin(), sys.friction_contacts().end(),
                  [](const auto& c) { return c.mu_static > 0.0; })) {
    ode.set_screen([&run](double t, const double* xs) {
      run.screen_sticking(t, xs);
      run.screen_stops();
    });
  }
  detail::SegmentHooks hooks;
  hooks.after_step = [&](double t, double* xs, bool& changed) {
    return run.after_step(t, xs, changed);
  };
  hooks.output = [&](double t, const double* xs) { return run.record(t, xs); };
  if (run.projecting()) {
    hooks.project_error = [&](double t, const double* xs, double* err) {
      return run.project_error(t, xs, err);
    };
    hooks.project_stage = [&](double t, double* xs) { return run.project_stage(t, xs); };
  }
  const std::vector<double> ends = segment_ends(sys, o);
  // (constraints released or activated inside the run: a step into a dead centre at such a
  // breakpoint is bridged across it, see Run::entered_dead_centre)
  bool activity_changes = false;
  for (std::size_t i = 0; i + 2 < ends.size(); ++i) {
    const double m0 = 0.5 * (ends[i] + ends[i + 1]), m1 = 0.5 * (ends[i + 1] + ends[i + 2]);
    for (Index k = 0; k < sys.constraint_count(); ++k) {
      if (sys.constraint(k).is_active(m0) != sys.constraint(k).is_active(m1)) {
        activity_changes = true;
      }
    }
  }
  // (Coulomb contacts, all with mu = 0: no carry-through of theirs at a dead centre, whose
  // entries are bridged as a run with switches bridges them, see Run::entered_dead_centre)
  const bool frictionless =
      !sys.friction_contacts().empty() &&
      std::all_of(sys.friction_contacts().begin(), sys.friction_contacts().end(),
                  [](const auto& c) { return c.mu_static == 0.0; });
  if (!sys.friction_contacts().empty() || run.locates_switches() || activity_changes) {
    hooks.find_event = [&](double t0, const double* x0, double t1, const double* x1,
                           const detail::SegmentHooks::Dense& dense) {
      return run.find_event(t0, x0, t1, x1, dense);
    };
  }
  // unilateral contacts (docs/contact.md): their first impact or release, and the other events
  // up to it
  bool contact_event = false;
  std::vector<double> x_contact(x.size());
  if (contacts.any()) {
    hooks.find_event = [&, others = hooks.find_event](double t0, const double* x0, double t1,
                                                      const double* x1,
                                                      const detail::SegmentHooks::Dense& dense) {
      contact_event = false;
      const double tc = contacts.find(t0, x0, t1, x1, dense);
      if (std::isnan(tc)) return others ? others(t0, x0, t1, x1, dense) : tc;
      if (others) {
        dense(tc, x_contact.data());
        if (const double te = others(t0, x0, tc, x_contact.data(), dense); !std::isnan(te))
          return te;
      }
      contact_event = true;
      return tc;
    };
  }

  run.set_samples(samples);
  auto finish = [&](Status status, const std::string& message, double t_reached) {
    // the sink's exception, once the integrator has returned
    if (run.sink_error()) {
      std::fill(ws.activity_override.begin(), ws.activity_override.end(), -1);
      std::rethrow_exception(run.sink_error());
    }
    traj.stats.status = status;
    traj.stats.message = message;
    if (status == Status::kInterrupted && message.empty()) {
      traj.stats.message = "interrupted at t = " + format(t_reached) + " " + o.units.time +
                           ": the run was stopped on request; the samples up to there are kept";
    }
    traj.stats.t_reached = t_reached;
    unmeasured_violations(sys, traj.stats);
    unsettled_reactions(sys, ws, o.units, traj.stats);
    traj.stats.evaluations = ode.evaluations();
    traj.stats.least_squares = ode.least_squares();
    // the energy balance certifies a run that reached its end
    // (a system that does not account for its forces' work is reported, not checked)
    const double tolerance = sys.accounts_for_energy() ? checked_energy_balance_tolerance(o)
                                                       : std::numeric_limits<double>::infinity();
    if (o.sample_sink) {
      run.balance().finish(traj.stats, tolerance, o.units);
    } else {
      compute_energy_balance(traj, tolerance, o.units);
    }
    traj.stats.wall_time =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    std::fill(ws.activity_override.begin(), ws.activity_override.end(), -1);
    return traj;
  };

  if (!contacts_started) return finish(contacts.failure_status(), contacts.failure(), o.t_start);

  // (CVODE estimates its own first step, which on stiff problems can be far below o.step)
  double first_step = o.integrator == Integrator::kBDF ? 0.0 : o.step;
  // after BDF failed (see bdf_fallback): the explicit method the run goes on with, and its
  // options (no stiffness switch)
  Integrator base_method = o.integrator;
  std::optional<SimulationOptions> fallback_options;
  // BDF's failure that the fallback started from: its status, message and time
  Status bdf_status = Status::kOk;
  std::string bdf_message;
  double bdf_time = 0.0;
  std::vector<double> x_start;       // (2n + 1) the state where the integrator last started
  double a_start = o.t_start;        // its time (both: other than at an event)
  bool after_event = false;          // the integrator restarts at an event
  std::vector<double> nudge, trial;  // (size of x) f and the state past a switch event
  std::size_t next_sample = 0;
  // a restart at a dead centre bridged past it (Run::bridge_dead_centre): at most this long;
  // the samples it steps over, in (from, to], from the bridge's formula (false: recording failed,
  // with the status and time)
  const double bridge_limit = 1e-3 * (o.t_end - o.t_start);
  // (from outside the pose's neighbourhood, q'' linear between the bridge's ends: a slow
  // passage's, as the twin arms' swing of 0.005 rad, takes up to 5e-3 s of 3 s)
  const double entry_limit = 1e-2 * (o.t_end - o.t_start);
  Status bridge_status = Status::kOk;
  double bridge_time = 0.0;
  std::vector<double> x_bridged(x.size());
  auto record_bridged = [&](double from, double to) {
    for (; next_sample < samples.size() && samples[next_sample] <= to; ++next_sample) {
      if (samples[next_sample] <= from) continue;
      run.bridged_state(samples[next_sample], x_bridged.data());
      if (const Status s = run.record(samples[next_sample], x_bridged.data()); s != Status::kOk) {
        bridge_status = s;
        bridge_time = samples[next_sample];
        return false;
      }
    }
    return true;
  };
  run.initial_contact_modes(o.t_start, x.data());
  run.initial_switch_sides(o.t_start, x.data());
  // where the next segment starts when a bridge crossed its start (else -inf)
  double resume = -std::numeric_limits<double>::infinity();
  // the constraints of segment seg: those active in its interior
  auto activate = [&](std::size_t seg) {
    const double mid = 0.5 * (ends[seg] + ends[seg + 1]);
    for (Index k = 0; k < sys.constraint_count(); ++k) {
      ws.activity_override[std::size_t(k)] = sys.constraint(k).is_active(mid) ? 1 : 0;
    }
    run.apply_contact_modes();
    if (contacts.any()) contacts.apply();
    const double inf = std::numeric_limits<double>::infinity();
    ode.set_window(seg == 0 ? -inf : ends[seg], seg + 2 == ends.size() ? inf : ends[seg + 1]);
  };
  for (std::size_t seg = 0; seg + 1 < ends.size(); ++seg) {
    double a = ends[seg];
    const double b = ends[seg + 1];
    // its constraints, contact modes and evaluation window (evaluations at a breakpoint end
    // are one-sided; the run's own ends are not breakpoints)
    activate(seg);
    run.set_bridging_entries(run.locates_switches() || activity_changes || frictionless);
    // a constraint that switches on finds the state inconsistent: project onto it (at a dead
    // centre, bridged past it instead: Run::bridge_dead_centre)
    bool changed = false;
    if (resume > a) {
      // (a bridge across this segment's start from inside the one before: landed here)
      a = resume;
    } else if (seg > 0 && sys.constraint_count() > 0) {
      Status s = Status::kOk;
      if (const double past = run.bridge_dead_centre(a, b, bridge_limit, x.data(), ode, s);
          s == Status::kOk && past > a) {
        if (!record_bridged(a, past)) return finish(bridge_status, run.failure(), bridge_time);
        a = past;
      } else if (s == Status::kOk) {
        ProjectionOptions all = o.projection;
        s = run.project(a, x.data(), all, changed);
      }
      if (s != Status::kOk) {
        return finish(s, run.failure().empty() ? describe_status(sys, ws) : run.failure(), a);
      }
    }
    // the sample at the start of the run
    if (seg == 0 && next_sample < samples.size() && samples[next_sample] == a) {
      if (const Status s = run.record(a, x.data()); s != Status::kOk) {
        return finish(s, run.failure(), a);
      }
      ++next_sample;
    }
    // [a, b], restarted after every stick/slip event and stiffness switch; the segment starts
    // with the chosen method, and goes on with BDF once dopri5 finds it stiff until the next
    // event (a switch of the dynamics) or the segment's end
    Integrator method = base_method;
    after_event = false;     // (an event at the last segment's end b does not carry over)
    bool crossing = false;   // dopri5 across a singular configuration for BDF
    bool r_crossed = false;  // the last segment was such a crossing
    // BDF restarts after a contact's impact or release with CVODE's own first step: the last
    // step before it can span a whole flight after it (a ball's last bounces, 1e-6 s), whose
    // impact the first-order interpolant of that one step then misplaces (located where the
    // chord crosses, still rising) and the restart there finds it again, step after step
    bool contact_restart = false;
    for (;;) {
      const detail::SampleTimes outputs(samples, next_sample, samples.upper_bound(b));
      const bool switched =
          method == Integrator::kBDF && base_method != Integrator::kBDF && !crossing;
      const SimulationOptions& om = fallback_options ? *fallback_options : o;
      // (a restart at an event keeps the state before it: the event may sit at the
      // configuration that makes the steps collapse, a dead centre)
      if (!after_event) {
        x_start = x;
        a_start = a;
      }
      after_event = false;
      run.set_integrator(method);
      run.arm_stops(a, x.data());
      hooks.cross_singular = crossing;
      hooks.max_steps = o.max_steps - traj.stats.steps;  // (> 0: checked after each segment)
      // (after a switch CVODE estimates its own first step: dopri5's last one is stability-bound)
      detail::SegmentResult r =
          method == Integrator::kBDF
              ? detail::integrate_bdf(ode, x, a, b, outputs, om, hooks,
                                      switched || r_crossed || contact_restart ? 0.0 : first_step)
              : detail::integrate_explicit(method, ode, x, a, b, outputs, om, hooks, first_step);
      contact_restart = false;
      traj.stats.steps += r.steps;
      traj.stats.rejected_steps += r.rejected;
      traj.stats.tangential_steps += r.tangential_steps;
      traj.stats.projected_stage_steps += r.projected_stage_steps;
      if (switched) traj.stats.stiff_steps += r.steps;
      // (the fixed-step methods keep o.step)
      const bool fixed = method == Integrator::kRK4 || method == Integrator::kRK5;
      if (r.last_step > 0 && !fixed) first_step = r.last_step;
      next_sample = std::max(next_sample, samples.upper_bound(r.t_reached));
      if (r.status == Status::kInterrupted) {
        // stopped on request: at a sample (recorded), or after a step, where x is the state at
        // r.t_reached (after drift control; BDF: its last accepted step), recorded as the last
        if (run.recorded() == 0 || r.t_reached > run.last_time()) {
          if (const Status s = run.record(r.t_reached, x.data(), true); s != Status::kOk) {
            return finish(s, run.failure(), r.t_reached);
          }
        }
        return finish(Status::kInterrupted, "", run.last_time());
      }
      if (r.status != Status::kOk) {
        std::string message = r.message;
        if (message.empty()) message = run.failure();
        if (message.empty()) message = describe_status(sys, ws);
        // BDF gave up (its Newton iteration left the model's domain, or its steps collapsed):
        // an explicit method goes on from BDF's last accepted state, once per run, and the
        // notes say so
        if (method == Integrator::kBDF && !fallback_options &&
            bdf_fallback(r, x, traj.stats.steps >= o.max_steps || run.sink_error())) {
          bdf_status = r.status;
          bdf_message = message;
          bdf_time = r.t_reached;
          fallback_options = o;
          fallback_options->stiff_switch = false;
          base_method = fallback_method(o);
          traj.stats.notes.push_back(
              "t = " + format(r.t_reached) + ": bdf" +
              (o.integrator == Integrator::kBDF ? std::string()
                                                : " (after the stiffness switch at t = " +
                                                      format(traj.stats.stiff_switch_time) + ")") +
              " failed (" + message.substr(0, kFallbackQuote) +
              (message.size() > kFallbackQuote ? "…" : "") + "); the run went on with " +
              to_string(base_method) + " without the stiffness switch");
          ode.clear_failure();
          method = base_method;
          // (BDF may have failed before accepting a step: the explicit method needs a first
          // step; and the restart keeps the reference state of the collapse diagnosis, as an
          // event's restart does)
          if (!(first_step > 0.0)) first_step = o.step;
          after_event = true;
          crossing = false;
          r_crossed = false;
          a = r.t_reached;
          continue;
        }
        // the explicit method got no further than BDF, out of the model's domain as BDF was
        // (the solution reaches the domain's boundary; the two may name different checks of M):
        // BDF's report stands, the note says the rest
        if (fallback_options && bdf_status != Status::kIntegratorFailure &&
            r.status != Status::kIntegratorFailure &&
            r.t_reached - bdf_time <= 1e-9 * std::max(1.0, std::abs(bdf_time))) {
          return finish(bdf_status, bdf_message, bdf_time);
        }
        // the step limit is no collapse (u19 01: a steady 6.3e-3 s step over 1e5 steps was
        // diagnosed as one): the mean step is said instead
        const bool step_limit =
            r.status == Status::kIntegratorFailure &&
            (traj.stats.steps >= o.max_steps || message.find("step limit") != std::string::npos);
        if (step_limit) {
          message += " (the run's limit max_steps = " + format_number(o.max_steps) +
                     " accepted steps, a mean step of " +
                     format((r.t_reached - o.t_start) / double(std::max(1L, traj.stats.steps))) +
                     " " + o.units.time + "; raise it: " + kRaiseMaxSteps + ")";
        }
        if (r.status == Status::kIntegratorFailure && detail::step_collapsed(r)) {
          std::string divergence;
          const std::string cause =
              run.diverged(r.t_reached, x.data(), divergence)
                  ? "Likely cause: " + divergence
                  : detail::diagnose_collapse(sys, ws, o, method, r, x, x_start, a_start,
                                              traj.stats, step_limit);
          if (!cause.empty()) message += ". " + cause;
        }
        return finish(r.status, message, r.t_reached);
      }
      if (r.singular || r.crossed) {
        // BDF before a singular configuration: dopri5 (projected stages) across it, then BDF
        crossing = r.singular;
        r_crossed = r.crossed;
        method = r.singular ? Integrator::kDopri5 : Integrator::kBDF;
        a = r.t_reached;
        continue;
      }
      r_crossed = false;
      // the run's step limit, reached exactly at the end of a segment that goes on
      if (traj.stats.steps >= o.max_steps && r.t_reached < o.t_end) {
        return finish(Status::kIntegratorFailure,
                      std::string(to_string(method)) +
                          ": step limit reached at t = " + format(r.t_reached) +
                          " (the run's limit max_steps = " + format_number(o.max_steps) +
                          " accepted steps; raise it: " + kRaiseMaxSteps + ")",
                      r.t_reached);
      }
      if (r.stiff) {
        // dopri5 found the problem stiff: BDF from here
        if (traj.stats.stiff_switches++ == 0) traj.stats.stiff_switch_time = r.t_reached;
        method = Integrator::kBDF;
        a = r.t_reached;
        continue;
      }
      if (!r.event) break;
      if (run.hands_over()) {
        // rkf78 at a dead centre where a Coulomb contact slides: dopri5 from here, which carries
        // the contact through it (Run::hands_over)
        base_method = Integrator::kDopri5;
        if (traj.stats.notes.size() < kMaxNotes) {
          traj.stats.notes.push_back(
              "t = " + format(r.t_reached) +
              ": rkf78 handed the run to dopri5 at a dead centre, where a Coulomb contact slides "
              "while the constraints nearly lose rank (rkf78's restarts there can leave the "
              "mechanism's branch; docs/friction.md, \"Dead centres\")");
        }
        method = base_method;
        a = r.t_reached;
        continue;
      }
      method = base_method;
      after_event = true;
      if (contact_event) {
        // a unilateral contact's impact or release: the velocity jump and the closed set (then
        // the Coulomb contacts' modes; their sticks and slips listed after it)
        run.before_mode_change(x.data());
        if (!contacts.handle(r.t_reached, x.data(), traj.stats)) {
          return finish(contacts.failure_status(), contacts.failure(), r.t_reached);
        }
        run.contacts_changed(r.t_reached, x.data());
        run.list_mode_changes(r.t_reached, x.data());
        contact_restart = true;
        if (const Status s = run.project_drift(r.t_reached, x.data()); s != Status::kOk) {
          return finish(s, run.failure().empty() ? describe_status(sys, ws) : run.failure(),
                        r.t_reached);
        }
        a = r.t_reached;
        if (!(a < b)) break;
        continue;
      }
      if (run.entered_dead_centre()) {
        // a step of dopri5 or BDF ended inside a dead centre's neighbourhood: bridged past the
        // pose from there (Run::entered_dead_centre), the switches it steps over take their
        // new sides; else (no landing within reach) the run goes on from there
        Status s = Status::kOk;
        a = run.bridge_dead_centre(r.t_reached, b, entry_limit, x.data(), ode, s, true);
        // (at a breakpoint where constraints are released or activated: across it, with the
        // next segment's constraints, landing past it)
        if (s == Status::kOk && a == r.t_reached && activity_changes && seg + 2 < ends.size() &&
            b - a < bridge_limit) {
          activate(seg + 1);
          a = run.bridge_dead_centre(r.t_reached, ends[seg + 2], bridge_limit, x.data(), ode, s,
                                     true, b);
          if (s == Status::kOk && a > b) {
            if (!record_bridged(r.t_reached, a)) {
              return finish(bridge_status, run.failure(), bridge_time);
            }
            resume = a;
            break;
          }
          activate(seg);
        }
        if (s == Status::kOk && a > r.t_reached) {
          if (!record_bridged(r.t_reached, a)) {
            return finish(bridge_status, run.failure(), bridge_time);
          }
          traj.stats.switch_events += long(run.sides_after_bridge(a, x.data()));
        } else if (s == Status::kOk) {
          s = run.project_drift(r.t_reached, x.data());
        }
        if (s != Status::kOk) {
          return finish(s, run.failure().empty() ? describe_status(sys, ws) : run.failure(),
                        r.t_reached);
        }
        if (!(a < b)) break;
        continue;
      }
      if (run.switch_event() && run.switch_approach()) {
        // on the way to a switch: restarted clearly before it, the next step finds it again
        a = r.t_reached;
        continue;
      }
      if (run.switch_event()) {
        // a non-smooth function switches: go on from there, on its other side (drift control
        // first: the state at the event is a step's, not yet projected)
        if (!run.switch_crawls()) ++traj.stats.switch_events;
        std::string chatter;
        if (run.switch_chatters(r.t_reached, chatter)) {
          return finish(Status::kIntegratorFailure, chatter, r.t_reached);
        }
        // (at a dead centre: bridged past it, Run::bridge_dead_centre)
        Status s = Status::kOk;
        a = run.bridge_dead_centre(r.t_reached, b, bridge_limit, x.data(), ode, s);
        if (s == Status::kOk && a > r.t_reached) {
          if (!record_bridged(r.t_reached, a)) {
            return finish(bridge_status, run.failure(), bridge_time);
          }
        } else if (s == Status::kOk) {
          s = run.project_drift(r.t_reached, x.data());
        }
        if (s != Status::kOk) {
          return finish(s, run.failure().empty() ? describe_status(sys, ws) : run.failure(),
                        r.t_reached);
        }
        // the restart state lies just before the switch (every stage of the step to it on the
        // old side); the next step's first stage must see the new side: x ← x + δ f(a, x), δ
        // from the bracket's width, doubled until the switched functions are across (an error
        // O(δ · jump), δ ~ 1e-14 |t|)
        if (!run.switch_settled(a, x.data())) {
          nudge.resize(x.size());
          trial.resize(x.size());
          if (ode(x.data(), nudge.data(), a)) {
            double delta = std::max(run.switch_width(), 1e-15 * std::max(1.0, std::abs(a)));
            for (int k = 0; k < 40 && a + delta < b; ++k, delta *= 2.0) {
              for (std::size_t i = 0; i < x.size(); ++i) trial[i] = x[i] + delta * nudge[i];
              if (run.switch_settled(a + delta, trial.data())) {
                x.swap(trial);
                a += delta;
                break;
              }
            }
          } else {
            ode.clear_failure();
          }
          // samples stepped over by the nudge, from its state
          for (; next_sample < samples.size() && samples[next_sample] <= a; ++next_sample) {
            if (samples[next_sample] <= r.t_reached) continue;
            if (const Status rs = run.record(samples[next_sample], x.data()); rs != Status::kOk) {
              return finish(rs, run.failure(), samples[next_sample]);
            }
          }
        }
        if (!(a < b)) break;
        continue;
      }
      // a contact sticks or slips: switch it and go on from there (but not forever)
      if (traj.stats.events >= kMaxEvents) {
        return finish(Status::kIntegratorFailure,
                      "stick/slip: more than " + format_number(kMaxEvents) +
                          " transitions (chattering) by t = " + format(r.t_reached),
                      r.t_reached);
      }
      run.before_mode_change(x.data());
      if (const Status s = run.switch_contact(r.t_reached, x.data()); s != Status::kOk) {
        return finish(s, run.failure().empty() ? describe_status(sys, ws) : run.failure(),
                      r.t_reached);
      }
      run.list_mode_changes(r.t_reached, x.data());
      a = r.t_reached;
      if (!(a < b)) break;
    }
  }
  return finish(Status::kOk, "", o.t_end);
}

}  // namespace ukdyn

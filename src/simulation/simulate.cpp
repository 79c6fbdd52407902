// SPDX-License-Identifier: BSD-3-Clause
// simulate(): the driver of a run. Splits [t_start, t_end] at breakpoints (the ends of
// constraint intervals and those the user gives), integrates each segment with the chosen method,
// applies drift control after every accepted step, and records samples.
#include "ukdyn/simulation/simulate.hpp"

#include "ukdyn/simulation/options.hpp"

#include <Eigen/QR>

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
#include "simulation/sample_grid.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"

namespace ukdyn {

const char* to_string(Integrator integrator) {
  switch (integrator) {
    case Integrator::kRK4:
      return "rk4";
    case Integrator::kRK5:
      return "rk5";
    case Integrator::kDopri5:
      return "dopri5";
    case Integrator::kRKF78:
      return "rkf78";
    case Integrator::kBDF:
      return "bdf";
  }
  return "unknown";
}

Integrator integrator_from_string(const std::string& name) {
  for (Integrator i : {Integrator::kRK4, Integrator::kRK5, Integrator::kDopri5, Integrator::kRKF78,
                       Integrator::kBDF}) {
    if (name == to_string(i)) return i;
  }
  throw std::invalid_argument("ukdyn: unknown integrator '" + name +
                              "'; the integrators are rk4, rk5, dopri5, rkf78, bdf");
}

double checked_energy_balance_tolerance(const SimulationOptions& o) {
  constexpr double kBalancePerRtol = 1e3;
  const bool adaptive = o.integrator == Integrator::kDopri5 || o.integrator == Integrator::kRKF78 ||
                        o.integrator == Integrator::kBDF;
  return adaptive ? std::max(o.energy_balance_tolerance, kBalancePerRtol * o.rtol)
                  : o.energy_balance_tolerance;
}

const char* to_string(DriftControl drift) {
  switch (drift) {
    case DriftControl::kNone:
      return "none";
    case DriftControl::kBaumgarte:
      return "baumgarte";
    case DriftControl::kProjection:
      return "projection";
  }
  return "unknown";
}

DriftControl drift_from_string(const std::string& name) {
  for (DriftControl d :
       {DriftControl::kNone, DriftControl::kBaumgarte, DriftControl::kProjection}) {
    if (name == to_string(d)) return d;
  }
  throw std::invalid_argument("ukdyn: unknown drift control '" + name +
                              "'; the choices are none, baumgarte, projection");
}

namespace {

// stick/slip transitions after which a run is declared chattering
constexpr long kMaxEvents = 100000;
// notes a run keeps (RunStatistics::notes)
constexpr std::size_t kMaxNotes = 20;
// a run is declared chattering at a switch (SimulationOptions::switch_events) when kSwitchBurst
// switch events, or kSwitchBurst accepted steps after one (any steps: into, at or between
// switches), fall within kSwitchBurstSpan of the run's time span
constexpr std::size_t kSwitchBurst = 1000;
constexpr double kSwitchBurstSpan = 1e-6;
// the step into a switch below which the run restarts at the switch (see Run::find_event)
constexpr double kSwitchApproach = 1e-10;
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
// a run diverges when its kinetic energy exceeds kDivergence times the model's energy scale,
// T + |V| at its start (Run::diverged): the speeds then exceed the initial ones by 10⁴ and more.
// It stops there once kDivergentSteps steps in a row have done so at a pace that cannot reach
// t_end within max_steps (Run::diverges).
constexpr double kDivergence = 1e8;
constexpr int kDivergentSteps = 3;
// a contact carried through a dead centre restarts past it where the rank margin is back to
// this (Run::carried_past)
constexpr double kCarriedMargin = 3e-5;
// below this rank margin (Workspace::rank_margin, σ_r / σ_1 of W) growing speeds are those of a
// configuration where the constraints lose rank, not a divergence
constexpr double kDivergenceRankMargin = 1e-3;

// What a Coulomb contact does: slides (friction acts), sticks (the stick constraint acts), or
// slides through a zero of v_rel at which it could not stick (the zero is its next event).
enum class ContactMode : unsigned char { kSliding, kSticking, kPassing };

// three significant digits, for messages
std::string format(double v) { return detail::format_short(v); }

// where each front end sets max_steps (the end of every message about the step limit)
const std::string kRaiseMaxSteps =
    "simulate: max_steps in a model file, --max-steps on the command line, max_steps= in Python";

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

// the sizes of q0, qd0 and the per-constraint drift settings (the run's other settings:
// check_settings)
void validate(const System& sys, const Eigen::Ref<const VectorXd>& q0,
              const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& o) {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("ukdyn::simulate: " + what);
  };
  if (q0.size() != sys.coordinate_count() || qd0.size() != sys.coordinate_count()) {
    fail("q0 and qd0 need n = " + format_number(sys.coordinate_count()) + " entries, got " +
         format_number(q0.size()) + " and " + format_number(qd0.size()));
  }
  // a non-finite initial state is misuse, named like forward_dynamics names it
  for (Index i = 0; i < sys.coordinate_count(); ++i) {
    if (std::isfinite(q0[i]) && std::isfinite(qd0[i])) continue;
    const bool in_q = !std::isfinite(q0[i]);
    fail(std::string(in_q ? "q0" : "qd0") + " is not finite at coordinate '" +
         sys.coordinate_names()[std::size_t(i)] + "' (" + format(in_q ? q0[i] : qd0[i]) + ")");
  }
  for (const auto& [name, d] : o.drift_per_constraint) {
    sys.constraint_index(name);  // throws naming the unknown constraint
    if (!(d.alpha >= 0.0 && d.beta >= 0.0 && std::isfinite(d.alpha) && std::isfinite(d.beta))) {
      throw SettingError("drift_per_constraint", "ukdyn::simulate: Baumgarte gains of '" + name +
                                                     "' must be finite and >= 0");
    }
  }
}

// the resolution of the run's times: sorted_times merges samples and segment ends closer than this
double time_resolution(double a, double b) {
  return 1e-12 * std::max({1.0, std::abs(a), std::abs(b)});
}

// sorted, de-duplicated times in [a, b]
std::vector<double> sorted_times(std::vector<double> v, double a, double b) {
  v.erase(std::remove_if(v.begin(), v.end(),
                         [&](double t) { return !(t >= a && t <= b) || !std::isfinite(t); }),
          v.end());
  std::sort(v.begin(), v.end());
  const double eps = 1e-12 * std::max({1.0, std::abs(a), std::abs(b)});
  std::vector<double> out;
  for (double t : v) {
    if (out.empty() || t - out.back() > eps) out.push_back(t);
  }
  return out;
}

// the run's sample times (t_start, every output_every, output_at, t_end), refused above the
// bound of a streamed run, or of one kept in memory (values per sample: t, q, q', q'', Qc_ideal,
// Qc_nonideal, lambda, two violations per constraint, three energies, six works)
detail::SampleGrid sample_grid(const System& sys, const SimulationOptions& o) {
  if (o.sample_sink) {
    return detail::SampleGrid(o, kMaxStreamedSamples, "of a streamed run (kMaxStreamedSamples)");
  }
  const double per_sample = double(1 + 5 * sys.coordinate_count() + sys.constraint_rows() +
                                   2 * sys.constraint_count() + 9);
  const std::string bound = "of a run kept in memory (kMaxStoredValues = 2^28 values, " +
                            format_number(long(per_sample)) +
                            " per sample; a SimulationOptions::sample_sink streams up to 1e9)";
  return detail::SampleGrid(
      o, std::min(kMaxStreamedSamples, std::floor(kMaxStoredValues / per_sample)), bound.c_str());
}

// the segments' ends: t_start, breakpoints inside, t_end
std::vector<double> segment_ends(const System& sys, const SimulationOptions& o) {
  std::vector<double> v = o.breakpoints;
  for (const auto& c : sys.constraints()) {
    v.push_back(c.active_interval().begin);
    v.push_back(c.active_interval().end);
  }
  v.push_back(o.t_start);
  v.push_back(o.t_end);
  return sorted_times(std::move(v), o.t_start, o.t_end);
}

// The solver settings of the integration: the Gauss and virtual-work residuals are not part of a
// trajectory, so they are not computed at every evaluation (the consistency test still is).
SolverOptions integration_options(SolverOptions o) {
  o.compute_residuals = false;
  return o;
}

// Everything a run shares between the integrator's callbacks.
class Run {
 public:
  // a Run is neither copied nor moved (its members refer to each other)
  Run(const Run&) = delete;
  Run& operator=(const Run&) = delete;
  ~Run() {
    if (!finished_) return;
    try {
      finished_(ws_);
    } catch (...) {  // (an observer's failure must not end the program in a destructor)
    }
  }
  // `finished`: called with the workspace when the run ends (detail::simulate_observed)
  Run(const System& sys, const SimulationOptions& o, Trajectory& traj,
      std::function<void(const Workspace&)> finished = {})
      : finished_(std::move(finished)),
        sys_(sys),
        o_(o),
        ws_(sys, integration_options(o.solver)),
        traj_(traj),
        n_(sys.coordinate_count()),
        q_(n_),
        qd_(n_) {
    // a streamed run records each sample into one_, which the sink receives
    if (o.sample_sink) {
      one_.coordinate_names = traj.coordinate_names;
      one_.constraint_names = traj.constraint_names;
      one_.constraint_rows = traj.constraint_rows;
      one_.constraint_kinds = traj.constraint_kinds;
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

  Workspace& workspace() { return ws_; }
  bool projecting() const { return projecting_; }

  // --- Coulomb contacts: stick, slide, or slide through v_rel = 0 (docs/friction.md) ----------
  // the friction force while sliding, the stick constraint while sticking
  void apply_contact_modes() {
    const auto& contacts = sys_.friction_contacts();
    for (std::size_t c = 0; c < contacts.size(); ++c) {
      const bool sticks = mode_[c] == ContactMode::kSticking;
      ws_.nonideal_enabled[std::size_t(contacts[c].force)] = sticks ? 0 : 1;
      ws_.activity_override[std::size_t(contacts[c].stick_constraint)] = sticks ? 1 : 0;
    }
  }

  // initial modes: a contact at rest (|v_rel| <= eps) sticks when sticking is admissible, else it
  // starts to slide with friction against its impending motion
  void initial_contact_modes(double t, double* x) {
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

  // a Coulomb contact whose normal constraint is a unilateral contact that is open: no normal
  // force, so no friction (N = 0), no stick and no stop events (docs/contact.md, "Friction")
  bool separated(std::size_t c) const {
    const Index k = sys_.friction_contacts()[c].normal_constraint;
    return sys_.constraint(k).is_unilateral() && ws_.activity_override[std::size_t(k)] == 0;
  }

  // after an impact or release of unilateral contacts at (t, x): a Coulomb contact whose contact
  // is open slides (its friction is zero while open: a stick constraint would hold it in the
  // air); a closed one that an impact set sliding (|v_rel| > eps while it stuck) slides against
  // its motion; a closed one at rest (|v_rel| <= eps: it closed, or an impact's friction stopped
  // it) sticks when that is admissible, else starts to slide against its impending motion, as at
  // the start of a run
  void contacts_changed(double t, double* x) {
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

  // a contact with mu = mu_static = 0 exerts no friction in any mode: it never sticks, and its
  // stops and reversals are no events (each would restart the integrator for nothing)
  bool frictionless(std::size_t c) const { return sys_.friction_contacts()[c].mu_static == 0.0; }

  // the first switch of a contact inside [t0, t1] (see SegmentHooks::find_event)
  double find_event(double t0, const double* x0, double t1, const double* x1,
                    const detail::SegmentHooks::Dense& dense) {
    const auto& contacts = sys_.friction_contacts();
    double first = std::numeric_limits<double>::quiet_NaN();
    switching_ = -1;
    Index handover = -1;  // the contact whose passage rkf78 hands to dopri5 (see hands_over)
    // the rank margin at (or within the step's last stages before) t1: the step's last evaluation
    const double margin = ws_.rank_margin;
    for (std::size_t c = 0; c < contacts.size(); ++c) {
      if (frictionless(c) || separated(c)) continue;
      double te = std::numeric_limits<double>::quiet_NaN();
      switch (mode_[c]) {
        case ContactMode::kSticking:
          // the holding force reaches mu_static N: mu_static N − |holding force| falls to zero
          te = locate(t0, t1, x1, dense,
                      [&](double t, const double* x) { return stick_margin(c, t, x); });
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
          if (ws_.slip_hint.col(contacts[c].force).squaredNorm() > 0.0)
            set_slip_hint(c, VectorXd());
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
          te = locate(t0, t1, x1, dense, [&](double t, const double* x) {
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
          const Index k = Index(contacts[c].coordinates.size());
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
    hands_over_ = handover >= 0 && switching_ == handover;
    // the first sign change of a switching function, when it comes before the contacts' event
    switch_event_ = false;
    if (!locates_switches()) return first;
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
    const double ts = find_switch(t0, x0, t1, x1, dense, hi);
    approach_ = false;
    if (!std::isnan(ts) && (std::isnan(first) || ts < first)) {
      switch_event_ = true;
      hands_over_ = false;
      // the approach: the restart state at ts comes from one step [t0, ts] whose last stages
      // lie at ts, within their own error of the switch, on either side (rkf78's end-node
      // stages are not exact even for a quadratic motion: an error h·b·jump). So the run first
      // restarts 3/4 of the way, where every stage is clearly on the old side, and finds the
      // switch again from there, until the step to it is below kSwitchApproach (|t| ≥ 1)
      if (ts - t0 > kSwitchApproach * std::max(1.0, std::abs(ts))) {
        approach_ = true;
        return ts - 0.25 * (ts - t0);
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
        const bool flip = m <= 0.0 || landed_;
        flipped_[i] = flip ? 1 : 0;
        if (flip) side_[i] = static_cast<signed char>(-side_[i]);
      }
      return ts;
    }
    if (std::isnan(first)) {
      // no event: a function that was 0 takes the side where the step leaves it
      for (Index i = 0; i < g1_.size(); ++i) {
        if (side_[std::size_t(i)] == 0 && g1_[i] != 0.0)
          side_[std::size_t(i)] = g1_[i] > 0 ? 1 : -1;
      }
    }
    return first;
  }

  // The last event found by find_event is no switch but rkf78 handing the run to dopri5 at the
  // start of the step just taken, which it discards: in that step a Coulomb contact slides into
  // a rank drop (the rank margin at its end below kSingularMargin), or stops where the
  // mechanism passes a dead centre (passes_at_rank_drop). dopri5 and BDF carry such a contact
  // through the dead centre (carry_through); under rkf78 the same treatment, and the earlier one
  // (the stop no restart point), still left the branch at some mu — the twin arms at mu = 0.4–0.5,
  // the governor's swing at 0.3 and 0.5, once with status ok (docs/reliability.md) — so the run
  // goes on with dopri5 from the step's start, before the dead centre, and the notes say so.
  bool hands_over() const { return hands_over_; }

  // drift control at a restart after a switch event (the state there is a step's, not yet
  // projected)
  Status project_drift(double t, double* x) {
    bool changed = false;
    return projecting_ ? project(t, x, projection_, changed) : Status::kOk;
  }

  // --- switches of the non-smooth functions (System::switch_count, docs/simulation.md) -------
  // the width of the last switch's bracket (the restart is at its old end)
  double switch_width() const { return switch_width_; }
  // true when every function that switched at the last switch event is on its new side at
  // (t, x): side_i g_i > 0
  bool switch_settled(double t, const double* x) {
    evaluate_switches(t, x);
    for (std::size_t k = 0; k < crossing_count_; ++k) {
      const std::size_t i = crossing_[k];
      if (side_[i] != 0 && double(side_[i]) * g_[Index(i)] <= 0.0 && flipped(i)) return false;
    }
    return true;
  }

  // true when the run locates them (SimulationOptions::switch_events and switching functions)
  bool locates_switches() const { return g_.size() > 0; }
  // the last event found by find_event is a switch (not a contact's)
  bool switch_event() const { return switch_event_; }
  // ... or the report of steps that crawl after a switch (no switch: see switch_chatters)
  bool switch_crawls() const { return crawl_; }
  // ... or a restart on the way to a switch (no switch yet: see find_event)
  bool switch_approach() const { return approach_; }

  // g = the switching functions at (t, x)
  void evaluate_switches(double t, const double* x) {
    q_ = Eigen::Map<const VectorXd>(x, n_);
    qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
    sys_.switching_functions(q_, qd_, t, ws_.callables.get(), g_);
  }

  // each function's side: the sign of g at (t, x) (0: at its switch)
  void initial_switch_sides(double t, const double* x) {
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
  double find_switch(double t0, const double* x0, double t1, const double* x1,
                     const detail::SegmentHooks::Dense& dense, double& hi) {
    evaluate_switches(t1, x1);
    g1_ = g_;
    crossing_count_ = 0;
    landed_ = false;
    for (Index i = 0; i < g_.size(); ++i) {
      if (double(side_[std::size_t(i)]) * g_[i] < 0.0)
        crossing_[crossing_count_++] = std::size_t(i);
    }
    if (crossing_count_ == 0) {
      // a step that lands on a switch (an output time there: g(t1) within 1e-12 of g(t0) of 0,
      // on the old side) took its last stages at the tie, on either side: a switch at t1
      evaluate_switches(t0, x0);
      for (Index i = 0; i < g_.size(); ++i) {
        const double s0 = double(side_[std::size_t(i)]) * g_[i],
                     s1 = double(side_[std::size_t(i)]) * g1_[i];
        if (s0 > 0.0 && s1 >= 0.0 && s1 <= 1e-12 * s0)
          crossing_[crossing_count_++] = std::size_t(i);
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
  bool switch_chatters(double t, std::string& message) {
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
      message = of_constraint ? kink(window_start_)
                              : "switch events: " + format_number(long(kSwitchBurst)) +
                                    " steps after the switch of " + name +
                                    " at t = " + format(window_start_) +
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

  // switches the contact found by the last find_event at (t, x)
  Status switch_contact(double t, double* x) {
    const std::size_t c = std::size_t(switching_);
    ++traj_.stats.events;
    switch (mode_[c]) {
      case ContactMode::kSticking: {
        // release: friction from its full magnitude along the force that held the contact
        stick_margin(c, t, x);
        mode_[c] = ContactMode::kSliding;
        set_slip_hint(c, holding_);
        apply_contact_modes();
        bool changed = false;
        ProjectionOptions all = o_.projection;
        return project(t, x, all, changed);
      }
      case ContactMode::kSliding: {
        // the contact stops, or would have to: it sticks when that is admissible, else it
        // slides on through v_rel = 0, the next event of this contact
        if (try_stick(c, t, x)) return Status::kOk;
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
          if (try_stick(c, t, x, false)) return Status::kOk;
          set_slip_hint(c, carried_direction(c, 1.0));
          return Status::kOk;
        }
        // v_rel = 0: it sticks now if it can (a stop located early, where the velocity jump
        // was not yet tolerance-level); else the friction turns against the new motion, at
        // its full magnitude
        if (try_stick(c, t, x, false)) return Status::kOk;
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

  // projects x = [q; q'; W] in place with the given mask; false when it did not converge
  // q_, q'_ ← x projected onto the constraints of p: positions, then velocities (stops at the
  // first evaluation that fails: its status)
  Status project_into(double t, const double* x, const ProjectionOptions& p, ProjectionResult& rp,
                      ProjectionResult& rv) {
    q_ = Eigen::Map<const VectorXd>(x, n_);
    qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
    rp = project_positions(sys_, ws_, q_, t, p);
    if (rp.status != Status::kOk) return rp.status;
    rv = project_velocities(sys_, ws_, q_, qd_, t, p);
    return rv.status;
  }

  Status project(double t, double* x, const ProjectionOptions& p, bool& changed) {
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
      failure_ = "drift control: the projection onto the constraints did not converge at t = " +
                 format(t) + " (position violation " + format(rp.violation) +
                 ", velocity violation " + format(rv.violation) + " after " +
                 format_number(rp.iterations) + " and " + format_number(rv.iterations) +
                 " iterations)";
      // the cause, when it is that no state near satisfies the constraints (lock-up)
      const ConstraintConflict c = find_constraint_conflict(sys_, ws_, q_, qd_, t, p.tolerance);
      if (c.found) failure_ = describe_conflict(c, t) + "; " + failure_;
      return Status::kProjectionFailed;
    }
    return Status::kOk;
  }

  // removes from a step's error estimate err the components normal to the projected
  // constraints at the state x the step reached: what project() after the step removes
  bool project_error(double t, const double* x, double* err) {
    q_ = Eigen::Map<const VectorXd>(x, n_);
    qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
    Eigen::Map<VectorXd> dq(err, n_), dqd(err + n_, n_);
    return remove_normal_components(sys_, ws_, q_, qd_, t, projection_, dq, dqd) == Status::kOk;
  }

  // projects a stage state x in place onto the projected constraints; false when it failed
  bool project_stage(double t, double* x) {
    ProjectionResult rp, rv;
    if (project_into(t, x, projection_, rp, rv) != Status::kOk || !rp.converged || !rv.converged) {
      return false;
    }
    Eigen::Map<VectorXd>(x, n_) = q_;
    Eigen::Map<VectorXd>(x + n_, n_) = qd_;
    return true;
  }

  // drift control after an accepted step; then a requested stop (see stop_requested)
  Status after_step(double t, double* x, bool& changed) {
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

  // SimulationOptions::should_stop, asked once a step until it says yes (then remembered)
  bool stop_requested() {
    if (!stop_requested_ && o_.should_stop && o_.should_stop()) stop_requested_ = true;
    return stop_requested_;
  }

  // the run's sample times (sorted), which record() marks off as they are recorded
  void set_samples(const detail::SampleGrid& samples) { samples_ = &samples; }

  // samples recorded so far, and the time of the last one
  long recorded() const { return traj_.stats.samples; }
  double last_time() const { return last_time_; }
  // the energy balance of the samples recorded
  const detail::EnergyBalance& balance() const { return balance_; }
  // what the sample sink threw (null when nothing)
  const std::exception_ptr& sink_error() const { return sink_error_; }

  // the method taking the steps from now on (for the progress report)
  void set_integrator(Integrator method) { progress_.integrator = method; }

  // records a sample at t from the state x (projected first, when projecting); returns
  // kInterrupted after recording it when a stop was requested, unless it is the `last` one
  Status record(double t, const double* x, bool last = false) {
    std::copy(x, x + sample_.size(), sample_.begin());
    if (projecting_) {
      bool changed = false;
      ProjectionOptions quiet = projection_;
      if (const Status s = project(t, sample_.data(), quiet, changed); s != Status::kOk) return s;
    }
    q_ = Eigen::Map<const VectorXd>(sample_.data(), n_);
    qd_ = Eigen::Map<const VectorXd>(sample_.data() + n_, n_);
    const Status s = forward_dynamics(sys_, ws_, q_, qd_, t);
    // into the trajectory kept, or into one_ for the sink
    const bool streamed = bool(o_.sample_sink);
    Trajectory& out = streamed ? one_ : traj_;
    if (streamed) {
      for (auto* f : {&one_.t, &one_.q, &one_.qd, &one_.qdd, &one_.Qc_ideal, &one_.Qc_nonideal,
                      &one_.lambda, &one_.position_violation, &one_.velocity_violation,
                      &one_.kinetic_energy, &one_.potential_energy, &one_.energy,
                      &one_.work_nonideal, &one_.work_ideal, &one_.work_drive, &one_.work_external,
                      &one_.work_control, &one_.work_impact, &one_.energy_balance_residual}) {
        f->clear();
      }
    }
    auto push = [](std::vector<double>& f, const Eigen::Ref<const VectorXd>& v) {
      f.insert(f.end(), v.data(), v.data() + v.size());
    };
    out.t.push_back(t);
    push(out.q, q_);
    push(out.qd, qd_);
    push(out.qdd, ws_.qdd);
    push(out.Qc_ideal, ws_.Qc_ideal);
    push(out.Qc_nonideal, ws_.Qc_nonideal);
    push(out.lambda, ws_.lambda);
    const double T = detail::kinetic_energy(ws_, qd_),
                 V = sys_.potential_energy(q_, t, ws_.callables.get());
    out.kinetic_energy.push_back(T);
    out.potential_energy.push_back(V);
    out.energy.push_back(T + V);
    peak_kinetic_ = std::max(peak_kinetic_, T);
    // (T + |V| at the start, as the divergence message says; the run's energy unit, the power of
    // two nearest to max(T + |V|, |Q| l), where that is 0: a body released at rest at V = 0 has
    // no energy yet)
    if (!(energy_scale_ > 0.0)) {
      energy_scale_ = T + std::abs(V) > 0.0 ? T + std::abs(V) : ws_.energy_unit;
    }
    // the work channels (absent ones are zero), and the balance so far
    const auto work = [&](Index channel) {
      return channel < 0
                 ? 0.0
                 : sample_[std::size_t(2 * n_ + channel)] / works_.scale(channel, ws_.energy_unit);
    };
    const double works[6] = {work(works_.nonideal),
                             work(works_.ideal),
                             work(works_.drive),
                             work(works_.external),
                             0.0,
                             contacts_ ? contacts_->impact_work() : 0.0};
    out.work_nonideal.push_back(works[0]);
    out.work_ideal.push_back(works[1]);
    out.work_drive.push_back(works[2]);
    out.work_external.push_back(works[3]);
    out.work_control.push_back(works[4]);
    if (contacts_) out.work_impact.push_back(works[5]);
    out.energy_balance_residual.push_back(balance_.add(t, T, V, T + V, works));
    // violations of each constraint
    evaluate_violations(sys_, ws_, q_, qd_, t);
    for (Index k = 0; k < sys_.constraint_count(); ++k) {
      const double p = position_violation(sys_, ws_, k), v = velocity_violation(sys_, ws_, k);
      out.position_violation.push_back(p);
      out.velocity_violation.push_back(v);
      note_violation(p, v);
    }
    ++traj_.stats.samples;
    last_time_ = t;
    // the sample to the sink; what it throws stops the run (the driver rethrows it)
    if (streamed) {
      try {
        o_.sample_sink(one_);
      } catch (...) {
        sink_error_ = std::current_exception();
        failure_ = "the sample sink failed at t = " + format(t);
        return Status::kInterrupted;
      }
    }
    // the samples recorded (or passed) by now
    while (samples_ && next_sample_ < samples_->size() && (*samples_)[next_sample_] <= t) {
      ++next_sample_;
    }
    if (s != Status::kOk) {
      failure_ = describe_status(sys_, ws_);
      return s;
    }
    return !last && stop_requested() ? Status::kInterrupted : Status::kOk;
  }

  const std::string& failure() const { return failure_; }
  // the unilateral contacts, whose impacts' work record() writes (docs/contact.md)
  void set_contacts(const detail::ContactEvents* contacts) { contacts_ = contacts; }

  // --- a run that diverges (docs/simulation.md, "A run that diverges") -----------------------
  // The motion grows without bound when the kinetic energy T at (t, x) exceeds kDivergence
  // times the model's energy scale (T + |V| at the first sample, or at the first one after it
  // with energy when it has none). Then `why` says so (with the fastest coordinate) and this
  // returns true. Cost: one evaluation.
  bool diverged(double t, const double* x, std::string& why) {
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

 private:
  // After an accepted step to (t, x): true when the run diverges (see diverged) while its steps
  // are so short that the rest of the run would take more than max_steps of them — a crawl
  // that would otherwise go on for hours. The energy is evaluated only at such steps.
  bool diverges(double t, const double* x) {
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
  // twice that, and each step of it is judged (a slow passage may never leave the pose: the
  // twin arms swinging 0.005 rad about their dead centre). Across a step q' changes by at most
  // its duration times the accelerations, which are smooth along a branch: a change of q' (in
  // the M-norm) beyond kBranchFactor times the step times the larger M-norm of q'' at its two
  // ends — and beyond 1e-3 of |q'| — is a jump onto another branch (one of the twin arms
  // reversed: the mirror branch), which no status ok may hide. Costs one evaluation per step
  // end inside a passage; nothing elsewhere (Algorithm::kTextbook, whose margin is NaN, is not
  // checked).
  bool leaves_branch(double t, const double* x) {
    const double margin = ws_.rank_margin;
    if (!in_pose_ && !(margin < detail::kSingularMargin)) return false;
    q_ = Eigen::Map<const VectorXd>(x, n_);
    qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
    Workspace& w = branch_workspace();
    if (forward_dynamics(sys_, w, q_, qd_, t) != Status::kOk) return false;
    const double acceleration = std::sqrt(2.0 * detail::kinetic_energy(w, w.qdd));
    const bool entering = !in_pose_;
    const bool leaving = in_pose_ && margin >= 2.0 * detail::kSingularMargin;
    in_pose_ = !leaving;
    if (entering) {
      pose_t_ = step_t_ = t;
      pose_acceleration_ = step_acceleration_ = acceleration;
      pose_velocity_ = step_velocity_ = qd_;
      return false;
    }
    // a jump across the last step, or (leaving) across the whole passage; (BDF reports converged
    // attempts: after a rejected one, t can go back; not judged then)
    double t_from = step_t_, change = 0.0, bound = 0.0, speed = 0.0;
    const auto jumped = [&](double t0, double a0, VectorXd& v0, bool whole) {
      if (!(t > t0)) return false;
      t_from = t0;
      speed = std::sqrt(2.0 * detail::kinetic_energy(w, v0));
      v0 -= qd_;
      change = std::sqrt(2.0 * detail::kinetic_energy(w, v0));
      // (inside the passage, the part of the change that turns q' rather than stretching it:
      // the speeds of a driven mechanism that locks up grow along their direction, while a
      // jump onto the mirror branch reverses an arm at the same speed)
      if (!whole) {
        const double stretch = std::sqrt(2.0 * detail::kinetic_energy(w, qd_)) - speed;
        change = std::sqrt(std::max(0.0, change * change - stretch * stretch));
      }
      bound = (whole ? kBranchFactor * std::max(acceleration, a0) : kStepFactor * a0) * (t - t0);
      return change > bound && change > 1e-3 * speed;
    };
    // (inside the passage the accelerations at the step ends are those of states a roundoff
    // off the branch, amplified by the inverse margin: a step is held to the accelerations at
    // the passage's ends, where the rank is clear)
    const double regular = leaving ? acceleration : 0.0;
    const bool jump =
        jumped(step_t_, std::max(pose_acceleration_, regular), step_velocity_, false) ||
        (leaving && jumped(pose_t_, pose_acceleration_, pose_velocity_, true));
    step_t_ = t;
    step_acceleration_ = acceleration;
    step_velocity_ = qd_;
    if (!jump) return false;
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
  // integrator and the events left it. Copies of equal sizes: no allocation.
  Workspace& branch_workspace() {
    if (!branch_ws_) branch_ws_ = std::make_unique<Workspace>(sys_, ws_.options());
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
    w.energy_unit = ws_.energy_unit;
    return w;
  }
  static constexpr double kBranchFactor = 10.0;
  // (a step inside the passage, held to the accelerations at its entry: an order of magnitude
  // more room, as the accelerations along the branch may grow inside; the twin arms' slow
  // passage jumps by 18 times this bound, a governor's Coulomb passage peaks at 0.1 of it)
  static constexpr double kStepFactor = 100.0;

  // whether a sample time in (last recorded sample, t] has not been recorded yet
  bool sample_due(double t) const {
    return samples_ && next_sample_ < samples_->size() && (*samples_)[next_sample_] <= t;
  }

  // step size from the times the steps reach (BDF reports converged attempts, so a rejected
  // attempt can make t go back: then the step is unknown and the last one is kept)
  void report_progress(double t) {
    if (progress_.steps > 0 && t > progress_.t) progress_.step = t - progress_.t;
    progress_.t = t;
    ++progress_.steps;
    o_.progress(progress_);
  }

  // contact c's v_rel at (t, x) into the head of v; returns its length
  Index relative_velocity(std::size_t c, double t, const double* x, VectorXd& v) {
    q_ = Eigen::Map<const VectorXd>(x, n_);
    qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
    detail::sliding_velocity(sys_, ws_, Index(c), q_, qd_, t, false);
    const Index k = Index(sys_.friction_contacts()[c].coordinates.size());
    v.head(k) = ws_.sliding.col(Index(c)).head(k);
    return k;
  }

  // the first s in (t0, t1] with g(s) <= 0, by bisection on the dense output (g(t0) > 0 is
  // assumed), or NaN when g(t1) > 0
  // (the last time found with g > 0 into *last_positive when given)
  template <class G>
  double locate(double t0, double t1, const double* x1, const detail::SegmentHooks::Dense& dense,
                G&& g, double* last_positive = nullptr) {
    if (g(t1, x1) > 0.0) return std::numeric_limits<double>::quiet_NaN();
    double lo = t0, hi = t1;
    while (hi - lo > 1e-14 * std::max(1.0, std::abs(hi))) {
      const double mid = 0.5 * (lo + hi);
      dense(mid, event_x_.data());
      (g(mid, event_x_.data()) > 0.0 ? lo : hi) = mid;
    }
    if (last_positive) *last_positive = lo;
    return hi;
  }

  // mu_static N − |holding force|, with the contact sticking, at (t, x); NaN when the
  // constraints with the stick rows have no solution there. The stick rows make the normal
  // constraint's rows redundant, so their minimum-norm shares split the reaction arbitrarily;
  // the reaction R = share(normal) + share(stick) is unique, and is split here into its part
  // along the normal constraint's rows (N) and the rest (the friction that holds).
  double stick_margin(std::size_t c, double t, const double* x) {
    const FrictionContact& contact = sys_.friction_contacts()[c];
    q_ = Eigen::Map<const VectorXd>(x, n_);
    qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
    if (forward_dynamics(sys_, ws_, q_, qd_, t) != Status::kOk) {
      return std::numeric_limits<double>::quiet_NaN();
    }
    // R = the two constraints' shares of the ideal force and of the other contacts' friction
    reaction_ =
        ws_.shares.col(contact.normal_constraint) + ws_.shares.col(contact.stick_constraint);
    for (Index k : {contact.normal_constraint, contact.stick_constraint}) {
      detail::constraint_share(sys_, ws_, k, ws_.lambda_nonideal, reaction_part_);
      reaction_ += reaction_part_;
    }
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

  // Sticks contact c at (t, x) when sticking is admissible, projecting the velocities of x onto
  // the stick rows; else leaves x and the mode as they were and returns false. Admissible:
  // (1) the projection removes at most rtol · (largest kinetic energy of the run) — a zero of
  // v_rel that the mechanism passes through kinematically (a dead centre) would need a velocity
  // jump; (2) the constraints with the stick rows have a solution there; (3) the force that
  // holds the contact lies within mu_static N.
  // `report`: a refusal for reasons 1 or 2 is counted and noted.
  bool try_stick(std::size_t c, double t, double* x, bool report = true) {
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
    if (removed > stick_allowance(T_before)) {
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
  double stick_energy_loss(std::size_t c, double t, const double* x, ProjectionResult& rv,
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
  // the kinetic energy a stick may remove (rule 1 of try_stick): rtol · the largest of the run
  double stick_allowance(double T_before) const {
    return std::max(o_.rtol, 1e-14) * std::max(peak_kinetic_, T_before);
  }

  // True when contact c's stop located at te (dense: the step's state there) is a passage of
  // v_rel = 0 that the mechanism makes kinematically (a stick would remove kinetic energy) at a
  // configuration where the constraints nearly lose rank (Workspace::rank_margin below
  // kSingularMargin: a dead centre where two rows coincide). A restart there would start from
  // a state whose velocities the near-dependent rows fix only to (position error) / (distance
  // to the pose) — 1e-3 relative at the twin arms' dead centre, enough to take one arm onto the
  // mirror branch. No stick is possible there, and the friction turns within the step by its
  // regularized law, so the run goes on without restarting (docs/friction.md, "Dead centres").
  bool passes_at_rank_drop(std::size_t c, double te, const detail::SegmentHooks::Dense& dense) {
    dense(te, event_x_.data());
    q_ = Eigen::Map<const VectorXd>(event_x_.data(), n_);
    qd_ = Eigen::Map<const VectorXd>(event_x_.data() + n_, n_);
    if (forward_dynamics(sys_, ws_, q_, qd_, te) != Status::kOk) return false;
    if (!(ws_.rank_margin < detail::kSingularMargin)) return false;  // (NaN: unknown)
    ProjectionResult rv;
    double T_before = 0.0;
    const double removed = stick_energy_loss(c, te, event_x_.data(), rv, T_before);
    return std::isnan(removed) || removed > stick_allowance(T_before);
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
  bool carry_through(std::size_t c, Index k, double t1, const double* x1, double v_stop) {
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
  double carried_past(double tz, double t1, const double* x1,
                      const detail::SegmentHooks::Dense& dense) {
    const double te = locate(tz, t1, x1, dense, [&](double t, const double* x) {
      q_ = Eigen::Map<const VectorXd>(x, n_);
      qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
      if (forward_dynamics(sys_, ws_, q_, qd_, t) != Status::kOk) return 1.0;
      return ws_.rank_margin < kCarriedMargin ? 1.0 : -1.0;
    });
    return std::isnan(te) ? t1 : te;
  }
  // contact c's carried friction force is held (see carry_through)
  bool held(std::size_t c) const {
    return ws_.slip_hint_held[std::size_t(sys_.friction_contacts()[c].force)] != 0;
  }
  // sign × contact c's passing direction on its sliding coordinates, into holding_ (n)
  const VectorXd& carried_direction(std::size_t c, double sign) {
    const auto& coords = sys_.friction_contacts()[c].coordinates;
    holding_.setZero();
    for (std::size_t r = 0; r < coords.size(); ++r)
      holding_[coords[r]] = sign * passing_(Index(r), Index(c));
    return holding_;
  }

  // contact c slides from v_rel = 0 (passing, or at the start): friction at its full magnitude
  // against the impending motion, the acceleration of v_rel without this friction. Returns
  // false when that friction would turn the motion back (it could hold the contact): then the
  // regularized law acts instead, with no hint.
  bool start_sliding(std::size_t c, double t, const double* x) {
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
    holding_.setZero();
    const auto& coords = contact.coordinates;
    for (std::size_t r = 0; r < coords.size(); ++r) holding_[coords[r]] = -velocity_[Index(r)];
    set_slip_hint(c, holding_);
    // with the friction at its full magnitude against it, does the contact still move that way?
    // If not, friction could hold it although the stick was not admissible (a stick constraint
    // that the model cannot express): no hint then, the regularized law holds it near rest
    const Index k = Index(coords.size());
    direction_.head(k) = velocity_.head(k);
    if (forward_dynamics(sys_, ws_, q_, qd_, t) != Status::kOk) return true;
    relative_acceleration(c, t);
    if (velocity_.head(k).dot(direction_.head(k)) > 0.0) return true;
    set_slip_hint(c, VectorXd());
    return false;
  }

  // a_rel = P (q''_c − u') of contact c from the last evaluation (at q_, qd_, t) into the head of
  // velocity_, P the tangential projector of sliding_velocity
  void relative_acceleration(std::size_t c, double t) {
    const FrictionContact& contact = sys_.friction_contacts()[c];
    const Index k = Index(contact.coordinates.size());
    for (Index r = 0; r < k; ++r) velocity_[r] = ws_.qdd[contact.coordinates[std::size_t(r)]];
    const Index basis = detail::sliding_velocity(sys_, ws_, Index(c), q_, qd_, t, false);
    if (contact.surface_velocity) velocity_.head(k) -= ws_.surface_u_dot.head(k);
    detail::remove_normals(ws_, basis, velocity_.head(k));
  }

  // the direction of the friction at |v_rel| <= eps: along `along` (n) on the contact's
  // sliding coordinates, normalized; none when `along` is empty or zero (see CoulombFriction)
  void set_slip_hint(std::size_t c, const Eigen::Ref<const VectorXd>& along) {
    const FrictionContact& contact = sys_.friction_contacts()[c];
    auto hint = ws_.slip_hint.col(contact.force);
    hint.setZero();
    if (along.size() == 0) return;
    for (Index i : contact.coordinates) hint[i] = along[i];
    if (hint.norm() > 0.0) hint.normalize();
  }

  void note_violation(double p, double v) {
    traj_.stats.max_position_violation = std::max(traj_.stats.max_position_violation, p);
    traj_.stats.max_velocity_violation = std::max(traj_.stats.max_velocity_violation, v);
  }

  std::function<void(const Workspace&)> finished_;
  bool projected_last_ = false;  // the last project() changed the state
  const System& sys_;
  const SimulationOptions& o_;
  Workspace ws_;
  Trajectory& traj_;
  Index n_;
  VectorXd q_, qd_;
  // the work channels after q, q' in x (quiet unless BDF, see WorkLayout)
  detail::WorkLayout works_ = detail::WorkLayout(sys_, o_.integrator != Integrator::kBDF);
  std::vector<double> sample_ = std::vector<double>(std::size_t(2 * n_ + works_.count));
  ProjectionOptions projection_;
  bool projecting_ = false;
  std::vector<ContactMode> mode_;                // (contacts) what contact c does
  std::vector<unsigned char> separated_before_;  // (contacts) normal contact open before an event
  MatrixXd passing_ = MatrixXd::Zero(
      n_,
      Index(sys_.friction_contacts().size()));  // (n × contacts)
                                                // head of col c: v_rel's direction when c passes
  std::vector<double> trial_ = std::vector<double>(sample_.size());  // a trial state
  double peak_kinetic_ = 0.0;  // largest kinetic energy at the samples so far
  double energy_scale_ = 0.0;  // largest T + |V| of the early samples (see diverged)
  double last_step_end_ = -std::numeric_limits<double>::infinity();  // t of the last step
  int crawling_steps_ = 0;  // steps in a row, up to now, that diverged at a crawl
  // a passage of a singular configuration (see leaves_branch): under way; its start's time, the
  // M-norm of q'' there, and q' there (n)
  std::unique_ptr<Workspace> branch_ws_;  // (branch_workspace)
  bool in_pose_ = false;
  double pose_t_ = 0.0, pose_acceleration_ = 0.0, step_t_ = 0.0, step_acceleration_ = 0.0;
  VectorXd pose_velocity_ = VectorXd::Zero(n_), step_velocity_ = VectorXd::Zero(n_);
  VectorXd holding_ = VectorXd::Zero(n_);        // (n) holding force of the last stick_margin
  VectorXd reaction_ = VectorXd::Zero(n_);       // (n) scratch of stick_margin: R
  VectorXd reaction_part_ = VectorXd::Zero(n_);  // (n) scratch of stick_margin
  VectorXd normal_ = VectorXd::Zero(n_);         // (n) scratch of stick_margin: R_N
  MatrixXd normals_;                             // (rows × n) the normal constraint's rows of A
  VectorXd velocity_ = VectorXd::Zero(n_);       // (n) sliding velocities (head)
  VectorXd direction_ = VectorXd::Zero(n_);      // (n) sliding direction at the step's start (head)
  std::vector<double> event_x_ = std::vector<double>(sample_.size());  // dense state
  Index switching_ = -1;  // the contact of the last event found
  // the switching functions (System::switch_count, none unless SimulationOptions::switch_events):
  // their values (g_ scratch, g1_ at the end of the step), the side each is on (sign of g,
  // flipped at its event: the restart state may lie within roundoff on the old side), the ones
  // crossing in the step being checked, and the times of the last kSwitchBurst switch events
  Index switches_ = o_.switch_events ? sys_.switch_count() : 0;
  VectorXd g_ = VectorXd::Zero(switches_), g1_ = VectorXd::Zero(switches_);
  std::vector<signed char> side_ = std::vector<signed char>(std::size_t(switches_), 0);
  std::vector<std::size_t> crossing_ = std::vector<std::size_t>(std::size_t(switches_), 0);
  std::size_t crossing_count_ = 0;
  std::size_t switch_fired_ = 0;
  bool switch_event_ = false;
  std::vector<double> burst_ = std::vector<double>(switches_ > 0 ? kSwitchBurst : 0, 0.0);
  std::size_t burst_next_ = 0;
  std::vector<unsigned char> flipped_ = std::vector<unsigned char>(std::size_t(switches_), 0);
  bool flipped(std::size_t i) const { return flipped_[i] != 0; }  // at the last switch event
  double switch_width_ = 0.0;  // hi − lo of the last switch event's bracket
  // the switch that opened the window of the crawl test (NaN: none open), and the accepted
  // steps since then (up to kSwitchBurst)
  double window_start_ = std::numeric_limits<double>::quiet_NaN();
  std::size_t steps_since_switch_ = 0;
  bool crawl_ = false;       // the steps after a switch crawl (find_event)
  bool approach_ = false;    // the last event is a restart before a switch
  bool hands_over_ = false;  // the last event is rkf78 handing the run to dopri5
  bool landed_ = false;      // the last switch found is a step landing on it
  std::string failure_;
  const detail::ContactEvents* contacts_ = nullptr;  // (see set_contacts)
  std::string refusal_;      // why the last refused stick was refused (empty: friction cannot hold)
  ProgressReport progress_;  // what the last progress report said
  // a requested stop (SimulationOptions::should_stop): asked for; accepted steps since, waiting
  // for a sample due inside the step; the sample times and the first one not recorded yet
  bool stop_requested_ = false;
  long stop_wait_ = 0;
  static constexpr long kMaxStopWait = 1000;
  const detail::SampleGrid* samples_ = nullptr;
  std::size_t next_sample_ = 0;
  // streamed runs (SimulationOptions::sample_sink): the sample being recorded; what the sink threw
  Trajectory one_;
  std::exception_ptr sink_error_;
  double last_time_ = 0.0;         // time of the last sample recorded
  detail::EnergyBalance balance_;  // of the samples recorded
};

}  // namespace

void check_settings(const System& sys, const SimulationOptions& o) {
  auto fail = [](const char* setting, const std::string& what) {
    throw SettingError(setting, "ukdyn::simulate: " + std::string(setting) + " " + what);
  };
  auto finite = [](double v) { return std::isfinite(v); };
  // the run's interval: finite, and longer than the resolution of its times
  if (!finite(o.t_start)) fail("t_start", "(" + format(o.t_start) + ") must be a finite number");
  if (!finite(o.t_end)) fail("t_end", "(" + format(o.t_end) + ") must be a finite number");
  if (!(o.t_end - o.t_start > time_resolution(o.t_start, o.t_end))) {
    fail("t_end", "(" + format(o.t_end) + ") must exceed t_start (" + format(o.t_start) +
                      ") by more than 1e-12 max(1, |t_start|, |t_end|) = " +
                      format(time_resolution(o.t_start, o.t_end)) +
                      ", the resolution of the run's times");
  }
  if (!(o.step > 0.0) || !finite(o.step))
    fail("step", "must be a finite number > 0, got " + format(o.step));
  if (!(o.rtol > 0.0) || !finite(o.rtol))
    fail("rtol", "must be a finite number > 0, got " + format(o.rtol));
  if (!(o.atol > 0.0) || !finite(o.atol))
    fail("atol", "must be a finite number > 0, got " + format(o.atol));
  if (!(o.output_every >= 0.0) || !finite(o.output_every)) {
    fail("output_every",
         "must be a finite number >= 0 (0: only t_start and t_end), got " + format(o.output_every));
  }
  for (std::size_t i = 0; i < o.output_at.size(); ++i) {
    const double t = o.output_at[i];
    if (!(t >= o.t_start && t <= o.t_end)) {
      fail("output_at", "time " + format(t) + " (entry " + format_number(i) +
                            ") is outside the run [" + format(o.t_start) + ", " + format(o.t_end) +
                            "]");
    }
  }
  if (!(o.max_step >= 0.0))
    fail("max_step", "must be >= 0 (0: unlimited), got " + format(o.max_step));
  if (!(o.energy_balance_tolerance > 0.0)) {
    fail("energy_balance_tolerance",
         "must be > 0 (infinity: no check), got " + format(o.energy_balance_tolerance));
  }
  if (o.max_steps <= 0) fail("max_steps", "must be positive, got " + format_number(o.max_steps));
  if (!(o.baumgarte_alpha >= 0.0) || !finite(o.baumgarte_alpha)) {
    fail("baumgarte_alpha", "must be a finite number >= 0, got " + format(o.baumgarte_alpha));
  }
  if (!(o.baumgarte_beta >= 0.0) || !finite(o.baumgarte_beta)) {
    fail("baumgarte_beta", "must be a finite number >= 0, got " + format(o.baumgarte_beta));
  }
  if (!(o.initial_tolerance >= 0.0) || !finite(o.initial_tolerance)) {
    fail("initial_tolerance", "must be a finite number >= 0, got " + format(o.initial_tolerance));
  }
  if (!(o.projection.tolerance > 0.0) || !finite(o.projection.tolerance)) {
    fail("projection_tolerance", "(projection.tolerance) must be a finite number > 0, got " +
                                     format(o.projection.tolerance));
  }
  // every option within the range of the options table (simulation/options.hpp): the ones not
  // checked above
  try {
    check_options(o);
  } catch (const OptionError& e) {
    throw SettingError(e.setting(), "ukdyn::simulate: " + e.problem());
  }
  const double resolution = 16.0 * std::numeric_limits<double>::epsilon() *
                            std::max(std::abs(o.t_start), std::abs(o.t_end));
  // the adaptive methods held to max_step: a step that t resolves, and a run that max_steps
  // allows — at least (t_end − t_start) / max_step steps (else the run would crawl towards
  // max_steps for hours, e.g. max_step = 1e-300)
  if (o.max_step > 0.0 && o.integrator != Integrator::kRK4 && o.integrator != Integrator::kRK5) {
    if (!(o.max_step >= resolution)) {
      fail("max_step", "(" + format(o.max_step) + ") is below the resolution of t on [" +
                           format(o.t_start) + ", " + format(o.t_end) +
                           "], 16 eps max(|t_start|, |t_end|) = " + format(resolution) +
                           " (0: unlimited)");
    }
    const double least = (o.t_end - o.t_start) / o.max_step;
    if (least > double(o.max_steps)) {
      fail("max_step", "(" + format(o.max_step) + ") needs at least " + format(least) +
                           " steps over [" + format(o.t_start) + ", " + format(o.t_end) +
                           "], more than max_steps = " + format_number(o.max_steps) +
                           " (a larger max_step, or raise max_steps: " + kRaiseMaxSteps + ")");
    }
  }
  // the fixed-step methods: a step that t resolves, and at most max_steps of them
  if (o.integrator == Integrator::kRK4 || o.integrator == Integrator::kRK5) {
    if (!(o.step >= resolution)) {
      fail("step", "(" + format(o.step) + ") of " + to_string(o.integrator) +
                       " is below the resolution of t on [" + format(o.t_start) + ", " +
                       format(o.t_end) +
                       "], 16 eps max(|t_start|, |t_end|) = " + format(resolution));
    }
    // samples no closer than the steps (between steps they would be interpolated, not
    // integrated)
    if (o.output_every > 0.0 && o.output_every < o.step) {
      fail("output_every", "(" + format(o.output_every) + ") is below the step (" + format(o.step) +
                               ") of " + to_string(o.integrator) +
                               ": take a step <= output_every, or output_every >= step");
    }
    // the steps of each segment, as integrate_explicit takes them (counted in double: the
    // count may exceed any integer)
    const std::vector<double> ends = segment_ends(sys, o);
    double steps = 0.0;
    for (std::size_t k = 0; k + 1 < ends.size(); ++k) {
      steps += std::max(1.0, std::ceil((ends[k + 1] - ends[k]) / o.step * (1.0 - 1e-12)));
    }
    if (steps > double(o.max_steps)) {
      fail("step", "(" + format(o.step) + ") of " + to_string(o.integrator) + " takes " +
                       format(steps) + " steps over [" + format(o.t_start) + ", " +
                       format(o.t_end) + "], more than max_steps = " + format_number(o.max_steps) +
                       " (take a larger step, or raise max_steps: " + kRaiseMaxSteps + ")");
    }
  }
  // the sample grid: within the bound of a streamed run (o.sample_sink) or of one kept in memory,
  // its spacing above the resolution of t (SettingError naming output_every or output_at)
  (void)sample_grid(sys, o);
}

std::string user_message(const std::exception& e) {
  std::string message = e.what();
  const std::string prefix = "ukdyn::simulate: ";
  if (message.rfind(prefix, 0) == 0) message.erase(0, prefix.size());
  return message;
}

std::vector<std::string> detail::check_initial_conditions(const System& sys,
                                                          const Eigen::Ref<const VectorXd>& q,
                                                          const Eigen::Ref<const VectorXd>& qd,
                                                          double t, double tolerance,
                                                          double duration) {
  Workspace ws(sys);
  // the scales a run from this state takes (simulate's own check compares against the same)
  set_run_scales(sys, ws, q, qd, t, duration);
  detail::release_open_contacts(sys, ws, q, qd, t);  // (an open gap is no violation)
  evaluate_violations(sys, ws, q, qd, t);
  return violated(sys, ws, tolerance);
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
    traj.constraint_names.push_back(c.name());
    traj.constraint_rows.push_back(c.rows());
    traj.constraint_kinds.push_back(c.kind());
  }
  traj.n = sys.coordinate_count();
  traj.m = sys.constraint_rows();
  if (!rtol_note.empty()) traj.stats.notes.push_back(rtol_note);
  Run run(sys, o, traj, finished);
  Workspace& ws = run.workspace();
  const Index n = sys.coordinate_count();

  // initial conditions: consistent, or projected on request (constraints that contradict each
  // other are named: no projection helps); the unilateral contacts open or closed first
  VectorXd q = q0, qd = qd0;
  // the scales of the tolerances on the constraints' violations and of the work channels
  // (relative, unit-free)
  set_run_scales(sys, ws, q, qd, o.t_start, o.t_end - o.t_start);
  detail::ContactEvents contacts(sys, ws, std::size_t(2 * n + detail::WorkLayout(sys).count));
  if (contacts.any()) {
    contacts.start(o.t_start, q, qd, o.initial_tolerance, traj.stats);
    run.set_contacts(&contacts);
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

  // x = [q; q'; W] (the work channels start at 0)
  std::vector<double> x(std::size_t(2 * n + detail::WorkLayout(sys).count), 0.0);
  Eigen::Map<VectorXd>(x.data(), n) = q;
  Eigen::Map<VectorXd>(x.data() + n, n) = qd;

  // (quiet work channels for the explicit integrators; stage states violated beyond the
  // projection tolerance may take the least-squares q'')
  detail::ConstrainedOde ode(sys, ws, o.integrator != Integrator::kBDF, o.projection.tolerance);
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
  if (!sys.friction_contacts().empty() || run.locates_switches()) {
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

  const std::vector<double> ends = segment_ends(sys, o);
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
      traj.stats.message = "interrupted at t = " + format(t_reached) +
                           ": the run was stopped on request; the samples up to there are kept";
    }
    traj.stats.t_reached = t_reached;
    traj.stats.evaluations = ode.evaluations();
    traj.stats.least_squares = ode.least_squares();
    // the energy balance certifies a run that reached its end
    // (a system that does not account for its forces' work is reported, not checked)
    const double tolerance = sys.accounts_for_energy() ? checked_energy_balance_tolerance(o)
                                                       : std::numeric_limits<double>::infinity();
    if (o.sample_sink) {
      run.balance().finish(traj.stats, tolerance);
    } else {
      compute_energy_balance(traj, tolerance);
    }
    traj.stats.wall_time =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    std::fill(ws.activity_override.begin(), ws.activity_override.end(), -1);
    return traj;
  };

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
  run.initial_contact_modes(o.t_start, x.data());
  run.initial_switch_sides(o.t_start, x.data());
  for (std::size_t seg = 0; seg + 1 < ends.size(); ++seg) {
    double a = ends[seg];
    const double b = ends[seg + 1], mid = 0.5 * (a + b);
    // the constraints of this segment: those active in its interior
    for (Index k = 0; k < sys.constraint_count(); ++k) {
      ws.activity_override[std::size_t(k)] = sys.constraint(k).is_active(mid) ? 1 : 0;
    }
    run.apply_contact_modes();
    if (contacts.any()) contacts.apply();
    // a constraint that switches on finds the state inconsistent: project onto it
    bool changed = false;
    if (seg > 0 && sys.constraint_count() > 0) {
      ProjectionOptions all = o.projection;
      if (const Status s = run.project(a, x.data(), all, changed); s != Status::kOk) {
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
    // evaluations at a breakpoint end are one-sided (the run's own ends are not breakpoints)
    const double inf = std::numeric_limits<double>::infinity();
    ode.set_window(seg == 0 ? -inf : a, seg + 2 == ends.size() ? inf : b);
    // [a, b], restarted after every stick/slip event and stiffness switch; the segment starts
    // with the chosen method, and goes on with BDF once dopri5 finds it stiff until the next
    // event (a switch of the dynamics) or the segment's end
    Integrator method = base_method;
    after_event = false;     // (an event at the last segment's end b does not carry over)
    bool crossing = false;   // dopri5 across a singular configuration for BDF
    bool r_crossed = false;  // the last segment was such a crossing
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
      hooks.cross_singular = crossing;
      hooks.max_steps = o.max_steps - traj.stats.steps;  // (> 0: checked after each segment)
      // (after a switch CVODE estimates its own first step: dopri5's last one is stability-bound)
      detail::SegmentResult r =
          method == Integrator::kBDF
              ? detail::integrate_bdf(ode, x, a, b, outputs, om, hooks,
                                      switched || r_crossed ? 0.0 : first_step)
              : detail::integrate_explicit(method, ode, x, a, b, outputs, om, hooks, first_step);
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
        if (r.status == Status::kIntegratorFailure &&
            (traj.stats.steps >= o.max_steps || message.find("step limit") != std::string::npos)) {
          message += " (the run's limit max_steps = " + format_number(o.max_steps) +
                     " accepted steps; raise it: " + kRaiseMaxSteps + ")";
        }
        if (r.status == Status::kIntegratorFailure && detail::step_collapsed(r)) {
          std::string divergence;
          message += run.diverged(r.t_reached, x.data(), divergence)
                         ? ". Likely cause: " + divergence
                         : ". " + detail::diagnose_collapse(sys, ws, o, method, r, x, x_start,
                                                            a_start, traj.stats);
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
        // a unilateral contact's impact or release: the velocity jump and the closed set
        if (!contacts.handle(r.t_reached, x.data(), traj.stats)) {
          return finish(Status::kIntegratorFailure, contacts.failure(), r.t_reached);
        }
        run.contacts_changed(r.t_reached, x.data());
        if (const Status s = run.project_drift(r.t_reached, x.data()); s != Status::kOk) {
          return finish(s, run.failure().empty() ? describe_status(sys, ws) : run.failure(),
                        r.t_reached);
        }
        a = r.t_reached;
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
        if (const Status s = run.project_drift(r.t_reached, x.data()); s != Status::kOk) {
          return finish(s, run.failure().empty() ? describe_status(sys, ws) : run.failure(),
                        r.t_reached);
        }
        a = r.t_reached;
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
            if (const Status s = run.record(samples[next_sample], x.data()); s != Status::kOk) {
              return finish(s, run.failure(), samples[next_sample]);
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
      if (const Status s = run.switch_contact(r.t_reached, x.data()); s != Status::kOk) {
        return finish(s, run.failure().empty() ? describe_status(sys, ws) : run.failure(),
                      r.t_reached);
      }
      a = r.t_reached;
      if (!(a < b)) break;
    }
  }
  return finish(Status::kOk, "", o.t_end);
}

}  // namespace ukdyn

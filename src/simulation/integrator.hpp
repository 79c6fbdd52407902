// SPDX-License-Identifier: BSD-3-Clause
// Internal: the interface between the simulation driver (simulation/simulate.cpp) and the
// integrators (simulation/integrators_explicit.cpp: Boost.Odeint; simulation/integrator_bdf.cpp:
// SUNDIALS CVODE). Not installed.
#pragma once

#include <algorithm>
#include <array>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "simulation/observed_run.hpp"
#include "simulation/sample_grid.hpp"
#include "ukdyn/core/status.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::detail {

class ContactEvents;  // (simulation/contact_events.hpp)

// The work channels integrated after q and q' (docs/simulation.md, "Energy balance"): their
// offsets in x after 2n, or −1 when the system does not need the channel.
//   nonideal  W_nonideal' = q'ᵀ Qc_nonideal                         (always)
//   ideal     W_ideal'    = q'ᵀ Qc_ideal − (the drives' part)        (the system has constraints)
//   drive     W_drive'    = Σ over drives k of q'ᵀ A_kᵀ lambda_k      (a constraint is_drive())
//   external  W_external' = P_ext(q, q', t)                          (System::has_external_power)
//
// Every channel is stored in the run's energy unit (the power of 1000 nearest to its energy
// scale / 10, Workspace::energy_unit: 1 for a model in SI units). The channels after W_nonideal are
// stored scaled by kQuietScale = 2⁻³² as well (x holds W · 2⁻³² / unit), so that the step-size
// control, which weighs every component of x, follows the motion (and W_nonideal, as it always has)
// alone: a power that carries noise — q'ᵀ Qc_ideal of scleronomic constraints near a singular
// configuration, where the multipliers are large and A q' is roundoff — must not shrink the steps
// (it switched the double four-bar's branch). The quadrature itself is unchanged: the same stages,
// and scaling by a power of two commutes with rounding, so W · 2⁻³² · 2³² is bit for bit the
// unscaled sum.
//
// With BDF the channels are not scaled: CVODE's error test is a root-mean-square over the
// components, which a component of negligible error would loosen (by √((N+1)/N)).
struct WorkLayout {
  static constexpr double kQuietScale = 0x1p-32;
  // quiet: scale the channels after W_nonideal (the explicit integrators); quad: integrals
  // after the work channels (channels quadrature … count − 1), or null
  explicit WorkLayout(const System& sys, bool quiet = true, const Quadratures* quad = nullptr);
  // the scale of channel c in x: 1 / unit for W_nonideal, and for every channel when not
  // quiet, kQuietScale / unit for the others; unit the run's energy unit (a power of 1000,
  // Workspace::energy_unit from set_run_scales), so that the step-size control weighs the
  // work channels relative to the run's energies (a pendulum of 1e20 kg took 726,143 steps
  // instead of 205 under atol in joules)
  double scale(Index c, double unit) const {
    return (c == nonideal || !quiet ? 1.0 : kQuietScale) / unit;
  }
  bool quiet = true;
  Index nonideal = 0, ideal = -1, drive = -1, external = -1;
  Index quadrature = -1;  // the first of the quadratures' channels (Quadratures), or −1
  Index count = 1;        // number of channels (the quadratures' included)
  // (count − quadrature) the unit of each quadrature (Quadratures::unit): every method's
  // step-size control (the explicit ones' and BDF's) takes atol · unit_i as its atol, and
  // dopri5's stiffness probe compares it in this unit
  std::vector<double> quadrature_units;
  std::vector<Index> drives;  // indices of the drive constraints
};

// The power of constraint k's share of the ideal force along q', q'ᵀ A_kᵀ lambda_k, after
// solve_ideal (either engine); scratch (n) is used by the sparse engine. Cost O(rows · n).
double constraint_power(const System& sys, const Workspace& ws, Index k,
                        const Eigen::Ref<const VectorXd>& qd, VectorXd& scratch);

// The first-order system x' = f(t, x) of a constrained mechanical system, x = [q; q'; W; z]
// (2n + WorkLayout::count), W the work channels, z the caller's quadratures (if any):
//   f = [q'; q''; q'ᵀ Qc_nonideal; q'ᵀ Qc_ideal − P_drive; P_drive; P_ext; g],  q'' from
//   forward_dynamics (absent channels left out), g = Quadratures::rate.
// A failed evaluation (status not kOk) fills dxdt with NaN, is remembered, and makes
// operator() return false; integrators must stop at once when it does.
//
// Off the constraint manifold, one failure is not one: the stage states of a Runge–Kutta step
// (and CVODE's Newton iterates) are not projected, so they violate the constraints by about the
// local error. With redundant constraints (A rank deficient on the manifold, as in an
// overconstrained loop) the redundant rows' b then no longer agree with the others and
// A q'' = b has no solution, although the state projected after the step is consistent. Such an
// evaluation is accepted with the least-squares (minimum M-norm) q'' of the pseudo-inverse form
// and counted (least_squares()) when the inconsistency is explained by the state's own
// violation (explained_by_violation below); see docs/simulation.md, "Redundant constraints".
class ConstrainedOde {
 public:
  // quiet: see WorkLayout (true for the explicit integrators, false for BDF);
  // off_manifold_tolerance: a row violated by more than this (|phi| or |phi'|, |psi|; the
  // projection tolerance) puts the state off the manifold; 0 or NaN: never accept
  // quad: integrals integrated after the work channels (Quadratures), or null
  ConstrainedOde(const System& sys, Workspace& ws, bool quiet = true,
                 double off_manifold_tolerance = 0.0, const Quadratures* quad = nullptr);

  // dxdt = f(t, x) for x, dxdt of size(); false when the evaluation failed
  bool operator()(const double* x, double* dxdt, double t);

  Index size() const { return 2 * n_ + works_.count; }
  const WorkLayout& works() const { return works_; }
  Index coordinate_count() const { return n_; }
  long evaluations() const { return evaluations_; }
  // evaluations off the constraint manifold that found A q'' = b without solution and went on
  // with the least-squares q''
  long least_squares() const { return least_squares_; }
  bool failed() const { return failure_ != Status::kOk; }
  Status failure() const { return failure_; }
  // describe_status() of the first failure, with its time
  const std::string& failure_message() const { return failure_message_; }
  void clear_failure();
  // Takes the failure for a rejected step attempt (its trial state left the model's domain):
  // keeps its status and description without its time (for left_domain()) and clears it.
  // Returns that status.
  Status take_failure(std::string& description_without_time);

  // Evaluations of the segment [a, b] take place strictly inside it at a breakpoint end: t is
  // clamped to [a + δ, b − δ] (δ = 1e-13 relative), so each segment sees its own side of a jump
  // that the user's callables make at a breakpoint. Infinite ends: no clamping.
  void set_window(double a, double b);

  // contacts->screen(t) is called after each successful evaluation at t, with the workspace
  // that evaluation filled (ws.lambda): the unilateral contacts' release screening at the
  // integrator's stages, a direct call of its inline sign tests (one per closed contact). Null
  // (the default): none, and nothing to pay but the rare_ test
  void watch_releases(ContactEvents* contacts) {
    contacts_ = contacts;
    rare_ = rare_ || contacts_ != nullptr;
  }
  // screen(t, x) is called after each successful evaluation at (t, x), with the workspace that
  // evaluation filled (ws.lambda): the Coulomb contacts' slip screening at the integrator's
  // stages (Run::screen_sticking). Runs without sticking friction set none and pay nothing (the
  // rare_ test)
  void set_screen(std::function<void(double t, const double* x)> screen) {
    screen_ = std::move(screen);
    rare_ = rare_ || static_cast<bool>(screen_);
    channels_ = channels_ || static_cast<bool>(screen_);
  }

  const System& system() const { return sys_; }
  Workspace& workspace() { return ws_; }

 private:
  // after forward_dynamics reported kInconsistentConstraints at (q, qd, t): true when the
  // rows that carry the residual A q'' − b (|r_i| >= kResidualShare max |r|) all belong to
  // holonomic or nonholonomic constraints (an acceleration-form row has no violation that could
  // explain it) and at least one of them is violated by more than off_manifold_tolerance_.
  // Overwrites ws.phi, ws.phi_dot, ws.tmp_m; allocates nothing.
  bool explained_by_violation(const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t);
  // dxdt's P_drive (`drive`) and quadratures z' = g at x (Quadratures::rate), after the
  // evaluation at (x, t)
  [[gnu::noinline]] void rare_channels(const double* x, double* dxdt, double t, double drive) const;
  static constexpr double kResidualShare = 1e-3;

  const System& sys_;
  Workspace& ws_;
  Index n_;
  WorkLayout works_;
  const Quadratures* quad_ = nullptr;
  bool rare_ = false;      // drives, quadratures, a screen or contacts to watch
  bool channels_ = false;  // drives, quadratures or a screen: rare_channels
  std::function<void(double t, const double* x)> screen_;  // see set_screen, or empty
  ContactEvents* contacts_ = nullptr;                      // see watch_releases, or null
  VectorXd share_;                                         // (n) scratch: A_kᵀ lambda_k
  std::vector<unsigned char> violation_rows_;  // (m) row i has a violation (not acceleration form)
  double off_manifold_tolerance_ = 0.0;
  long evaluations_ = 0;
  long least_squares_ = 0;
  double lo_ = -std::numeric_limits<double>::infinity();
  double hi_ = std::numeric_limits<double>::infinity();
  Status failure_ = Status::kOk;
  std::string failure_message_;
};

// Workspace::rank_margin (σ_r/σ_1) below which the constraints are near a singular
// configuration: dopri5 and rkf78 project their stages there, BDF hands the crossing to dopri5
// (docs/simulation.md, "Singular configurations")
constexpr double kSingularMargin = 1e-2;
// rank margin below which BDF's error estimate loses its components normal to the constraints
constexpr double kTangentialMargin = std::numeric_limits<double>::infinity();

// What the driver asks of an integrator for one segment [t0, t1] (no breakpoint inside).
struct SegmentHooks {
  // after every accepted step, with the state at t: may correct x in place (projection) and
  // then sets `changed`; returns kOk to go on, anything else to stop with that status
  std::function<Status(double t, double* x, bool& changed)> after_step;
  // at every output time, ascending, with the state there (dense output / landing / Hermite);
  // returns kOk to go on
  std::function<Status(double t, const double* x)> output;
  // optional, after every accepted step [t0, t1] (before drift control): the first time in
  // (t0, t1] at which the dynamics switches (an event), or NaN for none; dense(s, x) writes the
  // state at s in [t0, t1]. The integrator then stops there (SegmentResult::event).
  using Dense = std::function<void(double s, double* x)>;
  // optional: removes from a step's local error estimate err (the size of x) the components
  // that after_step's projection removes at the state x reached by the step (before drift
  // control); false when drift control does not project, and err is then used as it is. The
  // adaptive methods measure a rejected step's error again this way (see
  // docs/simulation.md, "Singular configurations").
  std::function<bool(double t, const double* x, double* err)> project_error;
  // optional: projects the state x at t onto the constraints, as after_step does (no other
  // effect); false when it could not
  std::function<bool(double t, double* x)> project_stage;
  // the accepted steps this segment may take: the run's options.max_steps less the steps
  // taken before it (the driver sets it before each segment); the integrators stop at
  // min(options.max_steps, max_steps)
  long max_steps = std::numeric_limits<long>::max();
  // dopri5 crossing a singular configuration for BDF: ends the segment (SegmentResult::crossed)
  // once the margin, having been below kSingularMargin, is back above twice it; no stiffness
  // switch meanwhile
  bool cross_singular = false;
  std::function<double(double t0, const double* x0, double t1, const double* x1,
                       const Dense& dense)>
      find_event;
};

// Outcome of one segment.
struct SegmentResult {
  Status status = Status::kOk;  // kOk, or why it stopped
  std::string message;          // describe the failure ("" when ok)
  double t_reached = 0.0;       // time of the state left in x
  long steps = 0;               // accepted steps
  long rejected = 0;            // rejected steps (error test failures)
  double last_step = 0.0;       // size of the last accepted step (a good first step next time)
  bool event = false;           // stopped early at an event found by hooks.find_event
  // stopped early because the problem became stiff (dopri5 with options.stiff_switch): the
  // state left in x is the projected state after the last accepted step; the driver goes on
  // with BDF (see StiffnessTest)
  bool stiff = false;
  // the step size collapsed: the adaptive method gave up (step size underflow, too many
  // rejections, or options.max_steps); the driver adds a diagnosis to the message
  bool collapsed = false;
  double stiffness = 0.0;  // largest h·ρ of the last accepted steps (dopri5; 0: unknown)
  // BDF stopped before a singular configuration (a step reached rank_margin < kSingularMargin):
  // x is the last accepted state; the driver crosses with dopri5 (hooks.cross_singular)
  bool singular = false;
  bool crossed = false;  // dopri5 with hooks.cross_singular is past the singular configuration
  // accepted steps whose error estimate passed only once its components normal to the
  // constraints (which the projection after the step removes) were taken out
  long tangential_steps = 0;
  long projected_stage_steps = 0;  // accepted steps with projected stages
};

// Hairer and Wanner's stiffness test of dopri5 (Hairer, Nørsett, Wanner, Solving ODEs I,
// sec. IV.2; the STIFF branch of DOPRI5). The 6th and 7th (FSAL) stages of Dormand–Prince are
// both evaluated at t + h, at states y6 and y7, so
//   h·ρ ≈ h ‖f(y7) − f(y6)‖ / ‖y7 − y6‖
// estimates h times the dominant eigenvalue of ∂f/∂x along the direction in which the step
// errs. dopri5's stability region reaches about 3.3 along the negative real axis: when the
// step size is held there by stability rather than by accuracy, h·ρ sits near 3.3. The problem
// is declared stiff after kStiffSteps accepted steps with h·ρ > kStiffBound, unless
// kNonStiffSteps consecutive steps below it intervene (which restart the count).
class StiffnessTest {
 public:
  static constexpr double kStiffBound = 3.25;
  static constexpr int kStiffSteps = 15;
  static constexpr int kNonStiffSteps = 6;

  // after an accepted step of size h with h·ρ = h_rho; true once the problem is stiff
  bool accepted(double h_rho) {
    last_ = h_rho;
    recent_[next_++ % recent_.size()] = h_rho;
    if (h_rho > kStiffBound) {
      non_stiff_ = 0;
      return ++stiff_ >= kStiffSteps;
    }
    if (++non_stiff_ >= kNonStiffSteps) stiff_ = 0;
    return false;
  }
  double last() const { return last_; }
  // the largest h·ρ of the last kStiffSteps + 1 accepted steps (at the stability bound h·ρ
  // oscillates around 3.3, so one step says little)
  double recent() const { return *std::max_element(recent_.begin(), recent_.end()); }

 private:
  int stiff_ = 0, non_stiff_ = 0;
  double last_ = 0.0;
  std::array<double, kStiffSteps + 1> recent_{};
  std::size_t next_ = 0;
};

// Integrates x (size ode.size(), the state at t0) to t1, calling hooks.output at each of
// `outputs` (ascending, inside (t0, t1]) and hooks.after_step after each accepted step.
// first_step: the step to try first (adaptive) or the step (RK4). On return x is the state at
// result.t_reached (t1 unless it failed).
SegmentResult integrate_explicit(Integrator method, ConstrainedOde& ode, std::vector<double>& x,
                                 double t0, double t1, const SampleTimes& outputs,
                                 const SimulationOptions& options, SegmentHooks& hooks,
                                 double first_step);

// The same with SUNDIALS CVODE (BDF, Newton iteration, dense direct linear solver with a
// difference-quotient Jacobian); projection through CVodeSetProjFn calling hooks.after_step.
SegmentResult integrate_bdf(ConstrainedOde& ode, std::vector<double>& x, double t0, double t1,
                            const SampleTimes& outputs, const SimulationOptions& options,
                            SegmentHooks& hooks, double first_step);

// The message of an adaptive method (`method`) that gives up because every step from t, down to
// the smallest step h, reached a state where the model cannot be evaluated (M not positive
// definite, a NaN, …: the solution leaves the model's domain there): it quotes the one time t,
// the last state reached, and `description` (ConstrainedOde::take_failure) says what failed.
std::string left_domain(const char* method, double t, double h, const std::string& description);

// --- step-size collapse (simulation/step_diagnosis.cpp)
// ----------------------------------------------

// three significant digits, for messages
std::string format_short(double v);
// the adaptive method gave up (explicit methods say so; CVODE by its flags)
bool step_collapsed(const SegmentResult& r);
// The likely cause of the collapse that r reports, and what to try (one or two sentences):
// x is the state where the method gave up (r.t_reached), x0 the one where it started (t0).
// At the step limit (step_limit) only a singular configuration or stiffness is a cause worth
// saying: with neither, "" (a steady step that ran out of steps did not collapse).
std::string diagnose_collapse(const System& sys, Workspace& ws, const SimulationOptions& o,
                              Integrator method, const SegmentResult& r,
                              const std::vector<double>& x, const std::vector<double>& x0,
                              double t0, const RunStatistics& stats, bool step_limit = false);

}  // namespace ukdyn::detail

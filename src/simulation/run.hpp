// SPDX-License-Identifier: BSD-3-Clause
// Internal (not installed): the Run of simulate(), everything a run shares between the
// integrator's callbacks, and what the files of the simulation driver share. The driver
// (simulate.cpp) splits [t_start, t_end] into segments, integrates each and restarts at events;
// the Run's members are defined one job per file:
//   run_drift.cpp       construction, drift control after each step (projection), and the checks
//                       that stop a run that diverges or leaves its branch (docs/simulation.md,
//                       "Drift control", "A run that diverges", "Singular configurations")
//   run_events.cpp      the first event inside a step (Coulomb contacts' and switches') and the
//                       switches of the non-smooth functions (docs/simulation.md, "Switch events")
//   run_stick_slip.cpp  Coulomb contacts: stick, slide, or slide through v_rel = 0
//                       (docs/friction.md, "Stick and slip, as events")
//   run_output.cpp      the samples (recorded or streamed) and the progress report
//   settings_check.cpp  the run's settings: check_settings, validate, sample times, segment ends
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <exception>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "dynamics/internal.hpp"
#include "simulation/contact_events.hpp"
#include "simulation/energy_balance.hpp"
#include "simulation/integrator.hpp"
#include "simulation/sample_grid.hpp"
#include "simulation/split_margin.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"
#include "ukdyn/simulation/options.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::detail {

// notes a run keeps (RunStatistics::notes)
inline constexpr std::size_t kMaxNotes = 20;
// a run is declared chattering at a switch (SimulationOptions::switch_events) when kSwitchBurst
// switch events, or kSwitchBurst accepted steps after one (any steps: into, at or between
// switches), fall within kSwitchBurstSpan of the run's time span
inline constexpr std::size_t kSwitchBurst = 1000;
inline constexpr double kSwitchBurstSpan = 1e-6;
// the step into a switch below which the run restarts at the switch (see Run::find_event)
inline constexpr double kSwitchApproach = 1e-10;
// a run diverges when its kinetic energy exceeds kDivergence times the model's energy scale,
// T + |V| at its start (Run::diverged): the speeds then exceed the initial ones by 10⁴ and more.
// It stops there once kDivergentSteps steps in a row have done so at a pace that cannot reach
// t_end within max_steps (Run::diverges).
inline constexpr double kDivergence = 1e8;
inline constexpr int kDivergentSteps = 3;
// a contact carried through a dead centre restarts past it where the rank margin is back to
// this (Run::carried_past)
inline constexpr double kCarriedMargin = 3e-5;
// a relative acceleration below this fraction of the run's class of accelerations is no impending
// motion (Run::start_sliding; Run::acceleration_scale)
inline constexpr double kStillAcceleration = 1e-9;
// a switch located where the rank margin is below this (and above kCarriedMargin) under dopri5,
// rkf78 or BDF restarts there, bridged past the pose (Run::entered_dead_centre)
inline constexpr double kBridgedSwitchMargin = 1e-3;
// below this rank margin (Workspace::rank_margin, σ_r / σ_1 of W) growing speeds are those of a
// configuration where the constraints lose rank, not a divergence
inline constexpr double kDivergenceRankMargin = 1e-3;

// the rows a Coulomb contact's sliding velocity and directions take: n, or the largest d of a
// contact-point contact (ContactKinematics) when larger
inline Index sliding_width(const System& sys, Index n) {
  Index w = n;
  for (const auto& c : sys.friction_contacts()) w = std::max(w, c.size());
  return w;
}

// What a Coulomb contact does: slides (friction acts), sticks (the stick constraint acts), or
// slides through a zero of v_rel at which it could not stick (the zero is its next event).
enum class ContactMode : unsigned char { kSliding, kSticking, kPassing };

// three significant digits, for messages
inline std::string format(double v) { return detail::format_short(v); }

// where each front end sets max_steps (the end of every message about the step limit)
inline const std::string kRaiseMaxSteps =
    "simulate: max_steps in a model file, --max-steps on the command line, max_steps= in Python";

// "the constraints … contradict each other …" / "… the mechanism locks up …" (run messages;
// run_drift.cpp)
std::string describe_conflict(const ConstraintConflict& c, double t);

// the run's settings (settings_check.cpp): the sizes of q0, qd0 and the per-constraint drift
// settings (the others: check_settings); the run's sample times; the segments' ends (t_start,
// breakpoints inside, t_end)
void validate(const System& sys, const Eigen::Ref<const VectorXd>& q0,
              const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& o);
detail::SampleGrid sample_grid(const System& sys, const SimulationOptions& o);
std::vector<double> segment_ends(const System& sys, const SimulationOptions& o);

// A run of a system with constraints given in acceleration form only (ConstraintKind::
// kAcceleration): their violations are unknown — stats' largest violations NaN, and a note
// (run_output.cpp). Nothing for other systems. Cost O(K).
void unmeasured_violations(const System& sys, RunStatistics& stats);

// A run whose non-ideal forces did not settle on the reactions they cause in some evaluations
// (Counters::nonideal_unsettled of ws, the run's workspace): a note with how many, when, the
// worst residual and the constraint it names (Workspace::unsettled), in `units`' time. Nothing
// for other runs. Cost O(1).
void unsettled_reactions(const System& sys, const Workspace& ws, const UnitSystem& units,
                         RunStatistics& stats);

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
  // `quad`: a caller's integrals after the work channels (detail::Quadratures; null: none),
  // whose values Run::record writes into quad->sample before each sample's sink
  Run(const System& sys, const SimulationOptions& o, Trajectory& traj,
      std::function<void(const Workspace&)> finished = {}, Quadratures* quad = nullptr);

  Workspace& workspace() { return ws_; }
  // `started` is called with every workspace the run makes besides its own (the branch check's,
  // when it is made), as detail::simulate_observed calls it with the run's: a controlled plant's
  // scratch then mirrors that workspace's contact modes (control/simulate_controlled.cpp)
  void set_started(std::function<void(Workspace&)> started) { started_ = std::move(started); }
  bool projecting() const { return projecting_; }

  // --- drift control (run_drift.cpp; docs/simulation.md, "Drift control") ------------------
  // q_, q'_ ← x projected onto the constraints of p (positions, then velocities)
  Status project_into(double t, const double* x, const ProjectionOptions& p, ProjectionResult& rp,
                      ProjectionResult& rv);
  // drift control of x at t onto the constraints of p; `changed`: x was projected
  Status project(double t, double* x, const ProjectionOptions& p, bool& changed);
  // removes from a step's error estimate err what project() after the step removes
  bool project_error(double t, const double* x, double* err);
  // projects a stage state x in place onto the projected constraints; false when it failed
  bool project_stage(double t, double* x);
  // drift control after an accepted step; then a requested stop (see stop_requested)
  Status after_step(double t, double* x, bool& changed);
  // drift control at a restart after a switch event (the state there is a step's, not yet
  // projected)
  Status project_drift(double t, double* x) {
    bool changed = false;
    return projecting_ ? project(t, x, projection_, changed) : Status::kOk;
  }
  // --- a run that diverges (docs/simulation.md, "A run that diverges") -----------------------
  // the kinetic energy at (t, x) exceeds kDivergence times the model's energy scale (`why`)
  bool diverged(double t, const double* x, std::string& why);

  // --- events inside a step, and switches (run_events.cpp; docs/simulation.md, "Switch events")
  // the first switch of a contact or a switching function inside [t0, t1] (see
  // SegmentHooks::find_event), or NaN
  double find_event(double t0, const double* x0, double t1, const double* x1,
                    const detail::SegmentHooks::Dense& dense);
  // at each evaluation of the integrator's stages at (t, x) (ConstrainedOde::set_screen), after
  // its forward dynamics: the earliest such t at which a sticking contact's (minimum-norm) stick
  // margin is negative, per contact, for find_event's slip test (a force pulse within one long
  // step of a body at rest). O(sticking contacts · n), no evaluation of the dynamics
  void screen_sticking(double t, const double* x);
  // Stops under rk4, rk5 and rkf78, whose dense output is a step of the method from the step's
  // start (docs/friction.md, "Stops under every integrator"). A stage past a sliding contact's
  // stop sees its friction reversed, and the step's end can then lie before the stop again: rk4
  // with the stop in the first half of its step ends at the speed it started with, and never
  // stops. So the stop is read from the stages too. arm_stops: at the start of an integration
  // (after set_integrator), each sliding contact's direction of motion at (t, x); then at each
  // evaluation of the stages (ConstrainedOde::set_screen, after its forward dynamics, which
  // filled Workspace::sliding) screen_stops notes whether the speed along it fell to v_stop.
  // O(sliding contacts · d) per evaluation, no evaluation of the dynamics; nothing under dopri5
  // and BDF (their dense output is an interpolant, not a step of the method)
  void arm_stops(double t, const double* x);
  void screen_stops() {
    if (!screens_stops_) return;
    const auto& contacts = sys_.friction_contacts();
    for (std::size_t c = 0; c < contacts.size(); ++c) {
      if (!stop_armed_[c] || stop_seen_[c] || mode_[c] != ContactMode::kSliding) continue;
      const Index k = contacts[c].size();
      const double along =
          ws_.sliding.col(Index(c)).head(k).dot(stop_direction_.col(Index(c)).head(k));
      if (along <= 100.0 * contacts[c].eps) stop_seen_[c] = 1;
    }
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
  // the width of the last switch's bracket (the restart is at its old end)
  double switch_width() const { return switch_width_; }
  // true when every function that switched at the last switch event is on its new side
  bool switch_settled(double t, const double* x);
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
  void initial_switch_sides(double t, const double* x);
  // the time just before the first switch in (t0, t1], or NaN (bracket end into hi)
  double find_switch(double t0, const double* x0, double t1, const double* x1,
                     const detail::SegmentHooks::Dense& dense, double& hi);
  // after a switch event at t: true when the run chatters (`message` then says so)
  bool switch_chatters(double t, std::string& message);

  // --- a restart at a dead centre (run_events.cpp; docs/reliability.md, "Open") -------------
  // The rank margin (Workspace::rank_margin) of the constraints active now at (t, x), from an
  // evaluation in the branch check's workspace; NaN when none (Algorithm::kTextbook). Cost: one
  // evaluation.
  double rank_margin_at(double t, const double* x);
  // A restart at (t, x) — a switch event, a release or an activation — where the constraints
  // nearly lose rank is bridged past the pose: near it the
  // constraints hold the branch only to the position tolerance ε (the twin arms' θ₁² − θ₂²),
  // and a state within about √ε of it is as near the mirror branch as its own, so a restart
  // there — its projection, or its first short steps — can take the mirror branch. Below
  // kCarriedMargin (where a contact carried through a dead centre restarts) the bridge
  // keeps q' (the branch is fixed by the velocity, which the degenerate velocity constraint
  // cannot fix) and steps over the pose to t + h, the first h (doubled from 1e-12 |t|) where the
  // margin is back to kCarriedMargin, by q(t+h) = q + h q' + h²/2 q''(t+h), q'(t+h) = q' + h
  // q''(t+h) (W likewise), q'' evaluated at the landing only (projected onto the constraints
  // there), then projected: its error O(h² q''') in q'. Returns t + h with x the state there, or
  // t (x unchanged) when the restart is not at a rank drop or no h ≤ h_max (and < b − t)
  // reaches the margin. `status` is the landing projection's (kOk otherwise). Cost: about
  // 25 evaluations at a bridged restart, one otherwise.
  // `ahead`: (t, x) lies outside the neighbourhood (its margin below kSingularMargin), the
  // pose ahead (an entry, see entered_dead_centre): the landing is the first h where the
  // margin, after falling below half its start's, is back to it, and q'' varies linearly
  // from the start's to the landing's (exact for q'' linear in t; the error O(h³ q'''')); from
  // an entry's end inside the neighbourhood, the start's on the line through the entering
  // step's start and the landing (inside, q'' is a roundoff off the branch times the inverse
  // margin).
  // `after`: the landing lies past it (a bridge across a breakpoint, with the constraints of
  // the segment after it).
  double bridge_dead_centre(double t, double b, double h_max, double* x, ConstrainedOde& ode,
                            Status& status, bool ahead = false,
                            double after = -std::numeric_limits<double>::infinity());
  // the state of the last bridge at s in [its start, its end] (by the bridge's formula) into
  // out (size of x): the samples it steps over
  void bridged_state(double s, double* out) const;
  // The last event found by find_event is no switch but a restart of dopri5, rkf78 or BDF
  // (bridging_entries) to be bridged past a dead centre (bridge_dead_centre with `ahead`), from
  // outside the pose's neighbourhood where the constraints nearly lose rank: at the end of a
  // step that entered it (the rank margin there, rank_margin_at, below kCarriedMargin, at the
  // last step end judged above); at the start of a step that jumped onto another branch near
  // it (q' turned by more than kStepFactor times the accelerations at the start allow, the test
  // of leaves_branch); at the start of a step in which a switch is located at the pose and
  // that ends inside it; or just before a switch located where the margin is below
  // kBridgedSwitchMargin. Under rkf78 an entry, and a step that passes through the
  // neighbourhood and ends outside, are bridged from outside instead: from the step's start or
  // the last point of its dense output checked whose margin is kCrossingRestartMargin
  // (enters_dead_centre). Restarts inside the neighbourhood, and steps that go on there, left
  // the branch: a state within about √ε of the pose is as near the mirror branch as its own,
  // and q' at the pose is fixed only to roundoff (docs/reliability.md, "Open"). Each start is
  // tried once: a failed bridge leaves the run to go on (and Run::leaves_branch to judge it).
  bool entered_dead_centre() const { return entered_; }
  // whether find_event ends a step at such an entry (set by the driver for each segment):
  // a run whose switches it locates, or whose Coulomb contacts all have mu = 0 (no
  // carry-through of theirs), or a segment whose end is a breakpoint (a constraint released or
  // activated there, at a pose)
  void set_bridging_entries(bool on) { bridging_entries_ = on; }
  // after a bridge to (t, x): each switching function that is across its side there takes its
  // new side (the bridge stepped over its switch); returns how many did
  std::size_t sides_after_bridge(double t, const double* x);

  // --- Coulomb contacts: stick, slide, or slide through v_rel = 0 (run_stick_slip.cpp;
  // docs/friction.md) ---------------------------------------------------------------------------
  // the friction force while sliding, the stick constraint while sticking
  void apply_contact_modes();
  // initial modes: a contact at rest sticks when sticking is admissible, else slides
  void initial_contact_modes(double t, double* x);
  // a Coulomb contact whose normal constraint is a unilateral contact that is open: no normal
  // force, so no friction (N = 0), no stick and no stop events (docs/contact.md, "Friction")
  bool separated(std::size_t c) const {
    const Index k = sys_.friction_contacts()[c].normal_constraint;
    return sys_.constraint(k).is_unilateral() && ws_.activity_override[std::size_t(k)] == 0;
  }
  // the modes after an impact or release of unilateral contacts at (t, x)
  void contacts_changed(double t, double* x);
  // a contact with mu = mu_static = 0 exerts no friction in any mode: it never sticks, and its
  // stops and reversals are no events (each would restart the integrator for nothing)
  bool frictionless(std::size_t c) const { return sys_.friction_contacts()[c].mu_static == 0.0; }
  // switches the contact found by the last find_event at (t, x)
  Status switch_contact(double t, double* x);
  // --- the sticks and slips listed (run_events.cpp; RunStatistics::contact_events) ---
  // before the driver hands an event at state x to the Coulomb contacts (a stop, a release, an
  // impact's aftermath): their modes and the state then; no slip noted yet
  void before_mode_change(const double* x);
  // after it: each contact that stuck or slipped since before_mode_change, listed in time order
  // (its sliding speed before and at x after; a slip's holding force and mu_s N when noted)
  void list_mode_changes(double t, const double* x);

  // --- samples and progress (run_output.cpp) ---------------------------------------------------
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

  // the method taking the steps from now on (for the progress report; and whether stops are
  // read from the stages too, see arm_stops)
  void set_integrator(Integrator method) {
    progress_.integrator = method;
    screens_stops_ =
        method == Integrator::kRK4 || method == Integrator::kRK5 || method == Integrator::kRKF78;
  }
  // records a sample at t from the state x (projected first, when projecting); returns
  // kInterrupted after recording it when a stop was requested, unless it is the `last` one
  Status record(double t, const double* x, bool last = false);

  const std::string& failure() const { return failure_; }
  // the unilateral contacts, whose impacts' work record() writes (docs/contact.md)
  void set_contacts(const detail::ContactEvents* contacts) { contacts_ = contacts; }
  // true when the unilateral constraint k is the normal of a Coulomb contact that sticks with
  // others and some split of their holding forces lies inside every cone with k pushing
  // (holding_split with N along the push only): its multiplier, the minimum-norm split's, may
  // pull without a release (ContactEvents::set_held). Cost: one evaluation and a split search,
  // only for a stuck contact whose multiplier pulls.
  bool holds_pushing(Index k, double t, const double* x);

 private:
  // (run_drift.cpp)
  // after an accepted step: the run diverges (see diverged) at a crawl
  bool diverges(double t, const double* x);
  // after an accepted step: the motion left its branch at a singular configuration
  bool leaves_branch(double t, const double* x);
  // the branch check's own workspace, in the run's modes (see leaves_branch)
  Workspace& branch_workspace();
  static constexpr double kBranchFactor = 10.0;
  // (a step inside the passage, held to the accelerations at its entry, with room for their
  // growth inside: of the suite's runs that keep their branch, the largest step change is 0.085
  // of this bound (the twin arms with friction), the four-bars' 0.03; the twin arms' slow passage
  // under rkf78 and BDF reaches 1.1-1.5 at its first step off the branch, a switch or release at
  // a dead centre 7e3 and beyond)
  static constexpr double kStepFactor = 30.0;

  // (run_output.cpp)
  // whether a sample time in (last recorded sample, t] has not been recorded yet
  bool sample_due(double t) const {
    return samples_ && next_sample_ < samples_->size() && (*samples_)[next_sample_] <= t;
  }
  // reports the progress of a step to t (SimulationOptions::progress)
  void report_progress(double t);

  // (run_stick_slip.cpp; relative_velocity and locate also serve run_events.cpp)
  // contact c's v_rel at (t, x) into the head of v; returns its length
  Index relative_velocity(std::size_t c, double t, const double* x, VectorXd& v) {
    q_ = Eigen::Map<const VectorXd>(x, n_);
    qd_ = Eigen::Map<const VectorXd>(x + n_, n_);
    detail::sliding_velocity(sys_, ws_, Index(c), q_, qd_, t, false);
    const Index k = sys_.friction_contacts()[c].size();
    v.head(k) = ws_.sliding.col(Index(c)).head(k);
    return k;
  }

  // the first s in (t0, t1] with g(s) <= 0, by bisection on the dense output (g(t0) > 0 is
  // assumed), or NaN when g(t1) > 0 (x1 null: g(t1) <= 0 is known)
  // (the last time found with g > 0 into *last_positive when given)
  template <class G>
  double locate(double t0, double t1, const double* x1, const detail::SegmentHooks::Dense& dense,
                G&& g, double* last_positive = nullptr) {
    if (x1 != nullptr && g(t1, x1) > 0.0) return std::numeric_limits<double>::quiet_NaN();
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
  // constraints with the stick rows have no solution there
  double stick_margin(std::size_t c, double t, const double* x);
  // stick_margin's split of the reaction on the contact-point path (ContactKinematics)
  double point_stick_margin(std::size_t c, const FrictionContact& contact, double t);
  // sticks contact c at (t, x) when sticking is admissible; else false
  bool try_stick(std::size_t c, double t, double* x, bool report = true);
  // stick_margin from the evaluation just made with the contact sticking (at q_, qd_, t)
  double stick_margin_here(std::size_t c, double t);
  // --- several contacts sticking together (run_stick_slip.cpp, "Several contacts";
  // docs/friction.md, "Several contacts") ---
  // at contact c's stop: c and every other contact stopped with it stick together when that is
  // admissible jointly, else c alone (try_stick)
  bool try_stick_together(std::size_t c, double t, double* x, bool report = true);
  // the release test of sticking contact c with others sticking: its stick_margin while the
  // minimum-norm split holds in every cone; else positive while some split does, negative when
  // none does
  double group_margin(std::size_t c, double t, const double* x);
  // after a release at (t, x) (of `first`): the contacts still sticking that no split can hold
  // slip too (each counted as an event when `events`), those released into released_
  void release_unheld(double t, double* x, bool events = true,
                      std::size_t first = std::numeric_limits<std::size_t>::max());
  // the contacts released_ slide from rest together: friction against their joint impending
  // motion (at q_, qd_, t)
  void slide_together(double t);
  // the contacts `rest` at rest at (t, x) (at the start, after an impact) stick together with
  // the sticking ones, less those no split holds; one at a time when that is not admissible
  void stick_at_rest(double t, double* x, const std::vector<std::size_t>& rest);
  // the contacts sticking in mode_ and not in modes_before_ stick jointly at (t, x) when
  // admissible, with a split inside every cone (`split`) or releasing those none holds; else
  // mode_ = modes_before_ and false
  bool stick_jointly(double t, double* x, bool split);
  // the sticking contacts, at the evaluation just made: 1 when every one's minimum-norm margin
  // is >= 0, 0 when a split of the holding forces inside every cone exists (the correction of
  // the multipliers into split_), -1 when none does; the most negative margin's contact into
  // *worst when given
  // (without `search`, 0 means only that one exists: split_ is left zero)
  int holding_split(double t, std::size_t* worst = nullptr, bool search = true);
  // the holding force of sticking contact stuck_[i] at holding_split's split of largest margin,
  // into holding_ (as stick_margin_here leaves it)
  const VectorXd& split_holding(std::size_t i);
  // the sticking contacts (not separated) into stuck_; returns their count
  std::size_t sticking_contacts();
  // the kinetic energy that projecting the velocities of x onto contact c's stick rows removes
  double stick_energy_loss(std::size_t c, double t, const double* x, ProjectionResult& rv,
                           double& T_before);
  // the kinetic energy a stick of contact c may remove (rule 1 of try_stick), at a state just
  // evaluated: rtol · the largest of the run, and at least ½ m (10 v_stop)², m = 1ᵀ M 1 / n the
  // mass scale of M there — a slide stops at v_stop = 100 eps whatever its speed before, so a
  // slow one (2 mm/s, or 2 m/s written in km) removes ½ m v_stop², which rtol · its small
  // kinetic energy refused (docs/friction.md, "Stick and slip")
  double stick_allowance(std::size_t c, double T_before) {
    change_.setConstant(10.0 * 100.0 * sys_.friction_contacts()[c].eps);
    const double stop = detail::kinetic_energy(ws_, change_) / double(n_);
    return std::max(std::max(o_.rtol, 1e-14) * std::max(peak_kinetic_, T_before), stop);
  }
  // the holding force of sticking contact c and mu_s N, where stick_margin (or _here) just gave
  // `margin` (holding_ the force that held it), for the slip about to be listed
  void note_slip(std::size_t c, double margin) {
    if (c >= slip_holding_.size()) return;
    slip_holding_[c] = holding_.norm();
    slip_limit_[c] = margin + slip_holding_[c];
  }
  // contact c's stop at te is a kinematic passage at a rank drop (no restart there)
  bool passes_at_rank_drop(std::size_t c, double te, const detail::SegmentHooks::Dense& dense);
  // contact c, sliding near a rank drop, is carried through the dead centre
  bool carry_through(std::size_t c, Index k, double t1, const double* x1, double v_stop);
  // the restart after a carried contact's zero of v_rel at tz
  double carried_past(double tz, double t1, const double* x1,
                      const detail::SegmentHooks::Dense& dense);
  // contact c's carried friction force is held (see carry_through)
  bool held(std::size_t c) const {
    return ws_.slip_hint_held[std::size_t(sys_.friction_contacts()[c].force)] != 0;
  }
  // sign × contact c's passing direction on its sliding coordinates, into holding_ (n)
  const VectorXd& carried_direction(std::size_t c, double sign);
  // contact c slides from v_rel = 0 against its impending motion; false when friction could
  // hold it
  bool start_sliding(std::size_t c, double t, const double* x);
  // a_rel = P (q''_c − u') of contact c from the last evaluation into velocity_
  void relative_acceleration(std::size_t c, double t);
  // the run's class of accelerations, v² / ℓ (set_run_scales), 0 before the scales are set
  double acceleration_scale() const;
  // contact c's slip hint against the a_rel that relative_acceleration left in velocity_
  void hint_against_acceleration(std::size_t c);
  // the direction of the friction at |v_rel| <= eps (the contact's slip hint)
  void set_slip_hint(std::size_t c, const Eigen::Ref<const VectorXd>& along);

  // the largest violations of the run so far (RunStatistics) take in (p, v)
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
  Quadratures* quad_;  // a caller's integrals after the work channels (may be null)
  // the work channels after q, q' in x (quiet unless BDF, see WorkLayout)
  detail::WorkLayout works_ = detail::WorkLayout(sys_, o_.integrator != Integrator::kBDF, quad_);
  std::vector<double> sample_ = std::vector<double>(std::size_t(2 * n_ + works_.count));
  ProjectionOptions projection_;
  bool projecting_ = false;
  std::vector<ContactMode> mode_;                // (contacts) what contact c does
  std::vector<unsigned char> separated_before_;  // (contacts) normal contact open before an event
  MatrixXd passing_ = MatrixXd::Zero(
      sliding_width(sys_, n_),
      Index(sys_.friction_contacts().size()));  // (sliding width × contacts)
                                                // head of col c: v_rel's direction when c passes
  std::vector<double> trial_ = std::vector<double>(sample_.size());  // a trial state
  double peak_kinetic_ = 0.0;  // largest kinetic energy at the samples so far
  double energy_scale_ = 0.0;  // largest T + |V| of the early samples (see diverged)
  double last_step_end_ = -std::numeric_limits<double>::infinity();  // t of the last step
  int crawling_steps_ = 0;  // steps in a row, up to now, that diverged at a crawl
  // a passage of a singular configuration (see leaves_branch): under way; its start's time, the
  // M-norm of q'' there, and q' there (n)
  std::unique_ptr<Workspace> branch_ws_;     // (branch_workspace)
  std::function<void(Workspace&)> started_;  // (set_started)
  bool in_pose_ = false;
  double pose_t_ = 0.0, pose_acceleration_ = 0.0, pose_margin_ = 0.0, step_t_ = 0.0;
  VectorXd pose_velocity_ = VectorXd::Zero(n_), step_velocity_ = VectorXd::Zero(n_);
  VectorXd change_ = VectorXd::Zero(n_);         // (n) scratch of leaves_branch
  VectorXd holding_ = VectorXd::Zero(n_);        // (n) holding force of the last stick_margin
  VectorXd reaction_ = VectorXd::Zero(n_);       // (n) scratch of stick_margin: R
  VectorXd reaction_part_ = VectorXd::Zero(n_);  // (n) scratch of stick_margin
  VectorXd normal_ = VectorXd::Zero(n_);         // (n) scratch of stick_margin: R_N
  MatrixXd normals_;                             // (rows × n) the normal constraint's rows of A
  std::vector<std::size_t> stuck_;               // (sticking_contacts) the sticking contacts
  std::vector<std::size_t> rest_;                // (contacts) the contacts at rest to decide
  std::vector<std::size_t> released_;            // (contacts) released by release_unheld
  std::vector<ContactMode> modes_before_;        // (contacts) modes before a joint stick
  VectorXd split_;  // (m) holding_split: the change of the multipliers to the feasible split
  MatrixXd split_rows_, split_null_, split_G_;  // (holding_split scratch, sized at its calls)
  VectorXd split_h_;                            // (holding_split scratch)
  double split_lowest_ = 0.0;                   // holding_split: the lowest minimum-norm margin
  bool split_push_only_ = false;  // holding_split: unilateral N along the push only (holds_pushing)
  // holding_split: the sticking contacts' forces on the split's coordinates (stuck_'s order),
  // the largest margin of a split inside every cone (relative to the forces; NaN where not
  // solved) and its split (nz), whether that decided (split_exact_), and the index into stuck_
  // of the contact least held there when none holds
  SplitSpace space_;
  std::vector<SplitCone>& split_cones_ = space_.cones;
  VectorXd lambda_total_;             // (m) holding_split: Λ = λ + λ_nonideal
  std::vector<std::size_t> sliding_;  // (contacts) holding_split: the closed ones sliding
  double split_margin_ = 0.0;
  VectorXd split_y_;
  bool split_exact_ = false;
  std::size_t split_worst_ = 0;
  // group_margin's last split search (not the minimum-norm case): its t, x (2n) and answer; t NaN
  // when the modes changed since
  double group_t_ = std::numeric_limits<double>::quiet_NaN(), group_margin_ = 0.0;
  std::vector<double> group_x_;
  // holding_split's rounds of cutting planes (each adds one per violated cone): the boxes'
  // splits converge in 5 to 8 to 1e-7 of the forces, except within about that of a breakaway
  static constexpr int kSplitRounds = 16;
  VectorXd velocity_ = VectorXd::Zero(sliding_width(sys_, n_));        // (width) sliding velocities
  VectorXd direction_ = VectorXd::Zero(sliding_width(sys_, n_));       // (width) the step's start's
  std::vector<double> event_x_ = std::vector<double>(sample_.size());  // dense state
  // (contacts) the earliest stage time in the step at which sticking contact c's margin was
  // negative (screen_sticking), or NaN
  std::vector<double> stick_screened_ = std::vector<double>(
      sys_.friction_contacts().size(), std::numeric_limits<double>::quiet_NaN());
  // sticking contact c's slip inside [t0, t1] (from x0 at t0) that the stages saw
  // (screen_sticking), confirmed on the dense output and located, or NaN (run_events.cpp)
  double screened_slip(std::size_t c, double t0, const double* x0, double t1,
                       const detail::SegmentHooks::Dense& dense);
  // (see arm_stops) rk4, rk5, rkf78: stops are read from the stages too
  bool screens_stops_ = false;
  // (width × contacts) column c: sliding contact c's direction of motion that screen_stops reads
  // the speed along, where stop_armed_[c]; stop_seen_[c]: an evaluation since it was last reset
  // had that speed at or below v_stop
  MatrixXd stop_direction_ =
      MatrixXd::Zero(sliding_width(sys_, n_), Index(sys_.friction_contacts().size()));
  std::vector<unsigned char> stop_armed_ =
      std::vector<unsigned char>(sys_.friction_contacts().size(), 0);
  std::vector<unsigned char> stop_seen_ =
      std::vector<unsigned char>(sys_.friction_contacts().size(), 0);
  // sliding contact c's direction of motion at (t, x) for screen_stops, if faster than v_stop
  void arm_stop(std::size_t c, double t, const double* x, double v_stop);
  // under rk4, rk5, rkf78: sliding contact c's stop inside [t0, t1] (its speed along direction_,
  // the step's start's, of length k, falling to v_stop), from the step's end and its stages,
  // located by bisection on steps of the method whose stages are read too; or NaN
  double locate_stop(std::size_t c, Index k, double t0, double t1, const double* x1,
                     const detail::SegmentHooks::Dense& dense, double v_stop);
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
  // the last bridge over a dead centre (bridge_dead_centre): its start time and state, and the
  // rate x' at its landing (size of x)
  double bridge_t_ = 0.0, bridge_h_ = 1.0;  // (its start and length)
  std::vector<double> bridge_rate0_;        // (size of x) x' at its start
  std::vector<double> bridge_x_ = std::vector<double>(sample_.size());
  std::vector<double> bridge_rate_ = std::vector<double>(sample_.size());
  // the switch that opened the window of the crawl test (NaN: none open), and the accepted
  // steps since then (up to kSwitchBurst)
  double window_start_ = std::numeric_limits<double>::quiet_NaN();
  std::size_t steps_since_switch_ = 0;
  bool crawl_ = false;       // the steps after a switch crawl (find_event)
  bool approach_ = false;    // the last event is a restart before a switch
  bool hands_over_ = false;  // the last event is rkf78 handing the run to dopri5
  bool landed_ = false;      // the last switch found is a step landing on it
  // dead-centre entries (see entered_dead_centre): located for this segment; the last event is
  // one; a step ended outside the neighbourhood since the last one (an entry may fire)
  bool bridging_entries_ = false;
  bool entered_ = false;
  bool entry_armed_ = true;
  // the rank margin at the last step end judged, and the step start where the last jump was
  // found (a step that jumps again from there is left to leaves_branch)
  double entry_margin_ = std::numeric_limits<double>::infinity();
  double entry_failed_ = std::numeric_limits<double>::quiet_NaN();
  // find_event (see entered_dead_centre): the step is near a rank drop; it jumped onto another
  // branch (bridged from t0); it ends an entry into the neighbourhood (bridged from t1; under
  // rkf78, or when it passes through the neighbourhood, from t0 or a point inside the step)
  bool near_dead_centre();
  bool jumps_branch(double t0, const double* x0, double t1, const double* x1);
  double enters_dead_centre(double t0, const double* x0, double t1, const double* x1,
                            const detail::SegmentHooks::Dense& dense);
  // (rkf78: a step's dense output is checked for a passage through the neighbourhood at the
  // interior points t0 + k (t1 − t0) / kCrossingSamples; the bridge starts at the last one whose
  // rank margin is at least kCrossingRestartMargin. Measured on the twin arms' slow passage:
  // restarts from 1e-4 took states within 1.9e-5 rad of the pose, their q' already off by 0.3 %
  // (energy balance 1.3e-5); from 4e-4 and from t0 alone, bridges of up to 1.2e-2 and 1.6e-2 s,
  // q'' linear across them (1.4e-6 and 2.8e-6); 2e-4: 1.5e-7)
  static constexpr int kCrossingSamples = 16;
  static constexpr double kCrossingRestartMargin = 2e-4;
  // the start of the step whose end an entry bridges from (NaN: none), and its state
  double entry_t0_ = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> entry_x0_ = std::vector<double>(sample_.size());
  std::string failure_;
  const detail::ContactEvents* contacts_ = nullptr;  // (see set_contacts)
  // (contacts) the modes at before_mode_change, and a slip's holding force and mu_s N noted
  // since (NaN: none); (size of x) the state at before_mode_change
  std::vector<ContactMode> listed_modes_;
  std::vector<double> slip_holding_, slip_limit_, listed_x_;
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

}  // namespace ukdyn::detail

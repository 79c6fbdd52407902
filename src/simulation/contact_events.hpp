// SPDX-License-Identifier: BSD-3-Clause
// The events of unilateral contacts in a run (docs/contact.md): a closed contact is an ordinary
// row of A; an open one is not. find() locates, after each accepted step, the first impact (an
// open gap closing) or release (a closed contact's multiplier turning to pull); handle() then
// applies it: the velocity jump of the impact, and the set of contacts that stay closed (the
// LCP). Nothing here runs in a step of a run without unilateral constraints, and a step of a run
// with them costs one or two evaluations of each open gap (no LCP while nothing changes sign),
// kSweepPoints more for a moving one, and a sign test per closed contact at each stage (screen).
#pragma once

#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dynamics/contact_dynamics.hpp"
#include "simulation/integrator.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::detail {

// The run cannot start because the contacts at its initial state cannot be solved (Painlevé's
// paradox: a sliding Coulomb contact past its critical mu; an LCP with no solution): thrown by
// ContactEvents::start, a std::invalid_argument as before, which also names the contacts at
// fault so that the model's front ends point at their entries (locate_contact_start,
// modelfile/contact_start.hpp).
class ContactStartError : public std::invalid_argument {
 public:
  // what: the full message; contacts: the names of the contacts at fault (may be empty)
  ContactStartError(const std::string& what, std::vector<std::string> contacts)
      : std::invalid_argument(what), contacts_(std::move(contacts)) {}
  const std::vector<std::string>& contacts() const { return contacts_; }

 private:
  std::vector<std::string> contacts_;
};

class ContactEvents {
 public:
  // an impact slower than this fraction of the contact's fastest impact of the run closes it
  // (e = 0 for that impact): the rest criterion that ends an accumulation of impacts (Zeno)
  static constexpr double kRestFraction = 1e-6;
  // an open gap at most this far from zero takes part in an impact (simultaneous contacts)
  static constexpr double kTouchGap = 1e-9;
  // a gap rate at most this large is roundoff, not motion: an open contact closes by an impact
  // only when it approaches faster, a touching contact that leaves an impact slower stays
  // closed, and a touching open contact that moves slower (an unloaded corner of a box on four
  // corners: W singular, the LCP's vertex) must penetrate by kTouchGap before it is hit.
  // Relative to the contact's speed unit (still_rate), as kTouchGap to its length unit (the
  // class of ‖a‖ ℓ of its row / 10: 1 in SI units, docs/simulation.md)
  static constexpr double kStillRate = 1e-9;
  // a closed contact's multiplier above −kUnloaded times the largest load of the closed contacts
  // is roundoff of zero (the unloaded corner again), not a release; an opened contact whose gap
  // acceleration after the LCP is at most kUnloaded times the contacts' free ones stays touching
  // unloaded and is no release event either
  static constexpr double kUnloaded = 1e-9;
  // a run is declared chattering when kChatterEvents impacts and releases fall within
  // kChatterSpan of its time span (a rate, not a count: an elastic ball bouncing every 0.09 s
  // for 10⁴ s makes 110 700 regular impacts)
  static constexpr long kChatterEvents = 10000;
  static constexpr double kChatterSpan = 1e-4;
  // ... unless they converge: the newest impact of those events is slower than kConverging times
  // the oldest (an accumulation of impacts that the rest criterion ends, kRestFraction: a ball at
  // e = 0.999 makes its last 10 000 impacts in 20 s, 4.5e-5 of the first's speed, within 1e-4 of
  // a span of 10⁶ s)
  static constexpr double kConverging = 0.5;
  // handle() stops the run when more than this many events are located and handled at one
  // instant (t within 1e-14 |t|, locate()'s bracket), listed or not: the integrator would locate
  // the same event for ever (an impact whose answer leaves a contact penetrated and receding
  // lists nothing, so the chattering test never counts it). A real sequence at one instant (a
  // release then an impact elsewhere) is a few events per contact
  static constexpr int kSameInstantEvents = 1000;
  // the gap of an open contact that depends explicitly on t (a moving surface: the vibrating
  // table, a cam) is screened at this many equally spaced interior points of each step's dense
  // output (sweep): the step size knows nothing of the surface's motion
  static constexpr int kSweepPoints = 16;

  // x_size: the size of the run's state x = [q; q'; W]; span: the run's t_end − t_start
  ContactEvents(const System& sys, Workspace& ws, std::size_t x_size, double span);

  // the run's units (SimulationOptions::units), for the notes' times
  void set_units(const UnitSystem& units) { units_ = units; }
  // an integrator that cannot follow a flight far below its tolerance (BDF: CVODE restarts at
  // order 1 after every event, whose error on a flight at constant acceleration a is h² a / 2 per
  // step, not zero as for the Runge–Kutta methods): an impact whose flight since the contact
  // left its last impact or release rose less than kUnresolvedFlight × rtol × its gap's length
  // scale (apex ≈ speed × flight time / 4) ends the contact's sequence as the rest criterion
  // does, and the group rest holds the touching contacts that leave slower than it came. 0 (the
  // default): off. (Under BDF a rocking block's 51st landing came 35 times faster than its 50th,
  // 1.8e-6 m/s, and it rested 2.7e-4 s after t∞; a ball on a vibrating table stalled at steps of
  // 5e-16 s.)
  void set_flight_tolerance(double rtol) { flight_rtol_ = rtol; }
  // the unresolved flight's factor (set_flight_tolerance)
  static constexpr double kUnresolvedFlight = 10.0;
  // held(k, t, x): true when the closed contact k (a System index), whose multiplier at (t, x)
  // pulls, is nevertheless held pushing: the normal of a Coulomb contact that sticks with others,
  // whose holding forces some split holds inside every cone with k pushing (Run::holds_pushing).
  // The multiplier of such a contact is the minimum-norm split's, which depends on the units
  // and on how its rows are written: no release then (the friction's slip event decides).
  void set_held(std::function<bool(Index k, double t, const double* x)> held) {
    held_ = std::move(held);
  }
  // true when the system has unilateral constraints
  bool any() const { return !dyn_.contacts().empty(); }
  // each contact's mode into ws.activity_override (closed 1, open 0), and the rows of the closed
  // ones for screen() and find()'s quiet step. O(contacts), no allocation
  void apply();
  // the initial modes at (t, x = [q; q'; …]): an open gap, a closed contact that pushes, or an
  // impact at the start (x's velocities jump). @throws InconsistentInitialState naming a
  // penetrated contact (g < −tolerance), ContactStartError when the contacts cannot be solved
  // there (Painlevé's paradox: naming its contacts). False, with failure() set and every contact
  // open, when a gap or gap rate is not finite there (failure_status(): kNonFiniteInput)
  bool start(double t, VectorXd& q, VectorXd& qd, double tolerance, RunStatistics& stats);
  // the first impact or release in (t0, t1] (see SegmentHooks::find_event), NaN for none; or
  // the last time before an open contact's gap or gap rate turns non-finite (NaN, Inf: its
  // expression left its domain), where handle() then stops the run
  // A step of a run whose contacts are all closed, none pulling at a stage (screen) or in the
  // step's last evaluation, has none: one sign test per contact, inline (bench/RESULTS.md, "A
  // closed contact against the bilateral constraint it replaces"); else search()
  double find(double t0, const double* x0, double t1, const double* x1,
              const SegmentHooks::Dense& dense) {
    if (closed_rows_.size() == closed_.size() && !any_pulled_ && ws_.status == Status::kOk) {
      const double* lambda = ws_.lambda.data();
      const double* extra = ws_.lambda_nonideal.data();
      bool push = true;
      for (const Index row : closed_rows_) push = push && lambda[row] + extra[row] > 0.0;
      if (push) return std::numeric_limits<double>::quiet_NaN();
    }
    return search(t0, x0, t1, x1, dense);
  }
  // at each evaluation of the integrator's stages (ConstrainedOde::watch_releases), after its
  // forward dynamics at time t: the earliest such t at which a closed contact's multiplier pulls
  // (below −kUnloaded of the largest load), per contact, for find()'s release test. One sign
  // test per closed contact while all push (inline: the common case of every evaluation of a
  // run with contacts, ~4 instructions a contact); no evaluation, no allocation
  void screen(double t) {
    const double* lambda = ws_.lambda.data();
    const double* extra = ws_.lambda_nonideal.data();
    for (const Index row : closed_rows_) {
      if (!(lambda[row] + extra[row] >= 0.0)) [[unlikely]] {
        screen_pulls(t);
        return;
      }
    }
  }
  // applies the event find() located, at (t, x) (x's velocities may jump); false with
  // failure() set when the contacts' dynamics cannot be solved there, or the event is a
  // non-finite gap
  bool handle(double t, double* x, RunStatistics& stats);
  // the work of the impacts so far: Σ (T⁺ − T⁻) <= 0
  double impact_work() const { return impact_work_; }
  const std::string& failure() const { return failure_; }
  // the status of failure(): kNonFiniteInput for a non-finite gap, else kIntegratorFailure
  Status failure_status() const {
    return nonfinite_ ? Status::kNonFiniteInput : Status::kIntegratorFailure;
  }

 private:
  // resolves the contacts at (t, x): the impact of the touching ones when `event` (a contact
  // index, or −1) or any touching one approaches, then the closed set
  bool resolve(double t, double* x, Index event, RunStatistics& stats);
  // contact i (a position in contacts()) at gap g takes part in resolving `event`: closed, the
  // event's, or an open gap within kTouchGap (NaN counts). O(1)
  bool takes_part(std::size_t i, Index event, double g) const;
  // the touching contacts at (t, x) (closed, the located event's, or an open gap within
  // kTouchGap), each with its gap, rate and mode, for a message. O(contacts)
  std::string touching_names(double t, const double* x);
  // the event ev into stats.contact_events, its time into recent_ (the chattering test)
  void list(const ContactEvent& ev, RunStatistics& stats);
  // the events of recent_ converge: its newest impact is slower than kConverging times its
  // oldest (a Zeno sequence the rest criterion ends, not chattering). O(kChatterEvents) at most;
  // run only when the events fall within the chattering window
  bool converging() const;
  // each contact of `opened` (System indices, closed before the event at t): its whole
  // multiplier with the contacts closed as they were (was_closed, per contact), at q and the
  // velocities before the event (qd_before_), into force (one evaluation; NaN when it fails)
  void forces_before(double t, const Eigen::Ref<const VectorXd>& q,
                     const std::vector<unsigned char>& was_closed, const std::vector<Index>& opened,
                     std::vector<double>& force);
  // after the LCP of a release event at t kept the event's contact k (a System index) closed
  // (candidates: the LCP's contacts): true when k's multiplier with the decided modes pushes
  // (one evaluation); else false with failure_ naming the contact, t, and both signs
  bool hold_pushes(double t, const Eigen::Ref<const VectorXd>& q,
                   const Eigen::Ref<const VectorXd>& qd, const std::vector<Index>& candidates,
                   Index k);
  // the first s in [t0, t1] where f(s) < level, by bisection on dense output (f(t0) >= level),
  // to 1e-14 |t|: for a gap the last s found with f >= level, for a multiplier the first < 0
  double locate(double t0, double t1, const SegmentHooks::Dense& dense, Index k, bool gap,
                double level);
  // f of contact k at (t, x): its gap, or its multiplier in the run's evaluation
  double value(Index k, bool gap, double t, const double* x);
  // find() for a step that may hold an event: every contact's impact or release test.
  // O(contacts) without an event; an open contact's test is one or two gap evaluations
  // (kSweepPoints more when it moves), a release's ≤ 2 evaluations and a bisection
  double search(double t0, const double* x0, double t1, const double* x1,
                const SegmentHooks::Dense& dense);
  // screen()'s rest, once a closed contact's multiplier is negative or NaN: pulled_ and
  // any_pulled_. O(contacts)
  void screen_pulls(double t);
  // closed contact k's multiplier at (t, x) pulls beyond roundoff of zero (below −kUnloaded of
  // the largest load of the closed contacts in that evaluation). One evaluation
  bool pulls(Index k, double t, const double* x);
  // the release of closed contact k in (t0, t1]: where its multiplier turns negative, when the
  // step's stages (screen) or its end see it pull; NaN for none. No evaluation while it pushes
  // at every stage and at t1; else ≤ 2 evaluations and a bisection (one per halving)
  double release(double t0, const double* x0, double t1, const double* x1,
                 const SegmentHooks::Dense& dense, Index k);
  // open contact k's gap depends explicitly on t at state x (its rate at q' = 0, ∂g/∂t, is not
  // zero at t): remembered for the run in moving_. One gap evaluation until it is found
  bool moving(Index k, double t, const double* x);
  // an impact of open contact k (moving) inside the step that the step's ends do not show: the
  // gap below level, or a dip of it, between kSweepPoints equally spaced points of the dense
  // output (from g0' = gd0 at t0); the located impact time, or NaN. Cost kSweepPoints gap
  // evaluations per step (and a bisection when it finds one)
  double sweep(double t0, double gd0, double t1, const SegmentHooks::Dense& dense, Index k,
               double level);
  // a dip of open contact k's gap within a step that ends open: when its rate falls at t0
  // (gd0 < 0) and rises at t1 (gd1 > 0), the time of the gap's minimum in between (bisection
  // on the rate's sign along the dense output) if the gap there is below level, else NaN.
  // Cost ≤ 41 gap evaluations, only for such steps
  double dip(double t0, double gd0, double t1, double gd1, const SegmentHooks::Dense& dense,
             Index k, double level);
  // open contact k approaches at t in [t0, t1] (dense output; x0 at t0): its gap rate below
  // −still_rate (a non-finite gap counts as approaching: the caller's tests see it). One gap
  // evaluation
  bool approaches(Index k, double t0, const double* x0, double t, const SegmentHooks::Dense& dense);
  // contact k's gap g and gap rate gd at (t, x); true when both are finite
  bool finite_gap(Index k, double t, const double* x, double& g, double& gd);
  // the last time in [t0, t1] where open contact k's gap and rate are finite, by bisection on
  // dense output (to 1e-14 |t|; t0 when they are not finite there), with its gap there in g,
  // and the message naming the contact, the first non-finite time and value
  double last_finite(double t0, const double* x0, double t1, const double* x1,
                     const SegmentHooks::Dense& dense, Index k, double& g, std::string& message);
  // the whole multiplier lambda + lambda_nonideal of the unilateral constraint k (a System index)
  // in the last evaluation (pushes when > 0)
  double multiplier(Index k) const;
  // the largest |multiplier| of the closed contacts in the last evaluation (O(contacts))
  double largest_load() const;
  // an open contact at (g, g') on the old side of a step: the level its gap must fall below for
  // an impact (0, or −kTouchGap for a touching contact at rest or just penetrated)
  double impact_level(Index k, double g, double gd) const;
  // the gap rate at most which contact k (a System index) is still: kStillRate times its speed
  // unit, the class of ‖a‖ v of its row / 10 (1 in SI units) or, in a sequence of impacts,
  // the sequence's fastest impact speed when that is slower (at least 1e-6 of the class).
  // O(1)
  double still_rate(Index k) const;

  const System& sys_;
  Workspace& ws_;
  ContactDynamics dyn_;
  Index n_;
  std::vector<unsigned char> closed_;  // (contacts) 1 while closed
  std::vector<unsigned char> pushes_;  // (contacts) closed and pushing at the step's end (find)
  std::function<bool(Index, double, const double*)> held_;  // (set_held; empty: none)
  std::vector<double> fastest_;  // (contacts) fastest impact speed of the current sequence
  std::vector<long> impacts_;    // (contacts) impacts of the current sequence (since a release)
  std::vector<double> left_;     // (contacts) when it last left an impact or a release, or NaN
  double flight_rtol_ = 0.0;     // see set_flight_tolerance (0: off)
  std::vector<double> pulled_;   // (contacts) earliest stage time it pulled (screen), or NaN
  bool any_pulled_ = false;      // some pulled_ is not NaN
  // (closed contacts) their rows, sys_.row_offset(k) (multiplier), as apply() set the modes
  std::vector<Index> closed_rows_;
  std::vector<unsigned char> moving_;  // (contacts) 1 once its gap was seen to depend on t
  std::vector<std::size_t> position_;  // (constraints) k's position in contacts(), or K
  Index event_ = -1;                   // the contact of the event find() located
  bool nonfinite_ = false;             // failure_ is a non-finite gap
  std::string nonfinite_event_;        // the message when that event is a non-finite gap
  VectorXd q_, qd_, xs_;               // (n, n, size of x) scratch
  VectorXd qd_before_;                 // (n) resolve: the velocities before the event
  // the times of the last impacts, rests and releases (up to kChatterEvents, then a ring: the
  // one listed_ % kChatterEvents is the oldest)
  std::vector<double> recent_;
  std::vector<double> recent_speed_;  // (as recent_) each one's impact speed, NaN for a release
  std::size_t listed_ = 0;            // impacts, rests and releases listed so far
  double instant_ = std::numeric_limits<double>::quiet_NaN();  // the t of the last handle()
  int instant_events_ = 0;  // the events handled at instant_ (kSameInstantEvents)
  double span_;             // the run's t_end − t_start
  double impact_work_ = 0.0;
  std::string failure_;
  UnitSystem units_;  // see set_units
};

}  // namespace ukdyn::detail

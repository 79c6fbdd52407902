// SPDX-License-Identifier: BSD-3-Clause
// The events of unilateral contacts in a run (docs/contact.md): a closed contact is an ordinary
// row of A; an open one is not. find() locates, after each accepted step, the first impact (an
// open gap closing) or release (a closed contact's multiplier turning to pull); handle() then
// applies it: the velocity jump of the impact, and the set of contacts that stay closed (the
// LCP). Nothing here runs in a step of a run without unilateral constraints, and a step of a run
// with them costs one evaluation of each open gap (no LCP while nothing changes sign).
#pragma once

#include <string>
#include <vector>

#include "dynamics/contact_dynamics.hpp"
#include "simulation/integrator.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::detail {

class ContactEvents {
 public:
  // an impact slower than this fraction of the contact's fastest impact of the run closes it
  // (e = 0 for that impact): the rest criterion that ends an accumulation of impacts (Zeno)
  static constexpr double kRestFraction = 1e-6;
  // an open gap at most this far from zero takes part in an impact (simultaneous contacts)
  static constexpr double kTouchGap = 1e-9;
  // impacts and releases after which a run is declared chattering
  static constexpr long kMaxEvents = 100000;

  // x_size: the size of the run's state x = [q; q'; W]
  ContactEvents(const System& sys, Workspace& ws, std::size_t x_size);

  // true when the system has unilateral constraints
  bool any() const { return !dyn_.contacts().empty(); }
  // each contact's mode into ws.activity_override (closed 1, open 0)
  void apply() const;
  // the initial modes at (t, x = [q; q'; …]): an open gap, a closed contact that pushes, or an
  // impact at the start (x's velocities jump). @throws InconsistentInitialState naming a
  // penetrated contact (g < −tolerance).
  void start(double t, VectorXd& q, VectorXd& qd, double tolerance, RunStatistics& stats);
  // the first impact or release in (t0, t1] (see SegmentHooks::find_event), NaN for none
  double find(double t0, const double* x0, double t1, const double* x1,
              const SegmentHooks::Dense& dense);
  // applies the event find() located, at (t, x) (x's velocities may jump); false with
  // failure() set when the contacts' dynamics cannot be solved there
  bool handle(double t, double* x, RunStatistics& stats);
  // the work of the impacts so far: Σ (T⁺ − T⁻) <= 0
  double impact_work() const { return impact_work_; }
  const std::string& failure() const { return failure_; }

 private:
  // resolves the contacts at (t, x): the impact of the touching ones when `event` (a contact
  // index, or −1) or any touching one approaches, then the closed set
  bool resolve(double t, double* x, Index event, RunStatistics& stats);
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
  // the whole multiplier lambda + lambda_nonideal of the unilateral constraint k (a System index)
  // in the last evaluation (pushes when > 0)
  double multiplier(Index k) const;

  const System& sys_;
  Workspace& ws_;
  ContactDynamics dyn_;
  Index n_;
  std::vector<unsigned char> closed_;  // (contacts) 1 while closed
  std::vector<unsigned char> pushes_;  // (contacts) closed and pushing at the step's end (find)
  std::vector<double> fastest_;        // (contacts) fastest impact speed so far
  std::vector<long> impacts_;          // (contacts) impacts so far
  Index event_ = -1;                   // the contact of the event find() located
  VectorXd q_, qd_, xs_;               // (n, n, size of x) scratch
  double impact_work_ = 0.0;
  std::string failure_;
};

}  // namespace ukdyn::detail

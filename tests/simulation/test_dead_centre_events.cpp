// SPDX-License-Identifier: BSD-3-Clause
// Events at a rank drop (issue #29 item 1): a switch of a non-smooth force located at a dead
// centre of a linkage, a constraint released and another activated there, and a slow passage
// of it never end ok off the branch the motion is on, the governor's swing
// through its dead centre is right on every adaptive integrator, and a step size that
// collapses near a dead centre is blamed on the singular configuration. The mechanism is the twin
// arms of tests/data/twin_arms_coulomb.yaml: at the bottom (th1 = th2 = 0) the two link rows
// coincide, and the symmetric motion th1 = th2 is that of a model of one coordinate without
// constraints (tests/data/twin_arms_symmetric_reduced.yaml), the reference here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "simulation/integrator.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/ukdyn.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

const std::string kData = std::string(UKDYN_TESTS_DIR) + "/data/";

// coordinate `name` of sample i
double coord(const Model& m, const Trajectory& tr, const std::string& name, Index i) {
  return tr.q[std::size_t(i * tr.n + m.system.coordinate_index(name))];
}

// The reduced model's motion (th) for the twin arms at `mu` from rest at th0, dopri5 at rtol
// 1e-12 (output every `every` s up to t_end): the reference of the tests below
Trajectory reduced_motion(double mu, double th0, double t_end = 3.0, double every = 0.01) {
  const Model reduced =
      load_model(kData + "twin_arms_symmetric_reduced.yaml", {{"mu", mu}, {"th0", th0}});
  SimulationOptions ro = reduced.options;
  ro.integrator = Integrator::kDopri5;
  ro.rtol = 1e-12;
  ro.atol = 1e-14;
  ro.t_end = t_end;
  ro.output_every = every;
  Trajectory ref = simulate(reduced.system, reduced.q0, reduced.qd0, ro);
  EXPECT_EQ(ref.stats.status, Status::kOk) << ref.stats.message;
  return ref;
}

// The twin arms' run tr follows the reduced model's motion ref (the same samples): |th1 − th2|
// below 3e-8 and th1 within `tolerance` of th at every sample
void expect_follows(const Model& m, const Trajectory& tr, const Trajectory& ref,
                    double tolerance = 5e-7) {
  ASSERT_EQ(tr.samples(), ref.samples());
  double asymmetry = 0.0, worst = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    asymmetry = std::max(asymmetry, std::abs(coord(m, tr, "th1", i) - coord(m, tr, "th2", i)));
    worst = std::max(worst, std::abs(coord(m, tr, "th1", i) - ref.q[std::size_t(i)]));
  }
  EXPECT_LT(asymmetry, 3e-8);
  EXPECT_LT(worst, tolerance);
}

// The sleeve's friction as the force −mu P sign(zs_dot): its switch events fall at the dead
// centre (zs_dot = Z'(th) th_dot vanishes with Z'(0) = 0) and at the turning points. Restarts
// at the dead centre — the approach to the switch closing in on the pose, then the restart at
// it — took one arm onto the mirror branch (|th1 − th2| 5.5e-3 to 0.53 rad) on every adaptive
// integrator. A switch where the rank margin is below kCarriedMargin is not approached: it
// takes effect at the end of the step that crossed it when the margin is back there, else the
// restart is bridged past the pose (Run::bridge_dead_centre). That left dopri5 at mu = 0.1,
// 0.3, 0.5 and BDF at 0.1, 0.5 off the branch on a later passage (stopped with the cause at
// t = 1.04 … 2.38 s): a switch located at the pose in a step that ended inside the pose's
// neighbourhood restarted at the pose, and the bridge from there reversed an arm (th' 0.73 →
// 5.37 rad/s); and steps that ended inside the neighbourhood went on there. Now dopri5 and BDF
// restart such a switch at the step's start, outside the neighbourhood, and any step that
// ends inside it from outside, each bridged over the pose from there to where the margin is
// back (q'' linear between the bridge's ends; Run::entered_dead_centre). Every mu, every
// adaptive integrator: the symmetric motion, its energy balanced (at mu = 0 conserved).
TEST(DeadCentreEvents, ASwitchAtADeadCentreKeepsTheBranchForEveryMuOnEveryAdaptiveIntegrator) {
  for (const double mu : {0.0, 0.1, 0.3, 0.5}) {
    const Model m = load_model(kData + "twin_arms_sign_force.yaml", {{"mu", mu}});
    const Trajectory ref = reduced_motion(mu, 0.3);
    for (const Integrator method : {Integrator::kDopri5, Integrator::kRKF78, Integrator::kBDF}) {
      SCOPED_TRACE("mu = " + std::to_string(mu) + ", " + to_string(method));
      SimulationOptions o = m.options;
      o.integrator = method;
      const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
      ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
      EXPECT_EQ(tr.stats.t_reached, 3.0);
      // (a switch at each passage of the bottom and each turning point: 12 to 14 in 3 s, those
      // bridged over included)
      EXPECT_GE(tr.stats.switch_events, 10);
      EXPECT_LE(tr.stats.switch_events, 20);
      // (th within 5e-7 of the reduced model at mu = 0, |th1 − th2| ≤ 6.5e-9; at mu > 0 rkf78
      // within 3.7e-6, as the step that crosses the switch at the pose takes its stages on both
      // sides; dopri5 and BDF, bridged, within 2.4e-7)
      const double tolerance = mu == 0.0 ? 5e-7 : method == Integrator::kRKF78 ? 5e-6 : 1e-6;
      expect_follows(m, tr, ref, tolerance);
      // (at most 5.7e-7: BDF at mu = 0)
      EXPECT_LT(std::abs(tr.stats.energy_balance), 1e-6);
      if (mu == 0.0) {
        EXPECT_NEAR(tr.energy.back(), tr.energy[0], 1e-6 * std::abs(tr.energy[0]));
      }
    }
  }
}

// A constraint released and another activated at the dead centre (issue #29 item 1): the twin
// arms' rod written as two constraints of the same row (tests/data/twin_arms_release.yaml),
// swapped at t_release = the time the arms first pass the bottom (th = 0 of the reduced model,
// found to about 1e-9 s: the restart lies within about 1e-8 rad of the pose, where the
// velocities are fixed only to (position tolerance) / (distance to the pose)). The motion is
// the reduced model's at mu = 0. The run restarted there (a segment's end) with a projection
// onto the new set: rkf78 followed the symmetric motion; the steps of dopri5 and BDF shrank as
// they closed in on the breakpoint in the pose and left the branch before reaching it (stopped
// with the cause by Run::leaves_branch). Now the first step of dopri5 or BDF that ends inside
// the pose's neighbourhood (or jumps off the branch near it) is bridged from there across the
// breakpoint, with the next segment's constraints, to where the rank margin is back
// (Run::entered_dead_centre): every adaptive integrator follows the symmetric motion.
TEST(DeadCentreEvents, AReleaseAndAnActivationAtADeadCentreKeepTheBranchOnEveryAdaptiveIntegrator) {
  // the first passage of the bottom: th's zero, bracketed on a grid of 1e-5 s and placed by
  // the secant through the bracket
  const Trajectory fine = reduced_motion(0.0, 0.3, 0.5, 1e-5);
  double t_bottom = 0.0;
  for (std::size_t i = 1; i < fine.t.size() && t_bottom == 0.0; ++i) {
    if (fine.q[i - 1] > 0.0 && fine.q[i] <= 0.0) {
      t_bottom = fine.t[i - 1] + fine.q[i - 1] / (fine.q[i - 1] - fine.q[i]) * 1e-5;
    }
  }
  // (the small-swing quarter period pi/2 sqrt(I/k) is 0.20 s; 0.2054 s from 0.3 rad)
  ASSERT_GT(t_bottom, 0.2);
  ASSERT_LT(t_bottom, 0.21);
  const Trajectory ref = reduced_motion(0.0, 0.3);
  const Model m = load_model(kData + "twin_arms_release.yaml", {{"t_release", t_bottom}});
  for (const Integrator method : {Integrator::kDopri5, Integrator::kRKF78, Integrator::kBDF}) {
    SCOPED_TRACE(to_string(method));
    SimulationOptions o = m.options;
    o.integrator = method;
    const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_EQ(tr.stats.t_reached, 3.0);
    expect_follows(m, tr, ref);  // (rkf78: |th1 − th2| 4.5e-10, E(3) − E(0) = 5e-12 J)
    EXPECT_NEAR(tr.energy.back(), tr.energy[0], 1e-6 * std::abs(tr.energy[0]));
    EXPECT_LT(std::abs(tr.stats.energy_balance), 1e-6);
  }
}

// A slow passage of the dead centre, no event (issue #29 item 1): the twin arms at mu = 0
// released at rest from th = 0.005, so that the whole swing lies where the constraints nearly
// lose rank (the rank margin 1.75 |th| below 1e-2): the passage never ends, and
// Run::leaves_branch judges each of its steps. rkf78 and BDF reversed one arm at the dead
// centre (onto the mirror branch, |th1 − th2| = 0.01, at the same energy: the energy balance
// cannot see it) and were stopped there with that cause (rkf78 at t = 0.602, the first
// passage; BDF at 2.61, the fifth). Now the step that enters the pose's neighbourhood (rank
// margin below kCarriedMargin) or jumps off the branch near it is bridged over the pose, q''
// linear between the bridge's ends, on dopri5, rkf78 and BDF (Run::entered_dead_centre; the
// arms' sleeve friction at mu = 0 has no carry-through of its own). rkf78 then kept the branch
// but ended with status energy_balance (5.2e-6 of the energy level's floor, 1.3e-3 J, against
// 1e-6). Measured: −6.6e-9 J at the bridge from the entry's end at th = −1.6e-5 rad (t = 0.601,
// where q' is fixed only to the position tolerance over th²: th1' and th2' 0.34 % apart), and
// +7.9e-9 J in the step across the pose at t = 1.40 that ended outside (no entry; 13 stages on
// both sides). Now rkf78 bridges a step that passes through the neighbourhood too, and bridges
// both from outside (Run::enters_dead_centre): every adaptive integrator follows the
// symmetric motion with status ok.
TEST(DeadCentreEvents, ASlowPassageKeepsItsBranchOnEveryAdaptiveIntegrator) {
  const Model m = load_model(kData + "twin_arms_coulomb.yaml", {{"mu", 0.0}, {"th0", 0.005}});
  const Trajectory ref = reduced_motion(0.0, 0.005);
  for (const Integrator method : {Integrator::kDopri5, Integrator::kRKF78, Integrator::kBDF}) {
    SCOPED_TRACE(to_string(method));
    SimulationOptions o = m.options;
    o.integrator = method;
    const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_EQ(tr.stats.t_reached, 3.0);
    EXPECT_EQ(tr.t.back(), 3.0);
    // (|th1 − th2| 1.3e-10 dopri5, 2.1e-9 rkf78, 7.5e-9 BDF; th1 within 1.7e-10, 4.1e-9,
    // 4.4e-9 of the reference; the energy balance 9.9e-9, 1.8e-7, 2.1e-7)
    expect_follows(m, tr, ref);
    EXPECT_NEAR(tr.energy.back(), tr.energy[0], 1e-6 * std::abs(tr.energy[0]));
    EXPECT_LT(std::abs(tr.stats.energy_balance), 1e-6);
  }
}

// A run that leaves its branch where no bridge covers it is stopped with that cause
// (Run::leaves_branch): the slow passage above with the sleeve's friction written as the force
// −mu P sign(zs_dot) at mu = 0 and switch_events off — no Coulomb contact, no switch located,
// no breakpoint, so no entry is bridged (bridging every run moved examples: docs/reliability.md)
// — reverses an arm at the second passage of the bottom under rkf78. The step off the branch
// is judged where the rank margin is an order below the passage's entry (8.75e-3 at
// th0 = 0.005: the whole swing is one passage), |th| < 5e-4, within 5e-4 / th'(bottom) of the
// bottom (th' = 0.039 rad/s there: 0.013 s). The samples before it are kept and are those of
// the symmetric motion.
TEST(DeadCentreEvents, ARunThatLeavesItsBranchUnbridgedStopsWithThatCause) {
  const Model m = load_model(kData + "twin_arms_sign_force.yaml", {{"mu", 0.0}, {"th0", 0.005}});
  // the second passage of the bottom (th rising through 0): bracketed on a grid of 1e-5 s,
  // placed by the secant; and th' there
  const Trajectory fine = reduced_motion(0.0, 0.005, 0.8, 1e-5);
  double t_bottom = 0.0, rate = 0.0;
  for (std::size_t i = 1; i < fine.t.size() && t_bottom == 0.0; ++i) {
    if (fine.q[i - 1] < 0.0 && fine.q[i] >= 0.0) {
      t_bottom = fine.t[i - 1] + fine.q[i - 1] / (fine.q[i - 1] - fine.q[i]) * 1e-5;
      rate = fine.qd[i];
    }
  }
  // (three quarter periods: 3 pi/2 sqrt(I/k) = 0.60 s)
  ASSERT_GT(t_bottom, 0.59);
  ASSERT_LT(t_bottom, 0.62);
  ASSERT_GT(rate, 0.03);
  SimulationOptions o = m.options;
  o.integrator = Integrator::kRKF78;
  o.switch_events = false;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kIntegratorFailure) << tr.stats.message;
  EXPECT_NEAR(tr.stats.t_reached, t_bottom, 5e-4 / rate);
  const std::string& why = tr.stats.message;
  EXPECT_NE(why.find("the motion left its branch at the singular configuration passed between "
                     "t = "),
            std::string::npos)
      << why;
  EXPECT_NE(why.find("(the constraints nearly lose rank there: a dead centre or a branch point)"),
            std::string::npos)
      << why;
  EXPECT_NE(why.find("a jump onto another branch of the mechanism"), std::string::npos) << why;
  // the samples up to the stop (every 0.01 s), the symmetric motion's
  ASSERT_GE(tr.samples(), 2);
  EXPECT_LE(tr.t.back(), tr.stats.t_reached);
  EXPECT_GT(tr.t.back(), tr.stats.t_reached - 0.01);
  const Trajectory ref = reduced_motion(0.0, 0.005, tr.t.back());
  expect_follows(m, tr, ref);
}

// The governor's swing of the reproducers (tests/data/governor_sleeve_friction.yaml without
// engine, load and dashpot, released at th = 0.6 with the spindle at rest): the arms swing
// through the dead centre, where the sleeve's Coulomb friction stops and turns. At mu = 0 the
// kinetic energy went from 1.96 J to 118 J (one arm onto the mirror branch). dopri5 and BDF
// carry the contact through the dead centre (Run::carry_through); rkf78 left the branch there at
// mu = 0.3 (stopped with that cause) and at 0.5 (|th1 − th2| = 0.02 rad, status ok), and now
// hands the run to dopri5 there (Run::hands_over). Every mu, every adaptive integrator: the
// symmetric motion, with its energy balanced (at mu = 0: E conserved).
TEST(DeadCentreEvents, TheGovernorsSwingIsSymmetricForEveryMuOnEveryAdaptiveIntegrator) {
  for (const double mu : {0.0, 0.1, 0.3, 0.5}) {
    const Model m = load_model(kData + "governor_sleeve_friction.yaml", {{"Tmax", 0.0},
                                                                         {"TL", 0.0},
                                                                         {"dTL", 0.0},
                                                                         {"cL", 0.0},
                                                                         {"cs", 0.0},
                                                                         {"mu", mu},
                                                                         {"th0", 0.6},
                                                                         {"w0", 0.0}});
    for (const Integrator method : {Integrator::kDopri5, Integrator::kRKF78, Integrator::kBDF}) {
      SCOPED_TRACE("mu = " + std::to_string(mu) + ", " + to_string(method));
      SimulationOptions o = m.options;
      o.integrator = method;
      o.t_end = 3.0;
      const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
      ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
      double asymmetry = 0.0, peak = 0.0;
      for (Index i = 0; i < tr.samples(); ++i) {
        asymmetry = std::max(asymmetry, std::abs(coord(m, tr, "th1", i) - coord(m, tr, "th2", i)));
        peak = std::max(peak, tr.kinetic_energy[std::size_t(i)]);
      }
      EXPECT_LT(asymmetry, 1e-8);
      // (the swing from th = 0.6 at rest: T = 1.911 J at the bottom at mu = 0)
      EXPECT_LT(peak, 2.0);
      EXPECT_GT(peak, mu == 0.0 ? 1.85 : 0.1);
      EXPECT_LT(std::abs(tr.stats.energy_balance), 1e-6);
      if (mu == 0.0) {
        EXPECT_NEAR(tr.energy.back(), tr.energy[0], 1e-6 * std::abs(tr.energy[0]));
      } else {
        EXPECT_LT(tr.work_nonideal.back(), 0.0);  // friction takes energy out
      }
    }
  }
}

// the twin arms' state on their symmetric branch at th1 = th2 = th with th' = w (consistent),
// as the integrators hold it: [q; q'; W]
std::vector<double> symmetric_state(double th, double w) {
  const double c = 0.15, b = 0.2;
  const double root = std::sqrt(b * b - c * c * std::sin(th) * std::sin(th));
  const double dZ = c * std::sin(th) + c * c * std::sin(th) * std::cos(th) / root;
  return {th, th, 0.0, -c * std::cos(th) - root, w, w, 0.0, dZ * w, 0.0};
}

// BDF giving up near the dead centre (CVODE's convergence failures, as the governor's Coulomb
// event once made it) is blamed on the singular configuration, with the gap of A M^{-1/2}
// (sigma_3 / sigma_1 = 0.875 th here): it said "no sign of ... a singular configuration" down
// to th = 1e-6, as the gap had to fall below 1e-6. Away from the dead centre it still says
// there is no such sign.
TEST(DeadCentreEvents, AStepCollapseAtADeadCentreNamesTheRankDrop) {
  const Model m = load_model(kData + "twin_arms_coulomb.yaml");
  Workspace ws(m.system);
  detail::SegmentResult r;
  r.status = Status::kIntegratorFailure;
  r.message = "bdf: CVODE failed (CV_CONV_FAILURE)";
  r.collapsed = true;
  RunStatistics stats;
  stats.steps = 200;
  stats.rejected_steps = 10;
  const std::vector<double> start = symmetric_state(0.3, 0.0);
  for (const double th : {1e-3, 1e-4, 1e-6}) {
    SCOPED_TRACE("th = " + std::to_string(th));
    r.t_reached = 0.22;
    const std::string why = detail::diagnose_collapse(m.system, ws, m.options, Integrator::kBDF, r,
                                                      symmetric_state(th, -2.0), start, 0.0, stats);
    EXPECT_NE(why.find("Likely cause: a singular configuration at t = 0.22 s"), std::string::npos)
        << why;
    EXPECT_NE(why.find("about to lose rank (sigma_3 / sigma_1 = "), std::string::npos) << why;
    EXPECT_EQ(why.find("no sign"), std::string::npos) << why;
  }
  const std::string regular = detail::diagnose_collapse(
      m.system, ws, m.options, Integrator::kBDF, r, symmetric_state(0.2, -2.0), start, 0.0, stats);
  EXPECT_NE(regular.find("no sign of stiffness or of a singular configuration"), std::string::npos)
      << regular;
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

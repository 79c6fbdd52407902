// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts under control (issue #31 item 3, docs/contact.md "Contacts under control"),
// each against a closed form: a block resting on a floor while the control slides it (the floor
// carries m g, the control force is m x_d''), the same block lifted off by a requirement (the
// release at the instant the requirement starts to lift, then y = y_d and F_y = m (y_d'' + g)),
// brought back below the floor (the run stops: the floor would have to pull), a ball bouncing
// under horizontal control (the uncontrolled impacts and apexes e^(2k) h0), and the errors.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "control/contact_modes.hpp"
#include "simulation/observed_run.hpp"
#include "ukdyn/control/control.hpp"
#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/ukdyn.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81;

// A block (mass m) on a frictionless floor y >= 0, its slide required to follow
// x_d = a sin(w t) from the consistent start x = 0, x' = a w.
constexpr const char* kBlock = R"(
parameters: {m: 2, g: 9.81, a: 0.5, w: 2}
coordinates: [x, y]
kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)
potential_energy: m*g*y
constraints:
  - {name: floor, holonomic: y, unilateral: true}
control:
  requirements:
    - {name: slide, holonomic: x - a*sin(w*t), dynamics: {omega: 10, zeta: 1}}
  law: gauss
initial: {q: {x: 0, y: 0}, q_dot: {x: 1}}
simulate: {t_end: 1.2, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0.1}
)";

// The same block, also required from t1 = 0.5 on to follow y_d = c (t − t1)³ (T − t) (c = 1,
// T = 1.5): it lifts the block off at t1 (y_d'' = 6 c (t − t1)(T + t1 − 2t) > 0 just after) and
// brings it back to the floor at T with speed y_d'(T) = −c (T − t1)³, then below it.
std::string lift_model() {
  std::string text = kBlock;
  const std::string slide = "dynamics: {omega: 10, zeta: 1}}\n";
  text.insert(text.find(slide) + slide.size(),
              "    - {name: lift, holonomic: y - (t - 0.5)^3*(1.5 - t), active: [0.5, 100],\n"
              "       dynamics: {omega: 10, zeta: 1}}\n");
  return text;
}

constexpr double kM = 2.0, kA = 0.5, kW = 2.0, kC = 1.0, kT1 = 0.5, kT = 1.5;

double y_d(double t) { return t < kT1 ? 0.0 : kC * std::pow(t - kT1, 3) * (kT - t); }
double y_d2(double t) { return t < kT1 ? 0.0 : 6.0 * kC * (t - kT1) * (kT + kT1 - 2.0 * t); }

ControlledTrajectory run(const Model& m) {
  return simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
}

TEST(ControlContacts, BlockSlidesOnTheFloorItPressesWithMg) {
  const Model m = parse_model(kBlock);
  const ControlledTrajectory r = run(m);
  const Trajectory& p = r.plant;
  ASSERT_EQ(p.stats.status, Status::kOk) << p.stats.message;
  EXPECT_EQ(r.control.not_met, 0);
  EXPECT_TRUE(p.stats.contact_events.empty());
  ASSERT_EQ(p.samples(), 13);
  for (Index j = 0; j < p.samples(); ++j) {
    const double t = p.t[std::size_t(j)];
    const std::size_t i = std::size_t(2 * j);
    // x = x_d, the block on the floor
    EXPECT_NEAR(p.q[i], kA * std::sin(kW * t), 1e-9) << "t = " << t;
    EXPECT_NEAR(p.q[i + 1], 0.0, 1e-12) << "t = " << t;
    // the control force m x_d'' along x, none along the floor's normal
    EXPECT_NEAR(r.Qc_control[i], -kM * kA * kW * kW * std::sin(kW * t), 1e-9) << "t = " << t;
    EXPECT_NEAR(r.Qc_control[i + 1], 0.0, 1e-9) << "t = " << t;
    // the floor carries m g (the force Aᵀλ with A = [0 1])
    EXPECT_NEAR(p.lambda[std::size_t(j)], kM * kG, 1e-9) << "t = " << t;
  }
}

TEST(ControlContacts, RequirementThatLiftsTheBlockReleasesTheFloorWhenItStartsLifting) {
  const Model m = parse_model(lift_model());
  const ControlledTrajectory r = run(m);
  const Trajectory& p = r.plant;
  ASSERT_EQ(p.stats.status, Status::kOk) << p.stats.message;
  // one event: the release, at t1 (the requirement starts to lift there)
  ASSERT_EQ(p.stats.contact_events.size(), 1u);
  EXPECT_EQ(p.stats.contact_events[0].kind, ContactEvent::Kind::kRelease);
  EXPECT_NEAR(p.stats.contact_events[0].t, kT1, 1e-9);
  ASSERT_EQ(p.samples(), 13);
  const Index m_r = 2;
  for (Index j = 0; j < p.samples(); ++j) {
    const double t = p.t[std::size_t(j)];
    const std::size_t i = std::size_t(2 * j);
    EXPECT_NEAR(p.q[i], kA * std::sin(kW * t), 1e-9) << "t = " << t;
    EXPECT_NEAR(r.Qc_control[i], -kM * kA * kW * kW * std::sin(kW * t), 1e-8) << "t = " << t;
    if (t <= kT1) {
      // on the floor, which carries m g; the lift not yet required (y_d'' = 0 at t1)
      EXPECT_NEAR(p.q[i + 1], 0.0, 1e-12) << "t = " << t;
      EXPECT_NEAR(p.lambda[std::size_t(j)], kM * kG, 1e-9) << "t = " << t;
      EXPECT_NEAR(r.Qc_control[i + 1], 0.0, 1e-9) << "t = " << t;
    } else {
      // lifted: y = y_d, F_y = m (y_d'' + g), the floor open (no force)
      EXPECT_NEAR(p.q[i + 1], y_d(t), 1e-9) << "t = " << t;
      EXPECT_GT(p.q[i + 1], 0.0) << "t = " << t;
      EXPECT_NEAR(r.Qc_control[i + 1], kM * (y_d2(t) + kG), 1e-7) << "t = " << t;
      EXPECT_NEAR(p.lambda[std::size_t(j)], 0.0, 1e-12) << "t = " << t;
      EXPECT_NEAR(r.error[std::size_t(j * m_r + 1)], 0.0, 1e-9) << "t = " << t;
    }
  }
  EXPECT_EQ(r.control.not_met, 0);
}

TEST(ControlContacts, RequirementBelowTheFloorStopsTheRunNamingContactRequirementAndTime) {
  Model m = parse_model(lift_model());
  m.options.t_end = 2.0;
  const ControlledTrajectory r = run(m);
  const Trajectory& p = r.plant;
  // the block lands at T (y_d = 0, y_d' = −c (T − t1)³): an impact, then the requirement drives
  // it below the floor, which only a pulling floor could refuse
  EXPECT_NE(p.stats.status, Status::kOk);
  EXPECT_NE(p.stats.status, Status::kEnergyBalance);
  const std::string& msg = p.stats.message;
  EXPECT_NE(msg.find("'floor'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'lift'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("pull"), std::string::npos) << msg;
  EXPECT_NE(msg.find("t = 1.5 "), std::string::npos) << msg;
  EXPECT_NEAR(p.stats.t_reached, kT, 1e-8);
  // the impact at T, with the analytic approach speed
  ASSERT_GE(p.stats.contact_events.size(), 2u);
  EXPECT_EQ(p.stats.contact_events[1].kind, ContactEvent::Kind::kImpact);
  EXPECT_NEAR(p.stats.contact_events[1].t, kT, 1e-8);
  EXPECT_NEAR(p.stats.contact_events[1].speed_before, -kC * std::pow(kT - kT1, 3), 1e-7);
  // the samples before are kept: 0, 0.1, …, 1.5 (the last at T or just before)
  ASSERT_GE(p.samples(), 15);
  ASSERT_LE(p.samples(), 16);
  for (Index j = 0; j < 15; ++j) {
    const double t = p.t[std::size_t(j)];
    EXPECT_NEAR(t, 0.1 * double(j), 1e-12);
    EXPECT_NEAR(p.q[std::size_t(2 * j + 1)], y_d(t), 1e-9) << "t = " << t;
  }
}

// ---- a ball bouncing under horizontal control: the uncontrolled bounces ------------------------

TEST(ControlContacts, BallBouncingUnderHorizontalControlKeepsTheUncontrolledBounces) {
  const double e = 0.5, h0 = 1.0, mass = 0.5, a = 0.5, w = 2.0;
  Model m = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/control_bouncing_ball.yaml");
  m.options.rtol = 1e-11;
  m.options.atol = 1e-13;
  const double t0 = std::sqrt(2.0 * h0 / kG), v0 = kG * t0;
  // samples at the first apexes: t_k + e^(k+1) v0 / g
  std::vector<double> apex_t;
  double tk = t0;
  for (int k = 0; k < 4; ++k) {
    apex_t.push_back(tk + std::pow(e, k + 1) * v0 / kG);
    tk += 2.0 * std::pow(e, k + 1) * v0 / kG;
  }
  m.options.output_every = 0.0;
  m.options.output_at = apex_t;
  m.options.output_at.push_back(1.9);
  const ControlledTrajectory r = run(m);
  const Trajectory& p = r.plant;
  ASSERT_EQ(p.stats.status, Status::kOk) << p.stats.message;
  std::vector<ContactEvent> impacts, rests;
  for (const auto& ev : p.stats.contact_events) {
    if (ev.kind == ContactEvent::Kind::kImpact) impacts.push_back(ev);
    if (ev.kind == ContactEvent::Kind::kRest) rests.push_back(ev);
  }
  // the impacts of the uncontrolled ball (test_contact.cpp): 20, then the rest
  ASSERT_EQ(impacts.size(), 20u);
  ASSERT_EQ(rests.size(), 1u);
  tk = t0;
  for (std::size_t k = 0; k < impacts.size(); ++k) {
    const double ek = std::pow(e, double(k));
    EXPECT_NEAR(impacts[k].t, tk, 1e-9) << "impact " << k;
    EXPECT_NEAR(impacts[k].speed_before, -ek * v0, 1e-8 * v0) << "impact " << k;
    EXPECT_NEAR(impacts[k].speed_after, e * ek * v0, 1e-8 * v0) << "impact " << k;
    tk += 2.0 * e * ek * v0 / kG;
  }
  EXPECT_NEAR(rests[0].t, t0 * (1.0 + e) / (1.0 - e), 2e-6 * t0 * (1.0 + e) / (1.0 - e));
  // the samples t = 0, the apexes, 1.9 and t_end: x on x_d and the control force m x_d''
  ASSERT_EQ(p.samples(), Index(apex_t.size() + 3));
  for (std::size_t j = 0; j < std::size_t(p.samples()); ++j) {
    const double t = p.t[j];
    EXPECT_NEAR(p.q[2 * j], a * std::sin(w * t), 1e-9) << "t = " << t;
    EXPECT_NEAR(r.Qc_control[2 * j], -mass * a * w * w * std::sin(w * t), 1e-8) << "t = " << t;
    EXPECT_NEAR(r.Qc_control[2 * j + 1], 0.0, 1e-9) << "t = " << t;
  }
  // the apexes e^(2(k+1)) h0
  for (std::size_t k = 0; k < apex_t.size(); ++k) {
    ASSERT_NEAR(p.t[k + 1], apex_t[k], 1e-12);
    EXPECT_NEAR(p.q[2 * (k + 1) + 1], std::pow(e, 2.0 * double(k + 1)) * h0, 1e-8) << "apex " << k;
    EXPECT_NEAR(p.qd[2 * (k + 1) + 1], 0.0, 1e-7) << "apex " << k;
  }
  // the energy balance with the impacts' work: all of m g h0 is lost, and the run is certified
  EXPECT_TRUE(p.stats.energy_balance_checked);
  ASSERT_EQ(p.work_impact.size(), p.t.size());
  EXPECT_NEAR(p.work_impact.back(), -mass * kG * h0, 1e-8);
  // at rest on the floor at 1.9 and 2: the floor carries m g
  EXPECT_NEAR(p.q[2 * (apex_t.size() + 1) + 1], 0.0, 1e-10);
  EXPECT_NEAR(p.q.back(), 0.0, 1e-10);
  EXPECT_NEAR(p.lambda.back(), mass * kG, 1e-8);
}

// ---- two coupled contacts: the release decided jointly with the requirements -------------------

// A bar (mass m, length L, J = m L²/12; centre (x, y), angle th) lying on a frictionless floor on
// both ends, gaps y ∓ (L/2) sin th, its tilt required to follow th_d = c t²/2 from rest (th'' = c).
std::string bar_model(double c, const std::string& requirement, const std::string& name = "tilt") {
  return "parameters: {m: 2, g: 9.81, L: 2, c: " + std::to_string(c) +
         "}\n"
         "coordinates: [x, y, th]\n"
         "kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2) + 0.5*(m*L^2/12)*th_dot^2\n"
         "potential_energy: m*g*y\n"
         "constraints:\n"
         "  - {name: left, holonomic: y - L/2*sin(th), unilateral: true}\n"
         "  - {name: right, holonomic: y + L/2*sin(th), unilateral: true}\n"
         "control:\n"
         "  requirements:\n"
         "    - {name: " +
         name + ", holonomic: " + requirement +
         ", dynamics: {omega: 10, zeta: 1}}\n"
         "  law: gauss\n"
         "initial: {q: {x: 0, y: 0, th: 0}}\n";
}

constexpr double kBarM = 2.0, kBarL = 2.0, kTilt = 3.0;

// The controller's model at rest (q = q' = 0, t = 0) with both ends closed, as the run holds them.
struct BarAtRest {
  explicit BarAtRest(const std::string& text)
      : model(parse_model(text)), ctrl(*model.controller), cws(ctrl), modes(ctrl) {
    run.assign(std::size_t(ctrl.model().constraint_count()), 1);
    modes.mirror(&run, cws);
  }
  ControlStatus held() { return compute_control(ctrl, cws, q, qd, 0.0); }
  Model model;
  const Controller& ctrl;
  ControlWorkspace cws;
  control_detail::ContactModes modes;
  std::vector<signed char> run;
  VectorXd q = VectorXd::Zero(3), qd = VectorXd::Zero(3);
};

// Tilting the bar from rest needs one end lifted: th'' = c > 0 lifts the right end (the bar
// pivots on its left one), c < 0 the left. Under the control with both ends open (the bar free)
// y'' = −g and th'' = c drive BOTH gaps shut, g''_(left,right) = −g ∓ (L/2) c < 0 for |c| < 2g/L:
// the one-at-a-time rule held both back, missed the tilt with them held and reported a pulling
// contact. The joint problem: the requirement removes th from the contacts' compliance, so
// W̃ = (1/m) [1 1; 1 1] (the common normal y only) and r̃ = (−g − (L/2)c, −g + (L/2)c); its
// solution holds the pivot end with λ = m (g + (L/2)|c|) — the vertical balance of the bar whose
// centre rises with y'' = (L/2)|c| — and lets the other end rise with g'' = L |c|.
TEST(ControlContacts, TiltedBarKeepsThePivotEndAndLiftsTheOtherJointly) {
  for (const double c : {kTilt, -kTilt}) {
    BarAtRest bar(bar_model(c, "th - c*t^2/2"));
    const Index left = 0, right = 1, pivot = c > 0.0 ? left : right, lifted = 1 - pivot;
    // held on both ends the tilt is missed
    ControlStatus s = bar.held();
    ASSERT_EQ(s, ControlStatus::kRequirementsNotMet);
    // the premise: with both open the control drives both gaps shut
    {
      std::vector<signed char> open(2, 0);
      BarAtRest free(bar_model(c, "th - c*t^2/2"));
      free.modes.mirror(&open, free.cws);
      ASSERT_EQ(free.held(), ControlStatus::kOk);
      EXPECT_NEAR(free.cws.qdd[1], -kG, 1e-12);
      EXPECT_NEAR(free.cws.qdd[2], c, 1e-12);
      EXPECT_LT(free.cws.qdd[1] - 0.5 * kBarL * free.cws.qdd[2], -1.0);  // left shut
      EXPECT_LT(free.cws.qdd[1] + 0.5 * kBarL * free.cws.qdd[2], -1.0);  // right shut
    }
    std::string failure;
    ASSERT_TRUE(bar.modes.settle(bar.ctrl, bar.cws, bar.q, bar.qd, 0.0, s, failure)) << failure;
    EXPECT_EQ(s, ControlStatus::kOk);
    EXPECT_TRUE(failure.empty()) << failure;
    // the LCP's multipliers: the pivot pushes with m (g + (L/2)|c|), the lifted end none
    ASSERT_EQ(bar.modes.decided_contacts().size(), 2u);
    const VectorXd lambda = bar.modes.decided_lambda();
    EXPECT_NEAR(lambda[pivot], kBarM * (kG + 0.5 * kBarL * std::abs(c)), 1e-9) << "c = " << c;
    EXPECT_NEAR(lambda[lifted], 0.0, 1e-12) << "c = " << c;
    // the control computed with the pivot held: x'' = 0, y'' = (L/2)|c|, th'' = c
    EXPECT_NEAR(bar.cws.qdd[0], 0.0, 1e-12);
    EXPECT_NEAR(bar.cws.qdd[1], 0.5 * kBarL * std::abs(c), 1e-9) << "c = " << c;
    EXPECT_NEAR(bar.cws.qdd[2], c, 1e-9) << "c = " << c;
    EXPECT_EQ(bar.cws.model.active[std::size_t(pivot)], 1) << "c = " << c;
    EXPECT_EQ(bar.cws.model.active[std::size_t(lifted)], 0) << "c = " << c;
    // the lifted end rises: g'' = y'' ± (L/2) th'' = L |c|
    const double sign = lifted == right ? 1.0 : -1.0;
    EXPECT_NEAR(bar.cws.qdd[1] + sign * 0.5 * kBarL * bar.cws.qdd[2], kBarL * std::abs(c), 1e-9);
    // (under the Gauss law the model's own reaction is the uncontrolled one, which the control
    // does not load: the pivot of a bar at rest carries m g / (1 + 3 cos² th) = m g / 4)
    EXPECT_NEAR(bar.cws.model.lambda[pivot], kBarM * kG / 4.0, 1e-9) << "c = " << c;
    // the run's modes are left as they were
    EXPECT_EQ(bar.cws.model.activity_override[0], 1);
    EXPECT_EQ(bar.cws.model.activity_override[1], 1);
  }
}

// the bar model `text` (its requirement th_d = c (t − 0.5)^3) as a run to t = 1: the tilt
// required from t1 = 0.5 on, samples every `every`
std::string tilt_run(std::string text, const std::string& every) {
  const std::string dyn = ", dynamics: {omega: 10, zeta: 1}}";
  text.replace(text.find(dyn), dyn.size(), ", active: [0.5, 100]" + dyn);
  return text +
         "simulate: {t_end: 1.0, integrator: dopri5, rtol: 1e-11, atol: 1e-13}\n"
         "output: {every: " +
         every + "}\n";
}

// the bar model `text` under the weighted law with cost matrix N (a YAML matrix)
std::string with_weighted_law(std::string text, const std::string& N) {
  const std::string gauss = "  law: gauss\n";
  return text.replace(text.find(gauss), gauss.size(), "  law: weighted\n  N: " + N + "\n");
}

// The same bar in a run, its tilt required from t1 = 0.5 on to follow th_d = c (t − t1)³
// (th_d'' = 6 c (t − t1) starts from 0): the run releases the right end at t1 — an event whose LCP
// sees the control answer the contact forces (ContactModes::anticipate) — and the bar pivots on
// its left end, which stays on the floor: y = (L/2) sin th, x = 0. Under the Gauss law the control
// loads no closed contact, so the left end carries the uncontrolled pivot's reaction
// N = m (g − (L/2) sin th th'²) / (1 + 3 cos² th) (m y'' = N − m g, J th'' = −(L/2) cos th N), and
// the control force is M (q'' − a_p): F_th = J (th_d'' − th''_p), F_y = m (L/2) cos th (th_d'' −
// th''_p), th''_p = −(L/2) cos th N / J.
TEST(ControlContacts, TiltedBarRunReleasesTheRightEndAndPivotsOnTheLeft) {
  const Model m = parse_model(tilt_run(bar_model(1.0, "th - c*(t - 0.5)^3"), "0.1"));
  const ControlledTrajectory r = run(m);
  const Trajectory& p = r.plant;
  ASSERT_EQ(p.stats.status, Status::kOk) << p.stats.message;
  EXPECT_EQ(r.control.not_met, 0);
  // one event: the right end's release, at t1
  ASSERT_EQ(p.stats.contact_events.size(), 1u);
  EXPECT_EQ(p.stats.contact_events[0].kind, ContactEvent::Kind::kRelease);
  EXPECT_EQ(p.stats.contact_events[0].constraint, 1);
  EXPECT_NEAR(p.stats.contact_events[0].t, 0.5, 1e-9);
  ASSERT_EQ(p.samples(), 11);
  const double J = kBarM * kBarL * kBarL / 12.0, h = 0.5 * kBarL;
  for (Index j = 0; j < p.samples(); ++j) {
    const double t = p.t[std::size_t(j)], s = std::max(t - 0.5, 0.0);
    const double th = s * s * s, thd = 3.0 * s * s, thdd = 6.0 * s;
    const std::size_t i = std::size_t(3 * j), l = std::size_t(2 * j);
    if (std::abs(t - 0.5) < 1e-12) continue;  // (the event's instant: before or after it)
    EXPECT_NEAR(p.q[i], 0.0, 1e-12) << "t = " << t;
    EXPECT_NEAR(p.q[i + 2], th, 1e-9) << "t = " << t;
    // the left end on the floor, the right one above it by L sin th
    EXPECT_NEAR(p.q[i + 1], h * std::sin(th), 1e-9) << "t = " << t;
    if (t > 0.55) {
      EXPECT_GT(p.q[i + 1] + h * std::sin(p.q[i + 2]), 1e-4) << "t = " << t;
    }
    if (t < 0.5) {
      // both ends carry m g / 2, no control
      EXPECT_NEAR(p.lambda[l], 0.5 * kBarM * kG, 1e-9) << "t = " << t;
      EXPECT_NEAR(p.lambda[l + 1], 0.5 * kBarM * kG, 1e-9) << "t = " << t;
      for (std::size_t c = 0; c < 3; ++c)
        EXPECT_NEAR(r.Qc_control[i + c], 0.0, 1e-9) << "t = " << t;
      continue;
    }
    const double c2 = std::cos(th) * std::cos(th);
    const double N = kBarM * (kG - h * std::sin(th) * thd * thd) / (1.0 + 3.0 * c2);
    const double thdd_p = -h * std::cos(th) * N / J;
    EXPECT_NEAR(p.lambda[l], N, 1e-8) << "t = " << t;
    EXPECT_NEAR(p.lambda[l + 1], 0.0, 1e-12) << "t = " << t;
    EXPECT_NEAR(r.Qc_control[i], 0.0, 1e-9) << "t = " << t;
    EXPECT_NEAR(r.Qc_control[i + 1], kBarM * h * std::cos(th) * (thdd - thdd_p), 1e-8)
        << "t = " << t;
    EXPECT_NEAR(r.Qc_control[i + 2], J * (thdd - thdd_p), 1e-8) << "t = " << t;
  }
}

// Lowering the bar's centre below the floor (y'' = −1) with both ends on it: every pushing
// contact force only raises it, so no λ >= 0 meets the requirement (W̃ = (3/m) [1 −1; −1 1],
// r̃ = (−1, −1): the two rows sum to −2 >= 0) — both ends would have to pull, and the control
// says so, naming them, the requirement row and the time.
TEST(ControlContacts, BarPushedIntoTheFloorNamesBothEndsThatWouldPull) {
  BarAtRest bar(bar_model(0.0, "y + t^2/2", "sink"));
  ControlStatus s = bar.held();
  ASSERT_EQ(s, ControlStatus::kRequirementsNotMet);
  std::string failure;
  EXPECT_FALSE(bar.modes.settle(bar.ctrl, bar.cws, bar.q, bar.qd, 0.0, s, failure));
  EXPECT_NE(failure.find("at t = 0 s the requirement row 'sink'"), std::string::npos) << failure;
  EXPECT_NE(failure.find("contact 'left', 'right' pulls"), std::string::npos) << failure;
  EXPECT_NE(failure.find("missed by 1 "), std::string::npos) << failure;
  EXPECT_EQ(bar.cws.model.activity_override[0], 1);
  EXPECT_EQ(bar.cws.model.activity_override[1], 1);
}

// ---- a weighted law: W̃ neither symmetric nor positive semi-definite ---------------------------

// The bar of the tilt above under the weighted law with N = [1 0 0; 0 1 −2; 0 −2 5] (N⁻¹'s
// (y, th) block [5 2; 2 1]): with both ends open (X = [0 0 1/J]) the least Q_cᵀ N Q_c with
// X Q_c = c is Q_c = J c v / v_3, v = N⁻¹ e_th = (0, 2, 1), so the control also pushes y up with
// 2 J c (ρ = v_2 / v_3 = 2): q''₀ = (0, −g + ρ J c / m, c). K = J v / v_3, and with h = L/2 and
// the rows A_left,right = (0, 1, ∓h):
//   W̃ = A_c M⁻¹ (I − v e_thᵀ / v_3) A_cᵀ = (1/m) [1 + hρ  1 − hρ; 1 + hρ  1 − hρ] = [1.5 −0.5; 1.5
//   −0.5],
// not symmetric and not positive semi-definite; r̃ = (y''₀ − h c, y''₀ + h c) = (−10.81, −4.81).
// Its solution by hand: the rows of W̃ λ are equal, so w_right − w_left = 2 h c > 0, λ_right = 0,
// and w_left = 0 gives λ_left = m (h c − y''₀) / (1 + hρ) = 2 · 10.81 / 3. The pivot then holds
// and the bar tilts on it: q'' = (0, h c, c). With N = [1 0 0; 0 1 2; 0 2 5] (ρ = −2: the
// control's answer to a contact force pushes the bar down more than the force lifts it),
// W̃ = (1/m) [−1 3; −1 3] and r̃ = (−14.81, −8.81): λ_right > 0 would need w_right = 0 and then
// w_left = −2 h c < 0, λ_right = 0 leaves w_left = r̃_left − λ_left / m < 0 — no solution, both
// ends named.
std::string weighted_bar(double c, const std::string& n23) {
  return with_weighted_law(bar_model(c, "th - c*t^2/2"),
                           "[[1, 0, 0], [0, 1, " + n23 + "], [0, " + n23 + ", 5]]");
}

TEST(ControlContacts, WeightedLawsNonSymmetricLcpHoldsThePivotOrNamesBothEnds) {
  const double h = 0.5 * kBarL, J = kBarM * kBarL * kBarL / 12.0, c = kTilt;
  {
    BarAtRest bar(weighted_bar(c, "-2"));
    ControlStatus s = bar.held();
    ASSERT_EQ(s, ControlStatus::kRequirementsNotMet);
    std::string failure;
    ASSERT_TRUE(bar.modes.settle(bar.ctrl, bar.cws, bar.q, bar.qd, 0.0, s, failure)) << failure;
    EXPECT_EQ(s, ControlStatus::kOk);
    const double rho = 2.0, y0 = -kG + rho * J * c / kBarM;
    ASSERT_EQ(bar.modes.decided_contacts().size(), 2u);
    const VectorXd lambda = bar.modes.decided_lambda();
    EXPECT_NEAR(lambda[0], kBarM * (h * c - y0) / (1.0 + h * rho), 1e-9);
    EXPECT_NEAR(lambda[1], 0.0, 1e-12);
    // the left end held, the right one open, and the bar tilts on the left: q'' = (0, h c, c)
    EXPECT_EQ(bar.cws.model.active[0], 1);
    EXPECT_EQ(bar.cws.model.active[1], 0);
    EXPECT_NEAR(bar.cws.qdd[0], 0.0, 1e-12);
    EXPECT_NEAR(bar.cws.qdd[1], h * c, 1e-9);
    EXPECT_NEAR(bar.cws.qdd[2], c, 1e-9);
  }
  {
    BarAtRest bar(weighted_bar(c, "2"));
    ControlStatus s = bar.held();
    ASSERT_EQ(s, ControlStatus::kRequirementsNotMet);
    std::string failure;
    EXPECT_FALSE(bar.modes.settle(bar.ctrl, bar.cws, bar.q, bar.qd, 0.0, s, failure));
    EXPECT_NE(failure.find("at t = 0 s the requirement row 'tilt'"), std::string::npos) << failure;
    EXPECT_NE(failure.find("contact 'left', 'right' pulls"), std::string::npos) << failure;
    EXPECT_EQ(bar.cws.model.activity_override[0], 1);
    EXPECT_EQ(bar.cws.model.activity_override[1], 1);
  }
}

// The bar's run of the tilt th_d = c (t − t1)³ from t1 = 0.5 (c = 10) under the weighted law with
// N = diag(1, 1/20, 1): N⁻¹ couples nothing, so the release LCP is the Gauss one (W̃ symmetric)
// and holds the left end from t1 on, while the control computed with it held (the least
// Q_cᵀ N Q_c among the forces with F_th + h cos th F_y = s₀ = (J + m h² cos² th) th'' +
// h cos th (m g − m h sin th th'²), which is what meeting th'' takes on the pivot) pushes y with
// F_y = 20 h cos th s₀ / (20 h² cos² th + 1), so the pivot's reaction in the plant
//   N_left = m (h cos th th'' − h sin th th'²) + m g − F_y
// falls from 0.93 at t1 to zero at the t* found below. There the plant releases the left end,
// but the run's LCP (with the control answering the contact force) holds it again: the two
// disagree in sign, and the run stops at t*, naming the contact, the time and both signs, with
// the samples before kept (before: the run never got past t*, alternating without end).
TEST(ControlContacts, PivotWhoseHeldControlPullsStopsTheRunNamingTheContactAndBothSigns) {
  const Model m = parse_model(tilt_run(with_weighted_law(bar_model(10.0, "th - c*(t - 0.5)^3"),
                                                         "[[1, 0, 0], [0, 0.05, 0], [0, 0, 1]]"),
                                       "0.01"));
  const ControlledTrajectory r = run(m);
  const Trajectory& p = r.plant;
  // t*: the closed form's root, by bisection
  const double h = 0.5 * kBarL, J = kBarM * kBarL * kBarL / 12.0, c = 10.0;
  auto pivot = [&](double t) {
    const double s = t - 0.5, th = c * s * s * s, thd = 3.0 * c * s * s, thdd = 6.0 * c * s;
    const double co = std::cos(th), si = std::sin(th);
    const double s0 =
        (J + kBarM * h * h * co * co) * thdd + h * co * kBarM * (kG - h * si * thd * thd);
    const double Fy = 20.0 * h * co * s0 / (20.0 * h * h * co * co + 1.0);
    return kBarM * (h * co * thdd - h * si * thd * thd) + kBarM * kG - Fy;
  };
  double lo = 0.5, hi = 0.6;
  ASSERT_GT(pivot(lo), 0.9);
  ASSERT_LT(pivot(hi), 0.0);
  for (int i = 0; i < 100; ++i) (pivot(0.5 * (lo + hi)) > 0.0 ? lo : hi) = 0.5 * (lo + hi);
  const double t_star = 0.5 * (lo + hi);
  EXPECT_NE(p.stats.status, Status::kOk);
  EXPECT_NEAR(p.stats.t_reached, t_star, 1e-6);
  const std::string& msg = p.stats.message;
  EXPECT_NE(msg.find("the contact 'left' is released by its multiplier in the plant, -"),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find("(pulling, with the contact held), but held by the LCP of the "
                     "accelerations, lambda = "),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find("(pushing)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("contacts at t = 0.52"), std::string::npos) << msg;
  // the samples before it kept: the bar pivots on its left end, th = th_d, y = h sin th
  ASSERT_GE(p.samples(), 52);
  for (Index j = 0; j < 52; ++j) {
    const double t = p.t[std::size_t(j)], s = std::max(t - 0.5, 0.0), th = c * s * s * s;
    EXPECT_NEAR(p.q[std::size_t(3 * j + 2)], th, 1e-8) << "t = " << t;
    EXPECT_NEAR(p.q[std::size_t(3 * j + 1)], h * std::sin(th), 1e-8) << "t = " << t;
  }
}

// ---- errors -------------------------------------------------------------------------------------

System block_system(bool unilateral_floor) {
  auto floor = holonomic("floor", 1, [](const auto& q, const auto&, auto& g) { g[0] = q[1]; });
  if (unilateral_floor) floor.unilateral(0.0);
  return SystemBuilder({"x", "y"})
      .mass_matrix(MatrixXd::Identity(2, 2))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q << 0.0, -kG; })
      .add(floor)
      .build();
}

Constraint slide() {
  return holonomic("slide", 1, [](const auto& q, const auto& t, auto& g) { g[0] = q[0] - t; });
}

template <class F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "no std::invalid_argument";
  return "";
}

TEST(ControlContacts, BadCombinationsAreRefusedByName) {
  const ErrorDynamics d = ErrorDynamics::second_order(10.0);
  // a unilateral requirement
  auto gap = holonomic("above", 1, [](const auto& q, const auto&, auto& g) { g[0] = q[1]; });
  gap.unilateral(0.0);
  std::string msg =
      message_of([&] { (void)ControllerBuilder(block_system(true)).require(gap, d).build(); });
  EXPECT_NE(msg.find("requirement 'above' is unilateral"), std::string::npos) << msg;
  // the plant's contact two-sided in the controller's model
  const Controller two_sided = ControllerBuilder(block_system(false)).require(slide(), d).build();
  msg = message_of([&] {
    (void)simulate_controlled(two_sided, block_system(true), VectorXd::Zero(2),
                              VectorXd::Unit(2, 0), SimulationOptions{});
  });
  EXPECT_NE(msg.find("'floor': it is unilateral in the plant only"), std::string::npos) << msg;
  // controlled_system with contacts (its model cannot follow a run's contact modes)
  const Controller ctrl = ControllerBuilder(block_system(true)).require(slide(), d).build();
  msg = message_of([&] { (void)controlled_system(ctrl, block_system(true)); });
  EXPECT_NE(msg.find("'floor' is unilateral"), std::string::npos) << msg;
  EXPECT_NE(msg.find("simulate_controlled"), std::string::npos) << msg;
  // a model file's requirement cannot be unilateral (the keys of a requirement say so)
  std::string text = kBlock;
  const std::string req = "x - a*sin(w*t),";
  text.replace(text.find(req), req.size(), req + " unilateral: true,");
  try {
    (void)parse_model(text);
    ADD_FAILURE() << "a unilateral requirement was accepted";
  } catch (const std::exception& ex) {
    EXPECT_NE(std::string(ex.what()).find("unilateral"), std::string::npos) << ex.what();
  }
}

// The workspaces a run makes besides its own reach the `started` observer too: the branch
// check's (made at the first step judged near a dead centre), whose controlled-plant scratch
// then mirrors its own contact modes (a copy of the run's) instead of holding every contact
// (simulate_controlled). The twin arms' slow passage of their dead centre under dopri5
// (tests/data/twin_arms_coulomb.yaml, mu = 0, from th = 0.005): the run's workspace first, then
// one other; the motion is bit for bit that of `simulate`.
TEST(ControlContacts, TheBranchChecksWorkspaceReachesTheStartedObserver) {
  const Model m = load_model(std::string(UKDYN_TESTS_DIR) + "/data/twin_arms_coulomb.yaml",
                             {{"mu", 0.0}, {"th0", 0.005}});
  SimulationOptions o = m.options;
  o.integrator = Integrator::kDopri5;
  std::vector<const Workspace*> started;
  std::vector<std::size_t> modes;
  const Trajectory tr = detail::simulate_observed(m.system, m.q0, m.qd0, o, {}, [&](Workspace& ws) {
    started.push_back(&ws);
    modes.push_back(ws.activity_override.size());
  });
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(started.size(), 2u);
  EXPECT_NE(started[0], started[1]);
  EXPECT_EQ(modes[0], modes[1]);
  const Trajectory plain = simulate(m.system, m.q0, m.qd0, o);
  EXPECT_EQ(tr.q, plain.q);
  EXPECT_EQ(tr.stats.steps, plain.stats.steps);
}

// ---- a requirement row that duplicates a held contact's ----------------------------------------

// A 2-link arm (URDF with joint damping and Coulomb friction) whose tip sphere rests on a table
// z = 0.3 (centre at zc = 0.325), its tip's abscissa required to follow x_d(t) (defect 12). Asked
// as x alone, the table holds z and carries the uncontrolled reaction (the Gauss law loads no
// held contact). Asked as a position [x_d, 0, zc], whose z row duplicates the contact's, the
// motion, the table's force and the control must be the same: the duplicated row is consistent
// and redundant, the contact carries what it carries without it (a roundoff-decided split let go
// of the table until t = 1.47, logged impacts at speeds 1e-21, took 2311 steps for 578).
std::string arm_on_table(std::string requirement) {
  // x0, the tip's initial abscissa
  const std::string x0 = "L1*cos(q10) + L2*cos(asin((H - zc - L1*sin(q10))/L2))";
  requirement.replace(requirement.find("x0"), 2, x0);
  return R"(
parameters: {e: 0.4, H: 0.6, L1: 0.45, L2: 0.35, zc: 0.325, q10: 0.6, A: 0.1, w: 2}
robot:
  urdf: arm2_table.urdf
contacts:
  - {name: tip, link: l2, point: [0.35, 0, 0], shape: sphere, radius: 0.025, restitution: e,
     plane: {body: ground, point: [0, 0, 0.3], normal: [0, 0, 1]}}
initial:
  q: {j1: q10, j2: asin((H - zc - L1*sin(q10))/L2) - q10}
control:
  requirements:
    - name: tool
)" + requirement +
         R"(
      dynamics: {omega: 20, zeta: 1}
simulate: {t_end: 2}
output:
  every: 0.05
)";
}

TEST(ControlContacts, RequirementRowThatDuplicatesAHeldContactLeavesItTheUncontrolledLoad) {
  const std::string file = std::string(UKDYN_TESTS_DIR) + "/data/arm2_table.yaml";
  const Model mx = parse_model(
      arm_on_table("      holonomic: L1*cos(j1) + L2*cos(j1 + j2) - (x0) + A*(1 - cos(w*t))"),
      file);
  const Model mp =
      parse_model(arm_on_table("      pose: {link: l2, point: [0.35, 0, 0],\n"
                               "             position: [\"x0 - A*(1 - cos(w*t))\", 0, zc]}"),
                  file);
  const ControlledTrajectory rx = run(mx), rp = run(mp);
  const Trajectory &px = rx.plant, &pp = rp.plant;
  ASSERT_EQ(px.stats.status, Status::kOk) << px.stats.message;
  ASSERT_EQ(pp.stats.status, Status::kOk) << pp.stats.message;
  // no event: the contact closed from the start, held throughout, no roundoff "impacts"
  EXPECT_TRUE(px.stats.contact_events.empty());
  EXPECT_TRUE(pp.stats.contact_events.empty());
  EXPECT_EQ(rx.control.not_met, 0);
  EXPECT_EQ(rp.control.not_met, 0);
  // the duplicated row costs no steps: 578 and 584 (were 578 and 2311)
  EXPECT_LE(pp.stats.steps, px.stats.steps * 11 / 10);
  EXPECT_LE(pp.stats.rejected_steps, 2 * px.stats.rejected_steps + 20);
  ASSERT_EQ(px.samples(), 41);
  ASSERT_EQ(pp.samples(), 41);
  // the same motion, control and table force (λ.tip: the uncontrolled reaction, 2.64 … 4.35 N);
  // the pose's position row x is the tip's abscissa
  const std::size_t m = std::size_t(px.m);
  ASSERT_EQ(pp.m, px.m);
  // the contact's row
  std::size_t tip = 0;
  for (std::size_t k = 0; k < px.constraint_names.size() && px.constraint_names[k] != "tip"; ++k)
    tip += std::size_t(px.constraint_rows[k]);
  ASSERT_LT(tip, m);
  for (std::size_t j = 0; j < 41; ++j) {
    const double t = px.t[j];
    for (std::size_t c = 0; c < 2; ++c) {
      EXPECT_NEAR(pp.q[2 * j + c], px.q[2 * j + c], 1e-9) << "t = " << t;
      EXPECT_NEAR(rp.Qc_control[2 * j + c], rx.Qc_control[2 * j + c], 1e-7) << "t = " << t;
    }
    EXPECT_NEAR(pp.lambda[m * j + tip], px.lambda[m * j + tip], 1e-8) << "t = " << t;
    EXPECT_GT(px.lambda[m * j + tip], 2.6) << "t = " << t;
    EXPECT_LT(px.lambda[m * j + tip], 4.4) << "t = " << t;
    EXPECT_NEAR(rp.error[3 * j], rx.error[j], 1e-9) << "t = " << t;
    EXPECT_NEAR(rp.error[3 * j + 2], 0.0, 1e-9) << "t = " << t;
  }
  EXPECT_NEAR(px.lambda[tip], 2.6374540234, 1e-9);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

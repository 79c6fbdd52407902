// SPDX-License-Identifier: BSD-3-Clause
// A requirement that needs a stuck Coulomb contact to slide breaks its stick (ContactModes::slip;
// docs/contact.md, "Contacts under control"): a particle on a rough floor whose x must follow
// x_d = A (1 − cos w t), actuated along x. Against closed forms: sliding from the start with
// F = m x_d'' + mu m g, the stick held until the stabilized requirement's force breaks it at t*,
// and static friction holding it (the requirement reported as not met, with the reason).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "support/contact_runs.hpp"
#include "ukdyn/control/control.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/ukdyn.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kM = 2.0, kG = 9.81, kMu = 0.2, kW = 5.0, kOmega = 20.0;

// the particle p (m = 2) at rest on the floor z >= 0 (mu = 0.2, mu_static), x required to follow
// A (1 − cos 5t) under the error dynamics e'' + 2 omega e' + omega² e = 0 (omega = 20), the
// control along x alone
std::string pushed_particle(double A, double mu_static, double t_end) {
  return "parameters: {m: 2, g: 9.81, A: " + std::to_string(A) +
         ", w: 5, mu: 0.2, mus: " + std::to_string(mu_static) + R"(}
bodies:
  - {name: p, type: particle, mass: m, position: [0, 0, 0]}
forces:
  - {type: gravity, g: [0, 0, -g]}
contacts:
  - {name: floor, body: p}
nonideal:
  - {friction: coulomb, constraint: floor, mu: mu, mu_static: mus}
control:
  requirements:
    - {name: pace, holonomic: p_x - A*(1 - cos(w*t)), dynamics: {omega: 20, zeta: 1}}
  actuated: [p_x]
simulate: {t_end: )" +
         std::to_string(t_end) +
         R"(, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0.05}
)";
}

ControlledTrajectory run(const std::string& text) {
  const Model m = parse_model(text);
  return simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
}

// field f of coordinate `name` at sample i
constexpr auto* at = &testing::coordinate_at;

// x_d and its derivatives
double x_d(double A, double t) { return A * (1.0 - std::cos(kW * t)); }
double x_d1(double A, double t) { return A * kW * std::sin(kW * t); }
double x_d2(double A, double t) { return A * kW * kW * std::cos(kW * t); }

// sliding from t = 0 on pace over 13 samples: x (coordinate `x`) = x_d, F = m x_d'' + mu m g,
// the friction (with the contacts' reaction along x) −mu m g, no error
void expect_slides_on_pace(const ControlledTrajectory& r, const std::string& x, double A,
                           double mass, double mu) {
  const Trajectory& tr = r.plant;
  ASSERT_EQ(tr.samples(), 13);
  for (std::size_t i = 0; i < std::size_t(tr.samples()); ++i) {
    const double t = tr.t[i];
    EXPECT_NEAR(at(tr, tr.q, x, i), x_d(A, t), 1e-8) << "t = " << t;
    EXPECT_NEAR(at(tr, tr.qd, x, i), x_d1(A, t), 1e-8) << "t = " << t;
    EXPECT_NEAR(at(tr, r.Qc_control, x, i), mass * x_d2(A, t) + mu * mass * kG, 1e-6)
        << "t = " << t;
    EXPECT_NEAR(at(tr, tr.Qc_nonideal, x, i) + at(tr, tr.Qc_ideal, x, i), -mu * mass * kG, 1e-6)
        << "t = " << t;
    EXPECT_NEAR(r.error[i], 0.0, 1e-8) << "t = " << t;
  }
}

TEST(ControlSlip, ParticlePushedFromRestSlidesWithTheClosedFormForce) {
  // F(0) = m A w² + mu m g = 8.924 N > mu_static m g = 5.886 N: it slides from t = 0, x = x_d,
  // F = m x_d'' + mu m g while x_d' > 0 (t < pi/5), the friction −mu m g
  const double A = 0.1;
  const ControlledTrajectory r = run(pushed_particle(A, 0.3, 0.6));
  const Trajectory& tr = r.plant;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(r.control.not_met, 0) << r.control.not_met_message;
  EXPECT_EQ(tr.stats.events, 0);  // (the stick refused at the start: no event)
  // the note of the broken stick, with its numbers at t = 0
  ASSERT_FALSE(tr.stats.notes.empty());
  const std::string& note = tr.stats.notes.back();
  EXPECT_NE(note.find("t = 0 s: the requirement row 'pace' needs the stuck contact"),
            std::string::npos)
      << note;
  EXPECT_NE(note.find("holding force of 8.924 N > mu_static N = 5.886 N"), std::string::npos)
      << note;
  // the note and the event list agree: the stick broken at the start never held, and the note
  // says why no slip is listed (u24: "so it slips" beside "0 sticks, 0 slips")
  EXPECT_TRUE(tr.stats.contact_events.empty());
  EXPECT_NE(note.find("so it slips from the start: it never stuck, so contact_events lists no "
                      "slip (its initial mode is sliding) (docs/contact.md"),
            std::string::npos)
      << note;
  expect_slides_on_pace(r, "p.x", A, kM, kMu);
}

// the stabilized requirement's acceleration while the particle stays at x = 0, x' = 0:
// x_d'' + 2 omega x_d' + omega² x_d
double a_stuck(double A, double t) {
  return x_d2(A, t) + 2.0 * kOmega * x_d1(A, t) + kOmega * kOmega * x_d(A, t);
}

// t* where a_stuck(t*) = (mu_s − mu) g, by bisection on [0, 0.1] (where a_stuck rises)
double stick_break(double A, double mu_static, double mu) {
  double lo = 0.0, hi = 0.1;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (a_stuck(A, mid) < (mu_static - mu) * kG ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(ControlSlip, ParticleHeldByStaticFrictionSlipsWhenTheRequirementsForceReachesMuStaticN) {
  // A = 0.02: F(0) = m A w² + mu m g = 4.924 N < mu_static m g = 5.886 N, so the stick holds
  // (x = 0, F = 0, the requirement not met, with the reason) while the error grows, until the
  // force that the stabilized requirement needs sliding, m a_stuck(t) + mu m g, reaches
  // mu_static m g at t* (a_stuck(t*) = (mu_static − mu) g, 0.021856 s); from there it slides,
  // x = x_d + e with the error dynamics e'' + 40 e' + 400 e = 0 from e(t*) = −x_d(t*),
  // e'(t*) = −x_d'(t*)
  const double A = 0.02, mus = 0.3;
  const double ts = stick_break(A, mus, kMu);
  EXPECT_NEAR(ts, 0.021856, 1e-6);
  const double c1 = -x_d(A, ts), c2 = -x_d1(A, ts) + kOmega * c1;
  Model m = parse_model(pushed_particle(A, mus, 0.5));
  m.options.output_at = {0.01, 0.02, ts - 1e-6, ts + 1e-6, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5};
  const ControlledTrajectory r =
      simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
  const Trajectory& tr = r.plant;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.events, 1);  // the release at t*
  // not met while stuck, and why
  EXPECT_GT(r.control.not_met, 0);
  EXPECT_EQ(r.control.first_not_met, 0.0);
  EXPECT_NE(
      r.control.not_met_message.find(
          "the requirement row 'pace' needs a stuck contact to slide, but static friction "
          "holds it: the control that meets it with the contact sliding would need a "
          "holding force of only 4.924 N <= mu_static N = 5.886 N (N = 19.62 N) with it stuck"),
      std::string::npos)
      << r.control.not_met_message;
  ASSERT_FALSE(tr.stats.notes.empty());
  // (located: the holding force at mu_static N, to its roundoff)
  EXPECT_NE(
      tr.stats.notes.back().find("t = 0.0218565 s: the requirement row 'pace' needs the stuck "
                                 "contact 'coulomb.floor' to slide"),
      std::string::npos)
      << tr.stats.notes.back();
  EXPECT_NE(tr.stats.notes.back().find("holding force of 5.886 N > mu_static N = 5.886 N"),
            std::string::npos)
      << tr.stats.notes.back();
  // the slip the note names is the one listed: at t*, its holding force at mu_static m g, and
  // the note says nothing of a start
  const auto slips =
      testing::events_of(tr, m.system.constraint_index("floor"), ContactEvent::Kind::kSlip);
  ASSERT_EQ(tr.stats.contact_events.size(), 1u);
  ASSERT_EQ(slips.size(), 1u);
  EXPECT_NEAR(slips[0].t, ts, 1e-9);
  EXPECT_EQ(slips[0].friction, "coulomb.floor");
  EXPECT_NEAR(slips[0].friction_limit, 0.3 * kM * kG, 1e-12);
  EXPECT_NEAR(slips[0].holding_force, 0.3 * kM * kG, 1e-9);
  EXPECT_EQ(tr.stats.notes.back().find("from the start"), std::string::npos);
  ASSERT_GE(tr.samples(), 12);
  for (std::size_t i = 0; i < std::size_t(tr.samples()); ++i) {
    const double t = tr.t[i];
    if (t < ts) {
      EXPECT_NEAR(at(tr, tr.q, "p.x", i), 0.0, 1e-15) << "t = " << t;
      EXPECT_NEAR(at(tr, r.Qc_control, "p.x", i), 0.0, 1e-12) << "t = " << t;
      // the floor holds it: the stick's reaction is the (zero) push, within mu_static N
      EXPECT_NEAR(r.error[i], -x_d(A, t), 1e-12) << "t = " << t;
      continue;
    }
    const double tau = t - ts, E = std::exp(-kOmega * tau);
    const double e = (c1 + c2 * tau) * E, e1 = (c2 - kOmega * (c1 + c2 * tau)) * E;
    const double e2 = (-2.0 * kOmega * c2 + kOmega * kOmega * (c1 + c2 * tau)) * E;
    EXPECT_NEAR(at(tr, tr.q, "p.x", i), x_d(A, t) + e, 1e-8) << "t = " << t;
    EXPECT_NEAR(at(tr, tr.qd, "p.x", i), x_d1(A, t) + e1, 1e-8) << "t = " << t;
    // F = m x'' − friction: the friction mu N (2e-6 N less at 1e-6 s after t*, where v_rel =
    // 1e-6 m/s: the sliding law's regularization at eps = 1e-9 m/s, which the control answers)
    const double friction = at(tr, tr.Qc_nonideal, "p.x", i);
    EXPECT_NEAR(friction, -kMu * kM * kG, 3e-6) << "t = " << t;
    EXPECT_NEAR(at(tr, r.Qc_control, "p.x", i), kM * (x_d2(A, t) + e2) - friction, 1e-7)
        << "t = " << t;
    EXPECT_NEAR(r.error[i], e, 1e-8) << "t = " << t;
  }
}

TEST(ControlSlip, ParticleThatStaticFrictionHoldsIsReportedNotMetWithBothForces) {
  // mu_static = 1: the sliding control's 4.924 N … 7.4 N stays below mu_static m g = 19.62 N
  // over the run: stuck throughout, the requirement not met at every evaluation, and said why
  const double A = 0.02;
  const ControlledTrajectory r = run(pushed_particle(A, 1.0, 0.05));
  const Trajectory& tr = r.plant;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.events, 0);
  // (all but the start's evaluations with the contact sliding, before its stick)
  EXPECT_GE(r.control.not_met, r.control.evaluations - 3);
  EXPECT_NE(
      r.control.not_met_message.find(
          "holding force of only 4.924 N <= mu_static N = 19.62 N (N = 19.62 N) with it stuck"),
      std::string::npos)
      << r.control.not_met_message;
  EXPECT_TRUE(tr.stats.notes.empty());
  ASSERT_EQ(tr.samples(), 2);
  EXPECT_NEAR(at(tr, tr.q, "p.x", 1), 0.0, 1e-15);
  EXPECT_NEAR(at(tr, r.Qc_control, "p.x", 1), 0.0, 1e-12);
  EXPECT_NEAR(r.error[1], -x_d(A, 0.05), 1e-12);
}

TEST(ControlSlip, ArmTipDrawnAlongARoughTableSlidesFromRest) {
  // a 2-link arm (tests/data/arm2_drawn.urdf) resting its tip (sphere, r = 0.02) on a table
  // (mu = 0.3) where static friction holds it against gravity; its tip's abscissa must follow
  // x0 − 0.05 (1 − cos 2t) and its height stay on the table (a row that duplicates the
  // contact's). Held, the stuck tip leaves the arm no freedom (rank 0: the run stopped or the
  // arm never moved); the requirement breaks the stick at t = 0 and the tip slides, the contact
  // closed, both rows met to roundoff, through the reversal at t = pi/2
  const std::string text = R"(
parameters: {mu: 0.3, x0: 0.6461085205282122}
robot: {urdf: arm2_drawn.urdf}
contacts:
  - {name: tip, link: fore, point: [0.35, 0, 0], shape: sphere, radius: 0.02,
     plane: {body: ground, point: [0, 0, 0.2], normal: [0, 0, 1]}}
nonideal:
  - {friction: coulomb, constraint: tip, mu: mu}
initial:
  q: {shoulder: 0.5, elbow: asin((0.38 - 0.4*sin(0.5))/0.35) - 0.5}
control:
  requirements:
    - {name: draw, holonomic: 0.4*cos(shoulder) + 0.35*cos(shoulder + elbow) - (x0 - 0.05*(1 - cos(2*t))),
       dynamics: {omega: 20, zeta: 1}}
    - {name: stay, holonomic: 0.6 - 0.4*sin(shoulder) - 0.35*sin(shoulder + elbow) - 0.22,
       dynamics: {omega: 20, zeta: 1}}
simulate: {t_end: 2}
output: {every: 0.05}
)";
  const Model m = parse_model(text, std::string(UKDYN_TEST_DATA_DIR) + "/arm2_drawn.yaml");
  const ControlledTrajectory r =
      simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
  const Trajectory& tr = r.plant;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(r.control.not_met, 0) << r.control.not_met_message;
  ASSERT_FALSE(tr.stats.notes.empty());
  EXPECT_NE(
      tr.stats.notes.back().find(
          "t = 0 s: the requirement row 'draw' needs the stuck contact 'coulomb.tip' to slide"),
      std::string::npos)
      << tr.stats.notes.back();
  ASSERT_EQ(tr.samples(), 41);
  const std::size_t m_rows = std::size_t(tr.m);
  for (std::size_t i = 0; i < 41; ++i) {
    const double t = tr.t[i];
    EXPECT_NEAR(r.error[2 * i], 0.0, 1e-9) << "t = " << t;
    EXPECT_NEAR(r.error[2 * i + 1], 0.0, 1e-9) << "t = " << t;
    // the tip's abscissa, from the joint angles
    const double s = tr.q[2 * i], e = tr.q[2 * i + 1];
    EXPECT_NEAR(0.4 * std::cos(s) + 0.35 * std::cos(s + e),
                0.6461085205282122 - 0.05 * (1.0 - std::cos(2.0 * t)), 1e-9)
        << "t = " << t;
    // sliding, pressed on the table: the stick rows carry nothing, the contact pushes
    for (std::size_t k = 1; k < m_rows; ++k) EXPECT_EQ(tr.lambda[m_rows * i + k], 0.0);
    EXPECT_GT(tr.lambda[m_rows * i], 1.0) << "t = " << t;
  }
}

// u16 02: a particle (m = 2, mu = mu_static = 0.2) on a rough floor, pushed along x by a constant
// F, and a requirement that holds it where it is (x = 0: its row duplicates the stuck contact's),
// written in generalized coordinates (the friction on the coordinate path) in SI or in mm, g, ms
// (where a force is g mm/ms² = 1 N: the same numbers)
std::string held_particle(double F, bool mm) {
  return std::string("parameters: {m: ") + (mm ? "2000, g: 9.81e-3" : "2, g: 9.81") +
         ", mu: 0.2, F: " + std::to_string(F) + "}\nunits: " +
         (mm ? "{length: mm, mass: g, time: ms}" : "{length: m, mass: kg, time: s}") + R"(
coordinates: [x, y]
kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)
potential_energy: m*g*y - F*x
constraints:
  - {name: floor, holonomic: y, unilateral: true}
nonideal:
  - {friction: coulomb, constraint: floor, coordinates: [x], mu: mu}
control:
  requirements:
    - {name: hold, holonomic: x, dynamics: {omega: )" +
         (mm ? "0.02" : "20") + R"(, zeta: 1}}
  law: gauss
simulate: {t_end: )" +
         (mm ? "1000" : "1") + R"(, integrator: dopri5, rtol: 1e-10, atol: 1e-12}
output: {every: )" +
         (mm ? "100" : "0.1") + "}\n";
}

TEST(ControlSlip, ParticleHeldInPlaceSharesThePushWithStaticFrictionInAnyUnits) {
  // |F| = 10 > mu m g = 3.924: static friction cannot hold it, so the friction acts at its full
  // magnitude against the push and the control pays the rest, F_c = −(F − mu m g sign F); it was
  // F_c = −10 with no friction in SI and −13.924 with the friction along the push in mm (a
  // roundoff direction). F = 2: the stick holds it alone, the control 0, every evaluation met
  // (it was "not met" at a residual of 7e-16, then slipped on a tie, 3.924 > 3.924, at a time
  // that depended on the units)
  const double muN = 0.2 * 2.0 * 9.81;
  for (const bool mm : {false, true}) {
    for (const double F : {10.0, -10.0, 2.0}) {
      SCOPED_TRACE(std::string(mm ? "mm, g, ms" : "SI") + ", F = " + std::to_string(F));
      const ControlledTrajectory r = run(held_particle(F, mm));
      const Trajectory& tr = r.plant;
      ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
      EXPECT_EQ(r.control.not_met, 0) << r.control.not_met_message;
      EXPECT_EQ(tr.stats.events, 0);
      EXPECT_TRUE(tr.stats.contact_events.empty());
      EXPECT_TRUE(tr.stats.notes.empty()) << tr.stats.notes.front();
      ASSERT_EQ(tr.samples(), 11);
      const bool slides = std::abs(F) > muN;
      for (std::size_t i = 0; i < 11; ++i) {
        EXPECT_NEAR(at(tr, tr.q, "x", i), 0.0, mm ? 1e-9 : 1e-12) << "t = " << tr.t[i];
        const double friction = at(tr, tr.Qc_nonideal, "x", i);
        const double control = at(tr, r.Qc_control, "x", i);
        if (slides) {
          EXPECT_NEAR(friction, -muN * (F > 0 ? 1.0 : -1.0), 1e-9) << "t = " << tr.t[i];
          EXPECT_NEAR(control, -(F + friction), 1e-9) << "t = " << tr.t[i];
        } else {
          EXPECT_NEAR(control, 0.0, 1e-9) << "t = " << tr.t[i];
          // the stick's reaction holds the push
          EXPECT_NEAR(at(tr, tr.Qc_ideal, "x", i) + friction, -F, 1e-9) << "t = " << tr.t[i];
        }
      }
    }
  }
}

TEST(ControlSlip, ContactPointHeldInPlaceSharesThePushWithStaticFriction) {
  // the same on a contact point's path (a particle's contacts: entry; the push is gravity tilted
  // along x, m g_x = F)
  for (const double F : {10.0, 2.0}) {
    SCOPED_TRACE("F = " + std::to_string(F));
    const std::string text = "parameters: {m: 2, g: 9.81, gx: " + std::to_string(F / 2.0) + R"(}
bodies:
  - {name: p, type: particle, mass: m, position: [0, 0, 0]}
forces:
  - {type: gravity, g: [gx, 0, -g]}
contacts:
  - {name: floor, body: p}
nonideal:
  - {friction: coulomb, constraint: floor, mu: 0.2}
control:
  requirements:
    - {name: hold, holonomic: p_x, dynamics: {omega: 20, zeta: 1}}
  actuated: [p_x]
simulate: {t_end: 1, integrator: dopri5, rtol: 1e-10, atol: 1e-12}
output: {every: 0.25}
)";
    const ControlledTrajectory r = run(text);
    const Trajectory& tr = r.plant;
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_EQ(r.control.not_met, 0) << r.control.not_met_message;
    EXPECT_EQ(tr.stats.events, 0);
    ASSERT_EQ(tr.samples(), 5);
    const double muN = 0.2 * 2.0 * 9.81;
    for (std::size_t i = 0; i < 5; ++i) {
      EXPECT_NEAR(at(tr, tr.q, "p.x", i), 0.0, 1e-12) << "t = " << tr.t[i];
      const double control = at(tr, r.Qc_control, "p.x", i);
      const double friction = at(tr, tr.Qc_nonideal, "p.x", i) + at(tr, tr.Qc_ideal, "p.x", i);
      EXPECT_NEAR(control, F > muN ? -(F - muN) : 0.0, 1e-9) << "t = " << tr.t[i];
      EXPECT_NEAR(friction, F > muN ? -muN : -F, 1e-9) << "t = " << tr.t[i];
    }
  }
}

// u17 02: a planar body (m = 2, mu = 0.3, mu_s = 0.4) pushed at its centre by F = 10 N and held
// there (box_x = 0), in SI or in mm, g, ms: on two bottom corners (shape: box) the corners cannot
// hold it (F > mu_s m g), so their friction is mu m g against the push and the control the rest,
// −4.114 N (in mm it was +5.886 along the push, −15.886); on one contact point below its centre
// the stick holds with no holding force (the held body cannot turn: a contact point sliding
// would need it to), the control all of −F (it slid at t = 0 under a friction that then lapsed,
// and in mm the run did not end)
std::string held_body(bool mm, bool box) {
  return std::string("parameters: {m: ") +
         (mm ? "2000, g: 9.81e-3, hx: 200, hy: 50" : "2, g: 9.81, hx: 0.2, hy: 0.05") +
         ", F: 10}\nunits: " +
         (mm ? "{length: mm, mass: g, time: ms}" : "{length: m, mass: kg, time: s}") + R"(
bodies:
  - {name: box, type: planar, mass: m, inertia: m*(hx^2+hy^2)/3, position: [0, hy]}
forces:
  - {type: gravity, g: [0, -g]}
  - {name: push, type: applied, body: box, force: [F, 0]}
contacts:
  - )" +
         (box ? "{name: lid, body: box, shape: box, size: [hx, hy]}"
              : "{name: lid, body: box, point: [0, -hy]}") +
         R"(
nonideal:
  - {friction: coulomb, constraint: lid, mu: 0.3, mu_static: 0.4}
control:
  requirements:
    - {name: stay, holonomic: box_x, dynamics: {omega: )" +
         (mm ? "0.01" : "10") + R"(, zeta: 1}}
simulate: {t_end: )" +
         (mm ? "500, rtol: 1e-10, atol: 1e-9}" : "0.5, rtol: 1e-10, atol: 1e-12}") +
         "\noutput: {every: " + (mm ? "50" : "0.05") + "}\n";
}

TEST(ControlSlip, BodyHeldAtItsCentreOnCornersOrAPointBelowInAnyUnits) {
  const double muN = 0.3 * 2.0 * 9.81;
  for (const bool mm : {false, true}) {
    for (const bool box : {true, false}) {
      SCOPED_TRACE(std::string(mm ? "mm, g, ms" : "SI") + (box ? ", box" : ", point"));
      const ControlledTrajectory r = run(held_body(mm, box));
      const Trajectory& tr = r.plant;
      ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
      ASSERT_EQ(tr.samples(), 11);
      for (std::size_t i = 0; i < 11; ++i) {
        EXPECT_NEAR(at(tr, tr.q, "box.x", i), 0.0, 1e-12) << "t = " << tr.t[i];
        const double friction = at(tr, tr.Qc_nonideal, "box.x", i);
        EXPECT_NEAR(friction, box ? -muN : 0.0, 1e-9) << "t = " << tr.t[i];
        EXPECT_NEAR(at(tr, r.Qc_control, "box.x", i), box ? -(10.0 - muN) : -10.0, 1e-9)
            << "t = " << tr.t[i];
      }
    }
  }
}

// ---- several stuck contacts under control: a box on two corners ------------------------------

// a tall planar box (m = 3, half-width a = 0.2, half-height c = 0.2) at rest on its two bottom
// corners (mu = 0.3, mu_s at each), its x required to follow A (1 − cos 5t) as the particle's,
// actuated along x at its centre: the corners carry N = m g / 2 ∓ F c / (2 a) (their sum m g),
// so the minimum-norm split (F / 2 each) leaves the lighter corner's cone from
// F = mu_s m g / (1 + mu_s c / a) on, while a split inside both cones exists up to mu_s m g;
// sliding, the friction is mu m g. The control decides with the run's test (some split inside
// both cones: ContactModes::hold_by_split), so a requirement needing less than mu_s m g keeps it
// stuck. In SI, or in mm, g, ms (`mm`: the same numbers scaled, times in ms).
constexpr double kBoxMass = 3.0, kBoxMu = 0.3;
std::string pushed_box(double A, double mu_static, double t_end, bool mm = false) {
  return std::string("parameters: {") +
         (mm ? "m: 3000, g: 9.81e-3, a: 200, c: 200, A: " + std::to_string(A * 1e3) +
                   ", w: 5e-3, omega: 0.02"
             : "m: 3, g: 9.81, a: 0.2, c: 0.2, A: " + std::to_string(A) + ", w: 5, omega: 20") +
         ", mu: 0.3, mus: " + std::to_string(mu_static) + "}\nunits: " +
         (mm ? "{length: mm, mass: g, time: ms}" : "{length: m, mass: kg, time: s}") + R"(
bodies:
  - {name: box, type: planar, mass: m, inertia: m*(4*a^2+4*c^2)/12, position: [0, c]}
forces:
  - {type: gravity, g: [0, -g]}
contacts:
  - {name: left, body: box, point: [-a, -c]}
  - {name: right, body: box, point: [a, -c]}
nonideal:
  - {friction: coulomb, constraint: left, mu: mu, mu_static: mus}
  - {friction: coulomb, constraint: right, mu: mu, mu_static: mus}
control:
  requirements:
    - {name: pace, holonomic: box_x - A*(1 - cos(w*t)), dynamics: {omega: omega, zeta: 1}}
  actuated: [box_x]
simulate: {t_end: )" +
         std::to_string(t_end * (mm ? 1e3 : 1.0)) +
         ", integrator: dopri5, rtol: 1e-11, atol: " + (mm ? "1e-10" : "1e-13") +
         "}\noutput: {every: " + (mm ? "50" : "0.05") + "}\n";
}

TEST(ControlSlip, BoxOnTwoCornersPushedFromRestSlidesWithTheClosedFormForce) {
  // A = 0.1: the sliding control F(0) = m A w² + mu m g = 16.33 N > mu_s m g = 14.7 N, so no
  // split of the two corners' holding forces holds it: both slide from t = 0, x = x_d,
  // F = m x_d'' + mu m g while x_d' > 0 (t < pi/5), the corners' friction −mu m g together
  const double A = 0.1;
  const ControlledTrajectory r = run(pushed_box(A, 0.5, 0.6));
  const Trajectory& tr = r.plant;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(r.control.not_met, 0) << r.control.not_met_message;
  expect_slides_on_pace(r, "box.x", A, kBoxMass, kBoxMu);
}

// (Enabled in h17/ctrlstuck. It was disabled because the unilateral contacts' LCP under control
// (settle_contacts) answered first with a control met by tipping the box onto its front corner,
// Q_x = (a m g + I_p x_d''(0) / c) / c = 39.43 N, which that corner cannot hold (|H| = 35.68 N >
// mu_s N = 19.91 N): the plant slid from t = 0. Now a control that leaves stuck contacts that
// cannot hold is not taken, and slip() decides; after the run releases the lighter corner at t*,
// the other's margin takes the sliding corner's friction at its N under F_s, so it slips too.)
// By hand, stuck (x'' = y'' = θ'' = 0, F along x at the centre, corners (∓a, −c)): H_l + H_r =
// −F, N_l + N_r = m g, a (N_r − N_l) = c F; a split inside both cones exists iff F <= mu_s m g
// (the cones' sum), the minimum-norm one (H = −F / 2 each) iff F <= mu_s m g / (1 + mu_s c / a);
// the split of largest margin gives both margins (mu_s m g − F) / 2.
TEST(ControlSlip, BoxOnTwoCornersHeldBySomeSplitSlipsAtMuStaticMgInAnyUnits) {
  // mu_s = 0.6, A = 0.05: the sliding control F(0) = m A w² + mu m g = 12.58 N lies between the
  // minimum-norm split's limit mu_s m g / (1 + mu_s c / a) = 11.04 N and mu_s m g = 17.66 N: held
  // (x = 0, no control force, the corners' holding forces summing to the push, 0), the
  // requirement not met, with the numbers of the corner least held at the split of largest
  // margin (both margins (mu_s m g − F) / 2 there: the light corner, N = m g / 2 − F c / (2 a),
  // H = (F − mu_s F c / a) / 2); slides once m a_stuck(t) + mu m g reaches mu_s m g at t*
  // (a_stuck(t*) = (mu_s − mu) g, as for the particle: the split limit is the total mu_s N),
  // then x = x_d + e under the error dynamics, F = m x'' + mu m g. The same in mm, g, ms.
  const double A = 0.05, mus = 0.6;
  const double ts = stick_break(A, mus, kBoxMu);
  const double c1 = -x_d(A, ts), c2 = -x_d1(A, ts) + kOmega * c1;
  for (const bool mm : {false, true}) {
    SCOPED_TRACE(mm ? "mm, g, ms" : "SI");
    const double T = mm ? 1e3 : 1.0, L = mm ? 1e3 : 1.0;  // (model units per s, per m)
    Model m = parse_model(pushed_box(A, mus, 0.3, mm));
    m.options.output_at.clear();
    for (double t : {0.005, ts - 1e-6, ts + 1e-6, 0.05, 0.1, 0.2, 0.3})
      m.options.output_at.push_back(t * T);
    const ControlledTrajectory r =
        simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
    const Trajectory& tr = r.plant;
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_GT(r.control.not_met, 0);
    EXPECT_EQ(r.control.first_not_met, 0.0);
    const double F0 = kBoxMass * A * kW * kW + kBoxMu * kBoxMass * kG;
    const double N = kBoxMass * kG / 2 - F0 / 2, H = (F0 - mus * F0) / 2;
    EXPECT_NEAR(N, 8.4255, 1e-4);
    EXPECT_NEAR(mus * N - H, (mus * kBoxMass * kG - F0) / 2, 1e-12);
    const std::string f = mm ? " g·mm/ms²" : " N";
    EXPECT_NE(r.control.not_met_message.find(
                  "static friction holds it: the control that meets it with the contact sliding "
                  "would need a holding force of only " +
                  format_number(H, 6) + f + " <= mu_static N = " + format_number(mus * N, 6) + f +
                  " (N = " + format_number(N, 6) + f + ") with it stuck"),
              std::string::npos)
        << r.control.not_met_message;
    // the release at t*, located: the note's time is t* to its 6 digits (the samples 1e-6 s
    // either side of it, below, are stuck and sliding), the same in both units
    ASSERT_FALSE(tr.stats.notes.empty());
    const std::string& note = tr.stats.notes.back();
    EXPECT_NE(note.find("t = " + format_number(ts * T, 6) + (mm ? " ms" : " s") +
                        ": the requirement row 'pace' needs the stuck contact"),
              std::string::npos)
        << note;
    // (the samples: t = 0, output_at's 7 and the model's every 0.05 s: 0.15 and 0.25 more)
    ASSERT_EQ(tr.samples(), 10);
    for (std::size_t i = 0; i < 10; ++i) {
      const double t = tr.t[i] / T;
      const double x = at(tr, tr.q, "box.x", i) / L;
      const double F = at(tr, r.Qc_control, "box.x", i);  // (g mm/ms² = N)
      if (t < ts) {
        EXPECT_NEAR(x, 0.0, 1e-12) << "t = " << t;
        EXPECT_NEAR(F, 0.0, 1e-9) << "t = " << t;
        EXPECT_NEAR(r.error[i] / L, -x_d(A, t), 1e-9) << "t = " << t;
        continue;
      }
      const double tau = t - ts, E = std::exp(-kOmega * tau);
      const double e = (c1 + c2 * tau) * E;
      const double e2 = (-2.0 * kOmega * c2 + kOmega * kOmega * (c1 + c2 * tau)) * E;
      EXPECT_NEAR(x, x_d(A, t) + e, 1e-7) << "t = " << t;
      EXPECT_NEAR(F, kBoxMass * (x_d2(A, t) + e2) + kBoxMu * kBoxMass * kG, 1e-5) << "t = " << t;
    }
  }
}

// ---- several contacts stopping together under control: a cube on its corners (u21 01) -------

// a cube (m = 2, half side h = 0.05, a rigid body in quaternions) on a rough floor with its box
// contact (mu = 0.2, mu_s = 0.3), every coordinate actuated, its x required to follow
// A (1 − cos 5t), A = 0.2: x_d''(0) = 5 > mu_s g, so it slides from t = 0 with
// F_x = m x_d'' + mu m g. At t = pi/5, where x_d' reverses, its four bottom corners stop at once;
// holding them would take m |x_d''| = 10 N > mu_s m g = 5.886 N, so all of them slip back at
// once, F_x = m x_d'' − mu m g, and by symmetry the cube stays on y = 0 without turning. (The stop
// was decided for the corner whose event came first alone: it stuck, the control turned the cube
// about it, 0.22 rad by t = 1, y = 0.0164.)
TEST(ControlSlip, CubeWhoseCornersStopTogetherSlipsBackTogetherWithoutTurning) {
  Model m = parse_model(R"(parameters: {m: 2, h: 0.05, g: 9.81, mu: 0.2, mus: 0.3, A: 0.2}
bodies:
  - {name: box, type: rigid, mass: m, inertia: m*(2*h)^2/6, position: [0, 0, h]}
forces:
  - {type: gravity, g: [0, 0, -g]}
contacts:
  - {name: base, body: box, shape: box, size: [h, h, h]}
nonideal:
  - {friction: coulomb, constraint: base, mu: mu, mu_static: mus}
control:
  requirements:
    - {name: pull, holonomic: box_x - A*(1 - cos(5*t)), dynamics: {omega: 20, zeta: 1}}
simulate: {t_end: 1, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0.05}
)");
  const double A = 0.2, ts = std::acos(-1.0) / kW, d = 1e-6;
  for (double t : {ts - d, ts + d}) m.options.output_at.push_back(t);
  const ControlledTrajectory r =
      simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
  const Trajectory& tr = r.plant;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.samples(), 23);
  for (std::size_t i = 0; i < std::size_t(tr.samples()); ++i) {
    const double t = tr.t[i];
    // on y = 0, level, not turned (the quaternion's vector part 0)
    EXPECT_NEAR(at(tr, tr.q, "box.y", i), 0.0, 1e-9) << "t = " << t;
    for (const char* u : {"box.u1", "box.u2", "box.u3"})
      EXPECT_NEAR(at(tr, tr.q, u, i), 0.0, 1e-9) << u << ", t = " << t;
    EXPECT_NEAR(at(tr, r.Qc_control, "box.y", i), 0.0, 1e-9) << "t = " << t;
    if (t == 0.0) continue;
    // on pace, the friction mu m g against x_d' (forward before pi/5, back after); the stop
    // projects away its v_stop (x' -1e-7 at pi/5 + 1e-6), which the error dynamics then remove:
    // m 2 omega 1e-7 = 8e-6 N at most in F
    EXPECT_NEAR(at(tr, tr.q, "box.x", i), x_d(A, t), 1e-8) << "t = " << t;
    EXPECT_NEAR(at(tr, tr.qd, "box.x", i), x_d1(A, t), 2e-7) << "t = " << t;
    const double sliding = t < ts ? 1.0 : -1.0;
    EXPECT_NEAR(at(tr, r.Qc_control, "box.x", i), kM * x_d2(A, t) + sliding * kMu * kM * kG, 2e-5)
        << "t = " << t;
  }
}

// ---- a requirement that the actuators reach only through a held contact (u21 02) ------------

// tests/data/rolling_wheel.urdf (M = 4 kg moves in x, 3 kg in z, the wheel's I = 0.01, r = 0.1)
// on a rough floor (mu = 0.2, mu_static = 0.3, N = 3 g = 29.43 N), only the axle (pitch)
// actuated, x required to follow v0 t + c t²/2 under e'' + 20 e' + 100 e = 0. The axle moves x
// only through the friction under the wheel: held (rolling), tau = (I/r + r M) x'' = 0.5 x''
// and the friction M x''; sliding, the torque does not move x at all.
std::string driven_wheel(double c, double v0) {
  return "parameters: {c: " + format_number(c) + ", v0: " + format_number(v0) + R"(}
robot: {urdf: rolling_wheel.urdf}
contacts:
  - {name: floor, link: wheel, shape: sphere, radius: 0.1}
nonideal:
  - {friction: coulomb, constraint: floor, mu: 0.2, mu_static: 0.3}
initial:
  q_dot: {x: v0, pitch: v0/0.1}
control:
  actuated: [pitch]
  requirements:
    - {name: go, holonomic: x - v0*t - c*t^2/2, dynamics: {omega: 10, zeta: 1}}
simulate: {t_end: 1, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0.1}
)";
}

ControlledTrajectory run_wheel(double c, double v0) {
  const Model m =
      parse_model(driven_wheel(c, v0), std::string(UKDYN_TEST_DATA_DIR) + "/wheel_drive.yaml");
  return simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
}

constexpr double kWheelMass = 4.0, kWheelN = 3.0 * kG, kWheelR = 0.1, kWheelI = 0.01;

// c <= mu_static N / M = 2.20725: it rolls on pace, tau = 0.5 c, the friction M c, and every
// evaluation meets the requirement (the 3 evaluations of the start with the contact sliding
// used to say the axle "does not move" x)
TEST(ControlSlip, WheelDrivenByItsAxleRollsOnPaceWhereStaticFrictionTransmitsTheForce) {
  for (const double v0 : {0.0, 1.0}) {
    for (const double c : {1.5, 2.1}) {
      SCOPED_TRACE("c = " + format_number(c) + ", v0 = " + format_number(v0));
      const ControlledTrajectory r = run_wheel(c, v0);
      const Trajectory& tr = r.plant;
      ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
      EXPECT_EQ(r.control.not_met, 0) << r.control.not_met_message;
      EXPECT_EQ(r.control.not_met_message.find("not moved"), std::string::npos);
      ASSERT_EQ(tr.samples(), 11);
      for (std::size_t i = 0; i < 11; ++i) {
        const double t = tr.t[i];
        EXPECT_NEAR(at(tr, tr.q, "x", i), v0 * t + c * t * t / 2.0, 1e-9) << "t = " << t;
        EXPECT_NEAR(at(tr, tr.qdd, "x", i), c, 1e-9) << "t = " << t;
        EXPECT_NEAR(at(tr, tr.qdd, "pitch", i), c / kWheelR, 1e-8) << "t = " << t;
        EXPECT_NEAR(at(tr, r.Qc_control, "pitch", i),
                    (kWheelI / kWheelR + kWheelR * kWheelMass) * c, 1e-9)
            << "t = " << t;
        EXPECT_NEAR(r.error[i], 0.0, 1e-9) << "t = " << t;
      }
    }
  }
}

// c = 2.5: rolling needs the friction M c = 10 N > mu_static N = 8.829 N. The control is the one
// that meets the requirement with the contact held (the rolling torque 0.5 x''_req, x''_req =
// c − 20 e' − 100 e), the run's stick test refuses the stick at t = 0, and the wheel spins and
// slides, the friction mu N = 5.886 N pushing it at x'' = mu N / M = 1.4715 m/s² — so e =
// (1.4715 − c) t²/2, and the wheel's pitch'' = (tau − r mu N) / I. The requirement is reported as
// not met, naming the contact and the forces, never as "not moved by the actuated coordinates".
// (Before: tau = 0 throughout, the wheel never turned, and the warning said the axle does not
// move x.)
TEST(ControlSlip, WheelDrivenBeyondWhatStaticFrictionTransmitsSpinsAndSlidesAtMuG) {
  const double c = 2.5, a = 0.2 * kWheelN / kWheelMass;  // 1.4715
  for (const double v0 : {0.0, 1.0}) {
    SCOPED_TRACE("v0 = " + format_number(v0));
    const ControlledTrajectory r = run_wheel(c, v0);
    const Trajectory& tr = r.plant;
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_GT(r.control.not_met, 0);
    EXPECT_EQ(r.control.first_not_met, 0.0);
    EXPECT_EQ(r.control.not_met_message.find("not moved"), std::string::npos)
        << r.control.not_met_message;
    const std::string said =
        "t = 0 s: the requirement row 'go' can be met only with the contact 'coulomb.floor' held "
        "(stuck): with it sliding the actuated coordinates do not meet it, and the control that "
        "meets it with it held needs a holding force of 10 N > mu_static N = 8.829 N "
        "(N = 29.43 N), more than static friction gives";
    EXPECT_NE(r.control.not_met_message.find(said), std::string::npos) << r.control.not_met_message;
    ASSERT_FALSE(tr.stats.notes.empty());
    EXPECT_EQ(tr.stats.notes.back().find(said), 0u) << tr.stats.notes.back();
    ASSERT_EQ(tr.samples(), 11);
    for (std::size_t i = 0; i < 11; ++i) {
      const double t = tr.t[i];
      const double e = (a - c) * t * t / 2.0, e1 = (a - c) * t;
      const double tau = (kWheelI / kWheelR + kWheelR * kWheelMass) * (c - 20.0 * e1 - 100.0 * e);
      EXPECT_NEAR(at(tr, r.Qc_control, "pitch", i), tau, 1e-6) << "t = " << t;
      EXPECT_NEAR(r.error[i], e, 1e-6) << "t = " << t;
      EXPECT_NEAR(at(tr, tr.q, "x", i), v0 * t + a * t * t / 2.0, 1e-6) << "t = " << t;
      if (t == 0.0) continue;  // (the first instant's sample: the stick's refusal decides it)
      EXPECT_NEAR(at(tr, tr.qdd, "x", i), a, 1e-6) << "t = " << t;
      EXPECT_NEAR(at(tr, tr.qdd, "pitch", i), (tau - kWheelR * 0.2 * kWheelN) / kWheelI, 1e-4)
          << "t = " << t;
    }
  }
}

// ---- a box yawed on its four corners by a torque (u22 02) -----------------------------------

// a box (m = 2, half-extents 0.2 x 0.1 x 0.05, a rigid body in quaternions) on its four bottom
// corners on a rough floor (mu = mu_s = 0.3), the control acting on its quaternion only (a
// torque), required to yaw psi = 2 k t² (u3 = sin(k t²) at u1 = u2 = 0). Each corner, at
// rho = sqrt(0.05) from the centre, holds at most mu m g / 4, so any psi'' = 4 k > 0 needs the
// torque I_z psi'' + mu m g rho beyond what static friction holds: the box turns from t = 0 and
// follows psi exactly with that torque. (It stayed stuck up to psi'' = 4.11 — the run released one
// corner, and the control with the other three sliding took their friction against a motion that
// the released corner's friction pushed sideways, needing 0.64 of Coulomb's torque, which the
// three then held.)
std::string yawed_box(double k) {
  return "parameters: {m: 2, a: 0.2, b: 0.1, c: 0.05, mu: 0.3, k: " + format_number(k) + R"(}
bodies:
  - {name: box, type: rigid, mass: m, inertia: [m*(b^2+c^2)/3, m*(a^2+c^2)/3, m*(a^2+b^2)/3],
     position: [0, 0, c]}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: floor, body: box, shape: box, size: [a, b, c]}
nonideal:
  - {friction: coulomb, constraint: floor, mu: mu}
control:
  actuated: [box_u0, box_u1, box_u2, box_u3]
  requirements:
    - {name: yaw, holonomic: box_u3 - sin(k*t^2)}
simulate: {t_end: 0.5}
output: {every: 0.05}
)";
}

TEST(ControlSlip, BoxYawedOnFourCornersTurnsWithCoulombsTorqueForAnyYawAcceleration) {
  const double m = 2.0, Iz = m * (0.04 + 0.01) / 3.0, rho = std::sqrt(0.05);
  const double coulomb = 0.3 * m * kG * rho;  // 1.31615
  EXPECT_NEAR(coulomb, 1.3161496116, 1e-9);
  // psi'' = 0.1, 1, 4 (held before: up to 4.11), 8
  for (const double k : {0.025, 0.25, 1.0, 2.0}) {
    SCOPED_TRACE("psi'' = " + format_number(4.0 * k));
    const ControlledTrajectory r = run(yawed_box(k));
    const Trajectory& tr = r.plant;
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_EQ(r.control.not_met, 0) << r.control.not_met_message;
    ASSERT_EQ(tr.samples(), 11);
    for (std::size_t i = 0; i < 11; ++i) {
      const double t = tr.t[i];
      const double u0 = at(tr, tr.q, "box.u0", i), u3 = at(tr, tr.q, "box.u3", i);
      EXPECT_NEAR(2.0 * std::atan2(u3, u0), 2.0 * k * t * t, 1e-9) << "t = " << t;
      // the torque about z of the generalized force on the quaternion (u1 = u2 = 0):
      // tau_z = (u0 Q3 − u3 Q0) / 2
      const double tau =
          (u0 * at(tr, r.Qc_control, "box.u3", i) - u3 * at(tr, r.Qc_control, "box.u0", i)) / 2.0;
      EXPECT_NEAR(tau, Iz * 4.0 * k + coulomb, 1e-8) << "t = " << t;
      EXPECT_NEAR(at(tr, tr.q, "box.x", i), 0.0, 1e-9) << "t = " << t;
      EXPECT_NEAR(at(tr, tr.q, "box.y", i), 0.0, 1e-9) << "t = " << t;
    }
  }
  // psi'' = 0: nothing to do, it stays stuck with no torque
  const ControlledTrajectory r = run(yawed_box(0.0));
  ASSERT_EQ(r.plant.stats.status, Status::kOk) << r.plant.stats.message;
  EXPECT_EQ(r.control.not_met, 0) << r.control.not_met_message;
  for (std::size_t i = 0; i < std::size_t(r.plant.samples()); ++i) {
    EXPECT_NEAR(at(r.plant, r.plant.q, "box.u3", i), 0.0, 1e-12);
    EXPECT_NEAR(at(r.plant, r.Qc_control, "box.u3", i), 0.0, 1e-12);
  }
}

// ---- a ball driven round a circle by a torque beyond what friction transmits (u22 05) -------

// a solid ball (m = 1, r = 0.1) rolling on a rough floor (mu = mu_s = 0.5), the control on its
// quaternion only, its centre required to go round a circle of radius 0.5 at W = 4: the
// centripetal 8 m/s² > mu g = 4.905. With the contact sliding the torque does not move the
// centre, so the control is the one that meets the requirement with the contact held; the ball
// slides under it, its centre accelerated by the friction mu m g alone. (Before: with the
// contact sliding, the actuated columns of X were roundoff of its centre's, ~1e-17, taken as
// rank: Qc ~ 1e16, the step size underflowed at t = 7.5e-10 s, and bdf hung.)
TEST(ControlSlip, BallDrivenRoundACircleFasterThanFrictionAllowsSlidesAtMuG) {
  const std::string text = R"(parameters: {m: 1, r: 0.1, R: 0.5, W: 4, mu: 0.5}
bodies:
  - {name: ball, type: rigid, mass: m, inertia: 0.4*m*r^2, position: [R, 0, r],
     velocity: [0, R*W, 0], angular_velocity: [-R*W/r, 0, 0]}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: floor, body: ball, shape: sphere, radius: r}
nonideal:
  - {friction: coulomb, constraint: floor, mu: mu}
control:
  actuated: [ball_u0, ball_u1, ball_u2, ball_u3]
  requirements:
    - {name: cx, holonomic: ball_x - R*cos(W*t)}
    - {name: cy, holonomic: ball_y - R*sin(W*t)}
simulate: {t_end: 1}
output: {every: 0.05}
)";
  for (const Integrator integrator : {Integrator::kDopri5, Integrator::kBDF}) {
    SCOPED_TRACE(to_string(integrator));
    Model model = parse_model(text);
    model.options.integrator = integrator;
    const ControlledTrajectory r =
        simulate_controlled(*model.controller, model.system, model.q0, model.qd0, model.options);
    const Trajectory& tr = r.plant;
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    ASSERT_EQ(tr.samples(), 21);
    EXPECT_GT(r.control.not_met, 0);
    EXPECT_TRUE(r.control.held_control);
    EXPECT_NE(r.control.not_met_message.find(
                  "the control that meets them with the sliding contact held applied (the "
                  "contact slides under it). Not met: 'cx' (residual 8)"),
              std::string::npos)
        << r.control.not_met_message;
    EXPECT_NE(r.control.not_met_message.find(
                  "needs a holding force of 8 N > mu_static N = 4.905 N (N = 9.81 N), more than "
                  "static friction gives"),
              std::string::npos)
        << r.control.not_met_message;
    // the centre's horizontal acceleration is the friction's, mu g, throughout
    for (std::size_t i = 0; i < 21; ++i) {
      const double ax = at(tr, tr.qdd, "ball.x", i), ay = at(tr, tr.qdd, "ball.y", i);
      EXPECT_NEAR(std::hypot(ax, ay), 0.5 * kG, 1e-9) << "t = " << tr.t[i];
    }
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// Switch events (issue #16 item 6): the sign changes of a model's non-smooth functions (sign,
// abs, heaviside, min, max, if) located as integrator events, the tie rule at a kink, the chatter
// guard of a sliding mode, and SimulationOptions::switch_events. The references are closed forms:
// between switches these models are polynomial or harmonic, so every method that stops at the
// switches reaches them to roundoff or to its own order.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// the sample of tr at time t (failing when there is none)
std::size_t sample_at(const Trajectory& tr, double t) {
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    if (std::abs(tr.t[i] - t) < 1e-12) return i;
  }
  ADD_FAILURE() << "no sample at t = " << t;
  return 0;
}

// The bang-bang oscillator x'' = −sign(x) from rest at x = A: x = A − t²/2 until it reaches 0 at
// t1 = √(2A) with x' = −√(2A), then the mirror image; period 4√(2A), amplitude A. With A = ½:
// t1 = 1, period 4, switches at t = 1, 3, 5, 7.
constexpr const char* kBangBang = R"(
parameters: {A: 0.5}
coordinates: [x]
mass_matrix: [[1]]
forces: [-sign(x)]
initial: {q: {x: A}}
simulate: {t_end: 8}
output: {every: 0, at: [1, 2, 3, 4, 5, 6, 7]}
)";

// x(t) and x'(t) of the bang-bang oscillator with A = ½ (period 4)
double bang_bang_x(double t) {
  const double s = std::fmod(t, 4.0);
  if (s <= 1.0) return 0.5 - 0.5 * s * s;
  if (s <= 3.0) return -0.5 + 0.5 * (s - 2.0) * (s - 2.0);
  return 0.5 - 0.5 * (s - 4.0) * (s - 4.0);
}
double bang_bang_v(double t) {
  const double s = std::fmod(t, 4.0);
  if (s <= 1.0) return -s;
  if (s <= 3.0) return s - 2.0;
  return -(s - 4.0);
}

struct MethodCase {
  Integrator method;
  double step, rtol, atol, tolerance;
};

class BangBang : public ::testing::TestWithParam<MethodCase> {};

TEST_P(BangBang, MatchesItsClosedFormWithTwoSwitchesPerPeriod) {
  const MethodCase c = GetParam();
  const Model m = parse_model(kBangBang);
  ASSERT_EQ(m.system.switch_count(), 1);
  EXPECT_EQ(m.system.switch_names()[0], "x");
  SimulationOptions o = m.options;
  o.integrator = c.method;
  o.step = c.step;
  o.rtol = c.rtol;
  o.atol = c.atol;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  // 2 switches per period: at t = 1, 3, 5, 7
  EXPECT_EQ(tr.stats.switch_events, 4);
  EXPECT_EQ(tr.stats.events, 0);  // (no Coulomb contact)
  for (double t : {1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0}) {
    const std::size_t i = sample_at(tr, t);
    EXPECT_NEAR(tr.q[i], bang_bang_x(t), c.tolerance) << to_string(c.method) << " t = " << t;
    EXPECT_NEAR(tr.qd[i], bang_bang_v(t), c.tolerance) << to_string(c.method) << " t = " << t;
  }
  // amplitude and period: back at x = A at rest after two periods
  EXPECT_NEAR(tr.q.back(), 0.5, c.tolerance);
  EXPECT_NEAR(tr.qd.back(), 0.0, c.tolerance);
}

// rk4 and rk5 integrate the quadratic pieces exactly: only the located switch times err (by the
// bisection's 1e-14); the adaptive methods meet their tolerance
INSTANTIATE_TEST_SUITE_P(
    Methods, BangBang,
    ::testing::Values(MethodCase{Integrator::kRK4, 0.03, 1e-6, 1e-9, 1e-10},
                      MethodCase{Integrator::kRK5, 0.03, 1e-6, 1e-9, 1e-10},
                      MethodCase{Integrator::kDopri5, 0.01, 1e-10, 1e-12, 1e-8},
                      MethodCase{Integrator::kRKF78, 0.01, 1e-10, 1e-12, 1e-8},
                      MethodCase{Integrator::kBDF, 0.01, 1e-10, 1e-12, 1e-7}),
    [](const ::testing::TestParamInfo<MethodCase>& i) { return to_string(i.param.method); });

// A bodies-and-joints model's applied forces switch too: a particle pushed by −sign(x) along x is
// the bang-bang oscillator above, located by rk4 to roundoff; a drive's kink is collected as well
TEST(SwitchEvents, AppliedForceAndDriveOfABodiesModel) {
  const Model m = parse_model(R"(
parameters: {A: 0.5}
bodies:
  - {name: p, type: particle, mass: 1, position: [A, 0, 0]}
forces:
  - {name: push, type: applied, body: p, force: [-sign(p_x), 0, 0]}
simulate: {t_end: 8, integrator: rk4, step: 0.03}
output: {every: 0, at: [1, 2, 3, 4, 5, 6, 7]}
)");
  ASSERT_EQ(m.system.switch_count(), 1);
  EXPECT_EQ(m.system.switch_names()[0], "p_x");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.switch_events, 4);
  for (double t : {1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0}) {
    const std::size_t i = sample_at(tr, t);
    EXPECT_NEAR(tr.q[3 * i], bang_bang_x(t), 1e-10) << "t = " << t;
    EXPECT_NEAR(tr.qd[3 * i], bang_bang_v(t), 1e-10) << "t = " << t;
    EXPECT_NEAR(tr.q[3 * i + 1], 0.0, 1e-14);
  }
  const Model driven = parse_model(R"(
bodies:
  - {name: bar, type: planar, mass: 1, inertia: 0.1, position: [0, 0]}
joints:
  - {name: pivot, type: revolute, parent: ground, child: bar, drive: 0.5*abs(t - 1)}
)");
  ASSERT_EQ(driven.system.switch_count(), 1);
  EXPECT_EQ(driven.system.switch_names()[0], "-1+t");
}

// A controlled plant keeps its switches: the controlled system (the plant plus the control force)
// used to drop them, so a switch went unlocated under control. x is made to follow sin(t) against
// the force −sign(x − 0.3); the error still follows e'' + 4e' + 4e = 0, e = (1 + t) e^(−2t), and x
// crosses 0.3 once on [0, 3]
TEST(SwitchEvents, AControlledPlantKeepsItsSwitches) {
  const Model m = parse_model(R"(
coordinates: [x]
mass_matrix: [[1]]
forces: [-sign(x - 0.3)]
control:
  requirements:
    - {name: track, holonomic: x - sin(t), dynamics: {omega: 2, zeta: 1}}
initial: {q: {x: 1}}
simulate: {t_end: 3}
)");
  const ModelRun r = run_model(m);
  EXPECT_EQ(r.trajectory.stats.status, Status::kOk) << r.trajectory.stats.message;
  EXPECT_EQ(r.trajectory.stats.switch_events, 1);
  bool found = false;
  for (const auto& c : r.columns()) {
    if (c.name != "error.track") continue;
    found = true;
    for (std::size_t i = 0; i < c.values.size(); ++i) {
      const double t = r.trajectory.t[i];
      EXPECT_NEAR(c.values[i], (1 + t) * std::exp(-2 * t), 1e-8) << t;
    }
  }
  EXPECT_TRUE(found);
}

// switch_events: false steps across the switches (the old behaviour): no event is counted, and
// rkf78 misses the closed form by far more than its tolerance (issue #16: 4.5e-2 at x(4))
TEST(SwitchEvents, OffStepsAcrossTheSwitches) {
  const Model m = parse_model(kBangBang);
  SimulationOptions o = m.options;
  o.integrator = Integrator::kRKF78;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.switch_events = false;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  EXPECT_EQ(tr.stats.switch_events, 0);
  o.switch_events = true;
  const Trajectory located = simulate(m.system, m.q0, m.qd0, o);
  const double off = std::abs(tr.q[sample_at(tr, 4.0)] - 0.5),
               on = std::abs(located.q[sample_at(located, 4.0)] - 0.5);
  EXPECT_GT(off, 1e3 * std::max(on, 1e-14));
  EXPECT_NEAR(on, 0.0, 1e-8);
}

// A smooth model has no switching function (no hook, nothing to pay); abs of a parameter folds
TEST(SwitchEvents, SmoothModelsHaveNone) {
  const Model m = parse_model(R"(
parameters: {k: -2}
coordinates: [x]
mass_matrix: [[1]]
forces: [-abs(k)*x + sign(k)]
)");
  EXPECT_EQ(m.system.switch_count(), 0);
}

// A mass at rest exactly at a kink of max, min or if, in an energy or a force, stays there: the
// tie rule takes the one-sided derivative nearer 0 (0 when they have opposite signs), as abs does.
// (The tie rule b′ gave max(x, −x)'s force +2 and the run chattered, dopri5 at h ≈ 4e-10.)
TEST(SwitchEvents, MassAtRestAtAKinkStaysAtRest) {
  for (const char* energy : {"2*max(x, -x)", "-2*min(x, -x)", "2*if(x, x, -x)", "2*abs(x)",
                             "3*max(x, 0)", "-3*min(x, 0)", "if(x - 0, x^2, 0) + 2*max(x, -x)"}) {
    const Model m = parse_model(std::string(R"(
coordinates: [x]
kinetic_energy: 0.5*x_dot^2
potential_energy: )") + energy + R"(
initial: {q: {x: 0}}
simulate: {t_end: 1, integrator: dopri5}
)");
    Workspace ws(m.system);
    ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk);
    EXPECT_EQ(ws.qdd[0], 0.0) << energy;
    const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
    ASSERT_EQ(tr.stats.status, Status::kOk) << energy << ": " << tr.stats.message;
    EXPECT_NEAR(tr.q.back(), 0.0, 1e-15) << energy;
    EXPECT_NEAR(tr.qd.back(), 0.0, 1e-15) << energy;
    EXPECT_GE(tr.stats.steps, 1) << energy;
    EXPECT_LE(tr.stats.steps, 20) << energy;
    EXPECT_EQ(tr.stats.switch_events, 0) << energy;
  }
}

// A one-sided spring written with if: x'' = if(x, −k x, 0), k = 4 (ω = 2), from x = −1 at speed
// 1: it reaches the spring at t = 1, is thrown back after half a period π/ω, and leaves at
// speed −1: x(t) = sin(2 (t − 1))/2 on [1, 1 + π/2], then −(t − 1 − π/2).
TEST(SwitchEvents, OneSidedSpringWithIf) {
  const Model m = parse_model(R"yaml(
parameters: {k: 4}
coordinates: [x]
mass_matrix: [[1]]
forces: ["if(x, -k*x, 0)"]
initial: {q: {x: -1}, q_dot: {x: 1}}
simulate: {t_end: 3.5}
output: {every: 0, at: [1.5, 2]}
)yaml");
  const double pi = std::acos(-1.0), t_out = 1.0 + pi / 2;
  for (const MethodCase c : {MethodCase{Integrator::kRK4, 1e-3, 1e-6, 1e-9, 1e-9},
                             MethodCase{Integrator::kDopri5, 0.01, 1e-12, 1e-14, 1e-9},
                             MethodCase{Integrator::kRKF78, 0.01, 1e-12, 1e-14, 1e-9}}) {
    SimulationOptions o = m.options;
    o.integrator = c.method;
    o.step = c.step;
    o.rtol = c.rtol;
    o.atol = c.atol;
    const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_EQ(tr.stats.switch_events, 2) << to_string(c.method);
    const std::size_t i = sample_at(tr, 1.5), j = sample_at(tr, 2.0);
    EXPECT_NEAR(tr.q[i], 0.5 * std::sin(1.0), c.tolerance) << to_string(c.method);
    EXPECT_NEAR(tr.qd[i], std::cos(1.0), c.tolerance) << to_string(c.method);
    EXPECT_NEAR(tr.q[j], 0.5 * std::sin(2.0), c.tolerance) << to_string(c.method);
    EXPECT_NEAR(tr.q.back(), -(3.5 - t_out), c.tolerance) << to_string(c.method);
    EXPECT_NEAR(tr.qd.back(), -1.0, c.tolerance) << to_string(c.method);
  }
}

// A sliding mode: friction written by hand, x'' = −x − sign(x'), from x = 2.5 at rest slides to
// x = 1 + 1.5 cos t and stops at t = π, x = −0.5, where |x| < 1: there sign(x') turns the motion
// back from either side, a switch at every step. The run ends as chattering, at once, naming the
// switch — it does not crawl to max_steps.
TEST(SwitchEvents, ASlidingModeIsDeclaredChattering) {
  const Model m = parse_model(R"(
coordinates: [x]
mass_matrix: [[1]]
forces: [-x - sign(x_dot)]
initial: {q: {x: 2.5}}
simulate: {t_end: 5, integrator: dopri5, rtol: 1e-10, atol: 1e-12}
)");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kIntegratorFailure);
  EXPECT_NE(tr.stats.message.find("chattering"), std::string::npos) << tr.stats.message;
  EXPECT_NE(tr.stats.message.find("'x_dot'"), std::string::npos) << tr.stats.message;
  EXPECT_NE(tr.stats.message.find("switch_events"), std::string::npos) << tr.stats.message;
  EXPECT_NEAR(tr.stats.t_reached, std::acos(-1.0), 1e-6);
  EXPECT_GE(tr.stats.switch_events, 1);
  EXPECT_LE(tr.stats.switch_events, 1001);
  EXPECT_LE(tr.stats.steps, 100000);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

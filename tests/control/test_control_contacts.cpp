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

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

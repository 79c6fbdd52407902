// SPDX-License-Identifier: BSD-3-Clause
// Multibody model files (bodies:, joints:, forces:; src/modelfile/reader_multibody.cpp): the
// gallery's multibody examples against closed forms and against the same models built with the C++
// API (multibody/multibody.hpp), the report columns of a run, drives and applied forces written as
// expressions, and located errors.
//
// The reference numbers come from analysis (closed forms of the validation problems of issue 5,
// as in tests/multibody/test_multibody.cpp) or from the C++ builder, never from the file under
// test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "support/model_output.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/multibody/multibody.hpp"
#include "ukdyn/simulation/simulate.hpp"

#include "support/slider_crank.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using Eigen::Vector3d;
using mb::Frame;
using mb::kGround;

constexpr double kG = 9.81;
constexpr double kPi = std::numbers::pi;

Model load_example(const std::string& name, const std::map<std::string, double>& set = {}) {
  return load_model(std::string(UKDYN_EXAMPLES_DIR) + "/" + name + ".yaml", set);
}

// sample i of a field stored N × width
VectorXd at(const std::vector<double>& f, Index width, Index i) {
  return Trajectory::view(f, width).col(i);
}

Trajectory run(const Model& m) {
  Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  EXPECT_EQ(tr.stats.status, Status::kOk) << m.file << ": " << tr.stats.message;
  EXPECT_NEAR(tr.t.back(), m.options.t_end, 1e-12) << m.file;
  return tr;
}

// the column `name` of a model run
const std::vector<double>& column(const ModelRun& r, const std::string& name) {
  for (const auto& c : r.extra_columns) {
    if (c.name == name) return c.values;
  }
  static const std::vector<double> none;
  ADD_FAILURE() << "no column " << name;
  return none;
}

using testing::output;  // support/model_output.hpp

// the body z axis in the world at sample i (body b's quaternion starts at coordinate o + 3)
Vector3d axis_z(const mb::MultibodyModel& m, const Trajectory& tr, Index i) {
  return mb::body_pose(m, at(tr.q, tr.n, i), 0).R_WB * Vector3d::UnitZ();
}

// ---------------------------------------------------------------------------------------------
// (a) IFToMM A02 double four-bar; the same with a redundant, massless crank

// the A02 mechanism with the C++ builder: three cranks, two couplers
// (tests/multibody/test_multibody.cpp)
mb::MultibodyModel double_four_bar_api() {
  mb::Multibody b;
  b.set_gravity({0, -kG, 0});
  const Frame lo = Frame::planar(-0.5, 0), hi = Frame::planar(0.5, 0);
  mb::BodyId c[3];
  for (int k = 0; k < 3; ++k) {
    c[k] = b.add_planar_body("crank" + std::to_string(k), 1.0, 1.0 / 12, {double(k), 0.5, kPi / 2},
                             {0.5, 0.0, -1.0});
  }
  const mb::BodyId cp0 = b.add_planar_body("coupler0", 1.0, 1.0 / 12, {0.5, 1.0, 0.0}, {1, 0, 0});
  const mb::BodyId cp1 = b.add_planar_body("coupler1", 1.0, 1.0 / 12, {1.5, 1.0, 0.0}, {1, 0, 0});
  for (int k = 0; k < 3; ++k)
    b.add_joint(mb::revolute("pivot" + std::to_string(k), kGround, Frame::planar(k, 0), c[k], lo));
  b.add_joint(mb::revolute("tip0a", c[0], hi, cp0, lo));
  b.add_joint(mb::revolute("tip0b", c[1], hi, cp0, hi));
  b.add_joint(mb::revolute("tip1a", c[1], hi, cp1, lo));
  b.add_joint(mb::revolute("tip1b", c[2], hi, cp1, hi));
  return b.build();
}

TEST(ModelMultibody, DoubleFourBarIsTheCppModelAndMeetsTheIFToMMReference) {
  const Model m = load_example("double_four_bar_bodies");
  ASSERT_TRUE(m.multibody);
  const mb::MultibodyModel api = double_four_bar_api();
  // the same coordinates, initial state and equations
  EXPECT_EQ(m.system.coordinate_names(), api.system.coordinate_names());
  EXPECT_NEAR((m.q0 - api.q0).norm(), 0.0, 1e-15);
  EXPECT_NEAR((m.qd0 - api.qd0).norm(), 0.0, 1e-15);
  Workspace w1(m.system), w2(api.system);
  ASSERT_EQ(forward_dynamics(m.system, w1, m.q0, m.qd0, 0.0), Status::kOk);
  ASSERT_EQ(forward_dynamics(api.system, w2, api.q0, api.qd0, 0.0), Status::kOk);
  EXPECT_NEAR((w1.qdd - w2.qdd).norm(), 0.0, 1e-13);
  const CheckReport r = check_model(m);
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(r.constraint_rows, 14);
  EXPECT_EQ(r.rank, 14);
  EXPECT_EQ(r.degrees_of_freedom, 1);
  EXPECT_TRUE(r.redundant.empty());
}

TEST(ModelMultibody, RedundantCrankIsNamedByCheckAndLeavesTheMotionUnchanged) {
  const Model plain = load_example("double_four_bar_bodies");
  const Model m = load_example("double_four_bar_bodies_redundant");
  const CheckReport r = check_model(m);
  EXPECT_TRUE(r.ok());
  EXPECT_TRUE(r.initial_violations.empty());
  EXPECT_EQ(r.coordinates, 12);
  EXPECT_EQ(r.constraint_rows, 12);
  EXPECT_EQ(r.rank, 11);
  EXPECT_EQ(r.degrees_of_freedom, 1);
  ASSERT_EQ(r.redundant.size(), 1u);
  EXPECT_EQ(r.redundant[0], "tip1_y");
  // RK4 at h = 1e-3 over 10 s, as the IFToMM protocol: the left crank tip of both models
  const Trajectory ref = run(plain), tr = run(m);
  ASSERT_EQ(ref.samples(), tr.samples());
  const auto x0 = output(plain, ref, "tip_x"), y0 = output(plain, ref, "tip_y");
  const auto x1 = output(m, tr, "tip_x"), y1 = output(m, tr, "tip_y");
  double d = 0.0;
  for (std::size_t i = 0; i < x0.size(); ++i)
    d = std::max(d, std::hypot(x1[i] - x0[i], y1[i] - y0[i]));
  EXPECT_NEAR(d, 0.0, 1e-9);
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-10);
  EXPECT_NEAR(ref.stats.max_position_violation, 0.0, 1e-10);
  // IFToMM A02: the left crank tip at t = 10 s
  for (const auto& [x, y] : {std::pair{x0, y0}, std::pair{x1, y1}}) {
    EXPECT_NEAR(x.back(), 0.32845811, 1e-6);
    EXPECT_NEAR(y.back(), 0.94451854, 1e-6);
  }
}

// The same redundant crank with its coupler pin as one revolute joint (the C++ test's variants 1
// and 2): one of the pin's two rows is redundant, which check_model shows as the rank only. The
// outer cranks of the plain model carry the middle crank's mass (1.5 kg each: the same 3 theta''
// = 3.5 g sin theta), so the motion is the same.
std::string rigid_coupler_model(bool middle_crank) {
  const std::string cm = middle_crank ? "1" : "1.5";
  std::string s =
      "parameters: {g: 9.81}\n"
      "bodies:\n"
      "  - {name: coupler, type: planar, mass: 2, inertia: 2*4/12, position: [1, 1], "
      "velocity: [1, 0]}\n";
  std::string joints = "joints:\n";
  for (int k = 0; k < 3; ++k) {
    if (!middle_crank && k == 1) continue;
    const std::string n = std::to_string(k);
    s += "  - {name: crank" + n + ", type: planar, mass: " + cm + ", inertia: " + cm +
         "/12, position: [" + n +
         ", 0.5], angle: pi/2, velocity: [0.5, 0], angular_velocity: -1}\n";
    joints += "  - {name: pivot" + n + ", type: revolute, parent: ground, child: crank" + n +
              ", parent_point: [" + n + ", 0], child_point: [-0.5, 0]}\n";
    joints += "  - {name: tip" + n + ", type: revolute, parent: crank" + n +
              ", child: coupler, parent_point: [0.5, 0], child_point: [" + n + " - 1, 0]}\n";
  }
  return s + joints +
         "forces: [{type: gravity, g: [0, -g]}]\n"
         "simulate: {t_end: 1, integrator: rk4, step: 1e-3}\n"
         "output: {every: 0.05}\n";
}

TEST(ModelMultibody, RedundantCrankWithMassLeavesOneRowRedundantAndTheMotionUnchanged) {
  const Model plain = parse_model(rigid_coupler_model(false), "plain.yaml");
  const Model m = parse_model(rigid_coupler_model(true), "three_cranks.yaml");
  const CheckReport r0 = check_model(plain), r = check_model(m);
  EXPECT_EQ(r0.rank, 8);
  EXPECT_EQ(r0.degrees_of_freedom, 1);
  EXPECT_EQ(r.constraint_rows, 12);
  EXPECT_EQ(r.rank, 11);  // one row of the last pin adds nothing
  EXPECT_EQ(r.degrees_of_freedom, 1);
  EXPECT_TRUE(r.redundant.empty());  // but the pin's other row does
  const Trajectory ref = run(plain), tr = run(m);
  ASSERT_EQ(ref.samples(), tr.samples());
  double d = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    // the coupler's centre (coordinates 0, 1 in both)
    d = std::max(d, (at(tr.q, 12, i).head<3>() - at(ref.q, 9, i).head<3>()).norm());
  }
  EXPECT_NEAR(d, 0.0, 1e-9);
}

// ---------------------------------------------------------------------------------------------
// (b) heavy symmetric top

struct TopParameters {
  double m, l, Ic, I3, g, theta0, spin;
  double I1() const { return Ic + m * l * l; }
  // m g l = phid (I3 w3 − I1 phid cos theta), the slow root
  double steady_precession() const {
    const double ct = std::cos(theta0), L3 = I3 * spin;
    return (L3 - std::sqrt(L3 * L3 - 4 * I1() * ct * m * g * l)) / (2 * I1() * ct);
  }
};

TopParameters top_parameters(const Model& m) {
  const auto& p = m.parameters;
  return {p.at("m"), p.at("l"), p.at("Ic"), p.at("I3"), p.at("g"), p.at("theta0"), p.at("spin")};
}

TEST(ModelMultibody, HeavyTopPrecessesSteadilyAtTheClosedFormRate) {
  const TopParameters c = top_parameters(load_example("heavy_top"));
  const double phid = c.steady_precession();
  // the file carries the closed form's value
  EXPECT_NEAR(load_example("heavy_top").parameters.at("precession"), phid, 1e-12);
  const Model m = load_example("heavy_top", {{"precession", phid}});
  ASSERT_TRUE(m.multibody);
  const Trajectory tr = run(m);
  const auto tilt = output(m, tr, "tilt"), azimuth = output(m, tr, "azimuth");
  double worst = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    worst = std::max(worst, std::abs(tilt[std::size_t(i)] - c.theta0));
    // the output agrees with the pose the layer reports
    EXPECT_NEAR(std::acos(axis_z(*m.multibody, tr, i).z()), tilt[std::size_t(i)], 1e-12);
  }
  EXPECT_NEAR(worst, 0.0, 1e-7);
  EXPECT_NEAR(azimuth.back(), phid * m.options.t_end, 1e-7);
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-10);
}

TEST(ModelMultibody, HeavyTopReleasedWithoutPrecessionNutatesBetweenTheBoundsOfItsIntegrals) {
  Model m = load_example("heavy_top", {{"precession", 0.0}});
  const TopParameters c = top_parameters(m);
  m.options.t_end = 1.0;
  m.options.output_every = 1e-3;
  // turning points u = cos theta: u0 and the root of (I3 w3)² (u0 − u) = 2 I1 m g l (1 − u²)
  const double u0 = std::cos(c.theta0), L2 = std::pow(c.I3 * c.spin, 2),
               k = 2 * c.I1() * c.m * c.g * c.l;
  const double u1 = (L2 - std::sqrt(L2 * L2 - 4 * k * (L2 * u0 - k))) / (2 * k);
  const Trajectory tr = run(m);
  double umin = 1.0, umax = -1.0, dL = 0.0;
  const double Lz0 = mb::momentum(*m.multibody, m.q0, m.qd0).second.z();
  for (Index i = 0; i < tr.samples(); ++i) {
    const double u = axis_z(*m.multibody, tr, i).z();
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    dL = std::max(
        dL, std::abs(mb::momentum(*m.multibody, at(tr.q, 7, i), at(tr.qd, 7, i)).second.z() - Lz0));
  }
  EXPECT_NEAR(umax, u0, 1e-5);
  EXPECT_NEAR(umin, u1, 1e-5);
  EXPECT_NEAR(dL, 0.0, 1e-7);
  double dE = 0.0;
  for (double e : tr.energy) dE = std::max(dE, std::abs(e - tr.energy.front()));
  EXPECT_NEAR(dE, 0.0, 2e-8 * std::abs(tr.energy.front()));
}

// ---------------------------------------------------------------------------------------------
// (c) rolling disk in steady circular motion

TEST(ModelMultibody, RollingDiskInSteadyCircleKeepsItsLeanAndReturnsAfterOnePeriod) {
  const auto& p = load_example("rolling_disk_bodies").parameters;
  const double R = p.at("R"), lean = p.at("lean"), rho = p.at("rho"), g = p.at("g");
  // Omega² = 4 g sin(theta) / [cos(theta) (R sin(theta) + 6 rho)]
  const double Omega =
      std::sqrt(4 * g * std::sin(lean) / (std::cos(lean) * (R * std::sin(lean) + 6 * rho)));
  EXPECT_NEAR(p.at("Omega"), Omega, 1e-12);
  const Model m = load_example("rolling_disk_bodies", {{"Omega", Omega}});
  EXPECT_NEAR(m.options.t_end, 2 * kPi / Omega, 1e-12);
  EXPECT_TRUE(check_initial_conditions(m.system, m.q0, m.qd0, 0.0, 1e-13).empty());
  const Trajectory tr = run(m);
  const auto lean_out = output(m, tr, "lean");
  double worst = 0.0;
  for (double v : lean_out) worst = std::max(worst, std::abs(v - lean));
  EXPECT_NEAR(worst, 0.0, 1e-7);
  // back at the start after one period
  const VectorXd qT = at(tr.q, 7, tr.samples() - 1);
  EXPECT_NEAR((qT.head<3>() - Vector3d(rho, 0, R * std::cos(lean))).norm(), 0.0, 1e-6);
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-10);
  EXPECT_NEAR(tr.stats.max_velocity_violation, 0.0, 1e-10);
}

// ---------------------------------------------------------------------------------------------
// (d) slider-crank with a prescribed crank rotation

using test::SliderCrank;

TEST(ModelMultibody, SliderCrankPistonAndDrivingTorqueMatchTheClosedFormAndTheEnergyBalance) {
  const Model m = load_example("slider_crank");
  const auto& p = m.parameters;
  const SliderCrank c{p.at("r"),  p.at("l"), p.at("mc"), p.at("mr"),
                      p.at("ms"), p.at("g"), p.at("w"),  p.at("th0")};
  EXPECT_TRUE(m.project_initial);
  const ModelRun run = run_model(m);
  const Trajectory& tr = run.trajectory;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.samples(), 9);
  const Index slider_x = m.system.coordinate_index("slider.x");
  const auto& drive = column(run, "drive.pin");
  double worst_x = 0.0, worst_tau = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    worst_x = std::max(worst_x, std::abs(at(tr.q, 9, i)[slider_x] - c.at(t).x));
    // tau w = dE/dt, E by hand (central difference of the closed form)
    const double h = 1e-5;
    const double tau = (c.energy(t + h) - c.energy(t - h)) / (2 * h) / c.w;
    worst_tau = std::max(worst_tau, std::abs(drive[std::size_t(i)] - tau) / (1.0 + std::abs(tau)));
  }
  EXPECT_NEAR(worst_x, 0.0, 1e-8);
  EXPECT_NEAR(worst_tau, 0.0, 1e-6);
  double piston = 0.0;
  for (double v : output(m, tr, "piston_error")) piston = std::max(piston, std::abs(v));
  EXPECT_NEAR(piston, 0.0, 1e-8);
}

// ---------------------------------------------------------------------------------------------
// (e) closed chain of pendulums

TEST(ModelMultibody, ClosedChainOfPendulumsKeepsEnergyAndClosure) {
  const Model m = load_example("pendulum_loop");
  const CheckReport r = check_model(m);
  EXPECT_TRUE(r.ok());
  EXPECT_TRUE(r.initial_violations.empty());
  EXPECT_EQ(r.degrees_of_freedom, 4);
  const Trajectory tr = run(m);
  const double E0 = mb::total_energy(*m.multibody, m.q0, m.qd0, 0.0);
  EXPECT_NEAR(tr.energy.front(), E0, 1e-12 * std::abs(E0));
  double dE = 0.0, moved = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    dE = std::max(dE, std::abs(tr.energy[std::size_t(i)] - E0));
    moved = std::max(moved, (at(tr.q, 18, i) - m.q0).norm());
  }
  EXPECT_GT(moved, 0.1);
  EXPECT_NEAR(dE, 0.0, 1e-8 * std::abs(E0));
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-10);
  EXPECT_NEAR(tr.stats.max_velocity_violation, 0.0, 1e-10);
}

// ---------------------------------------------------------------------------------------------
// the columns of a run: poses, energies, joint reactions, friction, drive

TEST(ModelMultibody, RunColumnsHoldPosesEnergiesReactionsAndFriction) {
  // a rod of mass m and length L pinned at its end, released horizontally at rest, with viscous
  // pin friction c: at t = 0 the pin force is m a_G − m g = (0, m g / 4) (theta'' = 3g/(2L))
  const std::string text =
      "parameters: {m: 2, L: 1.5, g: 9.81, c: 0.3}\n"
      "bodies:\n"
      "  - {name: rod, type: planar, mass: m, inertia: m*L^2/12, position: [L/2, 0]}\n"
      "joints:\n"
      "  - {name: pin, type: revolute, parent: ground, child: rod, child_point: [-L/2, 0],\n"
      "     friction: {viscous: c}}\n"
      "forces: [{type: gravity, g: [0, -g]}]\n"
      "simulate: {t_end: 1}\n"
      "output: {every: 0.1}\n";
  const Model m = parse_model(text, "rod.yaml");
  const ModelRun run = run_model(m);
  ASSERT_EQ(run.trajectory.stats.status, Status::kOk);
  const Trajectory& tr = run.trajectory;
  const double mass = 2, L = 1.5;
  EXPECT_NEAR(column(run, "reaction.pin.fx")[0], 0.0, 1e-12);
  EXPECT_NEAR(column(run, "reaction.pin.fy")[0], mass * kG / 4, 1e-12);
  EXPECT_NEAR(column(run, "rod.kinetic_energy")[0], 0.0, 1e-15);
  // the pin's friction torque is −c theta'; the ideal torque about the pin vanishes
  const auto& friction = column(run, "reaction.pin.friction_tz");
  const auto& tz = column(run, "reaction.pin.tz");
  for (Index i = 0; i < tr.samples(); ++i) {
    const VectorXd q = at(tr.q, 3, i), qd = at(tr.qd, 3, i);
    EXPECT_NEAR(friction[std::size_t(i)], -0.3 * qd[2], 1e-12);
    EXPECT_NEAR(tz[std::size_t(i)], 0.0, 1e-10);
    // kinetic energy of a rod turning about its end: ½ (m L²/3) theta'²
    EXPECT_NEAR(column(run, "rod.kinetic_energy")[std::size_t(i)],
                0.5 * mass * L * L / 3 * qd[2] * qd[2], 1e-9);
    // the pose columns (rod.x, rod.y are the coordinate columns: not repeated)
    EXPECT_EQ(column(run, "rod.z")[std::size_t(i)], 0.0);
    EXPECT_NEAR(column(run, "rod.qw")[std::size_t(i)], std::cos(q[2] / 2), 1e-15);
  }
  for (const auto& col : run.extra_columns) EXPECT_TRUE(col.name != "rod.x" && col.name != "rod.y");
  // a planar joint reports fx, fy, tz only
  for (const auto& col : run.extra_columns) EXPECT_NE(col.name, "reaction.pin.fz");
}

TEST(ModelMultibody, SpatialReactionOfTheTopsTipIsItsCentresAccelerationMinusGravity) {
  // steady precession: the centre runs round a circle of radius l sin theta0 at phid, so at
  // t = 0 the tip pushes with m (−phid² l sin theta0, 0, g) and no torque (a ball joint)
  const Model probe = load_example("heavy_top");
  const TopParameters c = top_parameters(probe);
  const double phid = c.steady_precession();
  Model m = load_example("heavy_top", {{"precession", phid}});
  m.options.t_end = 0.1;
  const ModelRun run = run_model(m);
  ASSERT_EQ(run.trajectory.stats.status, Status::kOk);
  EXPECT_NEAR(column(run, "reaction.tip.fx")[0], -c.m * phid * phid * c.l * std::sin(c.theta0),
              1e-9);
  EXPECT_NEAR(column(run, "reaction.tip.fy")[0], 0.0, 1e-9);
  EXPECT_NEAR(column(run, "reaction.tip.fz")[0], c.m * c.g, 1e-9);
  for (const char* t : {"reaction.tip.tx", "reaction.tip.ty", "reaction.tip.tz"}) {
    for (double v : column(run, t)) EXPECT_NEAR(v, 0.0, 1e-9) << t;
  }
  // the body's kinetic energy column is the trajectory's (one body)
  const auto& T = column(run, "top.kinetic_energy");
  for (Index i = 0; i < run.trajectory.samples(); ++i)
    EXPECT_NEAR(T[std::size_t(i)], run.trajectory.kinetic_energy[std::size_t(i)],
                1e-10 * T[std::size_t(i)]);
}

// ---------------------------------------------------------------------------------------------
// drives and applied forces as expressions; the initial state

TEST(ModelMultibody, DriveExpressionIsDifferentiatedTwiceAndItsTorqueIsTheInertiaTimesFpp) {
  // a rod turned about its end in a horizontal plane at f(t) = 0.5 t² + 0.2: f'' = 1, so the
  // driving torque is (m L²/3) f'' = m L² / 3 at every time
  const std::string text =
      "parameters: {m: 3, L: 0.8}\n"
      "bodies:\n"
      "  - {name: rod, type: planar, mass: m, inertia: m*L^2/12,\n"
      "     position: [L/2*cos(0.2), L/2*sin(0.2)], angle: 0.2}\n"
      "joints:\n"
      "  - {name: pin, type: revolute, parent: ground, child: rod, child_point: [-L/2, 0],\n"
      "     drive: 0.5*t^2 + 0.2}\n"
      "simulate: {t_end: 1}\n"
      "output: {every: 0.25}\n";
  const Model m = parse_model(text, "driven.yaml");
  const ModelRun run = run_model(m);
  ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
  const auto& tau = column(run, "drive.pin");
  const Trajectory& tr = run.trajectory;
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    EXPECT_NEAR(tau[std::size_t(i)], 3 * 0.8 * 0.8 / 3, 1e-9);
    EXPECT_NEAR(at(tr.q, 3, i)[2], 0.5 * t * t + 0.2, 1e-9);
  }
}

TEST(ModelMultibody, AppliedForceExpressionOfTimeAndVelocityDrivesASlider) {
  // a block on a prismatic joint along x pushed by F = F0 sin(t) − c x': with c = 0 the closed
  // form is x = (F0/m)(t − sin t); the applied torque on a planar body is a scalar
  const std::string text =
      "parameters: {m: 2, F0: 3, c: 0}\n"
      "bodies:\n"
      "  - {name: block, type: planar, mass: m, inertia: 0.1}\n"
      "joints:\n"
      "  - {name: slide, type: prismatic, parent: ground, child: block}\n"
      "forces:\n"
      "  - {name: push, type: applied, body: block, point: [0, 0.1],\n"
      "     force: [F0*sin(t) - c*block_x_dot, 0], torque: 0}\n"
      "simulate: {t_end: 2, rtol: 1e-10, atol: 1e-12}\n"
      "output: {every: 0.5}\n";
  const Model m = parse_model(text, "push.yaml");
  const Trajectory tr = run(m);
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    EXPECT_NEAR(at(tr.q, 3, i)[0], 1.5 * (t - std::sin(t)), 1e-8);
    EXPECT_NEAR(at(tr.q, 3, i)[2], 0.0, 1e-12);  // the prismatic joint takes the couple
  }
  // with damping the velocity-dependent term acts (x' smaller than without)
  const Model damped = parse_model(text, "push.yaml", {{"c", 1.0}});
  const Trajectory td = run(damped);
  EXPECT_LT(at(td.qd, 3, td.samples() - 1)[0], at(tr.qd, 3, tr.samples() - 1)[0] - 0.1);
}

TEST(ModelMultibody, InitialSectionOverridesABodysCoordinateByNameAndProjects) {
  // the rod's angle from initial: q: (its centre then projected onto the pin)
  const std::string text =
      "bodies:\n"
      "  - {name: rod, type: planar, mass: 1, inertia: 1/12, position: [0.5, 0]}\n"
      "joints:\n"
      "  - {name: pin, type: revolute, parent: ground, child: rod, child_point: [-0.5, 0]}\n"
      "initial: {q: {rod_theta: 0.1}, project: true}\n";
  const Model m = parse_model(text, "rod.yaml");
  EXPECT_EQ(m.q0[2], 0.1);
  EXPECT_EQ(m.q0[0], 0.5);  // from bodies:
  EXPECT_TRUE(m.project_initial);
  EXPECT_EQ(m.system.coordinate_names()[2], "rod.theta");
}

// ---------------------------------------------------------------------------------------------
// errors: file:line:column at the offending node, with a hint

// 1-based line and column of the first occurrence of `token` in text
std::pair<int, int> where(const std::string& text, const std::string& token) {
  const std::size_t k = text.find(token);
  EXPECT_NE(k, std::string::npos) << token;
  const int line = 1 + int(std::count(text.begin(), text.begin() + long(k), '\n'));
  const std::size_t start = text.rfind('\n', k);
  const int column = int(k - (start == std::string::npos ? 0 : start + 1)) + 1;
  return {line, column};
}

struct BadCase {
  const char* what;
  std::string text;
  std::string token;    // where the error must point (its first occurrence)
  std::string message;  // part of the message
};

const std::string kRod =
    "bodies:\n"
    "  - {name: rod, type: planar, mass: 1, inertia: 0.1, position: [0.5, 0]}\n";

TEST(ModelMultibody, ErrorsNameFileLineAndColumnWithAHint) {
  const std::vector<BadCase> cases = {
      {"unknown body in a joint",
       kRod + "joints:\n  - {name: pin, type: revolute, parent: ground, child: rdo}\n", "rdo",
       "joint 'pin' child: unknown body 'rdo'"},
      {"unknown joint type",
       kRod + "joints:\n  - {name: pin, type: hinge, parent: ground, child: rod}\n", "hinge",
       "unknown joint type 'hinge'"},
      {"missing mass", "bodies:\n  - {name: rod, type: planar, inertia: 0.1}\n", "{name: rod",
       "body 'rod' needs 'mass'"},
      {"non-positive inertia", "bodies:\n  - {name: rod, type: planar, mass: 1, inertia: -0.1}\n",
       "-0.1", "inertia (about the centre of mass) must be > 0"},
      {"rigid inertia", "bodies:\n  - {name: b, type: rigid, mass: 1, inertia: [1, 1, 3]}\n",
       "[1, 1, 3]", "triangle inequality"},
      {"joint to itself",
       kRod + "joints:\n  - {name: pin, type: revolute, parent: rod, child: rod}\n", "rod}",
       "joint 'pin' joins body 'rod' to itself"},
      {"gear referring to itself",
       kRod + "joints:\n  - {name: pin, type: revolute, parent: ground, child: rod}\n"
              "  - {name: g, type: gear, a: g, b: pin, ratio: 2}\n",
       "g, b: pin", "joint 'g' refers to itself"},
      {"unknown key in a body",
       "bodies:\n  - {name: rod, type: planar, mass: 1, inertia: 0.1, colour: red}\n", "colour",
       "unknown key 'colour' in planar body 'rod'"},
      {"unknown body type", "bodies:\n  - {name: rod, type: rigidbody, mass: 1}\n", "rigidbody",
       "unknown type 'rigidbody'"},
      {"body declared twice", kRod + "  - {name: rod, type: planar, mass: 1, inertia: 0.1}\n",
       "rod, type: planar, mass: 1, inertia: 0.1}\n", "body 'rod' is declared twice"},
      {"ground as a body", "bodies:\n  - {name: ground, type: particle, mass: 1}\n", "ground",
       "'ground' is the world"},
      {"coordinates beside bodies", "coordinates: [x]\n" + kRod, "coordinates",
       "'coordinates' does not go with 'bodies:'"},
      {"3-vector on a planar joint",
       kRod + "joints:\n  - {name: pin, type: revolute, parent: ground, child: rod, "
              "child_point: [-0.5, 0, 0]}\n",
       "[-0.5, 0, 0]", "child_point must be a list of 2 numbers"},
      {"spatial joint between planar bodies",
       kRod + "joints:\n  - {name: s, type: spherical, parent: ground, child: rod}\n", "spherical",
       "a spherical joint is spatial"},
      {"planar and rigid bodies mixed",
       kRod + "  - {name: b, type: rigid, mass: 1, inertia: [1, 1, 1]}\n", "rigid",
       "body 'b' is rigid but 'rod' is planar"},
      {"drive depending on a coordinate",
       kRod + "joints:\n  - {name: pin, type: revolute, parent: ground, child: rod, "
              "child_point: [-0.5, 0], drive: rod_x*t}\n",
       "rod_x*t", "a drive is a function of time, but depends on 'rod_x'"},
      {"unknown name in a drive",
       kRod + "joints:\n  - {name: pin, type: revolute, parent: ground, child: rod, "
              "drive: omga*t}\n",
       "omga", "unknown name 'omga'"},
      {"friction on a distance joint",
       kRod + "joints:\n  - {name: d, type: distance, parent: ground, child: rod, length: 1, "
              "friction: {mu: 0.1}}\n",
       "friction", "unknown key 'friction' in distance joint 'd'"},
      {"unknown force type", kRod + "forces:\n  - {type: magnet}\n", "magnet",
       "unknown force type 'magnet'"},
      {"gravity twice",
       kRod + "forces:\n  - {type: gravity, g: [0, -1]}\n  - {g: [0, -2], type: gravity}\n",
       "gravity}", "gravity is given twice"},
      {"forces as a list of expressions", kRod + "forces: [0, 0, 0]\n", "0, 0, 0",
       "a force element must be a mapping"},
      {"particle on a revolute joint",
       "bodies:\n  - {name: p, type: particle, mass: 1, position: [1, 0, 0]}\n"
       "joints:\n  - {name: pin, type: revolute, parent: ground, child: p}\n",
       "revolute", "a particle has no orientation"},
      {"rolling disk on a planar body",
       kRod + "joints:\n  - {name: roll, type: rolling_disk, body: rod, radius: 0.3}\n",
       "rod, radius", "a rolling disk is a rigid body"},
      {"parameter clash", "parameters: {rod_x: 1}\n" + kRod, "rod, type",
       "its coordinate 'rod_x' is also a parameter"},
      {"zero quaternion",
       "bodies:\n  - {name: b, type: rigid, mass: 1, inertia: 1, orientation: {quaternion: [0, "
       "0, 0, 0]}}\n",
       "[0, 0, 0, 0]", "the quaternion is zero"},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.what);
    try {
      parse_model(c.text, "bad.yaml");
      ADD_FAILURE() << "no error for: " << c.text;
    } catch (const ModelError& e) {
      EXPECT_EQ(e.file(), "bad.yaml");
      EXPECT_NE(e.message().find(c.message), std::string::npos) << e.what();
      const auto [line, column] = where(c.text, c.token);
      EXPECT_EQ(e.line(), line) << e.what();
      EXPECT_EQ(e.column(), column) << e.what();
    }
  }
}

TEST(ModelMultibody, GearBetweenARevoluteAndAPrismaticJointIsRefusedAtItsReference) {
  const std::string text = kRod +
                           "  - {name: arm, type: planar, mass: 1, inertia: 0.1}\n"
                           "joints:\n"
                           "  - {name: pin, type: revolute, parent: ground, child: rod}\n"
                           "  - {name: rail, type: prismatic, parent: ground, child: arm}\n"
                           "  - {name: g, type: gear, a: pin, b: rail, ratio: 2}\n";
  try {
    parse_model(text, "bad.yaml");
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(e.message().find("'rail' is a prismatic joint, not revolute"), std::string::npos)
        << e.what();
    EXPECT_EQ(e.line(), where(text, "b: rail").first);
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// Validation problems of the multibody layer (issue 5) against closed forms and published values:
// the IFToMM double four-bar with and without a redundant crank, the heavy top's steady
// precession and nutation, the rolling disk's circular motion, the slider-crank's piston and
// driving torque, and a closed chain of pendulums. (Joints, rigid bodies, forces and reports:
// test_multibody.cpp.)
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/multibody/multibody.hpp"
#include "ukdyn/simulation/simulate.hpp"

#include "support/slider_crank.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using Eigen::Quaterniond;
using Eigen::Vector3d;
using mb::BodyId;
using mb::Frame;
using mb::kGround;
using mb::Multibody;
using mb::MultibodyModel;

constexpr double kG = 9.81;
constexpr double kPi = std::numbers::pi;

Quaterniond about(double angle, const Vector3d& axis) {
  return Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
}

// column i of a trajectory field stored N × width
VectorXd sample(const std::vector<double>& f, Index width, Index i) {
  return Trajectory::view(f, width).col(i);
}

// ---------------------------------------------------------------------------------------------
// IFToMM A02 double four-bar with planar bodies and revolute joints; variants with a rigid
// coupler on two cranks, and the same with a redundant third crank

// crank k (pivot (k, 0)) and couplers as planar rods of length 1 along their body x axis
MultibodyModel double_four_bar(int variant) {
  Multibody b;
  b.set_gravity({0, -kG, 0});
  const double pi2 = kPi / 2;
  const auto crank = [&](int k, double mass) {
    return b.add_planar_body("crank" + std::to_string(k), mass, mass / 12.0, {double(k), 0.5, pi2},
                             {0.5, 0.0, -1.0});
  };
  const Frame lo = Frame::planar(-0.5, 0), hi = Frame::planar(0.5, 0);
  if (variant == 0) {  // three cranks, two couplers (as the gallery's natural-coordinate model)
    BodyId c[3];
    for (int k = 0; k < 3; ++k) {
      c[k] = crank(k, 1.0);
      b.add_joint(
          mb::revolute("pivot" + std::to_string(k), kGround, Frame::planar(k, 0), c[k], lo));
    }
    for (int k = 0; k < 2; ++k) {
      const BodyId cp = b.add_planar_body("coupler" + std::to_string(k), 1.0, 1.0 / 12,
                                          {k + 0.5, 1.0, 0.0}, {1.0, 0.0, 0.0});
      b.add_joint(mb::revolute("tip" + std::to_string(k) + "a", c[k], hi, cp, lo));
      b.add_joint(mb::revolute("tip" + std::to_string(k) + "b", c[k + 1], hi, cp, hi));
    }
    return b.build();
  }
  // one rigid 2 m coupler of 2 kg on the outer cranks; with variant 1 the outer cranks carry
  // the middle crank's mass (1.5 kg each: the same 3 theta'' = 3.5 g sin theta), with variant 2
  // the middle crank (1 kg each) is back and its coupler pin is redundant
  const double mass = variant == 1 ? 1.5 : 1.0;
  const BodyId cp = b.add_planar_body("coupler", 2.0, 2.0 * 4 / 12, {1.0, 1.0, 0.0}, {1.0, 0, 0});
  for (int k = 0; k < 3; ++k) {
    if (variant == 1 && k == 1) continue;
    const BodyId c = crank(k, mass);
    b.add_joint(mb::revolute("pivot" + std::to_string(k), kGround, Frame::planar(k, 0), c, lo));
    b.add_joint(mb::revolute("tip" + std::to_string(k), c, hi, cp, Frame::planar(k - 1.0, 0)));
  }
  return b.build();
}

// RK4 at h = 1e-3, the IFToMM protocol: the mechanism passes singular poses (every link along
// the x axis, twice per turn) where the constraints lose rank and admit other branches; an
// adaptive method whose error control is tighter than the roundoff there shrinks its steps onto
// the singular pose and may leave the parallelogram branch (simulation/simulate.hpp, rtol), as
// dopri5 does on these 15-coordinate models at rtol 1e-9 and 1e-10. Measured: all three variants
// land on (0.32845811, 0.94451854) to 1e-8 and agree with each other to 1e-12.
TEST(MultibodyValidation, DoubleFourBarMatchesIFToMMWithAndWithoutARedundantCrank) {
  const int rows[] = {14, 8, 12}, ranks[] = {14, 8, 11};
  std::vector<std::vector<Vector3d>> tips(3);
  for (int variant : {0, 1, 2}) {
    SCOPED_TRACE(variant);
    const MultibodyModel m = double_four_bar(variant);
    ASSERT_EQ(m.system.constraint_rows(), rows[variant]);
    ASSERT_TRUE(check_initial_conditions(m.system, m.q0, m.qd0, 0.0, 1e-14).empty());
    Workspace ws(m.system);
    ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk);
    EXPECT_EQ(ws.rank, ranks[variant]);  // variant 2: one redundant row, all the time
    SimulationOptions o;
    o.t_end = 10.0;
    o.output_every = 0.5;
    o.integrator = Integrator::kRK4;
    o.step = 1e-3;
    const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    for (Index i = 0; i < tr.samples(); ++i) {
      tips[std::size_t(variant)].push_back(mb::world_point(
          m, sample(tr.q, m.system.coordinate_count(), i), m.body("crank0"), {0.5, 0, 0}));
    }
    const Vector3d tip = tips[std::size_t(variant)].back();
    EXPECT_NEAR(tip.x(), 0.32845811, 1e-6);
    EXPECT_NEAR(tip.y(), 0.94451854, 1e-6);
    EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-10);
  }
  // identical motion, sample by sample
  for (std::size_t i = 0; i < tips[0].size(); ++i) {
    EXPECT_NEAR((tips[1][i] - tips[0][i]).norm(), 0.0, 1e-9);
    EXPECT_NEAR((tips[2][i] - tips[0][i]).norm(), 0.0, 1e-9);
  }
}

// ---------------------------------------------------------------------------------------------
// heavy symmetric top on a spherical joint at its tip

struct Top {
  double m = 1.0, l = 0.5, Ic = 0.05, I3 = 0.08, spin = 30.0, theta0 = 0.5;
  double I1() const { return Ic + m * l * l; }
};

// the top tilted by theta0 about y, spinning at `spin` about its axis, precessing at phid
MultibodyModel top_model(const Top& c, double phid) {
  Multibody b;
  const Vector3d a(std::sin(c.theta0), 0, std::cos(c.theta0));
  const Vector3d w0 = phid * Vector3d::UnitZ() + (c.spin - phid * std::cos(c.theta0)) * a;
  const Vector3d r0 = c.l * a;
  const BodyId B = b.add_rigid_body("top", c.m, {c.Ic, c.Ic, c.I3}, r0,
                                    about(c.theta0, Vector3d::UnitY()), w0.cross(r0), w0);
  b.add_joint(mb::spherical("tip", kGround, {0, 0, 0}, B, {0, 0, -c.l}));
  b.set_gravity({0, 0, -kG});
  return b.build();
}

TEST(MultibodyValidation, HeavyTopPrecessesSteadilyAtTheClosedFormRate) {
  const Top c;
  // m g l = phid (I3 w3 − I1 phid cos theta), the slow root
  const double ct = std::cos(c.theta0), L3 = c.I3 * c.spin;
  const double phid =
      (L3 - std::sqrt(L3 * L3 - 4 * c.I1() * ct * c.m * kG * c.l)) / (2 * c.I1() * ct);
  const MultibodyModel m = top_model(c, phid);
  SimulationOptions o;
  o.t_end = 0.8;
  o.output_every = 0.01;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  double worst_tilt = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const Vector3d a = mb::body_pose(m, sample(tr.q, 7, i), 0).R_WB * Vector3d::UnitZ();
    worst_tilt = std::max(worst_tilt, std::abs(std::acos(a.z()) - c.theta0));
  }
  const Vector3d a =
      mb::body_pose(m, sample(tr.q, 7, tr.samples() - 1), 0).R_WB * Vector3d::UnitZ();
  EXPECT_NEAR(worst_tilt, 0.0, 1e-7);
  EXPECT_NEAR(std::atan2(a.y(), a.x()), phid * 0.8, 1e-7);
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-10);
}

TEST(MultibodyValidation, HeavyTopNutatesBetweenTheBoundsOfItsIntegrals) {
  const Top c;
  const MultibodyModel m = top_model(c, 0.0);  // released without precession
  // turning points u = cos theta: u0 and the root of (I3 w3)² (u0 − u) = 2 I1 m g l (1 − u²)
  const double u0 = std::cos(c.theta0), L2 = std::pow(c.I3 * c.spin, 2),
               k = 2 * c.I1() * c.m * kG * c.l;
  const double u1 = (L2 - std::sqrt(L2 * L2 - 4 * k * (L2 * u0 - k))) / (2 * k);
  SimulationOptions o;
  o.t_end = 1.0;
  o.output_every = 1e-3;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  double umin = 1.0, umax = -1.0, dL = 0.0, dE = 0.0;
  const auto [P0, L0] = mb::momentum(m, m.q0, m.qd0);
  const double E0 = mb::total_energy(m, m.q0, m.qd0, 0.0);
  for (Index i = 0; i < tr.samples(); ++i) {
    const VectorXd q = sample(tr.q, 7, i), qd = sample(tr.qd, 7, i);
    const double u = (mb::body_pose(m, q, 0).R_WB * Vector3d::UnitZ()).z();
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    dL = std::max(dL, std::abs(mb::momentum(m, q, qd).second.z() - L0.z()));
    dE = std::max(dE, std::abs(mb::total_energy(m, q, qd, tr.t[std::size_t(i)]) - E0));
  }
  EXPECT_NEAR(umax, u0, 1e-5);
  EXPECT_NEAR(umin, u1, 1e-5);
  EXPECT_NEAR(dL, 0.0, 1e-7);  // L_z about the fixed point: gravity's moment is horizontal
  EXPECT_NEAR(dE, 0.0, 2e-8 * E0);
}

// ---------------------------------------------------------------------------------------------
// uniform thin disk rolling in a steady circle

TEST(MultibodyValidation, RollingDiskInSteadyCircularMotionReturnsAfterOnePeriod) {
  // lean theta from the vertical (towards the circle's centre), centre circle of radius rho:
  // Omega² = 4 g sin(theta) / [cos(theta) (R sin(theta) + 6 rho)]; rolling fixes the spin
  const double m = 1.0, R = 0.3, theta = 0.3, rho = 1.0;
  const double Omega =
      std::sqrt(4 * kG * std::sin(theta) / (std::cos(theta) * (R * std::sin(theta) + 6 * rho)));
  const Vector3d a(std::cos(theta), 0, std::sin(theta));  // the disk's axis
  const Vector3d w0 = Omega * Vector3d::UnitZ() - Omega * (rho / R + std::sin(theta)) * a;
  const Vector3d r0(rho, 0, R * std::cos(theta));
  Multibody b;
  const BodyId D =
      b.add_rigid_body("disk", m, {m * R * R / 4, m * R * R / 4, m * R * R / 2}, r0,
                       about(kPi / 2 - theta, Vector3d::UnitY()), {0, Omega * rho, 0}, w0);
  b.add_joint(mb::rolling_disk("roll", D, R));
  b.set_gravity({0, 0, -kG});
  const MultibodyModel mm = b.build();
  ASSERT_TRUE(check_initial_conditions(mm.system, mm.q0, mm.qd0, 0.0, 1e-13).empty());
  SimulationOptions o;
  o.t_end = 2 * kPi / Omega;
  o.output_every = o.t_end / 50;
  const Trajectory tr = simulate(mm.system, mm.q0, mm.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  double worst = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const Vector3d ai = mb::body_pose(mm, sample(tr.q, 7, i), 0).R_WB * Vector3d::UnitZ();
    worst = std::max(worst, std::abs(std::asin(ai.z()) - theta));
  }
  EXPECT_NEAR(worst, 0.0, 1e-7);
  const VectorXd qT = sample(tr.q, 7, tr.samples() - 1);
  EXPECT_NEAR((qT.head<3>() - r0).norm(), 0.0, 1e-6);
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-10);
  EXPECT_NEAR(tr.stats.max_velocity_violation, 0.0, 1e-10);
}

// ---------------------------------------------------------------------------------------------
// slider-crank with prescribed crank rotation

using test::SliderCrank;

MultibodyModel slider_crank(const SliderCrank& c) {
  const auto z = c.at(0.0);
  const double s = std::sin(z.th), co = std::cos(z.th);
  const Vector3d B(c.r * co, c.r * s, 0), Bd(-c.r * c.w * s, c.r * c.w * co, 0);
  Multibody b;
  b.set_gravity({0, -kG, 0});
  const BodyId crank = b.add_planar_body("crank", c.mc, c.Ic(), {B.x() / 2, B.y() / 2, z.th},
                                         {Bd.x() / 2, Bd.y() / 2, c.w});
  const BodyId rod = b.add_planar_body("rod", c.mr, c.Ir(), {(B.x() + z.x) / 2, B.y() / 2, z.phi},
                                       {(Bd.x() + z.xd) / 2, Bd.y() / 2, z.phid});
  const BodyId slider = b.add_planar_body("slider", c.ms, 0.01, {z.x, 0, 0}, {z.xd, 0, 0});
  mb::Joint pin =
      mb::revolute("pin", kGround, Frame::planar(0, 0), crank, Frame::planar(-c.r / 2, 0));
  pin.drive = [c](double t) { return Vector3d(c.th0 + c.w * t, c.w, 0.0); };
  b.add_joint(pin);
  b.add_joint(
      mb::revolute("crank_rod", crank, Frame::planar(c.r / 2, 0), rod, Frame::planar(-c.l / 2, 0)));
  b.add_joint(
      mb::revolute("rod_slider", rod, Frame::planar(c.l / 2, 0), slider, Frame::planar(0, 0)));
  b.add_joint(mb::prismatic("slide", kGround, Frame::planar(0, 0), slider, Frame::planar(0, 0)));
  return b.build();
}

TEST(MultibodyValidation, SliderCrankPistonAndDrivingTorqueMatchClosedForms) {
  const SliderCrank c;
  const MultibodyModel m = slider_crank(c);
  ASSERT_TRUE(check_initial_conditions(m.system, m.q0, m.qd0, 0.0, 1e-13).empty());
  SimulationOptions o;
  o.t_end = 1.0;
  o.output_every = 0.125;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const Index pin = m.joint("pin"), slider_x = m.system.coordinate_index("slider.x");
  Workspace ws(m.system);
  double worst_x = 0.0, worst_tau = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    const VectorXd q = sample(tr.q, 9, i), qd = sample(tr.qd, 9, i);
    worst_x = std::max(worst_x, std::abs(q[slider_x] - c.at(t).x));
    // the driving torque against the energy balance tau w = dE/dt (E closed form)
    ASSERT_EQ(forward_dynamics(m.system, ws, q, qd, t), Status::kOk);
    const double h = 1e-5;
    const double tau = (c.energy(t + h) - c.energy(t - h)) / (2 * h) / c.w;
    const double effort = mb::drive_effort(m, q, qd, t, ws.lambda, pin);
    worst_tau = std::max(worst_tau, std::abs(effort - tau) / (1.0 + std::abs(tau)));
  }
  EXPECT_NEAR(worst_x, 0.0, 1e-8);
  EXPECT_NEAR(worst_tau, 0.0, 1e-6);
}

// ---------------------------------------------------------------------------------------------
// chain of N pendulums whose free end is pinned back to the ground

TEST(MultibodyValidation, ClosedChainOfPendulumsKeepsEnergyAndClosure) {
  const double dir[] = {-60, -30, -10, 10, 30, 60};  // link directions (degrees)
  Multibody b;
  b.set_gravity({0, -kG, 0});
  Vector3d p(0, 0, 0);
  BodyId prev = kGround;
  for (int k = 0; k < 6; ++k) {
    const double th = dir[k] * kPi / 180;
    const Vector3d e(std::cos(th), std::sin(th), 0);
    const BodyId link = b.add_planar_body("link" + std::to_string(k), 1.0, 1.0 / 12,
                                          {p.x() + e.x() / 2, p.y() + e.y() / 2, th});
    b.add_joint(mb::revolute("pin" + std::to_string(k), prev,
                             prev == kGround ? Frame::planar(0, 0) : Frame::planar(0.5, 0), link,
                             Frame::planar(-0.5, 0)));
    p += e;
    prev = link;
  }
  b.add_joint(
      mb::revolute("closure", prev, Frame::planar(0.5, 0), kGround, Frame::planar(p.x(), p.y())));
  const MultibodyModel m = b.build();
  SimulationOptions o;
  o.t_end = 3.0;
  o.output_every = 0.05;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double E0 = mb::total_energy(m, m.q0, m.qd0, 0.0);
  double dE = 0.0, moved = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const VectorXd q = sample(tr.q, 18, i), qd = sample(tr.qd, 18, i);
    dE = std::max(dE, std::abs(mb::total_energy(m, q, qd, 0.0) - E0));
    moved = std::max(moved, (q - m.q0).norm());
  }
  EXPECT_GT(moved, 0.1);  // it does move
  EXPECT_NEAR(dE, 0.0, 1e-8 * std::abs(E0));
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-10);
  EXPECT_NEAR(tr.stats.max_velocity_violation, 0.0, 1e-10);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

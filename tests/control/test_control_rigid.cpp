// SPDX-License-Identifier: BSD-3-Clause
// A rigid (quaternion) body under control with every coordinate actuated (the Gauss law on M):
// its M is singular (the quaternion block 4 E_vᵀ J E_v; docs/singular-mass.md), and the law takes
// the model's completion M_A = M + A_pᵀ G A_p (control/laws.cpp), whose controlled motion is
// Gauss's (u17 03: "the nominal model failed: ok" above the floor, "the LCP of the closed
// contacts has no solution" on it). Against closed forms: a ball paced in free fall, on a
// frictionless floor, rolling on a rough one.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "support/contact_runs.hpp"
#include "ukdyn/control/control.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/ukdyn.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kM = 2.0, kG = 9.81, kR = 0.1, kA = 0.1, kW = 3.0;
constexpr auto* at = &testing::coordinate_at;

double x_d(double t) { return kA * (1.0 - std::cos(kW * t)); }
double x_d1(double t) { return kA * kW * std::sin(kW * t); }
double x_d2(double t) { return kA * kW * kW * std::cos(kW * t); }

// the ball (m = 2, I = 2/5 m r², r = 0.1) at height z0, its x required to follow
// A (1 − cos 3t), every coordinate actuated; `contact` the floor's lines (or none)
std::string paced_ball(double z0, const std::string& contact) {
  return "parameters: {m: 2, g: 9.81, r: 0.1, A: 0.1, w: 3}\nbodies:\n"
         "  - {name: ball, type: rigid, mass: m, inertia: [0.4*m*r^2, 0.4*m*r^2, 0.4*m*r^2],\n"
         "     position: [0, 0, " +
         std::to_string(z0) + "]}\nforces:\n  - {type: gravity, g: [0, 0, -g]}\n" + contact +
         R"(control:
  requirements:
    - {name: pace, holonomic: ball_x - A*(1 - cos(w*t)), dynamics: {omega: 10, zeta: 1}}
simulate: {t_end: 0.3, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0.05}
)";
}

ControlledTrajectory run(const std::string& text) {
  const Model m = parse_model(text);
  ControlledTrajectory r = simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
  EXPECT_EQ(r.plant.stats.status, Status::kOk) << r.plant.stats.message;
  EXPECT_EQ(r.control.not_met, 0) << r.control.not_met_message;
  return r;
}

// x = x_d and the control force m x_d'' along x alone (none on the quaternion: the M_A-least
// force has no part along the unit norm's row), over 7 samples
void expect_paced(const ControlledTrajectory& r, double Fx_extra) {
  const Trajectory& tr = r.plant;
  ASSERT_EQ(tr.samples(), 7);
  for (std::size_t i = 0; i < 7; ++i) {
    const double t = tr.t[i];
    EXPECT_NEAR(at(tr, tr.q, "ball.x", i), x_d(t), 1e-9) << "t = " << t;
    EXPECT_NEAR(at(tr, tr.qd, "ball.x", i), x_d1(t), 1e-9) << "t = " << t;
    EXPECT_NEAR(at(tr, r.Qc_control, "ball.x", i), kM * x_d2(t) + Fx_extra, 1e-8) << "t = " << t;
    EXPECT_NEAR(at(tr, r.Qc_control, "ball.y", i), 0.0, 1e-10) << "t = " << t;
    EXPECT_NEAR(at(tr, r.Qc_control, "ball.z", i), 0.0, 1e-10) << "t = " << t;
    EXPECT_NEAR(r.error[i], 0.0, 1e-9) << "t = " << t;
  }
}

TEST(ControlRigid, BallPacedInFreeFallGetsMTimesTheAccelerationAlongX) {
  // above the floor without contacts: x = x_d by F_x = m x_d'', z = z0 − g t² / 2 (it falls)
  const ControlledTrajectory r = run(paced_ball(1.0, ""));
  expect_paced(r, 0.0);
  const Trajectory& tr = r.plant;
  for (std::size_t i = 0; i < std::size_t(tr.samples()); ++i) {
    const double t = tr.t[i];
    EXPECT_NEAR(at(tr, tr.q, "ball.z", i), 1.0 - 0.5 * kG * t * t, 1e-9) << "t = " << t;
    for (int k = 0; k < 4; ++k) {
      const std::string u = "ball.u" + std::to_string(k);
      EXPECT_NEAR(at(tr, r.Qc_control, u, i), 0.0, 1e-10) << u << ", t = " << t;
      EXPECT_NEAR(at(tr, tr.q, u, i), k == 0 ? 1.0 : 0.0, 1e-12) << u << ", t = " << t;
    }
  }
}

TEST(ControlRigid, BallPacedOnAFrictionlessFloorSlidesWithTheFloorCarryingMG) {
  // touching the floor at t = 0 (the start's LCP with the control in it): it slides, the floor
  // carries m g, the control m x_d'' along x
  const ControlledTrajectory r =
      run(paced_ball(kR, "contacts:\n  - {name: floor, body: ball, shape: sphere, radius: r}\n"));
  expect_paced(r, 0.0);
  const Trajectory& tr = r.plant;
  for (std::size_t i = 0; i < std::size_t(tr.samples()); ++i) {
    EXPECT_NEAR(at(tr, tr.q, "ball.z", i), kR, 1e-12) << "t = " << tr.t[i];
    EXPECT_NEAR(testing::first_multiplier(tr, "floor", i), kM * kG, 1e-8) << "t = " << tr.t[i];
  }
}

TEST(ControlRigid, BallPacedOnARoughFloorRollsAsGaussPrincipleSays) {
  // stuck (mu = 0.5): rolling, x = x_d, ω_y = x_d' / r; Gauss's principle with the rolling,
  // the floor and the requirement as constraints determines q'', whatever completes M; the
  // control force and the floor's friction together give m x_d'' along x, and the floor m g
  const ControlledTrajectory r =
      run(paced_ball(kR,
                     "contacts:\n  - {name: floor, body: ball, shape: sphere, radius: r}\n"
                     "nonideal:\n  - {friction: coulomb, constraint: floor, mu: 0.5}\n"));
  const Trajectory& tr = r.plant;
  EXPECT_EQ(tr.stats.events, 0);
  EXPECT_EQ(tr.stats.stick_refusals, 0);
  ASSERT_EQ(tr.samples(), 7);
  for (std::size_t i = 0; i < 7; ++i) {
    const double t = tr.t[i];
    EXPECT_NEAR(at(tr, tr.q, "ball.x", i), x_d(t), 1e-9) << "t = " << t;
    EXPECT_NEAR(at(tr, tr.qd, "ball.x", i), x_d1(t), 1e-9) << "t = " << t;
    double u[4], d[4];
    for (int k = 0; k < 4; ++k) {
      u[k] = at(tr, tr.q, "ball.u" + std::to_string(k), i);
      d[k] = at(tr, tr.qd, "ball.u" + std::to_string(k), i);
    }
    const double omega_y = 2.0 * (u[0] * d[2] - d[0] * u[2] + u[3] * d[1] - u[1] * d[3]);
    EXPECT_NEAR(omega_y, x_d1(t) / kR, 1e-8) << "t = " << t;
    EXPECT_NEAR(at(tr, r.Qc_control, "ball.x", i) + at(tr, tr.Qc_ideal, "ball.x", i) +
                    at(tr, tr.Qc_nonideal, "ball.x", i),
                kM * x_d2(t), 1e-8)
        << "t = " << t;
    EXPECT_NEAR(testing::first_multiplier(tr, "floor", i), kM * kG, 1e-8) << "t = " << t;
  }
}

// ---- a box on a rough floor, pushed harder than static friction holds (#31 item 1) -----------

// a cube (m = 1, half side h = 0.1) on its four bottom corners (mu = mu_static), its x required
// to follow A (1 − cos 5t) (A = 0.1: m x_d''(0) + mu m g = 2.5 + mu m g > mu m g, no stick holds);
// `spatial`: a rigid body (quaternion, singular M completed by M_A), else the same box as a planar
// body (x, y, theta: a regular M) on its two bottom corners; `x_only`: actuated along x alone
std::string pushed_cube(bool spatial, double mu, bool x_only) {
  std::string s = "parameters: {m: 1, g: 9.81, h: 0.1, A: 0.1, w: 5, mu: " + std::to_string(mu) +
                  "}\nbodies:\n";
  if (spatial) {
    s += "  - {name: box, type: rigid, mass: m, inertia: [m*8*h^2/12, m*8*h^2/12, m*8*h^2/12],\n"
         "     position: [0, 0, h]}\nforces:\n  - {type: gravity, g: [0, 0, -g]}\ncontacts:\n";
    for (int k = 0; k < 4; ++k) {
      s += "  - {name: c" + std::to_string(k) + ", body: box, point: [" +
           (k % 2 != 0 ? "h" : "-h") + ", " + (k / 2 != 0 ? "h" : "-h") + ", -h]}\n";
    }
  } else {
    s += "  - {name: box, type: planar, mass: m, inertia: m*8*h^2/12, position: [0, h]}\n"
         "forces:\n  - {type: gravity, g: [0, -g]}\ncontacts:\n"
         "  - {name: c0, body: box, point: [-h, -h]}\n  - {name: c1, body: box, point: [h, -h]}\n";
  }
  s += "nonideal:\n";
  for (int k = 0; k < (spatial ? 4 : 2); ++k) {
    s += "  - {friction: coulomb, constraint: c" + std::to_string(k) + ", mu: mu}\n";
  }
  s += "control:\n  requirements:\n"
       "    - {name: pace, holonomic: box_x - A*(1 - cos(w*t)), dynamics: {omega: 10, zeta: 1}}\n";
  if (x_only) s += "  actuated: [box_x]\n";
  return s +
         "simulate: {t_end: 0.5, integrator: dopri5, rtol: 1e-10, atol: 1e-12}\n"
         "output: {every: 0.05}\n";
}

constexpr double kCubeA = 0.1, kCubeW = 5.0;

// sliding from t = 0 (11 samples): x = x_d, the corners' friction −mu m g along x, the control
// m x_d'' + mu m g along x alone, the floor m g, no tilt
void expect_cube_slides(const ControlledTrajectory& r, bool spatial, double mu) {
  const Trajectory& tr = r.plant;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(r.control.not_met, 0) << r.control.not_met_message;
  ASSERT_EQ(tr.samples(), 11);
  const int corners = spatial ? 4 : 2;
  for (std::size_t i = 0; i < 11; ++i) {
    const double t = tr.t[i];
    const double xd = kCubeA * (1.0 - std::cos(kCubeW * t));
    const double xd2 = kCubeA * kCubeW * kCubeW * std::cos(kCubeW * t);
    EXPECT_NEAR(at(tr, tr.q, "box.x", i), xd, 1e-9) << "t = " << t;
    EXPECT_NEAR(at(tr, tr.Qc_nonideal, "box.x", i), -mu * kG, 1e-9) << "t = " << t;
    EXPECT_NEAR(at(tr, r.Qc_control, "box.x", i), xd2 + mu * kG, 1e-7) << "t = " << t;
    EXPECT_NEAR(at(tr, r.Qc_control, spatial ? "box.z" : "box.y", i), 0.0, 1e-9) << "t = " << t;
    double N = 0.0;
    for (int k = 0; k < corners; ++k)
      N += testing::first_multiplier(tr, "c" + std::to_string(k), i);
    EXPECT_NEAR(N, kG, 1e-8) << "t = " << t;
    EXPECT_NEAR(spatial ? at(tr, tr.q, "box.u2", i) : at(tr, tr.q, "box.theta", i), 0.0, 1e-12)
        << "t = " << t;
  }
}

TEST(ControlRigid, CubePushedAlongXBeyondStaticFrictionSlidesWithTheClosedFormForce) {
  // actuated along x, mu = 0.6: no stick holds m x_d'' + mu m g (8.386 N > 5.886 N at t = 0), so
  // the four corners slip at t = 0 and slide: friction −mu m g = −5.886 N, the control
  // m x_d'' + mu m g, as the planar box (regular M) and the particle (test_control_slip.cpp);
  // 144 steps (the planar box 144)
  for (const bool spatial : {true, false}) {
    SCOPED_TRACE(spatial ? "rigid (quaternion)" : "planar");
    const Model m = parse_model(pushed_cube(spatial, 0.6, true));
    const ControlledTrajectory r =
        simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
    expect_cube_slides(r, spatial, 0.6);
    EXPECT_EQ(r.plant.stats.stiff_steps, 0);
    EXPECT_LE(r.plant.stats.steps, 300);
    ASSERT_FALSE(r.plant.stats.notes.empty());
    EXPECT_NE(r.plant.stats.notes.back().find(
                  "t = 0 s: the requirement row 'pace' needs the stuck contact"),
              std::string::npos)
        << r.plant.stats.notes.back();
  }
}

TEST(ControlRigid, CubeFullyActuatedSlidesBelowThreeFifthsAndTipsAboveAsThePlanarBox) {
  // every coordinate actuated, the Gauss law has a cheaper way than sliding: tip the cube about
  // its front edge with the front corners stuck. Gauss loads no held contact, so they carry the
  // uncontrolled reaction of a cube pivoting from rest about that edge: angular acceleration
  // m g h / I_edge = 3 g / (8 h), so H = 3 m g / 8 and N = 5 m g / 8, H / N = 3/5 exactly. Below
  // mu = 3/5 that stick cannot hold, and the cube slides as actuated along x alone (the closed
  // form above); above, it tips. The rigid body (singular M, completed) and the planar body
  // (regular M) give the same motion, to roundoff. (mu = 0.6 itself is the tie H = mu N, where
  // roundoff decides: the planar box slid at t = 2.4e-9 s, the rigid one tipped; neither is wrong)
  for (const bool spatial : {true, false}) {
    SCOPED_TRACE(spatial ? "rigid (quaternion)" : "planar");
    const Model m = parse_model(pushed_cube(spatial, 0.5, false));
    expect_cube_slides(simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options),
                       spatial, 0.5);
  }
  const Model ms = parse_model(pushed_cube(true, 0.7, false));
  const Model mp = parse_model(pushed_cube(false, 0.7, false));
  const ControlledTrajectory rs =
      simulate_controlled(*ms.controller, ms.system, ms.q0, ms.qd0, ms.options);
  const ControlledTrajectory rp =
      simulate_controlled(*mp.controller, mp.system, mp.q0, mp.qd0, mp.options);
  ASSERT_EQ(rs.plant.stats.status, Status::kOk) << rs.plant.stats.message;
  ASSERT_EQ(rp.plant.stats.status, Status::kOk) << rp.plant.stats.message;
  ASSERT_EQ(rs.plant.samples(), 11);
  ASSERT_EQ(rp.plant.samples(), 11);
  for (std::size_t i = 0; i < 11; ++i) {
    const double t = rs.plant.t[i];
    // the rotation about y, 2 atan2(u2, u0), is the planar body's −theta (its z axis is y)
    const double phi = 2.0 * std::atan2(at(rs.plant, rs.plant.q, "box.u2", i),
                                        at(rs.plant, rs.plant.q, "box.u0", i));
    EXPECT_NEAR(phi, -at(rp.plant, rp.plant.q, "box.theta", i), 1e-8) << "t = " << t;
    EXPECT_NEAR(at(rs.plant, rs.plant.q, "box.x", i), kCubeA * (1.0 - std::cos(kCubeW * t)), 1e-9)
        << "t = " << t;
    EXPECT_NEAR(at(rs.plant, rs.plant.q, "box.z", i), at(rp.plant, rp.plant.q, "box.y", i), 1e-9)
        << "t = " << t;
    EXPECT_NEAR(at(rs.plant, rs.Qc_control, "box.x", i), at(rp.plant, rp.Qc_control, "box.x", i),
                1e-6)
        << "t = " << t;
    // the front corners stuck: no sliding friction
    EXPECT_NEAR(at(rs.plant, rs.plant.Qc_nonideal, "box.x", i), 0.0, 1e-12) << "t = " << t;
  }
  // it has tipped by 1.3876 rad at t = 0.5 (both)
  EXPECT_NEAR(-at(rp.plant, rp.plant.q, "box.theta", 10), 1.3876, 1e-4);
}

// #31 item 2: M = diag(m, 0) with y fixed by a requirement alone. The requirement is met by a
// force, and the row y of M q'' = Q + F reads 0 = Q_y + F_y whatever y'' is: no force determines
// y'', so the controlled motion is not determined by the plant under its control (the Gauss
// function with M_A = M + A_rᵀ G A_r would pick one, but only by making the requirement a
// constraint of the plant, which a control force is not). A model file says so at load, naming
// the requirement and what to write; the C++ run stops at the control's first evaluation with the
// model's "motion not determined" naming y
std::string massless_y(bool hold_in_control) {
  return std::string(
             "parameters: {m: 2}\ncoordinates: [x, y]\nkinetic_energy: 0.5*m*x_dot^2\n"
             "potential_energy: 0\n") +
         (hold_in_control ? "" : "constraints:\n  - {name: hold, holonomic: y - x}\n") +
         "control:\n  requirements:\n"
         "    - {name: track, holonomic: x - sin(t), dynamics: {omega: 10, zeta: 1}}\n" +
         (hold_in_control ? "    - {name: hold, holonomic: y - x, dynamics: {omega: 10, zeta: 1}}\n"
                          : "") +
         "simulate: {t_end: 0.5, integrator: dopri5, rtol: 1e-11, atol: 1e-13}\n"
         "output: {every: 0.1}\n";
}

TEST(ControlSingularMass, ACoordinateThatOnlyARequirementFixesIsRefusedWithWhatToWrite) {
  // the model file: refused at load, the requirement named, with the way out
  const std::string got = testing::model_error_text(massless_y(true));
  EXPECT_NE(got.find("the accelerations of the coordinates 'y' are not determined"),
            std::string::npos)
      << got;
  EXPECT_NE(got.find("the control requirement 'hold' does not fix them: a requirement is met by "
                     "a force, and a force does not determine the acceleration of a coordinate "
                     "without inertia"),
            std::string::npos)
      << got;
  EXPECT_NE(got.find("write it under constraints:, else give the coordinate inertia"),
            std::string::npos)
      << got;
  // (a requirement on x alone is not named)
  EXPECT_EQ(got.find("'track'"), std::string::npos) << got;
  // written as the model's constraint (the way out), it runs: x = sin t − t exp(−10 t) = y
  const Model m = parse_model(massless_y(false));
  const ControlledTrajectory r =
      simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(r.plant.stats.status, Status::kOk) << r.plant.stats.message;
  ASSERT_EQ(r.plant.samples(), 6);
  for (std::size_t i = 0; i < 6; ++i) {
    const double t = r.plant.t[i], x = std::sin(t) - t * std::exp(-10.0 * t);
    EXPECT_NEAR(r.plant.q[2 * i], x, 1e-9) << "t = " << t;
    EXPECT_NEAR(r.plant.q[2 * i + 1], x, 1e-9) << "t = " << t;
  }
  // in C++: the run stops at t = 0 with the model's "motion not determined" naming y
  const System plant =
      SystemBuilder({"x", "y"})
          .mass_matrix((MatrixXd(2, 2) << 2.0, 0.0, 0.0, 0.0).finished())
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) { Q.setZero(); })
          .build();
  const Controller ctrl =
      ControllerBuilder(plant)
          .require(holonomic("track", 1, [](const auto& q, const auto&, auto& e) { e[0] = q[0]; }),
                   ErrorDynamics::second_order(10.0, 1.0))
          .require(
              holonomic("hold", 1, [](const auto& q, const auto&, auto& e) { e[0] = q[1] - q[0]; }),
              ErrorDynamics::second_order(10.0, 1.0))
          .build();
  SimulationOptions o;
  o.t_end = 0.5;
  const ControlledTrajectory c =
      simulate_controlled(ctrl, plant, Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.0, 1.0), o);
  EXPECT_NE(c.plant.stats.status, Status::kOk);
  EXPECT_NE(c.plant.stats.message.find("motion not determined"), std::string::npos)
      << c.plant.stats.message;
  EXPECT_NE(c.plant.stats.message.find("'y'"), std::string::npos) << c.plant.stats.message;
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

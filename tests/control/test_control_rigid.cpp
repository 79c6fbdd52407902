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

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

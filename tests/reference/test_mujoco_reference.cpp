// SPDX-License-Identifier: BSD-3-Clause
// MuJoCo as an independent reference (issue #15 item 3): the shared benchmark problem P1 (double
// pendulum of bench/data/README.md: two massless 1 m rods with a 1 kg point mass at each tip,
// inertia 1e-9 kg m² about the tips, pivot at the origin, gravity (0, −9.81), released at rest
// with both links along +x) simulated over 1 s by ukdyn's multibody layer (two planar bodies and
// two revolute joints, as bench/bench_multibody_problems.cpp builds P1: maximal coordinates,
// constraint forces by the Udwadia–Kalaba equation, projection drift control) and by MuJoCo
// (two hinge joints: minimal coordinates, no constraint at all, so no soft constraints), both with
// RK4 at h = 1e-4. Built only when MuJoCo (libmujoco-dev) is found.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include <mujoco/mujoco.h>

#include "ukdyn/multibody/multibody.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using Eigen::Vector3d;
namespace mb = ukdyn::mb;

constexpr double kT = 1.0;  // s

// the two link angles (rad, from world +x, counter-clockwise) at T
struct Angles {
  double phi1 = NAN, phi2 = NAN;
};

// --- MuJoCo -----------------------------------------------------------------------------------

// P1 as MJCF: each link a body with its frame at its proximal hinge, x along the link, a hinge
// about z and the point mass at the tip; no geoms (nothing collides), no damping or armature
std::string p1_mjcf(double h) {
  char step[32];
  std::snprintf(step, sizeof step, "%.17g", h);
  return std::string("<mujoco model=\"P1\">\n  <option integrator=\"RK4\" timestep=\"") + step +
         "\" gravity=\"0 -9.81 0\"/>\n"
         "  <worldbody>\n"
         "    <body name=\"L0\" pos=\"0 0 0\">\n"
         "      <joint name=\"J0\" type=\"hinge\" pos=\"0 0 0\" axis=\"0 0 1\"/>\n"
         "      <inertial pos=\"1 0 0\" mass=\"1\" diaginertia=\"1e-9 1e-9 1e-9\"/>\n"
         "      <body name=\"L1\" pos=\"1 0 0\">\n"
         "        <joint name=\"J1\" type=\"hinge\" pos=\"0 0 0\" axis=\"0 0 1\"/>\n"
         "        <inertial pos=\"1 0 0\" mass=\"1\" diaginertia=\"1e-9 1e-9 1e-9\"/>\n"
         "      </body>\n"
         "    </body>\n"
         "  </worldbody>\n"
         "</mujoco>\n";
}

// RK4 at step h from rest at qpos = 0 (both links along +x) over T; phi1 = q0, phi2 = q0 + q1
Angles mujoco_p1(double h) {
  // MuJoCo reads the model from a file (a temporary one: the virtual file system's API differs
  // between MuJoCo 2 and 3)
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() /
      ("ukdyn_test_mujoco_p1_" + std::to_string(::getpid()) + ".xml");
  std::ofstream(file) << p1_mjcf(h);
  char error[1000] = "";
  mjModel* m = mj_loadXML(file.string().c_str(), nullptr, error, int(sizeof error));
  mj_freeLastXML();
  std::filesystem::remove(file);
  if (m == nullptr) {
    ADD_FAILURE() << "MuJoCo did not load P1: " << error;
    return {};
  }
  EXPECT_EQ(m->nq, 2);
  EXPECT_EQ(m->neq, 0);
  mjData* d = mj_makeData(m);
  const long steps = std::lround(kT / h);
  for (long i = 0; i < steps; ++i) mj_step(m, d);
  EXPECT_NEAR(d->time, kT, 1e-9);
  const Angles a{d->qpos[0], d->qpos[0] + d->qpos[1]};
  mj_deleteData(d);
  mj_deleteModel(m);
  return a;
}

// --- ukdyn ------------------------------------------------------------------------------------

// P1 as bench_multibody_problems builds it: planar bodies (x, y, theta of the centre of mass, here
// the tip) with inertia 1e-9 and revolute joints at the hinges; RK4 at step h, projection drift
// control at tolerance 1e-12 (the default)
Angles ukdyn_p1(double h) {
  mb::Multibody b;
  b.set_gravity({0.0, -9.81, 0.0});
  const mb::BodyId l0 = b.add_planar_body("L0", 1.0, 1e-9, Vector3d(1.0, 0.0, 0.0));
  const mb::BodyId l1 = b.add_planar_body("L1", 1.0, 1e-9, Vector3d(2.0, 0.0, 0.0));
  b.add_joint(mb::revolute("J0", mb::kGround, mb::Frame::planar(0.0, 0.0), l0,
                           mb::Frame::planar(-1.0, 0.0)));
  b.add_joint(
      mb::revolute("J1", l0, mb::Frame::planar(0.0, 0.0), l1, mb::Frame::planar(-1.0, 0.0)));
  const mb::MultibodyModel m = b.build();
  SimulationOptions o;
  o.t_end = kT;
  o.integrator = Integrator::kRK4;
  o.step = h;
  o.output_every = 0.0;
  o.drift = DriftControl::kProjection;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_NEAR(tr.t.back(), kT, 1e-12);
  const Index n = tr.n, last = tr.samples() - 1;
  return {tr.q[std::size_t(last * n + m.bodies[std::size_t(l0)].offset + 2)],
          tr.q[std::size_t(last * n + m.bodies[std::size_t(l1)].offset + 2)]};
}

// Both integrate the same ODE with the same method and step, in different coordinates, so they
// differ by their truncation errors plus roundoff. RK4's global error at T is C h^4; C is measured
// below from MuJoCo at h = 1e-3 and 5e-4 (Richardson: e(h) = (phi(h) − phi(h/2)) · 16/15; C is
// about 24 rad/s^4 here, e(1e-3) ≈ 2.4e-11 rad), so at h = 1e-4 each error is about
// 24 · 1e-16 = 2.4e-15 rad. Roundoff: 10^4 steps of a few ulps of |phi| < 3 (ε = 2.2e-16), at
// most about 10^4 · 4 ε · 3 = 2.7e-11 rad if every step's rounding added up; ukdyn's drift
// projection holds the 1 m links to 1e-12 m, moving the angles by no more than about that per
// correction. 1e-10 rad covers all of these with room, and is still 10^10 times smaller than the
// angles travelled (about 2.2 and 2.6 rad in the second): the two engines' equations of motion
// agree, not just their order of magnitude.
constexpr double kStepRef = 1e-4;
constexpr double kTolerance = 1e-10;  // rad

TEST(MujocoReference, P1LinkAnglesAgreeAtOneSecond) {
  const Angles mj = mujoco_p1(kStepRef), uk = ukdyn_p1(kStepRef);
  // the pendulum has swung well below the horizontal (so the comparison is not trivial)
  EXPECT_LT(mj.phi1, -2.0);
  EXPECT_LT(mj.phi2, -2.4);
  EXPECT_LT(std::abs(uk.phi1 - mj.phi1), kTolerance) << uk.phi1 << " vs " << mj.phi1;
  EXPECT_LT(std::abs(uk.phi2 - mj.phi2), kTolerance) << uk.phi2 << " vs " << mj.phi2;
}

// the step-size argument behind kTolerance: MuJoCo's RK4 converges at 4th order on P1, with a
// truncation error at h = 1e-3 of 1e-12 to 1e-10 rad (so about 1e-16 to 1e-14 at h = 1e-4), and
// ukdyn's h = 1e-3 run lies within twice that error of MuJoCo's h = 1e-4 run
TEST(MujocoReference, P1TruncationErrorScalesAsH4) {
  const Angles a = mujoco_p1(1e-3), b = mujoco_p1(5e-4), ref = mujoco_p1(kStepRef);
  const double e1 = (a.phi1 - b.phi1) * 16.0 / 15.0;  // Richardson: the error at h = 1e-3
  EXPECT_GT(std::abs(e1), 1e-12);
  EXPECT_LT(std::abs(e1), 1e-10);
  // the h = 1e-3 run's error against the h = 1e-4 run (whose own error is 10^4 times smaller)
  // is the Richardson estimate, to within 20 %
  EXPECT_LT(std::abs((a.phi1 - ref.phi1) - e1), 0.2 * std::abs(e1));
  const Angles uk = ukdyn_p1(1e-3);
  EXPECT_LT(std::abs(uk.phi1 - ref.phi1), 2.0 * std::abs(e1) + kTolerance);
  EXPECT_LT(std::abs(uk.phi2 - ref.phi2), 2.0 * std::abs(e1) + kTolerance);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

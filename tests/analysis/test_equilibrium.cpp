// SPDX-License-Identifier: BSD-3-Clause
// Tests of find_equilibrium() (src/analysis/equilibrium.cpp): static equilibria of a closed
// loop, relative equilibria (a sleeping top, a disk in steady turning) and the error when none
// exists.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>

#include <Eigen/Core>

#include "analysis/models.hpp"
#include "ukdyn/analysis/linearize.hpp"
#include "ukdyn/modelfile/model.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

TEST(Equilibrium, FourBarHangsStraightDown) {
  // from a guess off the manifold: t1 = 0.4, t2 = 0.1, t3 = 0.3 → t1 = t3 = 0, t2 = 0
  const Model model = parse_model(test::kParallelogram);
  OperatingPoint guess{VectorXd::Zero(3), VectorXd::Zero(3), 0.0};
  guess.q << 0.4, 0.1, 0.3;
  const Equilibrium eq = find_equilibrium(model.system, guess);
  EXPECT_NEAR(eq.point.q(0), 0.0, 1e-10);
  EXPECT_NEAR(eq.point.q(1), 0.0, 1e-10);
  EXPECT_NEAR(eq.point.q(2), 0.0, 1e-10);
  EXPECT_NEAR(eq.residual, 0.0, 1e-10);
  EXPECT_GE(eq.iterations, 1);
}

TEST(Equilibrium, PendulumReleasedHorizontallyHangsAtTheEdgeOfItsFirstChart) {
  // Cartesian (x, y) on a rod of length L from (L, 0): the first chart's coordinate is y, and
  // the hanging state (0, −L) is where that chart is singular; the search changes charts
  const Model model = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/pendulum.yaml");
  const double L = model.parameters.at("L");
  OperatingPoint guess{model.q0, VectorXd::Zero(2), 0.0};
  guess.q << L * std::cos(0.3), -L * std::sin(0.3);
  const Equilibrium eq = find_equilibrium(model.system, guess);
  EXPECT_NEAR(eq.point.q(0), 0.0, 1e-10);
  EXPECT_NEAR(eq.point.q(1), -L, 1e-10);
  // exactly horizontal, the reduced acceleration −g (1 − y²/L²) is stationary in y: Newton has
  // no direction, and says so
  guess.q << L, 0;
  try {
    find_equilibrium(model.system, guess);
    ADD_FAILURE() << "no error";
  } catch (const EquilibriumError& e) {
    EXPECT_NE(std::string(e.what()).find("y'' = -9.81"), std::string::npos) << e.what();
  }
}

TEST(Equilibrium, TopSpinningUprightIsARelativeEquilibrium) {
  const Model model = parse_model(test::kCardanTop);
  OperatingPoint guess{VectorXd::Zero(3), VectorXd::Zero(3), 0.0};
  guess.q << 0.05, -0.03, 0.7;
  guess.qd(2) = 40;  // the spin, held
  EquilibriumOptions o;
  o.unknowns = {"a", "b"};
  const Equilibrium eq = find_equilibrium(model.system, guess, o);
  EXPECT_NEAR(eq.point.q(0), 0.0, 1e-10);
  EXPECT_NEAR(eq.point.q(1), 0.0, 1e-10);
  EXPECT_NEAR(eq.point.q(2), 0.7, 1e-15);
  EXPECT_NEAR(eq.point.qd(2), 40.0, 1e-15);
}

TEST(Equilibrium, RollingDiskSteadyTurningSpin) {
  // lean theta0 and heading rate Omega held; the spin rate phi' that makes theta'' = 0 is
  // phi' = w3 − Omega sin theta0, w3 = (R Ω² sin θ0 cos θ0/4 − g sin θ0) / ((3/2) R Ω cos θ0)
  const Model model = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/rolling_disk.yaml");
  const System& sys = model.system;
  const double R = 0.5, g = 9.81, th0 = 0.3, W = -2;
  OperatingPoint guess{VectorXd::Zero(5), VectorXd::Zero(5), 0.0};
  guess.q(sys.coordinate_index("theta")) = th0;
  guess.qd(sys.coordinate_index("psi")) = W;
  guess.qd(sys.coordinate_index("phi")) = 1.0;
  guess.qd(sys.coordinate_index("x")) = R * 1.0;  // on the manifold: x' = R phi' cos psi
  EquilibriumOptions o;
  o.unknowns = {"phi_dot"};
  const Equilibrium eq = find_equilibrium(sys, guess, o);
  const double w3 = (R * W * W * std::sin(th0) * std::cos(th0) / 4 - g * std::sin(th0)) /
                    (1.5 * R * W * std::cos(th0));
  const double phid = w3 - W * std::sin(th0);
  EXPECT_NEAR(eq.point.qd(sys.coordinate_index("phi")), phid, 1e-9 * std::abs(phid));
  EXPECT_NEAR(eq.point.qd(sys.coordinate_index("x")), R * phid, 1e-9 * std::abs(phid));
}

TEST(Equilibrium, NoneUnderAConstantPushIsAClearError) {
  // the cart pendulum pushed by F0 = 1 accelerates for every state: no equilibrium
  const Model model = parse_model(test::kCartPendulum, "<string>", {{"F0", 1.0}});
  OperatingPoint guess{VectorXd::Zero(2), VectorXd::Zero(2), 0.0};
  guess.q(1) = 0.1;
  EquilibriumOptions o;
  o.unknowns = {"x"};
  try {
    find_equilibrium(model.system, guess, o);
    ADD_FAILURE() << "no error";
  } catch (const EquilibriumError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no equilibrium found"), std::string::npos) << what;
    EXPECT_NE(what.find("at q = (x = "), std::string::npos) << what;
  }
  o.unknowns = {"y"};
  EXPECT_THROW(find_equilibrium(model.system, guess, o), std::invalid_argument);
}

// The stopping test is relative to the run's acceleration scale (the coordinates' scales at the
// rate² of the guess), not absolute in the model's units: a double pendulum (URDF-like, angles)
// in SI units and in mm, g and ms, identical after conversion, stops at the same iterate — to
// roundoff of 0 — rather than 1e-9 rad off in mm (u20 09: SI 1e-25, mm 4e-10 and 1.05e-9), and
// a four-bar's equilibrium in mm is as exact as in SI (it was 2.6e-7 rad off)
TEST(Equilibrium, TheSameEquilibriumInAnyUnits) {
  const std::string pendulum = R"(name: double pendulum
parameters: {m1: 1, m2: 0.5, l1: 0.5, l2: 0.4, g: 9.81}
coordinates: [q1, q2]
kinetic_energy: >-
  0.5*(m1 + m2)*l1^2*q1_dot^2 + 0.5*m2*l2^2*q2_dot^2 + m2*l1*l2*cos(q1 - q2)*q1_dot*q2_dot
potential_energy: -(m1 + m2)*g*l1*cos(q1) - m2*g*l2*cos(q2)
)";
  const std::map<std::string, double> mm{
      {"m1", 1000}, {"m2", 500}, {"l1", 500}, {"l2", 400}, {"g", 9.81e-3}};
  OperatingPoint guess{Eigen::Vector2d(0.5, 0.2), VectorXd::Zero(2), 0.0};
  const Equilibrium si = find_equilibrium(parse_model(pendulum, "dp").system, guess);
  const Equilibrium in_mm = find_equilibrium(parse_model(pendulum, "dp", mm).system, guess);
  EXPECT_EQ(si.iterations, in_mm.iterations);
  for (Index j = 0; j < 2; ++j) {
    EXPECT_NEAR(si.point.q(j), 0.0, 1e-12) << j;
    EXPECT_NEAR(in_mm.point.q(j), 0.0, 1e-12) << j;
    EXPECT_NEAR(in_mm.point.q(j), si.point.q(j), 1e-14) << j;
  }
  // the residual is in the model's units: 1e-6 of SI's per ms² (both at roundoff here)
  EXPECT_NEAR(si.residual, 0.0, 1e-10);
  EXPECT_NEAR(in_mm.residual, 0.0, 1e-16);

  // the four-bar (two loop rows) from a = 0.3 off the manifold
  const Model fb = parse_model(test::kParallelogram, "fb");
  const Model fb_mm =
      parse_model(test::kParallelogram, "fb",
                  {{"mc", 1000}, {"mk", 2000}, {"L", 500}, {"d", 1000}, {"g", 9.81e-3}});
  OperatingPoint from{Eigen::Vector3d(0.3, 0.0, 0.0), VectorXd::Zero(3), 0.0};
  const Equilibrium a = find_equilibrium(fb.system, from), b = find_equilibrium(fb_mm.system, from);
  for (Index j = 0; j < 3; ++j) {
    EXPECT_NEAR(a.point.q(j), 0.0, 1e-12) << j;
    EXPECT_NEAR(b.point.q(j), 0.0, 1e-12) << j;
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

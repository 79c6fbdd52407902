// SPDX-License-Identifier: BSD-3-Clause
// Projection onto the constraints (drift control) against closed forms.
#include <cmath>

#include <gtest/gtest.h>

#include <ukdyn/dynamics/projection.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/random_problem.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using testing::vec;

System circle(double L, const MatrixXd& M) {
  return SystemBuilder(2)
      .mass_matrix(M)
      .add(holonomic("rod", 1,
                     [L](const auto& q, const auto&, auto& phi) {
                       phi[0] = q[0] * q[0] + q[1] * q[1] - L * L;
                     }))
      .build();
}

TEST(Projection, MeasureViolationsGivesWhatTheProjectionsStartFrom) {
  // phi = x² + y² − L², phi' = 2 (x x' + y y'); the holonomic row takes part at both levels
  const double L = 1.5;
  const System sys = circle(L, MatrixXd::Identity(2, 2));
  Workspace ws(sys);
  const VectorXd q = vec({1.9, -0.4}), qd = vec({0.3, 0.7});
  const Violations v = measure_violations(sys, ws, q, qd, 0.0);
  EXPECT_TRUE(v.finite);
  EXPECT_NEAR(v.position, 1.9 * 1.9 + 0.4 * 0.4 - L * L, 1e-14);
  EXPECT_NEAR(v.velocity, std::abs(2.0 * (1.9 * 0.3 - 0.4 * 0.7)), 1e-14);
  // the same numbers as the projections' first measurement (bitwise: the same violation pass)
  VectorXd qp = q, qdp = qd;
  EXPECT_EQ(project_positions(sys, ws, qp, 0.0, {.tolerance = 10.0}).violation, v.position);
  EXPECT_EQ(project_velocities(sys, ws, q, qdp, 0.0, {.tolerance = 10.0}).violation, v.velocity);
  // a constraint left out by the mask takes no part (−1: no row)
  const Violations none = measure_violations(sys, ws, q, qd, 0.0, {.mask = {0}});
  EXPECT_EQ(none.position, -1.0);
  EXPECT_EQ(none.velocity, -1.0);
  // a non-finite state is left to the projections, which report it
  EXPECT_FALSE(measure_violations(sys, ws, vec({NAN, 0.0}), qd, 0.0).finite);
  EXPECT_FALSE(measure_violations(sys, ws, q, vec({0.0, INFINITY}), 0.0).finite);
}

TEST(Projection, PositionsOntoACircleAreRadialForScalarMass) {
  const double L = 1.5;
  const System sys = circle(L, 3.0 * MatrixXd::Identity(2, 2));
  Workspace ws(sys);
  VectorXd q = vec({1.9, -0.4});
  const VectorXd expected = L * q / q.norm();
  const ProjectionResult r = project_positions(sys, ws, q, 0.0);
  EXPECT_TRUE(r.converged);
  EXPECT_GE(r.iterations, 2);
  EXPECT_LE(r.iterations, 8);
  EXPECT_NEAR((q - expected).norm(), 0.0, 1e-12);
  EXPECT_NEAR(r.violation, 0.0, 1e-12);
}

TEST(Projection, LinearConstraintIsProjectedInOneStepWithTheMassNorm) {
  // a·q = c: the least-M-norm correction is −M⁻¹ a (a·q − c) / (aᵀ M⁻¹ a)
  MatrixXd M(3, 3);
  M << 4, 1, 0, 1, 3, 0.5, 0, 0.5, 2;
  const VectorXd a = vec({1.0, -2.0, 0.5});
  const double c = 0.7;
  const System sys = SystemBuilder(3)
                         .mass_matrix(M)
                         .add(holonomic("plane", 1,
                                        [a, c](const auto& q, const auto&, auto& phi) {
                                          phi[0] = a[0] * q[0] + a[1] * q[1] + a[2] * q[2] - c;
                                        }))
                         .build();
  Workspace ws(sys);
  VectorXd q = vec({0.3, 0.2, -1.0});
  const VectorXd Minv_a = M.ldlt().solve(a);
  const VectorXd expected = q - Minv_a * (a.dot(q) - c) / a.dot(Minv_a);
  const ProjectionResult r = project_positions(sys, ws, q, 0.0);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.iterations, 1);
  EXPECT_NEAR((q - expected).norm(), 0.0, 1e-14);
}

TEST(Projection, VelocitiesLoseTheirRadialPart) {
  const System sys = circle(1.0, MatrixXd::Identity(2, 2));
  Workspace ws(sys);
  const VectorXd q = vec({0.6, -0.8});
  VectorXd qd = vec({1.0, 2.0});
  const VectorXd expected = qd - qd.dot(q) * q;
  const ProjectionResult r = project_velocities(sys, ws, q, qd, 0.0);
  EXPECT_TRUE(r.converged);
  EXPECT_NEAR((qd - expected).norm(), 0.0, 1e-14);
}

TEST(Projection, NonholonomicConstraintNonlinearInVelocityConverges) {
  // x'² + y'² − c² z'² = 0
  const double c = 0.5;
  const System sys =
      SystemBuilder(3)
          .mass_matrix(MatrixXd::Identity(3, 3))
          .add(nonholonomic("cone", 1,
                            [c](const auto&, const auto& qd, const auto&, auto& psi) {
                              psi[0] = qd[0] * qd[0] + qd[1] * qd[1] - c * c * qd[2] * qd[2];
                            }))
          .build();
  Workspace ws(sys);
  const VectorXd q = VectorXd::Zero(3);
  VectorXd qd = vec({0.3, 0.4, 0.9});  // 0.25 − 0.2025 ≠ 0
  const ProjectionResult r = project_velocities(sys, ws, q, qd, 0.0);
  EXPECT_TRUE(r.converged);
  EXPECT_NEAR(qd[0] * qd[0] + qd[1] * qd[1] - c * c * qd[2] * qd[2], 0.0, 1e-12);
  // the correction is small (a nearby state, not a collapse to zero)
  EXPECT_NEAR((qd - vec({0.3, 0.4, 0.9})).norm(), 0.0, 0.1);
}

TEST(Projection, RedundantConstraintsProjectLikeASingleOne) {
  auto rod = [](const std::string& name) {
    return holonomic(name, 1, [](const auto& q, const auto&, auto& phi) {
      phi[0] = q[0] * q[0] + q[1] * q[1] - 1.0;
    });
  };
  const System one = SystemBuilder(2).mass_matrix(MatrixXd::Identity(2, 2)).add(rod("a")).build();
  const System two =
      SystemBuilder(2).mass_matrix(MatrixXd::Identity(2, 2)).add(rod("a")).add(rod("b")).build();
  Workspace w1(one), w2(two);
  VectorXd q1 = vec({1.3, 0.6}), q2 = q1;
  EXPECT_TRUE(project_positions(one, w1, q1, 0.0).converged);
  EXPECT_TRUE(project_positions(two, w2, q2, 0.0).converged);
  EXPECT_NEAR((q1 - q2).norm(), 0.0, 1e-14);
}

TEST(Projection, MaskLeavesOtherConstraintsAlone) {
  const System sys =
      SystemBuilder(2)
          .mass_matrix(MatrixXd::Identity(2, 2))
          .add(holonomic("x", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[0]; }))
          .add(holonomic("y", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[1]; }))
          .build();
  Workspace ws(sys);
  VectorXd q = vec({0.5, 0.25});
  ProjectionOptions o;
  o.mask = {0, 1};
  EXPECT_TRUE(project_positions(sys, ws, q, 0.0, o).converged);
  EXPECT_NEAR(q[0], 0.5, 1e-15);
  EXPECT_NEAR(q[1], 0.0, 1e-15);
}

TEST(Projection, NoConsistentStateNearIsReportedAsNotConverged) {
  // x = 0 and x = 1 at once
  const System sys =
      SystemBuilder(1)
          .mass_matrix(MatrixXd::Identity(1, 1))
          .add(holonomic("zero", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[0]; }))
          .add(holonomic("one", 1,
                         [](const auto& q, const auto&, auto& phi) { phi[0] = q[0] - 1.0; }))
          .build();
  Workspace ws(sys);
  VectorXd q = vec({0.2});
  const ProjectionResult r = project_positions(sys, ws, q, 0.0, {.max_iterations = 5});
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.iterations, 5);
  EXPECT_NEAR(r.violation, 0.5, 1e-12);  // the least-squares point x = 1/2
}

TEST(Projection, ViolationsOfEachLevel) {
  const System sys = circle(1.0, MatrixXd::Identity(2, 2));
  Workspace ws(sys);
  evaluate_violations(sys, ws, vec({1.0, 1.0}), vec({0.5, -2.0}), 0.0);
  EXPECT_NEAR(position_violation(sys, ws, 0), 1.0, 1e-15);  // 1 + 1 − 1
  EXPECT_NEAR(velocity_violation(sys, ws, 0), 3.0, 1e-15);  // |2 (1·0.5 + 1·(−2))|
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

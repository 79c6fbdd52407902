// SPDX-License-Identifier: BSD-3-Clause
// Non-ideal forces: the ready-made laws, custom C reading the ideal force, binding errors.
#include <cmath>

#include <gtest/gtest.h>

#include <ukdyn/ukdyn.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81;

// a particle of mass m in the plane on the line y = 0, under gravity
SystemBuilder particle_on_floor(double m) {
  SystemBuilder b({"x", "y"});
  b.mass_matrix(m * MatrixXd::Identity(2, 2))
      .forces([m](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                  Eigen::Ref<VectorXd> Q) { Q << 0.0, -m * kG; })
      .add(holonomic("floor", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[1]; }));
  return b;
}

TEST(Coulomb, RegularizationIsDocumentedSmoothSaturation) {
  // |C| = mu N v / sqrt(v² + eps²)
  const double m = 2.0, mu = 0.4, eps = 0.1;
  const System sys = particle_on_floor(m)
                         .add(coulomb_friction({.constraint = "floor",
                                                .mu = mu,
                                                .coordinates = {0},
                                                .regularization_velocity = eps}))
                         .build();
  Workspace ws(sys);
  VectorXd q(2), qd(2);
  q << 0.0, 0.0;
  for (double v : {-1.0, -0.1, 0.0, 0.05, 3.0}) {
    qd << v, 0.0;
    ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
    const double expected = -mu * m * kG * v / std::sqrt(v * v + eps * eps);
    EXPECT_NEAR(ws.C[0], expected, 1e-12);
    EXPECT_NEAR(ws.Qc_nonideal[0], expected, 1e-12);
    EXPECT_NEAR(ws.qdd[0], expected / m, 1e-12);
    EXPECT_NEAR(ws.Qc_ideal[1], m * kG, 1e-12);
  }
  EXPECT_EQ(sys.nonideal_name(0), "coulomb.floor");
}

TEST(Coulomb, NormalForceFollowsTheIdealShareOfTheNamedConstraint) {
  // a second, frictionless constraint must not contribute to N: a vertical wall x = 0 pushed by
  // a horizontal force, friction on the floor only
  const double m = 1.0, mu = 0.5, push = 3.0;
  const System sys =
      SystemBuilder({"x", "y", "z"})
          .mass_matrix(m * MatrixXd::Identity(3, 3))
          .forces([=](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                      Eigen::Ref<VectorXd> Q) { Q << -push, 0.0, -m * kG; })
          .add(holonomic("floor", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[2]; }))
          .add(holonomic("wall", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[0]; }))
          .add(coulomb_friction({.constraint = "floor", .mu = mu, .coordinates = {0, 1}}))
          .build();
  Workspace ws(sys);
  VectorXd q = VectorXd::Zero(3), qd(3);
  qd << 0.0, 2.0, 0.0;
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
  EXPECT_NEAR(ws.shares.col(0).norm(), m * kG, 1e-12);
  EXPECT_NEAR(ws.shares.col(1).norm(), push, 1e-12);
  EXPECT_NEAR(ws.Qc_nonideal[1], -mu * m * kG, 1e-12);
  EXPECT_NEAR(ws.qdd[1], -mu * kG, 1e-12);
}

TEST(Viscous, DampsOnlyAlongTheConstraint) {
  const double m = 1.5, c = 0.7;
  const System sys =
      particle_on_floor(m).add(viscous_friction({.coefficient = c, .coordinates = {}})).build();
  Workspace ws(sys);
  VectorXd q(2), qd(2);
  q << 0.3, 0.0;
  qd << 2.0, 0.0;
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
  EXPECT_NEAR(ws.qdd[0], -c * 2.0 / m, 1e-13);
  EXPECT_NEAR(ws.qdd[1], 0.0, 1e-13);
  // the component of C along the constraint normal is absorbed by the ideal reaction
  EXPECT_NEAR(ws.Qc_nonideal[1], 0.0, 1e-13);
}

TEST(CustomC, MayReadTheIdealForceAndChangeSignOnIntervals) {
  // C pushes along the floor with a force proportional to the normal reaction, on t >= 1 only
  const double m = 1.0, k = 0.25;
  const System sys =
      particle_on_floor(m)
          .add(NonIdealForce(
              "boost",
              [k](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double t,
                  const IdealForceInfo& ideal, Eigen::Ref<VectorXd> C) {
                if (t >= 1.0) C[0] = k * ideal.normal_force(ideal.constraint_index("floor"));
              }))
          .build();
  Workspace ws(sys);
  const VectorXd q = VectorXd::Zero(2), qd = VectorXd::Zero(2);
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.5), Status::kOk);
  EXPECT_NEAR(ws.qdd[0], 0.0, 1e-15);
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 1.5), Status::kOk);
  EXPECT_NEAR(ws.qdd[0], k * kG, 1e-13);
  EXPECT_NEAR(ws.Qc_nonideal[0], k * m * kG, 1e-13);
}

TEST(Binding, UnknownConstraintIsNamedInTheError) {
  auto builder = particle_on_floor(1.0);
  builder.add(coulomb_friction({.constraint = "flor", .mu = 0.3}));
  try {
    builder.build();
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no constraint named 'flor'"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("'floor'"), std::string::npos) << e.what();
  }
}

TEST(Binding, RejectsNegativeCoefficientsAndBadCoordinates) {
  EXPECT_THROW(
      particle_on_floor(1.0).add(coulomb_friction({.constraint = "floor", .mu = -1})).build(),
      std::invalid_argument);
  EXPECT_THROW(particle_on_floor(1.0)
                   .add(coulomb_friction({.constraint = "floor", .mu = 0.1, .coordinates = {5}}))
                   .build(),
               std::invalid_argument);
  EXPECT_THROW(particle_on_floor(1.0).add(viscous_friction({.coefficient = -0.1})).build(),
               std::invalid_argument);
  EXPECT_THROW(
      particle_on_floor(1.0)
          .add(coulomb_friction({.constraint = "floor", .mu = 0.1, .regularization_velocity = 0.0}))
          .build(),
      std::invalid_argument);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

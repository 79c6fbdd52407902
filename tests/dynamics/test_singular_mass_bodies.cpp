// SPDX-License-Identifier: BSD-3-Clause
// Singular (positive semi-definite) mass matrices of rigid bodies (issue #13, item 3;
// docs/theory.md section 6), and motion that [M; A] leaves undetermined (the pendulum in redundant
// coordinates, the massless midpoint, model files and the auxiliary systems:
// test_singular_mass.cpp). Every expected number comes from analysis or from an independent
// formulation, never from the code under test:
//
//  2. a torque-free symmetric rigid body on quaternions with the singular 4 × 4 quaternion mass
//     matrix 4 E_vᵀ J E_v (no fictitious J0): the closed-form precession and spin;
//  4. [M; A] rank deficient: Status::kMotionUndetermined naming the coordinates and the time;
//     an indefinite M stays kMassNotPositiveDefinite.
//
// Tests named SingularMassReference.* check the references themselves: they hold before and
// after the implementation. The SingularMass.* tests need it (the torque-free top also runs
// today, with the fictitious J0).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "ukdyn/core/autodiff.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/multibody/multibody.hpp"
#include "ukdyn/simulation/simulate.hpp"

#include "support/singular_mass.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;
using Eigen::Vector4d;

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

using test::expect_relative;
using test::kMotionUndetermined;

// column i of a trajectory field stored N × width
VectorXd sample(const std::vector<double>& f, Index width, Index i) {
  return Trajectory::view(f, width).col(i);
}

// =============================================================================================
// 2. the torque-free symmetric rigid body on quaternions
//
// J = diag(J1, J1, J3), body angular velocity w_B0, orientation R0 = R_WB(0). Euler's equations
// give w3 constant and (w1 + i w2)' = i Omega (w1 + i w2), Omega = (J3 − J1)/J1 w3, so
//   w_B(t) = Rot(e3, Omega t) w_B0.
// The angular momentum H_W = R J w_B is constant; since J w_B = J1 w_B + (J3 − J1) w3 e3,
//   w_W = H_W / J1 − Omega R e3,
// which R(t) = Rot(Ĥ, |H|/J1 t) R0 Rot(e3, −Omega t) satisfies (w_W of that product is
// |H|/J1 Ĥ − Omega R e3): the symmetry axis precesses about H at psi' = |H|/J1.
// The quaternion u (R_WB, scalar first) moves by u' = ½ u ⊗ (0, w_B), so
//   u'' = ½ u' ⊗ (0, w_B) + ½ u ⊗ (0, w_B'),  w_B' = Omega e3 × w_B.
struct SymmetricTop {
  double mass = 1.5, J1 = 0.2, J3 = 0.35;
  Vector3d w_B0{1.2, 0.0, 3.0};
  Quaterniond u0 = Quaterniond(Eigen::AngleAxisd(0.7, Vector3d(1, -0.5, 0.3).normalized()));
  Vector3d r0{0.1, 0.2, 0.3};

  Matrix3d J() const { return Vector3d(J1, J1, J3).asDiagonal(); }
  Vector3d H_W() const { return u0.toRotationMatrix() * J() * w_B0; }
  double Omega() const { return (J3 - J1) / J1 * w_B0.z(); }
  double precession_rate() const { return H_W().norm() / J1; }
  Matrix3d R(double t) const {
    return Eigen::AngleAxisd(precession_rate() * t, H_W().normalized()).toRotationMatrix() *
           u0.toRotationMatrix() *
           Eigen::AngleAxisd(-Omega() * t, Vector3d::UnitZ()).toRotationMatrix();
  }
  Vector3d w_B(double t) const {
    return Eigen::AngleAxisd(Omega() * t, Vector3d::UnitZ()).toRotationMatrix() * w_B0;
  }
  Vector3d w_W(double t) const { return R(t) * w_B(t); }
  // the nutation angle between the symmetry axis and H (constant)
  double nutation() const { return std::acos((J3 * w_B0.z()) / (J() * w_B0).norm()); }
};

Quaterniond pure(const Vector3d& v) { return Quaterniond(0.0, v.x(), v.y(), v.z()); }
// (w, x, y, z): the order of the coordinates u0..u3 (Eigen's coeffs() is x, y, z, w)
Vector4d coeffs_wxyz(const Quaterniond& q) { return Vector4d(q.w(), q.x(), q.y(), q.z()); }
Quaterniond scaled(const Quaterniond& q, double s) {
  return Quaterniond(s * q.w(), s * q.x(), s * q.y(), s * q.z());
}

mb::MultibodyModel top_model(const SymmetricTop& c) {
  mb::Multibody b;
  // no J0 argument: the default, which the implementation drops (the singular quaternion mass)
  b.add_rigid_body("top", c.mass, Vector3d(c.J1, c.J1, c.J3), c.r0, c.u0, Vector3d::Zero(),
                   c.u0.toRotationMatrix() * c.w_B0);
  return b.build();
}

TEST(SingularMassReference, SymmetricTopClosedFormIsARotationWithTheRightAngularVelocity) {
  const SymmetricTop c;
  EXPECT_GT(c.nutation(), 0.2);  // a real nutation angle, not a spin about the axis
  // R(t) is a rotation, starts at R0, and R' = [w_W]× R (central differences, h = 1e-5)
  EXPECT_NEAR((c.R(0.0) - c.u0.toRotationMatrix()).norm(), 0.0, 1e-15);
  for (double t : {0.0, 0.8, 4.3, 9.7}) {
    const Matrix3d R = c.R(t);
    EXPECT_NEAR((R.transpose() * R - Matrix3d::Identity()).norm(), 0.0, 1e-14);
    const double h = 1e-5;
    const Matrix3d Rdot = (c.R(t + h) - c.R(t - h)) / (2 * h);
    const Vector3d w = c.w_W(t);
    Matrix3d wx;
    wx << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
    EXPECT_NEAR((Rdot - wx * R).norm(), 0.0, 1e-8);
    // H_W = R J w_B constant; the symmetry axis keeps its angle to H
    EXPECT_NEAR((R * c.J() * c.w_B(t) - c.H_W()).norm(), 0.0, 1e-14);
    EXPECT_NEAR(std::acos((R * Vector3d::UnitZ()).dot(c.H_W().normalized())), c.nutation(), 1e-12);
  }
}

TEST(SingularMassReference, SymmetricTopQuaternionAccelerationIsTheClosedForm) {
  // holds today (with J0 > 0) and after (J0 dropped): q'' does not depend on J0
  const SymmetricTop c;
  const mb::MultibodyModel m = top_model(c);
  Workspace ws(m.system);
  ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk)
      << describe_status(m.system, ws);
  const Quaterniond u = c.u0;
  const Quaterniond ud = scaled(u * pure(c.w_B0), 0.5);
  EXPECT_NEAR((m.qd0.segment<4>(3) - coeffs_wxyz(ud)).norm(), 0.0, 1e-14);
  const Vector3d wd_B = c.Omega() * Vector3d::UnitZ().cross(c.w_B0);
  const Vector4d udd = 0.5 * (coeffs_wxyz(ud * pure(c.w_B0)) + coeffs_wxyz(u * pure(wd_B)));
  expect_relative(ws.qdd.segment<4>(3), udd, 1e-12, "u''");
  EXPECT_NEAR(ws.qdd.head<3>().norm(), 0.0, 1e-14);
}

TEST(SingularMass, QuaternionMassMatrixIsFourEvTransposeJEvWithoutFictitiousInertia) {
  // T = ½ w_Bᵀ J w_B with w_B = 2 E_v(u) u', E_v(u) = [−u_v | u0 I − [u_v]×] (3 × 4), so the
  // quaternion block of M is 4 E_vᵀ J E_v, of rank 3: M_uu u = 0 (u is the unit constraint's
  // direction, which [M; A] covers through the row uᵀ)
  const SymmetricTop c;
  const mb::MultibodyModel m = top_model(c);
  MatrixXd M(7, 7);
  m.system.mass_matrix(m.q0, 0.0, M);
  const Vector4d u = m.q0.segment<4>(3);
  Eigen::Matrix<double, 3, 4> Ev;
  Ev << -u[1], u[0], u[3], -u[2],  //
      -u[2], -u[3], u[0], u[1],    //
      -u[3], u[2], -u[1], u[0];
  const Eigen::Matrix4d expected = 4.0 * Ev.transpose() * c.J() * Ev;
  // the block of the check itself: w_B = 2 E_v u'
  EXPECT_NEAR((2.0 * Ev * m.qd0.segment<4>(3) - c.w_B0).norm(), 0.0, 1e-14);
  EXPECT_NEAR((M.block<4, 4>(3, 3) - expected).norm(), 0.0, 1e-14 * expected.norm());
  EXPECT_NEAR((M.block<4, 4>(3, 3) * u).norm(), 0.0, 1e-14 * expected.norm());
  EXPECT_NEAR((M.topLeftCorner<3, 3>() - c.mass * Matrix3d::Identity()).norm(), 0.0, 1e-15);
}

TEST(SingularMass, TorqueFreeSymmetricTopPrecessesAndSpinsAtTheClosedFormRates) {
  const SymmetricTop c;
  const mb::MultibodyModel m = top_model(c);
  const mb::BodyId B = m.body("top");
  SimulationOptions o;
  o.t_end = 10.0;
  o.integrator = Integrator::kRKF78;
  o.rtol = 1e-12;
  o.atol = 1e-14;
  o.output_every = 0.05;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_NEAR(tr.t.back(), 10.0, 1e-12);
  double worst_R = 0.0, worst_w = 0.0, worst_unit = 0.0, worst_H = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    const VectorXd q = sample(tr.q, 7, i), qd = sample(tr.qd, 7, i);
    const Matrix3d R = mb::body_pose(m, q, B).R_WB.toRotationMatrix();
    const Vector3d w_W = mb::body_velocity(m, q, qd, B).second;
    worst_R = std::max(worst_R, (R - c.R(t)).cwiseAbs().maxCoeff());
    worst_w = std::max(worst_w, (w_W - c.w_W(t)).cwiseAbs().maxCoeff());
    worst_w = std::max(worst_w, (R.transpose() * w_W - c.w_B(t)).cwiseAbs().maxCoeff());
    worst_unit = std::max(worst_unit, std::abs(q.segment<4>(3).norm() - 1.0));
    worst_H = std::max(worst_H, (mb::momentum(m, q, qd).second - c.H_W()).norm());
    EXPECT_NEAR((q.head<3>() - c.r0).norm(), 0.0, 1e-12) << "t = " << t;
  }
  EXPECT_NEAR(worst_R, 0.0, 1e-9);
  EXPECT_NEAR(worst_w, 0.0, 1e-8);  // |w| = 3.2 rad/s
  EXPECT_NEAR(worst_unit, 0.0, 1e-11);
  EXPECT_NEAR(worst_H, 0.0, 1e-9);
}

// =============================================================================================
// 4. errors: [M; A] rank deficient, M indefinite

TEST(SingularMass, UndeterminedCoordinateIsNamedWithTheTime) {
  ASSERT_TRUE(kMotionUndetermined.has_value()) << "Status::kMotionUndetermined is not declared";
  // M = diag(1, 0) and a constraint on 'anchor' only: nothing determines slack''
  const System sys =
      SystemBuilder(std::vector<std::string>{"anchor", "slack"})
          .mass_matrix(Eigen::Vector2d(1.0, 0.0).asDiagonal().toDenseMatrix())
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) { Q << 0.0, -1.0; })
          .add(holonomic("pin", 1,
                         [](const auto& q, const auto& t, auto& phi) {
                           using std::sin;
                           phi[0] = q[0] - 0.5 * sin(t);
                         }))
          .build();
  Workspace ws(sys);
  VectorXd q(2), qd(2);
  q << 0.5 * std::sin(0.75), 0.0;
  qd << 0.5 * std::cos(0.75), 0.0;
  EXPECT_EQ(forward_dynamics(sys, ws, q, qd, 0.75), *kMotionUndetermined);
  EXPECT_EQ(ws.status, *kMotionUndetermined);
  EXPECT_STREQ(to_string(*kMotionUndetermined), "motion not determined");
  const std::string message = describe_status(sys, ws);
  EXPECT_TRUE(contains(message, "motion not determined")) << message;
  EXPECT_TRUE(contains(message, "slack")) << message;
  EXPECT_TRUE(contains(message, "t = 0.75")) << message;
  EXPECT_FALSE(contains(message, "anchor")) << message;  // determined: not named
  EXPECT_THROW(throw_if_failed(sys, ws), SolveError);
  EXPECT_GE(ws.counters.failures, 1);
}

TEST(SingularMass, UndeterminedCombinationNamesEveryCoordinateInIt) {
  ASSERT_TRUE(kMotionUndetermined.has_value()) << "Status::kMotionUndetermined is not declared";
  // M = diag(2, 0, 0), constraint left + right = 1: the null space of [M; A] is (0, 1, −1)
  const System sys =
      SystemBuilder(std::vector<std::string>{"x", "left", "right"})
          .mass_matrix(Eigen::Vector3d(2.0, 0.0, 0.0).asDiagonal().toDenseMatrix())
          .add(holonomic("tie", 1,
                         [](const auto& q, const auto&, auto& phi) { phi[0] = q[1] + q[2] - 1.0; }))
          .build();
  Workspace ws(sys);
  VectorXd q(3), qd = VectorXd::Zero(3);
  q << 0.0, 0.4, 0.6;
  EXPECT_EQ(forward_dynamics(sys, ws, q, qd, 2.5), *kMotionUndetermined);
  const std::string message = describe_status(sys, ws);
  EXPECT_TRUE(contains(message, "left")) << message;
  EXPECT_TRUE(contains(message, "right")) << message;
  EXPECT_TRUE(contains(message, "t = 2.5")) << message;
}

TEST(SingularMass, SimulationStopsWhenTheOnlyConstraintOnAMasslessCoordinateEnds) {
  ASSERT_TRUE(kMotionUndetermined.has_value()) << "Status::kMotionUndetermined is not declared";
  // 'slack' has no mass and follows 'anchor' (in free fall) while 'hold' acts, on [0, 0.5]
  const System sys =
      SystemBuilder(std::vector<std::string>{"anchor", "slack"})
          .mass_matrix(Eigen::Vector2d(1.0, 0.0).asDiagonal().toDenseMatrix())
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) { Q << -9.81, 0.0; })
          .potential_energy([](const Eigen::Ref<const VectorXd>& q, double) { return 9.81 * q[0]; })
          .add(holonomic("hold", 1,
                         [](const auto& q, const auto&, auto& phi) { phi[0] = q[1] - q[0]; })
                   .active_between(0.0, 0.5))
          .build();
  VectorXd q0 = VectorXd::Zero(2), qd0 = VectorXd::Ones(2);
  const Trajectory tr = simulate(sys, q0, qd0, {.t_end = 1.0});
  EXPECT_EQ(tr.stats.status, *kMotionUndetermined) << tr.stats.message;
  EXPECT_NEAR(tr.stats.t_reached, 0.5, 1e-9);
  EXPECT_TRUE(contains(tr.stats.message, "motion not determined")) << tr.stats.message;
  EXPECT_TRUE(contains(tr.stats.message, "slack")) << tr.stats.message;
  EXPECT_TRUE(contains(tr.stats.message, "t = 0.5")) << tr.stats.message;
  // until then slack = anchor = t − 9.81 t²/2
  ASSERT_GT(tr.samples(), 10);
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    if (t > 0.5) break;
    const double expected = t - 0.5 * 9.81 * t * t;
    EXPECT_NEAR(sample(tr.q, 2, i)[0], expected, 1e-9);
    EXPECT_NEAR(sample(tr.q, 2, i)[1], expected, 1e-9);
  }
}

TEST(SingularMassReference, IndefiniteMassIsStillNotPositiveDefinite) {
  // [M; A] has full column rank in both cases: only positive semi-definite M are accepted
  const auto with_mass = [](const MatrixXd& M) {
    return SystemBuilder(std::vector<std::string>{"x", "y"})
        .mass_matrix(M)
        .add(holonomic("pin", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[1]; }))
        .build();
  };
  MatrixXd negative(2, 2), coupled(2, 2);
  negative << 1.0, 0.0, 0.0, -1.0;
  coupled << 1.0, 2.0, 2.0, 1.0;  // eigenvalues 3 and −1
  for (const MatrixXd& M : {negative, coupled}) {
    const System sys = with_mass(M);
    Workspace ws(sys);
    EXPECT_EQ(forward_dynamics(sys, ws, VectorXd::Zero(2), VectorXd::Zero(2), 0.0),
              Status::kMassNotPositiveDefinite);
    EXPECT_TRUE(contains(describe_status(sys, ws), "mass matrix not positive definite"))
        << describe_status(sys, ws);
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// Bodies, joints, force elements and reports of the multibody layer (multibody/multibody.hpp): each
// joint's closed-form A and b against automatic differentiation of the same position-level
// function; the quaternion equations of motion against Euler's equations and the fictitious-inertia
// form; reactions, drives, force elements and reports. (The validation problems of issue 5 against
// closed forms and published values: test_multibody_validation.cpp.)
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <string>

#include "../src/multibody/internal.hpp"
#include "ukdyn/core/autodiff.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/multibody/multibody.hpp"
#include "ukdyn/simulation/simulate.hpp"

#include "support/fictitious_inertia.hpp"

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
// joint-level checks: closed-form A, b and violations against forward-mode AD of joint_phi

// compares every closed-form joint constraint of `m` with an AD twin of its position function
void expect_joints_match_autodiff(const MultibodyModel& m, const Eigen::Ref<const VectorXd>& q,
                                  const Eigen::Ref<const VectorXd>& qd, double t,
                                  int expected_models) {
  const System& sys = m.system;
  const Index n = sys.coordinate_count();
  int checked = 0;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const Constraint& c = sys.constraint(k);
    const auto* jm = dynamic_cast<const mb::detail::JointModel*>(&c.model());
    if (jm == nullptr) continue;
    SCOPED_TRACE(c.name());
    auto f = [jm, t](const auto& qq, const auto& tt, auto& phi) {
      mb::detail::joint_phi_generic(*jm, qq, tt, t, phi);
    };
    const Constraint twin = holonomic("twin", c.rows(), f);
    auto s1 = c.model().make_scratch(n);
    auto s2 = twin.model().make_scratch(n);
    MatrixXd A1(c.rows(), n), A2(c.rows(), n);
    VectorXd b1(c.rows()), b2(c.rows()), p1(c.rows()), p2(c.rows()), v1(c.rows()), v2(c.rows());
    c.model().acceleration_form(q, qd, t, s1.get(), A1, b1);
    twin.model().acceleration_form(q, qd, t, s2.get(), A2, b2);
    c.model().violation(q, qd, t, s1.get(), p1, v1);
    twin.model().violation(q, qd, t, s2.get(), p2, v2);
    const double scale = 1.0 + A2.norm() + b2.norm();
    EXPECT_NEAR((A1 - A2).norm(), 0.0, 1e-13 * scale);
    EXPECT_NEAR((b1 - b2).norm(), 0.0, 1e-13 * scale);
    EXPECT_NEAR((p1 - p2).norm(), 0.0, 1e-14 * (1.0 + p2.norm()));
    EXPECT_NEAR((v1 - v2).norm(), 0.0, 1e-13 * scale);
    ++checked;
  }
  EXPECT_EQ(checked, expected_models);
}

TEST(MultibodyJoints, SpatialJointsMatchAutomaticDifferentiation) {
  // two rigid bodies and a particle in arbitrary poses (the joints need not hold: A and b are
  // the derivatives of phi anywhere), quaternions slightly off the unit sphere
  Multibody b;
  const BodyId A = b.add_rigid_body("A", 2.0, {0.1, 0.2, 0.3}, {0.1, -0.2, 0.3},
                                    about(0.7, {1, 2, 3}), {0.3, 0.1, -0.2}, {0.5, -1.1, 0.7});
  const BodyId B =
      b.add_rigid_body("B", 1.0, {0.2, 0.2, 0.1}, {0.4, 0.3, -0.1}, about(-1.2, {0.3, -1, 0.5}),
                       {-0.2, 0.4, 0.1}, {1.3, 0.2, -0.9});
  const BodyId P = b.add_particle("P", 0.5, {0.2, 0.9, -0.4}, {0.3, -0.6, 0.2});
  const Frame fa = Frame::with_z({0.1, 0.2, -0.3}, {0.2, 1.0, 0.4});
  const Frame fb = Frame::with_z({-0.2, 0.05, 0.15}, {1.0, -0.3, 0.2});
  b.add_joint(mb::spherical("sph", A, {0.1, 0.2, 0.3}, B, {-0.1, 0.0, 0.2}));
  b.add_joint(mb::revolute("rev", A, fa, B, fb));
  mb::Joint pri = mb::prismatic("pri", A, fa, B, fb);
  pri.drive = [](double t) {
    return Vector3d(0.2 * std::sin(t), 0.2 * std::cos(t), -0.2 * std::sin(t));
  };
  b.add_joint(pri);
  b.add_joint(mb::cylindrical("cyl", A, fa, B, fb));
  b.add_joint(mb::universal("uni", A, fa, B, fb));
  b.add_joint(mb::planar_joint("pla", A, fa, B, fb));
  b.add_joint(mb::weld("wel", A, fa, B, fb));
  b.add_joint(mb::distance("dis", A, {0.3, 0, 0}, B, {0, 0.1, 0.2}, 0.8));
  b.add_joint(mb::point_on_line("pol", A, fa, B, {0.1, 0.1, 0.1}));
  b.add_joint(mb::point_on_plane("pop", A, fa, B, {0.1, 0.1, 0.1}));
  b.add_joint(mb::spherical("sph_ground", kGround, {0.5, 0.5, 0.5}, B, {0.1, 0.2, 0.3}));
  b.add_joint(mb::spherical("sph_particle", A, {0.1, 0.0, 0.0}, P, {0, 0, 0}));
  b.add_joint(mb::point_on_plane("pop_particle", kGround, fa, P, {0, 0, 0}));
  // a disk's contact with a sphere, beyond the disk's rim (radius 0.05) and over its face (5)
  b.add_joint(mb::contact_disk_sphere("dsr", A, {0.1, 0.1, 0.1}, 0.02, B, fb, 0.05));
  b.add_joint(mb::contact_disk_sphere("dsf", A, {0.1, 0.1, 0.1}, 0.02, B, fb, 5.0));
  // a sphere's contact with a box of A, over a face, an edge and a corner
  b.add_joint(mb::contact_sphere_box("sbf", A, fa, {5.0, 5.0, 0.01}, B, {0.1, 0.1, 0.1}, 0.02));
  b.add_joint(mb::contact_sphere_box("sbe", A, fa, {5.0, 0.01, 0.01}, B, {0.1, 0.1, 0.1}, 0.02));
  b.add_joint(mb::contact_sphere_box("sbc", A, fa, {0.01, 0.01, 0.01}, B, {0.1, 0.1, 0.1}, 0.02));
  const MultibodyModel m = b.build();
  VectorXd q = m.q0, qd = m.qd0;
  q.segment<4>(3) *= 1.01;
  q.segment<4>(10) *= 0.98;
  expect_joints_match_autodiff(m, q, qd, 0.37, 19);  // 13 joints + 1 drive + 5 contacts
}

TEST(MultibodyJoints, PlanarJointsAndGearMatchAutomaticDifferentiation) {
  Multibody b;
  const BodyId A = b.add_planar_body("A", 1.0, 0.1, {0.1, 0.2, 0.3}, {0.5, -0.2, 1.1});
  const BodyId B = b.add_planar_body("B", 2.0, 0.3, {1.1, -0.4, -0.8}, {-0.3, 0.7, -0.6});
  const BodyId C = b.add_planar_body("C", 1.5, 0.2, {0.4, 0.9, 2.1}, {0.2, 0.1, 0.4});
  const Frame fa = Frame::planar(0.2, -0.1, 0.4), fb = Frame::planar(-0.3, 0.2, -0.2);
  mb::Joint rev = mb::revolute("rev", A, fa, B, fb);
  rev.drive = [](double t) { return Vector3d(t * t, 2 * t, 2.0); };
  b.add_joint(rev);
  mb::Joint pri = mb::prismatic("pri", A, fa, B, fb);
  pri.drive = [](double t) { return Vector3d(std::cos(t), -std::sin(t), -std::cos(t)); };
  b.add_joint(pri);
  b.add_joint(mb::weld("wel", kGround, fa, B, fb));
  b.add_joint(mb::distance("dis", A, {0.3, 0, 0}, C, {0, 0.1, 0}, 0.8));
  b.add_joint(mb::point_on_line("pol", C, fa, B, {0.1, 0.1, 0}));
  b.add_joint(mb::revolute("rev2", B, fb, C, fa));
  b.add_joint(mb::gear("gear", "rev", "rev2", -2.5));
  const MultibodyModel m = b.build();
  expect_joints_match_autodiff(m, m.q0, m.qd0, 0.8, 9);  // 7 joints + 2 drives
}

// at a pose where a joint holds, its rows are independent: rank(A) counts the degrees of
// freedom it removes (plus the unit norm for a rigid body), and A q'' = b holds
TEST(MultibodyJoints, EachJointRemovesItsDegreesOfFreedom) {
  const Frame fp = Frame::with_z({0.2, -0.1, 0.3}, {0.3, 0.4, 1.0});
  Frame turned = fp;  // the same origin, z turned onto −y of fp (for the universal joint)
  turned.R = fp.R * Eigen::AngleAxisd(kPi / 2, Vector3d::UnitX()).toRotationMatrix();
  const struct {
    mb::JointType type;
    Index removed;
  } spatial[] = {{mb::JointType::kSpherical, 3},    {mb::JointType::kRevolute, 5},
                 {mb::JointType::kUniversal, 4},    {mb::JointType::kCylindrical, 4},
                 {mb::JointType::kPrismatic, 5},    {mb::JointType::kPlanar, 3},
                 {mb::JointType::kWeld, 6},         {mb::JointType::kPointOnLine, 2},
                 {mb::JointType::kPointOnPlane, 1}, {mb::JointType::kDistance, 1}};
  for (const auto& c : spatial) {
    SCOPED_TRACE(mb::to_string(c.type));
    Multibody b;
    // the body at rest at the origin, frames coincident (distance: 0.5 apart along z_P)
    const BodyId B = b.add_rigid_body("B", 1.0, {0.1, 0.2, 0.3}, {0, 0, 0}, Quaterniond::Identity(),
                                      Vector3d::Zero(), Vector3d(0.1, -0.2, 0.3));
    mb::Joint j =
        mb::revolute("j", kGround, fp, B, c.type == mb::JointType::kUniversal ? turned : fp);
    j.type = c.type;
    if (c.type == mb::JointType::kDistance) {
      j.frame_parent.p += 0.5 * fp.R.col(2);
      j.length = 0.5;
    }
    b.add_joint(j);
    b.set_gravity({0, 0, -kG});
    const MultibodyModel m = b.build();
    Workspace ws(m.system);
    VectorXd qd = VectorXd::Zero(7);  // at rest: consistent with every kind
    ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, qd, 0.0), Status::kOk);
    EXPECT_EQ(ws.rank, c.removed + 1);
    EXPECT_NEAR(ws.residuals.constraint, 0.0, 1e-13);
  }
  const struct {
    mb::JointType type;
    Index removed;
  } planar[] = {{mb::JointType::kRevolute, 2},
                {mb::JointType::kPrismatic, 2},
                {mb::JointType::kWeld, 3},
                {mb::JointType::kPointOnLine, 1},
                {mb::JointType::kDistance, 1}};
  for (const auto& c : planar) {
    SCOPED_TRACE(mb::to_string(c.type));
    Multibody b;
    const BodyId B = b.add_planar_body("B", 1.0, 0.1, {0.3, 0.4, 0.5});
    const Frame f = Frame::planar(0.1, 0.2, 0.3);
    // the ground frame where the body's frame is: (0.3, 0.4) + R(0.5) (0.1, 0.2), angle 0.8
    const Vector3d o = Vector3d(0.3, 0.4, 0) + Eigen::AngleAxisd(0.5, Vector3d::UnitZ()) * f.p;
    mb::Joint j = mb::revolute("j", kGround, Frame::planar(o.x(), o.y(), 0.8), B, f);
    j.type = c.type;
    if (c.type == mb::JointType::kDistance) {
      j.frame_parent.p.x() += 0.5;
      j.length = 0.5;
    }
    b.add_joint(j);
    const MultibodyModel m = b.build();
    EXPECT_TRUE(check_initial_conditions(m.system, m.q0, m.qd0, 0.0, 1e-15).empty());
    Workspace ws(m.system);
    ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk);
    EXPECT_EQ(ws.rank, c.removed);
  }
}

TEST(MultibodyJoints, UnitQuaternionAndPointKinematics) {
  // the unit-norm row: A = uᵀ, b = −|u'|² against AD of (|u|² − 1)/2
  Multibody b;
  b.add_rigid_body("A", 1.0, {1, 2, 3}, {0, 0, 0}, about(0.4, {1, 1, 0}), Vector3d::Zero(),
                   {0.3, -0.2, 0.9});
  const MultibodyModel m = b.build();
  VectorXd q = m.q0 * 1.0;
  q.segment<4>(3) *= 1.05;
  const Constraint& c = m.system.constraint(0);
  const Constraint twin = holonomic("twin", 1, [](const auto& qq, const auto&, auto& phi) {
    phi[0] = 0.5 * (qq[3] * qq[3] + qq[4] * qq[4] + qq[5] * qq[5] + qq[6] * qq[6] - 1.0);
  });
  MatrixXd A1(1, 7), A2(1, 7);
  VectorXd b1(1), b2(1);
  auto s2 = twin.model().make_scratch(7);
  c.model().acceleration_form(q, m.qd0, 0.0, nullptr, A1, b1);
  twin.model().acceleration_form(q, m.qd0, 0.0, s2.get(), A2, b2);
  EXPECT_NEAR((A1 - A2).norm(), 0.0, 1e-15);
  EXPECT_NEAR(b1[0] - b2[0], 0.0, 1e-15);
  // the initial u' gives ω_W = 2 G_v(u) u' back, and the world point of (1, 0, 0) is R e_x
  const auto [v, w] = mb::body_velocity(m, m.q0, m.qd0, 0);
  EXPECT_NEAR((w - Vector3d(0.3, -0.2, 0.9)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((mb::world_point(m, m.q0, 0, Vector3d::UnitX()) -
               about(0.4, {1, 1, 0}).toRotationMatrix().col(0))
                  .norm(),
              0.0, 1e-15);
}

// ---------------------------------------------------------------------------------------------
// the quaternion equations of motion

// one free rigid body under a force at a body point and a torque: linear acceleration F/m and
// Euler's equations J w_B' + w_B × J w_B = tau_B with the singular quaternion mass matrix; and
// the same q'' as the fictitious-inertia formulation for J0 over five decades
TEST(MultibodyRigidBody, QuaternionEquationsMatchEulerAndTheFictitiousInertiaFormulation) {
  const Vector3d J(0.3, 0.5, 0.7), s(0.1, 0.2, -0.3), F(0.4, -0.3, 1.2), tau(0.2, -0.1, 0.4);
  const Quaterniond u0 = about(1.1, {0.3, -0.7, 0.2});
  const Vector3d w0(1.5, -2.0, 0.7);
  Multibody b;
  const BodyId B = b.add_rigid_body("B", 2.0, J, {0.1, 0.2, 0.3}, u0, {0.3, 0.0, -0.1}, w0);
  b.add_force(mb::applied(
      "push", B, s,
      [F, tau](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double) {
        return mb::Wrench{F, tau};
      }));
  const MultibodyModel m = b.build();
  Workspace ws(m.system);
  ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk);
  EXPECT_TRUE(ws.mass_singular);
  const Eigen::Matrix3d R = u0.toRotationMatrix();
  const Vector3d wB = R.transpose() * w0, tauB = R.transpose() * tau + s.cross(R.transpose() * F);
  const Vector3d wdB_euler = J.cwiseInverse().asDiagonal() * (tauB - wB.cross(J.asDiagonal() * wB));
  // w_B = 2 E_v(u) u'  ⇒  w_B' = 2 E_v(u) u'' (E_v(u') u' = 0)
  const Vector3d wdB = 2.0 * mb::detail::E_v(m.q0.segment<4>(3)) * ws.qdd.segment<4>(3);
  EXPECT_NEAR((wdB - wdB_euler).norm(), 0.0, 1e-12 * wdB_euler.norm());
  EXPECT_NEAR((ws.qdd.head<3>() - F / 2.0).norm(), 0.0, 1e-14);
  for (double J0 : {1e-3, 0.5, 50.0}) {
    SCOPED_TRACE(J0);
    const System regular = test::with_fictitious_inertia(m.system, J0);
    Workspace wr(regular);
    ASSERT_EQ(forward_dynamics(regular, wr, m.q0, m.qd0, 0.0), Status::kOk);
    EXPECT_FALSE(wr.mass_singular);
    EXPECT_NEAR((ws.qdd - wr.qdd).norm(), 0.0, 1e-12 * wr.qdd.norm());
    EXPECT_NEAR((ws.Qc - wr.Qc).norm(), 0.0, 1e-12 * (wr.Qc.norm() + 1.0));
  }
}

TEST(MultibodyRigidBody, TorqueFreeMotionKeepsEnergyAndAngularMomentumAsWithFictitiousInertia) {
  // an asymmetric body tumbling for 3 s keeps E and L (world) to the integration tolerance, and
  // follows the trajectory of the fictitious-inertia formulation (J0 = 0.01 and 10)
  Multibody b;
  b.add_rigid_body("B", 1.0, {0.2, 0.5, 0.9}, {0, 0, 0}, about(0.3, {1, 0, 0}), Vector3d::Zero(),
                   {0.1, 3.0, 0.2});
  const MultibodyModel m = b.build();
  SimulationOptions o;
  o.t_end = 3.0;
  o.output_every = 0.5;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto [P0, L0] = mb::momentum(m, m.q0, m.qd0);
  const double E0 = mb::total_energy(m, m.q0, m.qd0, 0.0);
  const Index N = tr.samples() - 1;
  const VectorXd q = sample(tr.q, 7, N), qd = sample(tr.qd, 7, N);
  const auto [P1, L1] = mb::momentum(m, q, qd);
  EXPECT_NEAR((L1 - L0).norm(), 0.0, 1e-8 * L0.norm());
  EXPECT_NEAR(mb::total_energy(m, q, qd, 3.0) - E0, 0.0, 1e-9 * E0);
  for (double J0 : {0.01, 10.0}) {
    SCOPED_TRACE(J0);
    const System regular = test::with_fictitious_inertia(m.system, J0);
    const Trajectory tj = simulate(regular, m.q0, m.qd0, o);
    ASSERT_EQ(tj.stats.status, Status::kOk) << tj.stats.message;
    // the same motion (both start from the same u), to the integration tolerance
    EXPECT_NEAR((sample(tj.q, 7, tj.samples() - 1) - q).norm(), 0.0, 1e-8);
  }
}

TEST(MultibodyForces, RotationalSpringBetweenRigidBodiesOscillatesAboutAFixedAxis) {
  // an isotropic body (J = j I) on a spherical joint at its centre, tied to the ground by a
  // rotational spring k: from rest at 0.8 rad about n the relative rotation stays about n with
  // angle 0.8 cos(sqrt(k/j) t); the energy ½ k theta² + ½ j w² is conserved
  const double j = 0.4, k = 3.0, theta0 = 0.8;
  const Vector3d n = Vector3d(1, 2, 2) / 3.0;
  Multibody b;
  const BodyId B = b.add_rigid_body("ball", 2.0, {j, j, j}, {0, 0, 0}, about(theta0, n));
  b.add_joint(mb::spherical("centre", kGround, {0, 0, 0}, B, {0, 0, 0}));
  b.add_force(mb::torsion_spring("spring", kGround, B, k, 0.0, 0.0));
  b.set_gravity({0, 0, -kG});
  const MultibodyModel m = b.build();
  SimulationOptions o;
  o.t_end = 3.0;
  o.output_every = 0.25;
  o.rtol = 1e-11;
  o.atol = 1e-13;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double E0 = mb::total_energy(m, m.q0, m.qd0, 0.0);
  EXPECT_NEAR(E0 - 2.0 * kG * 0.0, 0.5 * k * theta0 * theta0, 1e-12);
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    const VectorXd q = sample(tr.q, 7, i), qd = sample(tr.qd, 7, i);
    const Eigen::AngleAxisd rel(mb::body_pose(m, q, B).R_WB);
    const double expected = theta0 * std::cos(std::sqrt(k / j) * t);
    // the signed angle about n
    const double angle = rel.angle() * (rel.axis().dot(n) >= 0 ? 1.0 : -1.0);
    EXPECT_NEAR(angle, expected, 1e-8) << t;
    if (std::abs(expected) > 0.05) {
      EXPECT_NEAR(std::abs(rel.axis().dot(n)), 1.0, 1e-9) << t;
    }
    EXPECT_NEAR(mb::total_energy(m, q, qd, t), E0, 1e-9 * E0) << t;
  }
}

TEST(MultibodyForces, RotationalSpringAboutARevoluteAxisHasThePeriodOfJzzOverK) {
  // a rigid body on a revolute joint about the vertical z axis through its centre (gravity
  // does not act about it), twisted 0.3 rad: period 2 pi sqrt(J3 / k)
  const double J3 = 0.5, k = 2.0;
  Multibody b;
  const BodyId B = b.add_rigid_body("disk", 1.0, {0.3, 0.3, J3}, {0, 0, 0}, about(0.3, {0, 0, 1}));
  b.add_joint(mb::revolute("axle", kGround, Frame::at({0, 0, 0}), B, Frame::at({0, 0, 0})));
  b.add_force(mb::torsion_spring("twist", kGround, B, k, 0.0, 0.0));
  b.set_gravity({0, 0, -kG});
  const MultibodyModel m = b.build();
  SimulationOptions o;
  o.t_end = 2 * std::numbers::pi * std::sqrt(J3 / k);  // one period
  o.rtol = 1e-11;
  o.atol = 1e-13;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const VectorXd qT = sample(tr.q, 7, tr.samples() - 1);
  const Eigen::AngleAxisd rel(mb::body_pose(m, qT, B).R_WB);
  EXPECT_NEAR(rel.angle(), 0.3, 1e-8);
  EXPECT_NEAR(rel.axis().z(), 1.0, 1e-9);
}

TEST(MultibodyErrors, TorsionSpringNeedsTwoOrientedBodiesOfOneKind) {
  Multibody b;
  const BodyId P = b.add_particle("p", 1.0, {0, 0, 0});
  b.add_force(mb::torsion_spring("bad", kGround, P, 1.0, 0.0, 0.0));
  EXPECT_THROW(
      {
        try {
          b.build();
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("torsion spring 'bad' must join"), std::string::npos)
              << e.what();
          throw;
        }
      },
      std::invalid_argument);
  Multibody r;
  const BodyId R = r.add_rigid_body("r", 1.0, {1, 1, 1}, {0, 0, 0}, Quaterniond::Identity());
  r.add_force(mb::torsion_spring("rest", kGround, R, 1.0, 0.0, 0.2));
  EXPECT_THROW(r.build(), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// pendulum reactions and joint friction

struct PlanarPendulumCase {
  double m = 2.0, Ic = 0.1, l = 0.7, theta = -1.0, w = 1.3;
  double Ip() const { return Ic + m * l * l; }
};

MultibodyModel planar_pendulum(const PlanarPendulumCase& c, mb::JointFriction fr = {}) {
  Multibody b;
  const Vector3d pose(c.l * std::cos(c.theta), c.l * std::sin(c.theta), c.theta);
  const Vector3d vel(-c.l * c.w * std::sin(c.theta), c.l * c.w * std::cos(c.theta), c.w);
  const BodyId B = b.add_planar_body("bob", c.m, c.Ic, pose, vel);
  mb::Joint pin = mb::revolute("pin", kGround, Frame::planar(0, 0), B, Frame::planar(-c.l, 0));
  pin.friction = fr;
  b.add_joint(pin);
  b.set_gravity({0, -kG, 0});
  return b.build();
}

TEST(MultibodyReactions, PlanarPendulumPinForceIsTheClosedForm) {
  const PlanarPendulumCase c;
  const MultibodyModel m = planar_pendulum(c);
  Workspace ws(m.system);
  ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk);
  // theta'' = −m g l cos(theta) / I_p;  F = m a_G − m g
  const double thdd = -c.m * kG * c.l * std::cos(c.theta) / c.Ip();
  const Vector3d aG = c.l * thdd * Vector3d(-std::sin(c.theta), std::cos(c.theta), 0) -
                      c.l * c.w * c.w * Vector3d(std::cos(c.theta), std::sin(c.theta), 0);
  const Vector3d F = c.m * aG + Vector3d(0, c.m * kG, 0);
  EXPECT_NEAR(ws.qdd[2] - thdd, 0.0, 1e-13);
  const auto r = mb::joint_reaction(m, m.q0, m.qd0, 0.0, ws.lambda, 0);
  EXPECT_EQ(r.body, 0);
  EXPECT_NEAR((r.force_W - F).norm(), 0.0, 1e-12 * F.norm());
  EXPECT_NEAR(r.torque_W.norm(), 0.0, 1e-12);
  // in the body frame: rotated by −theta
  const Vector3d FB = Eigen::AngleAxisd(-c.theta, Vector3d::UnitZ()) * F;
  EXPECT_NEAR((r.force_B - FB).norm(), 0.0, 1e-12 * F.norm());
}

TEST(MultibodyReactions, SpatialPendulumOnARevoluteJointMatchesThePlanarClosedForm) {
  // rigid body swinging about the world y axis through the origin, gravity along −z; the
  // centre of mass at l (cos a, 0, sin a) in the (x, z) plane
  const double m = 2.0, l = 0.7, a = -1.0, w = 1.3, Iyy = 0.1;
  Multibody b;
  // rotation about +y by psi = −a takes the body x axis to (cos a, 0, sin a)
  const Vector3d r0 = l * Vector3d(std::cos(a), 0, std::sin(a));
  const Vector3d w0(0, -w, 0);
  const BodyId B = b.add_rigid_body("bob", m, {0.05, Iyy, 0.07}, r0, about(-a, Vector3d::UnitY()),
                                    w0.cross(r0), w0);
  b.add_joint(mb::revolute("pin", kGround, Frame::with_z({0, 0, 0}, Vector3d::UnitY()), B,
                           Frame::with_z({-l, 0, 0}, Vector3d::UnitY())));
  b.set_gravity({0, 0, -kG});
  const MultibodyModel mm = b.build();
  EXPECT_TRUE(check_initial_conditions(mm.system, mm.q0, mm.qd0, 0.0, 1e-14).empty());
  Workspace ws(mm.system);
  ASSERT_EQ(forward_dynamics(mm.system, ws, mm.q0, mm.qd0, 0.0), Status::kOk);
  const double add = -m * kG * l * std::cos(a) / (Iyy + m * l * l);
  const Vector3d aG = l * add * Vector3d(-std::sin(a), 0, std::cos(a)) -
                      l * w * w * Vector3d(std::cos(a), 0, std::sin(a));
  const Vector3d F = m * aG + Vector3d(0, 0, m * kG);
  EXPECT_NEAR((ws.qdd.head<3>() - aG).norm(), 0.0, 1e-12);
  const auto r = mb::joint_reaction(mm, mm.q0, mm.qd0, 0.0, ws.lambda, mm.joint("pin"));
  EXPECT_NEAR((r.force_W - F).norm(), 0.0, 1e-12 * F.norm());
  EXPECT_NEAR(r.torque_W.norm(), 0.0, 1e-12 * F.norm());
}

TEST(MultibodyReactions, PinFrictionIsCoulombOfTheJointsOwnReactionPlusViscous) {
  const PlanarPendulumCase c;
  const double mu = 0.2, radius = 0.05, visc = 0.3;
  const MultibodyModel ideal = planar_pendulum(c);
  const MultibodyModel m = planar_pendulum(c, {.mu = mu, .radius = radius, .viscous = visc});
  Workspace wi(ideal.system), ws(m.system);
  ASSERT_EQ(forward_dynamics(ideal.system, wi, ideal.q0, ideal.qd0, 0.0), Status::kOk);
  ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk);
  const auto ri = mb::joint_reaction(ideal, wi, ideal.q0, ideal.qd0, 0.0, 0);
  const auto r = mb::joint_reaction(m, ws, m.q0, m.qd0, 0.0, 0);
  // the ideal part does not see the friction; friction torque T = −(mu r N + c w) with N the
  // pin's whole force, which T itself changes through θ'' (N = |m a_G + m g e_y|,
  // a_G = l θ'' t − l w² r, θ'' = (−m g l cos θ + T) / I_p): the fixed point, by iteration
  const double N_ideal = ri.force_W.norm();
  const Eigen::Vector2d er(std::cos(c.theta), std::sin(c.theta)),
      et(-std::sin(c.theta), std::cos(c.theta));
  double T = -(mu * radius * N_ideal + visc * c.w), N = N_ideal;
  for (int k = 0; k < 100; ++k) {
    const double thdd = (-c.m * kG * c.l * std::cos(c.theta) + T) / c.Ip();
    N = (c.m * (c.l * thdd * et - c.l * c.w * c.w * er) + Eigen::Vector2d(0, c.m * kG)).norm();
    T = -(mu * radius * N + visc * c.w);
  }
  EXPECT_GT(std::abs(N - N_ideal), 1e-6 * N);  // (the friction does change the pin force)
  EXPECT_NEAR((r.force_W - ri.force_W).norm(), 0.0, 1e-12 * N);
  EXPECT_NEAR(r.nonideal_torque_W.z() - T, 0.0, 1e-9 * std::abs(T));
  EXPECT_NEAR(r.nonideal_force_W.norm(), 0.0, 1e-15);
  // and the pendulum feels it: theta'' = (−m g l cos theta + T) / I_p
  EXPECT_NEAR(ws.qdd[2] - (-c.m * kG * c.l * std::cos(c.theta) + T) / c.Ip(), 0.0, 1e-9);
}

// ---------------------------------------------------------------------------------------------
// spatial drives and gears, the rolling sphere, prismatic friction

TEST(MultibodyDrives, SpatialRevoluteDriveFollowsItsAngleWithTorqueJzzTimesAngularAcceleration) {
  // a body turning about the world z axis through its centre of mass, driven at
  // f(t) = 0.5 sin(2t) (+ its initial angle 0.3): the driving torque is J_zz f''
  const double Jzz = 0.7;
  const auto f = [](double t) {
    return Vector3d(0.3 + 0.5 * std::sin(2 * t), std::cos(2 * t), -2.0 * std::sin(2 * t));
  };
  Multibody b;
  const BodyId B =
      b.add_rigid_body("rotor", 2.0, {0.4, 0.5, Jzz}, {0, 0, 0}, about(0.3, Vector3d::UnitZ()),
                       Vector3d::Zero(), Vector3d(0, 0, 1.0));
  mb::Joint j = mb::revolute("motor", kGround, {}, B, {});
  j.drive = f;
  b.add_joint(j);
  b.set_gravity({0, 0, -kG});
  const MultibodyModel m = b.build();
  ASSERT_TRUE(check_initial_conditions(m.system, m.q0, m.qd0, 0.0, 1e-14).empty());
  SimulationOptions o;
  o.t_end = 2.0;
  o.output_every = 0.25;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  Workspace ws(m.system);
  double worst_angle = 0.0, worst_torque = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    const VectorXd q = sample(tr.q, 7, i), qd = sample(tr.qd, 7, i);
    const Vector3d x = mb::body_pose(m, q, 0).R_WB * Vector3d::UnitX();
    worst_angle = std::max(worst_angle, std::abs(std::atan2(x.y(), x.x()) - f(t)[0]));
    ASSERT_EQ(forward_dynamics(m.system, ws, q, qd, t), Status::kOk);
    worst_torque = std::max(worst_torque,
                            std::abs(mb::drive_effort(m, q, qd, t, ws.lambda, 0) - Jzz * f(t)[2]));
  }
  EXPECT_NEAR(worst_angle, 0.0, 1e-9);
  EXPECT_NEAR(worst_torque, 0.0, 1e-9);
}

TEST(MultibodyDrives, SpatialGearSharesTheTorqueByTheEffectiveInertia) {
  // two rotors on parallel world-z revolute joints, w_a = r w_b: a torque tau on rotor a gives
  // w_a' = tau / (J_a + J_b / r²)
  const double Ja = 0.3, Jb = 0.8, r = -2.0, tau = 1.5;
  Multibody b;
  const BodyId A = b.add_rigid_body("a", 1.0, {0.2, 0.2, Ja}, {0, 0, 0}, Quaterniond::Identity(),
                                    Vector3d::Zero(), Vector3d(0, 0, 2.0));
  const BodyId B = b.add_rigid_body("b", 1.0, {0.3, 0.3, Jb}, {1, 0, 0}, Quaterniond::Identity(),
                                    Vector3d::Zero(), Vector3d(0, 0, 2.0 / r));
  b.add_joint(mb::revolute("ja", kGround, {}, A, {}));
  b.add_joint(mb::revolute("jb", kGround, Frame::at({1, 0, 0}), B, {}));
  b.add_joint(mb::gear("gear", "ja", "jb", r));
  b.add_force(mb::applied(
      "motor", A, {0, 0, 0},
      [tau](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double) {
        return mb::Wrench{Vector3d::Zero(), Vector3d(0, 0, tau)};
      }));
  const MultibodyModel m = b.build();
  ASSERT_TRUE(check_initial_conditions(m.system, m.q0, m.qd0, 0.0, 1e-14).empty());
  Workspace ws(m.system);
  ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk);
  const double wa_dot = 2.0 * mb::detail::G_v(m.q0.segment<4>(3)).row(2).dot(ws.qdd.segment<4>(3));
  EXPECT_NEAR(wa_dot, tau / (Ja + Jb / (r * r)), 1e-12);
}

TEST(MultibodyRolling, SphereUnderAHorizontalPushAcceleratesAtFiveSeventhsOfFOverM) {
  // a solid sphere (J = 2/5 m R²) rolling on z = 0, pushed at its centre by F along x:
  // a = F / (m + J / R²) = 5 F / (7 m); it spins up about y at a / R
  const double m = 2.0, R = 0.25, F = 3.0, J = 0.4 * m * R * R;
  Multibody b;
  const BodyId S = b.add_rigid_body("ball", m, {J, J, J}, {0, 0, R}, Quaterniond::Identity(),
                                    {1.0, 0.5, 0}, {-0.5 / R, 1.0 / R, 0.3});
  b.add_joint(mb::rolling_sphere("roll", S, R));
  b.add_force(mb::applied(
      "push", S, {0, 0, 0},
      [F](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double) {
        return mb::Wrench{Vector3d(F, 0, 0), Vector3d::Zero()};
      }));
  b.set_gravity({0, 0, -kG});
  const MultibodyModel mm = b.build();
  ASSERT_TRUE(check_initial_conditions(mm.system, mm.q0, mm.qd0, 0.0, 1e-14).empty());
  Workspace ws(mm.system);
  ASSERT_EQ(forward_dynamics(mm.system, ws, mm.q0, mm.qd0, 0.0), Status::kOk);
  EXPECT_NEAR(ws.qdd[0], 5 * F / (7 * m), 1e-12);
  EXPECT_NEAR(ws.qdd[1], 0.0, 1e-12);
  EXPECT_NEAR(ws.qdd[2], 0.0, 1e-12);
  // contact reaction: normal m g, friction F − m a = 2F/7 backwards
  const auto r = mb::joint_reaction(mm, mm.q0, mm.qd0, 0.0, ws.lambda, 0);
  EXPECT_NEAR((r.force_W - Vector3d(-2 * F / 7, 0, m * kG)).norm(), 0.0, 1e-12);
}

TEST(MultibodyReactions, PrismaticCoulombFrictionDeceleratesASliderAtMuG) {
  // a planar slider on a horizontal prismatic joint, gravity −y, sliding at v > 0:
  // x'' = −mu g − c v / m, the friction reported as a force along −x on the slider
  const double m = 2.0, mu = 0.3, c = 0.4, v = 1.5;
  Multibody b;
  const BodyId S = b.add_planar_body("slider", m, 0.1, {0.2, 0, 0}, {v, 0, 0});
  mb::Joint j = mb::prismatic("rail", kGround, Frame::planar(0, 0), S, Frame::planar(0, 0));
  j.friction = {.mu = mu, .viscous = c};
  b.add_joint(j);
  b.set_gravity({0, -kG, 0});
  const MultibodyModel mm = b.build();
  Workspace ws(mm.system);
  ASSERT_EQ(forward_dynamics(mm.system, ws, mm.q0, mm.qd0, 0.0), Status::kOk);
  const double Ff = -(mu * m * kG + c * v);
  EXPECT_NEAR(ws.qdd[0], Ff / m, 1e-9);
  const auto r = mb::joint_reaction(mm, ws, mm.q0, mm.qd0, 0.0, 0);
  EXPECT_NEAR((r.force_W - Vector3d(0, m * kG, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((r.nonideal_force_W - Vector3d(Ff, 0, 0)).norm(), 0.0, 1e-9);
}

// ---------------------------------------------------------------------------------------------
// force elements, reports and errors

TEST(MultibodyForces, SpringPotentialAndGravityMatchTheirForces) {
  // Q = −dV/dq on the conservative part (finite differences of V, central, h = 1e-6)
  Multibody b;
  const BodyId A =
      b.add_rigid_body("A", 1.0, {0.1, 0.2, 0.3}, {0.1, 0.2, 0.3}, about(0.5, {1, 2, 0}));
  const BodyId P = b.add_planar_body("P", 2.0, 0.3, {0.5, -0.2, 0.7});
  const BodyId Pb = b.add_planar_body("Pb", 1.0, 0.2, {-0.5, 0.4, -0.3});
  b.add_force(mb::spring_damper("s1", A, {0.1, 0, 0.2}, kGround, {1, 1, 1}, 50.0, 0.0, 0.4));
  b.add_force(mb::spring_damper("s2", P, {0.2, 0.1, 0}, Pb, {-0.1, 0.3, 0}, 20.0, 0.0, 0.2));
  b.add_force(mb::torsion_spring("t", P, Pb, 3.0, 0.0, 0.1));
  b.set_gravity({0.3, -kG, 0.2});
  const MultibodyModel m = b.build();
  const Index n = m.system.coordinate_count();
  VectorXd Q(n);
  m.system.forces(m.q0, VectorXd::Zero(n), 0.0, Q);
  for (Index i = 0; i < n; ++i) {
    if (i >= 3 && i < 7) continue;  // quaternion: Q along the tangent only, checked below
    VectorXd qp = m.q0, qm = m.q0;
    qp[i] += 1e-6;
    qm[i] -= 1e-6;
    const double dV = (m.system.potential_energy(qp, 0) - m.system.potential_energy(qm, 0)) / 2e-6;
    EXPECT_NEAR(Q[i], -dV, 1e-6 * (1 + std::abs(dV)))
        << m.system.coordinate_names()[std::size_t(i)];
  }
  // quaternion directions tangent to the unit sphere: Q · t = −dV/dt
  const mb::detail::Vector4d u = m.q0.segment<4>(3);
  const mb::detail::Vector4d t = mb::detail::G_v(u).row(1).transpose();  // ⊥ u
  VectorXd qp = m.q0, qm = m.q0;
  qp.segment<4>(3) = (u + 1e-6 * t).normalized();
  qm.segment<4>(3) = (u - 1e-6 * t).normalized();
  const double dV = (m.system.potential_energy(qp, 0) - m.system.potential_energy(qm, 0)) / 2e-6;
  EXPECT_NEAR(Q.segment<4>(3).dot(t), -dV, 1e-6 * (1 + std::abs(dV)));
}

TEST(MultibodyReports, PosesCsvHasOneLinePerSampleAndQuaternions) {
  const PlanarPendulumCase c;
  const MultibodyModel m = planar_pendulum(c);
  SimulationOptions o;
  o.t_end = 0.1;
  o.output_every = 0.05;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  const std::string path = ::testing::TempDir() + "ukdyn_poses.csv";
  mb::write_poses_csv(m, tr, path);
  std::ifstream is(path);
  std::string header, line;
  std::getline(is, header);
  EXPECT_EQ(header, "t,bob.x,bob.y,bob.z,bob.qw,bob.qx,bob.qy,bob.qz");
  int lines = 0;
  while (std::getline(is, line)) ++lines;
  EXPECT_EQ(lines, tr.samples());
  // first sample: the quaternion of a rotation by theta about z
  EXPECT_NEAR(mb::body_pose(m, m.q0, 0).R_WB.z(), std::sin(c.theta / 2), 1e-15);
  std::remove(path.c_str());
}

TEST(MultibodyErrors, BuildNamesTheProblem) {
  const auto error_of = [](const Multibody& b) -> std::string {
    try {
      b.build();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  Multibody mixed;
  const BodyId P = mixed.add_planar_body("p", 1, 1, {0, 0, 0});
  const BodyId R = mixed.add_rigid_body("r", 1, {1, 1, 1}, {0, 0, 0}, Quaterniond::Identity());
  mixed.add_joint(mb::revolute("j", P, {}, R, {}));
  EXPECT_NE(error_of(mixed).find("joint 'j' joins a planar body to a spatial one"),
            std::string::npos)
      << error_of(mixed);
  Multibody particle;
  const BodyId X = particle.add_particle("x", 1, {0, 0, 0});
  particle.add_joint(mb::revolute("hinge", kGround, {}, X, {}));
  EXPECT_NE(error_of(particle).find("a particle has no orientation"), std::string::npos)
      << error_of(particle);
  Multibody spatial_drive;
  const BodyId S =
      spatial_drive.add_rigid_body("s", 1, {1, 1, 1}, {0, 0, 0}, Quaterniond::Identity());
  mb::Joint j = mb::spherical("ball", kGround, {0, 0, 0}, S, {0, 0, 0});
  j.drive = [](double) { return Vector3d::Zero(); };
  spatial_drive.add_joint(j);
  EXPECT_NE(error_of(spatial_drive)
                .find("a spatial drive needs a revolute (its angle), prismatic or "
                      "cylindrical joint (its slide d · z_P = f(t)), got spherical"),
            std::string::npos)
      << error_of(spatial_drive);
  Multibody bad;
  EXPECT_THROW(bad.add_rigid_body("z", -1, {1, 1, 1}, {0, 0, 0}, Quaterniond::Identity()),
               std::invalid_argument);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

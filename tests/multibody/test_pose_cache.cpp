// SPDX-License-Identifier: BSD-3-Clause
// The per-workspace memo of the bodies' rotations (detail::PoseCache, issue #15 item 3): each
// body's rotation is computed once per evaluation and shared by the joints, the forces and the
// violation checks; a cached rotation is never stale — an evaluation through a workspace that
// has seen other states gives bitwise what a fresh workspace gives, even when the state differs
// by one ulp in one angle or one quaternion entry.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "../src/multibody/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"
#include "ukdyn/multibody/multibody.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using Eigen::Quaterniond;
using Eigen::Vector3d;
using mb::BodyId;
using mb::Frame;
using mb::kGround;
using mb::Multibody;
using mb::MultibodyModel;

// bitwise equality of two vectors (NaN payloads and signed zeros included)
bool same_bits(const Eigen::Ref<const VectorXd>& a, const Eigen::Ref<const VectorXd>& b) {
  if (a.size() != b.size()) return false;
  for (Index i = 0; i < a.size(); ++i) {
    if (std::bit_cast<std::uint64_t>(a[i]) != std::bit_cast<std::uint64_t>(b[i])) return false;
  }
  return true;
}

// q with x moved by `ulps` units in the last place
double nudge(double x, int ulps) {
  for (int i = 0; i < ulps; ++i) x = std::nextafter(x, std::numeric_limits<double>::infinity());
  return x;
}

// A planar chain ground – b0 – b1 – b2 (revolute, revolute, prismatic), a spring-damper from b0
// to b2, a torsion spring b0–b1, a force applied off b1's centre and pin friction: every planar
// path that reads a body's cos/sin or R_WB (joint rows, violations, point forces, friction).
MultibodyModel planar_chain() {
  Multibody b;
  b.set_gravity({0, -9.81, 0});
  const BodyId b0 = b.add_planar_body("b0", 1.0, 0.1, {0.5, 0, 0.3}, {0, 0.5, 1.0});
  const BodyId b1 = b.add_planar_body("b1", 2.0, 0.2, {1.4, 0.3, -0.4}, {0.2, -0.1, 0.7});
  const BodyId b2 = b.add_planar_body("b2", 1.5, 0.3, {2.1, 0.1, 0.9}, {-0.3, 0.2, -0.5});
  mb::Joint pin = mb::revolute("pin", kGround, Frame::planar(0, 0), b0, Frame::planar(-0.5, 0));
  pin.friction.mu = 0.2;
  pin.friction.radius = 0.01;
  pin.friction.viscous = 0.05;
  b.add_joint(pin);
  b.add_joint(mb::revolute("elbow", b0, Frame::planar(0.5, 0), b1, Frame::planar(-0.4, 0.1)));
  b.add_joint(
      mb::prismatic("slide", b1, Frame::planar(0.4, 0, 0.2), b2, Frame::planar(-0.3, 0.05, -0.1)));
  b.add_force(mb::spring_damper("spring", b0, {0.2, 0.1, 0}, b2, {-0.1, 0.2, 0}, 30.0, 0.4, 1.1));
  b.add_force(mb::torsion_spring("torsion", b0, b1, 5.0, 0.1, 0.2));
  b.add_force(mb::applied(
      "push", b1, {0.3, -0.2, 0},
      [](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double t) {
        return mb::Wrench{Vector3d(std::cos(t), 0.5, 0), Vector3d(0, 0, 0.1)};
      }));
  return b.build();
}

// Two rigid bodies on spherical joints, joined by a rotational (torsion) spring, one of them also
// to the ground: the spring reads R_WB of both bodies (the quaternion path of the cache).
MultibodyModel spatial_pair() {
  Multibody b;
  b.set_gravity({0, 0, -9.81});
  const Quaterniond ua(Eigen::AngleAxisd(0.4, Vector3d(1, 2, 3).normalized()));
  const Quaterniond ub(Eigen::AngleAxisd(-0.9, Vector3d(0.3, -1, 0.5).normalized()));
  const BodyId a =
      b.add_rigid_body("a", 1.0, {0.1, 0.2, 0.3}, {0, 0, -0.5}, ua, {0.1, 0, 0}, {0.5, -1.1, 0.7});
  const BodyId c =
      b.add_rigid_body("c", 2.0, {0.2, 0.2, 0.1}, {0, 0, -1.5}, ub, {0, 0.2, 0}, {1.3, 0.2, -0.9});
  b.add_joint(mb::spherical("top", kGround, {0, 0, 0}, a, {0, 0, 0.5}));
  b.add_joint(mb::spherical("middle", a, {0, 0, -0.5}, c, {0, 0, 0.5}));
  b.add_force(mb::torsion_spring("twist", a, c, 4.0, 0.2, 0.0));
  b.add_force(mb::torsion_spring("anchor", kGround, a, 2.0, 0.0, 0.0));
  return b.build();
}

// the states: the initial one, every orientation coordinate one ulp up, the initial one again,
// then a large change
std::vector<VectorXd> states(const MultibodyModel& m) {
  std::vector<VectorXd> qs = {m.q0, m.q0, m.q0, m.q0};
  for (const mb::BodyInfo& b : m.bodies) {
    const Index first = b.kind == mb::BodyKind::kPlanar ? b.offset + 2 : b.offset + 3;
    const Index count = b.kind == mb::BodyKind::kPlanar ? 1 : 4;
    for (Index i = first; i < first + count; ++i) {
      qs[1][i] = nudge(qs[1][i], 1);
      qs[3][i] += 0.3 + 0.1 * double(i);
    }
  }
  return qs;
}

struct Evaluation {
  Status status;
  VectorXd qdd, lambda, Q, phi, phi_dot;
};

// forward dynamics, then the violations and Q, at (q, q0', t) through ws
Evaluation evaluate(const MultibodyModel& m, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                    double t) {
  Evaluation e;
  e.status = forward_dynamics(m.system, ws, q, m.qd0, t);
  e.qdd = ws.qdd;
  e.lambda = ws.lambda;
  evaluate_violations(m.system, ws, q, m.qd0, t);
  e.phi = ws.phi;
  e.phi_dot = ws.phi_dot;
  e.Q.resize(q.size());
  m.system.forces(q, m.qd0, t, ws.callables.get(), e.Q);
  return e;
}

void expect_never_stale(const MultibodyModel& m) {
  const std::vector<VectorXd> qs = states(m);
  Workspace used(m.system);
  std::vector<Evaluation> fresh;
  for (std::size_t i = 0; i < qs.size(); ++i) {
    SCOPED_TRACE("state " + std::to_string(i));
    const double t = 0.1 * double(i);
    const Evaluation a = evaluate(m, used, qs[i], t);
    Workspace once(m.system);
    const Evaluation b = evaluate(m, once, qs[i], t);
    ASSERT_EQ(a.status, Status::kOk);
    ASSERT_EQ(b.status, Status::kOk);
    EXPECT_TRUE(same_bits(a.qdd, b.qdd));
    EXPECT_TRUE(same_bits(a.lambda, b.lambda));
    EXPECT_TRUE(same_bits(a.Q, b.Q));
    EXPECT_TRUE(same_bits(a.phi, b.phi));
    EXPECT_TRUE(same_bits(a.phi_dot, b.phi_dot));
    fresh.push_back(b);
  }
  // the one-ulp state is told apart: a cache keyed loosely (or not at all) would have returned
  // state 0's rotations there, and the comparisons above would have failed
  EXPECT_FALSE(same_bits(fresh[1].qdd, fresh[0].qdd));
  EXPECT_FALSE(same_bits(fresh[1].Q, fresh[0].Q));
}

TEST(MultibodyPoseCache, PlanarEvaluationsThroughOneWorkspaceAreBitwiseThoseOfFreshOnes) {
  expect_never_stale(planar_chain());
}

TEST(MultibodyPoseCache, QuaternionEvaluationsThroughOneWorkspaceAreBitwiseThoseOfFreshOnes) {
  expect_never_stale(spatial_pair());
}

// the workspace's joints read the System's cache (its callables' scratch), so the joints, forces
// and violation checks of one evaluation compute each rotation once
TEST(MultibodyPoseCache, EachBodysRotationIsComputedOncePerEvaluation) {
  const MultibodyModel m = planar_chain();
  Workspace ws(m.system);
  const auto* cache = dynamic_cast<const mb::detail::PoseCache*>(ws.callables.get());
  ASSERT_NE(cache, nullptr);
  int joints = 0;
  for (Index k = 0; k < m.system.constraint_count(); ++k) {
    if (dynamic_cast<const mb::detail::JointModel*>(&m.system.constraint(k).model()) == nullptr)
      continue;
    const auto& s =
        static_cast<const mb::detail::JointModel::Scratch&>(*ws.scratch[std::size_t(k)]);
    EXPECT_EQ(s.cache, cache) << m.system.constraint(k).name();
    EXPECT_EQ(s.own, nullptr);
    ++joints;
  }
  EXPECT_EQ(joints, 3);
  // three planar bodies: three cos/sin pairs, and R_WB of the pin's parent (the ground: none)
  // for its friction; the same state again, and its violations: nothing new
  ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk);
  EXPECT_EQ(cache->computed(), 3);
  ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk);
  evaluate_violations(m.system, ws, m.q0, m.qd0, 0.0);
  EXPECT_EQ(cache->computed(), 3);
  // one body turned: its rotation only
  VectorXd q = m.q0;
  q[m.bodies[1].offset + 2] += 0.25;
  ASSERT_EQ(forward_dynamics(m.system, ws, q, m.qd0, 0.0), Status::kOk);
  EXPECT_EQ(cache->computed(), 4);

  // rigid bodies: R_WB of each (the torsion springs) once per evaluation
  const MultibodyModel s = spatial_pair();
  Workspace ws2(s.system);
  const auto* cache2 = dynamic_cast<const mb::detail::PoseCache*>(ws2.callables.get());
  ASSERT_NE(cache2, nullptr);
  ASSERT_EQ(forward_dynamics(s.system, ws2, s.q0, s.qd0, 0.0), Status::kOk);
  EXPECT_EQ(cache2->computed(), 2);
  ASSERT_EQ(forward_dynamics(s.system, ws2, s.q0, s.qd0, 0.0), Status::kOk);
  EXPECT_EQ(cache2->computed(), 2);
}

// a joint's constraint in another system (no PoseCache there) keeps a cache of its own and
// gives the same rows, bitwise
TEST(MultibodyPoseCache, AJointOutsideItsSystemEvaluatesWithACacheOfItsOwn) {
  const MultibodyModel m = planar_chain();
  const Index n = m.system.coordinate_count();
  const Constraint& elbow = m.system.constraint(m.system.constraint_index("elbow"));
  const System other = SystemBuilder(m.system.coordinate_names())
                           .mass_matrix(MatrixXd::Identity(n, n))
                           .add(elbow)
                           .build();
  Workspace mine(m.system), theirs(other);
  const auto& s = static_cast<const mb::detail::JointModel::Scratch&>(*theirs.scratch[0]);
  ASSERT_NE(s.own, nullptr);
  EXPECT_EQ(s.cache, s.own.get());
  for (const VectorXd& q : states(m)) {
    MatrixXd A1(2, n), A2(2, n);
    VectorXd b1(2), b2(2);
    const Index k = m.system.constraint_index("elbow");
    elbow.model().acceleration_form(q, m.qd0, 0.0, mine.scratch[std::size_t(k)].get(), A1, b1);
    elbow.model().acceleration_form(q, m.qd0, 0.0, theirs.scratch[0].get(), A2, b2);
    MatrixXd A3(2, n);
    VectorXd b3(2);
    elbow.model().acceleration_form(q, m.qd0, 0.0, nullptr, A3, b3);  // no cache at all
    EXPECT_TRUE(same_bits(A1.reshaped(), A2.reshaped()));
    EXPECT_TRUE(same_bits(A1.reshaped(), A3.reshaped()));
    EXPECT_TRUE(same_bits(b1, b2));
    EXPECT_TRUE(same_bits(b1, b3));
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

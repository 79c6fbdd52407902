// SPDX-License-Identifier: BSD-3-Clause
// No heap allocation per evaluation of a tree's system once the workspace exists.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "support/alloc_counter.hpp"
#include "ukdyn/control/control.hpp"
#include "ukdyn/core/nonideal.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/multibody/tree_closures.hpp"

namespace ukdyn::tree {
namespace UKDYN_TEST_FILE {

const std::string kPanda = std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf";

TEST(Tree, EvaluationsDoNotAllocate) {
  const System sys = make_system(load_urdf(kPanda));
  Workspace ws(sys);
  VectorXd q(7), qd(7);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd << 0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3;
  forward_dynamics(sys, ws, q, qd, 0.0);
  testing::start_counting_allocations();
  for (int i = 0; i < 10; ++i) forward_dynamics(sys, ws, q, qd, 0.01 * i);
  EXPECT_EQ(testing::stop_counting_allocations(), 0);
  EXPECT_EQ(ws.status, Status::kOk);
}

// the floating-base humanoid, whose M the engine factorizes along the tree's branches
// (SystemBuilder::mass_tree) with its unit quaternion's row: no allocation either
TEST(Tree, HumanoidEvaluationsDoNotAllocate) {
  const Tree tree =
      load_urdf(std::string(UKDYN_TEST_DATA_DIR) + "/../../examples/robots/humanoid.urdf");
  const System sys = make_system(tree);
  ASSERT_FALSE(sys.mass_tree().empty());
  Workspace ws(sys);
  const Index n = tree.coordinate_count();
  VectorXd q = tree.neutral(), qd = VectorXd::Zero(n);
  qd.segment<4>(3) << 0, 0.15, -0.1, 0.25;
  for (Index i = 7; i < n; ++i) {
    q[i] = 0.3 * std::sin(double(i));
    qd[i] = 0.8 * std::cos(double(3 * i));
  }
  forward_dynamics(sys, ws, q, qd, 0.0);
  testing::start_counting_allocations();
  for (int i = 0; i < 10; ++i) forward_dynamics(sys, ws, q, qd, 0.01 * i);
  EXPECT_EQ(testing::stop_counting_allocations(), 0);
  EXPECT_EQ(ws.status, Status::kOk);
  EXPECT_GT(ws.qdd.norm(), 0.1);
}

// the loop closures (point, distance) and the task-space requirement, under the control law
// whose evaluation runs them all (compute_control), and the momentum and limit passes
TEST(Tree, FrameConstraintsAndTaskControlDoNotAllocate) {
  const Tree tree = load_urdf(kPanda);
  const Index tool = tree.link_index("panda_tool"), l3 = tree.link_index("panda_link3");
  VectorXd q(7), qd(7);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd << 0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3;
  SystemBuilder sb = system_builder(tree);
  sb.add(
      distance_constraint(tree, "rod", {tool, Vector3d::Zero()}, {l3, Vector3d(0.1, 0, 0)}, 0.5));
  const System held = sb.build();
  const System free = make_system(tree);
  const Controller ctrl =
      ControllerBuilder(free)
          .require(
              pose_requirement(tree, "tool", {tool, Vector3d::Zero()},
                               [](double t, PoseSample& d) {
                                 d.p = Vector3d(0.3, 0.1 * t, 0.5);
                                 d.v = Vector3d(0, 0.1, 0);
                                 d.R = Eigen::AngleAxisd(t, Vector3d::UnitZ()).toRotationMatrix();
                                 d.w = Vector3d::UnitZ();
                               }),
              ErrorDynamics::second_order(10.0, 1.0))
          .require(point_constraint(tree, "ball", {l3, Vector3d::Zero()}, {-1, Vector3d::Zero()}),
                   ErrorDynamics::second_order(10.0, 1.0))
          .build();
  Workspace ws(held);
  ControlWorkspace cws(ctrl);
  TreeData d(tree);
  forward_dynamics(held, ws, q, qd, 0.0);
  compute_control(ctrl, cws, q, qd, 0.0);
  testing::start_counting_allocations();
  Vector6d h = Vector6d::Zero();
  for (int i = 0; i < 10; ++i) {
    forward_dynamics(held, ws, q, qd, 0.01 * i);
    compute_control(ctrl, cws, q, qd, 0.01 * i);
    h += momentum(tree, q, qd, d);
  }
  EXPECT_EQ(testing::stop_counting_allocations(), 0);
  EXPECT_EQ(ws.status, Status::kOk);
  EXPECT_GT(h.norm(), 0.0);
  // the arm under the control (controlled_system: the plant is the model, whose scratch the
  // plant's evaluation and the control's share: one forward kinematics, M kept for the second
  // caller) at changing states
  const System controlled = controlled_system(ctrl, free);
  Workspace cs(controlled);
  VectorXd qi = q;
  forward_dynamics(controlled, cs, q, qd, 0.0);
  testing::start_counting_allocations();
  for (int i = 0; i < 10; ++i) {
    qi[1] = q[1] + 0.01 * i;  // (a new state each time: M, Q and the kinematics recomputed)
    forward_dynamics(controlled, cs, qi, qd, 0.01 * i);
  }
  EXPECT_EQ(testing::stop_counting_allocations(), 0);
  EXPECT_EQ(cs.status, Status::kOk);
  EXPECT_GT(cs.qdd.norm(), 0.1);
}

// Coulomb friction at a link's contact point (tree::contact_kinematics,
// tree::disk_contact_kinematics): the friction's evaluation and its stick constraint's rows
// allocate nothing — a sphere on the floor, a sphere and a disk on a tilted plane of link 3
TEST(Tree, ContactPointFrictionDoesNotAllocate) {
  const Tree tree = load_urdf(kPanda);
  const Index tool = tree.link_index("panda_tool"), l3 = tree.link_index("panda_link3");
  VectorXd q(7), qd(7);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd << 0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3;
  LinkFrame tilted{l3, Vector3d(0.05, 0.1, -0.02), Matrix3d::Identity()};
  tilted.R = Eigen::AngleAxisd(0.4, Vector3d(1, 2, 0).normalized()).toRotationMatrix();
  const LinkDisk disk{tool, Vector3d(0.01, 0.02, 0.05), Vector3d(0.3, -0.2, 1.0), 0.04};
  for (int shape = 0; shape < 3; ++shape) {
    const LinkFrame plane =
        shape == 0 ? LinkFrame{-1, Vector3d::Zero(), Matrix3d::Identity()} : tilted;
    SystemBuilder sb = system_builder(tree);
    sb.add(shape == 2 ? disk_contact_constraint(tree, "c", disk, plane, q)
                      : contact_constraint(tree, "c", {tool, Vector3d::Zero()}, 0.02, plane));
    CoulombFriction spec;
    spec.constraint = "c";
    spec.mu = 0.3;
    spec.kinematics = shape == 2
                          ? disk_contact_kinematics(tree, "c", disk, plane)
                          : contact_kinematics(tree, "c", {tool, Vector3d::Zero()}, 0.02, plane);
    sb.add(coulomb_friction(spec));
    const System sys = sb.build();
    Workspace ws(sys);
    forward_dynamics(sys, ws, q, qd, 0.0);
    const Index stick = sys.constraint_index("stick.coulomb.c");
    MatrixXd A = MatrixXd::Zero(2, 7);
    VectorXd b = VectorXd::Zero(2);
    testing::start_counting_allocations();
    for (int i = 0; i < 5; ++i) {
      forward_dynamics(sys, ws, q, qd, 0.01 * i);
      sys.constraint(stick).model().acceleration_form(q, qd, 0.0,
                                                      ws.scratch[std::size_t(stick)].get(), A, b);
    }
    EXPECT_EQ(testing::stop_counting_allocations(), 0) << "shape " << shape;
    EXPECT_EQ(ws.status, Status::kOk) << "shape " << shape;
    EXPECT_GT(A.norm(), 0.0) << "shape " << shape;
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::tree

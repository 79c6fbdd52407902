// SPDX-License-Identifier: BSD-3-Clause
// One forward kinematics per state (multibody/tree/kinematics_cache.hpp): the frame constraints
// and requirements evaluated with a tree system's workspace read its kinematics. Shared only
// between trees of the same kinematics; results bit for bit those of constraints with their own
// kinematics, also when the states of the users interleave (the kept M, Q and Jacobians dropped
// when another user moved the kinematics); a controller's requirements share its model's.
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "multibody/tree/kinematics_cache.hpp"
#include "ukdyn/control/control.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {
namespace UKDYN_TEST_FILE {

const std::string kPanda = std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf";

VectorXd pose(double s) {
  VectorXd q(7);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  return q + s * VectorXd::LinSpaced(7, 0.2, -0.3);
}

VectorXd rates() {
  VectorXd qd(7);
  qd << 0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3;
  return qd;
}

// the panda's tree with link `i`'s joint origin moved by dx (x), or its mass scaled by `mass`
Tree changed(const Tree& tree, Index i, double dx, double mass) {
  std::vector<Link> links;
  for (Index k = 0; k < tree.link_count(); ++k) links.push_back(tree.link(k));
  links[std::size_t(i)].joint.p_PJ.x() += dx;
  links[std::size_t(i)].inertial.mass *= mass;
  return Tree(tree.name(), links, tree.gravity());
}

Constraint rod(const Tree& tree) {
  return distance_constraint(tree, "rod", {tree.link_index("panda_tool"), Vector3d::Zero()},
                             {tree.link_index("panda_link3"), Vector3d(0.1, 0, 0)}, 0.5);
}

// the Panda's tree with the rod closing a loop from its tool to its third link
System with_rod(const Tree& tree) {
  SystemBuilder sb = system_builder(tree);
  sb.add(rod(tree));
  return sb.build();
}

TEST(TreeSharedKinematics, SharedOnlyWithTheSameKinematics) {
  const Tree tree = load_urdf(kPanda);
  const System sys = make_system(tree);
  const auto scratch = sys.make_scratch();
  EXPECT_NE(detail::shared_kinematics(scratch.get(), tree), nullptr);
  // another tree of the same joints and other masses (a nominal model's): shared
  EXPECT_TRUE(detail::same_kinematics(tree, changed(tree, 3, 0.0, 1.5)));
  EXPECT_NE(detail::shared_kinematics(scratch.get(), changed(tree, 3, 0.0, 1.5)), nullptr);
  // a joint origin moved by 1 cm, another tree, no scratch: not shared
  EXPECT_FALSE(detail::same_kinematics(tree, changed(tree, 3, 0.01, 1.0)));
  EXPECT_EQ(detail::shared_kinematics(scratch.get(), changed(tree, 3, 0.01, 1.0)), nullptr);
  const Tree other =
      load_urdf(std::string(UKDYN_TEST_DATA_DIR) + "/../../examples/robots/humanoid.urdf");
  EXPECT_FALSE(detail::same_kinematics(tree, other));
  EXPECT_EQ(detail::shared_kinematics(scratch.get(), other), nullptr);
  EXPECT_EQ(detail::shared_kinematics(nullptr, tree), nullptr);
}

// M, Q and a closure's rows at one state: one forward kinematics between them
TEST(TreeSharedKinematics, OneForwardKinematicsPerState) {
  const Tree tree = load_urdf(kPanda);
  const System sys = with_rod(tree);
  Workspace ws(sys);
  detail::KinematicsCache* k = detail::shared_kinematics(ws.callables.get(), tree);
  ASSERT_NE(k, nullptr);
  const VectorXd q = pose(0.0), qd = rates();
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
  const std::uint64_t v = k->version;
  EXPECT_GE(v, 1u);
  // the same state again (M, Q, the closure's A, b and its violation): no forward kinematics
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.1), Status::kOk);
  EXPECT_EQ(k->version, v);
  ASSERT_EQ(forward_dynamics(sys, ws, pose(0.1), qd, 0.1), Status::kOk);
  EXPECT_EQ(k->version, v + 1);
}

// The users' states interleaved: the closure moved to q2 between two evaluations at q1 and q2,
// the tree's M and Q moved between the closure's: every result bit for bit that of a workspace
// whose closure has kinematics of its own (the kept M, Q and Jacobians dropped when stale)
TEST(TreeSharedKinematics, InterleavedStatesGiveTheUnsharedResults) {
  const Tree tree = load_urdf(kPanda);
  const System sys = with_rod(tree);
  const Constraint& c = sys.constraint(0);
  Workspace shared(sys), own(sys);
  own.scratch[0] = c.model().make_scratch(7);
  ASSERT_NE(detail::shared_kinematics(shared.callables.get(), tree), nullptr);
  const VectorXd q1 = pose(0.0), q2 = pose(0.3), qd = rates();
  MatrixXd A_shared(1, 7), A_own(1, 7);
  VectorXd b_shared(1), b_own(1);
  for (const VectorXd* q : {&q1, &q2, &q1}) {
    // the system at q, then the closure alone at the other state, then the system at q again
    const VectorXd& other = q == &q2 ? q1 : q2;
    for (int pass = 0; pass < 2; ++pass) {
      ASSERT_EQ(forward_dynamics(sys, shared, *q, qd, 0.0), Status::kOk);
      ASSERT_EQ(forward_dynamics(sys, own, *q, qd, 0.0), Status::kOk);
      EXPECT_EQ(shared.M, own.M);
      EXPECT_EQ(shared.qdd, own.qdd);
      EXPECT_EQ(shared.lambda, own.lambda);
      EXPECT_GT(shared.qdd.norm(), 0.1);
      c.model().acceleration_form(other, qd, 0.0, shared.scratch[0].get(), A_shared, b_shared);
      c.model().acceleration_form(other, qd, 0.0, own.scratch[0].get(), A_own, b_own);
      EXPECT_EQ(A_shared, A_own);
      EXPECT_EQ(b_shared, b_own);
      EXPECT_GT(A_own.norm(), 0.01);
    }
  }
  // and the rows differ between the states (the comparison can fail)
  MatrixXd A2(1, 7);
  VectorXd b2(1);
  c.model().acceleration_form(q1, qd, 0.0, own.scratch[0].get(), A_own, b_own);
  c.model().acceleration_form(q2, qd, 0.0, own.scratch[0].get(), A2, b2);
  EXPECT_GT((A_own - A2).norm(), 1e-3);
}

// Two callers of one scratch (a controller's model and its plant write M into different
// buffers: the second gets the M kept), and a closure moving the kinematics between them: M and
// Q are always those of the state asked for, bit for bit those of a scratch of their own
TEST(TreeSharedKinematics, KeptMassMatrixAndForcesFollowTheKinematics) {
  const Tree tree = load_urdf(kPanda);
  const System sys = with_rod(tree);
  const Constraint& c = sys.constraint(0);
  const auto scratch = sys.make_scratch();
  const auto closure = c.model().make_scratch_sharing(7, scratch.get());
  ASSERT_NE(detail::shared_kinematics(scratch.get(), tree), nullptr);
  const VectorXd q1 = pose(0.0), q2 = pose(0.3), qd = rates();
  MatrixXd M1(7, 7), M2(7, 7), M_ref(7, 7), A(1, 7);
  VectorXd Q1(7), Q_ref(7), b(1);
  TreeData d(tree);
  for (const auto& [qa, qb] : {std::pair{&q1, &q2}, std::pair{&q2, &q1}, std::pair{&q1, &q1}}) {
    // M at qa into two buffers (the second caller gets the kept M), then the closure at qb,
    // then M and Q at qb: the kinematics are at qb already, the M and Q kept are qa's
    sys.mass_matrix(*qa, 0.0, scratch.get(), M1);
    sys.mass_matrix(*qa, 0.0, scratch.get(), M2);
    sys.forces(*qa, qd, 0.0, scratch.get(), Q1);
    mass_matrix(tree, *qa, d, M_ref);
    EXPECT_EQ(M1, M_ref);
    EXPECT_EQ(M2, M_ref);
    c.model().acceleration_form(*qb, qd, 0.0, closure.get(), A, b);
    sys.mass_matrix(*qb, 0.0, scratch.get(), M2);
    sys.forces(*qb, qd, 0.0, scratch.get(), Q1);
    mass_matrix(tree, *qb, d, M_ref);
    const auto own = sys.make_scratch();
    sys.forces(*qb, qd, 0.0, own.get(), Q_ref);
    EXPECT_EQ(M2, M_ref);
    EXPECT_EQ(Q1, Q_ref);
  }
  // (M differs between the states: the comparison can fail)
  MatrixXd Ma(7, 7), Mb(7, 7);
  mass_matrix(tree, q1, d, Ma);
  mass_matrix(tree, q2, d, Mb);
  EXPECT_GT((Ma - Mb).norm(), 1e-3);
}

// A controller's pose requirement reads its model's kinematics: compute_control runs one forward
// kinematics per state, and its force is bit for bit that of a requirement with its own
TEST(TreeSharedKinematics, ControlRequirementsReadTheModelsKinematics) {
  const Tree tree = load_urdf(kPanda);
  const System model = make_system(tree);
  const Index tool = tree.link_index("panda_tool");
  const Controller ctrl =
      ControllerBuilder(model)
          .require(
              pose_requirement(tree, "tool", {tool, Vector3d::Zero()},
                               [](double t, PoseSample& d) {
                                 d.p = Vector3d(0.3, 0.1 * t, 0.5);
                                 d.v = Vector3d(0, 0.1, 0);
                                 d.R = Eigen::AngleAxisd(t, Vector3d::UnitZ()).toRotationMatrix();
                                 d.w = Vector3d::UnitZ();
                               }),
              ErrorDynamics::second_order(10.0, 1.0))
          .build();
  ControlWorkspace shared(ctrl), own(ctrl);
  const System& reqs = ctrl.requirements();
  own.req.scratch[0] = reqs.constraint(0).model().make_scratch(7);
  detail::KinematicsCache* k = detail::shared_kinematics(shared.model.callables.get(), tree);
  ASSERT_NE(k, nullptr);
  for (double s : {0.0, 0.2, 0.0}) {
    const VectorXd q = pose(s), qd = rates();
    const std::uint64_t before = k->version;
    ASSERT_EQ(compute_control(ctrl, shared, q, qd, s), ControlStatus::kOk);
    EXPECT_EQ(k->version, before + 1);  // the model's, read by the requirement
    ASSERT_EQ(compute_control(ctrl, own, q, qd, s), ControlStatus::kOk);
    EXPECT_EQ(shared.Qc_control, own.Qc_control);
    EXPECT_EQ(shared.req.A, own.req.A);
    EXPECT_EQ(shared.e, own.e);
    EXPECT_GT(shared.Qc_control.norm(), 1.0);
  }
}

// The link velocities the tree's RNEA leaves in the shared kinematics are read by a frame
// requirement's J' q' pass at that very state only: at the same q and another q', after the
// closure wrote them at another q', and after the kinematics moved, the closure's rows are bit
// for bit those of a closure with kinematics of its own
TEST(TreeSharedKinematics, RneaVelocitiesReadOnlyAtTheirState) {
  const Tree tree = load_urdf(kPanda);
  const System sys = with_rod(tree);
  const Constraint& c = sys.constraint(0);
  const auto scratch = sys.make_scratch();
  const auto closure = c.model().make_scratch_sharing(7, scratch.get());
  const auto own = c.model().make_scratch(7);
  detail::KinematicsCache* k = detail::shared_kinematics(scratch.get(), tree);
  ASSERT_NE(k, nullptr);
  const VectorXd q1 = pose(0.0), q2 = pose(0.3), qd1 = rates(), qd2 = -2.0 * rates();
  VectorXd Q(7), b(1), b_own(1);
  MatrixXd A(1, 7), A_own(1, 7);
  const auto check = [&](const VectorXd& q, const VectorXd& qd, bool reused) {
    k->at(tree, q);  // (what the closure does first: the kinematics at q)
    EXPECT_EQ(k->velocities_at(qd), reused);
    c.model().acceleration_form(q, qd, 0.0, closure.get(), A, b);
    c.model().acceleration_form(q, qd, 0.0, own.get(), A_own, b_own);
    EXPECT_EQ(A, A_own);
    EXPECT_EQ(b, b_own);
  };
  sys.forces(q1, qd1, 0.0, scratch.get(), Q);  // the RNEA at (q1, q1'): v marked
  check(q1, qd1, true);                        // read
  check(q1, qd2, false);                       // another q': computed (and the mark cleared)
  check(q1, qd1, false);                       // v written at q2': not read
  sys.forces(q1, qd2, 0.0, scratch.get(), Q);  // the RNEA at (q1, q2')
  check(q1, qd2, true);
  check(q2, qd2, false);  // the kinematics moved
  sys.forces(q2, qd1, 0.0, scratch.get(), Q);
  check(q2, qd1, true);
  // (b depends on q': the comparisons can fail)
  VectorXd b2(1);
  c.model().acceleration_form(q2, qd2, 0.0, own.get(), A_own, b2);
  EXPECT_GT(std::abs(b2[0] - b_own[0]), 1e-3);
}

// The velocity products c_i + v_i × S_i q'_i the RNEA keeps for a frame pass sharing its
// kinematics: kept only once such a pass shares them (an RNEA before leaves velocities without
// them, and the pass computes them, the same bits), then added instead of recomputed — the
// closure's rows bit for bit those of a closure with kinematics of its own either way
TEST(TreeSharedKinematics, RneaVelocityProductsKeptOnlyForASharingPass) {
  const Tree tree = load_urdf(kPanda);
  const System sys = with_rod(tree);
  const Constraint& c = sys.constraint(0);
  const auto scratch = sys.make_scratch();
  detail::KinematicsCache* k = detail::shared_kinematics(scratch.get(), tree);
  ASSERT_NE(k, nullptr);
  const VectorXd q = pose(0.2), qd = rates();
  VectorXd Q(7), b(1), b_own(1);
  MatrixXd A(1, 7), A_own(1, 7);
  sys.forces(q, qd, 0.0, scratch.get(), Q);  // no sharing pass yet: v marked, c not kept
  EXPECT_FALSE(k->keep_c);
  EXPECT_FALSE(k->c_valid);
  const auto closure = c.model().make_scratch_sharing(7, scratch.get());
  const auto own = c.model().make_scratch(7);
  EXPECT_TRUE(k->keep_c);
  EXPECT_TRUE(k->velocities_at(qd));
  c.model().acceleration_form(q, qd, 0.0, own.get(), A_own, b_own);
  c.model().acceleration_form(q, qd, 0.0, closure.get(), A, b);  // v read, c computed
  EXPECT_EQ(A, A_own);
  EXPECT_EQ(b, b_own);
  EXPECT_TRUE(k->velocities_at(qd));  // (v written again at the same q': still marked)
  sys.forces(q, -qd, 0.0, scratch.get(), Q);
  sys.forces(q, qd, 0.0, scratch.get(), Q);  // the RNEA at (q, q') again: c kept
  EXPECT_TRUE(k->c_valid);
  c.model().acceleration_form(q, qd, 0.0, closure.get(), A, b);  // v and c read
  EXPECT_EQ(A, A_own);
  EXPECT_EQ(b, b_own);
  // (the velocity products are not zero: the comparison can fail)
  EXPECT_GT(k->c[std::size_t(tree.link_index("panda_link3"))].norm(), 1e-2);
}

// A pose requirement's ω = J_ω q', formed by its acceleration form, is read again by its
// violation only at the same state: at another q' or q the violation is bit for bit that of a
// fresh scratch, and at the same one too
TEST(TreeSharedKinematics, PoseAngularVelocityReadOnlyAtItsState) {
  const Tree tree = load_urdf(kPanda);
  const Constraint req =
      pose_requirement(tree, "tool", {tree.link_index("panda_tool"), Vector3d(0, 0, 0.1)},
                       [](double t, PoseSample& d) {
                         d.p = Vector3d(0.3, 0.1 * t, 0.5);
                         d.R = Eigen::AngleAxisd(t, Vector3d::UnitZ()).toRotationMatrix();
                         d.w = Vector3d::UnitZ();
                       });
  const auto kept = req.model().make_scratch(7);
  MatrixXd A(6, 7);
  VectorXd b(6), pos(6), vel(6), pos_fresh(6), vel_fresh(6);
  const VectorXd q1 = pose(0.0), q2 = pose(0.3), qd1 = rates(), qd2 = -2.0 * rates();
  const auto check = [&](const VectorXd& q, const VectorXd& qd) {
    req.model().violation(q, qd, 0.1, kept.get(), pos, vel);
    const auto fresh = req.model().make_scratch(7);
    req.model().violation(q, qd, 0.1, fresh.get(), pos_fresh, vel_fresh);
    EXPECT_EQ(pos, pos_fresh);
    EXPECT_EQ(vel, vel_fresh);
  };
  req.model().acceleration_form(q1, qd1, 0.1, kept.get(), A, b);
  check(q1, qd1);  // ω read
  check(q1, qd2);  // another q': formed again
  req.model().acceleration_form(q1, qd1, 0.1, kept.get(), A, b);
  check(q2, qd1);  // the kinematics moved
  // (the orientation error's rate depends on ω: the comparisons can fail)
  VectorXd vel2(6);
  req.model().violation(q1, qd2, 0.1, kept.get(), pos, vel2);
  req.model().violation(q1, qd1, 0.1, kept.get(), pos, vel);
  EXPECT_GT((vel2.tail<3>() - vel.tail<3>()).norm(), 1e-3);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::tree

// SPDX-License-Identifier: BSD-3-Clause
// Constraints and requirements between tree frames (multibody/tree/frame_constraints.cpp) and
// the limit checks (limits.cpp): a four-bar loop closed on an arm held exactly, a distance
// closure, weld and revolute closures (a weld moving as the tree without the joint it spans, the
// shared four-bar P2 as a tree closed by a hinge), and exact task-space tracking of the 7-DOF arm
// (issue #30 item 4) whose control torques equal inverse dynamics (RNEA) of the motion achieved;
// effort-limit excess reported.
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "ukdyn/control/control.hpp"
#include "ukdyn/core/autodiff.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/multibody/tree_closures.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::tree {
namespace UKDYN_TEST_FILE {

const std::string kPanda = std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf";

VectorXd arm_pose() {
  VectorXd q(7);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  return q;
}

// A of a holonomic constraint against central differences of its violation along q' (the
// velocity level phi' = A q' + ∂phi/∂t), and b against the second difference of phi along the
// motion q(t) = q + q' t + q'' t²/2: phi'' = A q'' − b must vanish at the q'' that A q'' = b.
void expect_acceleration_form_consistent(const System& sys, Index k, const VectorXd& q,
                                         const VectorXd& qd) {
  const Constraint& c = sys.constraint(k);
  const Index n = q.size(), m = c.rows();
  auto scratch = c.model().make_scratch(n);
  MatrixXd A(m, n);
  VectorXd b(m), pos(m), vel(m);
  c.model().acceleration_form(q, qd, 0.0, scratch.get(), A, b);
  // phi' = A q'
  c.model().violation(q, qd, 0.0, scratch.get(), pos, vel);
  EXPECT_NEAR((A * qd - vel).norm(), 0.0, 1e-12 * (1.0 + vel.norm()));
  // phi(q + q' h + q'' h²/2) along a motion with a random q'': its second difference
  // approximates phi'' = A q'' − b
  const VectorXd qdd = VectorXd::LinSpaced(n, -1.0, 1.5);
  const double h = 1e-4;
  VectorXd p_plus(m), p_minus(m), p0(m), unused(m);
  const VectorXd zero = VectorXd::Zero(n);
  c.model().violation(q + qd * h + qdd * (h * h / 2), zero, 0.0, scratch.get(), p_plus, unused);
  c.model().violation(q - qd * h + qdd * (h * h / 2), zero, 0.0, scratch.get(), p_minus, unused);
  c.model().violation(q, zero, 0.0, scratch.get(), p0, unused);
  const VectorXd second = (p_plus - 2.0 * p0 + p_minus) / (h * h);
  const VectorXd expected = A * qdd - b;
  EXPECT_NEAR((second - expected).norm() / (1.0 + expected.norm()), 0.0, 1e-5);
}

TEST(TreeFrameConstraints, AccelerationFormsAgreeWithDifferencesOfTheViolation) {
  const Tree tree = load_urdf(kPanda);
  const Index tool = tree.link_index("panda_tool"), l3 = tree.link_index("panda_link3");
  const VectorXd q = arm_pose();
  VectorXd qd(7);
  qd << 0.4, -0.3, 0.5, 0.2, -0.6, 0.3, 0.7;
  SystemBuilder sb = system_builder(tree);
  sb.add(point_constraint(tree, "ball", {tool, Vector3d(0.01, 0.02, 0.05)},
                          {-1, Vector3d(0.4, 0.1, 0.5)}));
  sb.add(distance_constraint(tree, "rod", {tool, Vector3d(0, 0, 0.05)}, {l3, Vector3d(0.1, 0, 0)},
                             0.5));
  const System sys = sb.build();
  expect_acceleration_form_consistent(sys, 0, q, qd);
  expect_acceleration_form_consistent(sys, 1, q, qd);
}

// a distance closure from the tool to a world point, simulated: held to 1e-9 m, energy kept
TEST(TreeFrameConstraints, DistanceLoopClosureHoldsTheArm) {
  const Tree tree = load_urdf(kPanda);
  const Index tool = tree.link_index("panda_tool");
  const VectorXd q0 = arm_pose();
  TreeData d(tree);
  forward_kinematics(tree, q0, d);
  const Vector3d p_tool = world_point(d, tool, Vector3d::Zero());
  const Vector3d anchor = p_tool + Vector3d(0.0, 0.0, 0.3);
  SystemBuilder sb = system_builder(tree);
  sb.add(distance_constraint(tree, "rod", {tool, Vector3d::Zero()}, {-1, anchor}, 0.3));
  const System sys = sb.build();
  SimulationOptions options;
  options.t_end = 0.5;
  const Trajectory tr = simulate(sys, q0, VectorXd::Zero(7), options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  for (Index s = 0; s < tr.samples(); ++s) {
    forward_kinematics(tree, Eigen::Map<const VectorXd>(tr.q.data() + s * 7, 7), d);
    EXPECT_NEAR((world_point(d, tool, Vector3d::Zero()) - anchor).norm(), 0.3, 1e-9);
  }
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, 1e-6);
}

TEST(TreeFrameConstraints, RefusesBadPointsNamingTheConstraint) {
  const Tree tree = load_urdf(kPanda);
  try {
    point_constraint(tree, "loop", {-1, Vector3d::Zero()}, {-1, Vector3d::Ones()});
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'loop': both points are on the world"), std::string::npos)
        << e.what();
  }
  try {
    distance_constraint(tree, "rod", {2, Vector3d::Zero()}, {99, Vector3d::Zero()}, 0.1);
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'rod': link 99 of point b out of range"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(distance_constraint(tree, "rod", {2, Vector3d::Zero()}, {-1, Vector3d::Zero()}, 0),
               std::invalid_argument);
}

// ---- weld and revolute loop closures ---------------------------------------------------------

TEST(TreeFrameConstraints, WeldAndRevoluteAccelerationFormsAgreeWithDifferences) {
  const Tree tree = load_urdf(kPanda);
  const Index tool = tree.link_index("panda_tool"), l3 = tree.link_index("panda_link3");
  const Matrix3d Ra = Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Matrix3d Rb = Eigen::AngleAxisd(-0.4, Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  const VectorXd q = arm_pose();
  VectorXd qd(7);
  qd << 0.4, -0.3, 0.5, 0.2, -0.6, 0.3, 0.7;
  SystemBuilder sb = system_builder(tree);
  sb.add(weld_constraint(tree, "glue", {tool, Vector3d(0.01, 0.02, 0.05), Ra},
                         {l3, Vector3d(0.1, 0, 0.2), Rb}));
  sb.add(weld_constraint(tree, "fix", {-1, Vector3d(0.3, 0.1, 0.4), Rb},
                         {tool, Vector3d(0, 0, 0.1), Ra}));
  sb.add(revolute_constraint(tree, "hinge", {tool, Vector3d(0.01, 0.02, 0.05)},
                             Vector3d(0.2, 1, 0.3), {l3, Vector3d(0.1, 0, 0.2)},
                             Vector3d(1, 0, 0)));
  sb.add(revolute_constraint(tree, "pin", {-1, Vector3d(0.3, 0.1, 0.4)}, Vector3d(0, 0, 1),
                             {tool, Vector3d(0, 0.05, 0)}, Vector3d(0, 1, 1)));
  const System sys = sb.build();
  ASSERT_EQ(sys.constraint(0).rows(), 6);
  ASSERT_EQ(sys.constraint(2).rows(), 5);
  for (Index k = 0; k < 4; ++k) expect_acceleration_form_consistent(sys, k, q, qd);
}

// the arm with joint 4 welded where it starts (fixed origin R_PJ · Rot(axis, q4)): the tree the
// weld closure must reproduce
Tree arm_with_joint4_fixed(const Tree& arm, double q4) {
  std::vector<Link> links;
  for (Index i = 0; i < arm.link_count(); ++i) links.push_back(arm.link(i));
  Joint& j = links[std::size_t(arm.link_index("panda_link4"))].joint;
  j.R_PJ = j.R_PJ * Eigen::Quaterniond(Eigen::AngleAxisd(q4, j.axis));
  j.kind = JointKind::kFixed;
  return Tree("arm6", links, arm.gravity());
}

// a weld between link 4 and link 3 at their initial relative pose closes a loop around joint 4:
// the constrained arm moves as the 6-joint arm with joint 4 fixed, at every state (q'') and
// along 0.5 s of motion
TEST(TreeFrameConstraints, AWeldClosureMovesAsTheTreeWithTheJointRemoved) {
  const Tree arm = load_urdf(kPanda);
  const Index l3 = arm.link_index("panda_link3"), l4 = arm.link_index("panda_link4");
  const VectorXd q0 = arm_pose();
  TreeData d(arm);
  forward_kinematics(arm, q0, d);
  // link 4's frame in link 3's frame
  const Matrix3d& R3 = d.R_WL[std::size_t(l3)];
  const LinkFrame at3{l3, R3.transpose() * (d.p_WL[std::size_t(l4)] - d.p_WL[std::size_t(l3)]),
                      R3.transpose() * d.R_WL[std::size_t(l4)]};
  SystemBuilder sb = system_builder(arm);
  sb.add(weld_constraint(arm, "elbow_lock", {l4, Vector3d::Zero(), Matrix3d::Identity()}, at3));
  const System welded = sb.build();
  const Tree arm6 = arm_with_joint4_fixed(arm, q0[3]);
  ASSERT_EQ(arm6.coordinate_count(), 6);
  const System reduced = make_system(arm6);
  Workspace ws(welded), ws6(reduced);
  const auto full = [&](const VectorXd& x6) {  // 6 coordinates → 7, joint 4 at q0[3]
    VectorXd x(7);
    x << x6.head<3>(), 0.0, x6.tail<3>();
    return x;
  };
  std::mt19937 rng(30);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  double worst = 0;
  for (int state = 0; state < 20; ++state) {
    VectorXd q6(6), qd6(6);
    for (Index i = 0; i < 6; ++i) q6[i] = 1.5 * U(rng), qd6[i] = U(rng);
    VectorXd q = full(q6);
    q[3] = q0[3];
    ASSERT_EQ(forward_dynamics(welded, ws, q, full(qd6), 0.0), Status::kOk);
    ASSERT_EQ(forward_dynamics(reduced, ws6, q6, qd6, 0.0), Status::kOk);
    const VectorXd expected = full(ws6.qdd);
    const double e = (ws.qdd - expected).cwiseAbs().maxCoeff() / expected.cwiseAbs().maxCoeff();
    EXPECT_NEAR(e, 0.0, 1e-10) << "state " << state;
    worst = std::max(worst, e);
  }
  // 0.5 s from the same state, both at tight tolerances
  VectorXd qd0(7);
  qd0 << 0.4, -0.3, 0.5, 0.0, -0.6, 0.3, 0.7;
  VectorXd q6(6), qd6(6);
  q6 << q0.head<3>(), q0.tail<3>();
  qd6 << qd0.head<3>(), qd0.tail<3>();
  SimulationOptions options;
  options.t_end = 0.5;
  options.rtol = 1e-11;
  options.atol = 1e-13;
  const Trajectory a = simulate(welded, q0, qd0, options);
  const Trajectory b = simulate(reduced, q6, qd6, options);
  ASSERT_EQ(a.stats.status, Status::kOk) << a.stats.message;
  ASSERT_EQ(b.stats.status, Status::kOk) << b.stats.message;
  const Eigen::Map<const VectorXd> qa(a.q.data() + (a.samples() - 1) * 7, 7),
      qb(b.q.data() + (b.samples() - 1) * 6, 6);
  VectorXd qb7 = full(qb);
  qb7[3] = q0[3];
  EXPECT_NEAR((qa - qb7).cwiseAbs().maxCoeff(), 0.0, 1e-8);
  EXPECT_GT((qa - q0).cwiseAbs().maxCoeff(), 0.1);  // the arm did move
  EXPECT_NEAR(a.stats.energy_balance, 0.0, 1e-8);
  std::printf("weld closure vs the tree with joint 4 fixed: q'' %.2e, q(0.5 s) %.2e rad\n", worst,
              (qa - qb7).cwiseAbs().maxCoeff());
}

// the shared benchmark problem P2 (bench/data/README.md: crank-rocker four-bar, thin rods of
// 1 kg/m, released at rest with the crank at 150°) written as a tree of three hinges about z —
// crank and coupler in series from A = (0, 0), the rocker from D = (1, 0) — closed by a revolute
// loop at the coupler's tip: RK4 at h = 1e-3 as the shared protocol reaches the reference crank
// angle 3.1507615 rad at T = 10 s, with the loop held exactly
TEST(TreeFrameConstraints, ARevoluteClosureMakesTheSharedFourBarP2) {
  const double phi_crank = 2.6179938779914944, phi_coupler = 0.5636248679942388,
               phi_rocker = 2.1154295795750078;
  const auto rod = [](const std::string& name, const std::string& parent, const Vector3d& at,
                      double turn, double length) {
    Link l;
    l.name = name;
    l.parent = parent;
    l.joint.name = name;
    l.joint.kind = JointKind::kRevolute;
    l.joint.axis = Vector3d::UnitZ();
    l.joint.p_PJ = at;
    l.joint.R_PJ = Eigen::Quaterniond(Eigen::AngleAxisd(turn, Vector3d::UnitZ()));
    l.inertial.mass = length;  // 1 kg/m
    l.inertial.com = Vector3d(length / 2, 0, 0);
    const double I = length * length * length / 12;
    l.inertial.I_com = Vector3d(1e-9, I, I).asDiagonal();
    return l;
  };
  const Tree four_bar("P2",
                      {rod("crank", "", Vector3d::Zero(), phi_crank, 0.3),
                       rod("coupler", "crank", Vector3d(0.3, 0, 0), phi_coupler - phi_crank, 1.0),
                       rod("rocker", "", Vector3d(1, 0, 0), phi_rocker, 0.8)},
                      Vector3d(0, -9.81, 0));
  const Index coupler = four_bar.link_index("coupler"), rocker = four_bar.link_index("rocker");
  SystemBuilder sb = system_builder(four_bar);
  sb.add(revolute_constraint(four_bar, "tip", {coupler, Vector3d(1, 0, 0)}, Vector3d::UnitZ(),
                             {rocker, Vector3d(0.8, 0, 0)}, Vector3d::UnitZ()));
  const System sys = sb.build();
  SimulationOptions options;
  options.integrator = Integrator::kRK4;
  options.step = 1e-3;
  options.t_end = 10.0;
  options.output_every = 0.1;
  const Trajectory tr = simulate(sys, VectorXd::Zero(3), VectorXd::Zero(3), options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  TreeData d(four_bar);
  double worst_gap = 0;
  for (Index s = 0; s < tr.samples(); ++s) {
    forward_kinematics(four_bar, Eigen::Map<const VectorXd>(tr.q.data() + s * 3, 3), d);
    const Vector3d gap =
        world_point(d, coupler, Vector3d(1, 0, 0)) - world_point(d, rocker, Vector3d(0.8, 0, 0));
    worst_gap = std::max(worst_gap, gap.norm());
  }
  const double crank_T = phi_crank + tr.q[std::size_t((tr.samples() - 1) * 3)];
  EXPECT_NEAR(crank_T, 3.1507615, 1e-6);
  EXPECT_NEAR(worst_gap, 0.0, 1e-10);
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, 1e-6);
  std::printf(
      "P2 as a tree + revolute closure: crank at T %.10f rad (reference 3.1507615), loop "
      "%.2e m\n",
      crank_T, worst_gap);
}

TEST(TreeFrameConstraints, RefusesABadWeldFrameOrHingeAxis) {
  const Tree tree = load_urdf(kPanda);
  Matrix3d shear = Matrix3d::Identity();
  shear(0, 1) = 0.1;
  try {
    weld_constraint(tree, "glue", {2, Vector3d::Zero(), shear}, {-1});
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'glue': the orientation of frame a is not a rotation"),
              std::string::npos)
        << e.what();
  }
  try {
    revolute_constraint(tree, "hinge", {2}, Vector3d::UnitZ(), {-1}, Vector3d::Zero());
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'hinge': axis b must be a finite, nonzero vector"),
              std::string::npos)
        << e.what();
  }
}

// ---- exact task-space tracking of the redundant arm -----------------------------------------

// the tool point's path: a closed curve of a few cm and a rotation about a tilted world axis,
// each starting at rest (v = w = 0 at t = 0) from the arm's initial pose
struct ToolPath {
  Vector3d p0;
  Matrix3d R0;
  double r = 0.06, omega = 2.0 * M_PI, tilt = 0.4;
  Vector3d axis = Vector3d(1.0, 2.0, 2.0) / 3.0;
  void operator()(double t, PoseSample& d) const {
    const double c = std::cos(omega * t), s = std::sin(omega * t);
    const double c2 = std::cos(2 * omega * t), s2 = std::sin(2 * omega * t);
    // p = p0 + r [1 − cos ωt, (1 − cos 2ωt)/2, 0.3 (1 − cos ωt)]
    d.p = p0 + r * Vector3d(1 - c, 0.5 * (1 - c2), 0.3 * (1 - c));
    d.v = r * omega * Vector3d(s, s2, 0.3 * s);
    d.a = r * omega * omega * Vector3d(c, 2 * c2, 0.3 * c);
    // R = Rot(axis, θ) R0, θ = tilt (1 − cos ωt): w = axis θ', w' = axis θ''
    const double th = tilt * (1 - c), th1 = tilt * omega * s, th2 = tilt * omega * omega * c;
    d.R = Eigen::AngleAxisd(th, axis).toRotationMatrix() * R0;
    d.w = axis * th1;
    d.w_dot = axis * th2;
  }
};

struct TrackingRun {
  Tree tree = load_urdf(kPanda);
  ControlledTrajectory run;
  ToolPath path;
  Index tool = -1;
  std::shared_ptr<const Controller> ctrl;
};

TrackingRun track_tool(double t_end) {
  TrackingRun out;
  const Tree& tree = out.tree;
  out.tool = tree.link_index("panda_tool");
  const VectorXd q0 = arm_pose();
  TreeData d(tree);
  forward_kinematics(tree, q0, d);
  out.path.p0 = world_point(d, out.tool, Vector3d::Zero());
  out.path.R0 = d.R_WL[std::size_t(out.tool)];
  const System plant = make_system(tree);
  // 6 task rows and 1 posture row (joint 3, the arm's redundancy, held at its start) = 7 DOF
  const double q3 = q0[2];
  out.ctrl = std::make_shared<const Controller>(
      ControllerBuilder(plant)
          .require(pose_requirement(tree, "tool", {out.tool, Vector3d::Zero()}, out.path),
                   ErrorDynamics::second_order(20.0, 1.0))
          .require(holonomic("posture", 1,
                             [q3](const auto& q, const auto&, auto& e) { e[0] = q[2] - q3; }),
                   ErrorDynamics::second_order(20.0, 1.0))
          .build());
  SimulationOptions options;
  options.t_end = t_end;
  options.rtol = 1e-11;
  options.atol = 1e-13;
  out.run = simulate_controlled(*out.ctrl, plant, q0, VectorXd::Zero(7), options);
  return out;
}

// The errors a controlled run reports at its samples are the requirements' violations at the
// sample's state, bit for bit as a workspace of their own evaluates them (the run takes them
// from its assembly of the requirements there, which called the same violation()).
TEST(TreeTaskSpace, SampleErrorsAreTheRequirementsViolationsBitForBit) {
  const TrackingRun r = track_tool(0.2);
  const ControlledTrajectory& run = r.run;
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  const System& req = r.ctrl->requirements();
  Workspace ws(req);
  const Index N = run.samples(), n = 7, m = req.constraint_rows();
  ASSERT_EQ(m, 7);
  ASSERT_GT(N, 10);
  double largest = 0.0;
  for (Index s = 0; s < N; ++s) {
    const Eigen::Map<const VectorXd> q(run.plant.q.data() + s * n, n),
        qd(run.plant.qd.data() + s * n, n);
    evaluate_violations(req, ws, q, qd, run.plant.t[std::size_t(s)]);
    for (Index i = 0; i < m; ++i) {
      EXPECT_EQ(run.error[std::size_t(s * m + i)], ws.phi[i]) << s << ' ' << i;
      EXPECT_EQ(run.error_rate[std::size_t(s * m + i)], ws.phi_dot[i]) << s << ' ' << i;
      largest = std::max(largest, std::abs(ws.phi_dot[i]));
    }
  }
  EXPECT_GT(largest, 0.0);  // (not all zero: the comparison is not trivially met)
}

TEST(TreeTaskSpace, RedundantArmFollowsACartesianPoseExactly) {
  const TrackingRun r = track_tool(1.0);
  const Tree& tree = r.tree;
  const ControlledTrajectory& run = r.run;
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  EXPECT_EQ(run.control.not_met, 0);
  const Index N = run.samples(), n = 7;
  ASSERT_GT(N, 50);
  TreeData d(tree);
  VectorXd tau(n), damping(n);
  for (Index j = 0; j < n; ++j) damping[j] = tree.link(j + 1).joint.damping;
  double worst_p = 0, worst_R = 0, worst_tau = 0, tau_scale = 0, travel = 0;
  for (Index s = 0; s < N; ++s) {
    const Eigen::Map<const VectorXd> q(run.plant.q.data() + s * n, n),
        qd(run.plant.qd.data() + s * n, n), qdd(run.plant.qdd.data() + s * n, n),
        Qc(run.Qc_control.data() + s * n, n);
    // the pose achieved, against the path (independent of the requirement's own error)
    PoseSample want;
    r.path(run.plant.t[std::size_t(s)], want);
    forward_kinematics(tree, q, d);
    worst_p = std::max(worst_p, (world_point(d, r.tool, Vector3d::Zero()) - want.p).norm());
    const Eigen::AngleAxisd err(want.R.transpose() * d.R_WL[std::size_t(r.tool)]);
    worst_R = std::max(worst_R, std::abs(err.angle()));
    travel = std::max(travel, (want.p - r.path.p0).norm());
    // the control torques are the inverse dynamics of the motion achieved (plus the URDF's
    // joint dampers, which they overcome): Qc = M q'' + h + D q'
    inverse_dynamics(tree, q, qd, qdd, d, tau);
    tau += damping.cwiseProduct(qd);
    worst_tau = std::max(worst_tau, (Qc - tau).cwiseAbs().maxCoeff());
    tau_scale = std::max(tau_scale, Qc.cwiseAbs().maxCoeff());
  }
  EXPECT_GT(travel, 0.1);     // the tool travelled (the test is not trivially met)
  EXPECT_GT(tau_scale, 1.0);  // and the control carried gravity
  EXPECT_NEAR(worst_p, 0.0, 1e-8);
  EXPECT_NEAR(worst_R, 0.0, 1e-8);
  EXPECT_NEAR(worst_tau / tau_scale, 0.0, 1e-9);
  std::printf(
      "task-space tracking: position %.2e m, orientation %.2e rad, Qc − RNEA %.2e "
      "(relative to %.1f N·m)\n",
      worst_p, worst_R, worst_tau / tau_scale, tau_scale);
}

// the weighted law with a given N and the position rows only (3 of 7 DOF): the point still
// follows exactly, and the force is the N-weighted least one: N Qc lies in the row space of
// X = A_r M⁻¹ (the necessary condition of min Qcᵀ N Qc subject to X Qc = e)
TEST(TreeTaskSpace, PositionOnlyUnderTheWeightedLaw) {
  const Tree tree = load_urdf(kPanda);
  const Index tool = tree.link_index("panda_tool");
  const VectorXd q0 = arm_pose();
  TreeData d(tree);
  forward_kinematics(tree, q0, d);
  ToolPath path;
  path.p0 = world_point(d, tool, Vector3d::Zero());
  path.R0 = d.R_WL[std::size_t(tool)];
  const System plant = make_system(tree);
  const VectorXd weights = VectorXd::LinSpaced(7, 1.0, 7.0);
  const MatrixXd N = weights.asDiagonal();
  const Constraint req = pose_requirement(tree, "tool", {tool, Vector3d::Zero()}, path, false);
  ASSERT_EQ(req.rows(), 3);
  const Controller ctrl = ControllerBuilder(plant)
                              .require(req, ErrorDynamics::second_order(20.0, 1.0))
                              .weighted(N)
                              .build();
  SimulationOptions options;
  options.t_end = 0.5;
  options.rtol = 1e-11;
  options.atol = 1e-13;
  const ControlledTrajectory run = simulate_controlled(ctrl, plant, q0, VectorXd::Zero(7), options);
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  double worst_p = 0, worst_opt = 0;
  MatrixXd M(7, 7);
  Eigen::Matrix<double, 6, Eigen::Dynamic> J(6, 7);
  for (Index s = 0; s < run.samples(); ++s) {
    const Eigen::Map<const VectorXd> q(run.plant.q.data() + s * 7, 7),
        Qc(run.Qc_control.data() + s * 7, 7);
    PoseSample want;
    path(run.plant.t[std::size_t(s)], want);
    mass_matrix(tree, q, d, M);
    frame_jacobian(tree, d, tool, Vector3d::Zero(), J);
    worst_p = std::max(worst_p, (world_point(d, tool, Vector3d::Zero()) - want.p).norm());
    // N Qc = Xᵀ y for some y: its residual after projection on range(Xᵀ) vanishes
    const MatrixXd Xt = M.llt().solve(J.bottomRows<3>().transpose());
    const VectorXd NQc = N * Qc;
    const VectorXd y = Xt.colPivHouseholderQr().solve(NQc);
    worst_opt = std::max(worst_opt, (Xt * y - NQc).norm() / (1.0 + NQc.norm()));
  }
  EXPECT_NEAR(worst_p, 0.0, 1e-8);
  EXPECT_NEAR(worst_opt, 0.0, 1e-9);
}

TEST(TreeTaskSpace, EffortAndJointLimitsAreReportedNotClipped) {
  const TrackingRun r = track_tool(0.5);
  ASSERT_EQ(r.run.plant.stats.status, Status::kOk) << r.run.plant.stats.message;
  const Index n = 7, N = r.run.samples();
  // Panda's efforts (87, 12 N·m) hold: nothing to report
  EXPECT_TRUE(check_effort_limits(r.tree, r.run.plant.t, r.run.Qc_control).empty());
  // the same arm with joint 2's effort lowered below what the motion needs, and joint 4's
  // upper limit moved below where it starts
  std::vector<Link> links;
  for (Index i = 0; i < r.tree.link_count(); ++i) links.push_back(r.tree.link(i));
  double peak = 0, first = -1, worst_t = 0;
  for (Index s = 0; s < N; ++s) {
    const double v = std::abs(r.run.Qc_control[std::size_t(s * n + 1)]);
    if (v > peak) peak = v, worst_t = r.run.plant.t[std::size_t(s)];
  }
  const double effort = 0.8 * peak;
  for (Index s = 0; s < N && first < 0; ++s) {
    if (std::abs(r.run.Qc_control[std::size_t(s * n + 1)]) > effort)
      first = r.run.plant.t[std::size_t(s)];
  }
  links[2].joint.effort = effort;
  ASSERT_EQ(links[2].joint.name, "panda_joint2");
  links[4].joint.upper = -2.0;  // panda_joint4 starts at −1.9
  ASSERT_EQ(links[4].joint.name, "panda_joint4");
  const Tree weak("weak", links, r.tree.gravity());
  const auto excess = check_effort_limits(weak, r.run.plant.t, r.run.Qc_control);
  ASSERT_EQ(excess.size(), 1u);
  EXPECT_EQ(excess[0].joint, "panda_joint2");
  EXPECT_NEAR(excess[0].excess, peak - effort, 1e-12 * peak);
  EXPECT_NEAR(excess[0].first_time, first, 1e-12);
  EXPECT_NEAR(excess[0].worst_time, worst_t, 1e-12);
  EXPECT_NE(describe(excess[0]).find("joint 'panda_joint2' exceeds its effort limit"),
            std::string::npos)
      << describe(excess[0]);
  const auto limits = check_joint_limits(weak, r.run.plant.t, r.run.plant.q);
  ASSERT_EQ(limits.size(), 1u);
  EXPECT_EQ(limits[0].joint, "panda_joint4");
  EXPECT_EQ(limits[0].limit, "upper");
  EXPECT_NEAR(limits[0].first_time, 0.0, 1e-15);
  double q4_max = -10;
  for (Index s = 0; s < N; ++s) q4_max = std::max(q4_max, r.run.plant.q[std::size_t(s * n + 3)]);
  EXPECT_NEAR(limits[0].excess, q4_max + 2.0, 1e-14);
  EXPECT_THROW(check_joint_limits(weak, r.run.plant.t, std::vector<double>(3)),
               std::invalid_argument);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::tree

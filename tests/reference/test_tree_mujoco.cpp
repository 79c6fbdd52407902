// SPDX-License-Identifier: BSD-3-Clause
// The kinematic tree against MuJoCo 2.2.2 (issue #30 item 3): M(q) and the bias forces
// (qfrc_bias) at 100 random states, the forward dynamics with the URDF's damping, and 0.5 s of
// RK4 from the same state; a branched floating-base tree's accelerations at 100 random states.
//
// Two routes into MuJoCo. (1) mj_loadXML on the .urdf itself (fixed links fused into their
// parents, armature 0, the URDF's damping as dof_damping): MuJoCo's compiler diagonalizes each
// full inertia tensor with its own iterative eigensolver and keeps the principal axes only to
// about 1e-8, so this route agrees to 1e-7. (2) The same tree written as MJCF by the test, each
// inertia as diaginertia + quat from Eigen's eigensolver at full precision and no joint limits
// (so that MuJoCo's limit constraints stay out of the 0.5 s run): agreement to 1e-12.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <Eigen/Eigenvalues>

#include <gtest/gtest.h>

#include <mujoco/mujoco.h>

#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/multibody/tree.hpp"

#include "reference/tree_mjcf.hpp"

namespace ukdyn::tree {
namespace UKDYN_TEST_FILE {

const std::string kPanda = std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf";

// the tree as exact MJCF (tree_mjcf.hpp)
std::string write_mjcf(const Tree& tree) { return reference::write_tree_mjcf(tree); }

struct MuJoCo {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  explicit MuJoCo(const std::string& file) {
    char error[1000] = "";
    m = mj_loadXML(file.c_str(), nullptr, error, int(sizeof error));
    mj_freeLastXML();
    if (m) d = mj_makeData(m);
    EXPECT_NE(m, nullptr) << error;
  }
  ~MuJoCo() {
    if (d) mj_deleteData(d);
    if (m) mj_deleteModel(m);
  }
};

double max_abs(const MatrixXd& a) { return a.cwiseAbs().maxCoeff(); }

// the largest relative differences of M and h to MuJoCo's over 100 random states
std::pair<double, double> compare_at_random_states(const Tree& tree, MuJoCo& mj, double tol) {
  EXPECT_NE(mj.m, nullptr);
  if (!mj.m) return {1, 1};
  const Index n = tree.coordinate_count();
  EXPECT_EQ(mj.m->nq, n);
  if (mj.m->nq != n || mj.m->nv != n) return {1, 1};
  for (Index i = 0; i < n; ++i) {
    EXPECT_EQ(mj.m->dof_armature[i], 0.0);
    // the same joints in the same order
    EXPECT_EQ(std::string(mj_id2name(mj.m, mjOBJ_JOINT, int(i))), tree.coordinate_names()[i]);
  }
  TreeData data(tree);
  std::mt19937 rng(30);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  MatrixXd M(n, n), M_mj(n, n);
  VectorXd q(n), qd(n), h(n);
  double worst_M = 0, worst_h = 0;
  for (int state = 0; state < 100; ++state) {
    for (Index i = 0; i < n; ++i) {
      q[i] = 3.0 * U(rng);
      qd[i] = 2.0 * U(rng);
    }
    for (Index i = 0; i < n; ++i) mj.d->qpos[i] = q[i], mj.d->qvel[i] = qd[i];
    mj_forward(mj.m, mj.d);
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> dense(n, n);
    mj_fullM(mj.m, dense.data(), mj.d->qM);
    M_mj = dense;
    const Eigen::Map<const VectorXd> h_mj(mj.d->qfrc_bias, n);
    mass_matrix(tree, q, data, M);
    bias_forces(tree, q, qd, data, h);
    const double eM = max_abs(M - M_mj) / max_abs(M_mj), eh = max_abs(h - h_mj) / max_abs(h_mj);
    EXPECT_NEAR(eM, 0.0, tol) << "state " << state;
    EXPECT_NEAR(eh, 0.0, tol) << "state " << state;
    worst_M = std::max(worst_M, eM);
    worst_h = std::max(worst_h, eh);
  }
  return {worst_M, worst_h};
}

TEST(TreeMuJoCo, PandaUrdfLoadedByMuJoCo) {
  MuJoCo mj(kPanda);
  const auto [eM, eh] = compare_at_random_states(load_urdf(kPanda), mj, 1e-7);
  std::printf("URDF loaded by MuJoCo, 100 states: largest relative difference M %.2e, h %.2e\n", eM,
              eh);
}

TEST(TreeMuJoCo, PandaAsExactMjcf) {
  const Tree tree = load_urdf(kPanda);
  MuJoCo mj(write_mjcf(tree));
  const auto [eM, eh] = compare_at_random_states(tree, mj, 1e-12);
  std::printf("same tree as MJCF, 100 states: largest relative difference M %.2e, h %.2e\n", eM,
              eh);
}

TEST(TreeMuJoCo, PandaForwardDynamicsAndRk4Run) {
  const Tree tree = load_urdf(kPanda);
  MuJoCo mj(write_mjcf(tree));
  ASSERT_NE(mj.m, nullptr);
  const System sys = make_system(tree);
  const Index n = tree.coordinate_count();
  for (Index i = 0; i < n; ++i) {
    EXPECT_EQ(mj.m->dof_damping[i], tree.link(i + 1).joint.damping);
  }
  Workspace ws(sys);
  VectorXd q(n), qd(n);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd << 0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3;
  for (Index i = 0; i < n; ++i) mj.d->qpos[i] = q[i], mj.d->qvel[i] = qd[i];
  mj_forward(mj.m, mj.d);
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
  const Eigen::Map<const VectorXd> qacc(mj.d->qacc, n);
  EXPECT_NEAR(max_abs(ws.qdd - qacc) / max_abs(qacc), 0.0, 1e-11);
  // 0.5 s of classical RK4 at h = 1 ms in both (MuJoCo's mjINT_RK4; ours by hand)
  mj.m->opt.integrator = mjINT_RK4;
  mj.m->opt.timestep = 1e-3;
  const auto f = [&](const VectorXd& x, VectorXd& dx) {
    EXPECT_EQ(forward_dynamics(sys, ws, x.head(n), x.tail(n), 0.0), Status::kOk);
    dx << x.tail(n), ws.qdd;
  };
  VectorXd x(2 * n), k1(2 * n), k2(2 * n), k3(2 * n), k4(2 * n);
  x << q, qd;
  const double dt = 1e-3;
  for (int step = 0; step < 500; ++step) {
    f(x, k1);
    f(x + 0.5 * dt * k1, k2);
    f(x + 0.5 * dt * k2, k3);
    f(x + dt * k3, k4);
    x += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    mj_step(mj.m, mj.d);
  }
  const Eigen::Map<const VectorXd> q_mj(mj.d->qpos, n), qd_mj(mj.d->qvel, n);
  const double eq = max_abs(x.head(n) - q_mj), ev = max_abs(x.tail(n) - qd_mj);
  EXPECT_NEAR(eq, 0.0, 1e-10);
  EXPECT_NEAR(ev, 0.0, 1e-9);
  // the arm did move: the comparison is not of two resting states
  EXPECT_GT(max_abs(x.head(n) - q), 0.1);
  std::printf("after 0.5 s of RK4: |q - q_MuJoCo| %.2e rad, |q' - q'_MuJoCo| %.2e rad/s\n", eq, ev);
}

// a branched floating-base tree (two arms, revolute, prismatic and fixed joints, full
// inertias): ukdyn's constrained q'' (the unit-quaternion constraint completing the singular M)
// against MuJoCo's qacc. MuJoCo's free joint: qvel = (p' in the world, ω in the body frame), so
// ω_L = 2 E(u) u' and ω'_L = 2 E(u) u'' (2 E(u') u' = 0).
Tree branched_floating_tree() {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const auto inertial = [&](double mass) {
    Inertial in;
    in.mass = mass;
    in.com = 0.1 * Vector3d(U(rng), U(rng), U(rng));
    const Vector3d moments(0.03 + 0.005 * U(rng), 0.03 + 0.005 * U(rng), 0.03 + 0.005 * U(rng));
    const Matrix3d R =
        Eigen::Quaterniond(Eigen::Vector4d::Random().normalized()).toRotationMatrix();
    in.I_com = R * moments.asDiagonal() * R.transpose();
    return in;
  };
  std::vector<Link> links;
  const auto add = [&](const std::string& name, const std::string& parent, JointKind kind,
                       const Vector3d& axis, const Vector3d& p) {
    Link l;
    l.name = name;
    l.parent = parent;
    l.joint.name = name + "_joint";
    l.joint.kind = kind;
    l.joint.axis = axis;
    if (kind != JointKind::kFloating) {
      l.joint.p_PJ = p;
      l.joint.R_PJ =
          Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Vector3d(U(rng), U(rng), 1).normalized()));
    }
    l.inertial = inertial(1.0 + U(rng) * 0.5);
    links.push_back(l);
  };
  add("base", "", JointKind::kFloating, Vector3d::UnitZ(), Vector3d::Zero());
  add("l1", "base", JointKind::kRevolute, Vector3d(0, 1, 0.2), Vector3d(0.2, 0.1, 0));
  add("l2", "l1", JointKind::kPrismatic, Vector3d(1, 0, 0), Vector3d(0.3, 0, 0.05));
  add("l3", "l2", JointKind::kContinuous, Vector3d(0.1, 0.2, 1), Vector3d(0.1, 0.2, 0));
  add("tool", "l3", JointKind::kFixed, Vector3d::UnitZ(), Vector3d(0, 0, 0.1));
  add("r1", "base", JointKind::kRevolute, Vector3d(1, 0, 0), Vector3d(-0.2, -0.1, 0));
  add("r2", "r1", JointKind::kRevolute, Vector3d(0, 0, 1), Vector3d(-0.3, 0, 0));
  return Tree("floating_branched", links);
}

// the largest relative difference of ukdyn's q'' (in MuJoCo's velocity coordinates) to MuJoCo's
// qacc over random states, for a tree whose first link is floating
double compare_floating_accelerations(const Tree& tree, int states, double tol) {
  const Index n = tree.coordinate_count();
  MuJoCo mj(write_mjcf(tree));
  EXPECT_NE(mj.m, nullptr);
  if (!mj.m) return 1;
  EXPECT_EQ(mj.m->nq, n);
  EXPECT_EQ(mj.m->nv, n - 1);
  if (mj.m->nq != n || mj.m->nv != n - 1) return 1;
  const System sys = make_system(tree);
  Workspace ws(sys);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  double worst = 0;
  for (int state = 0; state < states; ++state) {
    VectorXd q(n), qd(n);
    for (Index i = 0; i < n; ++i) q[i] = U(rng), qd[i] = U(rng);
    q.segment<4>(3).normalize();
    const Eigen::Vector4d u = q.segment<4>(3);
    qd.segment<4>(3) -= u * u.dot(qd.segment<4>(3));  // u·u' = 0
    Eigen::Matrix<double, 3, 4> E;
    E << -u[1], u[0], u[3], -u[2], -u[2], -u[3], u[0], u[1], -u[3], u[2], -u[1], u[0];
    for (Index i = 0; i < n; ++i) mj.d->qpos[i] = q[i];
    for (int i = 0; i < 3; ++i) mj.d->qvel[i] = qd[i];
    const Vector3d w_L = 2 * E * qd.segment<4>(3);
    for (int i = 0; i < 3; ++i) mj.d->qvel[3 + i] = w_L[i];
    for (Index i = 7; i < n; ++i) mj.d->qvel[i - 1] = qd[i];
    mj_forward(mj.m, mj.d);
    EXPECT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
    VectorXd acc(n - 1);  // ukdyn's q'' in MuJoCo's velocity coordinates
    acc << ws.qdd.head<3>(), 2 * E * ws.qdd.segment<4>(3), ws.qdd.tail(n - 7);
    const Eigen::Map<const VectorXd> qacc(mj.d->qacc, n - 1);
    const double e = max_abs(acc - qacc) / max_abs(qacc);
    EXPECT_NEAR(e, 0.0, tol) << "state " << state;
    worst = std::max(worst, e);
  }
  return worst;
}

TEST(TreeMuJoCo, BranchedFloatingTreeAccelerations) {
  const Tree tree = branched_floating_tree();
  ASSERT_EQ(tree.coordinate_count(), 12);  // 7 + 5
  const double worst = compare_floating_accelerations(tree, 100, 1e-11);
  std::printf("floating branched tree, 100 states: largest relative difference of q'' %.2e\n",
              worst);
}

// the example humanoid (examples/robots/humanoid.urdf: 26 revolute joints on a floating pelvis,
// the tree of bench/bench_tree_step.cpp), its damping included
TEST(TreeMuJoCo, HumanoidAccelerations) {
  const Tree tree = load_urdf(std::string(UKDYN_ROBOTS_DIR) + "/humanoid.urdf");
  ASSERT_EQ(tree.coordinate_count(), 33);
  const double worst = compare_floating_accelerations(tree, 50, 1e-11);
  std::printf("humanoid (32 DOF), 50 states: largest relative difference of q'' %.2e\n", worst);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::tree

// SPDX-License-Identifier: BSD-3-Clause
// The tree passes' two paths for a 1-DOF joint (multibody/tree/spatial.hpp): an axis along a unit
// vector of the joint frame, where products with S are picks of one entry and the rotation turns
// two columns of R_PJ, and any other axis (the general products). The same mechanism written
// both ways — each joint frame twisted by a rotation Q_i, its axis, its child's inertial and its
// children's joint origins expressed in the twisted frame — has the same M, bias forces and world
// points at every state.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {
namespace UKDYN_TEST_FILE {

struct Spec {
  int axis;  // the axis e_k of the joint frame (3 + k: prismatic along e_k)
  Vector3d p_PJ, com;
  Eigen::Quaterniond R_PJ;
  double mass;
  Matrix3d I_com;
};

// a chain (every link's parent the one before) with joint frames twisted by Q[i]: axis Q_iᵀ e_k,
// R_PJ' = Q_{i−1}ᵀ R_PJ Q_i, p_PJ' = Q_{i−1}ᵀ p_PJ, com' = Q_iᵀ com, I' = Q_iᵀ I Q_i; link i's
// frame is then L_i Q_i (identity Q: the frame's own axes)
Tree chain(const std::vector<Spec>& specs, const std::vector<Matrix3d>& Q) {
  std::vector<Link> links;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const Spec& s = specs[i];
    const Matrix3d Qp = i == 0 ? Matrix3d::Identity() : Q[i - 1];
    Link l;
    l.name = "l" + std::to_string(i);
    l.parent = i == 0 ? "" : "l" + std::to_string(i - 1);
    l.joint.name = "j" + std::to_string(i);
    l.joint.kind = s.axis < 3 ? JointKind::kRevolute : JointKind::kPrismatic;
    l.joint.axis = Q[i].transpose() * Vector3d::Unit(s.axis % 3);
    l.joint.p_PJ = Qp.transpose() * s.p_PJ;
    l.joint.R_PJ = Eigen::Quaterniond(Matrix3d(Qp.transpose() * s.R_PJ.toRotationMatrix() * Q[i]));
    l.inertial.mass = s.mass;
    l.inertial.com = Q[i].transpose() * s.com;
    l.inertial.I_com = Q[i].transpose() * s.I_com * Q[i];
    links.push_back(l);
  }
  return Tree("chain", links, Vector3d(0.3, -0.2, -9.81));
}

TEST(TreePasses, UnitAxesAndTwistedFramesGiveTheSameDynamics) {
  std::vector<Spec> specs;
  const int axes[] = {2, 0, 1, 5, 2};  // z, x, y revolute, prismatic along z, z
  for (int i = 0; i < 5; ++i) {
    Spec s;
    s.axis = axes[i];
    s.p_PJ = Vector3d(0.1 * i, 0.05, 0.3 - 0.02 * i);
    s.com = Vector3d(0.02, -0.01 * i, 0.12);
    s.R_PJ = Eigen::Quaterniond(Eigen::AngleAxisd(0.4 + 0.3 * i, Vector3d(1, 2, 3).normalized()));
    s.mass = 1.0 + 0.5 * i;
    Matrix3d I;
    I << 0.04, 0.002, -0.001, 0.002, 0.05, 0.003, -0.001, 0.003, 0.03;
    s.I_com = I * (1.0 + 0.2 * i);
    specs.push_back(s);
  }
  std::vector<Matrix3d> identity(5, Matrix3d::Identity()), twisted;
  for (int i = 0; i < 5; ++i) {
    twisted.push_back(
        Eigen::AngleAxisd(0.7 + 0.4 * i, Vector3d(-1, 0.5 + i, 2).normalized()).toRotationMatrix());
  }
  const Tree unit = chain(specs, identity), general = chain(specs, twisted);
  // every axis of `unit` along its frame's axes, none of `general`'s
  for (Index i = 0; i < 5; ++i) {
    EXPECT_EQ(unit.link(i).joint.axis.cwiseAbs().maxCoeff(), 1.0);
    EXPECT_LT(general.link(i).joint.axis.cwiseAbs().maxCoeff(), 1.0 - 1e-3);
  }
  TreeData du(unit), dg(general);
  MatrixXd Mu(5, 5), Mg(5, 5);
  VectorXd hu(5), hg(5);
  for (int k = 0; k < 3; ++k) {
    VectorXd q(5), qd(5);
    for (int i = 0; i < 5; ++i) {
      q[i] = std::sin(1.3 * i + k) * (i == 3 ? 0.2 : 1.5);
      qd[i] = std::cos(0.7 * i - k) * 2.0;
    }
    mass_matrix(unit, q, du, Mu);
    mass_matrix(general, q, dg, Mg);
    bias_forces(unit, q, qd, du, hu);
    bias_forces(general, q, qd, dg, hg);
    EXPECT_LT((Mu - Mg).norm(), 1e-13 * Mu.norm()) << "state " << k;
    EXPECT_GT(Mu.norm(), 1.0);
    EXPECT_LT((hu - hg).norm(), 1e-13 * hu.norm()) << "state " << k;
    EXPECT_GT(hu.norm(), 1.0);
    // the same tip point in the world (its coordinates in link 4: com of the unit tree's link)
    const Vector3d pu = world_point(du, 4, specs[4].com);
    const Vector3d pg = world_point(dg, 4, twisted[4].transpose() * specs[4].com);
    EXPECT_LT((pu - pg).norm(), 1e-14 * (1.0 + pu.norm())) << "state " << k;
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::tree

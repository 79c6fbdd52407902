// SPDX-License-Identifier: BSD-3-Clause
// Centre of mass and momentum of a tree (multibody/tree/momentum.cpp): J_G against central
// differences of the centre of mass, l = m v_G, and the momentum [k_O; l] of a free branched
// tree in zero gravity conserved along a simulated motion (Newton and Euler for the whole).
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::tree {
namespace UKDYN_TEST_FILE {

const std::string kPanda = std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf";

TEST(TreeMomentum, CentreOfMassJacobianAgreesWithDifferences) {
  const Tree tree = load_urdf(kPanda);
  VectorXd q(7), qd(7);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd << 0.4, -0.3, 0.5, 0.2, -0.6, 0.3, 0.7;
  TreeData d(tree);
  // v_G by differences of p_WG along q'
  const double h = 1e-6;
  forward_kinematics(tree, q + h * qd, d);
  const Vector3d plus = center_of_mass(tree, d);
  forward_kinematics(tree, q - h * qd, d);
  const Vector3d minus = center_of_mass(tree, d);
  const Vector3d v_fd = (plus - minus) / (2 * h);
  forward_kinematics(tree, q, d);
  Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, 7);
  com_jacobian(tree, d, J);
  EXPECT_NEAR((J * qd - v_fd).norm(), 0.0, 1e-8 * v_fd.norm());
  EXPECT_GT(v_fd.norm(), 0.05);
  // the centre of mass by hand from two links' world points: total mass 1 + … (Gaz et al.)
  double m = 0;
  Vector3d sum = Vector3d::Zero();
  for (Index i = 0; i < tree.link_count(); ++i) {
    m += tree.link(i).inertial.mass;
    sum += tree.link(i).inertial.mass * world_point(d, i, tree.link(i).inertial.com);
  }
  EXPECT_NEAR(total_mass(tree), m, 1e-14 * m);
  EXPECT_NEAR((center_of_mass(tree, d) - sum / m).norm(), 0.0, 1e-15);
  // l = m_tot v_G
  const Vector6d hO = momentum(tree, q, qd, d);
  EXPECT_NEAR((hO.tail<3>() - m * J * qd).norm(), 0.0, 1e-12 * m * v_fd.norm());
  // ½ q'ᵀ M q' = ½ Σ (ω_i·I_i ω_i + m_i |v_i|²) is not the momentum, but a link alone is: one
  // joint turning (q' = e_7) moves only the last links about joint 7's axis a through p:
  // k_O = Σ (I_W ω + p_c × m v_c) with ω = a q', checked against the Jacobian of each link's com
  VectorXd e7 = VectorXd::Zero(7);
  e7[6] = 1.3;
  const Vector6d h7 = momentum(tree, q, e7, d);
  Vector3d k = Vector3d::Zero();
  Eigen::Matrix<double, 6, Eigen::Dynamic> Jl(6, 7);
  for (Index i = 0; i < tree.link_count(); ++i) {
    const Inertial& in = tree.link(i).inertial;
    frame_jacobian(tree, d, i, in.com, Jl);
    const Vector6d tw = Jl * e7;
    const Matrix3d& R = d.R_WL[std::size_t(i)];
    k += R * in.I_com * R.transpose() * tw.head<3>() +
         world_point(d, i, in.com).cross(in.mass * tw.tail<3>());
  }
  EXPECT_NEAR((h7.head<3>() - k).norm(), 0.0, 1e-13 * (1.0 + k.norm()));
  EXPECT_GT(k.norm(), 1e-3);
}

// a free branched tree (floating base, revolute and prismatic children) in zero gravity:
// nothing acts from outside, so [k_O; l] stays what it was
TEST(TreeMomentum, FreeTreeConservesItsMomentum) {
  std::vector<Link> links(3);
  links[0].name = "base";
  links[0].joint.name = "free";
  links[0].joint.kind = JointKind::kFloating;
  links[0].inertial.mass = 3.0;
  links[0].inertial.com = Vector3d(0.05, -0.02, 0.01);
  links[0].inertial.I_com << 0.2, 0.01, 0.0, 0.01, 0.3, 0.02, 0.0, 0.02, 0.25;
  links[1].name = "arm";
  links[1].parent = "base";
  links[1].joint.name = "hinge";
  links[1].joint.kind = JointKind::kRevolute;
  links[1].joint.axis = Vector3d(0, 1, 1);
  links[1].joint.p_PJ = Vector3d(0.3, 0, 0);
  links[1].inertial.mass = 1.0;
  links[1].inertial.com = Vector3d(0.2, 0, 0);
  links[1].inertial.I_com = Matrix3d::Identity() * 0.02;
  links[2].name = "slider";
  links[2].parent = "base";
  links[2].joint.name = "slide";
  links[2].joint.kind = JointKind::kPrismatic;
  links[2].joint.axis = Vector3d(0, 0, 1);
  links[2].joint.p_PJ = Vector3d(-0.2, 0.1, 0);
  links[2].inertial.mass = 0.5;
  links[2].inertial.I_com = Matrix3d::Identity() * 0.01;
  const Tree tree("free", links, Vector3d::Zero());
  ASSERT_EQ(tree.coordinate_count(), 9);
  VectorXd q0 = tree.neutral(), qd0 = VectorXd::Zero(9);
  // base: p' = (0.1, −0.2, 0.3), ω = (0.5, −0.4, 0.8) at u = 1 (u' = [0; ω/2]); joints moving
  qd0 << 0.1, -0.2, 0.3, 0.0, 0.25, -0.2, 0.4, 1.5, -0.7;
  TreeData d(tree);
  const Vector6d h0 = momentum(tree, q0, qd0, d);
  EXPECT_GT(h0.head<3>().norm(), 0.1);
  SimulationOptions options;
  options.t_end = 1.0;
  options.rtol = 1e-12;
  options.atol = 1e-14;
  const Trajectory tr = simulate(make_system(tree), q0, qd0, options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  double worst = 0;
  for (Index s = 0; s < tr.samples(); ++s) {
    const Vector6d hs = momentum(tree, Eigen::Map<const VectorXd>(tr.q.data() + s * 9, 9),
                                 Eigen::Map<const VectorXd>(tr.qd.data() + s * 9, 9), d);
    worst = std::max(worst, (hs - h0).norm());
  }
  EXPECT_NEAR(worst / h0.norm(), 0.0, 1e-8);
  // and the centre of mass moves uniformly: p_G(t) = p_G(0) + l t / m
  const Index N = tr.samples();
  forward_kinematics(tree, q0, d);
  const Vector3d G0 = center_of_mass(tree, d);
  forward_kinematics(tree, Eigen::Map<const VectorXd>(tr.q.data() + (N - 1) * 9, 9), d);
  const Vector3d G1 = center_of_mass(tree, d);
  EXPECT_NEAR((G1 - G0 - h0.tail<3>() / total_mass(tree) * tr.t.back()).norm(), 0.0, 1e-9);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::tree

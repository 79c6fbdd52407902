// SPDX-License-Identifier: BSD-3-Clause
// The kinematic tree in joint coordinates (multibody/tree.hpp): M, h, Jacobians and a floating
// base against closed forms and independent methods (Lagrange's equations by central
// differences of the CRBA's M and of the potential), the URDF loader's errors.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/simulation/simulate.hpp"

#include "support/urdf_errors.hpp"

namespace ukdyn::tree {
namespace UKDYN_TEST_FILE {

const std::string kPanda = std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf";

// a planar double pendulum swinging about y, full inertia tensors (only I_yy acts)
Tree double_pendulum(double m1, double m2, double L1, double c1, double c2, double I1, double I2) {
  Link a, b;
  a.name = "upper";
  a.joint.name = "shoulder";
  a.joint.kind = JointKind::kRevolute;
  a.joint.axis = Vector3d(0, 2, 0);  // normalized by the tree
  a.inertial.mass = m1;
  a.inertial.com = Vector3d(0, 0, -c1);
  a.inertial.I_com << 0.3, 0.01, 0.02, 0.01, I1, 0.03, 0.02, 0.03, 0.3;
  b.name = "lower";
  b.parent = "upper";
  b.joint.name = "elbow";
  b.joint.kind = JointKind::kContinuous;
  b.joint.axis = Vector3d::UnitY();
  b.joint.p_PJ = Vector3d(0, 0, -L1);
  b.inertial.mass = m2;
  b.inertial.com = Vector3d(0, 0, -c2);
  b.inertial.I_com << 0.2, -0.01, 0.0, -0.01, I2, 0.01, 0.0, 0.01, 0.2;
  return Tree("double_pendulum", {b, a});  // children may come first
}

double relative_error(const MatrixXd& a, const MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

TEST(Tree, DoublePendulumMatchesClosedForm) {
  const double m1 = 1.3, m2 = 0.7, L1 = 0.9, c1 = 0.4, c2 = 0.35, I1 = 0.05, I2 = 0.02, g = 9.81;
  const Tree tree = double_pendulum(m1, m2, L1, c1, c2, I1, I2);
  ASSERT_EQ(tree.coordinate_count(), 2);
  EXPECT_EQ(tree.link(0).name, "upper");  // parents first
  TreeData d(tree);
  const Eigen::Vector2d q(0.7, -1.1), qd(1.3, -0.4);
  MatrixXd M(2, 2);
  mass_matrix(tree, q, d, M);
  const double c = std::cos(q[1]), s = std::sin(q[1]);
  MatrixXd M_ref(2, 2);
  M_ref(0, 0) = I1 + I2 + m1 * c1 * c1 + m2 * (L1 * L1 + c2 * c2 + 2 * L1 * c2 * c);
  M_ref(0, 1) = M_ref(1, 0) = I2 + m2 * (c2 * c2 + L1 * c2 * c);
  M_ref(1, 1) = I2 + m2 * c2 * c2;
  EXPECT_LT(relative_error(M, M_ref), 1e-14);
  VectorXd h(2);
  bias_forces(tree, q, qd, d, h);
  // h = C q' + ∂V/∂q, V = −m1 g c1 cos θ1 − m2 g (L1 cos θ1 + c2 cos(θ1 + θ2))
  Eigen::Vector2d h_ref;
  h_ref[0] = -m2 * L1 * c2 * s * (2 * qd[0] * qd[1] + qd[1] * qd[1]) +
             m1 * g * c1 * std::sin(q[0]) +
             m2 * g * (L1 * std::sin(q[0]) + c2 * std::sin(q[0] + q[1]));
  h_ref[1] = m2 * L1 * c2 * s * qd[0] * qd[0] + m2 * g * c2 * std::sin(q[0] + q[1]);
  EXPECT_NEAR(h[0], h_ref[0], 1e-13 * h_ref.cwiseAbs().maxCoeff());
  EXPECT_NEAR(h[1], h_ref[1], 1e-13 * h_ref.cwiseAbs().maxCoeff());
}

// Lagrange: h = Ṁ q' − ½ ∂(q'ᵀ M q')/∂q + ∂V/∂q, by central differences of the CRBA's M and of
// V (from forward kinematics) — independent of the RNEA
TEST(Tree, PandaBiasForcesAreLagrangesEquations) {
  const Tree tree = load_urdf(kPanda);
  const Index n = tree.coordinate_count();
  ASSERT_EQ(n, 7);
  TreeData d(tree);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1.5, 1.5);
  const auto V = [&](const VectorXd& q) {
    forward_kinematics(tree, q, d);
    double v = 0;
    for (Index i = 0; i < tree.link_count(); ++i) {
      v -= tree.link(i).inertial.mass *
           tree.gravity().dot(world_point(d, i, tree.link(i).inertial.com));
    }
    return v;
  };
  for (int trial = 0; trial < 5; ++trial) {
    VectorXd q(n), qd(n);
    for (Index i = 0; i < n; ++i) q[i] = U(rng), qd[i] = U(rng);
    const double e = 1e-5;
    MatrixXd Mp(n, n), Mm(n, n), M(n, n);
    VectorXd h_ref = VectorXd::Zero(n);
    mass_matrix(tree, q + e * qd, d, Mp);
    mass_matrix(tree, q - e * qd, d, Mm);
    h_ref += (Mp - Mm) / (2 * e) * qd;  // Ṁ q'
    for (Index k = 0; k < n; ++k) {
      VectorXd dq = VectorXd::Zero(n);
      dq[k] = e;
      mass_matrix(tree, q + dq, d, Mp);
      mass_matrix(tree, q - dq, d, Mm);
      h_ref[k] -= 0.5 * qd.dot((Mp - Mm) * qd) / (2 * e);
      h_ref[k] += (V(q + dq) - V(q - dq)) / (2 * e);
    }
    VectorXd h(n);
    bias_forces(tree, q, qd, d, h);
    EXPECT_LT(relative_error(h, h_ref), 1e-8) << "trial " << trial;
    EXPECT_GT(relative_error(h, h_ref), 0.0);  // (a difference quotient is never exact)
    // and M is symmetric positive definite; τ = M q'' + h
    mass_matrix(tree, q, d, M);
    EXPECT_EQ((M - M.transpose()).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(Eigen::LLT<MatrixXd>(M).info(), Eigen::Success);
    VectorXd qdd(n), tau(n);
    for (Index i = 0; i < n; ++i) qdd[i] = U(rng);
    inverse_dynamics(tree, q, qd, qdd, d, tau);
    EXPECT_LT(relative_error(tau, M * qdd + h), 1e-13);
  }
}

TEST(Tree, FrameJacobianIsTheDerivativeOfForwardKinematics) {
  const Tree tree = load_urdf(kPanda);
  const Index n = tree.coordinate_count(), tool = tree.link_index("panda_tool");
  TreeData d(tree);
  VectorXd q(n), qd(n);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd << 0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3;
  const Vector3d p_L(0.02, -0.03, 0.08);
  forward_kinematics(tree, q, d);
  Eigen::Matrix<double, 6, Eigen::Dynamic> J(6, n);
  frame_jacobian(tree, d, tool, p_L, J);
  // central differences along q'
  const double e = 1e-6;
  forward_kinematics(tree, q + e * qd, d);
  const Vector3d pp = world_point(d, tool, p_L);
  const Matrix3d Rp = d.R_WL[std::size_t(tool)];
  forward_kinematics(tree, q - e * qd, d);
  const Vector3d pm = world_point(d, tool, p_L);
  const Matrix3d Rm = d.R_WL[std::size_t(tool)];
  forward_kinematics(tree, q, d);
  const Matrix3d W = (Rp - Rm) / (2 * e) * d.R_WL[std::size_t(tool)].transpose();  // [ω]×
  const Vector3d w_ref(W(2, 1), W(0, 2), W(1, 0));
  const Eigen::Matrix<double, 6, 1> twist = J * qd;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(twist[k], w_ref[k], 1e-8);
    EXPECT_NEAR(twist[3 + k], (pp - pm)[k] / (2 * e), 1e-8);
  }
  // J' q' by central differences of J along the motion, against frame_bias_acceleration
  Eigen::Matrix<double, 6, Eigen::Dynamic> Jp(6, n), Jm(6, n);
  forward_kinematics(tree, q + e * qd, d);
  frame_jacobian(tree, d, tool, p_L, Jp);
  forward_kinematics(tree, q - e * qd, d);
  frame_jacobian(tree, d, tool, p_L, Jm);
  const Eigen::Matrix<double, 6, 1> Jdqd = (Jp - Jm) / (2 * e) * qd;
  const Vector6d bias = frame_bias_acceleration(tree, q, qd, d, tool, p_L);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(bias[k], Jdqd[k], 1e-7 * Jdqd.norm()) << k;
  forward_kinematics(tree, q, d);
  // columns of the joints beyond a link are zero
  frame_jacobian(tree, d, tree.link_index("panda_link3"), Vector3d::Zero(), J);
  EXPECT_EQ(J.rightCols(4).cwiseAbs().maxCoeff(), 0.0);
}

// a free rigid body: p'' = g and Euler's equations J ω' + ω × J ω = 0, through the system's
// unit-quaternion constraint and ukdyn's fundamental equation (M is singular)
TEST(Tree, FloatingBodyFollowsEulersEquations) {
  Link body;
  body.name = "box";
  body.joint.name = "free";
  body.joint.kind = JointKind::kFloating;
  body.inertial.mass = 2.5;
  body.inertial.com = Vector3d(0.1, -0.05, 0.2);  // off the frame's origin
  body.inertial.I_com << 0.4, 0.05, -0.02, 0.05, 0.3, 0.01, -0.02, 0.01, 0.2;
  const Tree tree("free_body", {body});
  ASSERT_EQ(tree.coordinate_count(), 7);
  EXPECT_EQ(tree.coordinate_names()[3], "box.u0");
  const System sys = make_system(tree);
  ASSERT_EQ(sys.constraint_count(), 1);
  Workspace ws(sys);
  Eigen::Vector4d u(0.8, 0.2, -0.4, 0.4);
  u.normalize();
  const Vector3d w_L(1.5, -0.7, 2.0), v_com_W(0.3, 0.1, -0.2);
  // q' from ω_L and the com velocity: u' = ½ u ⊗ (0, ω_L), p' = v_com − R ω_L × c
  const Eigen::Quaterniond uq(u[0], u[1], u[2], u[3]);
  const Eigen::Quaterniond ud = uq * Eigen::Quaterniond(0, w_L.x(), w_L.y(), w_L.z());
  const Matrix3d R = uq.toRotationMatrix();
  VectorXd q(7), qd(7);
  q << 0.1, 0.2, 0.3, u;
  qd << v_com_W - R * w_L.cross(body.inertial.com), 0.5 * ud.w(), 0.5 * ud.x(), 0.5 * ud.y(),
      0.5 * ud.z();
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
  // ω'_L = 2 E(u) u'' (2 E(u') u' = 0)
  Eigen::Matrix<double, 3, 4> E;
  E << -u[1], u[0], u[3], -u[2], -u[2], -u[3], u[0], u[1], -u[3], u[2], -u[1], u[0];
  const Vector3d wd = 2 * E * ws.qdd.tail<4>();
  const Matrix3d& J = body.inertial.I_com;
  const Vector3d euler = J * wd + w_L.cross(J * w_L);
  EXPECT_NEAR(euler.norm(), 0.0, 1e-12);
  EXPECT_NEAR(wd.norm(), (J.inverse() * w_L.cross(J * w_L)).norm(), 1e-12);
  // com acceleration: p'' + R (ω' × c + ω × (ω × c)) = g
  const Vector3d c = body.inertial.com;
  const Vector3d a_com = ws.qdd.head<3>() + R * (wd.cross(c) + w_L.cross(w_L.cross(c)));
  EXPECT_NEAR((a_com - tree.gravity()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(u.dot(ws.qdd.tail<4>()), -qd.tail<4>().squaredNorm(), 1e-14);
}

TEST(Tree, SystemAppliesDampingAndTheTorqueInput) {
  const Tree tree = load_urdf(kPanda);
  const Index n = tree.coordinate_count();
  EXPECT_DOUBLE_EQ(tree.link(tree.link_index("panda_link1")).joint.damping, 0.5);
  EXPECT_DOUBLE_EQ(tree.link(tree.link_index("panda_link4")).joint.upper, -0.0698);
  EXPECT_DOUBLE_EQ(tree.link(tree.link_index("panda_link5")).joint.effort, 12.0);
  const System sys = make_system(tree, [](const auto&, const auto&, double t, auto tau) {
    for (Index i = 0; i < tau.size(); ++i) tau[i] = 0.5 * double(i) + t;
  });
  VectorXd q(n), qd(n), Q(n), h(n), D(n);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd << 0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3;
  D << 0.5, 0.5, 0.3, 0.3, 0, 0, 0;
  sys.forces(q, qd, 2.0, Q);
  TreeData d(tree);
  bias_forces(tree, q, qd, d, h);
  for (Index i = 0; i < n; ++i) {
    EXPECT_NEAR(Q[i], 0.5 * double(i) + 2.0 - D[i] * qd[i] - h[i], 1e-13 * (1 + std::abs(h[i])));
  }
  EXPECT_EQ(sys.coordinate_names()[0], "panda_joint1");
  EXPECT_NEAR(sys.external_power(q, qd, 2.0),
              qd.dot(VectorXd::LinSpaced(n, 2.0, 2.0 + 0.5 * double(n - 1)) - D.cwiseProduct(qd)),
              1e-13);
}

// simulate() applies unchanged: a damped arm driven by τ, whose energy balance (gravity's
// potential, the work of τ and of the dampers) closes
TEST(Tree, SimulatedArmClosesItsEnergyBalance) {
  const Tree tree = load_urdf(kPanda);
  const System sys = make_system(tree, [](const auto&, const auto& qd, double t, auto tau) {
    tau.setConstant(2.0 * std::sin(3.0 * t));
    tau -= 0.1 * qd;
  });
  ASSERT_TRUE(sys.accounts_for_energy());
  VectorXd q0(7), qd0 = VectorXd::Zero(7);
  q0 << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  SimulationOptions options;
  options.t_end = 1.0;
  const Trajectory tr = simulate(sys, q0, qd0, options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const Index N = tr.samples();
  double worst = 0;
  for (double r : tr.energy_balance_residual) worst = std::max(worst, std::abs(r));
  const double E_scale = std::abs(tr.potential_energy.front()) + 1.0;
  EXPECT_NEAR(worst / E_scale, 0.0, 1e-6);
  // the arm moved and the dampers and τ did work (the balance is not trivially zero)
  EXPECT_GT(std::abs(tr.work_external[std::size_t(N - 1)]), 1e-2);
  EXPECT_GT(std::abs(tr.energy[std::size_t(N - 1)] - tr.energy.front()), 1e-2);
}

// a constraint on the tree written with frame_jacobian and frame_bias_acceleration (as the
// ready-made ones of issue #30 will be): the arm's tool point held at a fixed world point,
// 3 rows A = J_v, b = −(J' q')_v. The fundamental equation holds it; the arm still moves.
struct ToolScratch final : ConstraintScratch {
  explicit ToolScratch(const Tree& tree) : data(tree), J(6, tree.coordinate_count()) {}
  TreeData data;
  Eigen::Matrix<double, 6, Eigen::Dynamic> J;
};

class ToolPointModel final : public ConstraintModel {
 public:
  ToolPointModel(const Tree& tree, Index link, const Vector3d& p_L, const Vector3d& p_W)
      : tree_(tree), link_(link), p_L_(p_L), p_W_(p_W) {}
  std::unique_ptr<ConstraintScratch> make_scratch(Index) const override {
    return std::make_unique<ToolScratch>(tree_);
  }
  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double, ConstraintScratch* s, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    auto& ts = *static_cast<ToolScratch*>(s);
    b = -frame_bias_acceleration(tree_, q, qd, ts.data, link_, p_L_).tail<3>();
    frame_jacobian(tree_, ts.data, link_, p_L_, ts.J);
    A = ts.J.bottomRows<3>();
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 ConstraintScratch* s, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& ts = *static_cast<ToolScratch*>(s);
    forward_kinematics(tree_, q, ts.data);
    position = world_point(ts.data, link_, p_L_) - p_W_;
    frame_jacobian(tree_, ts.data, link_, p_L_, ts.J);
    velocity = ts.J.bottomRows<3>() * qd;
  }

 private:
  Tree tree_;
  Index link_;
  Vector3d p_L_, p_W_;
};

TEST(Tree, ArmWithItsToolPointHeldByTheFundamentalEquation) {
  const Tree tree = load_urdf(kPanda);
  const Index tool = tree.link_index("panda_tool");
  const Vector3d p_L(0.0, 0.0, 0.05);
  VectorXd q0(7), qd0 = VectorXd::Zero(7);
  q0 << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  TreeData d(tree);
  forward_kinematics(tree, q0, d);
  const Vector3d p_W = world_point(d, tool, p_L);
  SystemBuilder sb = system_builder(tree);
  sb.add(Constraint("tool_point", ConstraintKind::kHolonomic, 3,
                    std::make_shared<ToolPointModel>(tree, tool, p_L, p_W)));
  const System held = sb.build();
  SimulationOptions options;
  options.t_end = 1.0;
  const Trajectory tr = simulate(held, q0, qd0, options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-8);
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, 1e-6);  // the ideal constraint does no work
  // the held arm swings in its 4-dimensional null space under gravity
  const Index N = tr.samples();
  const Eigen::Map<const VectorXd> q_end(tr.q.data() + (N - 1) * 7, 7);
  EXPECT_GT((q_end - q0).norm(), 0.05);
  forward_kinematics(tree, q_end, d);
  EXPECT_NEAR((world_point(d, tool, p_L) - p_W).norm(), 0.0, 1e-8);
}

// ---- URDF errors ----

std::string write_urdf(const std::string& name, const std::string& body) {
  const auto path = std::filesystem::temp_directory_path() / ("ukdyn_tree_" + name + ".urdf");
  std::ofstream(path) << "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n" << body << "</robot>\n";
  return path.string();
}

const std::string kInertial =
    "<inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" "
    "iyz=\"0\" izz=\"0.1\"/></inertial>";

// the message of loading a refused URDF file
constexpr auto* error_of = &ukdyn::testing::urdf_load_error;

TEST(Urdf, ErrorsNameTheLinkOrJoint) {
  const std::string joint =
      "<joint name=\"j1\" type=\"TYPE\"><parent link=\"base\"/><child "
      "link=\"arm\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" "
      "effort=\"1\" velocity=\"1\"/></joint>";
  const auto with = [&](std::string s, const std::string& type) {
    return s.replace(s.find("TYPE"), 4, type);
  };
  // malformed XML
  EXPECT_NE(error_of(write_urdf("malformed", "<link name=\"base\">")).find("not a valid URDF"),
            std::string::npos);
  // unknown and unsupported joint types
  std::string e = error_of(write_urdf("ball", "<link name=\"base\"/><link name=\"arm\">" +
                                                  kInertial + "</link>" + with(joint, "ball")));
  EXPECT_NE(e.find("j1"), std::string::npos) << e;
  EXPECT_NE(e.find("ball"), std::string::npos) << e;
  e = error_of(write_urdf("planar", "<link name=\"base\"/><link name=\"arm\">" + kInertial +
                                        "</link>" + with(joint, "planar")));
  EXPECT_NE(e.find("joint 'j1'"), std::string::npos) << e;
  EXPECT_NE(e.find("'planar' is not supported"), std::string::npos) << e;
  // a moving link without inertial
  e = error_of(write_urdf("no_inertial",
                          "<link name=\"base\"/><link name=\"arm\"/>" + with(joint, "revolute")));
  EXPECT_NE(e.find("link 'arm' moves (joint 'j1') but has no <inertial>"), std::string::npos) << e;
  // a non-positive-definite inertia
  e = error_of(
      write_urdf("not_pd",
                 "<link name=\"base\"/><link name=\"arm\"><inertial><mass value=\"1\"/><inertia "
                 "ixx=\"0.1\" ixy=\"0.2\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/></inertial>"
                 "</link>" +
                     with(joint, "revolute")));
  EXPECT_NE(e.find("link 'arm': the inertia of a moving link must be positive definite"),
            std::string::npos)
      << e;
  // not a tree: a link with two parents
  std::string j2 = with(joint, "revolute");
  j2.replace(j2.find("j1"), 2, "j2");
  j2.replace(j2.find("base"), 4, "other");
  e = error_of(write_urdf("two_parents", "<link name=\"base\"/><link name=\"other\">" + kInertial +
                                             "</link><link name=\"arm\">" + kInertial + "</link>" +
                                             with(joint, "revolute") + j2));
  // (urdfdom sees two roots, 'base' and 'other', and says so)
  EXPECT_NE(e.find("not a valid URDF"), std::string::npos) << e;
  EXPECT_NE(e.find("[other]"), std::string::npos) << e;
  // a <limit> with lower > upper (u18 06c: accepted, and every pose then exceeded a limit)
  std::string inverted = with(joint, "revolute");
  inverted.replace(inverted.find("lower=\"-1\" upper=\"1\""), 20, "lower=\"1\" upper=\"-1\"");
  e = error_of(write_urdf("inverted_limit", "<link name=\"base\"/><link name=\"arm\">" + kInertial +
                                                "</link>" + inverted));
  EXPECT_NE(e.find("joint 'j1' (child link 'arm'): its <limit> has lower = 1 > upper = -1"),
            std::string::npos)
      << e;
  // not a tree: a cycle below the root, base → a → b → a (urdfdom accepts it and links a's
  // children into a cycle, which a walk never left: u18 01)
  const auto joint_of = [](const std::string& name, const std::string& parent,
                           const std::string& child) {
    return "<joint name=\"" + name + "\" type=\"continuous\"><parent link=\"" + parent +
           "\"/><child link=\"" + child + "\"/><axis xyz=\"0 1 0\"/></joint>";
  };
  const std::string links = "<link name=\"base\"/><link name=\"a\">" + kInertial +
                            "</link><link name=\"b\">" + kInertial + "</link>";
  e = error_of(write_urdf("cycle", links + joint_of("j1", "base", "a") + joint_of("j2", "a", "b") +
                                       joint_of("j3", "b", "a")));
  EXPECT_NE(e.find("not a tree: link 'a' is the child of two joints, 'j1' and 'j3'"),
            std::string::npos)
      << e;
  // … and a cycle apart from the tree, c → d → c: its links are not reached from the root
  e = error_of(
      write_urdf("detached_cycle", links + "<link name=\"c\">" + kInertial +
                                       "</link><link name=\"d\">" + kInertial + "</link>" +
                                       joint_of("j1", "base", "a") + joint_of("j2", "a", "b") +
                                       joint_of("j3", "c", "d") + joint_of("j4", "d", "c")));
  EXPECT_NE(e.find("not a tree: link 'c' is not reached from the root link 'base'"),
            std::string::npos)
      << e;
  // no file
  EXPECT_NE(error_of("/nonexistent/robot.urdf").find("no such file"), std::string::npos);
}

TEST(Tree, ErrorsNameTheLinkOrJoint) {
  Link a;
  a.name = "a";
  a.joint.name = "ja";
  a.joint.kind = JointKind::kRevolute;
  a.inertial.mass = 1;
  a.inertial.I_com = Matrix3d::Identity();
  Link b = a;
  b.name = "b";
  b.joint.name = "jb";
  b.parent = "c";
  Link c = a;
  c.name = "c";
  c.joint.name = "jc";
  c.parent = "b";
  try {
    Tree("loop", {a, b, c});
    ADD_FAILURE() << "a cycle was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("not a tree: link 'b'"), std::string::npos) << e.what();
  }
  // a TreeData of another tree (same link count, other joints) is refused
  Link free = a;
  free.joint.kind = JointKind::kFloating;
  Link fixed_child = a;
  fixed_child.name = "d";
  fixed_child.joint.name = "jd";
  fixed_child.parent = "a";
  const Tree t1("t1", {a, fixed_child}), t2("t2", {free, fixed_child});
  TreeData other(t1);
  MatrixXd M(t2.coordinate_count(), t2.coordinate_count());
  try {
    mass_matrix(t2, t2.neutral(), other, M);
    ADD_FAILURE() << "another tree's data was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("make one TreeData per tree"), std::string::npos)
        << e.what();
  }
  Link bad = a;
  bad.inertial.I_com = Vector3d(1, 1, 3).asDiagonal();  // violates the triangle inequality
  try {
    Tree("bad", {bad});
    ADD_FAILURE() << "an impossible inertia was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("link 'a' (joint 'ja'): the inertia tensor"),
              std::string::npos)
        << e.what();
  }
}

// URDF's friction as Coulomb joint friction: a wheel spinning about its joint in zero gravity
// decelerates at F / I_zz until it stops (q' = w0 − (F/I) t, q = w0 t − (F/I) t²/2), and the
// friction's work closes the energy balance
TEST(Tree, UrdfFrictionIsCoulombJointFriction) {
  const std::string path = write_urdf(
      "friction",
      "<link name=\"base\"/><link name=\"wheel\"><inertial><mass value=\"2\"/>"
      "<inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.2\" iyz=\"0\" izz=\"0.3\"/></inertial>"
      "</link><joint name=\"spin\" type=\"continuous\"><parent link=\"base\"/>"
      "<child link=\"wheel\"/><axis xyz=\"0 0 1\"/><dynamics friction=\"0.6\"/></joint>");
  const Tree tree = load_urdf(path, Vector3d::Zero());
  EXPECT_EQ(tree.link(1).joint.friction, 0.6);
  const System sys = make_system(tree);
  SimulationOptions options;
  options.t_end = 0.8;  // it stops at t = w0 I / F = 1
  options.rtol = 1e-11;
  options.atol = 1e-13;
  VectorXd q0 = VectorXd::Zero(1), qd0 = VectorXd::Constant(1, 2.0);
  const Trajectory tr = simulate(sys, q0, qd0, options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double a = 0.6 / 0.3;
  for (Index s = 0; s < tr.samples(); ++s) {
    const double t = tr.t[std::size_t(s)];
    EXPECT_NEAR(tr.qd[std::size_t(s)], 2.0 - a * t, 1e-9);
    EXPECT_NEAR(tr.q[std::size_t(s)], 2.0 * t - a * t * t / 2, 1e-9);
  }
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, 1e-8);
  // the friction's work is the kinetic energy lost: F times the angle turned
  const double angle = tr.q.back();
  EXPECT_NEAR(tr.work_nonideal.back(), -0.6 * angle, 1e-8);
  // a negative friction is refused, naming the joint
  std::vector<Link> links = {tree.link(0), tree.link(1)};
  links[1].joint.friction = -1;
  try {
    Tree("bad", links);
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'spin'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("friction must be >= 0, got -1"), std::string::npos)
        << e.what();
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::tree

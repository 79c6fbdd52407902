// SPDX-License-Identifier: BSD-3-Clause
// The control adopts the plant's factor of M (#30 item 5): a controlled system's evaluation
// factorizes diag(M, I) before it asks for Q, and compute_control's fused stage 1 takes the
// leading block of that factor (FundamentalDecomposition::adopt_mass) instead of checking and
// factorizing M again. The adopted factor is bit for bit compute_mass(M), so the control is too;
// a plant whose M is not the model's, bit for bit, is refused and the control factorizes M.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <ukdyn/control/control.hpp>
#include <ukdyn/linalg/decomposition.hpp>
#include <ukdyn/multibody/tree.hpp>
#include <ukdyn/ukdyn.hpp>

#include "control/internal.hpp"
#include "support/random_problem.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// the leading block of diag(M, I)'s factor is M's own, bit for bit, and solves as it does
TEST(Decomposition, AdoptMassTakesTheLeadingBlockBitForBit) {
  const auto p = testing::random_problem(6, 2, 2, 17u, false);
  MatrixXd big = MatrixXd::Identity(9, 9);
  big.topLeftCorner(6, 6) = p.M;
  FundamentalDecomposition own(6, 2), adopted(6, 2), d9(9, 0);
  ASSERT_EQ(own.compute_mass(p.M).info(), Eigen::Success);
  // not factorized yet: refused
  EXPECT_FALSE(adopted.adopt_mass(d9));
  EXPECT_NE(adopted.info(), Eigen::Success);
  ASSERT_EQ(d9.compute_mass(big).info(), Eigen::Success);
  ASSERT_TRUE(adopted.adopt_mass(d9));
  EXPECT_EQ(adopted.info(), Eigen::Success);
  EXPECT_EQ(MatrixXd(adopted.matrix_llt().triangularView<Eigen::Lower>()),
            MatrixXd(own.matrix_llt().triangularView<Eigen::Lower>()));
  VectorXd x_own(6), x_adopted(6);
  own.solve_mass(p.Q, x_own);
  adopted.solve_mass(p.Q, x_adopted);
  EXPECT_EQ(x_adopted, x_own);
  // and it is M⁻¹ Q (Eigen's LLT)
  const VectorXd x = Eigen::LLT<MatrixXd>(p.M).solve(p.Q);
  EXPECT_LT((x_adopted - x).norm(), 1e-12 * x.norm());
  EXPECT_GT(x.norm(), 1e-3);
  // the constraint stage on the adopted factor: the same W, rank and q''
  own.compute_constraints(p.A);
  adopted.compute_constraints(p.A);
  EXPECT_EQ(adopted.rank(), own.rank());
  VectorXd dq_o(6), Qc_o(6), l_o(2), dq_a(6), Qc_a(6), l_a(2);
  own.solve_ideal(p.b, dq_o, Qc_o, l_o);
  adopted.solve_ideal(p.b, dq_a, Qc_a, l_a);
  EXPECT_EQ(dq_a, dq_o);
  EXPECT_EQ(l_a, l_o);
  // refused, leaving the factor as it was: a smaller source, a source above the small
  // Cholesky's 20 (Eigen's blocked kernel: other bits), a mass tree on either side
  FundamentalDecomposition d4(4, 0), d25(25, 0), tree9(9, 0);
  ASSERT_EQ(d4.compute_mass(p.M.topLeftCorner(4, 4)).info(), Eigen::Success);
  EXPECT_FALSE(adopted.adopt_mass(d4));
  MatrixXd huge = MatrixXd::Identity(25, 25);
  huge.topLeftCorner(6, 6) = p.M;
  ASSERT_EQ(d25.compute_mass(huge).info(), Eigen::Success);
  EXPECT_FALSE(adopted.adopt_mass(d25));
  tree9.set_mass_tree({-1, 0, 1, 2, 3, 4, -1, -1, -1});
  ASSERT_EQ(tree9.compute_mass(big).info(), Eigen::Success);
  EXPECT_FALSE(adopted.adopt_mass(tree9));
  FundamentalDecomposition tree6(6, 0);
  tree6.set_mass_tree({-1, 0, 1, 2, 3, 4});
  EXPECT_FALSE(tree6.adopt_mass(d9));
  EXPECT_EQ(MatrixXd(adopted.matrix_llt().triangularView<Eigen::Lower>()),
            MatrixXd(own.matrix_llt().triangularView<Eigen::Lower>()));
}

const std::string kPanda = std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf";

// the Panda's tool held at its pose, joint 3 at its angle (Gauss, fully actuated: fused)
Controller panda_hold(const tree::Tree& arm, const System& plant, const VectorXd& q0) {
  const Index tool = arm.link_index("panda_tool");
  tree::TreeData d(arm);
  tree::forward_kinematics(arm, q0, d);
  const Eigen::Vector3d p0 = tree::world_point(d, tool, Eigen::Vector3d::Zero());
  const Eigen::Matrix3d R0 = d.R_WL[std::size_t(tool)];
  const auto path = [p0, R0](double, tree::PoseSample& s) {
    s.p = p0;
    s.v.setZero();
    s.a.setZero();
    s.R = R0;
    s.w.setZero();
    s.w_dot.setZero();
  };
  const double q3 = q0[2];
  return ControllerBuilder(plant)
      .require(tree::pose_requirement(arm, "tool", {tool, Eigen::Vector3d::Zero()}, path),
               ErrorDynamics::second_order(20.0, 1.0))
      .require(
          holonomic("posture", 1, [q3](const auto& q, const auto&, auto& e) { e[0] = q[2] - q3; }),
          ErrorDynamics::second_order(20.0, 1.0))
      .build();
}

// the control with the plant's evaluation offered has the bits of compute_control; the factor
// is adopted only from an evaluation of this very M
TEST(ControlAdoptedFactor, PandaControlHasTheBitsOfItsOwnFactor) {
  const tree::Tree arm = tree::load_urdf(kPanda);
  const System plant = tree::make_system(arm);
  VectorXd q0(7), qd0(7);
  q0 << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd0 << 0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3;
  const Controller c = panda_hold(arm, plant, q0);
  ASSERT_TRUE(control_detail::fused_model(c));
  ControlWorkspace offered(c), own(c);
  Workspace pws(plant);
  FundamentalDecomposition d(7, 0);
  for (int k = 0; k < 4; ++k) {
    const VectorXd q = q0 + 0.1 * k * VectorXd::LinSpaced(7, -1.0, 1.0);
    const VectorXd qd = qd0 * (1.0 - 0.2 * k);
    const double t = 0.017 * k;
    // the plant's evaluation at q (k even) or at another q (k odd: refused)
    const VectorXd q_plant = k % 2 == 0 ? q : VectorXd(q + VectorXd::Constant(7, 1e-3));
    ASSERT_EQ(evaluate_unconstrained(plant, pws, q_plant, qd, t), Status::kOk);
    Workspace mws(plant);
    ASSERT_EQ(evaluate_unconstrained(plant, mws, q, qd, t), Status::kOk);
    EXPECT_EQ(control_detail::adopt_plant_factor(mws.M, &pws, d), k % 2 == 0) << k;
    EXPECT_FALSE(control_detail::adopt_plant_factor(mws.M, nullptr, d));
    ASSERT_EQ(control_detail::compute_control_in(c, offered, q, qd, t, &pws), ControlStatus::kOk)
        << describe_control_status(c, offered);
    ASSERT_EQ(compute_control(c, own, q, qd, t), ControlStatus::kOk)
        << describe_control_status(c, own);
    EXPECT_EQ(offered.model.qdd, own.model.qdd) << k;
    EXPECT_EQ(offered.Qc_control, own.Qc_control) << k;
    EXPECT_EQ(offered.qdd, own.qdd) << k;
    EXPECT_EQ(offered.residual, own.residual) << k;
    EXPECT_EQ(offered.power, own.power) << k;
    // q'' = M⁻¹ (Q + Qc) with M and Q afresh, and the requirements met
    const VectorXd qdd = mws.M.llt().solve(mws.Q + offered.Qc_control);
    EXPECT_LT((qdd - offered.qdd).norm(), 1e-12 * qdd.norm());
    EXPECT_GT(qdd.norm(), 1.0);
    const VectorXd r = offered.req.A * offered.qdd - offered.req.b;
    EXPECT_LT(r.norm(), 1e-12 * (offered.req.A.norm() * offered.qdd.norm() + offered.req.b.norm()));
  }
  // an evaluation that failed (non-finite q) leaves no factor to adopt
  VectorXd bad = q0;
  bad[1] = std::nan("");
  EXPECT_NE(evaluate_unconstrained(plant, pws, bad, qd0, 0.0), Status::kOk);
  Workspace mws(plant);
  ASSERT_EQ(evaluate_unconstrained(plant, mws, q0, qd0, 0.0), Status::kOk);
  EXPECT_FALSE(control_detail::adopt_plant_factor(mws.M, &pws, d));
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

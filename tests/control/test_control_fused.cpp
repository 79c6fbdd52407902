// SPDX-License-Identifier: BSD-3-Clause
// compute_control's fused stage 1 (control/nominal_motion.cpp, evaluate_model_fused): for the
// Gauss law, fully actuated, on a model without constraints, the model's M is factorized once,
// in the law's decomposition, for the model's a = M⁻¹ Q, the law and the control's effect. Its
// results are those of the five stages called one by one (which run the model's own
// forward_dynamics and factorize M twice) bit for bit; inputs and mass matrices the dense engine
// reports go through forward_dynamics and are reported as before.
#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/control/control.hpp>
#include <ukdyn/multibody/tree.hpp>
#include <ukdyn/ukdyn.hpp>

namespace ukdyn::tree {
namespace UKDYN_TEST_FILE {

const std::string kPanda = std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf";

// the Panda's tool on a 5 cm circle turning about z, joint 3 held (bench/bench_tree_step.cpp)
Controller panda_tracking(const tree::Tree& arm, const System& plant, const VectorXd& q0) {
  const Index tool = arm.link_index("panda_tool");
  tree::TreeData d(arm);
  tree::forward_kinematics(arm, q0, d);
  const Vector3d p0 = tree::world_point(d, tool, Vector3d::Zero());
  const Matrix3d R0 = d.R_WL[std::size_t(tool)];
  const auto path = [p0, R0](double t, tree::PoseSample& s) {
    const double w = 2.0, c = std::cos(w * t), sn = std::sin(w * t), r = 0.05;
    s.p = p0 + r * Vector3d(c - 1, sn, 0);
    s.v = r * w * Vector3d(-sn, c, 0);
    s.a = -r * w * w * Vector3d(c, sn, 0);
    s.R = Eigen::AngleAxisd(0.3 * sn, Vector3d::UnitZ()).toRotationMatrix() * R0;
    s.w = Vector3d(0, 0, 0.3 * w * c);
    s.w_dot = Vector3d(0, 0, -0.3 * w * w * sn);
  };
  const double q3 = q0[2];
  return ControllerBuilder(plant)
      .require(tree::pose_requirement(arm, "tool", {tool, Vector3d::Zero()}, path),
               ErrorDynamics::second_order(20.0, 1.0))
      .require(
          holonomic("posture", 1, [q3](const auto& q, const auto&, auto& e) { e[0] = q[2] - q3; }),
          ErrorDynamics::second_order(20.0, 1.0))
      .build();
}

// the five stages one by one (stage 1 is the model's forward_dynamics)
ControlStatus stages(const Controller& c, ControlWorkspace& ws, const VectorXd& q,
                     const VectorXd& qd, double t) {
  ControlStatus s = evaluate_model(c, ws, q, qd, t);
  if (s != ControlStatus::kOk) return s;
  if ((s = assemble_requirements(c, ws, q, qd, t)) != ControlStatus::kOk) return s;
  s = solve_law(c, ws, q, qd, t);
  if (s != ControlStatus::kOk && s != ControlStatus::kRequirementsNotMet) return s;
  if ((s = apply_robust(c, ws)) != ControlStatus::kOk) return s;
  return check_control(c, ws, qd);
}

void expect_same_bits(const VectorXd& x, const VectorXd& y, const char* what) {
  ASSERT_EQ(x.size(), y.size()) << what;
  for (Index i = 0; i < x.size(); ++i) EXPECT_EQ(x[i], y[i]) << what << "[" << i << "]";
}

TEST(ControlFused, PandaTrackingHasTheBitsOfTheStagesAndMeetsItsRequirements) {
  const tree::Tree arm = tree::load_urdf(kPanda);
  const System plant = tree::make_system(arm);
  VectorXd q0(7), qd0(7);
  q0 << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd0 << 0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3;
  const Controller c = panda_tracking(arm, plant, q0);
  ControlWorkspace fused(c), staged(c);
  for (int k = 0; k < 5; ++k) {
    const VectorXd q = q0 + 0.1 * k * VectorXd::LinSpaced(7, -1.0, 1.0);
    const VectorXd qd = qd0 * (1.0 - 0.2 * k);
    const double t = 0.013 * k;
    ASSERT_EQ(compute_control(c, fused, q, qd, t), ControlStatus::kOk)
        << describe_control_status(c, fused);
    ASSERT_EQ(stages(c, staged, q, qd, t), ControlStatus::kOk)
        << describe_control_status(c, staged);
    expect_same_bits(fused.model.qdd, staged.model.qdd, "a_p");
    expect_same_bits(fused.Qc_control, staged.Qc_control, "Qc_control");
    expect_same_bits(fused.qdd, staged.qdd, "q''");
    expect_same_bits(fused.residual, staged.residual, "residual");
    expect_same_bits(fused.Qc_physical, staged.Qc_physical, "Qc_physical");
    EXPECT_EQ(fused.power, staged.power);
    // the requirements met: A_r q'' = b_r (relative to |A_r| |q''| + |b_r|)
    const VectorXd r = fused.req.A * fused.qdd - fused.req.b;
    const double scale = fused.req.A.norm() * fused.qdd.norm() + fused.req.b.norm();
    EXPECT_GT(scale, 1.0);
    EXPECT_LT(r.norm(), 1e-12 * scale);
    // and q'' = M⁻¹ (Q + Qc), M and Q evaluated afresh
    Workspace ws(plant);
    ASSERT_EQ(evaluate_unconstrained(plant, ws, q, qd, t), Status::kOk);
    const VectorXd qdd = ws.M.llt().solve(ws.Q + fused.Qc_control);
    EXPECT_LT((qdd - fused.qdd).norm(), 1e-12 * qdd.norm());
    EXPECT_GT(qdd.norm(), 1.0);
  }
  // the fused path ran: the model's forward_dynamics never did
  EXPECT_EQ(fused.model.counters.evaluations, 0);
  EXPECT_EQ(staged.model.counters.evaluations, 5);
  EXPECT_EQ(fused.counters.evaluations, 5);
}

// 2 coordinates, M given by `mass`, Q = −q; one requirement q_0 = 0.1
Controller two_dof(
    std::function<void(const Eigen::Ref<const VectorXd>&, Eigen::Ref<MatrixXd>)> mass) {
  const System sys =
      SystemBuilder({"x", "y"})
          .mass_matrix([mass](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> M) {
            mass(q, M);
          })
          .forces([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) { Q = -q; })
          .build();
  return ControllerBuilder(sys)
      .require(holonomic("x", 1, [](const auto& q, const auto&, auto& e) { e[0] = q[0] - 0.1; }),
               ErrorDynamics::second_order(2.0))
      .build();
}

TEST(ControlFused, WhatTheEngineReportsIsReportedAsBefore) {
  VectorXd q(2);
  q << 0.3, -0.2;
  const VectorXd qd = VectorXd::Zero(2);
  // a regular M: met, a = M⁻¹ Q = (−0.3 / 2, 0.2 / 3) exactly as the stages give it
  {
    const Controller c = two_dof([](const auto&, auto M) { M << 2.0, 0.0, 0.0, 3.0; });
    ControlWorkspace ws(c), staged(c);
    ASSERT_EQ(compute_control(c, ws, q, qd, 0.0), ControlStatus::kOk);
    ASSERT_EQ(stages(c, staged, q, qd, 0.0), ControlStatus::kOk);
    EXPECT_NEAR(ws.model.qdd[0], -0.15, 1e-16);
    EXPECT_NEAR(ws.model.qdd[1], 0.2 / 3.0, 1e-16);
    expect_same_bits(ws.Qc_control, staged.Qc_control, "Qc_control");
    // x'' = −β² (x − 0.1) − 2α x' = −4 · 0.2 with the control, y'' = a_y untouched
    EXPECT_NEAR(ws.qdd[0], -0.8, 1e-14);
    EXPECT_NEAR(ws.qdd[1], 0.2 / 3.0, 1e-15);
    EXPECT_EQ(ws.model.counters.evaluations, 0);
  }
  // M not symmetric, not positive semi-definite, with NaN; a NaN state: the model's
  // forward_dynamics names it (kModelFailed, the model's status as the stages leave it)
  struct Case {
    const char* name;
    std::function<void(const Eigen::Ref<const VectorXd>&, Eigen::Ref<MatrixXd>)> mass;
    bool nan_q;  // q_0 = NaN
    Status model_status;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Case cases[] = {
      {"asymmetric", [](const auto&, auto M) { M << 2.0, 0.5, 0.4, 3.0; }, false,
       Status::kMassNotSymmetric},
      {"indefinite", [](const auto&, auto M) { M << 2.0, 0.0, 0.0, -3.0; }, false,
       Status::kMassNotPositiveDefinite},
      {"NaN in M", [nan](const auto&, auto M) { M << 2.0, nan, nan, 3.0; }, false,
       Status::kNonFiniteInput},
      {"NaN in q", [](const auto&, auto M) { M << 2.0, 0.0, 0.0, 3.0; }, true,
       Status::kNonFiniteInput},
  };
  for (const Case& k : cases) {
    const Controller c = two_dof(k.mass);
    ControlWorkspace ws(c), staged(c);
    VectorXd qk = q;
    if (k.nan_q) qk[0] = nan;
    EXPECT_EQ(compute_control(c, ws, qk, qd, 0.0), ControlStatus::kModelFailed) << k.name;
    EXPECT_EQ(ws.model.status, k.model_status) << k.name;
    EXPECT_EQ(stages(c, staged, qk, qd, 0.0), ControlStatus::kModelFailed) << k.name;
    EXPECT_EQ(staged.model.status, k.model_status) << k.name;
    EXPECT_EQ(describe_control_status(c, ws), describe_control_status(c, staged)) << k.name;
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::tree

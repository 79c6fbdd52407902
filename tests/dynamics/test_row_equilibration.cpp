// SPDX-License-Identifier: BSD-3-Clause
// Rows whose norms under- or overflow (issue #29 item 2, in part): a row written with a factor
// of 1e-170 or 1e170, or a state of 1e200, keeps its constraint: the rows are equilibrated where
// their squares would under- or overflow (linalg/decomposition.hpp, "Row equilibration"), never
// dropped with status ok. The reproducers constraint_underflow.sh and solve_overflow_rank0.py of
// ../shared/reproducers/2026-11-28, against the unscaled rows and the closed form.
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/dynamics/projection.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/random_problem.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using testing::vec;

// the planar pendulum of unit mass in Cartesian coordinates, its rod written as
// factor · (x² + y² − 1) = 0, gravity 9.81 along −y
System pendulum(double factor) {
  return SystemBuilder(2)
      .mass_matrix(MatrixXd::Identity(2, 2))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q << 0.0, -9.81; })
      .add(holonomic("rod", 1,
                     [factor](const auto& q, const auto&, auto& phi) {
                       phi[0] = factor * (q[0] * q[0] + q[1] * q[1] - 1.0);
                     }))
      .build();
}

// FundamentalDecomposition: the rank decision does not depend on the factor a row is written
// with, and the answer is that of the unscaled rows
TEST(RowEquilibration, RankDoesNotDependOnTheRowsFactors) {
  const MatrixXd M = vec({2.0, 3.0, 5.0}).asDiagonal();
  MatrixXd A(2, 3);
  A << 1.0, 2.0, 0.5, -1.0, 0.25, 3.0;
  const VectorXd e = vec({0.7, -1.3});
  FundamentalDecomposition ref(3, 2);
  ref.compute(M, A);
  VectorXd dq0(3), Qc0(3), l0(2);
  ref.solve_ideal(e, dq0, Qc0, l0);
  ASSERT_EQ(ref.rank(), 2);
  for (const double f : {1e-170, 1e-160, 1e-8, 1e8, 1e150, 1e170}) {
    SCOPED_TRACE(f);
    // row 0 scaled by f (e_0 with it), row 1 not: the same q'' and Qc; lambda_0 / f
    MatrixXd As = A;
    As.row(0) *= f;
    VectorXd es = e;
    es[0] *= f;
    FundamentalDecomposition d(3, 2);
    d.compute(M, As);
    EXPECT_EQ(d.rank(), 2);
    VectorXd dq(3), Qc(3), l(2);
    d.solve_ideal(es, dq, Qc, l);
    EXPECT_LE((dq - dq0).norm(), 1e-13 * dq0.norm());
    EXPECT_LE((Qc - Qc0).norm(), 1e-13 * Qc0.norm());
    EXPECT_NEAR(l[0] * f, l0[0], 1e-13 * l0.norm());
    EXPECT_NEAR(l[1], l0[1], 1e-13 * l0.norm());
  }
  // an exactly redundant row is still dropped, whatever its factor
  MatrixXd R(3, 3);
  R << A, 1e-170 * A.row(0);
  FundamentalDecomposition d(3, 3);
  d.compute(M, R);
  EXPECT_EQ(d.rank(), 2);
}

// solve_overflow_rank0.py: at q = (c, c), q' = 0 the rod's row (2c, 2c) asks x'' + y'' = 0,
// the answer (g/2, −g/2), whatever c; the rank stays 1 and the status ok. At q = (1e308, 0) the
// row overflows: a non-finite A, reported.
TEST(RowEquilibration, HugeStatesKeepTheConstraint) {
  const System sys = pendulum(1.0);
  Workspace ws(sys);
  for (const double c : {1.0, 1e150, 1e154, 1e200, 1e-150, 1e-200}) {
    SCOPED_TRACE(c);
    ASSERT_EQ(forward_dynamics(sys, ws, vec({c, c}), vec({0.0, 0.0}), 0.0), Status::kOk);
    EXPECT_EQ(ws.rank, 1);
    EXPECT_NEAR(ws.qdd[0], 4.905, 1e-12);
    EXPECT_NEAR(ws.qdd[1], -4.905, 1e-12);
    // ‖A q'' − b‖ relative to ‖A‖ ‖q''‖: roundoff (it overflowed to inf before)
    EXPECT_TRUE(std::isfinite(ws.residuals.constraint));
    EXPECT_LE(ws.residuals.constraint, 1e-14 * 2.0 * std::sqrt(2.0) * c * 4.905 * std::sqrt(2.0));
  }
  EXPECT_EQ(forward_dynamics(sys, ws, vec({1e308, 0.0}), vec({0.0, 0.0}), 0.0),
            Status::kNonFiniteInput);
  EXPECT_STREQ(ws.failed_quantity, "A");
}

// constraint_underflow.sh: the rod written as 1e-170 (x² + y² − 1) (A Aᵀ underflowed and the row
// was dropped: the bob fell freely to r = 5 m at t = 1 s with status ok). The same forward
// dynamics as the rod of factor 1 at every state of a run, hence the same motion.
TEST(RowEquilibration, TinyAndHugeRowFactorsGiveTheSameAccelerations) {
  const System ref_sys = pendulum(1.0);
  Workspace ref_ws(ref_sys);
  for (const double f : {1e-170, 1e-160, 1e150, 1e170}) {
    SCOPED_TRACE(f);
    const System sys = pendulum(f);
    Workspace ws(sys);
    for (const double angle : {-1.2, -0.3, 0.0, 0.4, 1.3}) {
      const VectorXd q = vec({std::sin(angle), -std::cos(angle)});
      const VectorXd qd = 1.7 * vec({std::cos(angle), std::sin(angle)});
      ASSERT_EQ(forward_dynamics(ref_sys, ref_ws, q, qd, 0.0), Status::kOk);
      ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
      EXPECT_EQ(ws.rank, 1);
      EXPECT_LE((ws.qdd - ref_ws.qdd).norm(), 1e-13 * ref_ws.qdd.norm());
      EXPECT_LE((ws.Qc - ref_ws.Qc).norm(), 1e-13 * ref_ws.Qc.norm());
    }
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

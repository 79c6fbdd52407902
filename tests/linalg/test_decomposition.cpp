// SPDX-License-Identifier: BSD-3-Clause
// FundamentalDecomposition against independent linear algebra (Eigen's SVD and LLT).
#include <cmath>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/SVD>

#include <ukdyn/linalg/decomposition.hpp>

#include "support/random_problem.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using testing::random_problem;
using testing::rel_diff;

using testing::Case;

class DecompositionCase : public ::testing::TestWithParam<Case> {};

// W = A L⁻ᵀ formed independently with Eigen's LLT
MatrixXd form_W(const MatrixXd& M, const MatrixXd& A) {
  Eigen::LLT<MatrixXd> llt(M);
  MatrixXd Wt = A.transpose();
  llt.matrixL().solveInPlace(Wt);
  return Wt.transpose();
}

// the operator y = W⁺ e as a matrix, one column per unit vector (test only)
MatrixXd pinv_matrix(FundamentalDecomposition& d, Index n, Index m) {
  MatrixXd X(n, m);
  VectorXd y(n);
  for (Index j = 0; j < m; ++j) {
    d.apply_pinv(VectorXd::Unit(m, j), y);
    X.col(j) = y;
  }
  return X;
}

MatrixXd svd_pinv(const MatrixXd& W, double rel_tol) {
  Eigen::JacobiSVD<MatrixXd> svd(W, Eigen::ComputeThinU | Eigen::ComputeThinV);
  VectorXd s = svd.singularValues();
  const double cutoff = rel_tol * s[0];
  for (Index i = 0; i < s.size(); ++i) s[i] = s[i] > cutoff ? 1.0 / s[i] : 0.0;
  return svd.matrixV() * s.asDiagonal() * svd.matrixU().transpose();
}

TEST_P(DecompositionCase, MoorePenroseConditionsHold) {
  const auto [n, m, r] = GetParam();
  const auto p = random_problem(n, m, r, 7u + unsigned(n * 31 + m), false);
  FundamentalDecomposition d(n, m);
  d.compute(p.M, p.A);
  ASSERT_EQ(d.info(), Eigen::Success);
  EXPECT_EQ(d.rank(), r);
  const MatrixXd W = form_W(p.M, p.A);
  const MatrixXd X = pinv_matrix(d, n, m);
  // W X W = W, X W X = X, (W X)ᵀ = W X, (X W)ᵀ = X W
  EXPECT_NEAR(rel_diff(W * X * W, W), 0.0, 1e-11);
  EXPECT_NEAR(rel_diff(X * W * X, X), 0.0, 1e-11);
  EXPECT_NEAR(rel_diff((W * X).transpose(), W * X), 0.0, 1e-11);
  EXPECT_NEAR(rel_diff((X * W).transpose(), X * W), 0.0, 1e-11);
  // and it equals the SVD pseudo-inverse
  EXPECT_NEAR(rel_diff(X, svd_pinv(W, 1e-10)), 0.0, 1e-10);
}

TEST_P(DecompositionCase, IdealPartMatchesSvdFormulas) {
  const auto [n, m, r] = GetParam();
  const auto p = random_problem(n, m, r, 11u + unsigned(n * 17 + m), true);
  FundamentalDecomposition d(n, m);
  d.compute(p.M, p.A);
  const VectorXd a = p.M.llt().solve(p.Q);
  const VectorXd e = p.b - p.A * a;
  VectorXd dqdd(n), Qc(n), lambda(m);
  d.solve_ideal(e, dqdd, Qc, lambda);
  // G⁺ e with G = A M⁻¹ Aᵀ by SVD
  const MatrixXd G = p.A * p.M.llt().solve(p.A.transpose());
  const VectorXd lambda_ref = svd_pinv(G, 1e-12) * e;
  EXPECT_NEAR(rel_diff(lambda, lambda_ref), 0.0, 1e-9);
  EXPECT_NEAR(rel_diff(Qc, p.A.transpose() * lambda_ref), 0.0, 1e-9);
  EXPECT_NEAR(rel_diff(dqdd, p.M.llt().solve(p.A.transpose() * lambda_ref)), 0.0, 1e-9);
  // non-ideal part: Qc_ni = C − Aᵀ G⁺ A M⁻¹ C, and Qc_ni = C + Aᵀ lambda_ni
  VectorXd dq_ni(n), Qc_ni(n), lambda_ni(m);
  d.project_nonideal(p.C, dq_ni, Qc_ni, lambda_ni);
  const VectorXd AMC = p.A * p.M.llt().solve(p.C);
  const VectorXd Qc_ni_ref = p.C - p.A.transpose() * (svd_pinv(G, 1e-12) * AMC);
  // (relative to ‖C‖: with rank A = n the non-ideal force vanishes)
  const double c = p.C.norm();
  EXPECT_NEAR(rel_diff(Qc_ni, Qc_ni_ref, c), 0.0, 1e-9);
  EXPECT_NEAR(rel_diff(p.C + p.A.transpose() * lambda_ni, Qc_ni_ref, c), 0.0, 1e-9);
  EXPECT_NEAR(rel_diff(dq_ni, p.M.llt().solve(Qc_ni_ref), c), 0.0, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Sizes, DecompositionCase,
                         ::testing::Values(Case{1, 1, 1}, Case{3, 1, 1}, Case{6, 3, 3},
                                           Case{6, 3, 2}, Case{6, 6, 6}, Case{6, 9, 6},
                                           Case{6, 9, 4}, Case{12, 6, 1}, Case{30, 20, 20},
                                           Case{30, 20, 13}, Case{60, 40, 25}, Case{120, 80, 80},
                                           Case{120, 80, 57}),
                         testing::CaseName());

TEST(Decomposition, ZeroConstraintMatrixHasRankZeroAndZeroForce) {
  const Index n = 4, m = 2;
  FundamentalDecomposition d(n, m);
  d.compute(MatrixXd::Identity(n, n) * 2.0, MatrixXd::Zero(m, n));
  EXPECT_EQ(d.rank(), 0);
  VectorXd dq(n), Qc(n), lambda(m);
  d.solve_ideal(VectorXd::Zero(m), dq, Qc, lambda);
  EXPECT_NEAR(dq.norm() + Qc.norm() + lambda.norm(), 0.0, 1e-300);
  // with no active constraint the non-ideal force is C itself
  const VectorXd C = VectorXd::LinSpaced(n, 1.0, 4.0);
  d.project_nonideal(C, dq, Qc, lambda);
  EXPECT_NEAR(rel_diff(Qc, C), 0.0, 1e-15);
  EXPECT_NEAR(rel_diff(dq, C / 2.0), 0.0, 1e-15);
}

TEST(Decomposition, RankIsInvariantUnderCommonScaling) {
  const auto p = random_problem(10, 6, 4, 3u, false);
  for (double s : {1e-8, 1.0, 1e8}) {
    FundamentalDecomposition d(10, 6);
    d.compute(p.M, s * p.A);
    EXPECT_EQ(d.rank(), 4) << "scale " << s;
  }
}

TEST(Decomposition, ThresholdDecidesNearlyDependentRows) {
  // rows (1, 0) and (1, delta): singular values ~ sqrt(2) and delta / sqrt(2)
  MatrixXd A(2, 2);
  A << 1.0, 0.0, 1.0, 1e-7;
  FundamentalDecomposition d(2, 2);
  d.compute(MatrixXd::Identity(2, 2), A);
  EXPECT_EQ(d.rank(), 2);
  d.set_threshold(1e-6).compute(MatrixXd::Identity(2, 2), A);
  EXPECT_EQ(d.rank(), 1);
  EXPECT_DOUBLE_EQ(d.threshold(), 1e-6);
}

TEST(Decomposition, RejectsThresholdOutsideUnitInterval) {
  FundamentalDecomposition d(2, 1);
  EXPECT_THROW(d.set_threshold(0.0), std::invalid_argument);
  EXPECT_THROW(d.set_threshold(1.5), std::invalid_argument);
}

TEST(Decomposition, ReportsMassNotPositiveDefinite) {
  FundamentalDecomposition d(2, 1);
  MatrixXd M(2, 2);
  M << 1.0, 2.0, 2.0, 1.0;  // eigenvalues 3 and −1
  d.compute_mass(M);
  EXPECT_EQ(d.info(), Eigen::NumericalIssue);
}

TEST(Decomposition, SolveMassInvertsM) {
  const auto p = random_problem(9, 3, 3, 5u, false);
  FundamentalDecomposition d(9, 3);
  d.compute_mass(p.M);
  VectorXd x(9);
  d.solve_mass(p.Q, x);
  EXPECT_NEAR(rel_diff(p.M * x, p.Q), 0.0, 1e-13);
}

// The small Cholesky stops each column's update at its last non-zero entry, found after the
// earlier columns' updates: with zero tails that fill in (column 2 of M is zero below row 2
// until column 0's update writes L_42), interior zeros and a block-diagonal diag(M, I) (a
// controlled system's), L is Eigen's LLT's to roundoff, and the block-diagonal factor is bit for
// bit the factor of M alone in its block and the identity in the other
TEST(Decomposition, CholeskyOfSparseColumnsMatchesEigen) {
  const Index n = 9;
  MatrixXd S = MatrixXd::Zero(n, n);
  for (Index k = 0; k < n; ++k) S(k, k) = 4.0 + 0.5 * double(k);
  const auto pair = [&](Index i, Index j, double v) { S(i, j) = S(j, i) = v; };
  pair(2, 0, 1.0);
  pair(4, 0, 1.5);  // fill-in at (4, 2)
  pair(6, 5, 0.4);
  pair(8, 1, 0.9);  // column 1: zeros between rows 2 and 7
  FundamentalDecomposition d(n, 0);
  ASSERT_EQ(d.compute_mass(S).info(), Eigen::Success);
  const MatrixXd L = d.matrix_llt().triangularView<Eigen::Lower>();
  const MatrixXd L_eigen = Eigen::LLT<MatrixXd>(S).matrixL();
  EXPECT_NEAR(rel_diff(L, L_eigen), 0.0, 1e-15);
  // the fill-in and the far entry are there: L_42 = −L_20 L_40 / L_22
  EXPECT_NEAR(L(4, 2), -(L(2, 0) * L(4, 0)) / L(2, 2), 1e-15);
  EXPECT_LT(L(4, 2), -0.05);
  EXPECT_NEAR(L(8, 1), 0.9 / std::sqrt(4.5), 1e-15);
  // diag(M, I): the block's factor is that of M alone, bit for bit; the identity stays
  const auto p = random_problem(6, 2, 2, 11u, false);
  MatrixXd big = MatrixXd::Identity(9, 9);
  big.topLeftCorner(6, 6) = p.M;
  FundamentalDecomposition d6(6, 0), d9(9, 0);
  ASSERT_EQ(d6.compute_mass(p.M).info(), Eigen::Success);
  ASSERT_EQ(d9.compute_mass(big).info(), Eigen::Success);
  const MatrixXd L9 = d9.matrix_llt().triangularView<Eigen::Lower>();
  EXPECT_EQ(MatrixXd(L9.topLeftCorner(6, 6)),
            MatrixXd(d6.matrix_llt().triangularView<Eigen::Lower>()));
  EXPECT_EQ(MatrixXd(L9.bottomRows(3)), MatrixXd(MatrixXd::Identity(9, 9).bottomRows(3)));
  EXPECT_NEAR(rel_diff(L9, MatrixXd(Eigen::LLT<MatrixXd>(big).matrixL())), 0.0, 1e-15);
  // a pivot that the trimmed update makes zero is still found (M_44 = L_40² + L_42² exactly
  // would leave 0; a little less, a negative pivot)
  MatrixXd singular = S;
  singular(4, 4) = L(4, 0) * L(4, 0) + L(4, 2) * L(4, 2) - 1e-3;
  EXPECT_EQ(d.compute_mass(singular).info(), Eigen::NumericalIssue);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

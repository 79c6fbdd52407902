// SPDX-License-Identifier: BSD-3-Clause
/// @file reference/reference.hpp
/// Independent algorithms kept for tests and benchmarks: the textbook formula of the paper and
/// a Lagrange-multiplier (KKT) solve. Neither is used by default; both allocate.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "ukdyn/core/types.hpp"

namespace ukdyn {

/// The fundamental equation exactly as printed (eqs. 9, 11, 12): M^{±1/2} by a symmetric
/// eigendecomposition, B = A M^{−1/2} and its Moore–Penrose inverse by SVD (singular values
/// below threshold · σ_max count as zero). Same interface as FundamentalDecomposition, so the
/// solver can run on either. Cost O(n³) with large constants; allocates on every compute.
class TextbookDecomposition {
 public:
  /// Sizes for n coordinates, m rows.
  TextbookDecomposition(Index n, Index m);
  /// Eigendecomposition of M; info() is NumericalIssue unless all eigenvalues are > 0.
  TextbookDecomposition& compute_mass(const Eigen::Ref<const MatrixXd>& M);
  /// B = A M^{−1/2}, its SVD and pseudo-inverse B⁺ (formed explicitly, as in the paper).
  TextbookDecomposition& compute_constraints(const Eigen::Ref<const MatrixXd>& A);
  Eigen::ComputationInfo info() const { return info_; }  ///< see compute_mass
  Index rank() const { return rank_; }                   ///< numerical rank of B
  TextbookDecomposition& set_threshold(double t);        ///< relative SVD threshold
  double threshold() const { return threshold_; }        ///< relative SVD threshold

  /// x = M⁻¹ f.
  void solve_mass(const Eigen::Ref<const VectorXd>& f, Eigen::Ref<VectorXd> x) const;
  /// dqdd = M^{−1/2} B⁺ e, Qc = M^{1/2} B⁺ e, lambda = (B Bᵀ)⁺ e.
  void solve_ideal(const Eigen::Ref<const VectorXd>& e, Eigen::Ref<VectorXd> dqdd,
                   Eigen::Ref<VectorXd> Qc, Eigen::Ref<VectorXd> lambda);
  /// dqdd = M^{−1/2}(I − B⁺B)M^{−1/2} C, Qc = M^{1/2}(I − B⁺B)M^{−1/2} C,
  /// lambda = −(B Bᵀ)⁺ B M^{−1/2} C.
  void project_nonideal(const Eigen::Ref<const VectorXd>& C, Eigen::Ref<VectorXd> dqdd,
                        Eigen::Ref<VectorXd> Qc, Eigen::Ref<VectorXd> lambda);

 private:
  Index n_, m_;
  MatrixXd M_half_, M_inv_half_, B_, B_pinv_, G_pinv_;
  Index rank_ = 0;
  double threshold_ = 1e-10;
  Eigen::ComputationInfo info_ = Eigen::InvalidInput;
};

/// Ideal constrained motion by the Lagrange-multiplier (KKT) system
///     [M  Aᵀ] [ q''] = [Q]
///     [A  0 ] [−λ  ]   [b]
/// factorized with Eigen's LDLT. Valid only when A has full row rank: with redundant rows the
/// matrix is singular and the result is NaN or wrong (that is what it is kept to show).
/// Memory is reserved by the constructor. Cost O((n+m)³/3).
class KktSolver {
 public:
  /// Sizes for n coordinates and m rows.
  KktSolver(Index n, Index m);
  /// Solves for q'' (n) and lambda (m), with M q'' = Q + Aᵀ lambda. Returns LDLT's info().
  Eigen::ComputationInfo solve(const Eigen::Ref<const MatrixXd>& M,
                               const Eigen::Ref<const VectorXd>& Q,
                               const Eigen::Ref<const MatrixXd>& A,
                               const Eigen::Ref<const VectorXd>& b, Eigen::Ref<VectorXd> qdd,
                               Eigen::Ref<VectorXd> lambda);

 private:
  Index n_, m_;
  MatrixXd K_;
  VectorXd rhs_;
  Eigen::LDLT<MatrixXd> ldlt_;
};

}  // namespace ukdyn

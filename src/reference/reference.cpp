// SPDX-License-Identifier: BSD-3-Clause
// The textbook formula (eqs. 9–12 with M^{±1/2} and an SVD pseudo-inverse) and the KKT solve,
// kept as independent references for tests and benchmarks.
#include "ukdyn/reference/reference.hpp"

#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "ukdyn/core/format.hpp"
#include "ukdyn/core/status.hpp"

namespace ukdyn {

TextbookDecomposition::TextbookDecomposition(Index n, Index m) : n_(n), m_(m) {}

TextbookDecomposition& TextbookDecomposition::set_threshold(double t) {
  if (!(t > 0.0 && t < 1.0)) {
    throw std::invalid_argument(
        "ukdyn::TextbookDecomposition::set_threshold: must lie in (0, 1),"
        " got " +
        format_number(t));
  }
  threshold_ = t;
  return *this;
}

TextbookDecomposition& TextbookDecomposition::compute_mass(const Eigen::Ref<const MatrixXd>& M) {
  UKDYN_CHECK(M.rows() == n_ && M.cols() == n_, "TextbookDecomposition: M has the wrong size");
  // M = V D Vᵀ;  M^{±1/2} = V D^{±1/2} Vᵀ
  Eigen::SelfAdjointEigenSolver<MatrixXd> es(M);
  if (es.info() != Eigen::Success || !(es.eigenvalues().minCoeff() > 0.0)) {
    info_ = Eigen::NumericalIssue;
    return *this;
  }
  const MatrixXd& V = es.eigenvectors();
  const VectorXd d = es.eigenvalues().cwiseSqrt();
  M_half_ = V * d.asDiagonal() * V.transpose();
  M_inv_half_ = V * d.cwiseInverse().asDiagonal() * V.transpose();
  info_ = Eigen::Success;
  return *this;
}

TextbookDecomposition& TextbookDecomposition::compute_constraints(
    const Eigen::Ref<const MatrixXd>& A) {
  UKDYN_CHECK(A.rows() == m_ && A.cols() == n_, "TextbookDecomposition: A has the wrong size");
  // B = A M^{−1/2} = U Σ Vᵀ;  B⁺ = V Σ⁺ Uᵀ;  (B Bᵀ)⁺ = U Σ⁺² Uᵀ
  B_ = A * M_inv_half_;
  if (m_ == 0) {  // no constraint: B⁺ is n × 0 (Eigen's SVD does not take an empty matrix)
    rank_ = 0;
    B_pinv_.setZero(n_, 0);
    G_pinv_.setZero(0, 0);
    return *this;
  }
  Eigen::BDCSVD<MatrixXd> svd(B_, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const VectorXd& s = svd.singularValues();
  const double smax = s.size() > 0 ? s[0] : 0.0;
  rank_ = 0;
  VectorXd inv = VectorXd::Zero(s.size());
  for (Index i = 0; i < s.size(); ++i) {
    if (s[i] > threshold_ * smax && s[i] > 0.0) {
      inv[i] = 1.0 / s[i];
      ++rank_;
    }
  }
  B_pinv_ = svd.matrixV() * inv.asDiagonal() * svd.matrixU().transpose();
  G_pinv_ = svd.matrixU() * inv.cwiseAbs2().asDiagonal() * svd.matrixU().transpose();
  return *this;
}

void TextbookDecomposition::solve_mass(const Eigen::Ref<const VectorXd>& f,
                                       Eigen::Ref<VectorXd> x) const {
  x = M_inv_half_ * (M_inv_half_ * f);
}

void TextbookDecomposition::solve_ideal(const Eigen::Ref<const VectorXd>& e,
                                        Eigen::Ref<VectorXd> dqdd, Eigen::Ref<VectorXd> Qc,
                                        Eigen::Ref<VectorXd> lambda) {
  const VectorXd y = B_pinv_ * e;
  dqdd = M_inv_half_ * y;
  Qc = M_half_ * y;
  lambda = G_pinv_ * e;
}

void TextbookDecomposition::project_nonideal(const Eigen::Ref<const VectorXd>& C,
                                             Eigen::Ref<VectorXd> dqdd, Eigen::Ref<VectorXd> Qc,
                                             Eigen::Ref<VectorXd> lambda) {
  const VectorXd c = M_inv_half_ * C;
  const VectorXd Bc = B_ * c;
  const VectorXd c_perp = c - B_pinv_ * Bc;
  dqdd = M_inv_half_ * c_perp;
  Qc = M_half_ * c_perp;
  lambda = -(G_pinv_ * Bc);
}

KktSolver::KktSolver(Index n, Index m)
    : n_(n), m_(m), K_(n + m, n + m), rhs_(n + m), ldlt_(n + m) {}

Eigen::ComputationInfo KktSolver::solve(const Eigen::Ref<const MatrixXd>& M,
                                        const Eigen::Ref<const VectorXd>& Q,
                                        const Eigen::Ref<const MatrixXd>& A,
                                        const Eigen::Ref<const VectorXd>& b,
                                        Eigen::Ref<VectorXd> qdd, Eigen::Ref<VectorXd> lambda) {
  // [M Aᵀ; A 0] [q''; −lambda] = [Q; b]
  K_.topLeftCorner(n_, n_) = M;
  K_.topRightCorner(n_, m_) = A.transpose();
  K_.bottomLeftCorner(m_, n_) = A;
  K_.bottomRightCorner(m_, m_).setZero();
  rhs_.head(n_) = Q;
  rhs_.tail(m_) = b;
  ldlt_.compute(K_);
  ldlt_.solveInPlace(rhs_);
  qdd = rhs_.head(n_);
  lambda = -rhs_.tail(m_);
  return ldlt_.info();
}

}  // namespace ukdyn

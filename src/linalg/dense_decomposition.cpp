// SPDX-License-Identifier: BSD-3-Clause
// FundamentalDecomposition: Cholesky of M, complete orthogonal decomposition of Wᵀ = L⁻¹ Aᵀ.
// Notation as in linalg/decomposition.hpp: Wᵀ Π = Q [T 0; 0 0] Z, Q = H_0 ⋯ H_{r−1}, Z = Z_0 ⋯
// Z_{r−1}.
#include "ukdyn/linalg/decomposition.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "linalg/safe_norm.hpp"
#include "linalg/tree_ltl.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/status.hpp"

namespace ukdyn {

namespace {
// Small dense kernels on column-major storage (ld = leading dimension), written as plain loops
// so that the compiler vectorizes them without the per-call set-up of Eigen's expression and
// blocking machinery, which dominates at the sizes of most mechanical systems. Every inner loop
// runs down a column: contiguous memory.

// dot product of n entries, with four independent partial sums so that the additions pipeline
// (one running sum is bound by the latency of the floating-point add)
inline double dot(const double* __restrict x, const double* __restrict y, Index n) {
  double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
  Index i = 0;
  for (; i + 4 <= n; i += 4) {
    s0 += x[i] * y[i];
    s1 += x[i + 1] * y[i + 1];
    s2 += x[i + 2] * y[i + 2];
    s3 += x[i + 3] * y[i + 3];
  }
  for (; i < n; ++i) s0 += x[i] * y[i];
  return (s0 + s1) + (s2 + s3);
}

// y ← y + a x over n entries
inline void axpy(double a, const double* __restrict x, double* __restrict y, Index n) {
  for (Index i = 0; i < n; ++i) y[i] += a * x[i];
}

// The triangular solves multiply by the reciprocals of the diagonal (`inv`, kept when the factor
// is made): a division's latency is four times a multiplication's, and each solve is a chain.

// x ← L⁻¹ x, L lower triangular (n × n)
inline void lower_solve(const double* L, Index ld, const double* inv, double* x, Index n) {
  for (Index k = 0; k < n; ++k) {
    x[k] *= inv[k];
    axpy(-x[k], L + k * ld + k + 1, x + k + 1, n - k - 1);
  }
}

// x ← L⁻ᵀ x, L lower triangular
inline void lower_transpose_solve(const double* L, Index ld, const double* inv, double* x,
                                  Index n) {
  for (Index k = n - 1; k >= 0; --k) {
    x[k] = (x[k] - dot(L + k * ld + k + 1, x + k + 1, n - k - 1)) * inv[k];
  }
}

// Y = A L⁻ᵀ for A (m × n, leading dimension lda) into Y (m × n, leading dimension m): each row's
// lower_solve, y_jᵀ = L⁻¹ a_jᵀ, with the same operations in the same order (x_i += (−x_k) L_ik for
// k < i, then x_i *= 1 / L_ii), so the same bits, but each step one contiguous loop over the m
// rows instead of m short loops down a column of L (the first step reads A: no copy of it)
inline void lower_solve_rows(const double* L, Index ld, const double* inv,
                             const double* __restrict A, Index lda, double* __restrict Y, Index m,
                             Index n) {
  if (n == 0) return;
  // k = 0: y_0 = a_0 / L_00,  y_i = a_i − L_i0 y_0
  for (Index j = 0; j < m; ++j) Y[j] = A[j] * inv[0];
  for (Index i = 1; i < n; ++i) {
    const double l = -L[i];
    const double* a = A + i * lda;
    double* y = Y + i * m;
    for (Index j = 0; j < m; ++j) y[j] = a[j] + l * Y[j];
  }
  // k = 1 … n − 1
  for (Index k = 1; k < n; ++k) {
    double* yk = Y + k * m;
    const double d = inv[k];
    for (Index j = 0; j < m; ++j) yk[j] *= d;
    for (Index i = k + 1; i < n; ++i) axpy(-L[k * ld + i], yk, Y + i * m, m);
  }
}

// y ← L x, L lower triangular
inline void lower_multiply(const double* L, Index ld, const double* x, double* y, Index n) {
  for (Index i = 0; i < n; ++i) y[i] = 0.0;
  for (Index k = 0; k < n; ++k) axpy(x[k], L + k * ld + k, y + k, n - k);
}

// x ← T⁻¹ x, T upper triangular (r × r)
inline void upper_solve(const double* T, Index ld, const double* inv, double* x, Index r) {
  for (Index k = r - 1; k >= 0; --k) {
    x[k] *= inv[k];
    axpy(-x[k], T + k * ld, x, k);
  }
}

// x ← T⁻ᵀ x, T upper triangular
inline void upper_transpose_solve(const double* T, Index ld, const double* inv, double* x,
                                  Index r) {
  for (Index k = 0; k < r; ++k) x[k] = (x[k] - dot(T + k * ld, x, k)) * inv[k];
}

// up to this n the plain loops (Cholesky, and L X = Aᵀ one column at a time) take fewer
// instructions than Eigen's blocked Cholesky and triangular solve; above it Eigen's win (callgrind
// counts per evaluation, n = 6 … 120: see bench/RESULTS.md)
constexpr Index kSmall = 20;

// A = L Lᵀ in place on the lower triangle of A (n × n), right-looking; false unless every pivot
// is positive. Column k's trailing update stops at its last non-zero entry e: the rows below
// it add L(j, k) L(i, k) = ±0, which leaves a finite entry as it is, so the result is bit for
// bit that of the full update for a finite A. A block-diagonal A (a controlled system's
// diag(M, I)) then costs what its blocks cost, a dense one a compare per column more.
inline bool cholesky_in_place(double* A, Index ld, Index n) {
  for (Index k = 0; k < n; ++k) {
    double* Ak = A + k * ld;
    if (!(Ak[k] > 0.0)) return false;
    const double d = std::sqrt(Ak[k]), inv = 1.0 / d;
    Ak[k] = d;
    Index e = n - 1;  // the last non-zero entry of column k below the diagonal (k: none)
    while (e > k && Ak[e] == 0.0) --e;
    for (Index i = k + 1; i <= e; ++i) Ak[i] *= inv;
    // trailing columns: A(j:e, j) −= L(j, k) L(j:e, k)
    for (Index j = k + 1; j <= e; ++j) axpy(-Ak[j], Ak + j, A + j * ld + j, e + 1 - j);
  }
  return true;
}
}  // namespace

void FundamentalDecomposition::resize(Index n, Index m) {
  n_ = n;
  m_ = m;
  L_.resize(n, n);
  X_.resize(n, 2 * m);  // (columns m … 2m − 1: the scratch of lower_solve_rows)
  tau_.resize(m);
  ztau_.resize(m);
  perm_.resize(m);
  norm_.resize(m);
  norm_ref_.resize(m);
  wm_.resize(m);
  wn_.resize(n);
  inv_ldiag_.resize(n);
  inv_tdiag_.resize(m);
  row_scale_.setOnes(m);
  if (Index(parent_.size()) != n) parent_.clear();
  if (!parent_.empty()) L_.setZero();  // (the tree's factor writes only its pattern)
  rank_ = 0;
  max_pivot_ = 0.0;
  info_ = Eigen::InvalidInput;
}

FundamentalDecomposition& FundamentalDecomposition::set_threshold(double threshold) {
  if (!(threshold > 0.0 && threshold < 1.0)) {
    throw std::invalid_argument(
        "ukdyn::FundamentalDecomposition::set_threshold: the relative rank threshold must lie "
        "in (0, 1), got " +
        format_number(threshold));
  }
  threshold_ = threshold;
  return *this;
}

FundamentalDecomposition& FundamentalDecomposition::set_mass_tree(
    const std::vector<Index>& parent) {
  const char* who = "ukdyn::FundamentalDecomposition::set_mass_tree";
  if (!parent.empty() && Index(parent.size()) != n_) {
    throw std::invalid_argument(std::string(who) + ": expected a parent for each of the " +
                                format_number(n_) + " coordinates (or none), got " +
                                format_number(Index(parent.size())));
  }
  for (std::size_t k = 0; k < parent.size(); ++k) {
    if (parent[k] < -1 || parent[k] >= Index(k)) {
      throw std::invalid_argument(std::string(who) + ": the parent of coordinate " +
                                  format_number(Index(k)) + " is " + format_number(parent[k]) +
                                  "; it must be -1 (a root) or a coordinate before it");
    }
  }
  parent_ = parent;  // (an empty parent keeps the capacity: no allocation)
  // the tree's factor writes L only on its pattern: the rest of its lower triangle stays zero
  if (!parent_.empty()) L_.setZero();
  return *this;
}

FundamentalDecomposition& FundamentalDecomposition::compute_mass(
    const Eigen::Ref<const MatrixXd>& M) {
  UKDYN_CHECK(M.rows() == n_ && M.cols() == n_, "compute_mass: M has the wrong size");
  if (!parent_.empty()) {
    // M = Lᵀ L along the tree's branches (linalg/tree_ltl.hpp), 1 / L_kk for the solves; M is
    // read on its pattern only (no copy of all n² entries)
    const bool ok = detail::tree_ltl(M.data(), M.outerStride(), L_.data(), parent_.data(),
                                     inv_ldiag_.data(), n_);
    info_ = ok ? Eigen::Success : Eigen::NumericalIssue;
    return *this;
  }
  // M = L Lᵀ, in place on the lower triangle of L_. Large n: Eigen's blocked kernel (the one
  // behind Eigen::LLT, called directly: an LLT object leaves its info member uninitialized until
  // compute(), so moving an unused one is undefined behaviour, and it also computes a norm we do
  // not need)
  L_ = M;
  const bool ok = n_ <= kSmall
                      ? cholesky_in_place(L_.data(), n_, n_)
                      : Eigen::internal::llt_inplace<double, Eigen::Lower>::blocked(L_) == -1;
  info_ = ok ? Eigen::Success : Eigen::NumericalIssue;
  // 1 / L_kk for the solves
  if (ok) inv_ldiag_ = L_.diagonal().cwiseInverse();
  return *this;
}

bool FundamentalDecomposition::adopt_mass(const FundamentalDecomposition& other) {
  if (other.info_ != Eigen::Success || !other.parent_.empty() || !parent_.empty() ||
      other.n_ < n_ || other.n_ > kSmall) {
    return false;
  }
  // the leading block of a block-diagonal factor is the block's own factor (cholesky_in_place)
  // (its lower triangle, column by column: the upper one is unspecified)
  for (Index j = 0; j < n_; ++j) {
    std::memcpy(L_.data() + j * n_ + j, other.L_.data() + j * other.n_ + j,
                sizeof(double) * std::size_t(n_ - j));
  }
  std::memcpy(inv_ldiag_.data(), other.inv_ldiag_.data(), sizeof(double) * std::size_t(n_));
  info_ = Eigen::Success;
  return true;
}

FundamentalDecomposition& FundamentalDecomposition::compute_constraints(
    const Eigen::Ref<const MatrixXd>& A) {
  UKDYN_CHECK(A.rows() == m_ && A.cols() == n_, "compute_constraints: A has the wrong size");
  UKDYN_CHECK(info_ == Eigen::Success, "compute_constraints: M is not factorized");
  // Wᵀ = L⁻¹ Aᵀ (F⁻¹ Aᵀ along a mass tree)
  auto Wt = X_.leftCols(m_);
  if (!parent_.empty()) {
    Wt = A.transpose();
    for (Index j = 0; j < m_; ++j) factor_solve(X_.col(j).data());
  } else if (n_ <= kSmall && m_ > 0) {
    // all rows at once on A's own layout (W = A L⁻ᵀ), then transposed into place
    double* Y = X_.data() + n_ * m_;  // (m × n) the scratch half of X_
    lower_solve_rows(L_.data(), n_, inv_ldiag_.data(), A.data(), A.outerStride(), Y, m_, n_);
    for (Index j = 0; j < m_; ++j) {
      double* x = X_.col(j).data();
      for (Index i = 0; i < n_; ++i) x[i] = Y[j + i * m_];
    }
  } else if (n_ > kSmall && m_ > 0) {  // (Eigen's solve takes &X(0, 0) even when X is empty)
    Wt = A.transpose();
    L_.triangularView<Eigen::Lower>().solveInPlace(Wt);
  }
  // the column norms for pivoting; where one leaves [2⁻⁴⁵⁰, 2⁴⁵⁰] (its square under- or
  // overflows: a row written as 1e-170 (x² + y² − 1), or q of 1e200), row equilibration: every
  // row j of W (column j of Wᵀ) scaled to unit norm, D = diag(1 / ‖w_j‖), so that no pivot's
  // square under- or overflows and the rank decision compares directions; the solves then take
  // D e and return D λ_D. Otherwise nothing is scaled (every ordinary model: the same bits as
  // without equilibration, one compare per row)
  equilibrated_ = false;
  for (Index j = 0; j < m_; ++j) {
    norm_[j] = X_.col(j).norm();
    // (a zero row, an inactive constraint, needs no scaling; a zero norm of a non-zero row is
    // an underflow)
    bool zero = norm_[j] == 0.0;
    for (Index i = 0; zero && i < n_; ++i) zero = X_(i, j) == 0.0;
    if (!(norm_[j] >= 0x1p-450 && norm_[j] <= 0x1p+450) && !zero) equilibrated_ = true;
  }
  if (equilibrated_) {
    for (Index j = 0; j < m_; ++j) {
      double* x = X_.col(j).data();
      const double norm = detail::safe_norm(x, n_);
      norm_[j] = norm > 0.0 ? 1.0 : norm;  // (inf or NaN stay: reported as such)
      row_scale_[j] = 1.0;
      if (!(norm > 0.0) || !std::isfinite(norm)) continue;
      const double inv = 1.0 / norm;
      row_scale_[j] = inv;
      if (std::isfinite(inv)) {
        for (Index i = 0; i < n_; ++i) x[i] *= inv;
      } else {  // ‖w_j‖ subnormal
        for (Index i = 0; i < n_; ++i) x[i] /= norm;
      }
    }
  }
  // Wᵀ Π = Q [R11 R12; 0 0], then [R11 R12] = [T 0] Z when rank-deficient
  factor_qr();
  if (rank_ < m_) factor_rz();
  // 1 / T_kk for the solves
  for (Index k = 0; k < rank_; ++k) inv_tdiag_[k] = 1.0 / X_(k, k);
  return *this;
}

void FundamentalDecomposition::factor_qr() {
  const Index n = n_, m = m_, kmax = std::min(n, m);
  // sqrt(eps): below it a downdated column norm is recomputed (LAPACK dlaqp2)
  const double tol3z = std::sqrt(std::numeric_limits<double>::epsilon());
  // (norm_ holds the column norms, from compute_constraints)
  for (Index j = 0; j < m; ++j) {
    norm_ref_[j] = norm_[j];
    perm_[j] = int(j);
  }
  rank_ = 0;
  max_pivot_ = 0.0;
  double* const X = X_.data();  // (column j at X + j n)
  double* const norm = norm_.data();
  double* const norm_ref = norm_ref_.data();
  for (Index k = 0; k < kmax; ++k) {
    // pivot: bring the remaining column of largest norm to position k
    Index p = k;
    for (Index j = k + 1; j < m; ++j) {
      if (norm[j] > norm[p]) p = j;
    }
    if (p != k) {
      std::swap_ranges(X + k * n, X + (k + 1) * n, X + p * n);
      std::swap(norm_[k], norm_[p]);
      std::swap(norm_ref_[k], norm_ref_[p]);
      std::swap(perm_[k], perm_[p]);
    }
    // |R_kk| = ‖X(k:n, k)‖; stop at the numerical rank
    auto v = X_.col(k).segment(k + 1, n - k - 1);
    const double alpha = X_(k, k);
    const double sigma = v.squaredNorm();
    const double pivot = std::sqrt(alpha * alpha + sigma);
    if (k == 0) max_pivot_ = pivot;
    if (pivot == 0.0 || pivot <= threshold_ * max_pivot_) break;
    // Householder H_k = I − tau v vᵀ (v_0 = 1) with H_k X(k:n, k) = beta e_1
    double tau = 0.0;
    if (sigma > 0.0) {
      const double beta = alpha >= 0.0 ? -pivot : pivot;
      tau = (beta - alpha) / beta;
      v *= 1.0 / (alpha - beta);
      X_(k, k) = beta;
    }
    tau_[k] = tau;
    // X(k:n, j) −= tau v (vᵀ X(k:n, j)) for the trailing columns
    if (tau != 0.0) {
      const double* vk = v.data();
      for (Index j = k + 1; j < m; ++j) {
        double* xj = X_.col(j).data() + k;
        const double s = tau * (xj[0] + dot(vk, xj + 1, n - k - 1));
        xj[0] -= s;
        axpy(-s, vk, xj + 1, n - k - 1);
      }
    }
    rank_ = k + 1;
    // downdate the partial norms of the trailing columns (only a later pivot search among two
    // or more columns reads them)
    if (k + 1 >= kmax || m - (k + 1) < 2) continue;
    for (Index j = k + 1; j < m; ++j) {
      if (norm[j] == 0.0) continue;
      const double* xj = X + j * n + k;
      const double ratio = std::abs(xj[0]) / norm[j];
      const double temp = std::max(0.0, 1.0 - ratio * ratio);
      const double rel = norm[j] / norm_ref[j];
      if (temp * rel * rel <= tol3z) {
        norm[j] = std::sqrt(dot(xj + 1, xj + 1, n - k - 1));
        norm_ref[j] = norm[j];
      } else {
        norm[j] *= std::sqrt(temp);
      }
    }
  }
}

void FundamentalDecomposition::factor_rz() {
  const Index r = rank_, p = m_ - rank_;
  // rows i = r−1 … 0: Z_i on coordinates {i, r … m−1} zeroes row i of R12
  for (Index i = r - 1; i >= 0; --i) {
    auto v = X_.row(i).segment(r, p);
    const double alpha = X_(i, i);
    const double sigma = v.squaredNorm();
    if (sigma == 0.0) {
      ztau_[i] = 0.0;
      continue;
    }
    const double norm = std::sqrt(alpha * alpha + sigma);
    const double beta = alpha >= 0.0 ? -norm : norm;
    const double tau = (beta - alpha) / beta;
    v *= 1.0 / (alpha - beta);
    X_(i, i) = beta;
    ztau_[i] = tau;
    // rows l < i: row_l ← row_l Z_i
    for (Index l = 0; l < i; ++l) {
      auto xl = X_.row(l).segment(r, p);
      const double s = tau * (X_(l, i) + xl.dot(v));
      X_(l, i) -= s;
      xl -= s * v;
    }
  }
}

void FundamentalDecomposition::apply_q(Eigen::Ref<VectorXd> x, bool transpose) const {
  // Q x = H_0 (H_1 (⋯ H_{r−1} x));  Qᵀ x = H_{r−1} (⋯ H_0 x)
  const Index n = n_, r = rank_;
  for (Index i = 0; i < r; ++i) {
    const Index k = transpose ? i : r - 1 - i;
    if (tau_[k] == 0.0) continue;
    const double* v = X_.col(k).data() + k + 1;
    double* xk = x.data() + k;
    const double s = tau_[k] * (xk[0] + dot(v, xk + 1, n - k - 1));
    xk[0] -= s;
    axpy(-s, v, xk + 1, n - k - 1);
  }
}

void FundamentalDecomposition::apply_z(Eigen::Ref<VectorXd> x, bool transpose) const {
  // Z x = Z_0 (⋯ Z_{r−1} x);  Zᵀ x = Z_{r−1} (⋯ Z_0 x)
  const Index r = rank_, p = m_ - rank_;
  if (p == 0) return;
  for (Index j = 0; j < r; ++j) {
    const Index i = transpose ? j : r - 1 - j;
    if (ztau_[i] == 0.0) continue;
    const auto v = X_.row(i).segment(r, p);
    auto xt = x.segment(r, p);
    const double s = ztau_[i] * (x[i] + xt.dot(v.transpose()));
    x[i] -= s;
    xt -= s * v.transpose();
  }
}

void FundamentalDecomposition::factor_solve(double* x) const {
  if (parent_.empty()) {
    lower_solve(L_.data(), n_, inv_ldiag_.data(), x, n_);
  } else {
    detail::tree_lt_solve(L_.data(), parent_.data(), inv_ldiag_.data(), x, n_);
  }
}

void FundamentalDecomposition::factor_transpose_solve(double* x) const {
  if (parent_.empty()) {
    lower_transpose_solve(L_.data(), n_, inv_ldiag_.data(), x, n_);
  } else {
    detail::tree_l_solve(L_.data(), parent_.data(), inv_ldiag_.data(), x, n_);
  }
}

void FundamentalDecomposition::factor_multiply(const double* x, double* y) const {
  if (parent_.empty()) {
    lower_multiply(L_.data(), n_, x, y, n_);
  } else {
    detail::tree_lt_multiply(L_.data(), parent_.data(), x, y, n_);
  }
}

void FundamentalDecomposition::solve_factor(Eigen::Ref<MatrixXd> X) const {
  UKDYN_CHECK(X.rows() == n_ && info_ == Eigen::Success, "solve_factor: wrong size or no factor");
  for (Index j = 0; j < X.cols(); ++j) factor_solve(X.col(j).data());  // (columns contiguous)
}

void FundamentalDecomposition::solve_mass(const Eigen::Ref<const VectorXd>& f,
                                          Eigen::Ref<VectorXd> x) const {
  UKDYN_CHECK(f.size() == n_ && x.size() == n_, "solve_mass: wrong sizes");
  // x = L⁻ᵀ L⁻¹ f
  x = f;
  factor_solve(x.data());
  factor_transpose_solve(x.data());
}

void FundamentalDecomposition::apply_pinv(const Eigen::Ref<const VectorXd>& e,
                                          Eigen::Ref<VectorXd> y) {
  UKDYN_CHECK(e.size() == m_ && y.size() == n_, "apply_pinv: wrong sizes");
  const Index r = rank_;
  // w = Z Πᵀ D e
  if (equilibrated_) {
    for (Index k = 0; k < m_; ++k) wm_[k] = e[perm_[k]] * row_scale_[perm_[k]];
  } else {
    for (Index k = 0; k < m_; ++k) wm_[k] = e[perm_[k]];
  }
  apply_z(wm_, false);
  // u = T⁻ᵀ w_{1:r}
  upper_transpose_solve(X_.data(), n_, inv_tdiag_.data(), wm_.data(), r);
  // y = Q [u; 0]
  y.head(r) = wm_.head(r);
  y.tail(n_ - r).setZero();
  apply_q(y, false);
}

void FundamentalDecomposition::solve_ideal(const Eigen::Ref<const VectorXd>& e,
                                           Eigen::Ref<VectorXd> dqdd, Eigen::Ref<VectorXd> Qc,
                                           Eigen::Ref<VectorXd> lambda) {
  UKDYN_CHECK(dqdd.size() == n_ && Qc.size() == n_ && lambda.size() == m_,
              "solve_ideal: wrong sizes");
  const Index r = rank_;
  // y = W⁺ e (leaves u = T⁻ᵀ w_{1:r} in wm_)
  apply_pinv(e, wn_);
  // Qc_ideal = L y;  q'' − a = L⁻ᵀ y
  factor_multiply(wn_.data(), Qc.data());
  dqdd = wn_;
  factor_transpose_solve(dqdd.data());
  // lambda = D Π Zᵀ [T⁻¹ u; 0]
  upper_solve(X_.data(), n_, inv_tdiag_.data(), wm_.data(), r);
  wm_.tail(m_ - r).setZero();
  apply_z(wm_, true);
  if (equilibrated_) {
    for (Index k = 0; k < m_; ++k) lambda[perm_[k]] = wm_[k] * row_scale_[perm_[k]];
  } else {
    for (Index k = 0; k < m_; ++k) lambda[perm_[k]] = wm_[k];
  }
}

void FundamentalDecomposition::project_nonideal(const Eigen::Ref<const VectorXd>& C,
                                                Eigen::Ref<VectorXd> dqdd, Eigen::Ref<VectorXd> Qc,
                                                Eigen::Ref<VectorXd> lambda) {
  UKDYN_CHECK(C.size() == n_ && dqdd.size() == n_ && Qc.size() == n_ && lambda.size() == m_,
              "project_nonideal: wrong sizes");
  const Index r = rank_;
  // v = Qᵀ L⁻¹ C
  wn_ = C;
  factor_solve(wn_.data());
  apply_q(wn_, true);
  // lambda = −D G_D⁺ D A M⁻¹ C = −D Π Zᵀ [T⁻¹ v_{1:r}; 0]
  wm_.head(r) = wn_.head(r);
  upper_solve(X_.data(), n_, inv_tdiag_.data(), wm_.data(), r);
  wm_.tail(m_ - r).setZero();
  apply_z(wm_, true);
  if (equilibrated_) {
    for (Index k = 0; k < m_; ++k) lambda[perm_[k]] = -wm_[k] * row_scale_[perm_[k]];
  } else {
    for (Index k = 0; k < m_; ++k) lambda[perm_[k]] = -wm_[k];
  }
  // c⊥ = (I − W⁺W) L⁻¹ C = Q [0; v_{r+1:n}]
  wn_.head(r).setZero();
  apply_q(wn_, false);
  // Qc_nonideal = L c⊥;  q''_nonideal = L⁻ᵀ c⊥
  factor_multiply(wn_.data(), Qc.data());
  dqdd = wn_;
  factor_transpose_solve(dqdd.data());
}

}  // namespace ukdyn

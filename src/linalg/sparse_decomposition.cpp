// SPDX-License-Identifier: BSD-3-Clause
// SparseDecomposition, the numerical part (every evaluation; no allocation): block Cholesky of M,
// W = A L⁻ᵀ, G = W Wᵀ, the rank-revealing up-looking LDLᵀ of P G Pᵀ, the null-space basis of
// the dropped rows, and the solves of linalg/sparse.hpp.
#include <algorithm>
#include <cmath>

#include "linalg/safe_norm.hpp"
#include "ukdyn/linalg/sparse.hpp"

namespace ukdyn {

namespace {
// The block kernels for an s × s column-major block; S > 0 fixes s at compile time (bodies'
// blocks are 3 × 3 and 4 × 4), S = 0 takes it at run time. The same operations in the same order
// either way.

// A = L Lᵀ in place on the lower triangle of A; inv ← 1 / L_kk; false unless every pivot is
// positive
template <Index S>
bool cholesky_kernel(double* A, Index size, double* inv) {
  const Index s = S > 0 ? S : size;
  for (Index k = 0; k < s; ++k) {
    double* Ak = A + k * s;
    if (!(Ak[k] > 0.0)) return false;
    const double d = std::sqrt(Ak[k]);
    inv[k] = 1.0 / d;
    Ak[k] = d;
    for (Index i = k + 1; i < s; ++i) Ak[i] *= inv[k];
    for (Index j = k + 1; j < s; ++j) {
      const double f = Ak[j];
      double* Aj = A + j * s;
      for (Index i = j; i < s; ++i) Aj[i] -= f * Ak[i];
    }
  }
  return true;
}

// x ← L⁻¹ x, L the lower triangle
template <Index S>
inline void lower_solve_kernel(const double* L, const double* inv, double* x, Index size) {
  const Index s = S > 0 ? S : size;
  for (Index k = 0; k < s; ++k) {
    const double xk = (x[k] *= inv[k]);
    const double* Lk = L + k * s;
    for (Index i = k + 1; i < s; ++i) x[i] -= Lk[i] * xk;
  }
}

// x ← L⁻ᵀ x
template <Index S>
inline void upper_solve_kernel(const double* L, const double* inv, double* x, Index size) {
  const Index s = S > 0 ? S : size;
  for (Index k = s - 1; k >= 0; --k) {
    const double* Lk = L + k * s;
    double v = x[k];
    for (Index i = k + 1; i < s; ++i) v -= Lk[i] * x[i];
    x[k] = v * inv[k];
  }
}

// M_A,bb = M_bb + Σ_i g_i a_i a_iᵀ + r s_b I into L (then factorized in place, inv ← 1 / L_kk)
// over the rows i local to the block (CSR rows [r0, r1) of A, their s entries at Av + row_ptr[i]),
// g_i = s_b / ‖a_i‖² (0 for an inactive row) into g; false unless M_A,bb is positive definite
template <Index S>
bool augment_kernel(const double* M, double* L, double* inv, Index size, double sb, const int* r0,
                    const int* r1, const int* row_ptr, const double* Av, double* g,
                    double regularization) {
  const Index s = S > 0 ? S : size;
  std::copy(M, M + s * s, L);
  for (const int* p = r0; p != r1; ++p) {
    const double* a = Av + row_ptr[*p];  // the block's s columns in order
    double norm2 = 0.0;
    for (Index k = 0; k < s; ++k) norm2 += a[k] * a[k];
    if (!(norm2 > 0.0)) {  // an inactive row
      g[*p] = 0.0;
      continue;
    }
    const double gi = sb / norm2;
    g[*p] = gi;
    for (Index j = 0; j < s; ++j) {
      const double f = gi * a[j];
      for (Index k = j; k < s; ++k) L[j * s + k] += f * a[k];
    }
  }
  if (regularization > 0.0) {
    for (Index k = 0; k < s; ++k) L[k * s + k] += regularization * sb;
  }
  return cholesky_kernel<S>(L, s, inv);
}

// Q += Σ_i g_i b_i a_i over the rows i local to a block (as augment_kernel), Q its s entries
template <Index S>
void augment_forces_kernel(double* Q, Index size, const int* r0, const int* r1, const int* row_ptr,
                           const double* Av, const double* g, const double* b) {
  const Index s = S > 0 ? S : size;
  for (const int* p = r0; p != r1; ++p) {
    const double gb = g[*p] * b[*p];
    if (gb == 0.0) continue;
    const double* a = Av + row_ptr[*p];
    for (Index k = 0; k < s; ++k) Q[k] += gb * a[k];
  }
}

// y = L x, L the lower triangle: y_i = Σ_{k <= i} L_ik x_k
template <Index S>
inline void lower_multiply_kernel(const double* L, const double* x, double* y, Index size) {
  const Index s = S > 0 ? S : size;
  for (Index i = 0; i < s; ++i) y[i] = 0.0;
  for (Index k = 0; k < s; ++k) {
    const double xk = x[k];
    for (Index i = k; i < s; ++i) y[i] += L[k * s + i] * xk;
  }
}

// v + Σ_t w_t x_t over one segment of a row of W (a whole block's columns)
template <Index S>
inline double dot_kernel(const double* w, const double* x, Index size, double v) {
  const Index s = S > 0 ? S : size;
  for (Index t = 0; t < s; ++t) v += w[t] * x[t];
  return v;
}
inline double segment_dot(const double* w, const double* x, Index s, double v) {
  switch (s) {
    case 3:
      return dot_kernel<3>(w, x, s, v);
    case 4:
      return dot_kernel<4>(w, x, s, v);
    default:
      return dot_kernel<0>(w, x, s, v);
  }
}
bool block_cholesky(double* A, Index s, double* inv) {
  switch (s) {
    case 3:
      return cholesky_kernel<3>(A, s, inv);
    case 4:
      return cholesky_kernel<4>(A, s, inv);
    default:
      return cholesky_kernel<0>(A, s, inv);
  }
}

// whether every pivot of the block's factor is regular (SparseDecomposition::pivot_is_regular):
// M the block (s × s, column-major), inv its 1 / L_kk
bool regular_pivots(const double* M, const double* inv, Index s) {
  for (Index k = 0; k < s; ++k) {
    if (!SparseDecomposition::pivot_is_regular(1.0 / (inv[k] * inv[k]), M[k * s + k])) return false;
  }
  return true;
}

inline void block_lower_solve(const double* L, const double* inv, double* x, Index s) {
  switch (s) {
    case 3:
      return lower_solve_kernel<3>(L, inv, x, s);
    case 4:
      return lower_solve_kernel<4>(L, inv, x, s);
    default:
      return lower_solve_kernel<0>(L, inv, x, s);
  }
}

inline void block_lower_multiply(const double* L, const double* x, double* y, Index s) {
  switch (s) {
    case 3:
      return lower_multiply_kernel<3>(L, x, y, s);
    case 4:
      return lower_multiply_kernel<4>(L, x, y, s);
    default:
      return lower_multiply_kernel<0>(L, x, y, s);
  }
}

inline void block_upper_solve(const double* L, const double* inv, double* x, Index s) {
  switch (s) {
    case 3:
      return upper_solve_kernel<3>(L, inv, x, s);
    case 4:
      return upper_solve_kernel<4>(L, inv, x, s);
    default:
      return upper_solve_kernel<0>(L, inv, x, s);
  }
}
}  // namespace

// --- M ------------------------------------------------------------------------------------

Eigen::Map<MatrixXd> SparseDecomposition::mass_block(Index b) {
  const Index s = block_size(b);
  return Eigen::Map<MatrixXd>(Mv_.data() + blk_val_[std::size_t(b)], s, s);
}

Eigen::Map<const MatrixXd> SparseDecomposition::mass_block(Index b) const {
  const Index s = block_size(b);
  return Eigen::Map<const MatrixXd>(Mv_.data() + blk_val_[std::size_t(b)], s, s);
}

double SparseDecomposition::mass_max_abs() const {
  double worst = 0.0;
  for (double v : Mv_) worst = std::max(worst, std::abs(v));
  return worst;
}

double SparseDecomposition::mass_asymmetry() const {
  double worst = 0.0;
  for (Index b = 0; b < block_count(); ++b) {
    const auto Mb = mass_block(b);
    for (Index j = 0; j < Mb.cols(); ++j) {
      for (Index i = 0; i < j; ++i) worst = std::max(worst, std::abs(Mb(i, j) - Mb(j, i)));
    }
  }
  return worst;
}

bool SparseDecomposition::mass_finite() const {
  for (double v : Mv_) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

SparseDecomposition& SparseDecomposition::compute_mass() {
  // M_bb = L_b L_bᵀ, block by block (constant blocks once); a singular block is checked to be
  // positive semi-definite and left for compute_augmented_mass (a block singular by
  // construction: checked at the first compute only)
  info_ = Eigen::Success;
  undetermined_block_ = -1;
  for (Index b = 0; b < block_count(); ++b) {
    const std::size_t bs = std::size_t(b);
    if ((blk_const_[bs] || blk_known_[bs]) && checked_) continue;
    const Index s = block_size(b), v0 = blk_val_[bs], o = block_offset(b);
    // a block found singular before skips the regular attempt (M_A serves any PSD block)
    if (!blk_sing_[bs]) {
      std::copy(Mv_.begin() + v0, Mv_.begin() + v0 + s * s, Lv_.begin() + v0);
      if (block_cholesky(Lv_.data() + v0, s, inv_ldiag_.data() + o) &&
          regular_pivots(Mv_.data() + v0, inv_ldiag_.data() + o, s)) {
        continue;
      }
    }
    // positive semi-definite: M_bb + 1e-10 max|M_bb| I is positive definite (a zero block is)
    double scale = 0.0;
    for (Index p = v0; p < v0 + s * s; ++p) scale = std::max(scale, std::abs(Mv_[std::size_t(p)]));
    if (scale > 0.0) {
      std::copy(Mv_.begin() + v0, Mv_.begin() + v0 + s * s, Lv_.begin() + v0);
      for (Index k = 0; k < s; ++k) Lv_[std::size_t(v0 + k * s + k)] += 1e-10 * scale;
      if (!block_cholesky(Lv_.data() + v0, s, inv_ldiag_.data() + o)) {
        info_ = Eigen::NumericalIssue;
        checked_ = false;
        return *this;
      }
    }
    if (!blk_sing_[bs]) {
      blk_sing_[bs] = 1;
      ++singular_blocks_;
    }
  }
  checked_ = true;
  return *this;
}

SparseDecomposition& SparseDecomposition::compute_augmented_mass(double regularization) {
  info_ = Eigen::Success;
  undetermined_block_ = -1;
  if (singular_blocks_ == 0) return *this;
  double global = -1.0;  // largest diagonal of M, for a zero block (found when first needed)
  for (Index b = 0; b < block_count(); ++b) {
    const std::size_t bs = std::size_t(b);
    if (!blk_sing_[bs]) continue;
    const Index s = block_size(b), v0 = blk_val_[bs], o = block_offset(b);
    const double* Mb = Mv_.data() + v0;
    // M_A,bb = M_bb + Σ_i g_i a_i a_iᵀ over the rows local to b, g_i = s_b / ‖a_i‖²,
    // s_b = max diag M_bb
    double sb = Mb[0];
    for (Index k = 1; k < s; ++k) sb = std::max(sb, Mb[k * s + k]);
    if (!(sb > 0.0)) {
      if (global < 0.0) {
        global = 0.0;
        for (Index c = 0; c < block_count(); ++c) {
          global = std::max(global, mass_block(c).diagonal().maxCoeff());
        }
        if (!(global > 0.0)) global = 1.0;
      }
      sb = global;
    }
    const int* r0 = local_rows_.data() + local_row_ptr_[bs];
    const int* r1 = local_rows_.data() + local_row_ptr_[bs + 1];
    double* L = Lv_.data() + v0;
    double* inv = inv_ldiag_.data() + o;
    bool ok;
    switch (s) {
      case 3:
        ok = augment_kernel<3>(Mb, L, inv, s, sb, r0, r1, row_ptr_.data(), Av_.data(),
                               aug_g_.data(), regularization);
        break;
      case 4:
        ok = augment_kernel<4>(Mb, L, inv, s, sb, r0, r1, row_ptr_.data(), Av_.data(),
                               aug_g_.data(), regularization);
        break;
      default:
        ok = augment_kernel<0>(Mb, L, inv, s, sb, r0, r1, row_ptr_.data(), Av_.data(),
                               aug_g_.data(), regularization);
    }
    if (!ok) {
      info_ = Eigen::NumericalIssue;
      undetermined_block_ = b;
      return *this;
    }
  }
  return *this;
}

void SparseDecomposition::augment_forces(const Eigen::Ref<const VectorXd>& b,
                                         Eigen::Ref<VectorXd> Q) const {
  // Q_b += Σ_i g_i b_i a_i over the rows local to each singular block
  for (Index blk = 0; blk < block_count(); ++blk) {
    const std::size_t bs = std::size_t(blk);
    if (!blk_sing_[bs]) continue;
    const Index s = block_size(blk);
    double* Qb = Q.data() + block_offset(blk);
    const int* r0 = local_rows_.data() + local_row_ptr_[bs];
    const int* r1 = local_rows_.data() + local_row_ptr_[bs + 1];
    switch (s) {
      case 3:
        augment_forces_kernel<3>(Qb, s, r0, r1, row_ptr_.data(), Av_.data(), aug_g_.data(),
                                 b.data());
        break;
      case 4:
        augment_forces_kernel<4>(Qb, s, r0, r1, row_ptr_.data(), Av_.data(), aug_g_.data(),
                                 b.data());
        break;
      default:
        augment_forces_kernel<0>(Qb, s, r0, r1, row_ptr_.data(), Av_.data(), aug_g_.data(),
                                 b.data());
    }
  }
}

void SparseDecomposition::mass_lower_solve(double* x) const {
  for (Index b = 0; b < block_count(); ++b) {
    const Index o = block_offset(b);
    block_lower_solve(Lv_.data() + blk_val_[std::size_t(b)], inv_ldiag_.data() + o, x + o,
                      block_size(b));
  }
}

void SparseDecomposition::mass_upper_solve(double* x) const {
  for (Index b = 0; b < block_count(); ++b) {
    const Index o = block_offset(b);
    block_upper_solve(Lv_.data() + blk_val_[std::size_t(b)], inv_ldiag_.data() + o, x + o,
                      block_size(b));
  }
}

void SparseDecomposition::mass_lower_multiply(const double* x, double* y) const {
  // y_i = Σ_{k <= i} L_ik x_k, block by block
  for (Index b = 0; b < block_count(); ++b) {
    const Index o = block_offset(b);
    block_lower_multiply(Lv_.data() + blk_val_[std::size_t(b)], x + o, y + o, block_size(b));
  }
}

void SparseDecomposition::solve_mass(const Eigen::Ref<const VectorXd>& f,
                                     Eigen::Ref<VectorXd> x) const {
  // x = L⁻ᵀ L⁻¹ f
  x = f;
  mass_lower_solve(x.data());
  mass_upper_solve(x.data());
}

void SparseDecomposition::solve_mass_in_place(Eigen::Ref<VectorXd> x) const {
  // x ← L⁻ᵀ L⁻¹ x
  mass_lower_solve(x.data());
  mass_upper_solve(x.data());
}

void SparseDecomposition::multiply_mass(const Eigen::Ref<const VectorXd>& x,
                                        Eigen::Ref<VectorXd> y) const {
  for (Index b = 0; b < block_count(); ++b) {
    const Index o = block_offset(b), s = block_size(b);
    y.segment(o, s).noalias() = mass_block(b) * x.segment(o, s);
  }
}

double SparseDecomposition::mass_norm_squared(const Eigen::Ref<const VectorXd>& x) const {
  // ‖Lᵀ x‖², (Lᵀ x)_k = Σ_{i >= k} L_ik x_i; xᵀ M_bb x for a singular block (L is M_A's factor)
  double sum = 0.0;
  for (Index b = 0; b < block_count(); ++b) {
    const Index o = block_offset(b), s = block_size(b);
    if (blk_sing_[std::size_t(b)]) {
      const double* Mb = Mv_.data() + blk_val_[std::size_t(b)];
      for (Index j = 0; j < s; ++j) {
        for (Index i = 0; i < s; ++i) sum += x[o + i] * Mb[j * s + i] * x[o + j];
      }
      continue;
    }
    const double* L = Lv_.data() + blk_val_[std::size_t(b)];
    for (Index k = 0; k < s; ++k) {
      double v = 0.0;
      for (Index i = k; i < s; ++i) v += L[k * s + i] * x[o + i];
      sum += v * v;
    }
  }
  return sum;
}

// --- A ------------------------------------------------------------------------------------

Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor, int>> SparseDecomposition::matrix_A()
    const {
  return Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor, int>>(
      m_, n_, Index(Av_.size()), row_ptr_.data(), col_.data(), Av_.data());
}

void SparseDecomposition::set_constraint_rows(Index k, const Eigen::Ref<const MatrixXd>& A_k) {
  const Index r0 = con_r0_[std::size_t(k)], rows = con_rows_[std::size_t(k)];
  const auto& lp = local_pos_[std::size_t(k)];
  for (Index r = 0; r < rows; ++r) {
    double* row = Av_.data() + row_ptr_[std::size_t(r0 + r)];
    if (lp.empty()) {
      // dense rows: all n columns in order
      for (Index c = 0; c < n_; ++c) row[c] = A_k(r, c);
    } else {
      // local columns into their places (the rest of the pattern stays zero)
      for (std::size_t j = 0; j < lp.size(); ++j) row[lp[j]] = A_k(r, Index(j));
    }
  }
}

void SparseDecomposition::zero_constraint_rows(Index k) {
  const Index r0 = con_r0_[std::size_t(k)], rows = con_rows_[std::size_t(k)];
  std::fill(Av_.begin() + row_ptr_[std::size_t(r0)], Av_.begin() + row_ptr_[std::size_t(r0 + rows)],
            0.0);
}

void SparseDecomposition::multiply_A(const Eigen::Ref<const VectorXd>& x,
                                     Eigen::Ref<VectorXd> y) const {
  for (Index i = 0; i < m_; ++i) {
    double v = 0.0;
    for (int p = row_ptr_[std::size_t(i)]; p < row_ptr_[std::size_t(i) + 1]; ++p) {
      v += Av_[std::size_t(p)] * x[col_[std::size_t(p)]];
    }
    y[i] = v;
  }
}

void SparseDecomposition::multiply_At(const Eigen::Ref<const VectorXd>& lambda,
                                      Eigen::Ref<VectorXd> y) const {
  y.setZero();
  for (Index i = 0; i < m_; ++i) {
    const double li = lambda[i];
    if (li == 0.0) continue;
    for (int p = row_ptr_[std::size_t(i)]; p < row_ptr_[std::size_t(i) + 1]; ++p) {
      y[col_[std::size_t(p)]] += Av_[std::size_t(p)] * li;
    }
  }
}

void SparseDecomposition::share(Index k, const Eigen::Ref<const VectorXd>& lambda,
                                Eigen::Ref<VectorXd> y) const {
  const Index r0 = con_r0_[std::size_t(k)], rows = con_rows_[std::size_t(k)];
  // every row of constraint k has the same pattern: zero it, then accumulate
  for (int p = row_ptr_[std::size_t(r0)]; p < row_ptr_[std::size_t(r0) + 1]; ++p) {
    y[col_[std::size_t(p)]] = 0.0;
  }
  for (Index i = r0; i < r0 + rows; ++i) {
    const double li = lambda[i];
    for (int p = row_ptr_[std::size_t(i)]; p < row_ptr_[std::size_t(i) + 1]; ++p) {
      y[col_[std::size_t(p)]] += Av_[std::size_t(p)] * li;
    }
  }
}

double SparseDecomposition::norm_A() const {
  double s = 0.0;
  for (double v : Av_) s += v * v;
  // (without under- or overflow where the squares leave the range: A of 1e-170 or 1e200)
  if (s >= 0x1p-900 && s <= 0x1p+900) return std::sqrt(s);
  return detail::safe_norm(Av_.data(), Index(Av_.size()));
}

void SparseDecomposition::constraint_rows_dense(Index k, Eigen::Ref<MatrixXd> out) const {
  const Index r0 = con_r0_[std::size_t(k)], rows = con_rows_[std::size_t(k)];
  out.setZero();
  for (Index r = 0; r < rows; ++r) {
    for (int p = row_ptr_[std::size_t(r0 + r)]; p < row_ptr_[std::size_t(r0 + r) + 1]; ++p) {
      out(r, col_[std::size_t(p)]) = Av_[std::size_t(p)];
    }
  }
}

// --- W, G and its factorization -----------------------------------------------------------

void SparseDecomposition::multiply_W(const double* x, double* y) const {
  for (Index i = 0; i < m_; ++i) {
    double v = 0.0;
    for (int p = row_ptr_[std::size_t(i)]; p < row_ptr_[std::size_t(i) + 1]; ++p) {
      v += Wv_[std::size_t(p)] * x[col_[std::size_t(p)]];
    }
    y[i] = v;
  }
}

void SparseDecomposition::multiply_Wt(const double* lambda, double* y) const {
  std::fill(y, y + n_, 0.0);
  for (Index i = 0; i < m_; ++i) {
    const double li = lambda[i];
    if (li == 0.0) continue;
    for (int p = row_ptr_[std::size_t(i)]; p < row_ptr_[std::size_t(i) + 1]; ++p) {
      y[col_[std::size_t(p)]] += Wv_[std::size_t(p)] * li;
    }
  }
}

SparseDecomposition& SparseDecomposition::compute_constraints() {
  // W = A L⁻ᵀ: each row segment on block b is L_b⁻¹ a_ibᵀ
  std::copy(Av_.begin(), Av_.end(), Wv_.begin());
  for (Index i = 0; i < m_; ++i) {
    for (int s = seg_ptr_[std::size_t(i)]; s < seg_ptr_[std::size_t(i) + 1]; ++s) {
      const Index b = seg_blk_[std::size_t(s)], o = block_offset(b);
      block_lower_solve(Lv_.data() + blk_val_[std::size_t(b)], inv_ldiag_.data() + o,
                        Wv_.data() + seg_pos_[std::size_t(s)], block_size(b));
    }
  }
  // G = W Wᵀ (permuted, upper): G_ij = Σ_b w_ib · w_jb. Each entry's first product is
  // assigned (program_first_), the others added in order (program_): the same bits as adding
  // them all to zero (+0 + x is x except for x = −0, which a dot started from +0 is not without
  // fused multiply-adds; with them a −0 entry would only be added to +0 or squared), without
  // clearing G first
  const auto assemble_G = [this] {
    const double* W = Wv_.data();
    for (const Product& pr : program_first_) {
      Gx_[std::size_t(pr.target)] = segment_dot(W + pr.wi, W + pr.wj, pr.len, 0.0);
    }
    for (const Product& pr : program_) {
      Gx_[std::size_t(pr.target)] += segment_dot(W + pr.wi, W + pr.wj, pr.len, 0.0);
    }
  };
  assemble_G();
  // row equilibration where a G_kk = ‖w_k‖² under- or overflows (see linalg/sparse.hpp; the
  // rank test d_k <= tau² G_kk is relative to each row's own norm already): w_i ← w_i / ‖w_i‖
  // and G again. Otherwise nothing is scaled (the common case, one compare per row): lambda is
  // G⁺ e, bit for bit as without equilibration
  const auto diagonal_in_range = [this] {
    for (Index k = 0; k < m_; ++k) {
      const double g = Gx_[std::size_t(Gdiag_[std::size_t(k)])];
      if (g >= 0x1p-900 && g <= 0x1p+900) continue;
      // zero: a zero row (an inactive constraint), or one whose squares underflowed
      const int i = perm_[std::size_t(k)];
      bool zero = g == 0.0;
      for (int p = row_ptr_[std::size_t(i)]; zero && p < row_ptr_[std::size_t(i) + 1]; ++p) {
        zero = Wv_[std::size_t(p)] == 0.0;
      }
      if (!zero) return false;
    }
    return true;
  };
  equilibrated_ = !diagonal_in_range();
  if (equilibrated_) {
    for (Index i = 0; i < m_; ++i) {
      double* w = Wv_.data() + row_ptr_[std::size_t(i)];
      const Index len = row_ptr_[std::size_t(i) + 1] - row_ptr_[std::size_t(i)];
      const double norm = detail::safe_norm(w, len);
      row_scale_[std::size_t(i)] = 1.0;
      if (!(norm > 0.0) || !std::isfinite(norm)) continue;
      const double inv = 1.0 / norm;
      row_scale_[std::size_t(i)] = inv;
      if (std::isfinite(inv)) {
        for (Index p = 0; p < len; ++p) w[p] *= inv;
      } else {  // ‖w_i‖ subnormal: lambda = D lambda_D is then not finite, and reported
        for (Index p = 0; p < len; ++p) w[p] /= norm;
      }
    }
    assemble_G();
  }
  factor_G();
  null_basis();
  return *this;
}

void SparseDecomposition::factor_G() {
  // up-looking LDLᵀ: row k of L_G from the sparse triangular solve L_G(0:k,0:k) D y = G(0:k, k)
  // along the elimination tree; a pivot d_k <= tau² G_kk marks row k as dependent on the rows
  // before it: d_k = 0 and column k of L_G stays zero (its entries would be roundoff / roundoff)
  const int m = int(m_);
  const double tau2 = threshold_ * threshold_;
  Index dropped = 0;
  rechecked_ = 0;
  // the smallest d_k / G_kk of the kept rows (sin² of the angle of w_k to the rows before it)
  double min_ratio = 1.0;
  for (int k = 0; k < m; ++k) {
    double* Y = Y_.data();
    Lnz_[std::size_t(k)] = 0;
    Y[k] = 0.0;
    // scatter column k of G
    for (int p = Gp_[std::size_t(k)]; p < Gp_[std::size_t(k) + 1]; ++p) {
      Y[Gi_[std::size_t(p)]] += Gx_[std::size_t(p)];
    }
    // d_k = G_kk − Σ l_ki² d_i over the pattern of row k of L_G (the union of the elimination
    // tree's paths from column k's entries, in topological order: structural, found once by the
    // analysis, at pattern_[pattern_[k] .. pattern_[k + 1]))
    double d = Y[k];
    Y[k] = 0.0;
    for (int top = pattern_[std::size_t(k)]; top < pattern_[std::size_t(k) + 1]; ++top) {
      const int i = pattern_[std::size_t(top)];
      const double yi = Y[i];
      Y[i] = 0.0;
      const int p2 = Lp_[std::size_t(i)] + Lnz_[std::size_t(i)];
      for (int p = Lp_[std::size_t(i)]; p < p2; ++p)
        Y[Li_[std::size_t(p)]] -= Lx_[std::size_t(p)] * yi;
      const double lki = yi * D_[std::size_t(i)];  // D_ holds 1/d_i, 0 for dropped rows
      d -= lki * yi;
      Li_[std::size_t(p2)] = k;
      Lx_[std::size_t(p2)] = lki;
      ++Lnz_[std::size_t(i)];
    }
    // rank decision. The pivot of G carries roundoff of order eps κ(G_11) G_kk (G_11: the rows
    // before k); a suspicious pivot is also estimated in the space of W: v = L_G⁻ᵀ e_k (rows
    // <= k) gives w_k − Σ_j c_j w_j = Σ_j v_j w_j, whose norm is d_k^{1/2} with an error of
    // order eps κ(G_11) ‖W‖ ‖v‖ — much smaller when the dependence is local, larger along long
    // loops. The row is dependent when either estimate is below the threshold. A row coupled
    // only to rows with no coupling before them has a pivot with a known small roundoff
    // (pivot_margin_, +inf for the others): clear of the threshold by it, it is independent.
    const double gkk = Gx_[std::size_t(Gdiag_[std::size_t(k)])];
    double d_margin = d;  // the pivot for the rank margin: the recomputed one where there is one
    if (gkk != 0.0 && d > tau2 * gkk && d <= kSuspect * gkk &&
        d <= (tau2 + pivot_margin_[std::size_t(k)]) * gkk) {
      d_margin = recompute_pivot(k);
      if (d_margin <= tau2 * gkk) d = 0.0;
    }
    if (gkk == 0.0) {
      dropped_[std::size_t(k)] = 2;  // zero row of A (an inactive constraint)
      D_[std::size_t(k)] = 0.0;
      ++dropped;
    } else if (d <= tau2 * gkk) {
      dropped_[std::size_t(k)] = 1;
      D_[std::size_t(k)] = 0.0;
      ++dropped;
    } else {
      dropped_[std::size_t(k)] = 0;
      D_[std::size_t(k)] = 1.0 / d;
      min_ratio = std::min(min_ratio, d_margin / gkk);
    }
  }
  rank_ = m_ - dropped;
  // rank margin: min over the kept rows of ‖w_k⊥‖ / ‖w_k‖ (1 without kept rows)
  rank_margin_ = std::sqrt(min_ratio);
}

double SparseDecomposition::recompute_pivot(int k) {
  // v = L_G⁻ᵀ e_k over the rows eliminated so far (permuted order; row k of L_G is complete).
  // Column j of L_G holds rows in (j, k] only, each written before v_j is: no clearing
  double* v = wm3_.data();
  v[k] = 1.0;
  for (int j = k - 1; j >= 0; --j) {
    double x = 0.0;
    for (int p = Lp_[std::size_t(j)]; p < Lp_[std::size_t(j)] + Lnz_[std::size_t(j)]; ++p) {
      x -= Lx_[std::size_t(p)] * v[Li_[std::size_t(p)]];
    }
    v[j] = x;
  }
  // r = Wᵀ Pᵀ v = Σ_j v_j w_(perm j);  d_k = ‖r‖²
  double* r = wn3_.data();
  std::fill(r, r + n_, 0.0);
  for (int j = 0; j <= k; ++j) {
    const double vj = v[j];
    if (vj == 0.0) continue;
    const int i = perm_[std::size_t(j)];
    for (int p = row_ptr_[std::size_t(i)]; p < row_ptr_[std::size_t(i) + 1]; ++p) {
      r[col_[std::size_t(p)]] += Wv_[std::size_t(p)] * vj;
    }
  }
  double d = 0.0;
  for (Index c = 0; c < n_; ++c) d += r[c] * r[c];
  ++rechecked_;
  return d;
}

void SparseDecomposition::null_basis() {
  // n_k = L_G⁻ᵀ e_k for each dependent row k (zero rows need no column: their n_k = e_k is
  // orthogonal to every other one); orthonormalized by modified Gram–Schmidt, twice
  d_ = 0;
  for (Index k = 0; k < m_; ++k) {
    if (dropped_[std::size_t(k)] != 1) continue;
    if (d_ == N_.cols()) {
      // more dependent rows than reserved: the only allocation after construction
      N_.conservativeResize(m_, std::min(m_, std::max<Index>(1, 2 * N_.cols())));
      null_rows_.resize(std::size_t(N_.cols()));
    }
    double* x = N_.col(d_).data();
    std::fill(x, x + m_, 0.0);
    x[k] = 1.0;
    for (Index j = k - 1; j >= 0; --j) {
      double v = 0.0;
      for (int p = Lp_[std::size_t(j)]; p < Lp_[std::size_t(j)] + Lnz_[std::size_t(j)]; ++p) {
        v += Lx_[std::size_t(p)] * x[Li_[std::size_t(p)]];
      }
      x[j] = -v;
    }
    auto col = N_.col(d_);
    for (int pass = 0; pass < 2; ++pass) {
      for (Index c = 0; c < d_; ++c) col -= N_.col(c).dot(col) * N_.col(c);
    }
    const double norm = col.norm();
    if (!(norm > 0.0)) continue;
    col /= norm;
    null_rows_[std::size_t(d_)] = int(k);
    ++d_;
  }
}

void SparseDecomposition::project_range(double* x) const {
  // x ← (I − N Nᵀ) x, and zero on zero rows
  for (Index k = 0; k < m_; ++k) {
    if (dropped_[std::size_t(k)] == 2) x[k] = 0.0;
  }
  Eigen::Map<VectorXd> v(x, m_);
  for (Index c = 0; c < d_; ++c) v -= N_.col(c).dot(v) * N_.col(c);
}

void SparseDecomposition::solve_G_permuted(double* x) {
  // x ← (I − N Nᵀ) L_G⁻ᵀ D⁺ L_G⁻¹ (I − N Nᵀ) x
  if (d_ > 0 || rank_ < m_) project_range(x);
  const int m = int(m_);
  for (int j = 0; j < m; ++j) {
    const double xj = x[j];
    if (xj != 0.0) {
      for (int p = Lp_[std::size_t(j)]; p < Lp_[std::size_t(j) + 1]; ++p) {
        x[Li_[std::size_t(p)]] -= Lx_[std::size_t(p)] * xj;
      }
    }
  }
  for (int j = 0; j < m; ++j) x[j] *= D_[std::size_t(j)];
  for (int j = m - 1; j >= 0; --j) {
    double v = x[j];
    for (int p = Lp_[std::size_t(j)]; p < Lp_[std::size_t(j) + 1]; ++p) {
      v -= Lx_[std::size_t(p)] * x[Li_[std::size_t(p)]];
    }
    x[j] = v;
  }
  if (d_ > 0) project_range(x);
}

void SparseDecomposition::scale_rows(const double* x, double* y) const {
  for (Index i = 0; i < m_; ++i) y[i] = x[i] * row_scale_[std::size_t(i)];
}

void SparseDecomposition::solve_min_norm(const double* e, double* lambda, double* y) {
  // lambda = G⁺ e, y = Wᵀ lambda
  for (Index k = 0; k < m_; ++k) wm_[std::size_t(k)] = e[perm_[std::size_t(k)]];
  solve_G_permuted(wm_.data());
  for (Index k = 0; k < m_; ++k) lambda[perm_[std::size_t(k)]] = wm_[std::size_t(k)];
  multiply_Wt(lambda, y);
  // one step of refinement (corrected seminormal equations): r = e − W y, lambda += G⁺ r,
  // y += Wᵀ G⁺ r — brings the error from eps κ(W)² towards that of an orthogonal factorization
  multiply_W(y, wm2_.data());
  for (Index k = 0; k < m_; ++k) {
    const Index i = perm_[std::size_t(k)];
    wm_[std::size_t(k)] = e[i] - wm2_[std::size_t(i)];
  }
  solve_G_permuted(wm_.data());
  for (Index k = 0; k < m_; ++k) {
    const Index i = perm_[std::size_t(k)];
    lambda[i] += wm_[std::size_t(k)];
    wm2_[std::size_t(i)] = wm_[std::size_t(k)];
  }
  multiply_Wt(wm2_.data(), wn2_.data());
  for (Index i = 0; i < n_; ++i) y[i] += wn2_[std::size_t(i)];
}

void SparseDecomposition::solve_ideal(const Eigen::Ref<const VectorXd>& e,
                                      Eigen::Ref<VectorXd> dqdd, Eigen::Ref<VectorXd> Qc,
                                      Eigen::Ref<VectorXd> lambda) {
  // lambda = G⁺ e;  y = Wᵀ lambda = W⁺ e (with equilibrated rows: lambda = D G_D⁺ D e)
  if (!equilibrated_) {
    solve_min_norm(e.data(), lambda.data(), wn_.data());
  } else {
    scale_rows(e.data(), wm3_.data());
    solve_min_norm(wm3_.data(), lambda.data(), wn_.data());
    scale_rows(lambda.data(), lambda.data());
  }
  // Qc = L y;  dqdd = L⁻ᵀ y
  mass_lower_multiply(wn_.data(), Qc.data());
  std::copy(wn_.begin(), wn_.end(), dqdd.data());
  mass_upper_solve(dqdd.data());
}

void SparseDecomposition::project_nonideal(const Eigen::Ref<const VectorXd>& C,
                                           Eigen::Ref<VectorXd> dqdd, Eigen::Ref<VectorXd> Qc,
                                           Eigen::Ref<VectorXd> lambda) {
  // c = L⁻¹ C;  lambda = −G⁺ W c, W⁺W c = Wᵀ G⁺ W c (equilibrated: −D G_D⁺ W_D c, W_D)
  std::copy(C.data(), C.data() + n_, wn_.begin());
  mass_lower_solve(wn_.data());
  multiply_W(wn_.data(), wm3_.data());
  solve_min_norm(wm3_.data(), lambda.data(), wn3_.data());
  if (!equilibrated_) {
    lambda = -lambda;
  } else {
    for (Index i = 0; i < m_; ++i) lambda[i] *= -row_scale_[std::size_t(i)];
  }
  // c⊥ = c − W⁺W c = (I − W⁺W) c;  Qc = L c⊥;  dqdd = L⁻ᵀ c⊥
  for (Index i = 0; i < n_; ++i) wn_[std::size_t(i)] -= wn3_[std::size_t(i)];
  mass_lower_multiply(wn_.data(), Qc.data());
  std::copy(wn_.begin(), wn_.end(), dqdd.data());
  mass_upper_solve(dqdd.data());
}

void SparseDecomposition::apply_pinv(const Eigen::Ref<const VectorXd>& e, Eigen::Ref<VectorXd> y) {
  // y = Wᵀ G⁺ e (equilibrated: W_Dᵀ G_D⁺ D e)
  if (!equilibrated_) {
    solve_min_norm(e.data(), wm3_.data(), y.data());
  } else {
    scale_rows(e.data(), wm4_.data());
    solve_min_norm(wm4_.data(), wm3_.data(), y.data());
  }
}

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// The dense engine on FundamentalDecomposition (dynamics/dense_engine.hpp), and the parts of the
// dense singular-mass completion that do not depend on the decomposition.
#include "dynamics/dense_engine.hpp"

namespace ukdyn::detail {

template <>
FundamentalDecomposition& decomposition_of<FundamentalDecomposition>(Workspace& ws) {
  return ws.decomposition;
}

const EngineOps& dense_engine() {
  static const DenseEngine<FundamentalDecomposition> engine;
  return engine;
}

double asymmetry(const MatrixXd& M) {
  double worst = 0.0;
  for (Index j = 0; j < M.cols(); ++j) {
    for (Index i = 0; i < j; ++i) worst = std::max(worst, std::abs(M(i, j) - M(j, i)));
  }
  return worst;
}

bool check_mass_entries(const MatrixXd& M, double& scale, double& asym) {
  // finite: Σ 0·M_ij is 0 unless an entry is NaN or ±Inf (Eigen's packed reductions)
  if (!((M.array() * 0.0).sum() == 0.0)) return false;
  scale = M.cwiseAbs().maxCoeff();
  // each pair (M_ij, M_ji), i < j
  const Index n = M.rows();
  const double* p = M.data();
  double worst = 0.0;
  for (Index j = 1; j < n; ++j) {
    const double* col = p + j * n;  // M_ij, i < j
    const double* row = p + j;      // M_ji = row[i n]
    for (Index i = 0; i < j; ++i) {
      const double d = std::abs(col[i] - row[i * n]);
      worst = d > worst ? d : worst;
    }
  }
  asym = worst;
  return true;
}

bool check_mass_entries_tree(const MatrixXd& M, const std::vector<Index>& parent, double& scale,
                             double& asym) {
  const Index n = M.rows();
  const double* p = M.data();
  const Index* up = parent.data();
  // one pass: Σ (M_ka − M_ak) + Σ 0·M_kk is finite unless an entry read is NaN or ±Inf (or the
  // sum overflows: an asymmetry of order 1e308); the maxima by compares (maxsd, written
  // `big > x ? big : x` so that the compiler keeps each maximum in its register: the same
  // maxima whenever the sum is finite, i.e. whenever they are used). The scale is max |M_kk|,
  // |M_ka| (the lower entries; the upper ones differ by at most the asymmetry)
  double sum = 0.0, big = 0.0, worst = 0.0;
  for (Index k = 0; k < n; ++k) {
    const double* col = p + k * n;  // M_ak = col[a]
    const double dk = col[k], ak = std::abs(dk);
    sum += dk * 0.0;
    big = big > ak ? big : ak;
    for (Index a = up[k]; a >= 0; a = up[a]) {
      const double lower = p[a * n + k], d = lower - col[a];
      const double al = std::abs(lower), ad = std::abs(d);
      sum += d;
      big = big > al ? big : al;
      worst = worst > ad ? worst : ad;
    }
  }
  if (!std::isfinite(sum)) return false;
  scale = big;
  asym = worst;
  return true;
}

bool positive_semidefinite(const System& sys, Workspace& ws, double shift) {
  using Llt = Eigen::internal::llt_inplace<double, Eigen::Lower>;
  if (sys.mass_is_block_diagonal()) {
    for (const MassBlock& b : sys.mass_blocks()) {
      if (ws.mass_singular && (b.constant() || b.singular)) continue;
      auto S = ws.M_aux.topLeftCorner(b.size, b.size);
      S.triangularView<Eigen::Lower>() = ws.M.block(b.offset, b.offset, b.size, b.size);
      S.diagonal().array() += shift;
      if (Llt::unblocked(S) != -1) return false;
    }
    return true;
  }
  ws.M_aux.triangularView<Eigen::Lower>() = ws.M;
  ws.M_aux.diagonal().array() += shift;
  return Llt::blocked(ws.M_aux) == -1;
}

namespace {
// M_A += g a aᵀ on one diagonal block (lower triangle; Mo its first entry, column-major with
// leading dimension ld), g = s / ‖a‖², a = the block's part of a row of A (entries a[k inc]);
// Qo (when not null) += g b_i a. S > 0 fixes the block size at compile time (a quaternion's 4).
template <Index S>
void add_local_row(double* Mo, Index ld, const double* a, Index inc, Index size, double s,
                   double b_i, double* Qo) {
  const Index n = S > 0 ? S : size;
  double norm2 = 0.0;
  for (Index k = 0; k < n; ++k) norm2 += a[k * inc] * a[k * inc];
  if (!(norm2 > 0.0)) return;  // an inactive row
  const double g = s / norm2;
  for (Index j = 0; j < n; ++j) {
    const double f = g * a[j * inc];
    for (Index k = j; k < n; ++k) Mo[j * ld + k] += f * a[k * inc];
    if (Qo) Qo[j] += f * b_i;
  }
}
}  // namespace

bool complete_singular_mass_locally(Workspace& ws, bool forces, bool regularize) {
  // M completed block by block with the rows local to its blocks singular by construction (a
  // quaternion's unit norm; the other blocks are constant), while they suffice:
  // M_A,bb = M_bb + Σ_local g_i a_i a_iᵀ, g_i = s_b / ‖a_i‖², s_b = max diag M_bb (as the sparse
  // engine), O(Σ size²) instead of O(Σ nnz(a_i)²)
  if (ws.singular_local_rows.empty() || ws.singular_completion == 2) return false;
  const Index n = ws.coordinate_count(), m = ws.rows();
  std::copy(ws.M.data(), ws.M.data() + n * n, ws.M_aux.data());  // (one memcpy)
  if (forces) ws.tmp_n = ws.Q;
  const auto& rows = ws.singular_local_rows;
  for (std::size_t r = 0; r < rows.size(); r += 3) {
    const Index i = rows[r], o = rows[r + 1], size = rows[r + 2];
    double* Mo = ws.M_aux.data() + o * n + o;
    const double* a = ws.A.data() + o * m + i;  // row i of A from column o
    double* Qo = forces ? ws.tmp_n.data() + o : nullptr;
    const double* Mb = ws.M.data() + o * n + o;
    double sb = Mb[0];
    for (Index k = 1; k < size; ++k) sb = std::max(sb, Mb[k * n + k]);
    if (!(sb > 0.0)) {  // a zero block: the largest diagonal of M (1 if M = 0)
      sb = ws.M.diagonal().maxCoeff();
      if (!(sb > 0.0)) sb = 1.0;
    }
    if (size == 4) {
      add_local_row<4>(Mo, n, a, m, size, sb, ws.b[i], Qo);
    } else {
      add_local_row<0>(Mo, n, a, m, size, sb, ws.b[i], Qo);
    }
  }
  // factorized, with regular pivots (SparseDecomposition::pivot_is_regular): on all of M_A the
  // first time, then on each completed block
  if (ws.decomposition.compute_mass(ws.M_aux).info() == Eigen::Success) {
    const auto& L = ws.decomposition.matrix_llt();
    const auto regular = [&](Index o, Index size) {
      for (Index k = o; k < o + size; ++k) {
        if (!SparseDecomposition::pivot_is_regular(L(k, k) * L(k, k), ws.M_aux(k, k))) {
          return false;
        }
      }
      return true;
    };
    bool ok = ws.singular_completion == 1 || regular(0, n);
    for (std::size_t r = 0; ok && ws.singular_completion == 1 && r < rows.size(); r += 3) {
      ok = regular(rows[r + 1], rows[r + 2]);
    }
    if (ok) {
      if (!regularize) ws.singular_completion = 1;
      if (forces) ws.decomposition.solve_mass(ws.tmp_n, ws.a);
      return true;
    }
  }
  // other blocks are singular too (or a projection left out the local rows): every row, from
  // now on unless this is a projection
  if (!regularize) ws.singular_completion = 2;
  return false;
}

double assemble_auxiliary_mass(Workspace& ws, bool forces) {
  double s = ws.M.diagonal().maxCoeff();
  if (!(s > 0.0)) s = 1.0;
  // M_A = M + Σ_i g_i a_i a_iᵀ (lower triangle), g_i = s / ‖a_i‖², s = max diag M; only the
  // non-zero entries of each row of A take part
  const Index n = ws.coordinate_count();
  ws.M_aux.triangularView<Eigen::Lower>() = ws.M;
  if (forces) ws.tmp_n = ws.Q;
  for (Index i = 0; i < ws.A.rows(); ++i) {
    Index nz = 0;
    double norm2 = 0.0;
    for (Index j = 0; j < n; ++j) {
      const double v = ws.A(i, j);
      if (v != 0.0) {
        ws.nonzero_cols[std::size_t(nz++)] = j;
        norm2 += v * v;
      }
    }
    if (nz == 0) continue;  // an inactive row
    const double g = s / norm2;
    for (Index p = 0; p < nz; ++p) {
      const Index j = ws.nonzero_cols[std::size_t(p)];
      const double f = g * ws.A(i, j);
      for (Index r = p; r < nz; ++r) {
        const Index k = ws.nonzero_cols[std::size_t(r)];
        ws.M_aux(std::max(j, k), std::min(j, k)) += f * ws.A(i, k);
      }
      if (forces) ws.tmp_n[j] += f * ws.b[i];
    }
  }
  return s;
}

}  // namespace ukdyn::detail

// SPDX-License-Identifier: BSD-3-Clause
// M = Lᵀ L along a tree's branches and the solves with L (linalg/tree_ltl.hpp). L_ij sits at
// L[i + j n] (column-major, lower triangle); each loop walks the ancestors of one coordinate.
#include "linalg/tree_ltl.hpp"

#include <cmath>

namespace ukdyn::detail {

namespace {
// y ← y − a x over n entries (contiguous, not overlapping: the compiler vectorizes it)
inline void axmy(double a, const double* __restrict x, double* __restrict y, Index n) {
  for (Index l = 0; l < n; ++l) y[l] -= a * x[l];
}
}  // namespace

bool tree_ltl_in_place(double* H, const Index* parent, double* inv, Index n) {
  return tree_ltl(H, n, H, parent, inv, n);
}

bool tree_ltl(const double* M, Index ldm, double* H, const Index* parent, double* inv, Index n) {
  // Row k of L has entries only at k and at its ancestors a_0 = λ(k), a_1 = λ(a_0), …, a_{d−1}
  // (d = d_k < k + 1): they are packed, nearest ancestor first, into the upper part of column k
  // (H[0 … d−1 + k n], which the factor does not use), so that row i = a_m, whose ancestors are
  // a_{m+1}, a_{m+2}, …, is packed in the same order as the tail of row k and the update of row
  // i by row k is one contiguous axpy (MuJoCo's layout; the walks along the strided lower
  // triangle were pointer chases). The same operations in the same order as walking the lower
  // triangle: the same bits.
  // (from M: its diagonal and the entries M_k,a_m; the factor reads no other)
  for (Index k = 0; k < n; ++k) {
    double* row = H + k * n;
    Index m = 0;
    for (Index i = parent[k]; i >= 0; i = parent[i]) row[m++] = M[k + i * ldm];
    H[k + k * n] = M[k + k * ldm];
  }
  // leaves first: L_kk = sqrt(H_kk), L_ki = H_ki / L_kk for the ancestors i of k, then
  // H_ij −= L_ki L_kj for the ancestors i of k and j of i (j = i included)
  for (Index k = n - 1; k >= 0; --k) {
    double& Hkk = H[k + k * n];
    if (!(Hkk > 0.0)) return false;
    const double d = std::sqrt(Hkk), r = 1.0 / d;
    Hkk = d;
    inv[k] = r;
    double* row = H + k * n;
    Index depth = 0;
    for (Index i = parent[k]; i >= 0; i = parent[i]) row[depth++] *= r;
    Index m = 0;
    for (Index i = parent[k]; i >= 0; i = parent[i], ++m) {
      const double a = row[m];
      H[i + i * n] -= a * a;
      axmy(a, row + m + 1, H + i * n, depth - m - 1);
    }
  }
  // L_ki also into the lower triangle (matrix_llt's factor; the solves read the packed rows)
  for (Index k = 0; k < n; ++k) {
    const double* row = H + k * n;
    Index m = 0;
    for (Index i = parent[k]; i >= 0; i = parent[i]) H[k + i * n] = row[m++];
  }
  return true;
}

// The solves read row k of L where the factorization packed it, L_k,a_m at L[m + k n] (m-th
// ancestor a_m of k): the same products in the same order as reading L[k + a_m n].

void tree_lt_solve(const double* L, const Index* parent, const double* inv, double* x, Index n) {
  // Lᵀ y = x, leaves first: y_k = x_k / L_kk, then x_j −= L_kj y_k for the ancestors j of k
  for (Index k = n - 1; k >= 0; --k) {
    const double y = x[k] * inv[k];
    x[k] = y;
    const double* row = L + k * n;
    for (Index j = parent[k]; j >= 0; j = parent[j]) x[j] -= *row++ * y;
  }
}

void tree_l_solve(const double* L, const Index* parent, const double* inv, double* x, Index n) {
  // L y = x, roots first: y_k = (x_k − Σ_{j ancestor of k} L_kj y_j) / L_kk
  for (Index k = 0; k < n; ++k) {
    double s = x[k];
    const double* row = L + k * n;
    for (Index j = parent[k]; j >= 0; j = parent[j]) s -= *row++ * x[j];
    x[k] = s * inv[k];
  }
}

void tree_lt_multiply(const double* L, const Index* parent, const double* x, double* y, Index n) {
  // y_j = Σ_k L_kj x_k over k = j and the descendants k of j
  for (Index k = 0; k < n; ++k) y[k] = L[k + k * n] * x[k];
  for (Index k = 0; k < n; ++k) {
    const double* row = L + k * n;
    for (Index j = parent[k]; j >= 0; j = parent[j]) y[j] += *row++ * x[k];
  }
}

}  // namespace ukdyn::detail

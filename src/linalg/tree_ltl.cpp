// SPDX-License-Identifier: BSD-3-Clause
// M = Lᵀ L along a tree's branches and the solves with L (linalg/tree_ltl.hpp). L_ij sits at
// L[i + j n] (column-major, lower triangle); each loop walks the ancestors of one coordinate.
#include "linalg/tree_ltl.hpp"

#include <cmath>

namespace ukdyn::detail {

bool tree_ltl_in_place(double* H, const Index* parent, double* inv, Index n) {
  const auto at = [H, n](Index i, Index j) -> double& { return H[i + j * n]; };
  // leaves first: L_kk = sqrt(H_kk), L_ki = H_ki / L_kk for the ancestors i of k, then
  // H_ij −= L_ki L_kj for the ancestors i of k and j of i (j = i included)
  for (Index k = n - 1; k >= 0; --k) {
    if (!(at(k, k) > 0.0)) return false;
    const double d = std::sqrt(at(k, k)), r = 1.0 / d;
    at(k, k) = d;
    inv[k] = r;
    for (Index i = parent[k]; i >= 0; i = parent[i]) at(k, i) *= r;
    for (Index i = parent[k]; i >= 0; i = parent[i]) {
      const double a = at(k, i);
      for (Index j = i; j >= 0; j = parent[j]) at(i, j) -= a * at(k, j);
    }
  }
  return true;
}

void tree_lt_solve(const double* L, const Index* parent, const double* inv, double* x, Index n) {
  // Lᵀ y = x, leaves first: y_k = x_k / L_kk, then x_j −= L_kj y_k for the ancestors j of k
  for (Index k = n - 1; k >= 0; --k) {
    const double y = x[k] * inv[k];
    x[k] = y;
    for (Index j = parent[k]; j >= 0; j = parent[j]) x[j] -= L[k + j * n] * y;
  }
}

void tree_l_solve(const double* L, const Index* parent, const double* inv, double* x, Index n) {
  // L y = x, roots first: y_k = (x_k − Σ_{j ancestor of k} L_kj y_j) / L_kk
  for (Index k = 0; k < n; ++k) {
    double s = x[k];
    for (Index j = parent[k]; j >= 0; j = parent[j]) s -= L[k + j * n] * x[j];
    x[k] = s * inv[k];
  }
}

void tree_lt_multiply(const double* L, const Index* parent, const double* x, double* y, Index n) {
  // y_j = Σ_k L_kj x_k over k = j and the descendants k of j
  for (Index k = 0; k < n; ++k) y[k] = L[k + k * n] * x[k];
  for (Index k = 0; k < n; ++k) {
    for (Index j = parent[k]; j >= 0; j = parent[j]) y[j] += L[k + j * n] * x[k];
  }
}

}  // namespace ukdyn::detail

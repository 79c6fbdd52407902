// SPDX-License-Identifier: BSD-3-Clause
// The factorization of a kinematic tree's mass matrix along its branches (not installed):
// Featherstone's LTL (Rigid Body Dynamics Algorithms, 2008, §6.5, algorithm 6.3; the LTDL of
// the same section with D^{1/2} folded into L, since the fundamental equation needs a factor F
// with M = F Fᵀ: W = A F⁻ᵀ).
//
// The coordinates form a tree given by `parent` (parent[k] < k, −1 for a root): M_ij = 0 unless
// one of i, j is an ancestor of the other (a tree's M in joint coordinates, the coordinates of
// one multi-DOF joint a chain). Then M = Lᵀ L with L lower triangular and L_ij ≠ 0 only where j
// is i or an ancestor of i: no fill-in, O(Σ_k d_k²) for the factorization and O(Σ_k d_k) for
// each solve, d_k the number of ancestors of k, against O(n³/3) and O(n²) for a dense
// Cholesky. L is kept in the lower triangle of a dense n × n column-major matrix (ld = n), so
// that FundamentalDecomposition keeps one storage for both of its factors; F = Lᵀ.
//
// Used by FundamentalDecomposition (linalg/dense_decomposition.cpp) when a system declares its
// M's tree (SystemBuilder::mass_tree). None allocates.
#pragma once

#include "ukdyn/core/types.hpp"

namespace ukdyn::detail {

/// M = Lᵀ L in place on the lower triangle of H (n × n, column-major, leading dimension n), the
/// strict upper triangle holding each row of L packed (its entries at the ancestors, nearest
/// first, in the upper part of its column: read by the solves below);
/// inv[k] = 1 / L_kk. False (H partly overwritten) unless every pivot is positive. Cost
/// O(Σ_k d_k²).
bool tree_ltl_in_place(double* H, const Index* parent, double* inv, Index n);

/// tree_ltl_in_place reading M from another matrix M (n × n, column-major, leading dimension
/// ldm): only its diagonal and its entries M_ka at the ancestors a of k are read, and only the
/// diagonal, the packed rows and the factor's entries of H are written — the rest of H's lower
/// triangle is left as it is (zero, for a factor L). The same bits as copying M into H and
/// factorizing in place, without the O(n²) copy. Cost O(n + Σ_k d_k²).
bool tree_ltl(const double* M, Index ldm, double* H, const Index* parent, double* inv, Index n);

/// The solves and the product take the L that tree_ltl_in_place left (they read the rows it
/// packed in the upper triangle).
/// x ← L⁻ᵀ x (= F⁻¹ x, the role of L⁻¹ in a dense M = L Lᵀ). Cost O(Σ_k d_k).
void tree_lt_solve(const double* L, const Index* parent, const double* inv, double* x, Index n);

/// x ← L⁻¹ x (= F⁻ᵀ x). Cost O(Σ_k d_k).
void tree_l_solve(const double* L, const Index* parent, const double* inv, double* x, Index n);

/// y ← Lᵀ x (= F x). Cost O(Σ_k d_k).
void tree_lt_multiply(const double* L, const Index* parent, const double* x, double* y, Index n);

}  // namespace ukdyn::detail

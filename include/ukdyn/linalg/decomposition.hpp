// SPDX-License-Identifier: BSD-3-Clause
/// @file linalg/decomposition.hpp
/// The decomposition behind the fundamental equation, in the shape of Eigen's decompositions.
///
/// With the Cholesky factor M = L Lᵀ and W = A L⁻ᵀ (m × n), every quantity of eqs. (9)–(12)
/// follows from a complete orthogonal decomposition of Wᵀ = L⁻¹ Aᵀ (n × m):
///
///     Wᵀ Π = Q [T 0; 0 0] Z,   T (r × r) upper triangular, r = rank A,
///
/// (Householder QR with column pivoting, then an RZ step when r < m; Π a permutation, Q and Z
/// orthogonal, kept as Householder reflectors). Because M^{−1/2} B⁺ = L⁻ᵀ W⁺ for any factor L,
/// neither M^{1/2} nor any pseudo-inverse is ever formed:
///
///     w = Z Πᵀ e,  u = T⁻ᵀ w_{1:r},  y = W⁺ e = Q [u; 0]
///     q'' − a  = L⁻ᵀ y,       Qc_ideal = L y,       lambda = G⁺ e = Π Zᵀ [T⁻¹ u; 0]
///     c = L⁻¹ C,  c⊥ = c − Q_r Q_rᵀ c:   Qc_nonideal = L c⊥,   q''_nonideal = L⁻ᵀ c⊥
///
/// Cost: compute_mass O(n³/3); compute_constraints O(m n² + 2 m² n); each solve O(n² + n m).
///
/// A kinematic tree's M (set_mass_tree): M_ij = 0 unless one of i, j is an ancestor of the other
/// in a tree of the coordinates. Then the factor is Featherstone's M = Lᵀ L along the branches
/// (linalg/tree_ltl.hpp) and every "L" above reads F = Lᵀ (any F with M = F Fᵀ gives the same
/// results): no fill-in, compute_mass O(Σ_k d_k²) and each product with F, F⁻¹ or F⁻ᵀ
/// O(Σ_k d_k), d_k the number of ancestors of coordinate k.
/// (When the rows are equilibrated, every quantity below is that of D W, see "Row
/// equilibration".)
/// Memory is reserved by the constructor; no method allocates afterwards.
///
/// Row equilibration, only where needed: when the norm of some row w_j of W leaves
/// [2⁻⁴⁵⁰, 2⁴⁵⁰] (its square, a pivot's, would under- or overflow: a row written as
/// 1e-170 (x² + y² − 1) was dropped as zero, with status ok, before; so was q = (1e200, 1e200)),
/// every row is scaled to unit norm, W_D = D W with D = diag(1 / ‖w_j‖) (‖w_j‖ computed without
/// overflow or underflow; a zero row, an inactive constraint, stays zero). A q'' = b is invariant
/// under row scaling, so q'', Qc and the least-squares answer of consistent constraints are
/// unchanged; the solves take D e and return lambda = D lambda_D. Otherwise (every ordinary
/// model) nothing is scaled and the results are bit for bit those without equilibration — the
/// minimum-norm lambda of redundant rows and a control law's least squares are unweighted.
///
/// Rank decision: pivot k counts as non-zero when |R_kk| > threshold · |R_00|, where R_00 is the
/// largest pivot (column pivoting makes |R_kk| non-increasing). The threshold is relative, so
/// the rank does not change when all constraints are scaled together (and with equilibrated
/// rows, |R_00| = 1, when each row is scaled separately); rows of ordinary norms but very
/// different scales are not equilibrated and should be normalized by the modeller.
/// Default 1e-10: exactly redundant rows (whose pivots are of order 1e-16) are dropped, and a
/// configuration-dependent loss of rank is detected once it is within 1e-10 of singular.
#pragma once
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "ukdyn/core/types.hpp"

namespace ukdyn {

/// Cholesky of M and complete orthogonal decomposition of A L⁻ᵀ (see the file comment).
class FundamentalDecomposition {
 public:
  /// The default relative rank threshold.
  static constexpr double kDefaultThreshold = 1e-10;

  /// An empty decomposition; call resize() before use.
  FundamentalDecomposition() = default;
  /// Reserves memory for n coordinates and m constraint rows.
  FundamentalDecomposition(Index n, Index m) { resize(n, m); }
  /// Reserves memory for n coordinates and m constraint rows (allocates).
  void resize(Index n, Index m);

  /// Factorizes M = L Lᵀ (reads the lower triangle), or M = F Fᵀ along the tree of
  /// set_mass_tree(). On failure info() is NumericalIssue. Cost O(n³/3), or O(Σ_k d_k²).
  FundamentalDecomposition& compute_mass(const Eigen::Ref<const MatrixXd>& M);
  /// Takes the factor of M from `other`, which factorized a larger M_o = [M 0; 0 M_2] (dense,
  /// M this object's n × n, the off-diagonal blocks zero): copies the leading n × n block of its
  /// L and 1 / L_kk, O(n²) instead of O(n³/3). For n_o <= 20 (both use the small Cholesky,
  /// which stops each column at its last non-zero) the result is bit for bit compute_mass(M).
  /// The caller guarantees the shape of M_o (a controlled system's diag(M, I) has it).
  /// Returns false, changing nothing, unless other is dense, factorized (info() Success), has
  /// n_o >= n coordinates, n_o <= 20, and this object has no mass tree.
  bool adopt_mass(const FundamentalDecomposition& other);
  /// Declares the sparsity of the M's to come: parent[k] is coordinate k's parent in a tree of
  /// the coordinates (−1 for a root, else 0 <= parent[k] < k), and M_ij = 0 unless one of i, j
  /// is an ancestor of the other — a kinematic tree's M in joint coordinates, the coordinates
  /// of one multi-DOF joint a chain (SystemBuilder::mass_tree). compute_mass then factorizes M
  /// = F Fᵀ, F = Lᵀ, along the branches (see the file comment); entries of M outside the pattern
  /// are ignored (the caller guarantees there are none). An empty parent goes back to the dense
  /// Cholesky (without allocating). Takes effect at the next compute_mass.
  /// @throws std::invalid_argument when parent has neither n nor 0 entries or an entry is out
  /// of range, naming it. Allocates (once).
  FundamentalDecomposition& set_mass_tree(const std::vector<Index>& parent);
  /// The tree of set_mass_tree (empty: dense Cholesky).
  const std::vector<Index>& mass_tree() const { return parent_; }
  /// Decomposes Wᵀ = L⁻¹ Aᵀ for A (m × n) with the last factorized M. Cost O(m n² + 2 m² n).
  FundamentalDecomposition& compute_constraints(const Eigen::Ref<const MatrixXd>& A);
  /// Both of the above.
  FundamentalDecomposition& compute(const Eigen::Ref<const MatrixXd>& M,
                                    const Eigen::Ref<const MatrixXd>& A) {
    compute_mass(M);
    if (info() == Eigen::Success) compute_constraints(A);
    return *this;
  }

  /// Success, or NumericalIssue when M is not positive definite.
  Eigen::ComputationInfo info() const { return info_; }
  /// r, the numerical rank of A (of W) after compute_constraints.
  Index rank() const { return rank_; }
  /// Sets the relative rank threshold (> 0 and < 1); takes effect at the next compute.
  /// @throws std::invalid_argument outside (0, 1).
  FundamentalDecomposition& set_threshold(double threshold);
  /// The relative rank threshold.
  double threshold() const { return threshold_; }
  /// Largest pivot |R_00| of the last decomposition (an estimate of ‖W‖₂; of ‖D W‖₂, 1 with a
  /// non-zero row, when the rows were equilibrated, see the file comment).
  double max_pivot() const { return max_pivot_; }
  /// Smallest kept pivot |R_{r−1,r−1}| of the last decomposition (an estimate of σ_r(W), the
  /// smallest non-zero singular value; of D W when the rows were equilibrated); 0 when r = 0.
  /// Cost O(1).
  double min_pivot() const { return rank_ > 0 ? 1.0 / std::abs(inv_tdiag_[rank_ - 1]) : 0.0; }
  /// Number of coordinates n and constraint rows m this object was sized for.
  Index coordinate_count() const { return n_; }
  /// Number of constraint rows m this object was sized for.
  Index rows() const { return m_; }
  /// The Cholesky factor L (lower triangle of the returned matrix; the upper is unspecified);
  /// with a mass tree, the L of M = Lᵀ L (see the file comment and solve_factor).
  const MatrixXd& matrix_llt() const { return L_; }
  /// X ← F⁻¹ X for the factor in force, M = F Fᵀ (F = L, or Lᵀ with a mass tree), column by
  /// column (X has n rows): W = A F⁻ᵀ = (F⁻¹ Aᵀ)ᵀ. Cost O(n² k), or O(k Σ_k d_k).
  void solve_factor(Eigen::Ref<MatrixXd> X) const;

  /// x = M⁻¹ f. Cost O(n²).
  void solve_mass(const Eigen::Ref<const VectorXd>& f, Eigen::Ref<VectorXd> x) const;

  /// The ideal part (eqs. 9, 11) for error signal e (m):
  /// dqdd = L⁻ᵀ W⁺ e (n), Qc = L W⁺ e (n), lambda = G⁺ e (m). Cost O(n² + n m + m²).
  void solve_ideal(const Eigen::Ref<const VectorXd>& e, Eigen::Ref<VectorXd> dqdd,
                   Eigen::Ref<VectorXd> Qc, Eigen::Ref<VectorXd> lambda);

  /// The non-ideal part (eqs. 9, 12) for work vector C (n):
  /// dqdd = L⁻ᵀ (I − W⁺W) L⁻¹ C, Qc = L (I − W⁺W) L⁻¹ C, lambda = −G⁺ A M⁻¹ C, so that
  /// Qc = C + Aᵀ lambda. Cost O(n² + n m + m²).
  void project_nonideal(const Eigen::Ref<const VectorXd>& C, Eigen::Ref<VectorXd> dqdd,
                        Eigen::Ref<VectorXd> Qc, Eigen::Ref<VectorXd> lambda);

  /// y = W⁺ e (n), the Moore–Penrose solution of W y = e. Cost O(n m + m²).
  void apply_pinv(const Eigen::Ref<const VectorXd>& e, Eigen::Ref<VectorXd> y);

 private:
  // x ← F⁻¹ x, x ← F⁻ᵀ x and y ← F x for the factor in force (M = F Fᵀ: F = L, or Lᵀ along
  // the mass tree)
  void factor_solve(double* x) const;
  void factor_transpose_solve(double* x) const;
  void factor_multiply(const double* x, double* y) const;
  // x ← Q x (forward = true) or x ← Qᵀ x, with the first rank_ reflectors of the QR step
  void apply_q(Eigen::Ref<VectorXd> x, bool transpose) const;
  // x ← Z x or x ← Zᵀ x (identity when rank_ == m_)
  void apply_z(Eigen::Ref<VectorXd> x, bool transpose) const;
  // Householder QR with column pivoting of X_, stopping at the numerical rank
  void factor_qr();
  // RZ step: [R11 R12] = [T 0] Z when rank_ < m_
  void factor_rz();

  Index n_ = 0, m_ = 0;
  MatrixXd L_;                 // (n × n) Cholesky factor M = L Lᵀ in the lower triangle (or the
                               // L of M = Lᵀ L along parent_)
  std::vector<Index> parent_;  // (n or 0) the mass tree of set_mass_tree; empty: dense
  // (n × 2m) Wᵀ, then R/T above the diagonal, reflectors below / right; its columns m … 2m − 1
  // are scratch (compute_constraints' W by rows)
  MatrixXd X_;
  VectorXd tau_;          // (m) QR reflector coefficients
  VectorXd ztau_;         // (m) RZ reflector coefficients
  Eigen::VectorXi perm_;  // (m) column permutation: column k of Wᵀ Π is column perm_[k] of Wᵀ
  VectorXd norm_, norm_ref_;  // (m) partial column norms for pivoting
  VectorXd inv_ldiag_;        // (n) 1 / L_kk
  VectorXd inv_tdiag_;        // (m) 1 / T_kk, first rank_ entries
  VectorXd row_scale_;  // (m) D: 1 / ‖w_j‖ of the last compute_constraints (1 for a zero row)
  bool equilibrated_ = false;  // whether the last compute_constraints scaled the rows by D
  VectorXd wm_;                // (m) scratch
  VectorXd wn_;                // (n) scratch
  Index rank_ = 0;
  double max_pivot_ = 0.0;
  double threshold_ = kDefaultThreshold;
  Eigen::ComputationInfo info_ = Eigen::InvalidInput;
};

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
/// @file linalg/sparse.hpp
/// The sparse engine: the fundamental equation for a block-diagonal M and a sparse A (bodies in
/// absolute coordinates joined by joints), at a cost that grows linearly with the number of
/// bodies for chains and trees with loop closures. docs/sparse.md explains the algorithm.
///
/// With M = blockdiag(M_bb) = L Lᵀ (L block-diagonal, one dense Cholesky factor per block) and
/// W = A L⁻ᵀ (the pattern of A, closed over blocks), G = A M⁻¹ Aᵀ = W Wᵀ is sparse: row i of G
/// touches the rows that share a body with row i. With a fill-reducing ordering P (AMD, from
/// CHOLMOD's analysis, once per workspace), the up-looking factorization
///
///     P G Pᵀ = L_G D L_Gᵀ,   L_G unit lower triangular, D diagonal >= 0,
///
/// drops every row that depends on the rows before it (pivot d_k <= tau² G_kk: then d_k = 0 and
/// column k of L_G is zero). The dropped rows give an exact basis of null(G) = null(Aᵀ):
/// n_k = Pᵀ L_G⁻ᵀ e_k, orthonormalized into N (m × d, d = m − rank). Then, exactly as the
/// dense engine's complete orthogonal decomposition (linalg/decomposition.hpp):
///
///     lambda = G⁺ e = (I − N Nᵀ) Pᵀ L_G⁻ᵀ D⁺ L_G⁻¹ P (I − N Nᵀ) e      (minimum norm, eq. 11)
///     y = W⁺ e = Wᵀ lambda,   q'' − a = L⁻ᵀ y,   Qc_ideal = L y = Aᵀ lambda
///     c = L⁻¹ C,  lambda_ni = −G⁺ W c,  c⊥ = c + Wᵀ lambda_ni:  Qc_nonideal = L c⊥,
///     q''_nonideal = L⁻ᵀ c⊥                                                  (eq. 12)
///
/// The projection of e onto range(G) makes an inconsistent e give the least-squares answer of
/// the dense engine (W⁺ e), so inconsistency is reported the same way.
///
/// Row equilibration, only where needed: when some G_kk = ‖w_k‖² lies outside [2⁻⁹⁰⁰, 2⁹⁰⁰]
/// (a row written as 1e-170 (x² + y² − 1) squared to zero and was dropped as a zero row, with
/// status ok, before), W is stored as D W, D = diag(1 / ‖w_i‖) (norms computed without under-
/// or overflow), and G formed again from it; the solves take D e and return lambda = D lambda_D,
/// so q'' and Qc are unchanged and lambda minimizes Σ_i (‖w_i‖ lambda_i)² among redundant rows.
/// Otherwise (every ordinary model) nothing is scaled: one compare per row, lambda = G⁺ e bit
/// for bit, the dense engine's split among redundant rows. The rank test below is relative to
/// each row's own norm in either case. Cost O(m) checks; O(nnz(A) + nnz(G)) when scaling.
///
/// Rank decision (relative, documented beside the dense one in linalg/decomposition.hpp): row k
/// counts as dependent when the part of its row w_k of W outside the span of the rows eliminated
/// before it is at most tau ‖w_k‖, i.e. d_k <= tau² G_kk. Default tau = 1e-6: G squares the
/// condition number of W, so a pivot of G carries roundoff of order eps κ(G) G_kk, and exactly
/// redundant rows give d_k / G_kk ~ 1e-16…1e-13 (loops closed twice, duplicated joints) up to
/// ~1e-11 (a self-stress along a ladder of 500 loops). A pivot below kSuspect G_kk is also
/// estimated in the space of W (‖Σ_j v_j w_j‖², v = L_G⁻ᵀ e_k), and the row is dependent when
/// either estimate is below tau² G_kk. Rows less than 1e-6 (relative) from dependent are
/// treated as dependent (the dense engine: 1e-10, on the pivots of W itself).
///
/// Cost per evaluation, for a chain or tree of N bodies with a bounded number of loop closures
/// and d redundant rows: O(N + (d + s) nnz(L_G) + m d²), s the suspicious pivots (about d) —
/// linear in N for fixed d. Memory O(nnz(A) + nnz(L_G) + m d). No method allocates after
/// construction unless d exceeds the reserved null-space capacity (16 columns; it then doubles).
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "ukdyn/core/types.hpp"

namespace ukdyn {

class System;

/// Block Cholesky of M, sparse A and W = A L⁻ᵀ, and the rank-revealing sparse LDLᵀ of
/// G = W Wᵀ (see the file comment). Built from a System's structure (mass blocks, constraint
/// columns); the pattern is fixed at construction.
class SparseDecomposition {
 public:
  /// Default relative rank threshold tau (on the rows of W; the pivots of G use tau²).
  static constexpr double kDefaultThreshold = 1e-6;
  /// Null-space columns reserved at construction.
  static constexpr Index kReservedNullity = 16;

  /// The analysis: block structure of M (sys.mass_blocks(), must be non-empty), the pattern of A
  /// from each constraint's columns() (dense rows for constraints without), the pattern of G,
  /// its AMD ordering (CHOLMOD) and the symbolic factorization. Allocates; O(nnz(G) + nnz(L_G)).
  /// @throws std::invalid_argument unless sys.mass_is_block_diagonal().
  explicit SparseDecomposition(const System& sys);
  ~SparseDecomposition();
  /// Moves the analysis and the factors, member by member (no allocation).
  SparseDecomposition(SparseDecomposition&&) noexcept;
  /// Moves the analysis and the factors, member by member (no allocation).
  SparseDecomposition& operator=(SparseDecomposition&&) noexcept;

  /// n, m, number of mass blocks, non-zeros of A's pattern and of the factor L_G (strictly
  /// lower part).
  Index coordinate_count() const { return n_; }
  /// m, the constraint rows (rows of A).
  Index rows() const { return m_; }
  /// Number of diagonal blocks M_bb of M.
  Index block_count() const { return Index(blk_off_.size()) - 1; }
  /// Non-zeros of A's (fixed) pattern.
  Index nonzeros() const { return Index(col_.size()); }
  /// Non-zeros of the factor L_G of G (strictly lower part), from the symbolic factorization.
  Index factor_nonzeros() const { return Index(Li_.size()); }

  // --- M = blockdiag(M_bb) = L Lᵀ -------------------------------------------------------
  /// Storage of block b of M (size × size), to be written before compute_mass. Cost O(1).
  Eigen::Map<MatrixXd> mass_block(Index b);
  /// Block b of M (size × size), read-only. Cost O(1).
  Eigen::Map<const MatrixXd> mass_block(Index b) const;
  /// First coordinate and size of block b.
  Index block_offset(Index b) const { return blk_off_[std::size_t(b)]; }
  /// Size (rows = columns) of block b.
  Index block_size(Index b) const {
    return blk_off_[std::size_t(b) + 1] - blk_off_[std::size_t(b)];
  }
  /// Whether block b is constant (its value was copied from the System at construction).
  bool block_is_constant(Index b) const { return blk_const_[std::size_t(b)] != 0; }
  /// max |M_ij| and max |M_ij − M_ji| over the blocks, and whether every entry is finite.
  /// Cost O(Σ size²).
  double mass_max_abs() const;
  /// max |M_ij − M_ji| over the blocks (0 for a symmetric M). Cost O(Σ size²).
  double mass_asymmetry() const;
  /// Whether every entry of every block is finite. Cost O(Σ size²).
  bool mass_finite() const;
  /// Factorizes every block M_bb = L_b L_bᵀ (reads the lower triangles). On failure info() is
  /// NumericalIssue. Cost O(Σ size³ / 3), i.e. O(N) for N bodies.
  SparseDecomposition& compute_mass();
  /// Success, or NumericalIssue when a block of M is not positive semi-definite (after
  /// compute_mass), or when a singular block is not determined by its constraints (after
  /// compute_augmented_mass; see undetermined_block()).
  Eigen::ComputationInfo info() const { return info_; }

  // --- singular M (docs/singular-mass.md) --------------------------------------------------
  /// A block whose Cholesky factorization fails, or one of whose pivots is not regular
  /// (pivot_is_regular), is singular. It is accepted when it is positive semi-definite
  /// (M_bb + 1e-10 max|M_bb| I is positive definite) and then factorized by
  /// compute_augmented_mass, once A is written. The ratio is generous: the last pivot of an
  /// exactly singular matrix carries roundoff of order eps · cond of its regular part (a rod's
  /// quaternion block, axial inertia 1e-4 of the transverse: ~1e-12 of its diagonal).
  /// A block singular by construction (MassBlock::singular) is singular from the start and
  /// checked at the first compute_mass only: later ones leave it to compute_augmented_mass.
  static constexpr double kSingularPivotRatio = 1e-8;
  /// Whether a pivot of the Cholesky factor of a block of M is that of a regular block: L_kk² is
  /// at least kSingularPivotRatio · M_kk, i.e. coordinate k keeps at least that share of its own
  /// inertia once the coordinates before it are eliminated. Relative to the coordinate's own
  /// diagonal, so invariant under a change of units (a diagonal scaling D M D): a point mass's
  /// body block diag(m, m, 1e-9 m L²) is regular, an exactly singular block (a zero axial
  /// inertia) is not. Cost O(1).
  static bool pivot_is_regular(double L_kk_squared, double M_kk) {
    return L_kk_squared >= kSingularPivotRatio * M_kk;
  }
  /// Whether the last compute_mass found a singular (positive semi-definite) block.
  bool mass_singular() const { return singular_blocks_ > 0; }
  /// Number of singular blocks, and whether block b is one.
  Index singular_blocks() const { return singular_blocks_; }
  /// Whether block b is singular (positive semi-definite only), after compute_mass.
  bool block_is_singular(Index b) const { return blk_sing_[std::size_t(b)] != 0; }
  /// The auxiliary mass matrix of Udwadia & Schutte for the singular blocks: each singular block
  /// b is factorized as M_bb + Σ_i g_i a_i a_iᵀ over the rows i of A local to b (rows touching
  /// no other block), g_i = s_b / ‖a_i‖² with s_b = max diag M_bb (the largest diagonal of M
  /// for a zero block). Rows touching other blocks are not used: they would couple the blocks.
  /// Then q'' and Qc of the fundamental equation with (M_A, Q_A = Q + Aᵀ G b) are those of the
  /// singular system (docs/theory.md, section 6). On failure info() is NumericalIssue and
  /// undetermined_block() names the block. With regularization > 0 (a projection's metric,
  /// which only needs to be positive definite) regularization · s_b I is added as well.
  /// Cost O(Σ_singular (local rows · size² + size³)).
  SparseDecomposition& compute_augmented_mass(double regularization = 0.0);
  /// Q += Aᵀ G b with the weights of the last compute_augmented_mass. Cost O(nnz of those rows).
  void augment_forces(const Eigen::Ref<const VectorXd>& b, Eigen::Ref<VectorXd> Q) const;
  /// The block compute_augmented_mass could not factorize, or −1.
  Index undetermined_block() const { return undetermined_block_; }
  /// x = M⁻¹ f (M_A⁻¹ f for a singular M); y = M x; returns xᵀ M x. Cost O(Σ size²).
  void solve_mass(const Eigen::Ref<const VectorXd>& f, Eigen::Ref<VectorXd> x) const;
  /// x ← M⁻¹ x (M_A⁻¹ x for a singular M). Cost O(Σ size²).
  void solve_mass_in_place(Eigen::Ref<VectorXd> x) const;
  /// y = M x (n), block by block from the stored blocks of M. Cost O(Σ size²).
  void multiply_mass(const Eigen::Ref<const VectorXd>& x, Eigen::Ref<VectorXd> y) const;
  /// xᵀ M x = ‖Lᵀ x‖² from the factors of the last compute_mass (xᵀ M_bb x on a singular
  /// block). Cost O(Σ size²).
  double mass_norm_squared(const Eigen::Ref<const VectorXd>& x) const;

  // --- A (m × n, sparse, fixed pattern) ---------------------------------------------------
  /// A as an Eigen sparse matrix (compressed rows, a view of the storage; explicit zeros where
  /// the pattern is wider than the constraints' columns).
  Eigen::Map<const Eigen::SparseMatrix<double, Eigen::RowMajor, int>> matrix_A() const;
  /// Writes the rows of constraint k: A_k is rows × columns().size() for a constraint with
  /// columns (its acceleration_form_local), rows × n for a dense one. Cost O(nnz of the rows).
  void set_constraint_rows(Index k, const Eigen::Ref<const MatrixXd>& A_k);
  /// Zeroes the rows of constraint k (an inactive constraint).
  void zero_constraint_rows(Index k);
  /// Whether constraint k has local columns (else its rows are dense).
  bool constraint_is_local(Index k) const { return !local_pos_[std::size_t(k)].empty(); }
  /// y = A x (m); y = Aᵀ lambda (n); share: y = A_kᵀ lambda_k on the columns of constraint k's
  /// pattern, other entries of y untouched (lambda has m entries); ‖A‖_F. Cost O(nnz(A)), resp.
  /// O(nnz of the rows of k).
  void multiply_A(const Eigen::Ref<const VectorXd>& x, Eigen::Ref<VectorXd> y) const;
  /// y = Aᵀ lambda (n), lambda (m). Cost O(nnz(A)).
  void multiply_At(const Eigen::Ref<const VectorXd>& lambda, Eigen::Ref<VectorXd> y) const;
  /// Constraint k's share y = A_kᵀ lambda_k, written on the columns of k's pattern only (other
  /// entries of y untouched; lambda has m entries). Cost O(nnz of the rows of k).
  void share(Index k, const Eigen::Ref<const VectorXd>& lambda, Eigen::Ref<VectorXd> y) const;
  /// ‖A‖_F, the Frobenius norm of the stored values (without overflow or underflow).
  /// Cost O(nnz(A)).
  double norm_A() const;
  /// Copies the rows of constraint k into out (rows × n, dense). Cost O(rows · n).
  void constraint_rows_dense(Index k, Eigen::Ref<MatrixXd> out) const;

  // --- G = W Wᵀ = L_G D L_Gᵀ --------------------------------------------------------------
  /// W = A L⁻ᵀ, G, its rank-revealing LDLᵀ and the null-space basis, for the current A and the
  /// last factorized M. Cost O(nnz(A) + Σ_bodies rows² + nnz(L_G) + d nnz(L_G) + m d²).
  SparseDecomposition& compute_constraints();
  /// rank A = m − d after compute_constraints.
  Index rank() const { return rank_; }
  /// How far A is from losing rank, after compute_constraints: min over the kept rows k of
  /// ‖w_k⊥‖ / ‖w_k‖ = (d_k / G_kk)^{1/2}, the sine of the angle between row w_k of W (of D W when
  /// equilibrated) and the span of the rows eliminated before it (the recomputed pivot where
  /// there is one); 1 without kept rows. The dense engine's counterpart is
  /// FundamentalDecomposition::min_pivot() / max_pivot() (σ_r / σ_1 of W, estimated): for rows
  /// of comparable norms both are of the order of the smallest singular value of the row-
  /// normalized W, and both fall linearly to 0 as two rows come to coincide (a dead centre);
  /// this one does not depend on the rows' scales. At least tau for rank() > 0. Cost O(1): the
  /// pivots are those of the factorization.
  double rank_margin() const { return rank_margin_; }
  /// Pivots of the last compute_constraints that were suspicious (d_k <= kSuspect G_kk) and
  /// recomputed in the space of W.
  Index rechecked_pivots() const { return rechecked_; }
  /// A pivot d_k <= kSuspect G_kk (sin² of the angle of w_k to the earlier rows) is recomputed
  /// as ‖Σ_j v_j w_j‖² with v = L_G⁻ᵀ e_k before the rank decision — unless row k is coupled
  /// only to rows that are coupled to nothing before them (then d_k = G_kk − Σ_i G_ik² / G_ii,
  /// whose roundoff is below c (p + 1) (n + 2) eps G_kk, p the rows in the sum, c = 4) and d_k
  /// clears tau² G_kk by that bound: the recheck could not reverse the decision.
  static constexpr double kSuspect = 1e-6;
  /// Sets the relative rank threshold tau (in (0, 1)); takes effect at the next compute.
  /// @throws std::invalid_argument outside (0, 1).
  SparseDecomposition& set_threshold(double threshold);
  /// The relative rank threshold tau in force (default kDefaultThreshold).
  double threshold() const { return threshold_; }

  /// The ideal part (eqs. 9, 11) for error signal e (m): dqdd = L⁻ᵀ W⁺ e, Qc = L W⁺ e,
  /// lambda = G⁺ e (minimum norm). Cost O(nnz(A) + nnz(L_G) + m d).
  void solve_ideal(const Eigen::Ref<const VectorXd>& e, Eigen::Ref<VectorXd> dqdd,
                   Eigen::Ref<VectorXd> Qc, Eigen::Ref<VectorXd> lambda);
  /// The non-ideal part (eqs. 9, 12) for C (n): dqdd = L⁻ᵀ (I − W⁺W) L⁻¹ C,
  /// Qc = L (I − W⁺W) L⁻¹ C, lambda = −G⁺ A M⁻¹ C (so Qc = C + Aᵀ lambda). Cost as solve_ideal.
  void project_nonideal(const Eigen::Ref<const VectorXd>& C, Eigen::Ref<VectorXd> dqdd,
                        Eigen::Ref<VectorXd> Qc, Eigen::Ref<VectorXd> lambda);
  /// y = W⁺ e (n). Cost as solve_ideal.
  void apply_pinv(const Eigen::Ref<const VectorXd>& e, Eigen::Ref<VectorXd> y);

 private:
  // x ← G⁺ x in the permuted order (projections onto range(G) before and after the solve)
  void solve_G_permuted(double* x);
  // lambda = G⁺ e and y = Wᵀ lambda (original order), with one refinement step
  void solve_min_norm(const double* e, double* lambda, double* y);
  // y = D x (m; y may be x)
  void scale_rows(const double* x, double* y) const;
  // x ← x − N (Nᵀ x) and the trivial (zero-row) entries zeroed, permuted order
  void project_range(double* x) const;
  // y = Wᵀ lambda (original row order)
  void multiply_Wt(const double* lambda, double* y) const;
  // y = W x
  void multiply_W(const double* x, double* y) const;
  // x ← L⁻¹ x, x ← L⁻ᵀ x, y = L x (block-diagonal mass factor)
  void mass_lower_solve(double* x) const;
  void mass_upper_solve(double* x) const;
  void mass_lower_multiply(const double* x, double* y) const;
  // the up-looking LDLᵀ of P G Pᵀ with dropping of dependent rows
  void factor_G();
  // the orthonormal basis of null(G) from the dropped pivots
  void null_basis();
  // pivot k recomputed in the space of W, ‖Wᵀ Pᵀ L_G⁻ᵀ e_k‖² (during factor_G)
  double recompute_pivot(int k);

  Index n_ = 0, m_ = 0;
  // M: blocks [blk_off_[b], blk_off_[b+1]); values (column-major) at blk_val_[b]
  std::vector<Index> blk_off_, blk_val_;
  std::vector<unsigned char> blk_const_;
  std::vector<double> Mv_, Lv_, inv_ldiag_;
  // a compute_mass succeeded: constant blocks factorized, blocks singular by construction checked
  bool checked_ = false;
  Eigen::ComputationInfo info_ = Eigen::InvalidInput;
  // A and W, compressed rows; each row is a run of whole blocks (segments)
  std::vector<int> row_ptr_, col_;
  std::vector<double> Av_, Wv_;
  std::vector<int> seg_ptr_, seg_blk_, seg_pos_;  // segments of row i: [seg_ptr_[i], seg_ptr_[i+1])
  // constraints: first row, rows, and for local ones the offset in the row of each column
  std::vector<Index> con_r0_, con_rows_;
  std::vector<std::vector<int>> local_pos_;
  // G in the permuted order, upper triangle by columns; the assembly program
  struct Product {
    int target, wi, wj, len;  // Gx[target] += W[wi .. wi+len) · W[wj .. wj+len)
  };
  std::vector<int> perm_, pinv_;  // perm_[k]: original row at position k; pinv_ its inverse
  std::vector<int> Gp_, Gi_, Gdiag_;
  std::vector<double> Gx_;
  std::vector<Product> program_first_, program_;  // first product of each entry; the others
  // L_G (strictly lower, by columns) and D; work arrays of the up-looking factorization
  std::vector<int> parent_, Lp_, Lnz_, Li_, flag_, pattern_;
  std::vector<double> Lx_, D_, Y_;
  // a bound on the roundoff of pivot d_k relative to G_kk, for rows coupled only to rows with
  // no coupling before them (their pivots need no recheck when clear of the threshold by it);
  // +inf for the others
  std::vector<double> pivot_margin_;
  // singular blocks: flags (found singular, or singular by construction), the rows local to each
  // block (CSR), the weights g_i of the last augmentation (0 for rows not used)
  std::vector<unsigned char> blk_sing_, blk_known_;
  std::vector<int> local_row_ptr_, local_rows_;
  std::vector<double> aug_g_;
  Index singular_blocks_ = 0, undetermined_block_ = -1;
  std::vector<unsigned char> dropped_;  // 0 kept, 1 dependent row, 2 zero row (trivial)
  // orthonormal null-space basis (permuted order), d_ columns of capacity N_.cols()
  MatrixXd N_;
  std::vector<int> null_rows_;  // (d_) the dropped position behind each column
  Index d_ = 0, rank_ = 0, rechecked_ = 0;
  double rank_margin_ = 1.0;  // see rank_margin(), filled by factor_G
  double threshold_ = kDefaultThreshold;
  // scratch
  std::vector<double> wm_, wm2_, wm3_, wm4_, wn_, wn2_, wn3_;
  // D: 1 / ‖w_i‖ of each row of W (1 for a zero row), see "Row equilibration"
  std::vector<double> row_scale_;
  bool equilibrated_ = false;  // whether the last compute_constraints scaled the rows by D
};

}  // namespace ukdyn

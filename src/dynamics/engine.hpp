// SPDX-License-Identifier: BSD-3-Clause
// The engine interface (not installed): the linear algebra of the fundamental equation for one
// kind of M and A, chosen once when a Workspace is made (Workspace::engine), so that each stage
// makes one call and none branches on the engine.
//
//   dense     M and A dense, FundamentalDecomposition (Cholesky of M, COD of W = A L⁻ᵀ):
//             dynamics/dense_engine.hpp, instantiated in dynamics/dense_engine.cpp
//   sparse    block-diagonal M, sparse A, SparseDecomposition (rank-revealing LDLᵀ of G = W Wᵀ):
//             dynamics/sparse_engine.cpp
//   textbook  the dense engine on TextbookDecomposition (eqs. 9–12 as printed):
//             reference/textbook_engine.cpp
//
// A system may declare its M's branch-induced sparsity (SystemBuilder::mass_tree, given by a
// kinematic tree's System): the workspace then hands the tree to the dense engine's
// decomposition once, when it is made (FundamentalDecomposition::set_mass_tree), and the same
// dense engine factorizes M = Lᵀ L along the branches (Featherstone's LTL, linalg/tree_ltl.hpp:
// O(Σ d_k²) instead of O(n³/3), no fill-in) with every product of the fundamental equation
// taken with F = Lᵀ; a singular M falls back to the dense completion.
//
// An engine holds no state: its buffers are the workspace's (M, A or ws.sparse, the
// decompositions), so one engine object serves every workspace and thread. Each operation is
// what one stage, the projections or the simulation needs; its cost is that of the engine's
// decomposition (linalg/decomposition.hpp, linalg/sparse.hpp). None allocates.
#pragma once

#include "ukdyn/core/status.hpp"
#include "ukdyn/core/types.hpp"

namespace ukdyn {
class System;
class Workspace;
class TextbookDecomposition;
}  // namespace ukdyn

namespace ukdyn::detail {

/// One engine's operations on a workspace made for it.
class EngineOps {
 public:
  virtual ~EngineOps() = default;

  // --- stage 1: M, its factor, a = M⁻¹ Q ---------------------------------------------------
  /// M(q,t), its checks and M = L Lᵀ (a singular, positive semi-definite M sets
  /// ws.mass_singular; it is factorized by complete_singular_mass once A is known).
  virtual Status evaluate_mass(const System& sys, Workspace& ws,
                               const Eigen::Ref<const VectorXd>& q, double t) const = 0;
  /// ws.a = M⁻¹ ws.Q with the factor of evaluate_mass (a regular M).
  virtual void solve_mass(Workspace& ws) const = 0;
  /// For a singular M, with A and b assembled: M_A = M + Aᵀ G A factorized; with `forces`,
  /// ws.a = M_A⁻¹ (Q + Aᵀ G b); with `regularize` (a projection's metric) M_A + 1e-8 s I when
  /// M_A is singular. See detail::complete_singular_mass.
  virtual Status complete_singular_mass(Workspace& ws, double t, bool forces,
                                        bool regularize) const = 0;
  /// ½ q'ᵀ M q' with the M of the last evaluation.
  virtual double kinetic_energy(const Workspace& ws, const VectorXd& qd) const = 0;

  // --- stage 2: A and b ---------------------------------------------------------------------
  /// Constraint k's rows of A and b from its acceleration form at (q, q', t); with `check`,
  /// kNonFiniteInput (recorded) when A is not finite.
  virtual Status write_constraint_rows(const System& sys, Workspace& ws, Index k,
                                       const Eigen::Ref<const VectorXd>& q,
                                       const Eigen::Ref<const VectorXd>& qd, double t,
                                       bool check) const = 0;
  /// Constraint k's rows of A set to zero (b is the caller's).
  virtual void zero_constraint_rows(const System& sys, Workspace& ws, Index k) const = 0;
  /// Constraint k's rows of A as last assembled, into out (rows × n).
  virtual void copy_constraint_rows(const System& sys, const Workspace& ws, Index k,
                                    Eigen::Ref<MatrixXd> out) const = 0;

  // --- products with the assembled A and the M of the last evaluation ------------------------
  /// out = A x (m).
  virtual void multiply_A(const Workspace& ws, const Eigen::Ref<const VectorXd>& x,
                          Eigen::Ref<VectorXd> out) const = 0;
  /// ws.e = b − A a: the error signal of stage 3.
  virtual void error_signal(Workspace& ws) const = 0;
  /// out = A x − b (m): the constraint residual of an acceleration x.
  virtual void constraint_residual(const Workspace& ws, const VectorXd& x, VectorXd& out) const = 0;
  /// out = Aᵀ y (n).
  virtual void multiply_At(const Workspace& ws, const VectorXd& y, VectorXd& out) const = 0;
  /// out = M x (n).
  virtual void multiply_mass(const Workspace& ws, const VectorXd& x, VectorXd& out) const = 0;
  /// ‖A‖_F.
  virtual double norm_A(const Workspace& ws) const = 0;
  /// out = A_kᵀ lambda_k (n): constraint k's share of the force Aᵀ lambda.
  virtual void constraint_share(const System& sys, const Workspace& ws, Index k,
                                const VectorXd& lambda, Eigen::Ref<VectorXd> out) const = 0;
  /// q'ᵀ A_kᵀ lambda_k with the multipliers of the last evaluation (scratch: n), the power of
  /// constraint k's ideal force.
  virtual double constraint_power(const System& sys, const Workspace& ws, Index k,
                                  const Eigen::Ref<const VectorXd>& qd,
                                  VectorXd& scratch) const = 0;

  // --- stage 3 and the projections: the decomposition of W = A L⁻ᵀ --------------------------
  /// Decomposes W = A L⁻ᵀ for the A last assembled and the factor of M in force.
  virtual void decompose_constraints(Workspace& ws) const = 0;
  /// Numerical rank of A from the last decompose_constraints.
  virtual Index rank(const Workspace& ws) const = 0;
  /// σ_r / σ_1 estimate of W from the last decompose_constraints (or the sparse engine's margin;
  /// NaN where the engine has none; see Workspace::rank_margin).
  virtual double rank_margin(const Workspace& ws) const = 0;
  /// dq = L⁻ᵀ W⁺ e, Qc = L W⁺ e, lambda = G⁺ e.
  virtual void solve_ideal(Workspace& ws, const VectorXd& e, VectorXd& dq, VectorXd& Qc,
                           VectorXd& lambda) const = 0;

  // --- stage 4 ------------------------------------------------------------------------------
  /// dq = L⁻ᵀ (I − W⁺W) L⁻¹ C, Qc_nonideal = L (I − W⁺W) L⁻¹ C, lambda with
  /// Qc_nonideal = C + Aᵀ lambda: ws.dqdd, ws.Qc_nonideal, ws.lambda_nonideal from ws.C.
  virtual void project_nonideal(Workspace& ws) const = 0;
};

/// The engines (one object each, shared by every workspace).
const EngineOps& dense_engine();
const EngineOps& sparse_engine();

/// The textbook engine is not in the core library: the reference library (src/reference/,
/// target ukdyn::reference) registers it when it is linked, before main (a static
/// initializer of reference/textbook_engine.cpp). Set once, then only read.
struct TextbookProvider {
  TextbookDecomposition* (*make)(Index n, Index m, double rank_threshold);
  void (*destroy)(TextbookDecomposition*);
  const EngineOps* engine;
};
/// The registered provider, or null when ukdyn::reference is not linked.
const TextbookProvider* textbook_provider();
/// Called by the reference library's static initializer.
void register_textbook_provider(const TextbookProvider* provider);

}  // namespace ukdyn::detail

// SPDX-License-Identifier: BSD-3-Clause
/// @file dynamics/forward.hpp
/// Forward dynamics of a constrained system: the fundamental equation as a pipeline of stages,
/// each callable on its own and each in its own source file:
///
///   1. evaluate_unconstrained   M, Q; Cholesky M = L Lᵀ; a = M⁻¹ Q
///   dynamics/unconstrained_motion.cpp
///   2. assemble_constraints     A, b of the active constraints
///   dynamics/acceleration_constraints.cpp
///   3. solve_ideal              e = b − A a; q'' = a + L⁻ᵀ W⁺ e; Qc_ideal; lambda
///   dynamics/ideal_constraint_force.cpp
///   4. apply_nonideal           C; Qc_nonideal; q'' += L⁻ᵀ(I − W⁺W)L⁻¹ C
///   dynamics/nonideal_constraint_force.cpp
///   5. check_result             residuals, consistency, finiteness dynamics/result_checks.cpp
///
/// forward_dynamics runs them in order (dynamics/forward.cpp). No stage allocates with the default
/// algorithm. Numerical failures set ws.status and stop the pipeline; nothing here throws
/// except for misuse (tier 1).
#pragma once

#include <Eigen/Core>

#include "ukdyn/core/status.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/workspace.hpp"

namespace ukdyn {

/// Evaluates the constrained motion at (q, q', t): fills every result field of ws
/// (q'', Qc, Qc_ideal, Qc_nonideal, lambda, e, rank, residuals) and returns ws.status.
/// When it fails before the results are computed (a non-finite t, q, q', M, Q, A, b or C; M
/// not positive definite or not symmetric; motion not determined), q'', Qc, Qc_ideal and
/// lambda are set to NaN, and so are Qc_nonideal and lambda_nonideal of a system with non-ideal
/// forces (without them they are zero at every state, and stay zero), never left at the
/// previous evaluation's values; kInconsistentConstraints and kNonFiniteResult keep what was
/// computed.
/// @throws std::invalid_argument if q or qd does not have n entries or ws belongs to another
/// system or is empty (moved from). Cost O(n³/3 + m n² + m² n) for a state-dependent M; O(m n² + m²
/// n) for a constant M.
/// q and qd (n each), here and in every entry point of ukdyn, are `Eigen::Ref<const VectorXd>`:
/// a VectorXd, a segment of a larger vector, an Eigen::Map or a fixed-size vector is passed
/// without a copy, down to the system's callables; any other expression (a matrix row, q + dq)
/// is first evaluated into a temporary, which allocates.
Status forward_dynamics(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                        const Eigen::Ref<const VectorXd>& qd, double t);

/// Stage 1: M(q,t), Q(q,q',t), the Cholesky factor of M (skipped after the first call when M
/// is constant) and a = M⁻¹ Q. Checks finiteness and symmetry. Cost O(n³/3).
Status evaluate_unconstrained(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t);

/// Stage 2: A and b of every constraint active at t (rows of inactive ones are zero).
/// Cost: the constraints' own evaluation, O(n m) besides.
Status assemble_constraints(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                            const Eigen::Ref<const VectorXd>& qd, double t);

/// Stage 3: e = b − A a, the decomposition of A L⁻ᵀ, q'' = a + L⁻ᵀ W⁺ e, Qc_ideal = L W⁺ e and
/// lambda = G⁺ e (eqs. 9, 11). Needs stages 1–2. Cost O(m n² + m² n).
Status solve_ideal(const System& sys, Workspace& ws);

/// Fills ws.shares: column k = A_kᵀ lambda_k, constraint k's share of Qc_ideal. Cost O(n m).
void compute_shares(const System& sys, Workspace& ws);

/// Stage 4: C from the system's non-ideal forces (which may read the ideal force), then
/// Qc_nonideal, lambda_nonideal, Qc and the non-ideal part of q'' (eqs. 9, 12). Needs stage 3.
/// Cost O(n² + n m) plus the forces' own.
Status apply_nonideal(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                      const Eigen::Ref<const VectorXd>& qd, double t);

/// Stage 5: residuals (see Residuals), the consistency test of A q'' = b and the finiteness of
/// the results. Cost O(n m), plus O(n² + n m) when options().compute_residuals.
Status check_result(const System& sys, Workspace& ws);

}  // namespace ukdyn

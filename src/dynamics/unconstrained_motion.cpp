// SPDX-License-Identifier: BSD-3-Clause
// Stage 1: the unconstrained system. M(q,t), Q(q,q',t), M = L Lᵀ, a = M⁻¹ Q (eqs. 1, 2).
// A singular (positive semi-definite) M is factorized after stage 2 as the auxiliary
// M_A = M + Aᵀ G A, with Q_A = Q + Aᵀ G b (complete_singular_mass; docs/singular-mass.md).
// The engine (dynamics/engine.hpp) holds the linear algebra of each kind of M.
#include "dynamics/engine.hpp"
#include "dynamics/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn {

Status evaluate_unconstrained(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t) {
  detail::require_same_system(sys, ws, "ukdyn::evaluate_unconstrained");
  detail::require_state_size(sys, q, &qd, "ukdyn::evaluate_unconstrained");
  if (const Status s = detail::evaluate_mass(sys, ws, q, t); s != Status::kOk) return s;
  // Q(q,q',t)
  sys.forces(q, qd, t, ws.callables.get(), ws.Q);
  if (!detail::all_finite(ws.Q)) return detail::fail(ws, Status::kNonFiniteInput, "Q", -1, t);
  // a = M⁻¹ Q; for a singular M, a = M_A⁻¹ Q_A once A is known (assemble_constraints)
  if (!ws.mass_singular) ws.engine->solve_mass(ws);
  return Status::kOk;
}

}  // namespace ukdyn

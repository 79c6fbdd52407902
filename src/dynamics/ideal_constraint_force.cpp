// SPDX-License-Identifier: BSD-3-Clause
// Stage 3: the ideal constrained motion (eqs. 9, 11):
//   e = b − A a,  q'' = a + L⁻ᵀ W⁺ e,  Qc_ideal = L W⁺ e = Aᵀ lambda,  lambda = G⁺ e.
// The engine decomposes W = A L⁻ᵀ (dynamics/engine.hpp): the dense one by a complete orthogonal
// decomposition of W (linalg/decomposition.hpp), the sparse one by a rank-revealing sparse LDLᵀ
// of G = W Wᵀ with the null space of the dropped rows (linalg/sparse.hpp).
#include "dynamics/engine.hpp"
#include "dynamics/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn {

Status solve_ideal(const System& sys, Workspace& ws) {
  detail::require_same_system(sys, ws, "ukdyn::solve_ideal");
  const detail::EngineOps& engine = *ws.engine;
  // e = b − A a;  decompose W = A L⁻ᵀ;  dq = L⁻ᵀ W⁺ e, Qc_ideal = L W⁺ e, lambda = G⁺ e
  engine.error_signal(ws);
  engine.decompose_constraints(ws);
  ws.rank = engine.rank(ws);
  ws.rank_margin = engine.rank_margin(ws);
  engine.solve_ideal(ws, ws.e, ws.dqdd, ws.Qc_ideal, ws.lambda);
  // q'' = a + dq
  ws.qdd = ws.a + ws.dqdd;
  if (ws.rank < ws.active_rows) ++ws.counters.rank_deficient;
  if (sys.nonideal_count() > 0) compute_shares(sys, ws);
  return Status::kOk;
}

void compute_shares(const System& sys, Workspace& ws) {
  detail::require_same_system(sys, ws, "ukdyn::compute_shares");
  if (ws.shares.rows() != sys.coordinate_count())
    ws.shares.setZero(sys.coordinate_count(), sys.constraint_count());
  // share_k = A_kᵀ lambda_k
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    detail::constraint_share(sys, ws, k, ws.lambda, ws.shares.col(k));
  }
}

}  // namespace ukdyn

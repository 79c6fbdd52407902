// Stage 3: the ideal constrained motion (eqs. 9, 11):
//   e = b − A a,  q'' = a + L⁻ᵀ W⁺ e,  Qc_ideal = L W⁺ e = Aᵀ lambda,  lambda = G⁺ e.
#include "detail.hpp"
#include "ukdyn/forward.hpp"

namespace ukdyn {

Status solve_ideal(const System& sys, Workspace& ws) {
  detail::require_same_system(sys, ws, "ukdyn::solve_ideal");
  // e = b − A a
  ws.e = ws.b;
  ws.e.noalias() -= ws.A * ws.a;
  // decompose A L⁻ᵀ; dq = L⁻ᵀ W⁺ e, Qc_ideal = L W⁺ e, lambda = G⁺ e
  detail::with_decomposition(ws, [&](auto& d) {
    d.compute_constraints(ws.A);
    ws.rank = d.rank();
    d.solve_ideal(ws.e, ws.dqdd, ws.Qc_ideal, ws.lambda);
  });
  // q'' = a + dq
  ws.qdd = ws.a + ws.dqdd;
  if (ws.rank < ws.active_rows) ++ws.counters.rank_deficient;
  if (sys.nonideal_count() > 0) compute_shares(sys, ws);
  return Status::kOk;
}

void compute_shares(const System& sys, Workspace& ws) {
  detail::require_same_system(sys, ws, "ukdyn::compute_shares");
  // share_k = A_kᵀ lambda_k
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const Index r0 = sys.row_offset(k), rows = sys.constraint(k).rows();
    ws.shares.col(k).noalias() =
        ws.A.middleRows(r0, rows).transpose() * ws.lambda.segment(r0, rows);
  }
}

}  // namespace ukdyn

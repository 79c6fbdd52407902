// Stage 3: the ideal constrained motion (eqs. 9, 11):
//   e = b − A a,  q'' = a + L⁻ᵀ W⁺ e,  Qc_ideal = L W⁺ e = Aᵀ lambda,  lambda = G⁺ e.
// Dense engine: complete orthogonal decomposition of W (linalg/decomposition.hpp); sparse engine:
// rank-revealing sparse LDLᵀ of G = W Wᵀ with the null space of the dropped rows
// (linalg/sparse.hpp).
#include <limits>
#include <type_traits>

#include "dynamics/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/linalg/sparse.hpp"

namespace ukdyn {

Status solve_ideal(const System& sys, Workspace& ws) {
  detail::require_same_system(sys, ws, "ukdyn::solve_ideal");
  if (ws.sparse) {
    // e = b − A a;  W = A L⁻ᵀ, G = W Wᵀ = P L_G D L_Gᵀ Pᵀ;  dq = L⁻ᵀ W⁺ e, Qc_ideal, lambda = G⁺ e
    SparseDecomposition& sp = *ws.sparse;
    sp.multiply_A(ws.a, ws.e);
    ws.e = ws.b - ws.e;
    sp.compute_constraints();
    ws.rank = sp.rank();
    ws.rank_margin = std::numeric_limits<double>::quiet_NaN();
    sp.solve_ideal(ws.e, ws.dqdd, ws.Qc_ideal, ws.lambda);
  } else {
    // e = b − A a
    ws.e = ws.b;
    ws.e.noalias() -= ws.A * ws.a;
    // decompose A L⁻ᵀ; dq = L⁻ᵀ W⁺ e, Qc_ideal = L W⁺ e, lambda = G⁺ e
    detail::with_decomposition(ws, [&](auto& d) {
      d.compute_constraints(ws.A);
      ws.rank = d.rank();
      if constexpr (std::is_same_v<std::decay_t<decltype(d)>, FundamentalDecomposition>) {
        ws.rank_margin = d.rank() == 0 ? 1.0 : d.min_pivot() / d.max_pivot();
      } else {
        ws.rank_margin = std::numeric_limits<double>::quiet_NaN();
      }
      d.solve_ideal(ws.e, ws.dqdd, ws.Qc_ideal, ws.lambda);
    });
  }
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

namespace detail {

void constraint_share(const System& sys, const Workspace& ws, Index k, const VectorXd& lambda,
                      Eigen::Ref<VectorXd> out) {
  if (ws.sparse) {
    // (the sparse engine writes constraint k's columns only)
    out.setZero();
    ws.sparse->share(k, lambda, out);
    return;
  }
  const Index r0 = sys.row_offset(k), rows = sys.constraint(k).rows();
  out.noalias() = ws.A.middleRows(r0, rows).transpose() * lambda.segment(r0, rows);
}

}  // namespace detail

}  // namespace ukdyn

// Stage 2: the constraints in acceleration form, A q'' = b (eq. 5). Rows of constraints that are
// inactive at t are zero, so they exert no force and cost no special case downstream.
#include "detail.hpp"
#include "ukdyn/forward.hpp"

namespace ukdyn {

Status assemble_constraints(const System& sys, Workspace& ws, const VectorXd& q,
                            const VectorXd& qd, double t) {
  detail::require_same_system(sys, ws, "ukdyn::assemble_constraints");
  ws.active_rows = 0;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const Constraint& c = sys.constraint(k);
    auto Ak = ws.A.middleRows(sys.row_offset(k), c.rows());
    auto bk = ws.b.segment(sys.row_offset(k), c.rows());
    if (!c.is_active(t)) {
      // inactive: zero rows
      Ak.setZero();
      bk.setZero();
      ws.active[std::size_t(k)] = 0;
      continue;
    }
    ws.active[std::size_t(k)] = 1;
    ws.active_rows += c.rows();
    // A_k, b_k from the constraint's own form
    c.model().acceleration_form(q, qd, t, ws.scratch[std::size_t(k)].get(), Ak, bk);
    if (!Ak.allFinite()) return detail::fail(ws, Status::kNonFiniteInput, "A", k, t);
    if (!bk.allFinite()) return detail::fail(ws, Status::kNonFiniteInput, "b", k, t);
  }
  return Status::kOk;
}

}  // namespace ukdyn

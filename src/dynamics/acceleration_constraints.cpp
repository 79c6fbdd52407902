// SPDX-License-Identifier: BSD-3-Clause
// Stage 2: the constraints in acceleration form, A q'' = b (eq. 5). Rows of constraints that are
// inactive at t are zero, so they exert no force and cost no special case downstream.
// Stabilized constraints (Baumgarte) get b ← b − 2α phi' − β² phi, resp. b ← b − α psi.
// The engine writes the rows (dynamics/engine.hpp): the sparse one takes each constraint's local
// columns (or dense rows) into the fixed sparse pattern of A (linalg/sparse.hpp).
#include "dynamics/engine.hpp"
#include "dynamics/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn {

Status assemble_constraints(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                            const Eigen::Ref<const VectorXd>& qd, double t) {
  detail::require_same_system(sys, ws, "ukdyn::assemble_constraints");
  detail::require_state_size(sys, q, &qd, "ukdyn::assemble_constraints");
  ws.active_rows = 0;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const Constraint& c = sys.constraint(k);
    auto bk = ws.b.segment(sys.row_offset(k), c.rows());
    if (!detail::is_active(sys, ws, k, t)) {
      // inactive: zero rows
      detail::zero_constraint_rows(sys, ws, k);
      ws.active[std::size_t(k)] = 0;
      continue;
    }
    ws.active[std::size_t(k)] = 1;
    ws.active_rows += c.rows();
    // A_k, b_k from the constraint's own form
    if (const Status s = detail::write_constraint_rows(sys, ws, k, q, qd, t); s != Status::kOk) {
      return s;
    }
    if (!detail::all_finite(bk)) return detail::fail(ws, Status::kNonFiniteInput, "b", k, t);
    // Baumgarte: phi'' + 2α phi' + β² phi = 0, psi' + α psi = 0
    const Stabilization& st = ws.stabilization[std::size_t(k)];
    if (st.enabled() && c.kind() != ConstraintKind::kAcceleration) {
      auto pk = ws.phi.segment(sys.row_offset(k), c.rows());
      auto vk = ws.phi_dot.segment(sys.row_offset(k), c.rows());
      c.model().violation(q, qd, t, ws.scratch[std::size_t(k)].get(), pk, vk);
      if (c.kind() == ConstraintKind::kHolonomic) {
        bk -= 2.0 * st.alpha * vk + st.beta * st.beta * pk;
      } else {
        bk -= st.alpha * vk;
      }
      if (!detail::all_finite(bk)) return detail::fail(ws, Status::kNonFiniteInput, "b", k, t);
    }
  }
  // a singular M: stage 1 completes with the constraints, M_A = M + Aᵀ G A, a = M_A⁻¹ Q_A
  if (ws.mass_singular) return detail::complete_singular_mass(ws, t, /*forces=*/true, false);
  return Status::kOk;
}

}  // namespace ukdyn

// Stage 4: non-ideal constraints (eqs. 7, 9, 12). C is summed from the system's forces, which may
// read the ideal force (it does not depend on C), then projected:
//   Qc_nonideal = L (I − W⁺W) L⁻¹ C,   q'' += L⁻ᵀ (I − W⁺W) L⁻¹ C.
#include "detail.hpp"
#include "ukdyn/forward.hpp"
#include "ukdyn/nonideal.hpp"
#include "ukdyn/sparse.hpp"

namespace ukdyn {

Status apply_nonideal(const System& sys, Workspace& ws, const VectorXd& q, const VectorXd& qd,
                      double t) {
  detail::require_same_system(sys, ws, "ukdyn::apply_nonideal");
  ws.C.setZero();
  if (sys.nonideal_count() == 0) {
    // ideal constraints: Qc = Qc_ideal
    ws.Qc_nonideal.setZero();
    ws.lambda_nonideal.setZero();
    ws.Qc = ws.Qc_ideal;
    return Status::kOk;
  }
  // v_rel of each Coulomb contact whose friction acts (its constraint's rows are assembled)
  const auto& contacts = sys.friction_contacts();
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    if (ws.nonideal_enabled[std::size_t(contacts[c].force)]) {
      detail::sliding_velocity(sys, ws, Index(c), q, qd, t, true);
    }
  }
  // C = Σ C_i(q, q', t, ideal force)
  const IdealForceInfo ideal(sys, ws);
  for (Index i = 0; i < sys.nonideal_count(); ++i) {
    if (!ws.nonideal_enabled[std::size_t(i)]) continue;
    ws.C_term.setZero();
    sys.nonideal(i)(q, qd, t, ideal, ws.C_term);
    if (!ws.C_term.allFinite()) return detail::fail(ws, Status::kNonFiniteInput, "C", i, t);
    ws.C += ws.C_term;
  }
  // Qc_nonideal, lambda_nonideal and dq = L⁻ᵀ (I − W⁺W) L⁻¹ C
  if (ws.sparse) {
    ws.sparse->project_nonideal(ws.C, ws.dqdd, ws.Qc_nonideal, ws.lambda_nonideal);
  } else {
    detail::with_decomposition(ws, [&](auto& d) {
      d.project_nonideal(ws.C, ws.dqdd, ws.Qc_nonideal, ws.lambda_nonideal);
    });
  }
  // q'' += dq;  Qc = Qc_ideal + Qc_nonideal
  ws.qdd += ws.dqdd;
  ws.Qc = ws.Qc_ideal + ws.Qc_nonideal;
  return Status::kOk;
}

}  // namespace ukdyn

// Stage 5: checks of the result. Inconsistent constraints are detected by the constraint residual
// ‖A q'' − b‖, which is computed only where they can occur — when A has lost row rank (the
// decomposition of stage 3 says so) — or on request with the Gauss and virtual-work residuals.
#include <limits>

#include "dynamics/engine.hpp"
#include "dynamics/internal.hpp"
#include "linalg/safe_norm.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn {

Status check_result(const System& sys, Workspace& ws) {
  detail::require_same_system(sys, ws, "ukdyn::check_result");
  const detail::EngineOps& engine = *ws.engine;
  Residuals& res = ws.residuals;
  const bool requested = ws.options().compute_residuals;
  // With full row rank (rank A = active rows), A q'' = b has a solution for every b: the
  // constraints cannot be inconsistent, and the test below is skipped (its residual is then
  // reported only when requested, else NaN).
  const bool full_rank = ws.rank == ws.active_rows;
  res.constraint = std::numeric_limits<double>::quiet_NaN();
  if (requested || !full_rank) {
    // r = A q'' − b
    engine.constraint_residual(ws, ws.qdd, ws.tmp_m);
    res.constraint = detail::safe_norm(ws.tmp_m.data(), ws.tmp_m.size());
  }
  if (requested) {
    // lambda_total = lambda + lambda_nonideal, so that Qc = C + Aᵀ lambda_total; its force
    // Aᵀ lambda_total in dqdd (scratch)
    ws.tmp_m = ws.lambda + ws.lambda_nonideal;
    engine.multiply_At(ws, ws.tmp_m, ws.dqdd);
    // virtual work: ‖Qc − C − Aᵀ lambda_total‖
    ws.tmp_n = ws.Qc - ws.C - ws.dqdd;
    res.virtual_work = detail::safe_norm(ws.tmp_n.data(), ws.tmp_n.size());
    // Gauss: ‖M q'' − Q − C − Aᵀ lambda_total‖
    engine.multiply_mass(ws, ws.qdd, ws.tmp_n);
    ws.tmp_n -= ws.Q + ws.C + ws.dqdd;
    res.gauss = detail::safe_norm(ws.tmp_n.data(), ws.tmp_n.size());
  }
  if (!detail::all_finite(ws.qdd) || !detail::all_finite(ws.Qc) || !detail::all_finite(ws.lambda)) {
    return detail::fail(ws, Status::kNonFiniteResult, "q''", -1, ws.failed_time);
  }
  // consistency: ‖A q'' − b‖ <= tol (‖A‖_F (‖q''‖ + ‖a‖) + ‖b‖)
  if (full_rank) return Status::kOk;
  // (norms without overflow or underflow: A of 1e200 or of 1e-170 is still a scale)
  const auto norm = [](const VectorXd& v) { return detail::safe_norm(v.data(), v.size()); };
  const double scale = engine.norm_A(ws) * (norm(ws.qdd) + norm(ws.a)) + norm(ws.b);
  if (res.constraint > ws.options().consistency_tolerance * scale) {
    return detail::fail(ws, Status::kInconsistentConstraints, "A q'' = b", -1, ws.failed_time);
  }
  return Status::kOk;
}

}  // namespace ukdyn

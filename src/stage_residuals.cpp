// Stage 5: checks of the result. The constraint residual is always computed (it is how
// inconsistent constraints are detected); the Gauss and virtual-work residuals on request.
#include "detail.hpp"
#include "ukdyn/forward.hpp"

namespace ukdyn {

Status check_result(const System& sys, Workspace& ws) {
  detail::require_same_system(sys, ws, "ukdyn::check_result");
  Residuals& res = ws.residuals;
  // r = A q'' − b
  ws.tmp_m = -ws.b;
  ws.tmp_m.noalias() += ws.A * ws.qdd;
  res.constraint = ws.tmp_m.norm();
  if (ws.options().compute_residuals) {
    // lambda_total = lambda + lambda_nonideal, so that Qc = C + Aᵀ lambda_total
    ws.tmp_m = ws.lambda + ws.lambda_nonideal;
    // virtual work: ‖Qc − C − Aᵀ lambda_total‖
    ws.tmp_n = ws.Qc - ws.C;
    ws.tmp_n.noalias() -= ws.A.transpose() * ws.tmp_m;
    res.virtual_work = ws.tmp_n.norm();
    // Gauss: ‖M q'' − Q − C − Aᵀ lambda_total‖
    ws.tmp_n.noalias() = ws.M * ws.qdd;
    ws.tmp_n -= ws.Q + ws.C;
    ws.tmp_n.noalias() -= ws.A.transpose() * ws.tmp_m;
    res.gauss = ws.tmp_n.norm();
  }
  if (!ws.qdd.allFinite() || !ws.Qc.allFinite() || !ws.lambda.allFinite()) {
    return detail::fail(ws, Status::kNonFiniteResult, "q''", -1, ws.failed_time);
  }
  // consistency: ‖A q'' − b‖ <= tol (‖A‖_F (‖q''‖ + ‖a‖) + ‖b‖)
  const double scale = ws.A.norm() * (ws.qdd.norm() + ws.a.norm()) + ws.b.norm();
  if (res.constraint > ws.options().consistency_tolerance * scale) {
    return detail::fail(ws, Status::kInconsistentConstraints, "A q'' = b", -1, ws.failed_time);
  }
  return Status::kOk;
}

}  // namespace ukdyn

// Stage 5: checks of the result. The constraint residual is always computed (it is how
// inconsistent constraints are detected); the Gauss and virtual-work residuals on request.
#include "dynamics/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/linalg/sparse.hpp"

namespace ukdyn {

namespace {
// the same checks with the sparse engine's A and M (products, never dense matrices)
Status check_result_sparse(Workspace& ws) {
  const SparseDecomposition& sp = *ws.sparse;
  Residuals& res = ws.residuals;
  // r = A q'' − b
  sp.multiply_A(ws.qdd, ws.tmp_m);
  ws.tmp_m -= ws.b;
  res.constraint = ws.tmp_m.norm();
  if (ws.options().compute_residuals) {
    // lambda_total = lambda + lambda_nonideal;  Aᵀ lambda_total in dqdd (scratch)
    ws.tmp_m = ws.lambda + ws.lambda_nonideal;
    sp.multiply_At(ws.tmp_m, ws.dqdd);
    // virtual work: ‖Qc − C − Aᵀ lambda_total‖
    ws.tmp_n = ws.Qc - ws.C - ws.dqdd;
    res.virtual_work = ws.tmp_n.norm();
    // Gauss: ‖M q'' − Q − C − Aᵀ lambda_total‖
    sp.multiply_mass(ws.qdd, ws.tmp_n);
    ws.tmp_n -= ws.Q + ws.C + ws.dqdd;
    res.gauss = ws.tmp_n.norm();
  }
  if (!ws.qdd.allFinite() || !ws.Qc.allFinite() || !ws.lambda.allFinite()) {
    return detail::fail(ws, Status::kNonFiniteResult, "q''", -1, ws.failed_time);
  }
  // consistency: ‖A q'' − b‖ <= tol (‖A‖_F (‖q''‖ + ‖a‖) + ‖b‖)
  const double scale = sp.norm_A() * (ws.qdd.norm() + ws.a.norm()) + ws.b.norm();
  if (res.constraint > ws.options().consistency_tolerance * scale) {
    return detail::fail(ws, Status::kInconsistentConstraints, "A q'' = b", -1, ws.failed_time);
  }
  return Status::kOk;
}
}  // namespace

Status check_result(const System& sys, Workspace& ws) {
  detail::require_same_system(sys, ws, "ukdyn::check_result");
  Residuals& res = ws.residuals;
  if (ws.sparse) return check_result_sparse(ws);
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

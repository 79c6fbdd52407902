// Stage 1: the unconstrained system. M(q,t), Q(q,q',t), M = L Lᵀ, a = M⁻¹ Q (eqs. 1, 2).
#include <algorithm>
#include <cmath>

#include "detail.hpp"
#include "ukdyn/forward.hpp"

namespace ukdyn {

namespace {
// max |M_ij − M_ji| over i < j
double asymmetry(const MatrixXd& M) {
  double worst = 0.0;
  for (Index j = 0; j < M.cols(); ++j) {
    for (Index i = 0; i < j; ++i) worst = std::max(worst, std::abs(M(i, j) - M(j, i)));
  }
  return worst;
}
}  // namespace

namespace detail {
Status evaluate_mass(const System& sys, Workspace& ws, const VectorXd& q, double t) {
  // M(q,t) and M = L Lᵀ; a constant M is evaluated and factorized once
  if (!(sys.mass_is_constant() && ws.mass_factorized)) {
    ws.mass_factorized = false;
    sys.mass_matrix(q, t, ws.M);
    if (!ws.M.allFinite()) return detail::fail(ws, Status::kNonFiniteInput, "M", -1, t);
    const double scale = ws.M.cwiseAbs().maxCoeff();
    if (asymmetry(ws.M) > ws.options().symmetry_tolerance * scale) {
      return detail::fail(ws, Status::kMassNotSymmetric, "M", -1, t);
    }
    const auto info = detail::with_decomposition(
        ws, [&](auto& d) { return d.compute_mass(ws.M).info(); });
    if (info != Eigen::Success) {
      return detail::fail(ws, Status::kMassNotPositiveDefinite, "M", -1, t);
    }
    ws.mass_factorized = true;
  }
  return Status::kOk;
}
}  // namespace detail

Status evaluate_unconstrained(const System& sys, Workspace& ws, const VectorXd& q,
                              const VectorXd& qd, double t) {
  detail::require_same_system(sys, ws, "ukdyn::evaluate_unconstrained");
  if (const Status s = detail::evaluate_mass(sys, ws, q, t); s != Status::kOk) return s;
  // Q(q,q',t)
  sys.forces(q, qd, t, ws.Q);
  if (!ws.Q.allFinite()) return detail::fail(ws, Status::kNonFiniteInput, "Q", -1, t);
  // a = M⁻¹ Q
  detail::with_decomposition(ws, [&](auto& d) { d.solve_mass(ws.Q, ws.a); });
  return Status::kOk;
}

}  // namespace ukdyn

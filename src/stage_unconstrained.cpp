// Stage 1: the unconstrained system. M(q,t), Q(q,q',t), M = L Lᵀ, a = M⁻¹ Q (eqs. 1, 2).
#include <algorithm>
#include <cmath>

#include "detail.hpp"
#include "ukdyn/forward.hpp"
#include "ukdyn/sparse.hpp"

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
namespace {
// the sparse engine: the blocks M_bb(q,t) that are not constant, the same checks as below on
// the blocks, and M_bb = L_b L_bᵀ block by block
Status evaluate_mass_blocks(const System& sys, Workspace& ws, const VectorXd& q, double t) {
  SparseDecomposition& sp = *ws.sparse;
  const auto& blocks = sys.mass_blocks();
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    if (!blocks[b].constant()) blocks[b].fn(q, t, sp.mass_block(Index(b)));
  }
  if (!sp.mass_finite()) return detail::fail(ws, Status::kNonFiniteInput, "M", -1, t);
  if (sp.mass_asymmetry() > ws.options().symmetry_tolerance * sp.mass_max_abs()) {
    return detail::fail(ws, Status::kMassNotSymmetric, "M", -1, t);
  }
  if (sp.compute_mass().info() != Eigen::Success) {
    return detail::fail(ws, Status::kMassNotPositiveDefinite, "M", -1, t);
  }
  return Status::kOk;
}
}  // namespace

double kinetic_energy(const Workspace& ws, const VectorXd& qd) {
  if (ws.sparse) return 0.5 * ws.sparse->mass_norm_squared(qd);
  return 0.5 * qd.dot(ws.M * qd);
}

Status evaluate_mass(const System& sys, Workspace& ws, const VectorXd& q, double t) {
  if (ws.sparse) {
    // M(q,t) block by block; constant blocks evaluated and factorized once
    if (!(sys.mass_is_constant() && ws.mass_factorized)) {
      ws.mass_factorized = false;
      if (const Status s = evaluate_mass_blocks(sys, ws, q, t); s != Status::kOk) return s;
      ws.mass_factorized = true;
    }
    return Status::kOk;
  }
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
  if (ws.sparse) {
    ws.sparse->solve_mass(ws.Q, ws.a);
  } else {
    detail::with_decomposition(ws, [&](auto& d) { d.solve_mass(ws.Q, ws.a); });
  }
  return Status::kOk;
}

}  // namespace ukdyn

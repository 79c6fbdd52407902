// SPDX-License-Identifier: BSD-3-Clause
// find_constraint_conflict: constraints that no state near (q, q') satisfies together — the
// diagnosis of a projection that does not converge, and of inconsistent initial conditions.
//
// Linearized at (q, t), the holonomic rows ask for a correction dq with A_h dq = −phi_h, and all
// rows ask for a velocity change dv with A dv = −phi' (phi' = A q' + phi_t, or psi). Each has a
// solution exactly when the right-hand side lies in the range of A; otherwise the least-squares
// residual u = (I − A A⁺) phi is what no correction can remove: Gauss–Newton (the projection)
// stalls at a nonzero violation. That happens when the constraints contradict each other
// (x = 0 and x = 1; 1 = 0), and when a mechanism locks up: at the pose where the loop can no
// longer close, A loses rank and the driven velocity leaves its range.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/QR>
#include <Eigen/SVD>

#include "dynamics/engine.hpp"
#include "dynamics/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"
#include "ukdyn/dynamics/workspace.hpp"

namespace ukdyn {
namespace {

// the part of rhs outside the numerical range of S (rows × n): rhs − S S⁺ rhs, with Eigen's
// column-pivoting QR of S at the relative rank threshold
VectorXd outside_range(const MatrixXd& S, const Eigen::Ref<const VectorXd>& rhs, double threshold) {
  if (S.rows() == 0) return rhs;
  if (S.cols() == 0 || S.isZero(0.0)) return rhs;
  Eigen::ColPivHouseholderQR<MatrixXd> qr(S);
  qr.setThreshold(threshold);
  const VectorXd x = qr.solve(rhs);
  return rhs - S * x;
}

// the part u of the violation v that no correction removes is significant: above the tolerance
// (what a projection stalls at) and not roundoff of the violation itself
bool significant(const VectorXd& u, const VectorXd& v, double tolerance) {
  const double un = u.cwiseAbs().maxCoeff();
  return un > tolerance && un > 1e-3 * v.cwiseAbs().maxCoeff();
}

// adds to `names` (once each) the constraints owning the rows (owner[i]) that carry at least a
// tenth of max |u|
void name_rows(const System& sys, const Eigen::Ref<const VectorXd>& u,
               const std::vector<Index>& owner, std::vector<std::string>& names) {
  const double un = u.cwiseAbs().maxCoeff();
  for (Index i = 0; i < u.size(); ++i) {
    if (std::abs(u[i]) < 0.1 * un) continue;
    const std::string& name = sys.constraint(owner[std::size_t(i)]).name();
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
}

// the conflict that u (outside the range, at the velocity level or not) shows, named by the
// constraints owning its rows (owner[i])
ConstraintConflict conflict(const System& sys, const VectorXd& u, bool velocity_level,
                            const std::vector<Index>& owner) {
  ConstraintConflict out;
  out.found = true;
  out.velocity_level = velocity_level;
  out.residual = u.norm();
  name_rows(sys, u, owner, out.names);
  return out;
}

// The sparse engine's form of the test (cost linear in the bodies of a chain or tree with loop
// closures; the dense form, a QR of A, is O(m n min(m, n)): 39 s on a 512-link loop). With M =
// L Lᵀ and W = A L⁻ᵀ, range(W) = range(A), so the part of rhs outside the range of A is
//   u = rhs − W W⁺ rhs = rhs − A (L⁻ᵀ W⁺ rhs),
// and L⁻ᵀ W⁺ rhs is the engine's solve_ideal with the rank-revealing LDLᵀ of G = W Wᵀ at its
// rank threshold (docs/sparse.md). The rows of A are those of the constraints for which
// `takes_part(k)` holds (the others zeroed); rhs holds their violations. False (and u
// untouched) when M cannot be factorized at q.
template <class TakesPart>
bool outside_range_sparse(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                          const Eigen::Ref<const VectorXd>& qd, double t, TakesPart takes_part,
                          const VectorXd& rhs, VectorXd& u) {
  const Index n = sys.coordinate_count(), m = sys.constraint_rows();
  // A on the rows that take part, zero elsewhere
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (takes_part(k)) {
      detail::write_constraint_rows(sys, ws, k, q, qd, t, /*check=*/false);
    } else {
      detail::zero_constraint_rows(sys, ws, k);
    }
  }
  // M = L Lᵀ (a singular M completed with these rows), then G = W Wᵀ = P L_G D L_Gᵀ Pᵀ
  Status s = detail::evaluate_mass(sys, ws, q, t);
  if (s == Status::kOk && ws.mass_singular) {
    s = detail::complete_singular_mass(ws, t, /*forces=*/false, /*regularize=*/true);
  }
  if (s != Status::kOk) return false;
  ws.engine->decompose_constraints(ws);
  // u = rhs − A L⁻ᵀ W⁺ rhs
  VectorXd dq(n), Qc(n), lambda(m), Adq(m);
  ws.engine->solve_ideal(ws, rhs, dq, Qc, lambda);
  ws.engine->multiply_A(ws, dq, Adq);
  u = rhs - Adq;
  return u.allFinite();
}

// find_constraint_conflict with the sparse engine (ws.is_sparse()), on the rows of the `active`
// constraints (their violations evaluated into ws.phi, ws.phi_dot), in the system's row order.
// Without the dense form's last test (sigma_min / sigma_max of A below 1e-6): the sparse rank
// decision counts a row within tau = 1e-6 of the span of the others as dependent, so a
// lock-up approached shows as a residual outside the range already.
ConstraintConflict find_conflict_sparse(const System& sys, Workspace& ws,
                                        const Eigen::Ref<const VectorXd>& q,
                                        const Eigen::Ref<const VectorXd>& qd, double t,
                                        double tolerance, const std::vector<Index>& active) {
  ConstraintConflict out;
  const Index m = sys.constraint_rows(), K = sys.constraint_count();
  // which constraints take part (all levels; the holonomic ones at the position level), the
  // owner of each row, and their violations (zero on the other rows)
  std::vector<unsigned char> part(std::size_t(K), 0), holonomic(std::size_t(K), 0);
  std::vector<Index> owner(std::size_t(m), 0);
  VectorXd phi = VectorXd::Zero(m), phi_dot = VectorXd::Zero(m), u(m);
  bool any_holonomic = false;
  for (Index k = 0; k < K; ++k) {
    for (Index i = 0; i < sys.constraint(k).rows(); ++i)
      owner[std::size_t(sys.row_offset(k) + i)] = k;
  }
  for (Index k : active) {
    const Index r = sys.row_offset(k), rows = sys.constraint(k).rows();
    part[std::size_t(k)] = 1;
    phi_dot.segment(r, rows) = ws.phi_dot.segment(r, rows);
    if (sys.constraint(k).kind() == ConstraintKind::kHolonomic) {
      holonomic[std::size_t(k)] = 1;
      any_holonomic = true;
      phi.segment(r, rows) = ws.phi.segment(r, rows);
    }
  }
  if (!phi.allFinite() || !phi_dot.allFinite()) return out;
  // what no correction removes, at the position level, then at the velocity level
  if (any_holonomic) {
    const auto takes_part = [&](Index k) { return holonomic[std::size_t(k)] != 0; };
    if (!outside_range_sparse(sys, ws, q, qd, t, takes_part, phi, u)) return out;
    if (significant(u, phi, tolerance)) return conflict(sys, u, false, owner);
  }
  const auto takes_part = [&](Index k) { return part[std::size_t(k)] != 0; };
  if (!outside_range_sparse(sys, ws, q, qd, t, takes_part, phi_dot, u)) return out;
  if (significant(u, phi_dot, tolerance)) return conflict(sys, u, true, owner);
  return out;
}

}  // namespace

ConstraintConflict find_constraint_conflict(const System& sys, Workspace& ws,
                                            const Eigen::Ref<const VectorXd>& q,
                                            const Eigen::Ref<const VectorXd>& qd, double t,
                                            double tolerance) {
  ConstraintConflict out;
  const Index n = sys.coordinate_count();
  if (q.size() != n || qd.size() != n || !q.allFinite() || !qd.allFinite()) return out;
  const double threshold = ws.options().rank_threshold;

  // phi, phi' and the rows of A of the active constraints
  evaluate_violations(sys, ws, q, qd, t);
  std::vector<Index> active;
  Index rows = 0, holonomic_rows = 0;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (!detail::is_active(sys, ws, k, t)) continue;
    if (sys.constraint(k).kind() == ConstraintKind::kAcceleration) continue;
    active.push_back(k);
    rows += sys.constraint(k).rows();
    if (sys.constraint(k).kind() == ConstraintKind::kHolonomic)
      holonomic_rows += sys.constraint(k).rows();
  }
  if (rows == 0) return out;
  if (ws.is_sparse()) return find_conflict_sparse(sys, ws, q, qd, t, tolerance, active);
  for (Index k : active) {
    if (detail::write_constraint_rows(sys, ws, k, q, qd, t, /*check=*/false) != Status::kOk)
      return out;
  }
  MatrixXd A(rows, n), Ah(holonomic_rows, n);
  VectorXd phi(holonomic_rows), phi_dot(rows);
  std::vector<Index> owner(static_cast<std::size_t>(rows)),
      owner_h(static_cast<std::size_t>(holonomic_rows));
  {
    Index r = 0, h = 0;
    for (Index k : active) {
      const Index m = sys.constraint(k).rows();
      detail::copy_constraint_rows(sys, ws, k, A.middleRows(r, m));
      phi_dot.segment(r, m) = ws.phi_dot.segment(sys.row_offset(k), m);
      for (Index i = 0; i < m; ++i) owner[std::size_t(r + i)] = k;
      if (sys.constraint(k).kind() == ConstraintKind::kHolonomic) {
        Ah.middleRows(h, m) = A.middleRows(r, m);
        phi.segment(h, m) = ws.phi.segment(sys.row_offset(k), m);
        for (Index i = 0; i < m; ++i) owner_h[std::size_t(h + i)] = k;
        h += m;
      }
      r += m;
    }
  }
  if (!A.allFinite() || !phi.allFinite() || !phi_dot.allFinite()) return out;

  // what no correction removes, first at the position level, then at the velocity level;
  // significant when it is above the tolerance (what a projection stalls at) and not roundoff
  // of the violation itself
  if (holonomic_rows > 0) {
    const VectorXd u = outside_range(Ah, phi, threshold);
    if (significant(u, phi, tolerance)) return conflict(sys, u, false, owner_h);
  }
  const VectorXd u = outside_range(A, phi_dot, threshold);
  if (significant(u, phi_dot, tolerance)) return conflict(sys, u, true, owner);
  // just short of the pose where A loses rank, A is still regular but nearly singular: the
  // velocities it asks for grow like 1/sigma_min (a four-bar at lock-up: |q'| ~ 1e6) and the
  // projection stalls at the roundoff of A q'. Near rank loss: sigma_min < 1e-6 sigma_max; the
  // rows are those of the left singular vector of sigma_min
  if (rows <= n) {
    Eigen::JacobiSVD<MatrixXd> svd(A, Eigen::ComputeFullU);
    const VectorXd& sv = svd.singularValues();
    const double ratio = sv[sv.size() - 1] / sv[0];
    if (sv[0] > 0.0 && ratio < 1e-6) {
      out.found = true;
      out.velocity_level = true;
      out.singular_ratio = ratio;
      out.residual = phi_dot.cwiseAbs().maxCoeff();
      name_rows(sys, svd.matrixU().col(sv.size() - 1), owner, out.names);
    }
  }
  return out;
}

}  // namespace ukdyn

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
#include <string>
#include <vector>

#include <Eigen/QR>
#include <Eigen/SVD>

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
  auto significant = [&](const Eigen::Ref<const VectorXd>& u, const Eigen::Ref<const VectorXd>& v) {
    const double un = u.cwiseAbs().maxCoeff();
    return un > tolerance && un > 1e-3 * v.cwiseAbs().maxCoeff();
  };
  auto name_rows = [&](const Eigen::Ref<const VectorXd>& u, const std::vector<Index>& who) {
    const double un = u.cwiseAbs().maxCoeff();
    for (Index i = 0; i < u.size(); ++i) {
      if (std::abs(u[i]) < 0.1 * un) continue;
      const std::string& name = sys.constraint(who[std::size_t(i)]).name();
      if (std::find(out.names.begin(), out.names.end(), name) == out.names.end())
        out.names.push_back(name);
    }
  };
  if (holonomic_rows > 0) {
    const VectorXd u = outside_range(Ah, phi, threshold);
    if (significant(u, phi)) {
      out.found = true;
      out.velocity_level = false;
      out.residual = u.norm();
      name_rows(u, owner_h);
      return out;
    }
  }
  const VectorXd u = outside_range(A, phi_dot, threshold);
  if (significant(u, phi_dot)) {
    out.found = true;
    out.velocity_level = true;
    out.residual = u.norm();
    name_rows(u, owner);
    return out;
  }
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
      name_rows(svd.matrixU().col(sv.size() - 1), owner);
    }
  }
  return out;
}

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// initial: project: {keep: [names]} — the initial state made consistent with the constraints
// while the named coordinates (and velocities) keep the values the file gives them: the others
// take the least M-norm change that satisfies the constraints, positions by Gauss–Newton over the
// free coordinates, then velocities by the least-norm solve over the free velocities
// (docs/model-format.md, "Initial state").
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include "modelfile/initial_keep.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"

namespace ukdyn::model_reader {
namespace {

// the rows of the constraints of `kind` (holonomic rows for the positions; holonomic and
// nonholonomic for the velocities), with the constraints' names
std::vector<Index> rows_of(const System& sys, bool velocity_level) {
  std::vector<Index> rows;
  Index r = 0;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const Constraint& c = sys.constraint(k);
    const bool take = c.kind() == ConstraintKind::kHolonomic ||
                      (velocity_level && c.kind() == ConstraintKind::kNonholonomic);
    for (Index i = 0; i < c.rows(); ++i, ++r) {
      if (take) rows.push_back(r);
    }
  }
  return rows;
}

// the constraint that holds row r
std::string constraint_of_row(const System& sys, Index r) {
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (r < sys.constraint(k).rows()) return sys.constraint(k).name();
    r -= sys.constraint(k).rows();
  }
  return "?";
}

// One Gauss–Newton level: x_F ← x_F + dx_F until max |residual| over `rows` is at the roundoff
// floor, dx_F the change of least M_FF-norm that zeroes the linearized residual:
//   dx_F = −L⁻ᵀ B⁺ r,   B = J_F L⁻ᵀ,   M_FF = L Lᵀ,   J_F = the rows' Jacobian over the free F.
// `residual(x)` evaluates the rows into ws.phi or ws.phi_dot (returned); ws.A and ws.M come
// from the stages. Returns "" or what went wrong.
template <class Residual>
std::string solve_level(const System& sys, Workspace& ws, VectorXd& q, VectorXd& qd, double t,
                        bool velocity_level, const std::vector<Index>& free,
                        const std::vector<Index>& rows, Residual residual,
                        const std::vector<std::string>& kept_names) {
  const Index n = sys.coordinate_count();
  const Index f = Index(free.size()), m = Index(rows.size());
  if (m == 0) return "";
  constexpr int kMaxIterations = 50;
  constexpr double kTolerance = 1e-12;
  const char* level = velocity_level ? "velocities" : "positions";
  double last = std::numeric_limits<double>::infinity();
  int stalled = 0;
  for (int it = 0; it <= kMaxIterations; ++it) {
    const VectorXd& all = residual();
    VectorXd r(m);
    for (Index i = 0; i < m; ++i) r[i] = all[rows[std::size_t(i)]];
    if (!r.allFinite()) return std::string("the constraints are not finite at the ") + level;
    const double violation = r.cwiseAbs().maxCoeff();
    // converged at the roundoff floor (three corrections that do not halve it) or below 1e-15
    if (violation <= 1e-15) return "";
    // everything kept: nothing is left to move, and the values given do not satisfy the rows
    if (f == 0) {
      return std::string("keeping ") + join(kept_names) + " leaves no " +
             (velocity_level ? "velocity" : "coordinate") +
             " free, and the values given violate the constraints' " + level + " rows by " +
             format_number(violation, 3);
    }
    stalled = violation > 0.5 * last ? stalled + 1 : 0;
    if (stalled >= 3 && violation <= kTolerance) return "";
    last = violation;
    if (it == kMaxIterations) break;
    if (evaluate_unconstrained(sys, ws, q, qd, t) != Status::kOk ||
        assemble_constraints(sys, ws, q, qd, t) != Status::kOk) {
      return std::string("the mass matrix or the constraints cannot be evaluated at the ") + level;
    }
    // J_F, and the rank of J over every coordinate: fewer with F only = over-determined
    MatrixXd J(m, n);
    for (Index i = 0; i < m; ++i) J.row(i) = ws.A.row(rows[std::size_t(i)]);
    MatrixXd JF(m, f);
    for (Index j = 0; j < f; ++j) JF.col(j) = J.col(free[std::size_t(j)]);
    // M_FF = L Lᵀ (the identity where M is not at hand or not positive definite there)
    MatrixXd MFF = MatrixXd::Identity(f, f);
    if (ws.M.rows() == n) {
      for (Index a = 0; a < f; ++a)
        for (Index b = 0; b < f; ++b) MFF(a, b) = ws.M(free[std::size_t(a)], free[std::size_t(b)]);
    }
    Eigen::LLT<MatrixXd> llt(MFF);
    if (llt.info() != Eigen::Success) {
      MFF.setIdentity();
      llt.compute(MFF);
    }
    // B = J_F L⁻ᵀ: Bᵀ = L⁻¹ J_Fᵀ
    const MatrixXd B = llt.matrixL().solve(JF.transpose()).transpose();
    Eigen::CompleteOrthogonalDecomposition<MatrixXd> cod(B);
    cod.setThreshold(1e-10);
    if (it == 0) {
      Eigen::CompleteOrthogonalDecomposition<MatrixXd> whole(J);
      whole.setThreshold(1e-10);
      if (cod.rank() < whole.rank()) {
        std::vector<std::string> names;
        for (Index i = 0; i < m; ++i) {
          const std::string c = constraint_of_row(sys, rows[std::size_t(i)]);
          if (std::find(names.begin(), names.end(), c) == names.end()) names.push_back(c);
        }
        return std::string("keeping ") + join(kept_names) +
               " over-determines the constraints: " + "the other " + level +
               " cannot satisfy them (rank " + format_number(cod.rank()) + " of the constraints' " +
               level + " rows over the free coordinates, " + format_number(whole.rank()) +
               " over all; constraints " + join(names) + ")";
      }
    }
    // dx_F = −L⁻ᵀ B⁺ r
    const VectorXd y = cod.solve(r);
    const VectorXd dx = -llt.matrixL().transpose().solve(y);
    VectorXd& x = velocity_level ? qd : q;
    for (Index j = 0; j < f; ++j) x[free[std::size_t(j)]] += dx[j];
  }
  return std::string("the Newton iteration for the ") + level + " did not converge in " +
         format_number(kMaxIterations) + " steps (violation " + format_number(last, 3) +
         "): no consistent state near the one given keeps " + join(kept_names);
}

}  // namespace

std::string project_keeping(const System& sys, VectorXd& q, VectorXd& qd, double t,
                            const std::vector<unsigned char>& keep_q,
                            const std::vector<unsigned char>& keep_qd,
                            const std::vector<std::string>& kept_names) {
  const Index n = sys.coordinate_count();
  // the dense engine, whose stages fill ws.A and ws.M (the sparse one, kAuto's choice for body
  // models, keeps them sparse): a Newton iteration once at load time
  SolverOptions dense_engine;
  dense_engine.engine = Engine::kDense;
  Workspace ws(sys, dense_engine);
  std::vector<Index> free_q, free_qd;
  for (Index j = 0; j < n; ++j) {
    if (!keep_q[std::size_t(j)]) free_q.push_back(j);
    if (!keep_qd[std::size_t(j)]) free_qd.push_back(j);
  }
  // positions: phi(q, t) = 0 over the free coordinates
  std::string why = solve_level(
      sys, ws, q, qd, t, false, free_q, rows_of(sys, false),
      [&]() -> const VectorXd& {
        evaluate_violations(sys, ws, q, qd, t);
        return ws.phi;
      },
      kept_names);
  if (!why.empty()) return why;
  // velocities: phi'(q, q', t) = 0 and psi(q, q', t) = 0 over the free velocities
  return solve_level(
      sys, ws, q, qd, t, true, free_qd, rows_of(sys, true),
      [&]() -> const VectorXd& {
        evaluate_violations(sys, ws, q, qd, t);
        return ws.phi_dot;
      },
      kept_names);
}

}  // namespace ukdyn::model_reader

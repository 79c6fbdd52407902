// SPDX-License-Identifier: BSD-3-Clause
// Stage 3 of the control pipeline: the control laws. A force F meets the requirements on the
// physically constrained nominal model iff X F = e, X = A_r P, P = L⁻ᵀ (I − W_p⁺ W_p) L⁻¹.
// Every law is the least-cost solution (least squares when none exists), computed with the
// decomposition of the fundamental equation — a "mass" matrix (the cost) and "constraint" rows:
//
//   Gauss, every coordinate actuated:  min F ᵀ M⁻¹ F     mass M,        rows X M:   F = L W⁺ e
//   otherwise, F = S u:                min uᵀ Nu u       mass Nu,       rows X S:   u = R⁻ᵀ W⁺ e
//        Nu = Sᵀ N S (weighted law; N itself when S = I), or Sᵀ M⁻¹ S (Gauss law with actuation)
//
// (with W = rows · (Cholesky factor)⁻ᵀ). Neither M^{1/2}, N^{1/2} nor any pseudo-inverse is formed.
// X M = A_r P M: row i is L (I − W_p⁺W_p) L⁻¹ A_r,iᵀ, the "non-ideal projection" of A_r,iᵀ, and
// X = A_r P: row i is P A_r,iᵀ; both A_r and A_r M⁻¹ without physical constraints.
#include <cmath>

#include "control/internal.hpp"

namespace ukdyn {

namespace {
// a requirement row the control cannot move: its row of X (S) within this fraction of the
// largest, relative to the rows of A_r (solve_law_on's feasibility test)
constexpr double kUnmoved = 1e-10;
// the roundoff of a held requirement row's e_i relative to ‖A_r,i‖ ‖a‖ (see compute_control)
constexpr double kHeldRoundoff = 1e-12;

// Whether a row of X (or X M) is roundoff of a direction the physical constraints remove, to be
// zeroed: ‖M P A_r,iᵀ‖ (mp: the non-ideal projection L Π L⁻¹ A_r,iᵀ, dimensionless against
// ‖A_r,i‖ and unchanged when M is scaled) within kUnmoved of ‖A_r,i‖ (a). A requirement on a
// held contact's gap, or on a combination parallel to its row, tilted against the coordinates,
// leaves ‖X_i‖ ~ 1e-17, not 0, and the decomposition's rank threshold is relative to the largest
// row: a lone such row counted as rank 1 and the law answered e_i / 1e-17 (a lift off an incline
// diverged at t = 5e-7 s; docs/contact.md, "Contacts under control"). Zeroed, it is a row the
// control cannot move, decided by the contacts (the feasibility test below). O(n).
bool removed(const VectorXd& mp, const VectorXd& a) { return mp.norm() <= kUnmoved * a.norm(); }
}  // namespace

namespace control_detail {

void apply_law(const Controller& ctrl, ControlWorkspace& ws, const Eigen::Ref<const VectorXd>& r,
               Eigen::Ref<VectorXd> u, Eigen::Ref<VectorXd> Q, Eigen::Ref<VectorXd> minv_Q) {
  if (gauss_direct(ctrl)) {
    // Q = L W⁺ r;  M⁻¹ Q = L⁻ᵀ W⁺ r
    ws.decomposition.solve_ideal(r, minv_Q, Q, ws.lambda_r);
    u = Q;
    return;
  }
  // u = R⁻ᵀ W⁺ r (Nu u into tmp_k)
  ws.decomposition.solve_ideal(r, u, ws.tmp_k, ws.lambda_r);
  // Q = S u
  if (ctrl.fully_actuated()) {
    Q = u;
  } else if (!ctrl.actuated_coordinates().empty()) {
    Q.setZero();
    const auto& idx = ctrl.actuated_coordinates();
    for (std::size_t j = 0; j < idx.size(); ++j) Q[idx[j]] = u[Index(j)];
  } else {
    Q.noalias() = ctrl.actuation() * u;
  }
}

}  // namespace control_detail

ControlStatus solve_law(const Controller& ctrl, ControlWorkspace& ws,
                        const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                        double t) {
  control_detail::require_same_controller(ctrl, ws, "ukdyn::solve_law");
  return control_detail::solve_law_on(ctrl, ws, q, qd, t, false);
}

ControlStatus control_detail::solve_law_on(const Controller& ctrl, ControlWorkspace& ws,
                                           const Eigen::Ref<const VectorXd>& q,
                                           const Eigen::Ref<const VectorXd>& qd, double t,
                                           bool mass_factorized) {
  const Index m_r = ctrl.requirement_rows();
  const bool physical = ws.model.active_rows > 0;
  FundamentalDecomposition& dp = ws.model.decomposition;  // M = L Lᵀ and W_p of the model
  const MatrixXd& A = ws.req.A;
  double solution_norm = 0.0;  // ‖M⁻¹ Q_c‖ resp. ‖u‖, for the feasibility test
  if (control_detail::gauss_direct(ctrl)) {
    // mass M (a constant M is factorized once; the fused stage 1 factorized it already). A
    // singular M (a rigid body's quaternion block; docs/singular-mass.md) takes the model's
    // completion M_A = M + A_pᵀ G A_p, positive definite where [M; A_p] has full column rank:
    // the compliance P of the model is the same (it is M_A's, the model's decomposition), the
    // law min Fᵀ M_A⁻¹ F over X F = e meets the requirements as M's would, and F differs from
    // an M-minimal one only by forces A_pᵀ μ that the physical constraints take (the
    // quaternion's unit norm: no motion, no work)
    const bool singular = ws.model.mass_singular;
    if (!mass_factorized && !(ctrl.model().mass_is_constant() && !singular && ws.cost_factorized)) {
      ws.decomposition.compute_mass(singular ? ws.model.M_aux : ws.model.M);
      if (ws.decomposition.info() != Eigen::Success) {
        return control_detail::fail(ws, ControlStatus::kModelFailed, "M", -1, t);
      }
      ws.cost_factorized = true;
    }
    // rows X M = A_r P M
    if (!physical) {
      ws.X = A;
    } else {
      for (Index i = 0; i < m_r; ++i) {
        ws.tmp_n = A.row(i).transpose();
        dp.project_nonideal(ws.tmp_n, ws.tmp_n2, ws.tmp_n3, ws.lambda_p);
        ws.X.row(i) = ws.tmp_n3.transpose();
        if (removed(ws.tmp_n3, ws.tmp_n)) ws.X.row(i).setZero();
      }
    }
    ws.decomposition.compute_constraints(ws.X);
    ws.rank = ws.decomposition.rank();
    // Qc = L W⁺ e, eq. (25);  M⁻¹ Qc into tmp_n
    control_detail::apply_law(ctrl, ws, ws.e, ws.u, ws.Qc_nominal, ws.tmp_n);
    // residual = X Qc − e = (X M)(M⁻¹ Qc) − e
    ws.residual.noalias() = ws.X * ws.tmp_n;
    ws.residual -= ws.e;
    solution_norm = ws.tmp_n.norm();
  } else {
    // X = A_r P
    for (Index i = 0; i < m_r; ++i) {
      ws.tmp_n = A.row(i).transpose();
      if (physical) {
        dp.project_nonideal(ws.tmp_n, ws.tmp_n2, ws.tmp_n3, ws.lambda_p);
      } else {
        dp.solve_mass(ws.tmp_n, ws.tmp_n2);
      }
      ws.X.row(i) = ws.tmp_n2.transpose();
      if (physical && removed(ws.tmp_n3, ws.tmp_n)) ws.X.row(i).setZero();
    }
    // cost matrix Nu and its Cholesky factor (a constant one once)
    const bool constant = ctrl.law() == ControlLaw::kWeighted ? ctrl.weight_is_constant()
                                                              : ctrl.model().mass_is_constant();
    if (!(constant && ws.cost_factorized)) {
      if (ctrl.law() == ControlLaw::kWeighted) {
        // N(q, q', t); Nu = Sᵀ N S
        ctrl.weight(q, qd, t, ws.N);
        if (!ws.N.allFinite()) {
          return control_detail::fail(ws, ControlStatus::kNonFiniteInput, "N", -1, t);
        }
        if (ctrl.fully_actuated()) {
          ws.decomposition.compute_mass(ws.N);
        } else {
          ws.MinvS.noalias() = ws.N * ctrl.actuation();
          ws.Nu.noalias() = ctrl.actuation().transpose() * ws.MinvS;
          ws.decomposition.compute_mass(ws.Nu);
        }
      } else {
        // Nu = Sᵀ M⁻¹ S
        for (Index j = 0; j < ctrl.actuators(); ++j) {
          dp.solve_mass(ctrl.actuation().col(j), ws.MinvS.col(j));
        }
        ws.Nu.noalias() = ctrl.actuation().transpose() * ws.MinvS;
        ws.decomposition.compute_mass(ws.Nu);
      }
      if (ws.decomposition.info() != Eigen::Success) {
        return control_detail::fail(ws, ControlStatus::kWeightNotPositiveDefinite, "N", -1, t);
      }
      ws.cost_factorized = true;
    }
    // rows X S
    if (ctrl.fully_actuated()) {
      ws.XS = ws.X;
    } else if (!ctrl.actuated_coordinates().empty()) {
      const auto& idx = ctrl.actuated_coordinates();
      for (std::size_t j = 0; j < idx.size(); ++j) ws.XS.col(Index(j)) = ws.X.col(idx[j]);
    } else {
      ws.XS.noalias() = ws.X * ctrl.actuation();
    }
    // a row the actuators do not move (X_i S roundoff of X_i: a ball sliding on a rough floor,
    // whose centre a torque moves only through the friction it does not change) zeroed, as
    // removed() zeroes X_i: its entries in the quaternion's columns, ~1e-17 of the centre's,
    // counted as rank and the law answered e_i / 1e-17 (Qc ~ 1e16, the step size underflowed
    // at t = 7.5e-10 s; u22 05)
    if (physical) {
      const double s_max = ctrl.fully_actuated() || !ctrl.actuated_coordinates().empty()
                               ? 1.0
                               : ctrl.actuation().colwise().norm().maxCoeff();
      for (Index i = 0; i < m_r; ++i) {
        if (ws.XS.row(i).norm() <= kUnmoved * s_max * ws.X.row(i).norm()) ws.XS.row(i).setZero();
      }
    }
    ws.decomposition.compute_constraints(ws.XS);
    ws.rank = ws.decomposition.rank();
    // u = R⁻ᵀ (X S R⁻ᵀ)⁺ e,  Qc = S u
    control_detail::apply_law(ctrl, ws, ws.e, ws.u, ws.Qc_nominal, ws.tmp_n);
    // residual = X S u − e
    ws.residual.noalias() = ws.XS * ws.u;
    ws.residual -= ws.e;
    solution_norm = ws.u.norm();
  }
  // row i met when |residual_i| <= tol (‖row_i‖ ‖solution‖ + |e_i| + ‖A_r,i‖ ‖a_p‖ + |b_r,i|):
  // the last two are the terms of e_i = b_r,i − A_r,i a_p, whose roundoff they bound. A row that
  // the control cannot move (row_i = 0 to roundoff, 1e-10 of the largest ‖row_j‖ / ‖A_r,j‖:
  // a requirement that duplicates a held contact or a joint) is decided by the physical
  // constraints, and met when they hold it to 100 tol of those terms: at a run's stage states,
  // off the constraints' manifold by the step's error, the requirement's stabilization turns
  // that drift into e_i ~ 1e-8 of its terms, which no control can meet (it was "not met", the
  // contact was let go, or the step failed; tests/control/test_control_contacts.cpp)
  const MatrixXd& rows = control_detail::gauss_direct(ctrl) ? ws.X : ws.XS;
  const double tol = ctrl.options().feasibility_tolerance;
  // (each added term only widens the test: a row met without them is met, and the common case
  // costs one row norm, as before they were added; the others are formed for a row that fails)
  // ‖a_p‖, ‖a‖ and the largest ‖row_j‖ / ‖A_r,j‖, when needed
  double qdd_p = -1.0, qdd_a = -1.0, moved = -1.0;
  ws.rows_not_met = 0;
  for (Index i = 0; i < m_r; ++i) {
    const double x = rows.row(i).norm(), r = std::abs(ws.residual[i]);
    bool ok = r <= tol * (x * solution_norm + std::abs(ws.e[i]));
    if (!ok) {
      if (qdd_p < 0.0) {
        qdd_p = ws.model.qdd.norm();
        qdd_a = ws.model.a.norm();
        moved = 0.0;
        for (Index j = 0; j < m_r; ++j) {
          const double a = A.row(j).norm();
          if (a > 0.0) moved = std::max(moved, rows.row(j).norm() / a);
        }
      }
      const double a = A.row(i).norm();
      const double terms = a * qdd_p + std::abs(ws.req.b[i]);
      const bool decided = a > 0.0 && x <= kUnmoved * moved * a;
      ok = r <= tol * (x * solution_norm + std::abs(ws.e[i]) + (decided ? 100.0 : 1.0) * terms);
      // (and a decided row at roundoff of a = M⁻¹ Q's terms: a held a_p is what the constraint
      // forces leave of a — a particle pushed by F and held at rest has e_i ~ 1e-16 F/m with
      // b_r,i = 0 and a_p = 0, which was "not met", u16 02)
      ok = ok || (decided && r <= kHeldRoundoff * a * qdd_a);
    }
    ws.met[std::size_t(i)] = ok ? 1 : 0;
    if (!ok) ++ws.rows_not_met;
  }
  if (ws.rows_not_met > 0) {
    ws.status = ControlStatus::kRequirementsNotMet;
    return ControlStatus::kRequirementsNotMet;
  }
  return ControlStatus::kOk;
}

}  // namespace ukdyn

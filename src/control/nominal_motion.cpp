// SPDX-License-Identifier: BSD-3-Clause
// Stage 1 of the control pipeline: the nominal model's physically constrained motion without
// control, a_p = a + L⁻ᵀ W_p⁺ (b_p − A_p a) (+ its non-ideal part), eq. (9) — the "unconstrained"
// acceleration that the requirements are then imposed on.
#include <cmath>
#include <cstring>

#include "control/internal.hpp"
#include "dynamics/dense_engine.hpp"
#include "dynamics/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/linalg/sparse.hpp"

namespace ukdyn {

ControlStatus evaluate_model(const Controller& ctrl, ControlWorkspace& ws,
                             const Eigen::Ref<const VectorXd>& q,
                             const Eigen::Ref<const VectorXd>& qd, double t) {
  control_detail::require_same_controller(ctrl, ws, "ukdyn::evaluate_model");
  // M, L, a, A_p, W_p, a_p = model.qdd, physical reaction model.Qc
  if (forward_dynamics(ctrl.model(), ws.model, q, qd, t) != Status::kOk) {
    return control_detail::fail(ws, ControlStatus::kModelFailed, "model", -1, t);
  }
  return ControlStatus::kOk;
}

namespace control_detail {

bool fused_model(const Controller& ctrl) {
  const System& model = ctrl.model();
  return gauss_direct(ctrl) && model.constraint_count() == 0 && model.nonideal_count() == 0 &&
         model.mass_tree().empty();
}

namespace {
// Q(q, q', t), a = M⁻¹ Q = a_p with the factorized M (no physical constraints: model.Qc stays
// zero); false for a non-finite Q
bool solve_fused(const System& model, ControlWorkspace& ws, const Eigen::Ref<const VectorXd>& q,
                 const Eigen::Ref<const VectorXd>& qd, double t) {
  Workspace& m = ws.model;
  model.forces(q, qd, t, m.callables.get(), m.Q);
  if (!detail::all_finite(m.Q)) return false;
  ws.decomposition.solve_mass(m.Q, m.a);
  m.qdd = m.a;
  return true;
}
}  // namespace

bool adopt_plant_factor(const MatrixXd& M, const Workspace* plant, FundamentalDecomposition& d) {
  // the plant's evaluation (dense engine, a regular M) holds M_p = L_p L_pᵀ of its M_p
  if (plant == nullptr || plant->engine != &detail::dense_engine() || plant->mass_singular ||
      !plant->mass_factorized) {
    return false;
  }
  const Index n = M.rows();
  const MatrixXd& Mp = plant->M;
  if (Mp.rows() < n) return false;
  // M is M_p's leading block bit for bit, and exactly symmetric (so the dense engine's checks,
  // which M_p passed, pass on M too)
  for (Index j = 0; j < n; ++j) {
    if (std::memcmp(M.col(j).data(), Mp.col(j).data(), sizeof(double) * std::size_t(n)) != 0) {
      return false;
    }
    for (Index i = j + 1; i < n; ++i) {
      if (!(M(i, j) == M(j, i))) return false;
    }
  }
  return d.adopt_mass(plant->decomposition);
}

bool evaluate_model_fused(const Controller& ctrl, ControlWorkspace& ws,
                          const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                          double t, const Workspace* plant) {
  if (!fused_model(ctrl)) return false;
  // (non-finite input: forward_dynamics says which)
  if (!std::isfinite(t) || detail::first_non_finite(q) >= 0 || detail::first_non_finite(qd) >= 0) {
    return false;
  }
  const System& model = ctrl.model();
  Workspace& m = ws.model;
  FundamentalDecomposition& d = ws.decomposition;
  // M(q, t) and M = L Lᵀ in the law's decomposition, with the dense engine's checks (a constant
  // M once); anything the dense engine would not factorize as it is (non-finite, not symmetric,
  // singular) goes to forward_dynamics, which reports or completes it
  if (!(model.mass_is_constant() && ws.cost_factorized)) {
    ws.cost_factorized = false;
    model.mass_matrix(q, t, m.callables.get(), m.M);
    // the plant's factor of this very M (its leading block), when it has one
    if (adopt_plant_factor(m.M, plant, d)) {
      ws.cost_factorized = true;
      return solve_fused(model, ws, q, qd, t);
    }
    double scale = 0.0, asym = 0.0;
    if (!detail::check_mass_entries(m.M, scale, asym) ||
        asym > m.options().symmetry_tolerance * scale) {
      return false;
    }
    if (d.compute_mass(m.M).info() != Eigen::Success) return false;
    const auto L = d.matrix_llt().diagonal();
    for (Index k = 0; k < L.size(); ++k) {
      if (!SparseDecomposition::pivot_is_regular(L[k] * L[k], m.M(k, k))) return false;
    }
    ws.cost_factorized = true;
  }
  return solve_fused(model, ws, q, qd, t);
}

}  // namespace control_detail

}  // namespace ukdyn

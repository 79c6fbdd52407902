// SPDX-License-Identifier: BSD-3-Clause
// Internal helpers shared by the control stages (not installed).
#pragma once

#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "ukdyn/control/control.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn::control_detail {

// A number for messages: 6 significant digits.
inline std::string format(double v) { return format_number(v, 6); }

// Records a failing status in the control workspace (tier 3) and returns it.
inline ControlStatus fail(ControlWorkspace& ws, ControlStatus s, const char* quantity, Index index,
                          double t) {
  ws.status = s;
  ws.failed_quantity = quantity;
  ws.failed_index = index;
  ws.failed_time = t;
  ++ws.counters.failures;
  return s;
}

// Tier 1: refuses a workspace made for another controller, or a moved-from one
// (controller_id() 0).
inline void require_same_controller(const Controller& ctrl, const ControlWorkspace& ws,
                                    const char* who) {
  if (ctrl.id() != ws.controller_id()) {
    if (ws.controller_id() == 0) {
      throw std::invalid_argument(std::string(who) +
                                  ": the control workspace is empty (moved from); make one with "
                                  "ControlWorkspace(ctrl)");
    }
    throw std::invalid_argument(std::string(who) +
                                ": the control workspace was made for another controller (make "
                                "one with ControlWorkspace(ctrl))");
  }
}

// The law's force for a requirement-space vector r (m_r) with the factorized decomposition:
// Gauss fully actuated: Q = L W⁺ r (and M⁻¹ Q into minv_Q); otherwise u = R⁻ᵀ (X S R⁻ᵀ)⁺ r and
// Q = S u (minv_Q untouched). Cost O(n² + n m_r) (+ O(n k) for S u).
void apply_law(const Controller& ctrl, ControlWorkspace& ws, const Eigen::Ref<const VectorXd>& r,
               Eigen::Ref<VectorXd> u, Eigen::Ref<VectorXd> Q, Eigen::Ref<VectorXd> minv_Q);

// Stage 3 (solve_law) with mass_factorized: the law's decomposition already holds the factor of
// this evaluation's M (evaluate_model_fused did it), for the Gauss law fully actuated.
ControlStatus solve_law_on(const Controller& ctrl, ControlWorkspace& ws,
                           const Eigen::Ref<const VectorXd>& q,
                           const Eigen::Ref<const VectorXd>& qd, double t, bool mass_factorized);

// Stage 5 (check_control) with dp, the decomposition that holds the model's M = L Lᵀ (and, with
// physical constraints, the model's W_p): ws.model.decomposition, or the law's after
// evaluate_model_fused.
ControlStatus check_control_on(const Controller& ctrl, ControlWorkspace& ws,
                               const Eigen::Ref<const VectorXd>& qd, FundamentalDecomposition& dp);

// Whether stage 1 and the law's factorization can be fused (evaluate_model_fused): the Gauss law
// fully actuated, on a model without constraints and non-ideal forces whose M is factorized
// densely (no mass tree). Then the law's "mass" is the model's M, a_p = a = M⁻¹ Q, and one
// Cholesky factor serves the model, the law and the control's effect. Cost O(1).
bool fused_model(const Controller& ctrl);

// Stage 1 fused with the law's factorization, for fused_model(ctrl): M, Q into ws.model (M,
// Q, a, qdd = a; model.Qc stays zero), M = L Lᵀ in ws.decomposition, with the dense engine's
// checks. The same bits as evaluate_model followed by solve_law's own factorization, one
// Cholesky and no empty constraint stage fewer. False when it does not apply, or when the
// input or M is one the dense engine would report or complete (non-finite, not symmetric,
// singular): then the caller runs evaluate_model, which does. With plant (a controlled
// system's workspace whose evaluation has just factorized its M_p = diag(M, I)), the factor of
// M is adopted from the plant's when M is M_p's leading block bit for bit (adopt_plant_factor):
// the same bits without the checks and the Cholesky. Cost O(n³/3) (O(n²) for a constant M
// after the first, or an adopted factor). No allocation.
bool evaluate_model_fused(const Controller& ctrl, ControlWorkspace& ws,
                          const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                          double t, const Workspace* plant = nullptr);

// d ← the factor of M taken from plant's decomposition (FundamentalDecomposition::adopt_mass),
// when plant (may be null) ran the dense engine on a regular M_p whose leading n × n block is M
// bit for bit, and M is exactly symmetric; else false, d unchanged. Cost O(n²).
bool adopt_plant_factor(const MatrixXd& M, const Workspace* plant, FundamentalDecomposition& d);

// compute_control, offering the controlled system's workspace plant (may be null) to
// evaluate_model_fused. The same results as compute_control.
ControlStatus compute_control_in(const Controller& ctrl, ControlWorkspace& ws,
                                 const Eigen::Ref<const VectorXd>& q,
                                 const Eigen::Ref<const VectorXd>& qd, double t,
                                 const Workspace* plant);

// True when the law runs on (M, X M) — Gauss, fully actuated — rather than on (cost, X S).
inline bool gauss_direct(const Controller& ctrl) {
  return ctrl.law() == ControlLaw::kGauss && ctrl.fully_actuated();
}

// The robust bound's check over a run's samples (robust_term.cpp): each active row's |error|
// against its guaranteed bound (ControlledTrajectory::error_bound); the first time and the worst
// ratio where it is exceeded by more than ControlStatistics::kBoundMargin go into the control's
// statistics and a note of the run. The bound holds only for requirements active from the start
// (docs/control.md, section 4): the others are not checked.
class BoundWatch {
 public:
  BoundWatch(const Controller& ctrl, double t_start);
  // one sample's row i: its error e and its bound. Cost O(1), no allocation.
  void add(double t, Index i, double e, double bound);
  // the statistics and the note (in the model's time unit); nothing if the bound held
  void finish(ControlStatistics& stats, RunStatistics& run, const std::string& time_unit) const;

 private:
  const Controller* ctrl_;
  double t_start_;
  double largest_ = 0.0;  // largest bound so far (the rounding floor's scale)
  double first_ = std::numeric_limits<double>::quiet_NaN();
  Index first_row_ = -1;
  long exceeded_ = 0, checked_ = 0;  // samples × rows outside the bound, and checked
  double worst_ = 0.0, worst_time_ = 0.0;
  Index worst_row_ = -1;
};

// describe_control_status(ctrl, ws), whose kRequirementsNotMet text says what the control
// applied: with `held`, the control that meets the requirements with the sliding Coulomb
// contacts held (ContactModes::hold_sliding), under which they slide; else the least-squares
// force. O(m_r n) (explain_requirements_not_met's)
std::string describe_control_status(const Controller& ctrl, const ControlWorkspace& ws, bool held);

}  // namespace ukdyn::control_detail

// SPDX-License-Identifier: BSD-3-Clause
// Internal helpers shared by the control stages (not installed).
#pragma once

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

// True when the law runs on (M, X M) — Gauss, fully actuated — rather than on (cost, X S).
inline bool gauss_direct(const Controller& ctrl) {
  return ctrl.law() == ControlLaw::kGauss && ctrl.fully_actuated();
}

}  // namespace ukdyn::control_detail

// SPDX-License-Identifier: BSD-3-Clause
// forward_dynamics: the stages of dynamics/forward.hpp in order.
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/core/format.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "dynamics/internal.hpp"

namespace ukdyn {

namespace {
void require_size(const Eigen::Ref<const VectorXd>& v, Index n, const char* what) {
  if (v.size() != n) {
    throw std::invalid_argument(std::string("ukdyn::forward_dynamics: ") + what + " has " +
                                format_number(v.size()) +
                                " entries, expected n = " + format_number(n));
  }
}

// A failure before the results were computed (non-finite input, M, A, b or C): q'', the forces
// and the multipliers hold NaN rather than the previous evaluation's values, which a caller
// ignoring the status would otherwise take for this one's. (A failure found by check_result —
// inconsistent constraints, a non-finite result — keeps what was computed: the least-squares
// q'' that describe_status reports the residual of.) The non-ideal parts of a system without
// non-ideal forces stay zero, their value at every state. No allocation.
Status invalidate_results(const System& sys, Workspace& ws, Status s) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ws.qdd.setConstant(nan);
  ws.Qc.setConstant(nan);
  ws.Qc_ideal.setConstant(nan);
  ws.lambda.setConstant(nan);
  if (sys.nonideal_count() > 0) {
    ws.Qc_nonideal.setConstant(nan);
    ws.lambda_nonideal.setConstant(nan);
  }
  return s;
}
}  // namespace

Status forward_dynamics(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                        const Eigen::Ref<const VectorXd>& qd, double t) {
  detail::require_same_system(sys, ws, "ukdyn::forward_dynamics");
  require_size(q, sys.coordinate_count(), "q");
  require_size(qd, sys.coordinate_count(), "q_dot");
  ++ws.counters.evaluations;
  ws.status = Status::kOk;
  ws.failed_quantity = "";
  ws.failed_index = -1;
  ws.failed_time = t;
  // inputs
  if (!std::isfinite(t)) {
    return invalidate_results(sys, ws, detail::fail(ws, Status::kNonFiniteInput, "t", -1, t));
  }
  if (Index i = detail::first_non_finite(q); i >= 0) {
    return invalidate_results(sys, ws, detail::fail(ws, Status::kNonFiniteInput, "q", i, t));
  }
  if (Index i = detail::first_non_finite(qd); i >= 0) {
    return invalidate_results(sys, ws, detail::fail(ws, Status::kNonFiniteInput, "q_dot", i, t));
  }
  // M, Q, a → A, b → ideal → non-ideal → checks
  Status s = evaluate_unconstrained(sys, ws, q, qd, t);
  if (s != Status::kOk) return invalidate_results(sys, ws, s);
  s = assemble_constraints(sys, ws, q, qd, t);
  if (s != Status::kOk) return invalidate_results(sys, ws, s);
  s = solve_ideal(sys, ws);
  if (s != Status::kOk) return invalidate_results(sys, ws, s);
  s = apply_nonideal(sys, ws, q, qd, t);
  if (s != Status::kOk) return invalidate_results(sys, ws, s);
  return check_result(sys, ws);
}

}  // namespace ukdyn

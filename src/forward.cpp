// forward_dynamics: the stages of forward.hpp in order.
#include "ukdyn/forward.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "detail.hpp"

namespace ukdyn {

namespace {
void require_size(const VectorXd& v, Index n, const char* what) {
  if (v.size() != n) {
    throw std::invalid_argument(std::string("ukdyn::forward_dynamics: ") + what + " has " +
                                std::to_string(v.size()) + " entries, expected n = " +
                                std::to_string(n));
  }
}
// index of the first non-finite entry, or −1
Index first_non_finite(const VectorXd& v) {
  for (Index i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) return i;
  }
  return -1;
}
}  // namespace

Status forward_dynamics(const System& sys, Workspace& ws, const VectorXd& q, const VectorXd& qd,
                        double t) {
  detail::require_same_system(sys, ws, "ukdyn::forward_dynamics");
  require_size(q, sys.dofs(), "q");
  require_size(qd, sys.dofs(), "q_dot");
  ++ws.counters.evaluations;
  ws.status = Status::kOk;
  ws.failed_quantity = "";
  ws.failed_index = -1;
  ws.failed_time = t;
  // inputs
  if (!std::isfinite(t)) return detail::fail(ws, Status::kNonFiniteInput, "t", -1, t);
  if (Index i = first_non_finite(q); i >= 0) {
    return detail::fail(ws, Status::kNonFiniteInput, "q", i, t);
  }
  if (Index i = first_non_finite(qd); i >= 0) {
    return detail::fail(ws, Status::kNonFiniteInput, "q_dot", i, t);
  }
  // M, Q, a → A, b → ideal → non-ideal → checks
  Status s = evaluate_unconstrained(sys, ws, q, qd, t);
  if (s != Status::kOk) return s;
  s = assemble_constraints(sys, ws, q, qd, t);
  if (s != Status::kOk) return s;
  s = solve_ideal(sys, ws);
  if (s != Status::kOk) return s;
  s = apply_nonideal(sys, ws, q, qd, t);
  if (s != Status::kOk) return s;
  return check_result(sys, ws);
}

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
/// @file core/status.hpp
/// Outcome of an evaluation and the exception that front ends may turn it into.
///
/// ukdyn reports errors in three tiers (see docs/style.md):
///  1. misuse at an entry point (wrong sizes, bad options, a workspace of another system)
///     throws std::invalid_argument whose text names the function, expected and actual value;
///  2. broken internal invariants fire UKDYN_CHECK (always on), which throws std::logic_error;
///  3. numerical conditions met during an evaluation (M not positive definite, inconsistent
///     constraints, NaN) never throw: they set a Status in the workspace; callers who want an
///     exception call throw_if_failed().
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace ukdyn {

/// Result of one evaluation of the fundamental equation.
enum class Status {
  kOk = 0,                   ///< q'' and all forces are valid
  kNonFiniteInput,           ///< q, q', t, M, Q, A, b or C holds NaN or Inf (see Workspace::detail)
  kMassNotSymmetric,         ///< M differs from Mᵀ by more than the symmetry tolerance
  kMassNotPositiveDefinite,  ///< M is not positive semi-definite (a singular, positive
                             ///< semi-definite M is accepted: see kMotionUndetermined)
  kInconsistentConstraints,  ///< A q'' = b has no solution; ‖A q'' − b‖ is in the residuals
  kNonFiniteResult,          ///< the inputs were finite but a result overflowed
  kProjectionFailed,         ///< drift control could not bring the state back onto the
                             ///< constraints (no consistent state near)
  kIntegratorFailure,        ///< the integrator gave up (step size underflow, step limit)
  /// A warning, not a failure: the run reached its end, but its energy balance residual
  /// (RunStatistics::energy_balance) exceeds SimulationOptions::energy_balance_tolerance — energy
  /// was gained or lost that no work channel accounts for. Its name is "energy_balance".
  kEnergyBalance,
  /// M is singular and [M; A] does not have full column rank: the constraints do not determine
  /// the accelerations of some coordinates (describe_status names them). Its name is
  /// "motion not determined".
  kMotionUndetermined,
  /// Not a failure: the run was stopped on request (SimulationOptions::should_stop — Ctrl-C in
  /// `ukdyn run` and in Python) before t_end. The samples up to RunStatistics::t_reached are
  /// kept, the last one at t_reached. Its name is "interrupted".
  kInterrupted,
  /// A controlled run (simulate_controlled, `ukdyn run` of a model with `control:`) stopped
  /// because its controller failed in the run's last step: its inputs and the plant were fine,
  /// the control could not be computed (a requirement that needs a contact to pull, the nominal
  /// model or the law failing: ControlStatus, describe_control_status). RunStatistics::message
  /// says why, after "the controller failed: ". Its name is "control failed".
  kControlFailed,
};

/// Short English name of a status ("ok", "mass matrix not positive definite", …). Cost O(1).
const char* to_string(Status s);

/// Thrown by throw_if_failed() and by front ends when an evaluation did not succeed.
class SolveError : public std::runtime_error {
 public:
  /// @param status the failing status; @param what the full message.
  SolveError(Status status, const std::string& what) : std::runtime_error(what), status_(status) {}
  /// The status that caused the error.
  Status status() const { return status_; }

 private:
  Status status_;
};

/// Thrown by simulate() (and the runs built on it) when the initial state does not satisfy the
/// constraints: a std::invalid_argument (misuse: tier 1), typed so that front ends tell the
/// causes apart without reading the message.
class InconsistentInitialState : public std::invalid_argument {
 public:
  /// Why no consistent initial state was used.
  enum class Cause {
    kNotProjected,      ///< violated, and project_initial is off: projecting may help
    kContradictory,     ///< constraints that no state satisfies together: no projection helps
    kProjectionFailed,  ///< project_initial was on, and no consistent state was found nearby
    /// a unilateral contact's gap is < 0 at the start: projection does not act on a gap, so
    /// project_initial cannot help; the initial state must change
    kPenetrated,
  };
  /// @param cause why; @param what the full message; @param constraints the constraints at
  /// fault, in declaration order (those that contradict each other, or those violated).
  InconsistentInitialState(Cause cause, const std::string& what,
                           std::vector<std::string> constraints = {})
      : std::invalid_argument(what), cause_(cause), constraints_(std::move(constraints)) {}
  /// Why no consistent initial state was used.
  Cause cause() const { return cause_; }
  /// The names of the constraints at fault (front ends point at their declarations): for
  /// kContradictory those that contradict each other, for kPenetrated the penetrated contacts,
  /// else those the state violates. May be
  /// empty (the projection did not converge, with no constraint left violated).
  const std::vector<std::string>& constraints() const { return constraints_; }

 private:
  Cause cause_;
  std::vector<std::string> constraints_;
};

namespace detail {
[[noreturn]] void check_failed(const char* expr, const char* file, int line, const char* msg);
}  // namespace detail

}  // namespace ukdyn

/// Always-on internal invariant check (tier 2): throws std::logic_error naming the expression.
#define UKDYN_CHECK(expr, msg) \
  ((expr) ? (void)0 : ::ukdyn::detail::check_failed(#expr, __FILE__, __LINE__, (msg)))

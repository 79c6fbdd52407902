// SPDX-License-Identifier: BSD-3-Clause
/// @file dynamics/projection.hpp
/// Constraint violations and their removal (drift control), as stages on a Workspace.
///
/// Integrating A q'' = b from a consistent state lets phi and psi drift. project_positions and
/// project_velocities move the state back onto the constraints with the correction of least
/// M-norm (section 5 of docs/theory.md),
///     dq = −M⁻¹ Aᵀ (A M⁻¹ Aᵀ)⁺ phi = −L⁻ᵀ W⁺ phi,
/// iterated (a Gauss–Newton iteration; quadratic when the rows are independent). The same
/// FundamentalDecomposition does the work, so redundant constraints are projected exactly.
/// Each stage overwrites the workspace's evaluation buffers (M, A, b, decomposition): call
/// forward_dynamics again before reading results.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/status.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/workspace.hpp"

namespace ukdyn {

/// Fills ws.phi (position level: phi for holonomic rows, 0 otherwise) and ws.phi_dot (velocity
/// level: d phi/dt = A q' + phi_t for holonomic rows, psi for nonholonomic rows) at (q, q', t).
/// Rows of inactive and of acceleration-form constraints are zero. Cost: one second-order pass
/// per holonomic constraint, one first-order pass per nonholonomic one.
void evaluate_violations(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                         const Eigen::Ref<const VectorXd>& qd, double t);

/// Largest |phi| (holonomic) and |psi| or |phi'| (velocity level) of constraint k in ws.phi,
/// ws.phi_dot (after evaluate_violations). Cost O(rows).
double position_violation(const System& sys, const Workspace& ws, Index k);
/// Largest |psi| or |phi'| of constraint k in ws.phi_dot (after evaluate_violations); see
/// position_violation. Cost O(rows).
double velocity_violation(const System& sys, const Workspace& ws, Index k);

/// Settings of a projection.
struct ProjectionOptions {
  /// Converged when every projected row satisfies |phi_i| <= tolerance · s_i (position) or
  /// |phi'_i| <= tolerance · s'_i (velocity), s_i and s'_i the row's scales in the workspace
  /// (Workspace::phi_scale: the classes of ‖a_i‖ ℓ and ‖a_i‖ v after set_run_scales, as every
  /// simulation sets them, so that the tolerance is relative and unit-free; 10 before, the
  /// constraint's own units), or when the violation
  /// has stalled at the roundoff floor of the rows, below 100 · tolerance (three corrections
  /// in a row that do not halve it: near a singular configuration, or with redundant rows, the
  /// floor can sit just above the tolerance). Must be > 0. The default 1e-13 (relative) is the
  /// former absolute 1e-12 for models in SI units: their ‖a_i‖ ℓ and ‖a_i‖ v (0.04 to 24 over
  /// the examples) are in the class of 10 (10 · the power of 1000 nearest to a scale).
  double tolerance = 1e-13;
  /// Gauss–Newton iterations at most (each one evaluation of M and the constraints).
  int max_iterations = 20;
  /// (K) constraints to project (non-zero entries), or empty for every constraint.
  std::vector<unsigned char> mask;
};

/// Outcome of a projection.
struct ProjectionResult {
  bool converged = false;  ///< the tolerance was met
  int iterations = 0;      ///< corrections applied
  /// max |row| after the last correction (0 if nothing to project; NaN when a non-finite
  /// input, violation or correction stopped the projection)
  double violation = 0.0;
  /// kOk, or why an evaluation failed: M (kMassNotPositiveDefinite, …), kNonFiniteInput for a
  /// non-finite t, q, q' or constraint violation, kNonFiniteResult for a correction that is
  /// not finite. A failing status is also recorded in the workspace (ws.status,
  /// failed_quantity "t", "q", "q_dot", "phi", "phi_dot", failed_index the coordinate or
  /// constraint), so describe_status / throw_if_failed name it ("non-finite input (NaN or Inf)
  /// at t = 0 in q (coordinate 'x')"); converged is then false.
  Status status = Status::kOk;
};

/// Constraints that cannot hold together near a state (find_constraint_conflict).
struct ConstraintConflict {
  bool found = false;           ///< a part of the violation that no correction removes
  bool velocity_level = false;  ///< found in phi' (a drive the constraints cannot follow)
  double residual = 0.0;        ///< |(I − A A⁺) phi| (or phi'): the violation left at least
  /// sigma_min / sigma_max of A when A is nearly singular (< 1e-6, lock-up approached), else 0
  double singular_ratio = 0.0;
  std::vector<std::string> names;  ///< the constraints whose rows carry it, declaration order
};

/// Whether the active constraints contradict each other at (q, q', t), linearized: the part
/// (I − A A⁺) phi of the position violation over the holonomic rows, then of the velocity
/// violation phi' over all rows, outside the range of A (at the workspace's rank threshold),
/// counts when it exceeds the tolerance and 1e-3 of the violation. Then Gauss–Newton (the
/// projection) stalls at a nonzero violation: contradictory constraints (x = 0 and x = 1, or
/// 1 = 0) or a mechanism that locks up (A loses rank while the drive asks for a motion outside
/// its range; or A nearly singular, sigma_min < 1e-6 sigma_max, with m <= n: the velocities
/// it asks for grow like 1/sigma_min as the lock-up is approached). A diagnosis, not a proof: at a
/// singular point of a consistent set the linearized test may also fire, so call it where the
/// projection has failed. Cost: one evaluation of the constraints and a QR of A, O(m n min(m, n)).
ConstraintConflict find_constraint_conflict(const System& sys, Workspace& ws,
                                            const Eigen::Ref<const VectorXd>& q,
                                            const Eigen::Ref<const VectorXd>& qd, double t,
                                            double tolerance);

/// The largest violations a projection would start from (see measure_violations).
struct Violations {
  /// max |phi_i| over the rows project_positions corrects (−1 when none takes part)
  double position = -1.0;
  /// max |phi'_i| (|psi_i|) over the rows project_velocities corrects (−1 when none takes part)
  double velocity = -1.0;
  /// t, q and q' are finite and so is every violation measured; else the entries above are
  /// unspecified and the projections, which report the cause, must run
  bool finite = true;
  /// every row measured is within options.tolerance times its scale (Workspace::phi_scale):
  /// neither projection would change the state
  bool within_tolerance = true;
};
/// The scales of a run (docs/simulation.md, "Scales and tolerances"), from the state it starts
/// at: ℓ = ‖q‖∞ (1 when q = 0); E = max(T + |V|, ‖Q‖∞ ℓ); v the largest of ‖q'‖∞, √(2E/m)
/// (m = 1ᵀ M 1 / n, a Rayleigh quotient of M: the speed the run's energy gives its masses) and
/// ℓ / duration (when duration > 0; ℓ per unit time when all are 0); and with a_i the row of A
/// at (q, q', t) (its constraint's largest row where below 1e-3 of
/// that largest, 1 when all vanish) the violation scales, classes (10 · the power of 1000
/// nearest): ws.phi_scale_i = class(‖a_i‖ ℓ), ws.phi_dot_scale_i = class(‖a_i‖ v) (a row's
/// violation over ‖a_i‖ ℓ is the state's relative distance from the constraint, to first order,
/// in any units and for any factor of the row), ws.length_scale = class(ℓ), ws.speed_scale =
/// class(v), and ws.energy_unit, the power of two nearest to the power of 1000 nearest to E / 10
/// (1 when E is 0 or not finite): the unit in which the simulation integrates the work channels
/// of the energy balance, so their step-size control is relative to the run's energies; and
/// ws.rate_unit = min(1, 10^⌊log10(v / ℓ)⌋), the decade of the run's rate at most 1 (1 when
/// q = 0), which the adaptive integrators' atol on q' is multiplied by.
/// With `angle_coordinates` (SimulationOptions::angle_coordinates: n flags, or empty for every
/// coordinate a length) each column of a_i is weighed by its coordinate's own scale s_j: ℓ_q for
/// a length, 1 for an angle, and phi_scale_i = class(‖a_i ∘ s‖),
/// phi_dot_scale_i = class(‖a_i ∘ s‖ v_q / ℓ_q) (v_q / ℓ_q an angle's speed scale), where ℓ_q
/// and v_q are ℓ and v taken over the length coordinates alone (their ‖q‖∞, ‖q'‖∞ and ‖Q‖∞, and
/// m = 1_Lᵀ M 1_L / n_L; T + |V| the whole system's): the same relative tolerance in any unit of
/// length for rows that mix lengths and angles. When no length coordinate is nonzero (ℓ_q = 0: a
/// robot of revolute joints, a floating base at the origin) every column is weighed as a length, as
/// without flags. Overwrites M, Q, A and b. Allocates (once per run). Cost: one evaluation of M, Q,
/// V and every non-acceleration constraint's rows, O(n³ + m n).
/// @throws std::invalid_argument when q or q' does not have n entries, angle_coordinates has
/// neither 0 nor n entries, or the workspace is of another system.
void set_run_scales(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                    const Eigen::Ref<const VectorXd>& qd, double t, double duration,
                    const std::vector<bool>& angle_coordinates = {});

/// The violations that project_positions and project_velocities would measure first at
/// (q, q', t) with these options, each constraint's violation() evaluated once for both
/// levels (the projections evaluate it once per level and also check the inputs). When both
/// are within options.tolerance and `finite`, neither projection would change the state: the
/// cheap test the simulation makes after every step before projecting. Writes ws.phi and
/// ws.phi_dot on the rows taking part. Cost: one violation pass per constraint, O(n).
/// @throws std::invalid_argument as project_velocities.
Violations measure_violations(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t,
                              const ProjectionOptions& options = {});

/// q ← q − M⁻¹ Aᵀ (A M⁻¹ Aᵀ)⁺ phi(q, t) over the holonomic constraints (active at t and in the
/// mask), iterated until converged. Cost per iteration O(n³/3 + m n² + m² n) and the constraints'.
/// @throws std::invalid_argument when q does not have n entries, the workspace is of another
/// system or empty (moved from), or the options are out of range. A non-finite t or q is not
/// projected: status kNonFiniteInput (see ProjectionResult), q unchanged.
ProjectionResult project_positions(const System& sys, Workspace& ws, VectorXd& q, double t,
                                   const ProjectionOptions& options = {});

/// q' ← q' − M⁻¹ Aᵀ (A M⁻¹ Aᵀ)⁺ phi'(q, q', t) over the holonomic and nonholonomic
/// constraints (active at t and in the mask), q fixed; iterated, since psi may be nonlinear in
/// q'. Cost as project_positions. Throws and reports non-finite inputs (t, q, q') as
/// project_positions does.
ProjectionResult project_velocities(const System& sys, Workspace& ws,
                                    const Eigen::Ref<const VectorXd>& q, VectorXd& qd, double t,
                                    const ProjectionOptions& options = {});

/// Removes from a perturbation (dq, dq') of the state (q, q') at t the components that
/// project_positions and project_velocities at (q, t) remove, to first order:
///     dq  ← dq  − M⁻¹ Aₚᵀ (Aₚ M⁻¹ Aₚᵀ)⁺ Aₚ dq,    Aₚ the rows of project_positions,
///     dq' ← dq' − M⁻¹ Aᵥᵀ (Aᵥ M⁻¹ Aᵥᵀ)⁺ Aᵥ dq',   Aᵥ the rows of project_velocities,
/// both M-orthogonal projections onto the null space of the rows (the same decomposition as a
/// projection, so redundant rows and a singular M are handled as there). What is left is the
/// part of the perturbation that a projection after it keeps: the integrators measure a step's
/// local error that way when drift control projects (docs/simulation.md, "Singular
/// configurations"). Overwrites the workspace's evaluation buffers as a projection does.
/// Cost: one evaluation of M and of the rows' Jacobians, one decomposition (two when
/// nonholonomic rows take part), O(n m) per vector. Allocates nothing.
Status remove_normal_components(const System& sys, Workspace& ws,
                                const Eigen::Ref<const VectorXd>& q,
                                const Eigen::Ref<const VectorXd>& qd, double t,
                                const ProjectionOptions& options, Eigen::Ref<VectorXd> dq,
                                Eigen::Ref<VectorXd> dqd);

}  // namespace ukdyn

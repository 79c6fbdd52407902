// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/linearize.hpp
/// Linear models of a constrained system on its constraint manifold, and its equilibria and
/// steady motions (issue #32; the theory is in docs/linearize.md).
///
/// Glossary (docs/linearize.md uses the same symbols):
///  - Φ(q, t) = 0     the active holonomic rows; Φ_q their Jacobian (rows of A)
///  - ψ(q, q', t) = 0 the active nonholonomic rows; ψ_q' their Jacobian (rows of A)
///  - J_v = [Φ_q; ψ_q']  the velocity-constraint Jacobian
///  - I_p, D_p        independent / dependent positions: Φ(q, t) = 0 fixes q_Dp given q_Ip
///  - I_v, D_v        independent / dependent velocities (D_v ⊇ D_p): J_v q' + … = 0 fixes q'_Dv
///  - x = (q_Ip, q'_Iv)  the state of the linear model, dimension (n − r_h) + (n − r_h − r_n)
///  - x' = f(x, u), y = g(x, u); A = ∂f/∂x, B = ∂f/∂u, C = ∂g/∂x, D = ∂g/∂u at (x₀, u₀ = 0)
///
/// The derivatives are Ridders' extrapolated central differences (Numerical Recipes §5.7): a
/// Richardson table of central differences at shrinking steps whose best entry, and the
/// difference to its neighbours as the error estimate, are kept per matrix entry
/// (LinearModel::A_error …); inputs that are generalized forces enter exactly (the
/// fundamental equation is affine in Q).
#pragma once

#include <complex>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/system.hpp"
#include "ukdyn/core/types.hpp"
#include "ukdyn/dynamics/workspace.hpp"

namespace ukdyn {

/// A state (q, q', t) on the constraint manifold about which to linearize; it must satisfy the
/// holonomic and nonholonomic constraints (checked: LinearizeOptions::manifold_tolerance).
struct OperatingPoint {
  VectorXd q;      ///< positions (n)
  VectorXd qd;     ///< velocities (n)
  double t = 0.0;  ///< time
};

/// `p` moved onto the constraint manifold: project_positions, then project_velocities (the
/// M-weighted least corrections; dynamics/projection.hpp), at p.t. For a state that is meant as
/// a guess (a model file's `initial: project: true`, `ukdyn linearize --project`).
/// @throws SolveError (kProjectionFailed) naming the level and the violation left when a
/// projection does not converge; std::invalid_argument on sizes. Cost: the projections'.
OperatingPoint project_onto_manifold(const System& sys, const OperatingPoint& p);

/// What an input of the linear model is.
enum class InputKind {
  kForce,      ///< a generalized force u added to Q_j along coordinate j
  kParameter,  ///< a parameter p = p₀ + u of a family of systems (e.g. a model file's)
};

/// One input u_k of the linear model (column k of B and D).
struct LinearInput {
  std::string name;                    ///< label (the coordinate's or the parameter's name)
  InputKind kind = InputKind::kForce;  ///< a generalized force or a parameter
  Index coordinate = -1;               ///< kForce: the coordinate j whose Q_j receives u
  /// kParameter: the system at parameter value p (called with p₀ + u, u small); must describe
  /// the same coordinates and constraints as the nominal system
  std::function<System(double p)> family;
  double nominal = 0.0;  ///< kParameter: p₀
};

/// A generalized force along the coordinate called `coordinate`.
/// @throws std::invalid_argument when there is no such coordinate. Cost O(n).
LinearInput force_input(const System& sys, const std::string& coordinate);

/// A parameter of a model file: the family loads the model text with `name` overridden (the
/// other overrides kept). Each evaluation parses the model (milliseconds).
/// @throws ModelError when the text does not load; std::invalid_argument when it has no
/// parameter `name`.
LinearInput model_parameter_input(const std::string& text, const std::string& file,
                                  const std::map<std::string, double>& overrides,
                                  const std::string& name);

struct Model;

/// The inputs called `names` of a model file: a coordinate's name is a generalized force along
/// it (force_input), a parameter's name the parameter (model_parameter_input, from `text`, the
/// model's own, with its parameters' values kept). `who` prefixes the messages.
/// @throws std::invalid_argument naming an input that is neither. Cost: one parse per parameter.
std::vector<LinearInput> model_inputs(const Model& model, const std::string& text,
                                      const std::vector<std::string>& names, const char* who);

/// One output y_k of the linear model (row k of C and D): a coordinate, its rate, or a function
/// of the state (a model file's output expression).
struct LinearOutput {
  std::string name;       ///< label: the coordinate's name, with "_dot" for its rate
  Index coordinate = -1;  ///< which coordinate (unused when `expression` is set)
  bool rate = false;      ///< q'_j instead of q_j
  /// y = expression(q, q', t) instead of a coordinate, when set (e.g. model_outputs()); it is
  /// evaluated at the completed state (q, q') on the manifold.
  std::function<double(const VectorXd& q, const VectorXd& qd, double t)> expression;
};

/// The output called `name`: a coordinate's name (its position) or the name followed by "_dot"
/// (its rate), as model-file expressions write them. @throws std::invalid_argument naming the
/// coordinates when there is none. Cost O(n).
LinearOutput coordinate_output(const System& sys, const std::string& name);

/// Settings of linearize().
struct LinearizeOptions {
  /// Independent positions by coordinate name (n − r_h of them); empty: chosen by the
  /// column-pivoted QR of Φ_q (the best-conditioned dependent set).
  std::vector<std::string> independent_positions;
  /// Independent velocities by name (n − r_h − r_n of them, among the independent positions);
  /// empty: chosen by a column-pivoted QR of J_v with D_p eliminated first.
  std::vector<std::string> independent_velocities;
  /// Rank threshold of the QR decisions: a pivot |R_kk| <= rank_threshold |R_00| counts as
  /// zero. Must lie in (0, 1).
  double rank_threshold = 1e-9;
  /// A kept pivot below singular_threshold |R_00| (or a named dependent set whose block of the
  /// Jacobian has σ_min / σ_max below it) is a singular configuration: linearize throws
  /// rather than return a matrix that depends on roundoff. Must lie in [rank_threshold, 1).
  double singular_threshold = 1e-6;
  /// Ridders' first step for state entry k: initial_step · σ_k, σ_k its own scale — |q_j| (or
  /// the model's scale min(ℓ̃, λ_j) where |q_j| is below 1e-3 of that; never above the
  /// coordinate's natural scale λ_j; ℓ̃ = ‖q‖∞ without coordinates below 1e-3 λ_j) for a
  /// position, |q'_j| (or the coordinate's scale at the run's rate) for a velocity, |p₀| (1 when
  /// p₀ = 0) for a parameter input — never an absolute number (docs/linearize.md, "Steps in the
  /// model's own scale"; `ukdyn linearize --initial-step`, `initial_step=` in Python). Must be
  /// > 0.
  double initial_step = 0.1;
  /// Ridders' table size (levels of step shrinking by `step_ratio`). Must be >= 2.
  int table_size = 10;
  double step_ratio = 1.4;  ///< the step shrinks by this per level; must be > 1
  /// The operating point must satisfy |Φ|, |ψ| (and |Φ'|) <= manifold_tolerance · max(1, ‖q‖,
  /// ‖q'‖). Must be > 0.
  double manifold_tolerance = 1e-8;
  /// The states to keep, by name (LinearModel::state_names, e.g. {"phi", "delta", "phi_dot",
  /// "delta_dot"}); empty: all. The kept states must form a subsystem the others do not act on
  /// (A's entries from a dropped state into a kept row zero to within their error estimate:
  /// cyclic coordinates, the rates they are ignorable in); then the kept block's eigenvalues are
  /// eigenvalues of the whole A. A bicycle's lean and steer about its straight run, without
  /// its position, heading and wheel angles. B keeps the kept rows, C the kept columns.
  std::vector<std::string> states;
  /// The solver's settings for the forward dynamics (the dense engine is always used).
  SolverOptions solver;
};

/// The linear model x' = A x + B u, y = C x + D u about an operating point, in deviations from
/// it, with each entry's error estimate.
struct LinearModel {
  MatrixXd A;        ///< ∂f/∂x (s × s), s = state_names.size()
  MatrixXd B;        ///< ∂f/∂u (s × inputs)
  MatrixXd C;        ///< ∂g/∂x (outputs × s)
  MatrixXd D;        ///< ∂g/∂u (outputs × inputs)
  MatrixXd A_error;  ///< Ridders' error estimate of each entry of A (same size); 0 where exact
  MatrixXd B_error;  ///< … of B
  MatrixXd C_error;  ///< … of C
  MatrixXd D_error;  ///< … of D
  /// The state's names: the independent positions' coordinate names, then the independent
  /// velocities' with "_dot" (only those of LinearizeOptions::states when it is given).
  std::vector<std::string> state_names;
  std::vector<std::string> input_names;       ///< the inputs' names (columns of B, D)
  std::vector<std::string> output_names;      ///< the outputs' names (rows of C, D)
  std::vector<Index> independent_positions;   ///< I_p, coordinate indices (increasing)
  std::vector<Index> independent_velocities;  ///< I_v, coordinate indices (increasing)
  VectorXd x0;                                ///< the operating state (q_Ip, q'_Iv)
  /// f(x₀, 0): zero at an equilibrium or steady motion; otherwise the model is the first-order
  /// expansion about a moving point (x' = f₀ + A δx + B u).
  VectorXd f0;
  /// σ_min / σ_max estimate of the dependent columns of J_v (1 without constraints): how far
  /// the chosen coordinates are from a singular configuration.
  double chart_condition = 1.0;
  /// The unilateral contacts open at the point, left out of the model (no rows, no force); the
  /// closed ones are held as bilateral constraints: the model is that of the point's contact
  /// mode, valid while no gap closes and no held contact would pull (docs/linearize.md,
  /// "Contacts").
  std::vector<std::string> open_contacts;
  Eigen::VectorXcd eigenvalues;   ///< of A (s), in the order of Eigen's EigenSolver
  Eigen::MatrixXcd eigenvectors;  ///< column k: the mode of eigenvalue k; rows: state_names
  /// The mode of eigenvalue k as (state name, component) pairs, largest magnitude first.
  std::vector<std::pair<std::string, std::complex<double>>> mode(Index k) const;
};

/// Linearizes `sys` about `at` in minimal coordinates of its constraint manifold: x = (q_Ip,
/// q'_Iv); dependent positions by Newton on Φ(q, t) = 0, dependent velocities by Newton on the
/// velocity constraints; accelerations from forward_dynamics (the fundamental equation).
/// A, C and parameter columns by Ridders' extrapolation with an error estimate per entry;
/// force columns of B exact (q'' is affine in Q: ∂q''/∂Q = N (Nᵀ M N)⁻¹ Nᵀ, N a basis of
/// null(A)).
/// @throws std::invalid_argument on misuse (sizes, names, options, a point off the manifold,
/// an acceleration-form constraint, force inputs with non-ideal forces where constraints act,
/// at a singular configuration — the message names the constraint rows or coordinates).
/// @throws SolveError when the dynamics cannot be evaluated near the point, or an entry's
/// Ridders table does not settle (a kink: friction at rest is named).
/// Cost: O(s · table_size) evaluations of the forward dynamics and the chart (each O(n³)), and
/// O(n) probes of M and A per coordinate for the steps' scales.
LinearModel linearize(const System& sys, const OperatingPoint& at,
                      const std::vector<LinearInput>& inputs = {},
                      const std::vector<LinearOutput>& outputs = {},
                      const LinearizeOptions& options = {});

/// Time-varying linearization along a trajectory (for tracking-error analysis): the linear
/// model δx' = A(t) δx + B(t) u, δy = C(t) δx + D(t) u of the deviations from the motion through
/// `path` (points on the manifold, e.g. a simulation's samples). One chart for all points: the
/// independent coordinates of `options`, or those chosen automatically at the first point, so
/// that δx means the same at every point (f0 is the motion's own x'). Each point as linearize().
/// @throws std::invalid_argument as linearize(), naming the point (index and t) — also where the
/// first point's coordinates become singular along the path. Cost: linearize() per point.
std::vector<LinearModel> linearize_along(const System& sys, const std::vector<OperatingPoint>& path,
                                         const std::vector<LinearInput>& inputs = {},
                                         const std::vector<LinearOutput>& outputs = {},
                                         const LinearizeOptions& options = {});

/// Settings of find_equilibrium().
struct EquilibriumOptions {
  /// The unknowns: coordinate names (their position) or names with "_dot" (their rate). Empty:
  /// every independent position (a static equilibrium when the guess is at rest, a relative
  /// equilibrium with the guess's velocities kept otherwise).
  std::vector<std::string> unknowns;
  /// Converged when every reduced acceleration q''_j (j in I_v) is <= tolerance times its
  /// coordinate's acceleration unit: its model scale min(ℓ̃, λ_j) at the guess's rate² (v / ℓ̃)²
  /// (docs/linearize.md, "Equilibria and steady motions") — relative, so that a model gives
  /// the same equilibrium in any units. Must be > 0.
  double tolerance = 1e-10;
  int max_iterations = 50;  ///< Newton steps; must be >= 1
  /// Chart and derivative settings (independent coordinates, thresholds).
  LinearizeOptions linearize;
};

/// An equilibrium or steady motion found by find_equilibrium().
struct Equilibrium {
  OperatingPoint point;  ///< on the manifold
  double residual = 0;   ///< ‖q''_Iv‖ there, in the model's units
  int iterations = 0;    ///< Newton steps taken
};

/// Thrown by find_equilibrium when Newton does not converge: what() gives the residual, the
/// coordinate with the largest reduced acceleration and the last iterate.
class EquilibriumError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Solves q''_Iv(x) = 0 for the unknowns (Gauss–Newton with a backtracking line search on
/// ‖q''_Iv‖², Jacobian by Ridders' extrapolation) from `guess`, the other entries of the state
/// held at the guess's values (e.g. the spin of a top, the heading rate of a turning disk).
/// @throws std::invalid_argument on misuse (names, sizes; as linearize).
/// @throws EquilibriumError when none is found. Cost: per step one Jacobian (O(unknowns ·
/// table_size) evaluations) and the line search.
Equilibrium find_equilibrium(const System& sys, const OperatingPoint& guess,
                             const EquilibriumOptions& options = {});

}  // namespace ukdyn

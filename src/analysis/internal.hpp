// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/internal.hpp
/// The stages of linearize() and find_equilibrium() (include/ukdyn/analysis/linearize.hpp):
///   1. choose_coordinates   I_p, D_p, I_v, D_v from the constraint Jacobians
///   analysis/coordinate_partition.cpp
///   2. ReducedDynamics      x → (q, q') on the manifold (Newton) → f(x), g(x)
///   analysis/reduced_dynamics.cpp
///   3. ridders_jacobian     ∂F/∂z with an error estimate per entry    analysis/ridders.cpp
///   4. linearize            assembles A, B, C, D and the modes       analysis/linearize.cpp
///   5. keep_states          the subsystem of LinearizeOptions::states analysis/state_subset.cpp
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/analysis/linearize.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/workspace.hpp"

namespace ukdyn::analysis {

/// The split of the coordinates into independent and dependent ones at a point.
struct Partition {
  std::vector<Index> ip, dp;  ///< independent / dependent positions (increasing)
  std::vector<Index> iv, dv;  ///< independent / dependent velocities (increasing); dv ⊇ dp
  std::vector<Index> holonomic_rows;  ///< rows of A of the active holonomic constraints
  std::vector<Index> velocity_rows;   ///< rows of the active holonomic and nonholonomic ones
  double condition = 1.0;  ///< σ_min/σ_max estimate of J_v's dependent columns (1 if none)
};

/// The contact mode of a point, held by every evaluation with `ws`: the unilateral constraints
/// whose gap is open at `at` are released (ws.activity_override 0: no rows, no force); the
/// closed ones act as bilateral constraints (docs/linearize.md, "Contacts"). Returns the open
/// ones' names. O(contacts).
std::vector<std::string> hold_contact_mode(const System& sys, Workspace& ws,
                                           const OperatingPoint& at);

/// The workspace options linearize uses: `solver` with the dense engine (M and A are read).
SolverOptions dense_options(const SolverOptions& solver);

/// Stage 1: evaluates A at `at` (ws, dense engine), checks that `at` lies on the manifold
/// (unless check_manifold is false: a guess), and chooses the partition (automatically, or from
/// the names in `options`). `who` prefixes the messages. @throws std::invalid_argument (see
/// linearize()).
Partition choose_coordinates(const System& sys, Workspace& ws, const OperatingPoint& at,
                             const LinearizeOptions& options, const char* who,
                             bool check_manifold = true);

/// Stage 2: the reduced dynamics of one system (the nominal one, or one of a parameter
/// family) in the chart of a partition based at a point.
class ReducedDynamics {
 public:
  ReducedDynamics(const System& sys, const Partition& p, const OperatingPoint& base,
                  const LinearizeOptions& options);
  /// Completes x = (q_Ip, q'_Iv) to (q, q') on the manifold: Newton on Φ for q_Dp, then on the
  /// velocity constraints for q'_Dv, each started from the base point. False when a Newton
  /// iteration does not converge (why() says where).
  bool complete(const Eigen::Ref<const VectorXd>& x);
  /// complete(x), then F = (f(x), g(x)): f = (q'_Ip, q''_Iv) by forward_dynamics, g the
  /// outputs. False on failure (why()).
  bool evaluate(const Eigen::Ref<const VectorXd>& x, const std::vector<LinearOutput>& outputs,
                Eigen::Ref<VectorXd> F);
  /// x of the base point.
  VectorXd base_state() const;
  /// The scale σ_k of each entry of x for Ridders' first step h_k = initial_step · σ_k
  /// (docs/linearize.md, "Steps in the model's own scale"). A position q_j takes |q_j|, or the
  /// model's ℓ̃ where |q_j| is below 1e-3 of that, and never more than its natural scale λ_j
  /// (natural_scale: an angle at 0 beside lengths of 500 mm is not stepped by 50 rad); ℓ̃ =
  /// ‖q‖∞ over the coordinates not at 0 or its roundoff (|q_j| >= 1e-3 λ_j), 1 when every one is
  /// (an equilibrium's q = 1e-14 rad is q = 0, not a length of 1e-14). A velocity q'_j takes
  /// |q'_j|, or σ_qj v / ℓ̃ where |q'_j| is below 1e-3 of that, v the speed a run from the base
  /// point takes (detail::run_length_speed: ‖q'‖∞ or √(2E / m)). Sets rate() = v / ℓ̃. Cost: one
  /// unconstrained evaluation, and a few evaluations of M and A per coordinate (natural_scale),
  /// O(n⁴).
  VectorXd state_scales();
  /// The run's rate v / ℓ̃ (1 / time) after state_scales(): the acceleration scale of a
  /// velocity state of scale σ is σ · rate().
  double rate() const { return rate_; }
  /// The model's scale of each coordinate (n) after state_scales(): min(ℓ̃, λ_j), what a
  /// coordinate at 0 is stepped by; its acceleration unit is model_scales() · rate()².
  const VectorXd& model_scales() const { return model_scales_; }
  /// The model's scale of each state after state_scales(): model_scales() of a position,
  /// model_scales() · rate() of a velocity (s).
  VectorXd model_state_scales() const;
  /// λ_j: ten times the least step p (found by factors of 4 from `start`; of 1024 while the
  /// change is below 1e-6, up to 1e24 start) along q_j that
  /// changes the model by 1 %: M's entries relative to √(M_aa M_bb), or a row a_i of the
  /// constraint Jacobian as ‖Δa_i D‖ over its constraint's largest ‖a_i D‖ at the base (all
  /// rows' largest where the constraint vanishes there: a fold), D = diag(M)^(-1/2) (both
  /// independent of the coordinates' units); infinite when neither changes (a cyclic
  /// coordinate). A Cartesian pendulum's x: 0.1 L; an angle of a loop: about 0.1 rad.
  double natural_scale(Index j, double start);
  const VectorXd& q() const { return q_; }         ///< after complete(): positions (n)
  const VectorXd& qd() const { return qd_; }       ///< after complete(): velocities (n)
  Workspace& workspace() { return ws_; }           ///< after evaluate(): the forward dynamics
  const std::string& why() const { return why_; }  ///< the last failure
  Index state_size() const { return Index(p_.ip.size() + p_.iv.size()); }  ///< s

 private:
  bool newton(bool velocity);
  // the model's change along q_j over a step p (natural_scale), infinite where M or A cannot
  // be evaluated
  double model_change(Index j, double p);

  const System& sys_;
  const Partition& p_;
  OperatingPoint base_;
  Workspace ws_;
  VectorXd q_, qd_;
  std::string why_;
  double rate_ = 1.0;
  VectorXd model_scales_;     // (n) state_scales()
  MatrixXd base_M_, base_A_;  // M and A at the base point (model_change)
  VectorXd D_;                // diag(M)^(-1/2) at the base point, 0 where M_jj <= 0
  VectorXd row_size_;         // (rows of A) what a row's change is measured against
};

/// Settings of ridders_jacobian (from LinearizeOptions).
struct RiddersOptions {
  int table_size = 10;
  double step_ratio = 1.4;
  double safe = 2.0;  ///< stop a column's entry once the error grows by this factor
};

/// A function R^k → R^p for ridders_jacobian: writes F(z) (p) and returns false when it cannot
/// be evaluated at z.
using VectorFunction =
    std::function<bool(const Eigen::Ref<const VectorXd>& z, Eigen::Ref<VectorXd> F)>;

/// Stage 3: J = ∂F/∂z at z0 by Ridders' method, column j from the first step h0(j); err(i, j)
/// is the estimate of |J(i, j) − exact|: the larger of the table's last improvement at the
/// chosen entry and the roundoff floor 4 ε |F| / h, plus 16 ε |J|. A failed evaluation at the first
/// level quarters the step (up to 3 times), at a later one ends the column's table. Returns false
/// (message in `why`) when a column cannot be started. Cost: up to 2 · table_size
/// evaluations per column.
bool ridders_jacobian(const VectorFunction& F, const Eigen::Ref<const VectorXd>& z0,
                      const Eigen::Ref<const VectorXd>& h0, Index p, const RiddersOptions& o,
                      MatrixXd& J, MatrixXd& err, std::string& why);

/// Stage 5: restricts `lm` (A, B, C and their errors, x0, f0, state_names) to the states called
/// `names`, in that order. @throws std::invalid_argument (prefixed `who`) naming a state that
/// does not exist or is named twice, or a dropped state whose column of A enters a kept row
/// beyond its error estimate. Cost O(s²).
void keep_states(LinearModel& lm, const std::vector<std::string>& names, const char* who);

/// Coordinate index of `name`, or of `name` without "_dot" with rate = true. @throws
/// std::invalid_argument naming `who` and the coordinates.
Index coordinate_of(const System& sys, const std::string& name, bool& rate, const char* who);

}  // namespace ukdyn::analysis

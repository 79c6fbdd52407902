// SPDX-License-Identifier: BSD-3-Clause
/// @file control/control.hpp
/// Exact tracking control from the fundamental equation (section 7 of
/// docs/theory.md; docs/control.md has the derivations).
///
/// A control engineer states what a mechanical system must do as *requirements*: constraints
/// phi(q,t) = 0 or psi(q,q',t) = 0 (any Constraint of core/constraint.hpp / core/autodiff.hpp),
/// each with chosen error dynamics, so that an initial error e = phi decays as
///     e'' + 2 zeta omega e' + omega² e = 0     (holonomic requirement)
///     e'  + k e                       = 0     (nonholonomic requirement).
/// ukdyn returns in closed form the control force Q_c that makes the *physically constrained*
/// plant meet them, with no linearization. In acceleration form the requirements read
/// A_r q'' = b_r (b_r includes the error dynamics, Constraint::stabilize).
///
/// The description/workspace split of System/Workspace: a Controller (immutable: the nominal
/// plant model, the requirements, the law, the actuation, the robust settings) and a
/// ControlWorkspace (every buffer, sized once; evaluations do not allocate). The evaluation is
/// a pipeline of stages, one file each in src/:
///
///   1. evaluate_model         the nominal model's physically constrained motion a_p,
///                             its M = L Lᵀ and physical reaction control/nominal_motion.cpp
///   2. assemble_requirements  A_r, b_r, e = b_r − A_r a_p               control/requirements.cpp
///   3. solve_law              X = A_r P, the law's decomposition, Qc_nominal,
///                             per-row residuals (which requirements are met)  control/laws.cpp
///   4. apply_robust           sliding variable, boundary layer, Qc_robust  control/robust_term.cpp
///   5. check_control          Qc_control, q'', physical reaction, power  control/effect_check.cpp
///
/// Glossary (beyond core/types.hpp):
///   A_p, b_p      the plant model's own (physical) constraints; W_p = A_p L⁻ᵀ
///   a_p (n)       acceleration of the physically constrained model without control (eq. 9)
///   P (n×n)       its compliance: a force F changes q'' by P F,
///                 P = M⁻¹ − M⁻¹ A_pᵀ G_p⁺ A_p M⁻¹ = L⁻ᵀ (I − W_p⁺ W_p) L⁻¹   (P = M⁻¹ if no A_p)
///   A_r, b_r (m_r) requirements in acceleration form, b_r with the error dynamics
///   e (m_r)       error signal of the requirements, e = b_r − A_r a_p
///   X (m_r×n)     X = A_r P: a control force Q_c meets the requirements iff X Q_c = e
///   S (n×k)       actuation: Q_c = S u, u (k) the actuator forces (S = I: every coordinate)
///   N (n×n)       weight of the weighted law: cost Q_cᵀ N Q_c
///   Qc_nominal    the law's force for e;  Qc_robust  the robust term;  Qc_control  their sum
///   s, kappa, v   robust term: sliding variable, gain, requirement-space acceleration
///
/// @code
///   ukdyn::Controller ctrl =
///       ukdyn::ControllerBuilder(model)   // a System: M, Q and the physical constraints
///           .require(ukdyn::holonomic("track", 1, [](const auto& q, const auto& t, auto& e) {
///                      using std::sin;
///                      e[0] = q[0] - sin(t);
///                    }),
///                    ukdyn::ErrorDynamics::second_order(/*omega=*/2.0, /*zeta=*/1.0))
///           .build();
///   ukdyn::ControlWorkspace cws(ctrl);
///   ukdyn::compute_control(ctrl, cws, q, qd, t);  // cws.Qc_control, cws.residual, cws.status
///   auto run = ukdyn::simulate_controlled(ctrl, plant, q0, qd0, options);
///   ukdyn::write_csv(run, "controlled.csv");     // + error.*, Qc_control.*, control_power, …
/// @endcode
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/core/types.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/io/trajectory_files.hpp"
#include "ukdyn/linalg/decomposition.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {

// ---------------------------------------------------------------------------------------------
// requirements

/// Prescribed error dynamics of a requirement, in the Baumgarte gains of Constraint::stabilize:
///   holonomic    e'' + 2 alpha e' + beta² e = 0   (alpha = zeta omega, beta = omega)
///   nonholonomic e'  + alpha e          = 0   (alpha = k)
/// where e is the requirement's value (phi, resp. psi) along the motion.
struct ErrorDynamics {
  /// The order of the dynamics: none (the requirement is imposed as declared, so an initial
  /// error is not removed), first (nonholonomic) or second (holonomic).
  enum class Order { kNone, kFirst, kSecond };
  Order order = Order::kNone;  ///< see Order
  double alpha = 0.0;          ///< damping gain (1/s)
  double beta = 0.0;           ///< stiffness gain (1/s), second order only

  /// e'' + 2 zeta omega e' + omega² e = 0. @throws std::invalid_argument unless omega > 0 and
  /// zeta > 0. Cost O(1).
  static ErrorDynamics second_order(double omega, double zeta = 1.0);
  /// e'' + 2 alpha e' + beta² e = 0 by its gains. @throws std::invalid_argument unless
  /// alpha >= 0 and beta >= 0. Cost O(1).
  static ErrorDynamics gains(double alpha, double beta);
  /// e' + rate e = 0. @throws std::invalid_argument unless rate > 0. Cost O(1).
  static ErrorDynamics first_order(double rate);
  /// No error dynamics: e'' = 0 (holonomic) or e' = 0 (nonholonomic) — exact tracking from a
  /// consistent initial state, no correction of an initial error. Cost O(1).
  static ErrorDynamics none() { return {}; }
};

/// The requirement `c` with error dynamics `d`: c.stabilize(d.alpha, d.beta).
/// @throws std::invalid_argument naming the requirement when the order does not fit its kind:
/// a holonomic requirement takes second-order dynamics, a nonholonomic one first-order
/// dynamics, an acceleration-form one none. Cost O(1).
Constraint requirement(Constraint c, const ErrorDynamics& d);

// ---------------------------------------------------------------------------------------------
// the description

/// Which force, among all that meet the requirements, the controller applies.
enum class ControlLaw {
  /// Gauss's choice, eq. (25): Q_c = M^{1/2} B⁺ e with B = A M^{−1/2} (no physical
  /// constraints), the least Q_cᵀ M⁻¹ Q_c ("nature's choice": the constraint force that would
  /// make the requirements hold if they were ideal constraints). Computed as L W⁺ e.
  kGauss,
  /// The least Q_cᵀ N Q_c: Q_c = N^{−1/2} (X N^{−1/2})⁺ e with N = R Rᵀ (Cholesky), computed
  /// as R⁻ᵀ (X R⁻ᵀ)⁺ e. N = M⁻¹ gives kGauss (and N = M does not).
  kWeighted,
};

/// Short name ("gauss", "weighted"). Cost O(1).
const char* to_string(ControlLaw law);

/// Writes the weight N(q, q', t) (n × n, symmetric positive definite; the lower triangle is
/// read). Must not allocate.
using WeightFn =
    std::function<void(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, Eigen::Ref<MatrixXd> N)>;

/// The robust term for a plant that differs from the nominal model (docs/control.md derives it).
/// The controller assumes that the nominal force leaves each requirement row i with the
/// residual eta_i = (A_r q'' − b_r)_i of the real plant bounded by
///     |eta_i| <= bound + relative_bound · |b_r,i|,
/// and that a requirement-space acceleration v asked of the nominal model produces (I + Delta) v
/// on the real plant with ‖Delta‖_∞ <= gain_uncertainty. For a pure mass error (real M =
/// nominal M / (1 + mu), forces known exactly, no physical constraints) eta = mu b_r and
/// Delta = mu I: relative_bound = gain_uncertainty = |mu|, bound = 0.
/// The term is v_i = −kappa_i sat(s_i / boundary_layer) with the sliding variable
///     s_i = e_i' + alpha e_i   (holonomic row),    s_i = e_i   (nonholonomic row),
/// kappa_i = rho_i + delta rho_max / (1 − delta), rho_i = bound + relative_bound |b_r,i|,
/// applied by the same law as the nominal force. It guarantees, per requirement row,
///     |e_i(t)| <= sqrt(V_i(t) / c_i),   V_i' = −gamma_i V_i + kappa_i(t) boundary_layer / 2,
/// V_i(0) the row's Lyapunov function at the start, c_i = alpha² + beta² (holonomic) or 1, and
/// gamma_i = 2 alpha (1 − alpha / sqrt(alpha² + beta²)) (holonomic) or 2 alpha (nonholonomic):
/// the bound that simulate_controlled integrates and reports (ControlledTrajectory::error_bound).
/// Needs every requirement to have error dynamics with alpha > 0 (and beta > 0 when holonomic).
struct RobustControl {
  double bound = 0.0;             ///< rho_0 >= 0, in the requirement's acceleration units
  double relative_bound = 0.0;    ///< rho_1 >= 0, dimensionless
  double gain_uncertainty = 0.0;  ///< delta in [0, 1)
  double boundary_layer = 0.0;    ///< epsilon > 0, in the units of s (requirement velocity)
};

/// Settings of a controller.
struct ControlOptions {
  /// Solver of the nominal model's physical constraints and of the law's decomposition (its
  /// rank threshold). Must use Algorithm::kDefault.
  SolverOptions solver;
  /// Requirement row i counts as met when |(X Q_c − e)_i| <= feasibility_tolerance ·
  /// (‖X_i‖ ‖Q_c‖ + |e_i|) (in the law's own scaling, see ControlWorkspace::residual). > 0.
  double feasibility_tolerance = 1e-8;
};

/// An immutable controller: the nominal model of the plant (a System, whose constraints are the
/// *physical* constraints — joints, rolling — that the control must respect), the requirements,
/// the law, the actuated coordinates, the weight and the robust settings. Built by
/// ControllerBuilder; cheap to copy (Systems and callables are shared).
///
/// How control and physical constraints combine (docs/control.md): the control acts on the
/// physically constrained model, whose acceleration under a force F is a_p + P F, so F meets the
/// requirements iff X F = e with X = A_r P. The law picks, among all such F, the one of least
/// cost; the physical constraints then react to it as they do to any applied force (reported
/// apart, ControlWorkspace::Qc_physical). With the Gauss law the chosen force satisfies
/// A_p M⁻¹ Q_c = 0: it loads no physical constraint, so the physical reaction is that of the
/// uncontrolled plant, and Qc_physical + Q_c equals the constraint force of the fundamental
/// equation with the physical constraints and the requirements stacked.
class Controller {
 public:
  Index coordinate_count() const { return n_; }    ///< n, coordinates of the plant
  Index requirement_rows() const { return m_r_; }  ///< m_r, rows of all requirements
  Index requirement_count() const { return requirements_.constraint_count(); }  ///< K_r
  Index actuators() const { return k_; }  ///< k, columns of S (n if fully actuated)
  bool fully_actuated() const { return fully_actuated_; }  ///< no actuation given: S = I
  /// The actuation matrix S (n × k), the identity when fully actuated.
  const MatrixXd& actuation() const { return S_; }
  /// The actuated coordinates when given by actuated() (empty otherwise).
  const std::vector<Index>& actuated_coordinates() const { return actuated_; }

  /// The nominal model of the plant (the parameters the controller believes).
  const System& model() const { return model_; }
  /// The requirements, as a System over the same coordinates whose constraints they are, so
  /// that the constraint stage (assemble_constraints, evaluate_violations) evaluates them; only
  /// its constraints are read (its mass matrix is the identity and is never evaluated).
  const System& requirements() const { return requirements_; }
  /// The requirement with index k (0 <= k < K_r).
  const Constraint& requirement(Index k) const { return requirements_.constraint(k); }
  /// Names of the requirement rows: "<requirement>" for one row, "<requirement>.<row>" else (m_r).
  const std::vector<std::string>& row_names() const { return row_names_; }
  /// The requirement that row i belongs to.
  Index row_requirement(Index i) const { return row_requirement_.at(std::size_t(i)); }

  ControlLaw law() const { return law_; }  ///< the law
  /// Writes N(q, q', t) (weighted law only). Cost: the user's callable.
  void weight(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double t,
              Eigen::Ref<MatrixXd> N) const {
    weight_(q, qd, t, N);
  }
  /// True when N was given as a constant matrix (factorized once per workspace).
  bool weight_is_constant() const { return weight_constant_; }

  /// The robust settings, if any.
  const std::optional<RobustControl>& robust() const { return robust_; }
  /// gamma_i, the decay rate of row i's Lyapunov bound (robust only; see RobustControl).
  double robust_rate(Index i) const { return gamma_.at(std::size_t(i)); }
  /// c_i of RobustControl: |e_i| <= sqrt(V_i / c_i).
  double robust_scale(Index i) const { return scale_.at(std::size_t(i)); }
  /// The ultimate bound on |e_i| for a gain kappa that stays below `kappa`:
  /// sqrt(kappa epsilon / (2 gamma_i c_i)). Robust only. Cost O(1).
  double ultimate_error_bound(Index i, double kappa) const;
  /// The Lyapunov function of row i, V_i = (beta² + 2 alpha²) e² + 2 alpha e e' + e'² (holonomic)
  /// or e² (nonholonomic), at error e and rate e'. Robust only. Cost O(1).
  double lyapunov(Index i, double e, double e_dot) const;

  const ControlOptions& options() const { return options_; }  ///< settings
  /// Identity shared by copies; a ControlWorkspace remembers it.
  std::uint64_t id() const { return id_; }

 private:
  friend class ControllerBuilder;
  Controller(System model, System requirements)
      : model_(std::move(model)), requirements_(std::move(requirements)) {}

  Index n_ = 0, m_r_ = 0, k_ = 0;
  System model_, requirements_;
  std::vector<std::string> row_names_;
  std::vector<Index> row_requirement_;
  ControlLaw law_ = ControlLaw::kGauss;
  WeightFn weight_;
  bool weight_constant_ = false;
  bool fully_actuated_ = true;
  MatrixXd S_;
  std::vector<Index> actuated_;
  std::optional<RobustControl> robust_;
  std::vector<double> gamma_, scale_;
  ControlOptions options_;
  std::uint64_t id_ = 0;
};

/// Collects the parts of a Controller, then validates and freezes them in build().
class ControllerBuilder {
 public:
  /// A controller for the nominal model `model` (its constraints are the plant's physical
  /// constraints).
  explicit ControllerBuilder(System model);

  /// Adds a requirement with the error dynamics it already carries (Constraint::stabilize).
  ControllerBuilder& require(Constraint c);
  /// Adds requirement(c, d). @throws std::invalid_argument as requirement().
  ControllerBuilder& require(Constraint c, const ErrorDynamics& d);

  /// The Gauss law (the default).
  ControllerBuilder& gauss();
  /// The weighted law with N(q, q', t).
  ControllerBuilder& weighted(WeightFn N);
  /// The weighted law with a constant N (n × n, symmetric positive definite).
  ControllerBuilder& weighted(const Eigen::Ref<const MatrixXd>& N);

  /// Only these coordinates are actuated: S = the columns of I that select them, Q_c = S u.
  ControllerBuilder& actuated(const std::vector<std::string>& coordinates);
  /// A general actuation matrix S (n × k, full column rank): Q_c = S u.
  ControllerBuilder& actuation(const Eigen::Ref<const MatrixXd>& S);

  /// Adds the robust term (see RobustControl).
  ControllerBuilder& robust(const RobustControl& settings);
  /// Solver settings (see ControlOptions).
  ControllerBuilder& options(const ControlOptions& options);

  /// Validates and returns the controller. @throws std::invalid_argument naming the problem:
  /// no requirement, duplicate requirement names, a weight of the wrong size or not symmetric
  /// positive definite, an unknown or repeated actuated coordinate, S of the wrong height or
  /// rank, robust settings out of range or a requirement without error dynamics under the
  /// robust term, the textbook algorithm, a feasibility tolerance <= 0. Cost O(n³ + K_r).
  Controller build() const;

 private:
  System model_;
  std::vector<Constraint> requirements_;
  ControlLaw law_ = ControlLaw::kGauss;
  WeightFn weight_;
  MatrixXd weight_constant_;
  bool has_weight_constant_ = false;
  std::vector<std::string> actuated_names_;
  MatrixXd S_;
  bool has_actuation_matrix_ = false;
  std::optional<RobustControl> robust_;
  ControlOptions options_;
};

// ---------------------------------------------------------------------------------------------
// the workspace

/// Outcome of one control evaluation.
enum class ControlStatus {
  kOk = 0,  ///< the force meets every requirement on the nominal model
  /// the requirements cannot all be met (actuators too few or badly placed, requirements that
  /// contradict each other or the physical constraints): Qc_nominal is the least-squares force
  /// of least cost; ControlWorkspace::met and residual say which rows are met and by how much
  /// the others are missed
  kRequirementsNotMet,
  kModelFailed,                ///< the nominal model's evaluation failed (see model.status)
  kNonFiniteInput,             ///< a requirement's A_r or b_r, or the weight, holds NaN or Inf
  kWeightNotPositiveDefinite,  ///< the Cholesky factorization of N (or Sᵀ N S) failed
  kNonFiniteResult,            ///< a result overflowed
};

/// Short English name of a status. Cost O(1).
const char* to_string(ControlStatus s);

/// Counters accumulated over a workspace's life.
struct ControlCounters {
  std::int64_t evaluations = 0;  ///< calls to compute_control
  std::int64_t not_met = 0;      ///< evaluations with kRequirementsNotMet
  std::int64_t failures = 0;     ///< evaluations that failed (any other status but kOk)
};

/// Buffers and results of the evaluations of one Controller (sized once; nothing allocates
/// afterwards). Fields are annotated with their size and the stage that fills them.
class ControlWorkspace {
 public:
  /// Sizes every buffer for `ctrl`. Cost O(n² + n m_r + n k).
  explicit ControlWorkspace(const Controller& ctrl);

  /// Identity of the controller this workspace was made for; 0 once moved from (the stages
  /// then throw std::invalid_argument saying the workspace is empty).
  std::uint64_t controller_id() const { return controller_id_; }

  // --- stage 1, evaluate_model -----------------------------------------------------------
  /// The nominal model's evaluation (forward_dynamics): M, Q, a_p = model.qdd (constrained,
  /// without control), model.Qc, M's factor and A_p's decomposition — under the Gauss law on a
  /// model without constraints M = L Lᵀ is in `decomposition` below (stages 1, 3 share it).
  Workspace model;
  // --- stage 2, assemble_requirements ----------------------------------------------------
  /// The requirements' evaluation: req.A = A_r (m_r × n), req.b = b_r (m_r, with the error
  /// dynamics), req.phi / req.phi_dot (their values, for stabilized requirements), req.active.
  Workspace req;
  VectorXd e;  ///< (m_r) error signal e = b_r − A_r a_p
  // --- stage 3, solve_law -----------------------------------------------------------------
  /// (m_r × n) X = A_r P (weighted law or actuation), or X M = A_r P M (Gauss, fully actuated:
  /// then the decomposition below is that of the fundamental equation with constraints X M)
  MatrixXd X;
  MatrixXd XS;     ///< (m_r × k) X S (weighted law or actuation)
  MatrixXd N;      ///< (n × n) the weight N(q, q', t) (weighted law)
  MatrixXd Nu;     ///< (k × k) cost matrix of u: Sᵀ N S, or Sᵀ M⁻¹ S (Gauss with actuation)
  MatrixXd MinvS;  ///< (n × k) M⁻¹ S (Gauss law) or N S (weighted law), with actuation
  /// The law's decomposition: Cholesky of the cost ("mass") matrix and complete orthogonal
  /// decomposition of the requirement rows — (n, m_r) with M and X M for Gauss fully actuated,
  /// (k, m_r) with Nu and X S otherwise. Never forms a pseudo-inverse.
  FundamentalDecomposition decomposition;
  Index rank = 0;       ///< numerical rank of the requirement rows (of X S)
  VectorXd u;           ///< (k) actuator forces of Qc_nominal (Q_c = S u); = Qc_nominal if S = I
  VectorXd Qc_nominal;  ///< (n) the law's force for e (eq. 25 and its weighted form)
  /// (m_r) nominal-model residual of each requirement row, (X Qc_nominal − e)_i in the
  /// requirement's acceleration units: zero (to rounding) where met, the least-squares miss
  /// where not
  VectorXd residual;
  std::vector<unsigned char> met;  ///< (m_r) row i met (see ControlOptions::feasibility_tolerance)
  Index rows_not_met = 0;          ///< number of rows not met
  // --- stage 4, apply_robust --------------------------------------------------------------
  VectorXd s;          ///< (m_r) sliding variable e' + alpha e (holonomic), e (nonholonomic)
  VectorXd kappa;      ///< (m_r) robust gain
  VectorXd v;          ///< (m_r) requirement-space acceleration asked of the robust term
  VectorXd u_robust;   ///< (k) actuator forces of Qc_robust
  VectorXd Qc_robust;  ///< (n) robust term (zero without robust settings)
  // --- stage 5, check_control -------------------------------------------------------------
  VectorXd Qc_control;  ///< (n) the control force to apply, Qc_nominal + Qc_robust
  /// (n) acceleration of the nominal model under the control, a_p + P Qc_control
  VectorXd qdd;
  /// (n) the physical constraints' force on the nominal model under the control:
  /// model.Qc − (Qc_control − M P Qc_control) (unchanged by the Gauss law). Exact for ideal
  /// physical constraints and for non-ideal forces C that do not read the ideal reaction.
  VectorXd Qc_physical;
  double power = 0.0;                         ///< control power Qc_controlᵀ q'
  ControlStatus status = ControlStatus::kOk;  ///< outcome of the last evaluation
  const char* failed_quantity = "";           ///< with a failing status: which quantity
  Index failed_index = -1;                    ///< …and which requirement / row, or −1
  double failed_time = 0.0;                   ///< t of the last evaluation
  ControlCounters counters;                   ///< accumulated over the workspace's life

  // --- scratch ---------------------------------------------------------------------------
  VectorXd tmp_n;                ///< (n)
  VectorXd tmp_n2;               ///< (n)
  VectorXd tmp_n3;               ///< (n)
  VectorXd tmp_k;                ///< (k)
  VectorXd lambda_r;             ///< (m_r) multipliers of the law's decomposition (unused)
  VectorXd lambda_p;             ///< (m_p) multipliers of a physical projection (unused)
  bool cost_factorized = false;  ///< a constant cost matrix is already factorized

 private:
  MovedFromZero<std::uint64_t> controller_id_;
};

// ---------------------------------------------------------------------------------------------
// the stages

/// Evaluates the control at (q, q', t): runs the five stages and returns ws.status (kOk, or
/// kRequirementsNotMet with a valid least-squares force, or a failure that stops the pipeline).
/// @throws std::invalid_argument if q or qd does not have n entries or ws belongs to another
/// controller. Cost: one forward_dynamics of the model, the requirements' evaluation, and
/// O(n² m_r + n m_r² + m_p n m_r) (+ O(n³/3) for a state-dependent M or N; + O(n² k) with
/// actuation). No allocation.
ControlStatus compute_control(const Controller& ctrl, ControlWorkspace& ws,
                              const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t);

/// Stage 1: forward_dynamics of the nominal model into ws.model (a_p = ws.model.qdd). Sets
/// kModelFailed when it fails. Cost O(n³/3 + m_p n² + m_p² n).
ControlStatus evaluate_model(const Controller& ctrl, ControlWorkspace& ws,
                             const Eigen::Ref<const VectorXd>& q,
                             const Eigen::Ref<const VectorXd>& qd, double t);

/// Stage 2: A_r and b_r of the requirements active at t (with their error dynamics) into ws.req,
/// and e = b_r − A_r a_p. Needs stage 1. Cost: the requirements' own, O(n m_r) besides.
ControlStatus assemble_requirements(const Controller& ctrl, ControlWorkspace& ws,
                                    const Eigen::Ref<const VectorXd>& q,
                                    const Eigen::Ref<const VectorXd>& qd, double t);

/// Stage 3: the law. X = A_r P; the decomposition; Qc_nominal = L W⁺ e with W = X M L⁻ᵀ
/// (Gauss, fully actuated: eq. 25 on the physically constrained model) or u = R⁻ᵀ (X S R⁻ᵀ)⁺ e,
/// R Rᵀ = Sᵀ N S (or Sᵀ M⁻¹ S), Qc_nominal = S u; then the residual of every row and which are
/// met. Needs stages 1–2. Cost O(m_r n² + m_r² n) (+ O(m_p n m_r) with physical constraints).
ControlStatus solve_law(const Controller& ctrl, ControlWorkspace& ws,
                        const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                        double t);

/// Stage 4: the robust term (no-op, Qc_robust = 0, without robust settings): s, kappa,
/// v = −kappa sat(s / epsilon), and Qc_robust = the law's force for v. Needs stage 3.
/// Cost O(n² + n m_r).
ControlStatus apply_robust(const Controller& ctrl, ControlWorkspace& ws);

/// Stage 5: Qc_control, q'' = a_p + P Qc_control, Qc_physical, power, finiteness.
/// Cost O(n² + n m_p).
ControlStatus check_control(const Controller& ctrl, ControlWorkspace& ws,
                            const Eigen::Ref<const VectorXd>& qd);

/// A one-line description of ws.status: for kRequirementsNotMet, which requirement rows are
/// missed and by how much, which are met, and the actuated coordinates; for a failure, what and
/// when. Allocates (meant for reports and error paths).
std::string describe_control_status(const Controller& ctrl, const ControlWorkspace& ws);

/// Why the rows that the last evaluation missed (ws.status == kRequirementsNotMet) cannot be
/// met, one clause per cause, joined by "; ": rows that physical constraints fix (naming
/// them: the requirement's row is a combination of theirs), rows that the actuated coordinates
/// do not move, rows that contradict each other (dependent rows of X S with different targets,
/// naming them). "" when every row was met or no cause is found. Allocates (reports and error
/// paths). Cost O(m_r² (n + k) + n m_p²): a least-squares solve and an SVD.
std::string explain_requirements_not_met(const Controller& ctrl, const ControlWorkspace& ws);

/// With actuation (not every coordinate actuated): the requirement rows active at the last
/// evaluation that the actuated coordinates do not move, or cannot meet together, whether or not
/// they were met there (a row asking for no force is met by none): what `ukdyn check` reports of
/// a model whose requirements are met at its initial state only because they ask for nothing
/// there. Rows that the physical constraints fix, or that depend on each other whatever the
/// actuators, are left to explain_requirements_not_met. "" if none. Allocates; cost as above.
std::string explain_unactuated_requirements(const Controller& ctrl, const ControlWorkspace& ws);

/// The requirements without error dynamics (no `dynamics:`, Constraint::stabilization() off)
/// that are active at t and that (q, q') violates beyond `tolerance` times the row's scale of a
/// run of length `duration` (the initial check's scales, check_initial_conditions): the control
/// keeps their error's second (holonomic) or first (nonholonomic) derivative at zero, so such an
/// error is never corrected — it stays, or grows at its rate. One clause per requirement
/// ("requirement 'a' starts unmet (position violation 1, velocity violation 0) and has no
/// dynamics"), joined by "; ", and what to do; "" if none. What `ukdyn check` reports as a
/// problem and a controlled run as a note (u21 05: x = 1 and x = 2 at once, no dynamics, ran
/// "ok"). Allocates; cost one evaluation of the requirements.
std::string explain_uncorrected_requirements(const Controller& ctrl,
                                             const Eigen::Ref<const VectorXd>& q,
                                             const Eigen::Ref<const VectorXd>& qd, double t,
                                             double tolerance, double duration);

// ---------------------------------------------------------------------------------------------
// controlled simulation

/// The plant under the control: a System with the plant's coordinates, mass matrix, potential,
/// physical constraints and non-ideal forces, whose impressed force is Q + Qc_control, the
/// control computed by `ctrl` (its nominal model may differ from the plant) with a control
/// workspace that each Workspace of the returned system owns (its CallableScratch, made when
/// the Workspace is). Run it with simulate() or forward_dynamics(). When the
/// controller fails at a state, Q is NaN there (forward_dynamics reports kNonFiniteInput on Q).
/// Thread-safe like any System: several threads may run it at once, one Workspace each (the
/// control's statistics are each workspace's). Coulomb stick/slip switching is not
/// carried over (the sliding law applies throughout). Requirements active on intervals switch
/// the force: give their ends as SimulationOptions::breakpoints (simulate_controlled does).
/// @throws std::invalid_argument unless the plant and the controller's model have the same
/// coordinates (names) and constraints (names, rows, unilateral or not), and when the plant has
/// unilateral contacts (they run in simulate_controlled, whose controller holds the contacts the
/// run holds). Cost O(n² + n m_r) once.
System controlled_system(const Controller& ctrl, const System& plant);

/// Statistics of the controller over a controlled run.
struct ControlStatistics {
  long evaluations = 0;         ///< control evaluations during the integration
  long not_met = 0;             ///< of which could not meet every requirement
  double max_residual = 0.0;    ///< largest |residual| of a row not met (0 if always met)
  double first_not_met = 0.0;   ///< time of the first evaluation not met (NaN if none)
  std::string not_met_message;  ///< describe_control_status() of that evaluation ("" if none)
  /// the control applied at that evaluation was the one that meets the requirements with a
  /// sliding Coulomb contact held (docs/contact.md, "Contacts under control"), not the
  /// least-squares force
  bool held_control = false;
  double max_kappa = 0.0;  ///< largest robust gain seen
  /// Robust settings only: the first sample time at which a row's |error| exceeded its
  /// guaranteed bound (error_bound) by more than kBoundMargin — the plant then lies outside the
  /// uncertainty model of RobustControl, and the bound guarantees nothing (NaN if never).
  double bound_exceeded_at = std::numeric_limits<double>::quiet_NaN();
  /// The largest |error_i| / error_bound_i over the samples where the bound was exceeded
  /// (0 if never).
  double bound_worst_ratio = 0.0;
  std::string bound_worst_row;  ///< the row of bound_worst_ratio ("" if never)
  /// the sample time of bound_worst_ratio (NaN if never)
  double bound_worst_time = std::numeric_limits<double>::quiet_NaN();
  /// The relative margin of that check: exceeded when |e| > (1 + kBoundMargin) bound + the
  /// rounding floor (1e-9 of the run's largest bound).
  static constexpr double kBoundMargin = 1e-3;
};

/// A controlled run: the plant's trajectory (as simulate() records it: q, q', q'', physical
/// constraint forces, multipliers, violations, energies) and, at every sample, the control.
/// Matrices are stored sample after sample, like Trajectory's fields.
struct ControlledTrajectory {
  /// The plant's trajectory. Its energy_drift is measured with the control's work:
  /// max |E(t) − E(0) − W_nonideal(t) − W_control(t)| (relative as in RunStatistics).
  Trajectory plant;
  std::vector<std::string> row_names;  ///< m_r names of the requirement rows
  /// N × m_r: each requirement row's value — phi (holonomic), psi (nonholonomic), or
  /// A_r q'' − b_r on the plant (acceleration form)
  std::vector<double> error;
  std::vector<double> error_rate;  ///< N × m_r: phi' (holonomic), 0 otherwise
  /// N × m_r: the robust term's guaranteed bound on |error| (empty without robust settings)
  std::vector<double> error_bound;
  std::vector<double> Qc_control;     ///< N × n: control force per coordinate
  std::vector<double> Qc_robust;      ///< N × n: its robust part (zeros without robust settings)
  std::vector<double> control_power;  ///< N: Qc_controlᵀ q'
  /// N: ∫ Qc_controlᵀ Qc_control dt from t_start, integrated exactly as a state of the ODE
  std::vector<double> control_effort;
  std::vector<double> control_work_abs;  ///< N: ∫ |Qc_controlᵀ q'| dt, likewise
  std::vector<double> control_work;      ///< N: ∫ Qc_controlᵀ q' dt, likewise
  ControlStatistics control;             ///< the controller over the run
  bool robust = false;                   ///< error_bound is filled

  /// Number of samples.
  Index samples() const { return plant.samples(); }
};

/// The warnings a front end gives for a controlled run's statistics, one line each without a
/// "warning: " prefix (`ukdyn run` prints them on stderr, Python raises UserWarning): the
/// requirements not met (stats.not_met > 0), and the robust bound left (bound_exceeded_at
/// finite). Times in `time_unit`. Empty when neither happened. Cost O(message length).
std::vector<std::string> control_warnings(const ControlStatistics& stats,
                                          const std::string& time_unit);

/// Simulates `plant` (a System, possibly different from the controller's nominal model)
/// under the control force of `ctrl`, with simulate() and every option it has (integrators,
/// drift control, outputs). The control's work, effort and absolute work, and with robust
/// settings each row's Lyapunov bound V_i, are integrated with the motion as further states
/// (first-order quadratures beside q and q', under the integrator's error control; M stays the
/// plant's). Ends of requirement activity intervals become breakpoints.
/// A controller failure stops the run (plant.stats.status, .message say why); requirements not
/// met are not a failure (control.not_met counts them).
/// Unilateral contacts (docs/contact.md, "Contacts under control") close, hold, release and
/// impact as in simulate(); the controller's model holds the contacts the run holds, a
/// requirement that lifts a contact off releases it, and one that could be met only with a
/// contact pulling stops the run, naming the contact, the requirement row and the time.
/// @throws std::invalid_argument as controlled_system() (contacts aside) and simulate().
/// The samples are kept in the result, bounded as simulate() bounds its own (kMaxStoredValues,
/// counting the control's values too); with options.sample_sink set, each sample's plant part
/// goes there instead (the overload below, which also passes the control's values).
/// Memory: the augmented run's samples are converted one at a time, never stored.
ControlledTrajectory simulate_controlled(const Controller& ctrl, const System& plant,
                                         const Eigen::Ref<const VectorXd>& q0,
                                         const Eigen::Ref<const VectorXd>& qd0,
                                         const SimulationOptions& options = {});

/// simulate_controlled streamed: each sample, the plant's and the control's values, goes to
/// `sample_sink` as a ControlledTrajectory holding that sample only (names filled, stats
/// empty; valid during the call only), in time order, as it is computed; the result holds
/// the names and the statistics but no sample (plant.stats.samples counts them; the energy
/// balance and the violations are certified as the samples go). Memory does not grow with the
/// run's length, and the grid may have up to kMaxStreamedSamples samples. An exception the
/// sink throws stops the run and propagates. An empty sink: the samples are kept, as above
/// (options.sample_sink is ignored by this overload).
ControlledTrajectory simulate_controlled(
    const Controller& ctrl, const System& plant, const Eigen::Ref<const VectorXd>& q0,
    const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& options,
    const std::function<void(const ControlledTrajectory& sample)>& sample_sink);

/// The per-sample fields of a controlled run in one list — the plant's (t, q, …,
/// energy_balance_residual), then the control's (error … control_work) — to clear or to
/// append samples to (run_model's chunks). Cost O(1).
std::vector<std::vector<double>*> sample_fields(ControlledTrajectory& run);

/// The control's CSV columns, in order: `error.<row>`, `error_bound.<row>` (robust only),
/// `Qc_control.<coord>`, `Qc_robust.<coord>` (robust only), `control_power`, `control_effort`,
/// `control_work_abs`, `control_work`. Cost O(N (n + m_r)).
std::vector<CsvColumn> control_csv_columns(const ControlledTrajectory& run);

/// Writes the plant's CSV (write_csv of io/trajectory_files.hpp) followed by the control's columns.
/// @throws std::runtime_error naming the path if it cannot be written.
void write_csv(const ControlledTrajectory& run, const std::string& path);

}  // namespace ukdyn

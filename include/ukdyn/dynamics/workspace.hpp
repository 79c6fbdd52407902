// SPDX-License-Identifier: BSD-3-Clause
/// @file dynamics/workspace.hpp
/// Everything one evaluation of the fundamental equation writes (MuJoCo's mjData, Pinocchio's
/// Data). Made once from a System, it owns every buffer, so evaluations never allocate.
/// One System can drive many workspaces, e.g. one per thread.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/status.hpp"
#include "ukdyn/core/types.hpp"
#include "ukdyn/linalg/anderson.hpp"
#include "ukdyn/linalg/decomposition.hpp"

namespace ukdyn {

class System;
struct CallableScratch;
namespace detail {
class EngineOps;
}
class TextbookDecomposition;
class SparseDecomposition;

/// Deletes a TextbookDecomposition through the reference library that made it (the core
/// library does not contain the textbook formula: target ukdyn::reference does).
struct TextbookDeleter {
  void operator()(TextbookDecomposition* p) const;  ///< Cost: the decomposition's destructor
};

/// Which algorithm evaluates the fundamental equation.
enum class Algorithm {
  kDefault,  ///< Cholesky of M + complete orthogonal decomposition of A L⁻ᵀ (no allocation)
  /// eqs. (9)–(12) as printed: M^{±1/2} by eigendecomposition, SVD B⁺ (allocates). A reference,
  /// in the library ukdyn::reference (link it; the command and the Python module do): without
  /// it, a Workspace asked for kTextbook throws std::invalid_argument saying so.
  kTextbook,
};

/// Engine::kAuto leaves a system with more rows than this from constraints without columns()
/// (dense rows) to the dense engine.
inline constexpr Index kAutoMaxDenseRows = 8;

/// Which engine carries the default algorithm (docs/sparse.md).
enum class Engine {
  /// kSparse when M is block-diagonal (SystemBuilder::mass_block), the algorithm is kDefault, at
  /// most kAutoMaxDenseRows rows come from constraints without columns(), and n >= sparse_threshold
  /// or M has two or more blocks and m <= n (docs/sparse.md, "Choice of engine"); else kDense.
  kAuto,
  kDense,  ///< dense M and A: FundamentalDecomposition (linalg/decomposition.hpp), O(n³) per
           ///< evaluation
  /// block-diagonal M, sparse A, sparse rank-revealing LDLᵀ of G (linalg/sparse.hpp): O(bodies) for
  /// chains and trees with loop closures. Needs a block-diagonal M and Algorithm::kDefault.
  kSparse,
};

/// Settings of a workspace. All tolerances are relative and documented where they are used.
struct SolverOptions {
  Algorithm algorithm = Algorithm::kDefault;  ///< see Algorithm
  Engine engine = Engine::kAuto;              ///< see Engine
  /// With Engine::kAuto, the sparse engine is used from this many coordinates on (below, for two
  /// or more mass blocks with m <= n). Measured (docs/sparse.md): from n = 24 on it was faster on
  /// every structure tried (chains: 3.9× at n = 24; densely coupled bodies: 1.4–2.6×) except
  /// heavily redundant ones (m > n), and below from two bodies on when m <= n. Must be >= 0.
  Index sparse_threshold = 24;
  /// Pivot k of the decomposition of A L⁻ᵀ counts as zero when |R_kk| <= rank_threshold · |R_00|
  /// (see linalg/decomposition.hpp). Must lie in (0, 1).
  double rank_threshold = FundamentalDecomposition::kDefaultThreshold;
  /// The sparse engine's rank threshold tau: row k of W = A L⁻ᵀ counts as dependent when its
  /// part outside the span of the rows eliminated before it has norm <= tau ‖w_k‖ (the pivot of
  /// G = W Wᵀ, or its recomputation in the space of W, is <= tau² G_kk; see linalg/sparse.hpp and
  /// docs/sparse.md for why 1e-6 and not rank_threshold's 1e-10). Must lie in (0, 1).
  double sparse_rank_threshold = 1e-6;
  /// The constraints are reported inconsistent (kInconsistentConstraints) when
  /// ‖A q'' − b‖ > consistency_tolerance · (‖A‖_F ‖q''‖ + ‖b‖ + ‖A‖_F ‖a‖). Must be > 0.
  double consistency_tolerance = 1e-8;
  /// M is reported not symmetric when max|M − Mᵀ| > symmetry_tolerance · max|M|. Must be >= 0.
  double symmetry_tolerance = 1e-12;
  /// Compute the Gauss-optimality and virtual-work residuals (O(n² + n m) extra).
  bool compute_residuals = true;
};

/// Residuals of the last evaluation (absolute, in the units of the quantity).
struct Residuals {
  /// ‖A q'' − b‖: the constraints are met. Computed with compute_residuals, and otherwise only
  /// when A has lost row rank (where inconsistent constraints can occur); NaN when not computed.
  double constraint = 0.0;
  /// ‖M q'' − Q − C − Aᵀ(lambda + lambda_nonideal)‖: stationarity of Gauss's function
  /// (M x − Q − C)ᵀ M⁻¹ (M x − Q − C) on {x : A x = b}.
  double gauss = 0.0;
  /// ‖Qc − C − Aᵀ(lambda + lambda_nonideal)‖: bounds |vᵀ(Qc − C)| / ‖v‖ over A v = 0, i.e. the
  /// virtual work of the constraint force differs from that prescribed by C by at most this.
  double virtual_work = 0.0;
};

/// Counters accumulated over the workspace's life (MuJoCo's warnings).
struct Counters {
  std::int64_t evaluations = 0;     ///< calls to forward_dynamics
  std::int64_t rank_deficient = 0;  ///< evaluations where rank A < active rows (redundancy)
  std::int64_t failures = 0;        ///< evaluations whose status was not kOk
  /// evaluations whose non-ideal forces, reading the reactions they cause themselves, did not
  /// settle within the iteration limit of apply_nonideal (the last iterate was used; where and
  /// by how much: Workspace::unsettled)
  std::int64_t nonideal_unsettled = 0;
  /// evaluations of the non-ideal forces' C by apply_nonideal: one per evaluation when no force
  /// reads a reaction, else one per round of its fixed point (docs/friction.md §1)
  std::int64_t nonideal_rounds = 0;
};

/// Where apply_nonideal's fixed point did not settle (Counters::nonideal_unsettled counts those
/// evaluations; kept, as MuJoCo keeps a warning's last info, over the workspace's life). The
/// residual of an evaluation is the largest move of a reaction in its last round relative to
/// the largest reaction (|ΔR|∞ / |R|∞; the absolute move when every reaction is 0).
struct UnsettledReactions {
  double first_t = std::numeric_limits<double>::quiet_NaN();  ///< t of the first one
  double last_t = std::numeric_limits<double>::quiet_NaN();   ///< t of the last one
  double worst_t = std::numeric_limits<double>::quiet_NaN();  ///< t of the largest residual
  double worst_residual = 0.0;  ///< the largest residual (NaN once one was not a number)
  Index worst_constraint = -1;  ///< the constraint whose reaction moved most there
};

/// A value that a move hands over, leaving a value-initialized one (0) behind: the identity and
/// sizes of a workspace, so that a moved-from workspace reads as empty (system_id() 0, which no
/// System has) and every entry point refuses it with std::invalid_argument rather than reading
/// its empty buffers. Costs nothing where it is read.
template <class T>
class MovedFromZero {
 public:
  MovedFromZero() = default;
  /// Holds v (implicit: it stands for a T).
  MovedFromZero(T v) : v_(v) {}  // NOLINT: implicit, it stands for a T
  /// Copies the value; the source keeps it.
  MovedFromZero(const MovedFromZero&) = default;
  /// Copies the value; the source keeps it.
  MovedFromZero& operator=(const MovedFromZero&) = default;
  /// Takes the value and leaves T{} (0) in o.
  MovedFromZero(MovedFromZero&& o) noexcept : v_(o.v_) { o.v_ = T{}; }
  /// Takes the value and leaves T{} (0) in o (self-assignment keeps it).
  MovedFromZero& operator=(MovedFromZero&& o) noexcept {
    v_ = o.v_;
    if (this != &o) o.v_ = T{};
    return *this;
  }
  /// The value (implicit: it stands for a T).
  operator T() const { return v_; }  // NOLINT: implicit, it stands for a T

 private:
  T v_{};
};

/// Buffers and results of evaluations of one System. Fields are public, annotated with their
/// size and the stage that fills them (dynamics/forward.hpp lists the stages).
class Workspace {
 public:
  /// Sizes every buffer for `sys` and makes each constraint's scratch.
  /// @throws std::invalid_argument if an option is out of range.
  explicit Workspace(const System& sys, const SolverOptions& options = {});
  ~Workspace();
  /// Moves every buffer; the moved-from workspace is left empty: system_id() 0, coordinate_count()
  /// and rows() 0, and every entry point given it throws std::invalid_argument ("the workspace is
  /// empty (moved from)") until a workspace is move-assigned into it.
  Workspace(Workspace&&) noexcept;
  /// Moves every buffer, as the move constructor: the moved-from workspace is left empty.
  Workspace& operator=(Workspace&&) noexcept;

  /// Options in force (set at construction).
  const SolverOptions& options() const { return options_; }
  /// Identity of the system this workspace was made for; 0 for a moved-from workspace.
  std::uint64_t system_id() const { return system_id_; }
  /// Index n and m of the system.
  Index coordinate_count() const { return n_; }
  /// The system's constraint row count m (0 for a moved-from workspace).
  Index rows() const { return m_; }

  /// True when this workspace runs the sparse engine (see Engine); then M and A below are
  /// empty (0 × 0) and their values live in `sparse` (sparse->mass_block(b), sparse->matrix_A()).
  bool is_sparse() const { return sparse != nullptr; }

  // --- stage 1, evaluate_unconstrained --------------------------------------------------
  MatrixXd M;  ///< mass matrix M(q,t) (n × n; 0 × 0 with the sparse engine)
  VectorXd Q;  ///< impressed force Q(q,q',t) (n)
  VectorXd a;  ///< unconstrained acceleration a = M⁻¹ Q (n); for a singular M, that
               ///< of the auxiliary system, M_A⁻¹ Q_A (see mass_singular)
  /// True once M was found singular (positive semi-definite, not definite; then [M; A] must
  /// have full column rank): from then on this workspace factorizes the auxiliary
  /// M_A = M + Aᵀ G A and uses Q_A = Q + Aᵀ G b after stage 2, which give the same q'' and Qc
  /// (Udwadia & Schutte 2010; docs/singular-mass.md). M and Q above stay the system's own.
  bool mass_singular = false;
  MatrixXd M_aux;  ///< M_A (n × n, lower triangle; dense engine)
  /// (3 per row: row, block offset, block size) the rows of A whose constraint's columns() lie
  /// in one mass block singular by construction (MassBlock::singular), e.g. a quaternion's unit
  /// norm, when every other block is constant; the dense engine then completes M with these
  /// alone, block by block as the sparse engine does. Filled at construction (dense engine).
  std::vector<Index> singular_local_rows;
  /// How the dense complete_singular_mass completes M: 0 not known yet, 1 with
  /// singular_local_rows (they made all of M_A regular once; later only the completed blocks are
  /// checked, the others being constant), 2 with every row of A (they did not).
  int singular_completion = 0;
  // --- stage 2, assemble_constraints ----------------------------------------------------
  MatrixXd A;  ///< constraint matrix (m × n; 0 × 0 with the sparse engine); rows of
               ///< inactive constraints are zero
  VectorXd b;  ///< constraint right-hand side (m); zero on inactive rows
  std::vector<unsigned char> active;  ///< (K) constraint k active at this t?
  Index active_rows = 0;              ///< rows of the active constraints
  /// (K) per constraint: −1 follow its time interval (default), 0 force inactive, 1 force
  /// active. The simulation sets it for each segment between breakpoints, so that evaluations
  /// at a segment's ends see the segment's own set of constraints.
  std::vector<signed char> activity_override;
  /// (K) Baumgarte gains in force, initialized from Constraint::stabilization(); the
  /// simulation may change them (DriftControl::kBaumgarte).
  std::vector<Stabilization> stabilization;
  // --- violations, evaluate_violations (dynamics/projection.hpp) and stabilized assembly ---
  VectorXd phi;      ///< position-level violation per row (m)
  VectorXd phi_dot;  ///< velocity-level violation per row (m)
  /// (m) the scale of each row's violation that the projections compare with their tolerance,
  /// |phi_i| <= tolerance · phi_scale_i · max(1, class(‖q‖∞) / length_scale) and
  /// |phi'_i| <= tolerance · phi_dot_scale_i (no factor of the state: speeds that grow without
  /// bound as a mechanism locks up must leave the projection failing): the classes of ‖a_i‖ ℓ
  /// and ‖a_i‖ v, filled by set_run_scales (dynamics/projection.hpp; the simulation calls it
  /// at the start of a run); 10 until then (the tolerance in each constraint's own units)
  VectorXd phi_scale;
  VectorXd phi_dot_scale;     ///< (m) see phi_scale
  double length_scale = 0.0;  ///< class of ℓ (set_run_scales), 0 until then (no state factor)
  double speed_scale = 0.0;   ///< class of v (set_run_scales), 0 until then
  /// the decade of the run's rate v / ℓ, min(1, 10^⌊log10(v / ℓ)⌋) (set_run_scales; 1 until
  /// then, for rates of 1 per unit time and above, and when q = 0: simulate then takes the
  /// time unit's, SimulationOptions::units): the adaptive integrators' atol on q' is atol times
  /// this, so that their velocity tolerance follows a slow run's time scale (docs/simulation.md,
  /// "Scales and tolerances")
  double rate_unit = 1.0;
  /// the unit of the run's energy, the power of 1000 nearest to E / 10 (set_run_scales), 1 until
  /// then: the simulation integrates the work channels in this unit
  double energy_unit = 1.0;
  // --- stage 3, solve_ideal ---------------------------------------------------------------
  FundamentalDecomposition decomposition;  ///< Cholesky of M, COD of A L⁻ᵀ (dense engine; sized
                                           ///< 0 × 0 with the sparse engine)
  /// the sparse engine (M blocks, sparse A, LDLᵀ of G), or null with the dense engine
  std::unique_ptr<SparseDecomposition> sparse;
  VectorXd e;         ///< error signal e = b − A a (m)
  VectorXd lambda;    ///< minimum-norm multipliers of the ideal force, G⁺ e (m)
  VectorXd Qc_ideal;  ///< ideal constraint force Aᵀ lambda, eq. (11) (n)
  MatrixXd shares;    ///< (n × K) column k: constraint k's share A_kᵀ lambda_k (filled when
                      ///< the system has non-ideal forces, or by compute_shares; with the
                      ///< sparse engine and no non-ideal forces, sized by the first
                      ///< compute_shares)
  Index rank = 0;     ///< numerical rank of A
  /// How far A is from losing rank: the smallest kept pivot of W = A L⁻ᵀ over the largest
  /// (FundamentalDecomposition::min_pivot() / max_pivot(), an estimate of σ_r / σ_1; the sparse
  /// engine's: SparseDecomposition::rank_margin()), 1 without constraint rows; NaN with
  /// Algorithm::kTextbook. It falls to 0 as a closed loop approaches a singular configuration.
  double rank_margin = 1.0;
  // --- stage 4, apply_nonideal ------------------------------------------------------------
  /// (number of non-ideal forces) force i takes part (default 1); the simulation switches a
  /// Coulomb friction off while its contact sticks
  std::vector<unsigned char> nonideal_enabled;
  /// (n × number of non-ideal forces) for a Coulomb force that has just started to slip from
  /// rest, the unit direction of the friction at |v| <= eps (opposing the impending motion:
  /// along the force that held it); zero columns when unset. Set by the simulation.
  MatrixXd slip_hint;
  /// (number of non-ideal forces) 1: force i's slip hint holds at every speed, not only at
  /// |v| <= 100 eps (a contact carried through a dead centre of its mechanism, where the
  /// friction turns with the step that crosses it; set by the simulation), default 0
  std::vector<unsigned char> slip_hint_held;
  /// (largest sliding coordinates × Coulomb contacts) column c: contact c's sliding velocity
  /// relative to its constraint, v_rel (see CoulombFriction), filled before the forces are called
  MatrixXd sliding;
  /// (n × K, when the system has non-ideal forces) column k: constraint k's whole reaction
  /// A_kᵀ (lambda_k + lambda_nonideal,k): its share of the ideal force plus the part that the
  /// non-ideal forces cause (the friction at one contact pressing on another). apply_nonideal
  /// evaluates C until it settles, so that a friction law reading its normal force
  /// (IdealForceInfo::reaction) sees the whole reaction.
  MatrixXd reactions;
  MatrixXd reactions_next;  ///< (n × K) scratch of that iteration
  /// (m, with non-ideal forces) the iterate of that fixed point: the lambda_nonideal whose
  /// reactions shares + A_kᵀ lambda_nonideal,k the forces read in the current round
  VectorXd lambda_read;
  /// (dimension m, depth 5, with non-ideal forces) the fixed point's Anderson acceleration on
  /// lambda_read, once the plain rounds converge slowly (apply_nonideal; docs/friction.md §1)
  AndersonAcceleration reaction_acceleration;
  UnsettledReactions unsettled;  ///< where the fixed point did not settle (apply_nonideal)
  /// Non-ideal work vector, sum of the system's forces (n). C, Qc_nonideal and lambda_nonideal
  /// of a system without non-ideal forces are zero from the workspace's construction on, and
  /// are not written again (not even with NaN on a failure).
  VectorXd C;
  VectorXd Qc_nonideal;      ///< non-ideal constraint force, eq. (12) (n)
  VectorXd lambda_nonideal;  ///< multipliers with Qc_nonideal = C + Aᵀ lambda_nonideal (m)
  VectorXd Qc;               ///< total constraint force Qc_ideal + Qc_nonideal (n)
  VectorXd qdd;              ///< constrained acceleration q'' (n), eq. (9)
  // --- stage 5, check_result ------------------------------------------------------------
  Residuals residuals;               ///< see Residuals
  Status status = Status::kOk;       ///< outcome of the last evaluation
  const char* failed_quantity = "";  ///< with a failing status: which quantity ("M", "A", …)
  Index failed_index = -1;           ///< …and which constraint / entry, or −1
  double failed_time = 0.0;          ///< t of the failing evaluation
  Counters counters;                 ///< accumulated over the workspace's life

  /// The multipliers of constraint k (its rows of lambda).
  Eigen::Ref<const VectorXd> lambda_of(const System& sys, Index k) const;

  // --- scratch (owned here so that nothing allocates during an evaluation) ---------------
  VectorXd dqdd;           ///< (n) increment of q'' from one stage
  VectorXd C_term;         ///< (n) one non-ideal force's C
  VectorXd tmp_n;          ///< (n)
  VectorXd tmp_m;          ///< (m)
  VectorXd zero_n;         ///< (n) zeros (the velocity of a position-only evaluation)
  VectorXd lambda_tmp;     ///< (m) multipliers of a projection (discarded)
  MatrixXd contact_rows;   ///< (largest normal rows × n) a contact's normal constraint's rows of A
  VectorXd contact_b;      ///< (largest normal rows) their b, when evaluated apart
  MatrixXd contact_basis;  ///< (largest normal rows × largest sliding coordinates) orthonormal N_k
  VectorXd surface_u;      ///< (largest sliding coordinates) a contact's surface velocity u
  VectorXd surface_u_dot;  ///< (largest sliding coordinates) its rate u' = du/dt
  /// (Coulomb contacts) contact c's Jacobian rows on the contact-point path, (1 + d) × |columns|
  /// (ContactKinematics; 0 × 0 on the coordinate path), filled by sliding_velocity
  std::vector<MatrixXd> contact_jacobian;
  /// (1 + largest d × Coulomb contacts) column c: contact c's bias J_P' q' on those rows
  MatrixXd contact_bias;
  /// (Coulomb contacts) the buffers of contact c's ContactKinematics (null when it has none)
  std::vector<std::unique_ptr<ConstraintScratch>> contact_scratch;
  /// (largest rows × widest constraint) one constraint's rows of A before they go into the
  /// sparse engine's pattern (width: its columns(), n for dense rows); 0 × 0 with the dense one
  MatrixXd A_rows;
  /// The buffers of the system's callables M, Q, V, P_ext and C (System::make_scratch; null when
  /// they need none): made before the constraints' scratch, which may share it.
  std::unique_ptr<CallableScratch> callables;
  std::vector<std::unique_ptr<ConstraintScratch>> scratch;  ///< (K) per-constraint buffers
  /// only with Algorithm::kTextbook (made by the reference library, ukdyn::reference)
  std::unique_ptr<TextbookDecomposition, TextbookDeleter> textbook;
  /// The engine chosen at construction (dense, sparse or textbook; src/dynamics/engine.hpp):
  /// the stages call it and never branch on the engine themselves. Internal.
  const detail::EngineOps* engine = nullptr;
  bool mass_factorized = false;     ///< constant M already factorized
  std::vector<Index> nonzero_cols;  ///< (n) columns of one row of A (the auxiliary M_A)

 private:
  SolverOptions options_;
  MovedFromZero<std::uint64_t> system_id_;
  MovedFromZero<Index> n_, m_;
};

/// A one-line description of ws.status: what failed, where and when, with the residual for
/// inconsistent constraints. Allocates (meant for error paths).
std::string describe_status(const System& sys, const Workspace& ws);

/// Throws SolveError with describe_status() unless ws.status is kOk.
void throw_if_failed(const System& sys, const Workspace& ws);

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
/// @file core/system.hpp
/// The description of a constrained mechanical system (MuJoCo's mjModel, Pinocchio's Model):
/// built once by SystemBuilder, then never changed by any algorithm. Everything an evaluation
/// writes lives in a Workspace (dynamics/workspace.hpp).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/nonideal.hpp"
#include "ukdyn/core/types.hpp"

namespace ukdyn {

// The callables below receive q and q' as `const Eigen::Ref<const VectorXd>&`: views of the
// caller's memory (a workspace's state, a segment of a larger one), valid only during the call —
// never keep one (or its data()) beyond it. Write the parameters with that type or as
// `const auto&`. A callable that takes `const VectorXd&` still converts to these types, but then
// q is copied on every call, which allocates in the hot path.

/// Writes the mass matrix M(q, t) (n × n, symmetric positive definite). Must not allocate.
using MassMatrixFn =
    std::function<void(const Eigen::Ref<const VectorXd>& q, double t, Eigen::Ref<MatrixXd> M)>;
/// Writes one diagonal block M_kk(q, t) (size × size, symmetric positive definite) of a
/// block-diagonal mass matrix. Must not allocate.
using MassBlockFn =
    std::function<void(const Eigen::Ref<const VectorXd>& q, double t, Eigen::Ref<MatrixXd> Mk)>;

/// One diagonal block of a block-diagonal mass matrix: the coordinates [offset, offset + size)
/// (one body's, in absolute coordinates). Constant (value) or state-dependent (fn).
struct MassBlock {
  Index offset = 0;  ///< first coordinate
  Index size = 0;    ///< number of coordinates
  MassBlockFn fn;    ///< M_kk(q, t); empty for a constant block
  MatrixXd value;    ///< the constant block (size × size) when fn is empty
  /// Singular (positive semi-definite, never definite) for every (q, t) by construction, like
  /// a unit quaternion's 4 E_vᵀ J E_v (SystemBuilder::singular_mass_block): the engines complete
  /// it with the constraints from the first evaluation on, and check it positive semi-definite
  /// at the first evaluation of a workspace only (docs/singular-mass.md).
  bool singular = false;
  /// True for a constant block.
  bool constant() const { return !fn; }
};

/// Potential energy V(q, t) of the forces in Q that derive from one (for energy reports only:
/// Q must already contain −dV/dq).
using PotentialFn = std::function<double(const Eigen::Ref<const VectorXd>& q, double t)>;
/// The external power P_ext(q, q', t) (W): the rate at which the forces in Q that do not derive
/// from the potential V do work, plus the explicit time dependence of the energy:
///   P_ext = q'ᵀ Q_np + ∂V/∂t − ½ q'ᵀ (∂M/∂t) q'   (Lagrangian Q, Q_np its non-potential part),
/// in general P_ext = q'ᵀ (Q + ∂V/∂q) + ½ q'ᵀ Ṁ q' + ∂V/∂t. Integrated into `work_external`
/// (docs/simulation.md, "Energy balance"). Must not allocate.
using PowerFn = std::function<double(const Eigen::Ref<const VectorXd>& q,
                                     const Eigen::Ref<const VectorXd>& qd, double t)>;
/// Writes the impressed force Q(q, q', t) (n). Must not allocate.
using ForceFn =
    std::function<void(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, Eigen::Ref<VectorXd> Q)>;

/// The buffers a description's callables (M, Q, V, P_ext, and the non-ideal forces' C through
/// IdealForceInfo::scratch()) write during an evaluation, for one Workspace — what
/// ConstraintScratch is for a constraint. Made once by System::make_scratch() when a Workspace
/// is constructed (sized then: nothing allocates afterwards) and passed to every evaluation of
/// that workspace. A System itself holds no mutable state: one System serves any number of
/// threads at once, each with its own Workspace (docs/algorithm.md, "Thread safety").
struct CallableScratch {
  virtual ~CallableScratch() = default;
};
/// Makes the per-workspace scratch of a description's callables (SystemBuilder::scratch).
using ScratchFactory = std::function<std::unique_ptr<CallableScratch>()>;
/// M(q, t) with the workspace's scratch (nullptr when the system has no ScratchFactory).
using MassMatrixScratchFn = std::function<void(const Eigen::Ref<const VectorXd>& q, double t,
                                               CallableScratch* s, Eigen::Ref<MatrixXd> M)>;
/// Q(q, q', t) with the workspace's scratch (see MassMatrixScratchFn).
using ForceScratchFn =
    std::function<void(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, CallableScratch* s, Eigen::Ref<VectorXd> Q)>;
/// V(q, t) with the workspace's scratch (see MassMatrixScratchFn).
using PotentialScratchFn =
    std::function<double(const Eigen::Ref<const VectorXd>& q, double t, CallableScratch* s)>;
/// P_ext(q, q', t) with the workspace's scratch (see MassMatrixScratchFn).
using PowerScratchFn =
    std::function<double(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, CallableScratch* s)>;

/// The switching functions g(q, q', t) of a description's non-smooth terms, written into g (one
/// entry per function), with the workspace's scratch (see MassMatrixScratchFn): the dynamics
/// (M, Q, the constraints, C) is smooth while no g_i changes sign, and jumps (or has a kink)
/// where one does (docs/simulation.md, "Switch events"). Must not allocate.
using SwitchScratchFn =
    std::function<void(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, CallableScratch* s, Eigen::Ref<VectorXd> g)>;

/// A Coulomb friction contact, for the simulation's stick/slip switching (see CoulombFriction).
struct FrictionContact {
  Index force = -1;                ///< index of the friction's non-ideal force
  Index normal_constraint = -1;    ///< index of the constraint whose share gives N
  Index stick_constraint = -1;     ///< index of the (normally inactive) stick constraint
  std::vector<Index> coordinates;  ///< the sliding coordinates
  /// p, the coordinates N is read on (CoulombFriction::normal_coordinates; empty: all n)
  std::vector<Index> normal_coordinates;
  double mu = 0.0;                     ///< kinetic friction coefficient
  double mu_static = 0.0;              ///< static friction coefficient (>= mu)
  double eps = 0.0;                    ///< regularization velocity: below it the contact is at rest
  SurfaceVelocityFn surface_velocity;  ///< the surface's tangential velocity, or empty
  ContactKinematics kinematics;        ///< the contact point's, or empty (coordinate path)
  /// the length of the sliding velocity: |coordinates|, or d on the contact-point path
  Index size() const { return kinematics ? kinematics.tangents : Index(coordinates.size()); }
};

/// An immutable constrained mechanical system M(q,t) q'' = Q(q,q',t) + Qc with constraints
/// A q'' = b and non-ideal work vector C. Cheap to copy (callables are shared).
/// Thread safety: a System is never written after build(); everything an evaluation writes is
/// in a Workspace (its CallableScratch and ConstraintScratch included), so any number of
/// threads may evaluate or simulate one System (and its copies) at once, one Workspace each.
class System {
 public:
  Index coordinate_count() const { return n_; }  ///< n, number of coordinates
  Index constraint_rows() const { return m_; }   ///< m, rows of all constraints
  Index constraint_count() const { return Index(constraints_.size()); }        ///< K constraints
  const std::vector<std::string>& coordinate_names() const { return names_; }  ///< n names
  const std::vector<Constraint>& constraints() const { return constraints_; }  ///< K
  /// Constraint k (0 <= k < K). @throws std::out_of_range otherwise. Cost O(1).
  const Constraint& constraint(Index k) const { return constraints_.at(std::size_t(k)); }
  /// First row of constraint k in A and b (rows k..k+rows−1 belong to it).
  Index row_offset(Index k) const { return offsets_.at(std::size_t(k)); }
  /// Index of the constraint called `name` (also the internal stick constraint
  /// "stick.<force>" of a Coulomb contact). @throws std::invalid_argument naming it and the
  /// constraints given to the builder when there is none. Cost O(K).
  Index constraint_index(std::string_view name) const;
  /// Index of the coordinate called `name`; a body's coordinate may also be spelled with '_'
  /// for '.' (crank_x for crank.x, as model-file expressions write it; docs/multibody.md) when
  /// that names exactly one coordinate. @throws std::invalid_argument. Cost O(n).
  Index coordinate_index(std::string_view name) const;

  /// True when M was given as a constant matrix (the workspace then factorizes it once).
  bool mass_is_constant() const { return mass_constant_; }
  /// True when M was given as diagonal blocks (SystemBuilder::mass_block): zero elsewhere.
  bool mass_is_block_diagonal() const { return !mass_blocks_.empty(); }
  /// The diagonal blocks of M, by increasing offset, tiling [0, n) (empty unless
  /// mass_is_block_diagonal()).
  const std::vector<MassBlock>& mass_blocks() const { return mass_blocks_; }
  /// The tree of M's sparsity (SystemBuilder::mass_tree): parent[k] of each coordinate, or
  /// empty when M is factorized densely.
  const std::vector<Index>& mass_tree() const { return mass_tree_; }
  /// The per-workspace scratch of the callables (SystemBuilder::scratch), or nullptr when they
  /// need none. A Workspace calls it once, when constructed.
  std::unique_ptr<CallableScratch> make_scratch() const { return scratch_ ? scratch_() : nullptr; }
  /// Writes M(q, t) into M (n × n); `s` is the workspace's scratch (make_scratch()).
  void mass_matrix(const Eigen::Ref<const VectorXd>& q, double t, CallableScratch* s,
                   Eigen::Ref<MatrixXd> M) const {
    mass_(q, t, s, M);
  }
  /// M(q, t) with a scratch of its own: allocates when the system has a ScratchFactory (for
  /// reports and tests; the engines pass their workspace's scratch).
  void mass_matrix(const Eigen::Ref<const VectorXd>& q, double t, Eigen::Ref<MatrixXd> M) const {
    const auto s = make_scratch();
    mass_(q, t, s.get(), M);
  }
  /// Writes Q(q, q', t) into Q (n); `s` is the workspace's scratch.
  void forces(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double t,
              CallableScratch* s, Eigen::Ref<VectorXd> Q) const {
    forces_(q, qd, t, s, Q);
  }
  /// Q(q, q', t) with a scratch of its own (allocates when the system has a ScratchFactory).
  void forces(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double t,
              Eigen::Ref<VectorXd> Q) const {
    const auto s = make_scratch();
    forces_(q, qd, t, s.get(), Q);
  }

  /// True when a potential energy was given.
  bool has_potential() const { return bool(potential_); }
  /// V(q, t), or 0 when none was given; `s` is the workspace's scratch.
  double potential_energy(const Eigen::Ref<const VectorXd>& q, double t, CallableScratch* s) const {
    return potential_ ? potential_(q, t, s) : 0.0;
  }
  /// V(q, t) with a scratch of its own (allocates when the system has a ScratchFactory).
  double potential_energy(const Eigen::Ref<const VectorXd>& q, double t) const {
    if (!potential_) return 0.0;
    const auto s = make_scratch();
    return potential_(q, t, s.get());
  }

  /// True when an external power was given (SystemBuilder::external_power); without one the
  /// forces in Q are taken to be conservative (−∂V/∂q and velocity terms that do no work).
  bool has_external_power() const { return bool(external_power_); }
  /// P_ext(q, q', t) (see PowerFn), or 0 when none was given; `s` is the workspace's scratch.
  double external_power(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                        double t, CallableScratch* s) const {
    return external_power_ ? external_power_(q, qd, t, s) : 0.0;
  }
  /// P_ext(q, q', t) with a scratch of its own (allocates when the system has a ScratchFactory).
  double external_power(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                        double t) const {
    if (!external_power_) return 0.0;
    const auto s = make_scratch();
    return external_power_(q, qd, t, s.get());
  }

  /// True when the description accounts for the work of every force in Q — it declared a
  /// potential or an external power, or gave no Q, or said so (SystemBuilder::
  /// accounts_for_energy) — so that a run's energy balance certifies it. A system that gives Q
  /// and neither V nor an external power makes no claim: its balance is reported, not checked.
  bool accounts_for_energy() const { return accounts_for_energy_; }

  /// Number of non-ideal forces.
  Index nonideal_count() const { return Index(nonideal_fns_.size()); }
  /// Name of non-ideal force i.
  const std::string& nonideal_name(Index i) const { return nonideal_names_.at(std::size_t(i)); }
  /// The bound callable of non-ideal force i.
  const NonIdealFn& nonideal(Index i) const { return nonideal_fns_.at(std::size_t(i)); }

  /// Number of switching functions (SystemBuilder::switching_functions); 0 for a smooth system.
  Index switch_count() const { return Index(switch_names_.size()); }
  /// The switching functions' names (a model file's: the expression g, as text, with " in the
  /// constraint 'NAME'" when a constraint holds it: a kink), for messages.
  const std::vector<std::string>& switch_names() const { return switch_names_; }
  /// g(q, q', t) (switch_count()) into g; `s` is the workspace's scratch. Nothing when the
  /// system has no switching functions. Cost: one evaluation of the functions.
  void switching_functions(const Eigen::Ref<const VectorXd>& q,
                           const Eigen::Ref<const VectorXd>& qd, double t, CallableScratch* s,
                           Eigen::Ref<VectorXd> g) const {
    if (switches_) switches_(q, qd, t, s, g);
  }

  /// The Coulomb friction contacts (one per coulomb_friction force).
  const std::vector<FrictionContact>& friction_contacts() const { return contacts_; }

  /// Identity of this description, shared by its copies; a Workspace remembers it so that a
  /// workspace of another system is refused.
  std::uint64_t id() const { return id_; }

 private:
  friend class SystemBuilder;
  System() = default;

  Index n_ = 0, m_ = 0;
  std::vector<std::string> names_;
  ScratchFactory scratch_;
  MassMatrixScratchFn mass_;
  bool mass_constant_ = false;
  std::vector<MassBlock> mass_blocks_;
  std::vector<Index> mass_tree_;
  ForceScratchFn forces_;
  PotentialScratchFn potential_;
  PowerScratchFn external_power_;
  bool accounts_for_energy_ = true;
  std::vector<Constraint> constraints_;
  std::size_t user_constraints_ = 0;  // the first ones; the others are the contacts' stick rows
  std::vector<Index> offsets_;
  std::vector<std::string> nonideal_names_;
  std::vector<NonIdealFn> nonideal_fns_;
  std::vector<FrictionContact> contacts_;
  std::vector<std::string> switch_names_;
  SwitchScratchFn switches_;
  std::uint64_t id_ = 0;
};

/// Collects the parts of a System, then validates and freezes them in build().
class SystemBuilder {
 public:
  /// A system with n >= 1 coordinates named q0, q1, …
  explicit SystemBuilder(Index n);
  /// A system whose coordinates have these (unique, non-empty) names.
  explicit SystemBuilder(std::vector<std::string> coordinate_names);

  /// The factory of the per-workspace scratch the callables given with a CallableScratch*
  /// parameter receive (System::make_scratch). Default: none (they receive nullptr).
  SystemBuilder& scratch(ScratchFactory factory);
  /// M(q, t) as a callable.
  SystemBuilder& mass_matrix(MassMatrixFn fn);
  /// M(q, t) as a callable of the workspace's scratch (SystemBuilder::scratch).
  SystemBuilder& mass_matrix(MassMatrixScratchFn fn);
  /// A constant mass matrix (n × n); factorized once per workspace.
  SystemBuilder& mass_matrix(const Eigen::Ref<const MatrixXd>& M);
  /// A constant diagonal block of M on the coordinates [offset, offset + M_kk.rows()). Blocks
  /// (of either kind, in any order) must tile [0, n) exactly; M is zero outside them. Replaces
  /// mass_matrix(); the sparse engine factorizes M block by block. Checked in build().
  SystemBuilder& mass_block(Index offset, const Eigen::Ref<const MatrixXd>& Mkk);
  /// A state-dependent diagonal block M_kk(q, t) (size × size) on [offset, offset + size).
  SystemBuilder& mass_block(Index offset, Index size, MassBlockFn fn);
  /// A state-dependent diagonal block that is singular and positive semi-definite for every
  /// (q, t) by construction — the 4 × 4 block of a unit quaternion, which its unit-norm
  /// constraint completes (MassBlock::singular). The caller guarantees it: after the first
  /// evaluation of a workspace the block is no longer checked, and the evaluations skip the
  /// regular factorization attempt and the semi-definiteness check (docs/singular-mass.md).
  SystemBuilder& singular_mass_block(Index offset, Index size, MassBlockFn fn);
  /// Declares M's branch-induced sparsity: parent[k] is coordinate k's parent in a tree of the
  /// coordinates (-1 for a root, else a coordinate before k), and M_ij = 0 for every (q, t)
  /// unless one of i, j is an ancestor of the other — a kinematic tree's M in joint
  /// coordinates, the coordinates of one multi-DOF joint a chain (tree::system_builder gives
  /// it). The dense engine then factorizes M along the branches, M = Lᵀ L with no fill-in,
  /// O(Σ_k d_k²) instead of O(n³/3) (Featherstone's LTL; linalg/decomposition.hpp). The caller
  /// guarantees the pattern (entries outside it are not read). An empty parent (the default)
  /// is the dense Cholesky. Checked in build().
  SystemBuilder& mass_tree(std::vector<Index> parent);
  /// Q(q, q', t) as a callable (default: zero).
  SystemBuilder& forces(ForceFn fn);
  /// Q(q, q', t) as a callable of the workspace's scratch (SystemBuilder::scratch).
  SystemBuilder& forces(ForceScratchFn fn);
  /// V(q, t) for energy reports (default: none, V = 0). Q must contain −dV/dq itself.
  SystemBuilder& potential_energy(PotentialFn fn);
  /// V(q, t) as a callable of the workspace's scratch (SystemBuilder::scratch).
  SystemBuilder& potential_energy(PotentialScratchFn fn);
  /// P_ext(q, q', t), the power of the forces in Q that V does not account for (dampers,
  /// applied loads, a time-dependent V; see PowerFn). Default: none — Q is −∂V/∂q plus
  /// velocity terms that do no work, and a Q that does work otherwise shows up in the
  /// simulation's energy balance residual.
  SystemBuilder& external_power(PowerFn fn);
  /// P_ext(q, q', t) as a callable of the workspace's scratch (SystemBuilder::scratch).
  SystemBuilder& external_power(PowerScratchFn fn);
  /// Declares that V and the external power (either possibly absent) account for the work of
  /// every force in Q — a Q of velocity terms that do no work, say — so that the simulation
  /// checks the energy balance (System::accounts_for_energy). Implied by potential_energy(),
  /// external_power(), and by giving no forces().
  SystemBuilder& accounts_for_energy(bool accounts = true);
  /// The switching functions of the system's non-smooth terms (see SwitchScratchFn), one name
  /// each: simulate() locates their sign changes as events (SimulationOptions::switch_events).
  /// Default: none.
  SystemBuilder& switching_functions(std::vector<std::string> names, SwitchScratchFn fn);
  /// Adds a constraint (names must be unique).
  SystemBuilder& add(Constraint c);
  /// Adds a non-ideal force (its C is summed with the others').
  SystemBuilder& add(NonIdealForce f);

  /// Validates and returns the system. @throws std::invalid_argument naming the problem: no mass
  /// matrix, a constant M of the wrong size, mass blocks that overlap or leave coordinates
  /// without a block, constraint columns() out of range or not increasing, duplicate names, a
  /// non-ideal force that cannot be bound.
  System build() const;

 private:
  Index n_;
  std::vector<std::string> names_;
  ScratchFactory scratch_;
  MassMatrixScratchFn mass_;
  MatrixXd mass_constant_;
  bool has_constant_mass_ = false;
  std::vector<MassBlock> mass_blocks_;
  std::vector<Index> mass_tree_;
  ForceScratchFn forces_;
  PotentialScratchFn potential_;
  PowerScratchFn external_power_;
  bool accounts_for_energy_ = false;
  std::vector<Constraint> constraints_;
  std::vector<NonIdealForce> nonideal_;
  std::vector<std::string> switch_names_;
  SwitchScratchFn switches_;
};

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
/// @file core/nonideal.hpp
/// Non-ideal constraints: the work vector C of eq. (7), supplied by the modeller.
///
/// C may depend on (q, q', t), on the ideal constraint force (which does not depend on C, eq. 11)
/// and on the constraints' whole reactions (IdealForceInfo::reaction: the ideal share plus the
/// reaction that C itself causes), which apply_nonideal settles by iteration: friction follows
/// the true normal force even where one contact's friction presses on another. A system may hold
/// several non-ideal forces; their C vectors are summed.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/types.hpp"

namespace ukdyn {

class System;
class Workspace;
class ConstraintScratch;
struct CallableScratch;
struct CoulombFriction;

/// Read-only view of the ideal constraint force at the current evaluation, handed to each
/// non-ideal force. Valid only during that call.
class IdealForceInfo {
 public:
  /// @param sys the system; @param ws its workspace after the ideal stage.
  IdealForceInfo(const System& sys, const Workspace& ws) : sys_(sys), ws_(ws) {}
  /// The same view with `scratch` for scratch() — for a wrapper that calls a force of another
  /// system with that system's scratch (the controlled plant's forces, inside the controlled
  /// system's workspace). Reading reactions through it counts as reading them through `outer`.
  IdealForceInfo(const IdealForceInfo& outer, CallableScratch* scratch)
      : sys_(outer.sys_), ws_(outer.ws_), outer_(&outer), scratch_(scratch), replaced_(true) {}

  /// The ideal constraint force Qc_ideal (n), eq. (11).
  const VectorXd& Qc_ideal() const;
  /// The minimum-norm multipliers of the ideal force (m), Qc_ideal = Aᵀ lambda.
  const VectorXd& lambda() const;
  /// The multipliers of constraint k (its rows of lambda).
  Eigen::Ref<const VectorXd> lambda(Index k) const;
  /// Constraint k's share of the ideal force, A_kᵀ lambda_k (n). The shares sum to Qc_ideal.
  Eigen::Ref<const VectorXd> share(Index k) const;
  /// Index of the constraint called `name` (O(K) string comparisons: to stay fast, resolve it
  /// once, in a NonIdealForce::Binder). @throws std::invalid_argument when there is none.
  Index constraint_index(std::string_view name) const;
  /// The slip hint of non-ideal force i (see Workspace::slip_hint): zero unless the force is a
  /// Coulomb friction that has just started to slip from rest.
  Eigen::Ref<const VectorXd> slip_hint(Index i) const;
  /// Whether that hint holds at every speed (see Workspace::slip_hint_held).
  bool slip_hint_held(Index i) const;
  /// The sliding velocity of Coulomb contact c relative to its constraint, v_rel (one entry per
  /// sliding coordinate; see CoulombFriction), computed once per evaluation before the
  /// non-ideal forces are called.
  Eigen::Ref<const VectorXd> sliding_velocity(Index c) const;
  /// The contact Jacobian of Coulomb contact c on the contact-point path (see
  /// ContactKinematics): rows n_Wᵀ J_P and t_iᵀ J_P ((1 + d) × |columns|), evaluated with
  /// sliding_velocity; empty (0 × 0) on the coordinate path.
  Eigen::Ref<const MatrixXd> contact_jacobian(Index c) const;
  /// The physical normal force of Coulomb contact c on the contact-point path, whose normal
  /// constraint is k: N = |w·R_k| / |w|², w = J_Pᵀ n_W (row 0 of contact_jacobian(c)), R_k =
  /// reaction(k), whatever the scale of the contact's row. Cost O(n).
  double contact_normal_force(Index c, Index k) const;
  /// C += scale · Tᵀ f on contact c's columns (contact-point path): f (d) the force's tangential
  /// components, T the tangential rows of contact_jacobian(c). Cost O(d · |columns|).
  void add_contact_force(Index c, double scale, const Eigen::Ref<const VectorXd>& f,
                         Eigen::Ref<VectorXd> C) const;
  /// Constraint k's whole reaction: its share of the ideal force plus the reaction that the
  /// non-ideal forces themselves cause on it, A_kᵀ lambda_nonideal,k (friction at one contact
  /// changes the normal force at another: a ladder against a rough wall and a rough floor).
  /// apply_nonideal evaluates C until this settles. Cost O(n).
  Eigen::Ref<const VectorXd> reaction(Index k) const;
  /// Euclidean norm of reaction(k): the normal force of a contact constraint written in
  /// Cartesian coordinates. Cost O(n).
  double normal_force(Index k) const { return reaction(k).norm(); }
  /// The normal force of a contact on the coordinate path from reaction(k), read on the
  /// coordinates `on` (all n when empty): N = |R_p| = |lambda| |a_p| for one row a, the
  /// physical normal force when `on` are the contact's translation coordinates, whatever the
  /// row's scale and units (docs/friction.md §1). Cost O(|on|) (O(n) when empty).
  double normal_force(Index k, const std::vector<Index>& on) const;
  /// The workspace's scratch of the system's callables (System::make_scratch; null when the
  /// system has no ScratchFactory): a non-ideal force's buffers for this evaluation.
  CallableScratch* scratch() const;
  /// True once reaction() or normal_force() was called (apply_nonideal iterates only then).
  bool read_reactions() const { return read_reactions_; }

 private:
  const System& sys_;
  const Workspace& ws_;
  const IdealForceInfo* outer_ = nullptr;  // the view this one replaces the scratch of
  CallableScratch* scratch_ = nullptr;     // scratch() when replaced_
  bool replaced_ = false;
  mutable bool read_reactions_ = false;  // (a transient view's own flag)
};

/// A non-ideal force's C(q, q', t, ideal force): writes C (n), which is zero on entry. q and q'
/// are views, valid during the call only (see the note on callables in core/system.hpp).
/// Must not allocate.
using NonIdealFn =
    std::function<void(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, const IdealForceInfo& ideal, Eigen::Ref<VectorXd> C)>;

/// A named contribution to C. It is bound to a system when the system is built, so it may
/// refer to constraints by name (resolved once, never in the hot path).
class NonIdealForce {
 public:
  /// Makes the callable once the system's constraints are known; may throw
  /// std::invalid_argument naming what it could not resolve.
  using Binder = std::function<NonIdealFn(const System& sys)>;

  /// A force given directly by its callable. @throws std::invalid_argument if fn is empty.
  NonIdealForce(std::string name, NonIdealFn fn);
  /// A force that needs the system to be bound (see Binder).
  NonIdealForce(std::string name, Binder bind);

  const std::string& name() const { return name_; }  ///< its name, unique within a system
  /// The callable for system `sys` (called once by SystemBuilder::build).
  NonIdealFn bind(const System& sys) const { return bind_(sys); }
  /// The Coulomb law behind this force, when it was made by coulomb_friction() (the
  /// simulation then handles sticking), or null.
  const CoulombFriction* coulomb() const { return coulomb_.get(); }

 private:
  friend NonIdealForce coulomb_friction(CoulombFriction spec);
  std::string name_;
  Binder bind_;
  std::shared_ptr<const CoulombFriction> coulomb_;
};

/// The velocity u of the surface's material point under a contact, on the contact's sliding
/// coordinates (one entry each), and its rate u' = du/dt = (du/dq) q' + du/dt along the motion.
/// u may depend on q and t, not on q'. Must not allocate.
using SurfaceVelocityFn =
    std::function<void(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, Eigen::Ref<VectorXd> u, Eigen::Ref<VectorXd> u_dot)>;

/// The kinematics of a contact point, for Coulomb friction that slides the contact point itself
/// rather than listed coordinates (a body that turns, a robot link in joint angles;
/// docs/friction.md, "At a contact point"). At (q, t) it writes, on the coordinates `columns`
/// (strictly increasing, local: column j of J is coordinate columns[j]):
///   J    ((1 + d) × |columns|)  row 0: n_Wᵀ J_P, rows 1..d: t_iᵀ J_P,
///   bias (1 + d)                the same rows of J_P' q' (the contact point's velocity rate at
///                               q'' = 0, for the stick constraint's acceleration form),
/// J_P = ∂v_P/∂q' the Jacobian of the velocity v_P of the body's material point at the contact,
/// n_W the contact's unit normal and t_1..t_d (d = 2 spatial, 1 planar) unit tangents with
/// (n_W, t_i) orthonormal. The sliding velocity is then v_rel = (t_iᵀ J_P q')_i (its components
/// in the tangent plane: P = I − n nᵀ applied and read in the tangent basis), the friction
/// C = J_Pᵀ f with f = Σ f_i t_i, and N the physical normal force, N = |w·R_k| / |w|² with
/// w = J_Pᵀ n_W the unit-normal row and R_k the contact constraint's reaction (whatever the
/// row's scale). `scratch` is made by make_scratch (null when that is empty). Must not allocate.
using ContactKinematicsFn = std::function<void(
    const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double t,
    ConstraintScratch* scratch, Eigen::Ref<MatrixXd> J, Eigen::Ref<VectorXd> bias)>;

/// A contact point's kinematics (see ContactKinematicsFn); empty (no evaluate) on the coordinate
/// path.
struct ContactKinematics {
  Index tangents = 0;            ///< d: 2 for a spatial contact, 1 for a planar one
  std::vector<Index> columns;    ///< the coordinates J_P acts on, strictly increasing
  ContactKinematicsFn evaluate;  ///< J and bias at (q, q', t)
  /// buffers of evaluate, one per workspace (empty: none, evaluate gets null). Allocates.
  std::function<std::unique_ptr<ConstraintScratch>(Index n)> make_scratch;
  explicit operator bool() const { return bool(evaluate); }  ///< on the contact-point path
};

/// Coulomb friction on a constraint surface (docs/friction.md has the equations). While sliding:
///   C_i = −mu N v_rel,i / sqrt(|v_rel|² + eps²)  for i in `coordinates`, zero elsewhere,
/// where N = |R_p| is the norm of constraint k's whole reaction R = A_kᵀ (lambda_k +
/// lambda_nonideal,k) on the coordinates p = `normal_coordinates` (all n when empty): for one row
/// a, N = |lambda| |a_p|, the physical normal force when p are the translation coordinates of the
/// contact's body (IdealForceInfo::normal_force) and v_rel the sliding velocity relative to the
/// constraint:
///   v_rel = P (v − u),   P = I − N_k⁺ N_k,
/// v = q' restricted to `coordinates` (Cartesian, for N to be the physical normal force), N_k
/// constraint k's rows of A restricted to those coordinates, u the surface velocity.
/// P removes the velocity along the constraint's normals, which a bilateral contact shares with
/// the surface: for phi(q, t) that depends on t (a wire that rotates, a platform that rises) the
/// surface's normal motion is thereby derived from phi itself. A motion of the surface along
/// itself (a conveyor belt, a turntable under a block in the plane) leaves phi unchanged and
/// cannot be derived: it is given as `surface_velocity`. For |v_rel| >> eps this is exact
/// Coulomb friction of magnitude mu N opposing v_rel. When the simulation releases a sticking
/// contact, or lets a contact pass through v_rel = 0, friction starts at its full magnitude
/// against the impending motion (Workspace::slip_hint), keeps that direction while
/// |v_rel| <= 100 eps (the speed at which stops are located) and then follows
/// −mu N v_rel/|v_rel| exactly.
///
/// Sticking: the system also gets a nonholonomic constraint "stick.<name>", P (v − u) = 0 on
/// `coordinates`, inactive unless the simulation switches it on. simulate() locates the instant
/// the sliding speed falls to 100 eps (an event on the integrator's dense output) and sticks
/// there only when sticking is admissible: the velocity projection onto the stick rows removes at
/// most a tolerance-level kinetic energy (a zero of v_rel that the mechanism passes through
/// kinematically, like a slider-crank's dead centre, would need a velocity jump), the
/// constraints stay consistent with the stick rows, and the force that holds the contact lies
/// within mu_static N. Otherwise the contact slides through v_rel = 0 (a second event, where the
/// friction reverses). A sticking contact slips again when its holding force exceeds
/// mu_static N. No regularization enters the stick phase. A single forward_dynamics call always
/// sees the sliding law. P is the tangential projector of v_rel: a stuck contact on a rheonomic
/// constraint moves with the surface's normal motion (a bead stuck on a rotating wire), which
/// the constraint imposes. A contact that comes to rest where friction could hold it but that
/// cannot stick stops the run (Status::kIntegratorFailure, with the reason) instead of creeping
/// under the regularized law.
struct CoulombFriction {
  std::string constraint;  ///< name of the constraint whose share gives N
  double mu = 0.0;         ///< kinetic friction coefficient, >= 0
  /// static friction coefficient (>= mu): a stick holds while |holding force| <= mu_static N;
  /// unset: equal to mu
  std::optional<double> mu_static;
  std::vector<Index> coordinates;  ///< sliding coordinates (empty: all n), distinct
  /// p: the coordinates on which N is read, N = |R_p| (docs/friction.md §1): the translation
  /// coordinates of the body at the contact (those in the sliding coordinates' length unit),
  /// so that a gap row with an angle (y + s sin th) gives the force, not force and torque
  /// mixed. Empty: all n (right only when every coordinate of the row is a length). Distinct,
  /// in range; must be empty on the contact-point path (its N is physical already).
  std::vector<Index> normal_coordinates;
  double regularization_velocity = 1e-9;  ///< eps above, > 0, in velocity units
  SurfaceVelocityFn surface_velocity;     ///< u above; empty: the surface has no tangential motion
  std::string name;                       ///< force name (default "coulomb.<constraint>")
  /// the contact point's kinematics: when set, the friction slides the contact point
  /// (v_rel = T q', C = Tᵀ f, N the physical normal force; see ContactKinematicsFn) instead of
  /// `coordinates`, which must then be empty, and `surface_velocity` too (a moving surface under
  /// a contact point is not supported yet); the stick constraint is T q' = 0, T q'' = −T' q'
  ContactKinematics kinematics;
};

/// The non-ideal force of a CoulombFriction law. Binding throws std::invalid_argument if the
/// constraint does not exist, mu < 0, mu_static < mu, eps <= 0, or a coordinate is out of range
/// or repeated. Cost per evaluation O(n + rows_k · |coordinates|).
NonIdealForce coulomb_friction(CoulombFriction spec);

/// Viscous friction C_i = −c_i q'_i on `coordinates` (all when empty).
struct ViscousFriction {
  double coefficient = 0.0;        ///< c >= 0, the same for every listed coordinate
  std::vector<Index> coordinates;  ///< damped coordinates (empty: all n)
  std::string name = "viscous";    ///< force name
};

/// The non-ideal force of a ViscousFriction law. Binding throws std::invalid_argument on
/// c < 0 or a coordinate out of range. Cost O(n).
NonIdealForce viscous_friction(ViscousFriction spec);

}  // namespace ukdyn

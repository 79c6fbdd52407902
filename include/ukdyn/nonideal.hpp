/// @file nonideal.hpp
/// Non-ideal constraints: the work vector C of eq. (7), supplied by the modeller.
///
/// C may depend on (q, q', t) and on the ideal constraint force, because Qc_ideal does not
/// depend on C (eq. 11): friction whose magnitude follows a normal reaction is therefore explicit,
/// with no iteration. A system may hold several non-ideal forces; their C vectors are summed.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/types.hpp"

namespace ukdyn {

class System;
class Workspace;
struct CoulombFriction;

/// Read-only view of the ideal constraint force at the current evaluation, handed to each
/// non-ideal force. Valid only during that call.
class IdealForceInfo {
 public:
  /// @param sys the system; @param ws its workspace after the ideal stage.
  IdealForceInfo(const System& sys, const Workspace& ws) : sys_(sys), ws_(ws) {}

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
  /// Euclidean norm of share(k): the normal force of a contact constraint written in Cartesian
  /// coordinates. Cost O(n).
  double normal_force(Index k) const { return share(k).norm(); }

 private:
  const System& sys_;
  const Workspace& ws_;
};

/// A non-ideal force's C(q, q', t, ideal force): writes C (n), which is zero on entry.
/// Must not allocate.
using NonIdealFn = std::function<void(const VectorXd& q, const VectorXd& qd, double t,
                                      const IdealForceInfo& ideal, Eigen::Ref<VectorXd> C)>;

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

/// Coulomb friction on a constraint surface. While sliding:
///   C_i = −mu N v_i / sqrt(|v|² + eps²)  for i in `coordinates`, zero elsewhere,
/// where v is q' restricted to `coordinates` (the sliding velocity, which must be Cartesian for
/// N to be the physical normal force), N = |A_kᵀ lambda_k| the norm of constraint k's share of
/// the ideal force, and eps = `regularization_velocity`. For |v| >> eps this is exact Coulomb
/// friction of magnitude mu N opposing v (relative error about eps² / (2 |v|²)). When the
/// simulation has just released a sticking contact (v = 0), friction starts at its full
/// magnitude mu N opposing the impending motion, i.e. along the force that held the contact,
/// and follows −mu N v/|v| exactly once |v| > eps (no regularization while slipping from rest).
/// Sticking: the system also gets a nonholonomic constraint "stick.<name>" (v = 0 on
/// `coordinates`), inactive unless the simulation switches it on. simulate() locates the instant
/// the sliding velocity reverses (an event, found on the integrator's dense output) and sticks
/// there: the friction force is switched off and the stick constraint on, so the block is held
/// by an ideal constraint force; it slips again when that force exceeds mu N (a second event).
/// No regularization enters the stick phase. A single forward_dynamics call always sees the
/// sliding law.
struct CoulombFriction {
  std::string constraint;            ///< name of the constraint whose share gives N
  double mu = 0.0;                   ///< friction coefficient, >= 0
  std::vector<Index> coordinates;    ///< sliding coordinates (empty: all n)
  double regularization_velocity = 1e-9;  ///< eps above, > 0, in velocity units
  std::string name;                  ///< force name (default "coulomb.<constraint>")
};

/// The non-ideal force of a CoulombFriction law. Binding throws std::invalid_argument if the
/// constraint does not exist, mu < 0, eps <= 0 or a coordinate is out of range. Cost O(n).
NonIdealForce coulomb_friction(CoulombFriction spec);

/// Viscous friction C_i = −c_i q'_i on `coordinates` (all when empty).
struct ViscousFriction {
  double coefficient = 0.0;          ///< c >= 0, the same for every listed coordinate
  std::vector<Index> coordinates;    ///< damped coordinates (empty: all n)
  std::string name = "viscous";      ///< force name
};

/// The non-ideal force of a ViscousFriction law. Binding throws std::invalid_argument on
/// c < 0 or a coordinate out of range. Cost O(n).
NonIdealForce viscous_friction(ViscousFriction spec);

}  // namespace ukdyn

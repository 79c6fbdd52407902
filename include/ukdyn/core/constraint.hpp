// SPDX-License-Identifier: BSD-3-Clause
/// @file core/constraint.hpp
/// A named constraint of any kind, and the interface its mathematics implements.
///
/// Every constraint, whatever its declared form, is reduced to rows of the acceleration form
/// A q'' = b (eq. 5):
///  - holonomic     phi(q,t) = 0:      A = dphi/dq,  b = −d²/ds² phi(q + s q', t + s) at s = 0
///  - nonholonomic  psi(q,q',t) = 0:   A = dpsi/dq', b = −(dpsi/dq · q' + dpsi/dt)
///  - acceleration  A(q,q',t), b(q,q',t) given directly.
/// The first two are built from one generic callable by automatic differentiation
/// (see core/autodiff.hpp); the third from a plain callable (acceleration_constraint below).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/types.hpp"

namespace ukdyn {

/// The form in which a constraint was declared.
enum class ConstraintKind {
  kHolonomic,     ///< phi(q,t) = 0, differentiated twice
  kNonholonomic,  ///< psi(q,q',t) = 0, differentiated once; may be nonlinear in q'
  kAcceleration,  ///< A q'' = b given directly
};

/// Baumgarte gains of a constraint (see Constraint::stabilize). Zero gains: none.
struct Stabilization {
  double alpha = 0.0;  ///< damping gain: 2 alpha phi' (holonomic), alpha psi (nonholonomic)
  double beta = 0.0;   ///< stiffness gain: beta² phi (holonomic only)
  /// True when any gain is non-zero.
  bool enabled() const { return alpha != 0.0 || beta != 0.0; }
};

/// Short name of a kind ("holonomic", "nonholonomic", "acceleration"). Cost O(1).
const char* to_string(ConstraintKind kind);

struct CallableScratch;

/// Scratch memory one constraint needs while it is evaluated (automatic-differentiation
/// buffers). Made once per workspace by ConstraintModel::make_scratch, so evaluation does not
/// allocate.
class ConstraintScratch {
 public:
  virtual ~ConstraintScratch() = default;
};

/// The mathematics of one constraint. Implementations are immutable after construction; all
/// mutable memory lives in the ConstraintScratch that the workspace owns.
class ConstraintModel {
 public:
  virtual ~ConstraintModel() = default;

  /// Scratch for evaluating this constraint on a system with n coordinates (may be null).
  /// Called once when a workspace is made; may allocate.
  virtual std::unique_ptr<ConstraintScratch> make_scratch(Index n) const;
  /// The same, given the workspace's scratch of the system's callables (System::make_scratch,
  /// possibly null), which a constraint may share buffers with — the compiled constraints of a
  /// large model file share one input vector there. Called by the Workspace; the default calls
  /// make_scratch(n).
  virtual std::unique_ptr<ConstraintScratch> make_scratch_sharing(Index n,
                                                                  CallableScratch* shared) const {
    (void)shared;
    return make_scratch(n);
  }

  /// Writes this constraint's rows of A (rows × n) and b (rows) at (q, q', t). q and q' (n
  /// each) are views of the caller's memory, valid during the call only (in every method here).
  /// Must not allocate. Cost: that of the user callable times ceil(n/4) + 1 passes for the
  /// automatically differentiated kinds. The default serves the local kind (columns() not
  /// empty): acceleration_form_local into the first columns of A, scattered in place to
  /// columns() and the rest zeroed — O(rows · n). A dense model must override it.
  virtual void acceleration_form(const Eigen::Ref<const VectorXd>& q,
                                 const Eigen::Ref<const VectorXd>& qd, double t,
                                 ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A,
                                 Eigen::Ref<VectorXd> b) const;

  /// The coordinates this constraint depends on, strictly increasing: its rows of A are zero
  /// in every other column (a joint touches the coordinates of its two bodies only). Empty, the
  /// default: any of the n coordinates (dense rows). A model that declares columns implements
  /// acceleration_form_local; the sparse engine then assembles A in O(rows · columns) per
  /// constraint, independent of n. Must return the same list on every call.
  virtual const std::vector<Index>& columns() const;

  /// The local acceleration form, for models with columns(): A_local (rows × columns().size())
  /// holds the non-zero columns of A in columns() order; b as in acceleration_form. Must not
  /// allocate. The default throws std::logic_error (a model with columns must override it).
  virtual void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                                       const Eigen::Ref<const VectorXd>& qd, double t,
                                       ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A_local,
                                       Eigen::Ref<VectorXd> b) const;

  /// Writes the violation of the constraint at position level (phi; zero for the nonholonomic
  /// and acceleration kinds) and velocity level (d phi/dt along the motion = A q' + dphi/dt for
  /// holonomic, psi for nonholonomic, zero for the acceleration kind). Both have `rows` entries.
  virtual void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, ConstraintScratch* scratch, Eigen::Ref<VectorXd> position,
                         Eigen::Ref<VectorXd> velocity) const;
};

/// A named constraint with any number of rows, optionally active on a time interval only.
/// Cheap to copy (the model is shared and immutable).
class Constraint {
 public:
  /// @param name unique within a system; @param kind declared form; @param rows number of
  /// scalar equations (> 0); @param model its mathematics (not null).
  /// @throws std::invalid_argument on an empty name, rows <= 0 or a null model.
  Constraint(std::string name, ConstraintKind kind, Index rows,
             std::shared_ptr<const ConstraintModel> model);

  /// Makes the constraint active on [begin, end] only; outside it its rows of A and b are zero
  /// (no force). @throws std::invalid_argument unless begin <= end, or if it is unilateral.
  Constraint& active_between(double begin, double end);

  /// Baumgarte stabilization: the constraint is imposed as phi'' + 2 alpha phi' + beta² phi = 0
  /// (holonomic) or psi' + alpha psi = 0 (nonholonomic; beta unused), i.e.
  /// b ← b − 2 alpha phi' − beta² phi, resp. b ← b − alpha psi. A drifting constraint then
  /// returns to zero with these error dynamics. Ignored for the acceleration kind.
  /// @throws std::invalid_argument unless alpha >= 0 and beta >= 0.
  Constraint& stabilize(double alpha, double beta);
  /// The Baumgarte gains (zero: no stabilization).
  const Stabilization& stabilization() const { return stabilization_; }

  /// Marks the constraint as a drive: a prescribed motion (a rheonomic constraint that an
  /// actuator enforces, like a multibody joint's `drive:`). Its force does work; the simulation
  /// reports that work as `work_drive`, apart from the other ideal constraints' `work_ideal`
  /// (docs/simulation.md, "Energy balance"). Changes nothing else.
  Constraint& mark_drive(bool drive = true) {
    drive_ = drive;
    return *this;
  }
  /// True for a drive (mark_drive).
  bool is_drive() const { return drive_; }

  /// Makes the constraint unilateral (docs/contact.md): its one holonomic row is a gap
  /// g(q, t) = phi >= 0 whose force only pushes (multiplier lambda >= 0 in Qc = Aᵀ lambda, A =
  /// dg/dq). The simulation keeps it as an ordinary row of A while it is closed and pushes,
  /// releases it where lambda would pull, and re-engages it at an impact, where the approach
  /// speed −g' jumps to e·(−g') the other way (Newton's law with restitution e). Cost O(1).
  /// @throws std::invalid_argument naming the constraint unless it is holonomic with one row,
  /// 0 <= restitution <= 1, and active for the whole run (no active_between: not supported).
  Constraint& unilateral(double restitution = 0.0);
  /// True for a unilateral constraint (see unilateral()).
  bool is_unilateral() const { return unilateral_; }
  /// Newton's coefficient of restitution e in [0, 1] of a unilateral constraint (0 otherwise).
  double restitution() const { return restitution_; }

  const std::string& name() const { return name_; }                ///< its unique name
  ConstraintKind kind() const { return kind_; }                    ///< declared form
  Index rows() const { return rows_; }                             ///< number of scalar rows
  const TimeInterval& active_interval() const { return active_; }  ///< when it acts
  bool is_active(double t) const { return active_.contains(t); }   ///< acts at time t?
  const ConstraintModel& model() const { return *model_; }         ///< its mathematics

 private:
  std::string name_;
  ConstraintKind kind_;
  Index rows_;
  TimeInterval active_;
  Stabilization stabilization_;
  bool drive_ = false;
  bool unilateral_ = false;
  double restitution_ = 0.0;
  std::shared_ptr<const ConstraintModel> model_;
};

/// User callable of the acceleration form: writes A (rows × n) and b (rows) at (q, q', t). q and
/// q' are views, valid during the call only (see the note on callables in core/system.hpp).
using AccelerationFormFn =
    std::function<void(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> b)>;

/// A constraint given directly in acceleration form A(q,q',t) q'' = b(q,q',t).
/// The callable must write every entry of its rows (they are not cleared between calls) and
/// should not allocate. @throws std::invalid_argument if fn is empty (and as Constraint()).
Constraint acceleration_constraint(std::string name, Index rows, AccelerationFormFn fn);

}  // namespace ukdyn

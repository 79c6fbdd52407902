// SPDX-License-Identifier: BSD-3-Clause
/// @file core/autodiff.hpp
/// Holonomic and nonholonomic constraints written once as generic callables and differentiated
/// exactly by forward-mode automatic differentiation (Eigen's AutoDiff module).
///
/// Include this header only where constraints are declared: it instantiates the user's callable
/// with the dual-number types below, which is the expensive part of compiling a model.
///
/// The callable is generic in its scalar type S and writes every row of `out`:
/// @code
///   auto rod = ukdyn::holonomic("rod", 1, [](const auto& q, const auto& t, auto& phi) {
///     phi[0] = q[0] * q[0] + q[1] * q[1] - 1.0;   // x² + y² − L² = 0
///   });
///   auto knife = ukdyn::nonholonomic("knife", 1,
///       [](const auto& q, const auto& qd, const auto& t, auto& psi) {
///         using std::sin; using std::cos;        // so that S = double finds them too
///         psi[0] = qd[0] * sin(q[2]) - qd[1] * cos(q[2]);
///       });
/// @endcode
/// q and q' arrive as `const Eigen::Matrix<S, Dynamic, 1>&`, t as `const S&`, out as
/// `Eigen::Matrix<S, Dynamic, 1>&` already sized to `rows`. Keep intermediate values in
/// variables of type S (`S x = q[0];`), not `auto`: AutoDiff expressions hold references.
/// Branch with if/else, not `cond ? q[1] : 0.0 * q[0]`: the two arms have different types and
/// their common type may be plain double, which silently drops the derivatives.
#pragma once

#include <memory>
#include <string>
#include <utility>

#include <Eigen/Core>
#include <unsupported/Eigen/AutoDiff>

#include "ukdyn/core/constraint.hpp"

namespace ukdyn {
/// Constraints written as generic callables and differentiated by forward-mode automatic
/// differentiation (this file).
namespace ad {

/// Number of derivative directions carried by one pass of forward mode.
inline constexpr int kChunk = 4;
/// First-order dual number carrying kChunk directional derivatives (Jacobian columns).
using Jet = Eigen::AutoDiffScalar<Eigen::Matrix<double, kChunk, 1>>;
/// First-order dual number with one direction.
using Dual = Eigen::AutoDiffScalar<Eigen::Matrix<double, 1, 1>>;
/// Second-order dual number along one direction: value, first and second derivative.
using Dual2 = Eigen::AutoDiffScalar<Eigen::Matrix<Dual, 1, 1>>;
/// Dynamic column vector of scalar S.
template <class S>
using Vec = Eigen::Matrix<S, Eigen::Dynamic, 1>;

/// Buffers of a holonomic constraint (sized once).
struct HolonomicScratch final : ConstraintScratch {
  /// Sized for n coordinates and `rows` constraint rows. Allocates; the passes do not.
  HolonomicScratch(Index n, Index rows) : qj(n), outj(rows), q2(n), out2(rows) {}
  Vec<Jet> qj;      ///< (n) q seeded with kChunk Jacobian directions, first-order pass
  Vec<Jet> outj;    ///< (rows) phi and its derivatives along those directions
  Vec<Dual2> q2;    ///< (n) q + s q' to second order in s, second-order pass
  Vec<Dual2> out2;  ///< (rows) phi(q + s q', t + s): value, d/ds, d²/ds²
};

/// Buffers of a nonholonomic constraint (sized once).
struct NonholonomicScratch final : ConstraintScratch {
  /// Sized for n coordinates and `rows` constraint rows. Allocates; the passes do not.
  NonholonomicScratch(Index n, Index rows) : qj(n), qdj(n), outj(rows) {}
  Vec<Jet> qj;    ///< (n) q, seeded along the direction (q', 0, 1) of (q, q', t)
  Vec<Jet> qdj;   ///< (n) q', seeded with the unit directions e_{q'_j}
  Vec<Jet> outj;  ///< (rows) psi and its derivatives along the seeded directions
};

/// Fills x with values v and zero derivatives. Cost O(n kChunk).
void set_constant(Vec<Jet>& x, const Eigen::Ref<const VectorXd>& v);
/// Seeds x(q + s q', t + s) for a second-order pass along (q', 1). Cost O(n).
void seed_second_order(Vec<Dual2>& x, const Eigen::Ref<const VectorXd>& q,
                       const Eigen::Ref<const VectorXd>& qd);
/// The time variable t + s of a second-order pass.
Dual2 seed_time_second_order(double t);

/// holonomic phi(q,t): A = dphi/dq (columns kChunk at a time), b = −d²/ds² phi(q+sq', t+s).
template <class F>
class HolonomicModel final : public ConstraintModel {
 public:
  /// A constraint of `rows` rows: f(q, t, out) writes phi(q, t) into out (rows); it is called
  /// with the scalar types Jet and Dual2 (a generic callable, see the file's comment).
  HolonomicModel(Index rows, F f) : rows_(rows), f_(std::move(f)) {}

  std::unique_ptr<ConstraintScratch> make_scratch(Index n) const override {
    return std::make_unique<HolonomicScratch>(n, rows_);
  }

  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, ConstraintScratch* s, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    auto& w = static_cast<HolonomicScratch&>(*s);
    const Index n = q.size();
    // A = dphi/dq, kChunk Jacobian columns per pass
    set_constant(w.qj, q);
    const Jet tj(t, Jet::DerType::Zero());
    for (Index j0 = 0; j0 < n; j0 += kChunk) {
      const Index k_end = std::min<Index>(kChunk, n - j0);
      for (Index k = 0; k < k_end; ++k) w.qj[j0 + k].derivatives()[k] = 1.0;
      f_(std::as_const(w.qj), tj, w.outj);
      for (Index k = 0; k < k_end; ++k) {
        w.qj[j0 + k].derivatives()[k] = 0.0;
        for (Index r = 0; r < rows_; ++r) A(r, j0 + k) = w.outj[r].derivatives()[k];
      }
    }
    // b = −d²/ds² phi(q + s q', t + s) at s = 0
    second_order_pass(q, qd, t, w);
    for (Index r = 0; r < rows_; ++r) b[r] = -w.out2[r].derivatives()[0].derivatives()[0];
  }

  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                 double t, ConstraintScratch* s, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& w = static_cast<HolonomicScratch&>(*s);
    // phi and d/ds phi(q + s q', t + s) from one second-order pass
    second_order_pass(q, qd, t, w);
    for (Index r = 0; r < rows_; ++r) {
      position[r] = w.out2[r].value().value();
      velocity[r] = w.out2[r].value().derivatives()[0];
    }
  }

 private:
  void second_order_pass(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, HolonomicScratch& w) const {
    seed_second_order(w.q2, q, qd);
    const Dual2 t2 = seed_time_second_order(t);
    f_(std::as_const(w.q2), t2, w.out2);
  }

  Index rows_;
  F f_;
};

/// nonholonomic psi(q,q',t): A = dpsi/dq', b = −d/ds psi(q + s q', q', t + s). The n + 1
/// directions (each q'_j, then (q', 0, 1) in (q, q', t)) are taken kChunk at a time.
template <class F>
class NonholonomicModel final : public ConstraintModel {
 public:
  /// A constraint of `rows` rows: f(q, qd, t, out) writes psi(q, q', t) into out (rows); it is
  /// called with the scalar type Jet (a generic callable, see the file's comment).
  NonholonomicModel(Index rows, F f) : rows_(rows), f_(std::move(f)) {}

  std::unique_ptr<ConstraintScratch> make_scratch(Index n) const override {
    return std::make_unique<NonholonomicScratch>(n, rows_);
  }

  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, ConstraintScratch* s, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    auto& w = static_cast<NonholonomicScratch&>(*s);
    const Index n = q.size();
    set_constant(w.qj, q);
    set_constant(w.qdj, qd);
    Jet tj(t, Jet::DerType::Zero());
    for (Index j0 = 0; j0 <= n; j0 += kChunk) {
      const Index k_end = std::min<Index>(kChunk, n + 1 - j0);
      // seed: direction j < n is e_{q'_j}; direction n is (q', 0, 1)
      for (Index k = 0; k < k_end; ++k) seed(w, qd, tj, j0 + k, k, 1.0);
      f_(std::as_const(w.qj), std::as_const(w.qdj), std::as_const(tj), w.outj);
      for (Index k = 0; k < k_end; ++k) {
        const Index j = j0 + k;
        seed(w, qd, tj, j, k, 0.0);
        if (j < n) {
          for (Index r = 0; r < rows_; ++r) A(r, j) = w.outj[r].derivatives()[k];
        } else {
          for (Index r = 0; r < rows_; ++r) b[r] = -w.outj[r].derivatives()[k];
        }
      }
    }
  }

  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                 double t, ConstraintScratch* s, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& w = static_cast<NonholonomicScratch&>(*s);
    set_constant(w.qj, q);
    set_constant(w.qdj, qd);
    const Jet tj(t, Jet::DerType::Zero());
    f_(std::as_const(w.qj), std::as_const(w.qdj), tj, w.outj);
    position.setZero();
    for (Index r = 0; r < rows_; ++r) velocity[r] = w.outj[r].value();
  }

 private:
  // sets derivative slot k of direction j to `on` (1 seeds, 0 clears)
  static void seed(NonholonomicScratch& w, const Eigen::Ref<const VectorXd>& qd, Jet& tj, Index j,
                   Index k, double on) {
    const Index n = qd.size();
    if (j < n) {
      w.qdj[j].derivatives()[k] = on;
    } else {
      for (Index i = 0; i < n; ++i) w.qj[i].derivatives()[k] = on * qd[i];
      tj.derivatives()[k] = on;
    }
  }

  Index rows_;
  F f_;
};

}  // namespace ad

/// A holonomic constraint phi(q, t) = 0 with `rows` rows, from a generic callable
/// `f(q, t, phi)` (see the file comment). A and b are derived exactly by forward-mode
/// automatic differentiation; no finite differences. Cost per evaluation: ceil(n/4) passes of f
/// with 4-direction duals plus one second-order pass.
/// @throws std::invalid_argument on an empty name or rows <= 0.
template <class F>
Constraint holonomic(std::string name, Index rows, F f) {
  return Constraint(std::move(name), ConstraintKind::kHolonomic, rows,
                    std::make_shared<ad::HolonomicModel<F>>(rows, std::move(f)));
}

/// A nonholonomic constraint psi(q, q', t) = 0 with `rows` rows, linear or nonlinear in q',
/// from a generic callable `f(q, qd, t, psi)`. A = dpsi/dq' and b = −(dpsi/dq q' + dpsi/dt)
/// by forward-mode automatic differentiation. Cost: ceil((n+1)/4) passes of f.
/// @throws std::invalid_argument on an empty name or rows <= 0.
template <class F>
Constraint nonholonomic(std::string name, Index rows, F f) {
  return Constraint(std::move(name), ConstraintKind::kNonholonomic, rows,
                    std::make_shared<ad::NonholonomicModel<F>>(rows, std::move(f)));
}

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
/// @file core/types.hpp
/// Basic types shared by every part of ukdyn.
///
/// Glossary (the symbols of Udwadia & Kalaba, used verbatim throughout the code; equation
/// numbers refer to docs/theory.md and the paper):
///   n            number of generalized coordinates q
///   m            number of constraint rows (all constraints stacked, active or not)
///   M (n×n)      mass matrix, symmetric positive definite                           (1)
///   Q (n)        impressed (given) force, so that M q'' = Q without constraints    (1)
///   a (n)        unconstrained acceleration a = M⁻¹ Q                               (2)
///   A (m×n), b (m)  constraints in acceleration form A q'' = b                      (5)
///   C (n)        non-ideal work vector: vᵀ Qᶜ = vᵀ C for every v with A v = 0       (7)
///   e (m)        error signal e = b − A a
///   L (n×n)      Cholesky factor M = L Lᵀ;   W = A L⁻ᵀ (m×n);   G = A M⁻¹ Aᵀ = W Wᵀ
///   Qc_ideal     ideal constraint force  Aᵀ G⁺ e = L W⁺ e                          (11)
///   Qc_nonideal  non-ideal constraint force  C − Aᵀ G⁺ A M⁻¹ C                     (12)
///   lambda (m)   minimum-norm multipliers of the ideal force, Qc_ideal = Aᵀ lambda
#pragma once

#include <Eigen/Core>
#include <limits>

/// The Udwadia–Kalaba fundamental equation: constrained multibody dynamics, exact tracking
/// control and unilateral contacts (the glossary of symbols: this file's comment).
namespace ukdyn {

/// Sizes and indices (Eigen's signed std::ptrdiff_t), as in every Eigen object.
using Index = Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

/// Closed time interval [begin, end] on which a constraint is active. The default is all time.
struct TimeInterval {
  double begin = -std::numeric_limits<double>::infinity();  ///< first instant of activity
  double end = std::numeric_limits<double>::infinity();     ///< last instant of activity

  /// True when t lies in [begin, end]. Cost O(1).
  bool contains(double t) const { return t >= begin && t <= end; }
};

}  // namespace ukdyn

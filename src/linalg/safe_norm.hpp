// ‖x‖ without overflow or underflow (not installed): the row equilibration of both
// decompositions (linalg/decomposition.hpp, linalg/sparse.hpp) and the residual norms.
#pragma once

#include <algorithm>
#include <cmath>

#include <Eigen/Core>

#include "ukdyn/core/types.hpp"

namespace ukdyn::detail {

// ‖x‖ over the n entries at x: Eigen's norm (the same bits as v.norm()) when it lies in
// [2⁻⁴⁵⁰, 2⁴⁵⁰], where no square under- or overflows (the common case, one pass), else
// rescaled by max |x_i| (a row written as 1e-170 (x² + y² − 1), or coordinates of 1e200, whose
// squares under- or overflow; and a zero vector). inf or NaN when an entry is. Cost O(n), twice
// that on the rare rescaled path.
inline double safe_norm(const double* x, Index n) {
  const double s = n > 0 ? Eigen::Map<const VectorXd>(x, n).norm() : 0.0;
  if (s >= 0x1p-450 && s <= 0x1p+450) return s;
  double big = 0.0;
  for (Index k = 0; k < n; ++k) {
    if (std::isnan(x[k])) return x[k];
    big = std::max(big, std::abs(x[k]));
  }
  if (!(big > 0.0) || !std::isfinite(big)) return big;  // 0 or inf
  double t = 0.0;
  for (Index k = 0; k < n; ++k) {
    const double r = x[k] / big;
    t += r * r;
  }
  return big * std::sqrt(t);
}

}  // namespace ukdyn::detail

// ‖x‖ without overflow or underflow (not installed): the row equilibration of both
// decompositions (linalg/decomposition.hpp, linalg/sparse.hpp) and the residual norms.
#pragma once

#include <algorithm>
#include <cmath>

#include "ukdyn/core/types.hpp"

namespace ukdyn::detail {

// ‖x‖ over the n entries at x: the plain sum of squares when it lies where every square keeps
// its precision (the common case, one pass), else rescaled by max |x_i| (a row written as
// 1e-170 (x² + y² − 1), or coordinates of 1e200, whose squares under- or overflow). inf or NaN
// when an entry is. Cost O(n), twice that on the rare rescaled path.
inline double safe_norm(const double* x, Index n) {
  constexpr double kLow = 0x1p-900, kHigh = 0x1p+900;
  double s0 = 0.0, s1 = 0.0;
  Index i = 0;
  for (; i + 2 <= n; i += 2) {
    s0 += x[i] * x[i];
    s1 += x[i + 1] * x[i + 1];
  }
  if (i < n) s0 += x[i] * x[i];
  const double s = s0 + s1;
  if (s >= kLow && s <= kHigh) return std::sqrt(s);
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

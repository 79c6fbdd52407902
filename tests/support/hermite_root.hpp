// SPDX-License-Identifier: BSD-3-Clause
// Test support: the root of a sampled function between two samples, located on its cubic
// Hermite interpolant (values and derivatives at both ends), as the tests find turning points
// and crossing times of a trajectory.
#pragma once

#include <cmath>

namespace ukdyn::testing {

// root of the cubic Hermite interpolant of f on [t0, t1] (f0, f1 of opposite signs, d0, d1 the
// derivatives), by bisection to round-off
inline double hermite_root(double t0, double t1, double f0, double f1, double d0, double d1) {
  const double h = t1 - t0;
  auto f = [&](double t) {
    const double s = (t - t0) / h, s2 = s * s, s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * f0 + (s3 - 2 * s2 + s) * h * d0 + (-2 * s3 + 3 * s2) * f1 +
           (s3 - s2) * h * d1;
  };
  double a = t0, b = t1, fa = f0;
  for (int it = 0; it < 200 && b - a > 1e-15 * std::abs(b); ++it) {
    const double c = 0.5 * (a + b), fc = f(c);
    if ((fc < 0) == (fa < 0)) {
      a = c;
      fa = fc;
    } else {
      b = c;
    }
  }
  return 0.5 * (a + b);
}

}  // namespace ukdyn::testing

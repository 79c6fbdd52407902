// SPDX-License-Identifier: BSD-3-Clause
// The solution of the error dynamics e'' + 2 zeta omega e' + omega² e = 0 from e(0) = e0,
// e'(0) = e1 (zeta <= 1): what a tracking controller must reproduce.
#pragma once

#include <cmath>

namespace ukdyn::test {

inline double second_order_error(double zeta, double omega, double e0, double e1, double t) {
  if (zeta == 1.0) return (e0 + (e1 + omega * e0) * t) * std::exp(-omega * t);
  const double wd = omega * std::sqrt(1.0 - zeta * zeta), a = zeta * omega;
  return std::exp(-a * t) * (e0 * std::cos(wd * t) + (e1 + a * e0) / wd * std::sin(wd * t));
}

}  // namespace ukdyn::test

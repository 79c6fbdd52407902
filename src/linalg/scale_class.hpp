// SPDX-License-Identifier: BSD-3-Clause
// The class of a scale (not installed): the run's scales of the tolerances (set_run_scales,
// dynamics/projection.hpp; docs/simulation.md, "Scales and tolerances").
#pragma once

#include <cmath>

namespace ukdyn::detail {

// 10^1.5: a scale's class changes where it crosses 10^(3k ± 1.5)
inline constexpr double kScaleClassHalfStep = 31.622776601683793;

// The class of a scale x > 0: 10 times the power of 1000 nearest to x on a logarithmic scale,
// 10 · 1000^k with |log10 x − 3k| <= 1.5. 10 for x in [0.0316, 31.6], where the row gradients
// times the lengths and the speeds of the examples in SI units lie (0.04 to 24); 10^7 for the
// gradient of a row x² + y² − L² times L with L = 1000 mm. A change of units by 10^(3j) moves
// the class by exactly 10^(3j), so that a tolerance relative to the class is unit-free, and a
// model in SI units keeps the tolerances it had in its own units (the projections' default
// 1e-13, relative, is the absolute 1e-12 there). 10 when x is not finite or not > 0. Cost: a
// logarithm and a power.
inline double scale_class(double x) {
  if (!(x > 0.0) || !std::isfinite(x)) return 10.0;
  const double k = std::round(std::log10(x) / 3.0);
  return k == 0.0 ? 10.0 : 10.0 * std::pow(1e3, k);
}

// The unit of an energy E > 0: the power of 1000 nearest to E / 10 on a logarithmic scale, 1 for
// E in [0.316, 316] J, where the energies of the examples in SI units lie (the double four-bars
// 36–39 J, the heavy top 136 J; the work channels of those run under BDF are weighed in it), and
// 10^6 for masses × 10^6. 1 when E is not finite or not > 0. Cost: a logarithm and a power.
inline double energy_class_unit(double E) {
  if (!(E > 0.0) || !std::isfinite(E)) return 1.0;
  const double k = std::round((std::log10(E) - 1.0) / 3.0);
  return k == 0.0 ? 1.0 : std::pow(1e3, k);
}

// The decade of a rate r > 0 (a speed over a length: the inverse of a run's time scale),
// 10^⌊log10 r⌋: 1 for r in [1, 10), where most examples in SI units lie (a 1 m pendulum's
// √(g / ℓ) = 3.1 per second; 0.1 to 43 over the examples). Unlike a class, it moves with every
// change of the time unit by a power of ten (time × 10: exactly / 10). 1 when r is not finite
// or not > 0. Cost: a logarithm and a power.
inline double rate_decade(double r) {
  if (!(r > 0.0) || !std::isfinite(r)) return 1.0;
  const double k = std::floor(std::log10(r));
  return k == 0.0 ? 1.0 : std::pow(10.0, k);
}

}  // namespace ukdyn::detail

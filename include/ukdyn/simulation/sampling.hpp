// SPDX-License-Identifier: BSD-3-Clause
/// @file simulation/sampling.hpp
/// The sample points of an ensemble (docs/ensembles.md): grids (the Cartesian product of axes),
/// random draws (uniform, normal, log-uniform; plain or Latin hypercube) and both together, from
/// a seed. The same design gives the same numbers on every platform and in every front end: the
/// raw 64-bit output of std::mt19937_64 (fixed by the C++ standard) is turned into variates by
/// ukdyn itself (std::uniform_real_distribution, std::normal_distribution and std::shuffle are
/// implementation-defined); the transforms use only +, ×, / and the C library's log, exp and
/// sqrt.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace ukdyn {

/// One axis of a grid: a name and its values, in order.
struct GridAxis {
  std::string name;            ///< a parameter, coordinate, `<coordinate>_dot` or option name
  std::vector<double> values;  ///< the values swept (at least one)
};

/// The law of a random variable.
enum class Distribution {
  kUniform,     ///< uniform on [a, b]
  kNormal,      ///< normal of mean a and standard deviation b
  kLogUniform,  ///< log-uniform on [a, b], 0 < a: exp(uniform(log a, log b))
};

/// A random variable of a design: `name~uniform(a,b)`, `name~normal(mean,sd)`,
/// `name~loguniform(a,b)`.
struct RandomVariable {
  std::string name;                                    ///< what it sets (as GridAxis::name)
  Distribution distribution = Distribution::kUniform;  ///< its law
  double a = 0.0;  ///< the law's first number (uniform, log-uniform: lower end; normal: mean)
  double b = 1.0;  ///< the law's second number (uniform, log-uniform: upper end; normal: sd)
};

/// What to sample: the Cartesian product of `grid` (the first axis varies slowest), each point
/// combined with the same `draws` random draws of `random` (common random numbers: the points
/// of the grid are compared on the same draws), from `seed`.
struct Design {
  std::vector<GridAxis> grid;          ///< the grid's axes (none: one point)
  std::vector<RandomVariable> random;  ///< the random variables (none: no draws)
  std::size_t draws = 0;               ///< draws per grid point (>= 1 when random is not empty)
  std::uint64_t seed = 0;              ///< the seed of std::mt19937_64
  bool latin_hypercube = false;        ///< stratify each variable's draws (Latin hypercube)
};

/// The sample points of a design: one row per sample, one column per name (the grid's axes, then
/// the random variables).
struct DesignTable {
  std::vector<std::string> names;         ///< the columns
  std::vector<std::vector<double>> rows;  ///< one per sample, names.size() values each
};

/// The sample points of `design`: grid points × draws rows, grid point major. A uniform variate
/// is u = (k + 0.5) 2⁻⁵³ with k the top 53 bits of one output of std::mt19937_64(seed), so
/// 0 < u < 1; draw j's variables take consecutive outputs in the order written. Latin hypercube:
/// each variable's draws fall one in each of `draws` equal strata of probability, in an order
/// shuffled by Fisher–Yates on the same generator (u = (stratum + u') / draws). A normal variate
/// is the inverse normal CDF of u (Acklam's approximation refined by one Halley step with erfc:
/// relative error below 1e-15).
/// @throws std::invalid_argument naming the variable: an axis without values, a value that is not
/// finite, a name given twice, random variables without draws (or draws without random
/// variables), b < a (uniform, log-uniform), a <= 0 (log-uniform), sd < 0 (normal), or more than
/// 10⁷ samples (each is a run, with its row in memory). Cost O(samples × variables).
DesignTable make_design(const Design& design);

/// An axis from the command line's text: `name=start:stop:count` (count >= 1 values evenly
/// spaced from start to stop, both included: start + i (stop − start) / (count − 1)) or
/// `name=v1,v2,…`. @throws std::invalid_argument naming the text and the expected form.
GridAxis parse_grid_axis(std::string_view text);

/// A random variable from the command line's text: `name~uniform(a,b)`, `name~normal(mean,sd)`,
/// `name~loguniform(a,b)` (also `log-uniform`). @throws std::invalid_argument naming the text,
/// the laws and the expected form.
RandomVariable parse_random_variable(std::string_view text);

/// The inverse CDF of the standard normal distribution at 0 < p < 1 (the quantile), to a
/// relative error below 1e-15. @throws std::invalid_argument for p outside (0, 1). Cost O(1).
double normal_quantile(double p);

}  // namespace ukdyn

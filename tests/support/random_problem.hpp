// SPDX-License-Identifier: BSD-3-Clause
// Reproducible random constrained problems for tests and benchmarks.
#pragma once

#include <initializer_list>
#include <ostream>
#include <random>
#include <string>

#include <Eigen/Core>
#include <Eigen/SVD>

#include <ukdyn/core/constraint.hpp>
#include <ukdyn/core/nonideal.hpp>
#include <ukdyn/core/system.hpp>

namespace ukdyn::testing {

/// M (n×n SPD), Q (n), A (m×n of rank r), b (m, consistent), C (n).
struct RandomProblem {
  MatrixXd M, A;
  VectorXd Q, b, C;
  Index rank = 0;
};

/// A vector from a list: vec({1.0, 2.0}).
inline VectorXd vec(std::initializer_list<double> values) {
  VectorXd x(Index(values.size()));
  Index i = 0;
  for (double v : values) x[i++] = v;
  return x;
}

/// Standard-normal matrix from a seeded generator.
inline MatrixXd gaussian(Index rows, Index cols, std::mt19937& gen) {
  std::normal_distribution<double> dist;
  MatrixXd X(rows, cols);
  for (Index j = 0; j < cols; ++j) {
    for (Index i = 0; i < rows; ++i) X(i, j) = dist(gen);
  }
  return X;
}

/// A random problem with n coordinates, m rows of rank r <= min(m, n); b = A x0 so that the
/// constraints are consistent; M = R Rᵀ / n + I (condition number of a few tens).
inline RandomProblem random_problem(Index n, Index m, Index r, unsigned seed, bool with_C) {
  std::mt19937 gen(seed);
  RandomProblem p;
  const MatrixXd R = gaussian(n, n, gen);
  p.M = R * R.transpose() / double(n) + MatrixXd::Identity(n, n);
  p.A = (r == m) ? gaussian(m, n, gen) : MatrixXd(gaussian(m, r, gen) * gaussian(r, n, gen));
  p.Q = gaussian(n, 1, gen);
  p.b = p.A * gaussian(n, 1, gen);
  p.C = with_C ? VectorXd(gaussian(n, 1, gen)) : VectorXd(VectorXd::Zero(n));
  p.rank = r;
  return p;
}

/// The problem as a System: constant M and Q, one acceleration-form constraint "A" holding all
/// rows, and a constant non-ideal force "C" when C is non-zero.
inline System make_system(const RandomProblem& p) {
  const Index n = p.M.rows();
  SystemBuilder builder(n);
  builder.mass_matrix(p.M).forces([Q = p.Q](const Eigen::Ref<const VectorXd>&,
                                            const Eigen::Ref<const VectorXd>&, double,
                                            Eigen::Ref<VectorXd> out) { out = Q; });
  if (p.A.rows() > 0) {
    builder.add(acceleration_constraint(
        "A", p.A.rows(),
        [A = p.A, b = p.b](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                           double, Eigen::Ref<MatrixXd> Aout, Eigen::Ref<VectorXd> bout) {
          Aout = A;
          bout = b;
        }));
  }
  if (!p.C.isZero(0.0)) {
    builder.add(NonIdealForce(
        "C", [C = p.C](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                       const IdealForceInfo&, Eigen::Ref<VectorXd> out) { out = C; }));
  }
  return builder.build();
}

/// An orthonormal basis of the null space of A (columns), by SVD.
inline MatrixXd null_space(const MatrixXd& A, double rel_tol = 1e-10) {
  Eigen::JacobiSVD<MatrixXd> svd(A, Eigen::ComputeFullV);
  const VectorXd& s = svd.singularValues();
  Index r = 0;
  while (r < s.size() && s[r] > rel_tol * s[0]) ++r;
  return svd.matrixV().rightCols(A.cols() - r);
}

/// Sizes of a random problem: n coordinates, m rows of rank r (parameter of sized tests).
struct Case {
  Index n, m, r;
};
inline void PrintTo(const Case& c, std::ostream* os) {
  *os << "(n, m, rank) = (" << c.n << ", " << c.m << ", " << c.r << ")";
}
/// Test-name generator for INSTANTIATE_TEST_SUITE_P over Case: "n6_m3_r2".
struct CaseName {
  template <class Info>
  std::string operator()(const Info& info) const {
    return "n" + std::to_string(info.param.n) + "_m" + std::to_string(info.param.m) + "_r" +
           std::to_string(info.param.r);
  }
};

/// ‖X − Y‖_F / max(‖Y‖_F, floor): the relative difference of two matrices.
inline double rel_diff(const MatrixXd& X, const MatrixXd& Y, double floor = 1e-300) {
  return (X - Y).norm() / std::max(Y.norm(), floor);
}

}  // namespace ukdyn::testing

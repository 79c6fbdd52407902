// SPDX-License-Identifier: BSD-3-Clause
// A particle pendulum in Cartesian coordinates (x, y) of mass m on a rod of length L about the
// origin, gravity g = 9.81 along −y: the rod is a physical constraint (x² + y² − L²) / (2L) = 0.
#pragma once

#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/system.hpp"

namespace ukdyn::test {

inline System cartesian_pendulum(double m, double L) {
  constexpr double kG = 9.81;
  return SystemBuilder({"x", "y"})
      .mass_matrix(m * MatrixXd::Identity(2, 2))
      .forces([m](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                  Eigen::Ref<VectorXd> Q) { Q << 0.0, -m * kG; })
      .potential_energy([m](const Eigen::Ref<const VectorXd>& q, double) { return m * kG * q[1]; })
      .add(holonomic("rod", 1,
                     [L](const auto& q, const auto&, auto& phi) {
                       phi[0] = (q[0] * q[0] + q[1] * q[1] - L * L) / (2 * L);
                     }))
      .build();
}

}  // namespace ukdyn::test

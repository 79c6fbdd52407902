// SPDX-License-Identifier: BSD-3-Clause
// x'' = −x (unit mass and stiffness), one coordinate: x = cos t from (1, 0), energy ½ x'² + ½ x².
#pragma once

#include "ukdyn/core/system.hpp"

namespace ukdyn::test {

inline System oscillator() {
  return SystemBuilder({"x"})
      .mass_matrix(MatrixXd::Identity(1, 1))
      .forces([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q[0] = -q[0]; })
      .potential_energy(
          [](const Eigen::Ref<const VectorXd>& q, double) { return 0.5 * q[0] * q[0]; })
      .build();
}

}  // namespace ukdyn::test

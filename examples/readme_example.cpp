// SPDX-License-Identifier: BSD-3-Clause
// The example of README.md: a block sliding down a rough incline (Coulomb friction as a
// non-ideal constraint). Kept compiling and running as a test so the README stays true.
#include <cmath>
#include <cstdio>
#include <ukdyn/ukdyn.hpp>

int main() {
  const double m = 2.0, g = 9.81, alpha = 0.5, mu = 0.3;
  ukdyn::System sys =
      ukdyn::SystemBuilder({"x", "y"})
          .mass_matrix(m * Eigen::Matrix2d::Identity())
          .forces([=](const auto&, const auto&, double, Eigen::Ref<Eigen::VectorXd> Q) {
            Q << 0, -m * g;
          })
          .add(ukdyn::holonomic("plane", 1,
                                [=](const auto& q, const auto&, auto& phi) {
                                  phi[0] = q[1] +
                                           q[0] * std::tan(alpha);  // the incline y = -x tan(alpha)
                                }))
          .add(ukdyn::coulomb_friction({.constraint = "plane", .mu = mu}))
          .build();
  ukdyn::Workspace ws(sys);
  Eigen::VectorXd q(2), qd(2);
  q << 0, 0;
  qd << std::cos(alpha), -std::sin(alpha);  // 1 m/s down the slope
  ukdyn::forward_dynamics(sys, ws, q, qd, 0.0);
  ukdyn::throw_if_failed(sys, ws);
  std::printf("acceleration along the slope %.6f (g(sin a - mu cos a) = %.6f)\n",
              ws.qdd[0] * std::cos(alpha) - ws.qdd[1] * std::sin(alpha),
              g * (std::sin(alpha) - mu * std::cos(alpha)));
  std::printf("normal force %.6f N, friction %.6f N\n", ws.Qc_ideal.norm(), ws.Qc_nonideal.norm());
}

// SPDX-License-Identifier: BSD-3-Clause
// The built-in example: a pendulum in Cartesian coordinates (x, y), a rod of length L as a
// holonomic constraint, and viscous friction in the pivot as a non-ideal constraint.
// Prints the constrained acceleration, the ideal and non-ideal constraint forces, and the
// same quantities from closed form.
#include <cmath>
#include <cstdio>

#include <ukdyn/ukdyn.hpp>

int main() {
  const double m = 1.0, L = 1.0, g = 9.81, c = 0.2;  // kg, m, m/s², N·s/m
  const double theta = 0.6, theta_dot = 1.5;         // rad from the downward vertical, rad/s

  // M q'' = Q with q = (x, y): M = m I, Q = (0, −m g); rod x² + y² − L² = 0; C = −c q'
  ukdyn::System sys =
      ukdyn::SystemBuilder({"x", "y"})
          .mass_matrix(m * Eigen::Matrix2d::Identity())
          .forces([=](const auto&, const auto&, double, Eigen::Ref<Eigen::VectorXd> Q) {
            Q << 0.0, -m * g;
          })
          .add(ukdyn::holonomic("rod", 1,
                                [=](const auto& q, const auto&, auto& phi) {
                                  phi[0] = q[0] * q[0] + q[1] * q[1] - L * L;
                                }))
          .add(ukdyn::viscous_friction({.coefficient = c, .coordinates = {}, .name = "pivot"}))
          .build();

  Eigen::VectorXd q(2), qd(2);
  q << L * std::sin(theta), -L * std::cos(theta);
  qd << L * std::cos(theta) * theta_dot, L * std::sin(theta) * theta_dot;

  ukdyn::Workspace ws(sys);
  ukdyn::forward_dynamics(sys, ws, q, qd, 0.0);
  ukdyn::throw_if_failed(sys, ws);

  // closed form: tension m (g cos θ + L θ'²) toward the pivot; θ'' = −(g/L) sin θ − c θ' / m
  const double tension = m * (g * std::cos(theta) + L * theta_dot * theta_dot);
  const double theta_ddot = -(g / L) * std::sin(theta) - c * theta_dot / m;
  std::printf("ukdyn pendulum demo: m = %g kg, L = %g m, theta = %g rad, theta' = %g rad/s\n", m, L,
              theta, theta_dot);
  std::printf("  q''          = (% .12f, % .12f) m/s^2\n", ws.qdd[0], ws.qdd[1]);
  std::printf("  Qc_ideal     = (% .12f, % .12f) N   |Qc_ideal| = %.12f N (closed form %.12f)\n",
              ws.Qc_ideal[0], ws.Qc_ideal[1], ws.Qc_ideal.norm(), tension);
  std::printf("  Qc_nonideal  = (% .12f, % .12f) N   (viscous pivot friction, c = %g)\n",
              ws.Qc_nonideal[0], ws.Qc_nonideal[1], c);
  std::printf("  theta''      = % .12f rad/s^2 (closed form % .12f)\n",
              (ws.qdd[0] * std::cos(theta) + ws.qdd[1] * std::sin(theta)) / L, theta_ddot);
  std::printf("  rank(A) = %ld, |A q'' - b| = %.3e, Gauss residual = %.3e, virtual work = %.3e\n",
              long(ws.rank), ws.residuals.constraint, ws.residuals.gauss,
              ws.residuals.virtual_work);
  return 0;
}

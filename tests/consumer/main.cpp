// SPDX-License-Identifier: BSD-3-Clause
// A consumer of the installed package (tests/consumer/CMakeLists.txt): a pendulum in Cartesian
// coordinates released at rest from theta0, simulated for a quarter period, checked against
// analysis. Returns 1 on any failure.
//
//   quarter period  T/4 = sqrt(L/g) K(k),  k = sin(theta0 / 2)   (complete elliptic integral K)
//   at T/4 the bob is at the bottom: x = 0, y = -L, speed sqrt(2 g L (1 - cos theta0))
//   rod tension at the bottom: m g (3 - 2 cos theta0)
#include <cmath>
#include <cstdio>
#include <numbers>

#include <ukdyn/ukdyn.hpp>

namespace {

int failures = 0;

// two-sided: |actual - expected| <= tol (a NaN fails)
void expect_near(const char* what, double actual, double expected, double tol) {
  const bool ok = std::abs(actual - expected) <= tol;
  std::printf("%-28s %.12f (expected %.12f, tolerance %.1e) %s\n", what, actual, expected, tol,
              ok ? "ok" : "FAILED");
  if (!ok) ++failures;
}

// K(k) = pi / (2 AGM(1, sqrt(1 - k^2)))
double elliptic_k(double k) {
  double a = 1.0, b = std::sqrt(1.0 - k * k);
  for (int i = 0; i < 30 && std::abs(a - b) > 1e-16 * a; ++i) {
    const double an = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = an;
  }
  return std::numbers::pi / (2.0 * a);
}

}  // namespace

int main() {
  const double m = 1.5, L = 0.8, g = 9.81, theta0 = 1.2;  // kg, m, m/s², rad from the vertical

  // M q'' = Q with q = (x, y): M = m I, Q = (0, −m g); the rod x² + y² − L² = 0
  const ukdyn::System sys = ukdyn::SystemBuilder({"x", "y"})
                                .mass_matrix(m * Eigen::Matrix2d::Identity())
                                .forces([=](const auto&, const auto&, double,
                                            Eigen::Ref<Eigen::VectorXd> Q) { Q << 0.0, -m * g; })
                                .add(ukdyn::holonomic("rod", 1,
                                                      [=](const auto& q, const auto&, auto& phi) {
                                                        phi[0] = q[0] * q[0] + q[1] * q[1] - L * L;
                                                      }))
                                .build();

  Eigen::VectorXd q0(2), qd0(2);
  q0 << L * std::sin(theta0), -L * std::cos(theta0);
  qd0 << 0.0, 0.0;

  // simulate to the quarter period
  const double quarter = std::sqrt(L / g) * elliptic_k(std::sin(theta0 / 2.0));
  ukdyn::SimulationOptions options;
  options.t_end = quarter;
  options.rtol = 1e-11;
  options.atol = 1e-13;
  const ukdyn::Trajectory tr = ukdyn::simulate(sys, q0, qd0, options);
  const std::size_t last = tr.t.size() - 1;
  const double x = tr.q[2 * last], y = tr.q[2 * last + 1];
  const double xd = tr.qd[2 * last], yd = tr.qd[2 * last + 1];
  expect_near("t_end", tr.t[last], quarter, 1e-12);
  expect_near("x(T/4) [m]", x, 0.0, 1e-9);
  expect_near("y(T/4) [m]", y, -L, 1e-9);
  expect_near("speed(T/4) [m/s]", std::hypot(xd, yd),
              std::sqrt(2.0 * g * L * (1.0 - std::cos(theta0))), 1e-9);

  // the rod's tension at the bottom: the ideal constraint force there
  Eigen::VectorXd qb(2), qdb(2);
  const double vb = std::sqrt(2.0 * g * L * (1.0 - std::cos(theta0)));
  qb << 0.0, -L;
  qdb << -vb, 0.0;
  const double tension = m * g * (3.0 - 2.0 * std::cos(theta0));
  ukdyn::Workspace ws(sys);
  ukdyn::forward_dynamics(sys, ws, qb, qdb, 0.0);
  ukdyn::throw_if_failed(sys, ws);
  expect_near("tension, bottom [N]", ws.Qc_ideal.norm(), tension, 1e-9 * tension);

#ifdef UKDYN_CONSUMER_TEXTBOOK
  // the textbook engine, from the installed ukdyn::reference objects
  ukdyn::SolverOptions textbook;
  textbook.algorithm = ukdyn::Algorithm::kTextbook;
  ukdyn::Workspace wt(sys, textbook);
  ukdyn::forward_dynamics(sys, wt, qb, qdb, 0.0);
  ukdyn::throw_if_failed(sys, wt);
  expect_near("tension, textbook [N]", wt.Qc_ideal.norm(), tension, 1e-9 * tension);
#endif

  std::printf("%s\n", failures == 0 ? "consumer: all checks passed" : "consumer: FAILED");
  return failures == 0 ? 0 : 1;
}

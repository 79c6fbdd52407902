// SPDX-License-Identifier: BSD-3-Clause
// The gallery of model files (examples/models/*.yaml): each model runs and meets a physical
// invariant or a closed-form value.
//
// Every model is read from its file with load_model and run with the settings of its own
// `simulate:` section (the test says so where it changes them); physical parameters are read
// from the file, not repeated here. The reference numbers come from analysis (closed forms, the
// complete elliptic integral by the arithmetic-geometric mean, quadratures, reduced equations
// integrated here) or from an independent description of the same system (the C++ gallery,
// gallery/gallery.hpp), never from the model under test.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/gallery/gallery.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/ukdyn.hpp"

#include "support/hermite_root.hpp"
#include "support/model_output.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kPi = std::numbers::pi;

Model load_example(const std::string& name, const std::map<std::string, double>& set = {}) {
  return load_model(std::string(UKDYN_EXAMPLES_DIR) + "/" + name + ".yaml", set);
}

// sample i of a field stored N × width
Eigen::Map<const VectorXd> at(const std::vector<double>& f, Index width, Index i) {
  return {f.data() + i * width, width};
}

// the model run with its own settings; the run must reach t_end
Trajectory run(const Model& m) {
  Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  EXPECT_EQ(tr.stats.status, Status::kOk) << m.file << ": " << tr.stats.message;
  EXPECT_NEAR(tr.t.back(), m.options.t_end, 1e-12) << m.file;
  return tr;
}

using testing::output;  // support/model_output.hpp

// largest |f_i| over the samples
double max_abs(const std::vector<double>& f) {
  double worst = 0.0;
  for (double v : f) worst = std::max(worst, std::abs(v));
  return worst;
}

// largest |f_i − f_0|
double max_change(const std::vector<double>& f) {
  double worst = 0.0;
  for (double v : f) worst = std::max(worst, std::abs(v - f.front()));
  return worst;
}

using testing::hermite_root;  // support/hermite_root.hpp

// times where coordinate j's velocity changes sign, located on the Hermite interpolant of q'_j
// (with q''_j from the samples)
std::vector<double> velocity_zeros(const Trajectory& tr, Index j) {
  std::vector<double> roots;
  const Index n = tr.n;
  for (Index i = 0; i + 1 < tr.samples(); ++i) {
    const double f0 = at(tr.qd, n, i)[j], f1 = at(tr.qd, n, i + 1)[j];
    if ((f0 > 0 && f1 <= 0) || (f0 < 0 && f1 >= 0)) {
      roots.push_back(hermite_root(tr.t[std::size_t(i)], tr.t[std::size_t(i + 1)], f0, f1,
                                   at(tr.qdd, n, i)[j], at(tr.qdd, n, i + 1)[j]));
    }
  }
  return roots;
}

// classical RK4 of s' = f(s) from s over [0, t_end] with n_steps steps
template <int N>
Eigen::Matrix<double, N, 1> rk4(
    const std::function<Eigen::Matrix<double, N, 1>(const Eigen::Matrix<double, N, 1>&)>& f,
    Eigen::Matrix<double, N, 1> s, double t_end, long n_steps) {
  const double h = t_end / double(n_steps);
  for (long i = 0; i < n_steps; ++i) {
    const auto k1 = f(s), k2 = f(s + h / 2 * k1), k3 = f(s + h / 2 * k2), k4 = f(s + h * k3);
    s += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// every file

TEST(ExampleModels, EveryFileLoadsAndChecksClean) {
  // every model file of the directory (those tested below and any added later)
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(UKDYN_EXAMPLES_DIR)) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    ++count;
    const Model m = load_model(entry.path().string());
    const CheckReport r = check_model(m);
    EXPECT_TRUE(r.ok()) << (r.problems.empty() ? "" : r.problems.front());
    // a file that asks for projection may start slightly off the constraints
    if (!m.project_initial) {
      EXPECT_TRUE(r.initial_violations.empty());
    }
    EXPECT_TRUE(r.mass_positive_definite);
    // (a fully driven mechanism has none, and so has the cam's follower while its contact is
    // closed: its one coordinate is the cam's lift until the contact opens)
    if (entry.path().stem() != "slider_crank" && entry.path().stem() != "cam_follower_jump") {
      EXPECT_GE(r.degrees_of_freedom, 1);
    }
  }
  EXPECT_GE(count, 11);
  for (const char* name :
       {"pendulum", "double_pendulum", "bead_on_rotating_wire", "incline_friction",
        "four_bar_friction", "spherical_pendulum", "chaplygin_sleigh", "rolling_disk",
        "block_slide_stick", "double_four_bar", "double_four_bar_redundant"}) {
    EXPECT_TRUE(std::filesystem::exists(std::string(UKDYN_EXAMPLES_DIR) + "/" + name + ".yaml"))
        << name;
  }
}

// ---------------------------------------------------------------------------------------------
// pendulum.yaml: released horizontally, back at the start after one period

TEST(ExampleModels, PendulumPeriodIsTheEllipticIntegralAndTheRodTensionThreeMgCos) {
  const Model m = load_example("pendulum");
  const double mass = m.parameters.at("m"), L = m.parameters.at("L"), g = m.parameters.at("g");
  // amplitude 90°: T = 4 sqrt(L/g) K(sin 45°); the file runs exactly one period
  const double period = 4 * std::sqrt(L / g) * std::comp_ellint_1(std::sin(kPi / 4));
  EXPECT_NEAR(m.options.t_end, period, 1e-11);  // the file holds 13 digits
  const Trajectory tr = run(m);
  const Index N = tr.samples();
  // y' changes sign at the bottom (T/4, 3T/4) and at the far turning point (−L, 0) (T/2); the
  // run ends at T, back at (L, 0) at rest
  std::vector<double> turns;
  for (double t : velocity_zeros(tr, 1)) {
    if (t < period - 0.05) turns.push_back(t);
  }
  ASSERT_EQ(turns.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(turns[k], double(k + 1) * period / 4, 1e-9 * period) << k;
  }
  EXPECT_NEAR((at(tr.q, 2, N - 1) - Eigen::Vector2d(L, 0)).norm(), 0.0, 1e-8);
  EXPECT_NEAR(at(tr.qd, 2, N - 1).norm(), 0.0, 1e-7);
  // tension 3 m g cos(theta) toward the pivot: the multiplier of the unit-gradient rod is
  // lambda = −3 m g cos(theta) = 3 m g y / L; E = 0 (V = m g y from the pivot)
  double tension_error = 0.0;
  for (Index i = 0; i < N; ++i) {
    tension_error = std::max(
        tension_error, std::abs(tr.lambda[std::size_t(i)] - 3 * mass * g * at(tr.q, 2, i)[1] / L));
  }
  EXPECT_NEAR(tension_error / (mass * g), 0.0, 1e-8);
  EXPECT_NEAR(max_abs(tr.energy) / (mass * g * L), 0.0, 1e-9);
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-11);
}

// ---------------------------------------------------------------------------------------------
// double_pendulum.yaml: chaotic, but energy and rods are kept, and the first seconds match the
// textbook equations of two point masses integrated here

// the double pendulum in the angles th1, th2 from the downward vertical (point masses):
//   (m1 + m2) L1 th1'' + m2 L2 th2'' cos d + m2 L2 th2'² sin d + (m1 + m2) g sin th1 = 0
//   L2 th2'' + L1 th1'' cos d − L1 th1'² sin d + g sin th2 = 0,       d = th1 − th2
Eigen::Vector4d double_pendulum_rates(const Eigen::Vector4d& s, double m1, double m2, double L1,
                                      double L2, double g) {
  const double d = s[0] - s[1], c = std::cos(d), sn = std::sin(d);
  // [a11 a12; a21 a22] (th1'', th2'') = (r1, r2), solved by Cramer's rule
  const double a11 = (m1 + m2) * L1, a12 = m2 * L2 * c, a21 = L1 * c, a22 = L2;
  const double r1 = -m2 * L2 * s[3] * s[3] * sn - (m1 + m2) * g * std::sin(s[0]);
  const double r2 = L1 * s[2] * s[2] * sn - g * std::sin(s[1]);
  const double det = a11 * a22 - a12 * a21;
  return {s[2], s[3], (r1 * a22 - a12 * r2) / det, (a11 * r2 - a21 * r1) / det};
}

TEST(ExampleModels, DoublePendulumKeepsEnergyAndRodsAndFollowsTheAngleEquations) {
  const Model m = load_example("double_pendulum");
  const double m1 = m.parameters.at("m1"), m2 = m.parameters.at("m2"), L1 = m.parameters.at("L1"),
               L2 = m.parameters.at("L2"), g = m.parameters.at("g");
  const Trajectory tr = run(m);
  // released at rest with both rods horizontal: the rods are slack, free fall
  EXPECT_NEAR((at(tr.qdd, 4, 0) - Eigen::Vector4d(0, -g, 0, -g)).norm(), 0.0, 1e-12);
  // E = 0 at the start (y = 0); the scale is the largest kinetic energy reachable,
  // g (m1 L1 + m2 (L1 + L2))
  const double scale = g * (m1 * L1 + m2 * (L1 + L2));
  EXPECT_NEAR(max_abs(tr.energy) / scale, 0.0, 1e-8);
  // both rods kept (violations in metres)
  for (Index k = 0; k < 2; ++k) {
    double worst = 0.0;
    for (Index i = 0; i < tr.samples(); ++i) {
      worst = std::max(worst, tr.position_violation[std::size_t(i * 2 + k)]);
    }
    EXPECT_NEAR(worst, 0.0, 1e-10) << k;
  }
  // the first two seconds against the angle equations (RK4, h = 1e-4 s), from
  // th1 = th2 = 90°: the tips at t = 1 s and 2 s (the motion is chaotic after that)
  for (double t : {1.0, 2.0}) {
    const Index i = Index(std::lround(t / m.options.output_every));
    ASSERT_NEAR(tr.t[std::size_t(i)], t, 1e-12);
    const Eigen::Vector4d s = rk4<4>(
        [&](const Eigen::Vector4d& x) { return double_pendulum_rates(x, m1, m2, L1, L2, g); },
        Eigen::Vector4d(kPi / 2, kPi / 2, 0, 0), t, std::lround(t / 1e-4));
    const Eigen::Vector2d tip1(L1 * std::sin(s[0]), -L1 * std::cos(s[0]));
    const Eigen::Vector2d tip2 = tip1 + Eigen::Vector2d(L2 * std::sin(s[1]), -L2 * std::cos(s[1]));
    EXPECT_NEAR((at(tr.q, 4, i).head<2>() - tip1).norm(), 0.0, 1e-8) << t;
    EXPECT_NEAR((at(tr.q, 4, i).tail<2>() - tip2).norm(), 0.0, 1e-8) << t;
  }
}

// ---------------------------------------------------------------------------------------------
// bead_on_rotating_wire.yaml: r(t) = r0 cosh(W t) + (rd0/W) sinh(W t), Coriolis force 2 m W r'

TEST(ExampleModels, BeadOnRotatingWireFollowsCoshSinhAndFeelsTheCoriolisForce) {
  const Model m = load_example("bead_on_rotating_wire");
  const double mass = m.parameters.at("m"), W = m.parameters.at("Omega"),
               r0 = m.parameters.at("r0"), rd0 = m.parameters.at("rd0");
  const Trajectory tr = run(m);
  double r_err = 0.0, across = 0.0, force_err = 0.0, along_force = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    const Eigen::Vector2d u(std::cos(W * t), std::sin(W * t)), n(-u.y(), u.x());
    const double r = r0 * std::cosh(W * t) + rd0 / W * std::sinh(W * t);
    const double rd = r0 * W * std::sinh(W * t) + rd0 * std::cosh(W * t);
    const auto q = at(tr.q, 2, i);
    const auto Qc = at(tr.Qc_ideal, 2, i);
    r_err = std::max(r_err, std::abs(q.dot(u) - r) / r);
    across = std::max(across, std::abs(q.dot(n)));
    force_err = std::max(force_err, std::abs(Qc.dot(n) - 2 * mass * W * rd));
    along_force = std::max(along_force, std::abs(Qc.dot(u)));
  }
  EXPECT_NEAR(r_err, 0.0, 1e-9);
  EXPECT_NEAR(across, 0.0, 1e-11);
  EXPECT_NEAR(force_err / (mass * W * rd0), 0.0, 1e-8);
  EXPECT_NEAR(along_force / (mass * W * rd0), 0.0, 1e-8);
  // the file's own check, r_error = r − closed form
  EXPECT_NEAR(max_abs(output(m, tr, "r_error")), 0.0, 1e-9);
}

// ---------------------------------------------------------------------------------------------
// incline_friction.yaml: sliding down, s'' = g (sin a − mu cos a)

TEST(ExampleModels, InclineFrictionSlidesAtGTimesSinMinusMuCos) {
  const Model m = load_example("incline_friction");
  const double mass = m.parameters.at("m"), g = m.parameters.at("g"), a = m.parameters.at("alpha"),
               mu = m.parameters.at("mu"), v0 = m.parameters.at("v0");
  const double acc = g * (std::sin(a) - mu * std::cos(a));
  ASSERT_GT(acc, 0.0);  // mu < tan(alpha): it never stops
  const Trajectory tr = run(m);
  const Eigen::Vector2d down(std::cos(a), -std::sin(a)), normal(std::sin(a), std::cos(a));
  double s_err = 0.0, v_err = 0.0, normal_err = 0.0, friction_err = 0.0, balance = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    const double s = v0 * t + 0.5 * acc * t * t;
    s_err = std::max(s_err, std::abs(at(tr.q, 2, i).dot(down) - s));
    v_err = std::max(v_err, std::abs(at(tr.qd, 2, i).dot(down) - (v0 + acc * t)));
    // the plane pushes m g cos(a) along its normal, friction mu m g cos(a) up the slope
    normal_err =
        std::max(normal_err, std::abs(at(tr.Qc_ideal, 2, i).dot(normal) - mass * g * std::cos(a)));
    friction_err = std::max(
        friction_err, std::abs(at(tr.Qc_nonideal, 2, i).dot(down) + mu * mass * g * std::cos(a)));
    // the work of friction, −mu m g cos(a) s, is the whole change of E
    const double W = -mu * mass * g * std::cos(a) * s;
    EXPECT_NEAR(tr.work_nonideal[std::size_t(i)], W, 1e-8 * (1 + std::abs(W))) << t;
    balance = std::max(balance, std::abs(tr.energy[std::size_t(i)] - tr.energy[0] - W));
  }
  EXPECT_NEAR(s_err, 0.0, 1e-9);
  EXPECT_NEAR(v_err, 0.0, 1e-9);
  EXPECT_NEAR(normal_err, 0.0, 1e-9);
  EXPECT_NEAR(friction_err, 0.0, 1e-9);
  EXPECT_NEAR(balance, 0.0, 1e-8);
  EXPECT_NEAR(max_abs(output(m, tr, "s_error")), 0.0, 1e-9);
}

// ---------------------------------------------------------------------------------------------
// four_bar_friction.yaml: E − E(0) − W = 0 with W the work of the pin friction; and, with the
// friction set to zero, the shared benchmark P2 (the same crank-rocker) from its start

TEST(ExampleModels, FourBarFrictionBalancesEnergyWithThePinWorkAndKeepsTheLoopClosed) {
  const Model m = load_example("four_bar_friction");
  const double lc = m.parameters.at("lc"), c = m.parameters.at("c"), mu = m.parameters.at("mu_pin"),
               r_pin = m.parameters.at("r_pin"), eps = m.parameters.at("eps");
  const Trajectory tr = run(m);
  const Index N = tr.samples();
  // the energy scale: the kinetic energy at the start
  const double scale = tr.kinetic_energy[0];
  ASSERT_GT(scale, 0.1);
  double balance = 0.0, power_err = 0.0, closure = 0.0;
  Workspace ws(m.system);
  for (Index i = 0; i < N; ++i) {
    const VectorXd q = at(tr.q, 4, i), qd = at(tr.qd, 4, i);
    balance = std::max(balance, std::abs(tr.energy[std::size_t(i)] - tr.energy[0] -
                                         tr.work_nonideal[std::size_t(i)]));
    // the power of the non-ideal force is that of the pin torque,
    //   tau w = −(c w + mu r_pin N sgn_eps(w)) w,  w the crank's rate, N the crank pin's whole
    // reaction (its ideal share and what the friction itself causes: Workspace::reactions, by
    // an evaluation at the sample)
    const double w = (q[0] * qd[1] - q[1] * qd[0]) / (lc * lc);
    ASSERT_EQ(forward_dynamics(m.system, ws, q, qd, tr.t[std::size_t(i)]), Status::kOk);
    const double N_crank = ws.reactions.col(m.system.constraint_index("crank")).norm();
    const double tau = -(c * w + mu * r_pin * N_crank * w / std::sqrt(w * w + eps * eps));
    power_err = std::max(power_err, std::abs(qd.dot(at(tr.Qc_nonideal, 4, i)) - tau * w));
    closure = std::max(closure, at(tr.position_violation, 3, i).maxCoeff());
    if (i > 0) {
      // friction only dissipates
      EXPECT_LE(tr.work_nonideal[std::size_t(i)], tr.work_nonideal[std::size_t(i - 1)] + 1e-12);
    }
  }
  // measured 1.1e-8 (dopri5 at the file's rtol 1e-9)
  EXPECT_NEAR(balance / scale, 0.0, 1e-7);
  EXPECT_NEAR(power_err / scale, 0.0, 1e-9);
  EXPECT_NEAR(closure, 0.0, 1e-10);
  // the friction drained a visible part of the energy (W(T) < 0 by more than 1% of T(0))
  EXPECT_LT(tr.work_nonideal.back(), -0.01 * scale);
}

TEST(ExampleModels, FourBarWithoutFrictionIsTheSharedBenchmarkP2) {
  // P2 is this crank-rocker (same rods, pivots and uniform mass) released at rest at 150°;
  // with c = mu_pin = 0 and P2's start and protocol (RK4, h = 1e-3, T = 10 s) the crank angle
  // lands on the reference of bench/data (an accuracy-1e-10 run of another engine)
  Model m = load_example("four_bar_friction", {{"c", 0.0}, {"mu_pin", 0.0}});
  const auto info = gallery::shared_problem("shared_P2");
  const auto p2 = gallery::shared_P2();
  m.options.integrator = Integrator::kRK4;
  m.options.step = 1e-3;
  m.options.t_end = info.T;
  m.options.output_every = 0.1;
  m.options.project_initial = false;
  const Trajectory tr = simulate(m.system, p2.q0, p2.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_NEAR(tr.t.back(), info.T, 1e-12);
  EXPECT_NEAR(gallery::reported_coordinate("shared_P2", at(tr.q, 4, tr.samples() - 1)),
              info.reference_coordinate, 1e-6);
  // no friction: E is conserved (scale: E(0) above the equilibrium, the largest kinetic energy)
  const double E0 = p2.system.potential_energy(p2.q0, 0.0);
  EXPECT_NEAR(max_change(tr.energy) / E0, 0.0, 1e-7);
  EXPECT_NEAR(max_abs(tr.work_nonideal), 0.0, 1e-15);
}

// ---------------------------------------------------------------------------------------------
// spherical_pendulum.yaml: E and the vertical angular momentum conserved; the height swings
// between the roots of the cubic and takes the quadrature's time to do it

TEST(ExampleModels, SphericalPendulumConservesEnergyAndLzAndSwingsBetweenTheCubicsRoots) {
  const Model m = load_example("spherical_pendulum");
  const double mass = m.parameters.at("m"), L = m.parameters.at("L"), g = m.parameters.at("g"),
               th0 = m.parameters.at("theta0"), v0 = m.parameters.at("v0");
  const Trajectory tr = run(m);
  const Index N = tr.samples();
  // invariants: E = m v0²/2 − m g L cos(theta0), Lz = m L sin(theta0) v0
  const double E = 0.5 * mass * v0 * v0 - mass * g * L * std::cos(th0);
  const double Lz = mass * L * std::sin(th0) * v0;
  double E_err = 0.0, Lz_err = 0.0;
  for (Index i = 0; i < N; ++i) {
    const auto q = at(tr.q, 3, i), qd = at(tr.qd, 3, i);
    E_err = std::max(E_err, std::abs(tr.energy[std::size_t(i)] - E));
    Lz_err = std::max(Lz_err, std::abs(mass * (q[0] * qd[1] - q[1] * qd[0]) - Lz));
  }
  EXPECT_NEAR(E_err / std::abs(E), 0.0, 1e-8);
  EXPECT_NEAR(Lz_err / Lz, 0.0, 1e-8);
  EXPECT_NEAR(max_abs(output(m, tr, "Lz")) / Lz, 1.0, 1e-8);
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-11);
  EXPECT_NEAR(tr.stats.max_velocity_violation, 0.0, 1e-11);

  // with e = E/m, h = Lz/m:
  //   L² z'² = f(z) = 2 (e − g z)(L² − z²) − h² = 2 g (z − z0)(z − z1)(z − z2);
  // z0 = −L cos(theta0) is a root (z' = 0 there); deflating the cubic gives the others
  const double e = E / mass, h = Lz / mass, z0 = -L * std::cos(th0);
  // f / (2 g) = z³ − (e/g) z² − L² z + (e L² − h²/2) / g = (z − z0)(z² + p z + r)
  const double p = z0 - e / g, r = z0 * p - L * L;
  ASSERT_NEAR(z0 * r + (e * L * L - h * h / 2) / g, 0.0, 1e-12);  // z0 is a root
  const double disc = std::sqrt(p * p - 4 * r);
  const double z1 = std::min(0.5 * (-p - disc), 0.5 * (-p + disc)),
               z2 = std::max(0.5 * (-p - disc), 0.5 * (-p + disc));
  ASSERT_GT(z2, L);
  ASSERT_LT(z1, z0);  // v0 below the conical speed: z0 is the top, z1 the bottom
  ASSERT_GT(z1, -L);
  // the time from top to bottom: t = ∫ L dz / sqrt(f(z)) over [z1, z0]; with
  // z = zm + dz sin(u) (zm, dz the middle and half-width) the root singularities cancel:
  //   t = ∫_{−pi/2}^{pi/2} L / sqrt(2 g (z2 − z(u))) du   (smooth: composite Simpson)
  const double zm = 0.5 * (z0 + z1), dz = 0.5 * (z0 - z1);
  const int n = 2000;
  double half = 0.0;
  for (int k = 0; k <= n; ++k) {
    const double u = -kPi / 2 + kPi * k / n;
    const double w = (k == 0 || k == n) ? 1.0 : (k % 2 ? 4.0 : 2.0);
    half += w * L / std::sqrt(2 * g * (z2 - (zm + dz * std::sin(u))));
  }
  half *= kPi / n / 3;
  // z' changes sign at the bottom (half), the top (2 half), …: the turning times and heights
  const std::vector<double> turns = velocity_zeros(tr, 2);
  ASSERT_GE(turns.size(), 3u);
  for (std::size_t k = 0; k < turns.size(); ++k) {
    EXPECT_NEAR(turns[k], double(k + 1) * half, 1e-8) << k;
  }
  // the heights at the turns: z − z'²/(2 z'') at the nearest sample (the vertex of the local
  // parabola)
  double z_low = 0.0, z_high = -L;
  for (double tk : turns) {
    const Index i = Index(std::lround((tk - tr.t[0]) / m.options.output_every));
    const double z = at(tr.q, 3, i)[2], zd = at(tr.qd, 3, i)[2], zdd = at(tr.qdd, 3, i)[2];
    const double extreme = z - zd * zd / (2 * zdd);
    (zdd > 0 ? z_low : z_high) = extreme;
  }
  EXPECT_NEAR(z_low, z1, 1e-7);
  EXPECT_NEAR(z_high, z0, 1e-7);
}

// ---------------------------------------------------------------------------------------------
// chaplygin_sleigh.yaml: v(t) = V tanh(k V t + atanh(v0/V)), w² = (k/a)(V² − v²), T conserved;
// the same system as gallery::chaplygin_sleigh()

TEST(ExampleModels, ChaplyginSleighFollowsTheTanhSolutionLikeTheGalleryOne) {
  const Model m = load_example("chaplygin_sleigh");
  const double mass = m.parameters.at("m"), a = m.parameters.at("a"), I = m.parameters.at("I"),
               w0 = m.parameters.at("w0"), v0 = m.parameters.at("v0");
  const double k = mass * a / (I + mass * a * a);
  const double V = std::sqrt(v0 * v0 + (I + mass * a * a) * w0 * w0 / mass);
  const double T0 = 0.5 * (mass * v0 * v0 + (I + mass * a * a) * w0 * w0);
  const Trajectory tr = run(m);
  double v_err = 0.0, w_err = 0.0, knife = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)], theta = at(tr.q, 3, i)[2];
    const auto qd = at(tr.qd, 3, i);
    const double v = qd[0] * std::cos(theta) + qd[1] * std::sin(theta);
    const double v_exact = V * std::tanh(k * V * t + std::atanh(v0 / V));
    v_err = std::max(v_err, std::abs(v - v_exact));
    // w keeps the sign of w0 (w' = −k v w)
    w_err = std::max(w_err, std::abs(qd[2] - std::sqrt(k / a * (V * V - v_exact * v_exact))));
    knife =
        std::max(knife, std::abs(-qd[0] * std::sin(theta) + qd[1] * std::cos(theta) - a * qd[2]));
  }
  EXPECT_NEAR(v_err, 0.0, 1e-9);
  EXPECT_NEAR(w_err, 0.0, 1e-9);
  EXPECT_NEAR(knife, 0.0, 1e-11);
  // measured 5.4e-10 of T0 at the file's rtol 1e-9
  EXPECT_NEAR(max_change(tr.energy) / T0, 0.0, 5e-9);
  EXPECT_NEAR(tr.energy[0], T0, 1e-14);
  EXPECT_NEAR(max_abs(output(m, tr, "v_error")), 0.0, 1e-9);
  // the gallery's sleigh with these parameters, run with the same options, moves alike
  const auto ex = gallery::chaplygin_sleigh(mass, a, I, w0, v0);
  EXPECT_NEAR((ex.q0 - m.q0).norm(), 0.0, 1e-15);
  EXPECT_NEAR((ex.qd0 - m.qd0).norm(), 0.0, 1e-15);
  const Trajectory ref = simulate(ex.system, ex.q0, ex.qd0, m.options);
  ASSERT_EQ(ref.samples(), tr.samples());
  double diff = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    diff = std::max(diff, (at(tr.q, 3, i) - at(ref.q, 3, i)).norm() +
                              (at(tr.qd, 3, i) - at(ref.qd, 3, i)).norm());
  }
  EXPECT_NEAR(diff, 0.0, 1e-9);
}

// ---------------------------------------------------------------------------------------------
// rolling_disk.yaml: steady circular rolling stays steady

// lean acceleration of the rolling disk at theta' = 0 from Lagrange's theta equation (the
// rolling rows do not act on theta):
//   (m R² + A) theta'' = (m R² + C) psi' w3 cos(theta) − A psi'² sin(theta) cos(theta)
//                        + m g R sin(theta),
// with A = m R²/4, C = m R²/2 and w3 = psi' sin(theta) + phi', i.e.
//   (5/4) R theta'' = (3/2) R psi' w3 cos(theta) − (1/4) R psi'² sin(theta) cos(theta)
//                     + g sin(theta);
// steady rolling (theta'' = 0) at psi' = Omega needs, with s = sin(theta), c = cos(theta),
//   w3 = (R Omega² s c / 4 − g s) / ((3/2) R Omega c)
double disk_lean_acceleration(double R, double g, double theta, double psid, double w3) {
  const double s = std::sin(theta), c = std::cos(theta);
  return (1.5 * R * psid * w3 * c - 0.25 * R * psid * psid * s * c + g * s) / (1.25 * R);
}
double disk_steady_spin(double R, double g, double theta, double Omega) {
  const double s = std::sin(theta), c = std::cos(theta);
  return (0.25 * R * Omega * Omega * s * c - g * s) / (1.5 * R * Omega * c);
}

TEST(ExampleModels, RollingDiskLeanAccelerationMatchesLagrangesThetaEquation) {
  // at a few states with theta' = 0 (steady or not) the model's theta'' is the closed form
  const Model m = load_example("rolling_disk");
  const double R = m.parameters.at("R"), g = m.parameters.at("g");
  Workspace ws(m.system);
  for (auto [theta, psid, phid] :
       {std::array<double, 3>{0.3, -2.0, 2.5}, std::array<double, 3>{-0.7, 3.0, -1.0},
        std::array<double, 3>{1.1, 0.4, 6.0}}) {
    const double psi = 0.8;
    VectorXd q(5), qd(5);
    q << 0.2, -0.1, psi, theta, 1.3;
    qd << R * phid * std::cos(psi), R * phid * std::sin(psi), psid, 0.0, phid;
    ASSERT_EQ(forward_dynamics(m.system, ws, q, qd, 0.0), Status::kOk);
    const double w3 = psid * std::sin(theta) + phid;
    EXPECT_NEAR(ws.qdd[3], disk_lean_acceleration(R, g, theta, psid, w3), 1e-12 * g / R) << theta;
    // rolling: (x'', y'') = d/dt (R phi' t) = R phi'' t + R phi' psi' l
    EXPECT_NEAR(ws.qdd[0], R * ws.qdd[4] * std::cos(psi) - R * phid * psid * std::sin(psi), 1e-12);
    EXPECT_NEAR(ws.qdd[1], R * ws.qdd[4] * std::sin(psi) + R * phid * psid * std::cos(psi), 1e-12);
  }
}

TEST(ExampleModels, RollingDiskSteadyCircleStaysSteadyAndClosesAfterOneTurn) {
  const Model m = load_example("rolling_disk");
  const double mass = m.parameters.at("m"), R = m.parameters.at("R"), g = m.parameters.at("g"),
               th0 = m.parameters.at("theta0"), Omega = m.parameters.at("Omega");
  const double w3 = disk_steady_spin(R, g, th0, Omega);
  const double phid = w3 - Omega * std::sin(th0), speed = R * phid;
  // the file starts in that steady motion and runs one turn of the heading
  VectorXd qd0(5);
  qd0 << speed, 0.0, Omega, 0.0, phid;
  EXPECT_NEAR((m.qd0 - qd0).norm(), 0.0, 1e-13);
  EXPECT_EQ(m.q0[3], th0);
  const double period = 2 * kPi / std::abs(Omega);
  EXPECT_NEAR(m.options.t_end, period, 1e-14);
  const Trajectory tr = run(m);
  const Index N = tr.samples();
  // the contact point runs round the circle of radius |speed/Omega| about (0, speed/Omega)
  // (it moves at speed along t(psi), psi = Omega t)
  const Eigen::Vector2d centre(0.0, speed / Omega);
  double lean = 0.0, lean_rate = 0.0, radius = 0.0, rates = 0.0, angles = 0.0;
  for (Index i = 0; i < N; ++i) {
    const double t = tr.t[std::size_t(i)];
    const auto q = at(tr.q, 5, i), qd = at(tr.qd, 5, i);
    lean = std::max(lean, std::abs(q[3] - th0));
    lean_rate = std::max(lean_rate, std::abs(qd[3]));
    radius = std::max(radius, std::abs((q.head<2>() - centre).norm() - std::abs(speed / Omega)));
    rates = std::max(rates, std::abs(qd[2] - Omega) + std::abs(qd[4] - phid));
    angles = std::max(angles, std::abs(q[2] - Omega * t) + std::abs(q[4] - phid * t));
  }
  EXPECT_NEAR(lean, 0.0, 1e-8);
  EXPECT_NEAR(lean_rate, 0.0, 1e-8);
  EXPECT_NEAR(radius, 0.0, 1e-8);
  EXPECT_NEAR(rates, 0.0, 1e-8);
  EXPECT_NEAR(angles, 0.0, 1e-8);
  // after one turn of the heading the contact point is back where it started
  EXPECT_NEAR(at(tr.q, 5, N - 1).head<2>().norm(), 0.0, 1e-8);
  // E = T + V conserved: T = m speed²/2 + ... evaluated at the start, V = m g R cos(theta0)
  const double T = 0.5 * mass * (std::pow(speed + R * Omega * std::sin(th0), 2)) +
                   0.5 * (mass * R * R / 4) * Omega * Omega * std::cos(th0) * std::cos(th0) +
                   0.5 * (mass * R * R / 2) * w3 * w3;
  EXPECT_NEAR(tr.energy[0], T + mass * g * R * std::cos(th0), 1e-12);
  EXPECT_NEAR(max_change(tr.energy) / T, 0.0, 1e-10);
  EXPECT_NEAR(tr.stats.max_velocity_violation, 0.0, 1e-11);

  // the same steady motion from the test's closed form at a general place and heading (the
  // file starts at psi = 0, where some terms vanish exactly): theta stays at theta0 for five
  // turns and the contact point closes its circle after each (this steady motion is stable: a
  // 1e-6 rad/s kick to theta' stays a ~6e-6 rad wobble)
  const double psi0 = 0.7;
  const Eigen::Vector2d p0(0.3, -0.2);
  VectorXd q(5), qd(5);
  q << p0, psi0, th0, 0.1;
  qd << speed * std::cos(psi0), speed * std::sin(psi0), Omega, 0.0, phid;
  SimulationOptions o = m.options;
  o.t_end = 5 * period;
  o.output_every = period / 4;
  const Trajectory tr5 = simulate(m.system, q, qd, o);
  ASSERT_EQ(tr5.stats.status, Status::kOk) << tr5.stats.message;
  ASSERT_EQ(tr5.samples(), 21);
  double lean5 = 0.0, closure5 = 0.0;
  for (Index i = 0; i < tr5.samples(); ++i) {
    lean5 = std::max(lean5, std::abs(at(tr5.q, 5, i)[3] - th0));
    if (i % 4 == 0) closure5 = std::max(closure5, (at(tr5.q, 5, i).head<2>() - p0).norm());
  }
  EXPECT_NEAR(lean5, 0.0, 1e-8);
  EXPECT_NEAR(closure5, 0.0, 1e-8);
}

// ---------------------------------------------------------------------------------------------
// block_slide_stick.yaml: slides down decelerating at g (mu cos a − sin a), stops, sticks

TEST(ExampleModels, BlockSlidesToTheClosedFormStopThenSticks) {
  const Model m = load_example("block_slide_stick");
  const double mass = m.parameters.at("m"), g = m.parameters.at("g"), a = m.parameters.at("alpha"),
               mu = m.parameters.at("mu"), v0 = m.parameters.at("v0");
  const double decel = g * (mu * std::cos(a) - std::sin(a));
  ASSERT_GT(decel, 0.0);  // tan(alpha) < mu
  const double t_stop = v0 / decel, s_stop = v0 * v0 / (2 * decel);
  ASSERT_LT(t_stop + 0.1, m.options.t_end);
  const Trajectory tr = run(m);
  const Eigen::Vector2d down(std::cos(a), -std::sin(a)), normal(std::sin(a), std::cos(a));
  // sliding: v = v0 − decel t, s = v0 t − decel t²/2; the last sliding sample extrapolates to
  // the stop
  double t_stop_estimate = -1.0, slide_err = 0.0;
  Index i = 0;
  for (; i < tr.samples() && tr.t[std::size_t(i)] < t_stop; ++i) {
    const double t = tr.t[std::size_t(i)];
    const double v = at(tr.qd, 2, i).dot(down), s = at(tr.q, 2, i).dot(down);
    slide_err = std::max(
        slide_err, std::abs(v - (v0 - decel * t)) + std::abs(s - (v0 * t - decel * t * t / 2)));
    t_stop_estimate = t + v / decel;
  }
  EXPECT_NEAR(slide_err, 0.0, 1e-9);
  EXPECT_NEAR(t_stop_estimate, t_stop, 1e-9);
  // one event (the stop; static friction then holds: mu > tan a), and at rest at s_stop from
  // the first sample after the stop to the end
  EXPECT_EQ(tr.stats.events, 1);
  double rest_s = 0.0, rest_v = 0.0, hold_err = 0.0;
  for (; i < tr.samples(); ++i) {
    rest_s = std::max(rest_s, std::abs(at(tr.q, 2, i).dot(down) - s_stop));
    rest_v = std::max(rest_v, at(tr.qd, 2, i).norm());
    // at rest the contact force balances gravity: m g sin(a) up the slope, m g cos(a) normal
    const Eigen::Vector2d R = at(tr.Qc_ideal, 2, i) + at(tr.Qc_nonideal, 2, i);
    hold_err = std::max(hold_err, std::abs(R.dot(down) + mass * g * std::sin(a)) +
                                      std::abs(R.dot(normal) - mass * g * std::cos(a)));
  }
  EXPECT_NEAR(rest_s, 0.0, 1e-8);
  EXPECT_NEAR(rest_v, 0.0, 1e-8);
  EXPECT_NEAR(hold_err / (mass * g), 0.0, 1e-9);
  // E(t) − E(0) = W: friction took mu m g cos(a) s_stop, and nothing after the stop
  EXPECT_NEAR(tr.work_nonideal.back(), -mu * mass * g * std::cos(a) * s_stop, 1e-8);
  EXPECT_NEAR(tr.energy.back() - tr.energy[0], tr.work_nonideal.back(), 1e-8);
}

// ---------------------------------------------------------------------------------------------
// double_four_bar.yaml: IFToMM A02, against the C++ gallery's mechanism and the benchmark value

TEST(ExampleModels, DoubleFourBarMatchesTheGalleryAndTheIFToMMReference) {
  const Model m = load_example("double_four_bar");
  const auto ex = gallery::double_four_bar();
  EXPECT_NEAR((ex.q0 - m.q0).norm(), 0.0, 1e-15);
  EXPECT_NEAR((ex.qd0 - m.qd0).norm(), 0.0, 1e-15);
  const Trajectory tr = run(m);
  const Trajectory ref = simulate(ex.system, ex.q0, ex.qd0, m.options);
  ASSERT_EQ(ref.stats.status, Status::kOk) << ref.stats.message;
  ASSERT_EQ(ref.samples(), tr.samples());
  double diff = 0.0, parallel = 0.0, dE = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const auto q = at(tr.q, 6, i);
    diff = std::max(diff, (q - at(ref.q, 6, i)).norm());
    // a parallelogram: tips 2 and 3 are tip 1 shifted by L and 2 L
    parallel = std::max(parallel, std::abs(q[2] - 1.0 - q[0]) + std::abs(q[4] - 2.0 - q[0]) +
                                      std::abs(q[3] - q[1]) + std::abs(q[5] - q[1]));
    // the same energy (and the same V: pivots at y = 0)
    dE = std::max(dE, std::abs(tr.energy[std::size_t(i)] - ref.energy[std::size_t(i)]));
  }
  EXPECT_NEAR(diff, 0.0, 1e-7);
  EXPECT_NEAR(parallel, 0.0, 1e-9);
  EXPECT_NEAR(dE, 0.0, 1e-9);
  EXPECT_NEAR(max_change(tr.energy) / tr.energy[0], 0.0, 1e-9);
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-10);
  // IFToMM A02: the left crank tip at t = 10 s
  const auto tip = at(tr.q, 6, tr.samples() - 1);
  EXPECT_NEAR(tip[0], 0.32845811, 1e-6);
  EXPECT_NEAR(tip[1], 0.94451854, 1e-6);
}

// ---------------------------------------------------------------------------------------------
// double_four_bar_redundant.yaml: a redundant, massless crank changes nothing

TEST(ExampleModels, RedundantCrankIsNamedByCheckAndLeavesTheMotionUnchanged) {
  const Model m = load_example("double_four_bar_redundant");
  const CheckReport r = check_model(m);
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(r.constraint_rows, 6);
  EXPECT_EQ(r.rank, 5);
  EXPECT_EQ(r.degrees_of_freedom, 1);
  ASSERT_EQ(r.redundant.size(), 1u);
  EXPECT_EQ(r.redundant[0], "crank4");

  const Model plain = load_example("double_four_bar");
  EXPECT_TRUE(check_model(plain).redundant.empty());
  // the same settings (RK4, h = 1e-3): the same steps
  const Trajectory tr = run(m);
  const Trajectory ref = run(plain);
  ASSERT_EQ(ref.samples(), tr.samples());
  // Near the singular poses (cranks horizontal, y1 = 0) the accelerations, forces and the
  // velocity projection of a sample carry a round-off of order eps / sigma_min(A) (see
  // SimulationOptions::rtol), which the extra row changes: at the samples within a few mm of
  // the pose q' differs by up to ~3e-8 m/s and Qc by up to ~1e-6 of its largest value (measured,
  // in different builds, 5e-9 to 3e-8 m/s and 1e-5 to 3e-5 N of 43 N at y1 = −0.003 m); the
  // positions do not feel it (5e-11 m). Away from the poses (|y1| > 0.05 L) the two agree to
  // round-off (measured 4e-10 m/s, 5e-11 of |Qc|).
  double dq = 0.0, dqd_regular = 0.0, dqd_all = 0.0, dQc_regular = 0.0, dQc_all = 0.0, Qc_max = 0.0,
         crank4 = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const bool regular = std::abs(at(ref.q, 6, i)[1]) > 0.05;
    dq = std::max(dq, (at(tr.q, 6, i) - at(ref.q, 6, i)).norm());
    const double dqd = (at(tr.qd, 6, i) - at(ref.qd, 6, i)).norm();
    dqd_all = std::max(dqd_all, dqd);
    if (regular) dqd_regular = std::max(dqd_regular, dqd);
    // the ideal constraint force is the same; only its split among the rows changes
    const double dQc = (at(tr.Qc_ideal, 6, i) - at(ref.Qc_ideal, 6, i)).norm();
    dQc_all = std::max(dQc_all, dQc);
    if (regular) dQc_regular = std::max(dQc_regular, dQc);
    Qc_max = std::max(Qc_max, at(ref.Qc_ideal, 6, i).norm());
    crank4 = std::max(crank4, tr.position_violation[std::size_t(i * 6 + 5)]);
  }
  EXPECT_NEAR(dq, 0.0, 1e-8);
  EXPECT_NEAR(dqd_regular, 0.0, 1e-8);
  EXPECT_NEAR(dqd_all, 0.0, 1e-6);
  EXPECT_NEAR(dQc_regular / Qc_max, 0.0, 1e-9);
  EXPECT_NEAR(dQc_all / Qc_max, 0.0, 1e-4);
  EXPECT_NEAR(crank4, 0.0, 1e-10);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

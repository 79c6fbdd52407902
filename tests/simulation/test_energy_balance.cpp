// SPDX-License-Identifier: BSD-3-Clause
// The energy balance (simulation/energy_balance.cpp, the work channels of
// simulation/constrained_ode.cpp): each work channel against a closed form or an independent
// quadrature, and the warning status of a run whose balance fails.
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/control/control.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/random_problem.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using testing::vec;

constexpr double kG = 9.81;

// composite Simpson quadrature of f (sampled every h) from sample 0 to each even sample i
std::vector<double> simpson(const std::vector<double>& f, double h) {
  std::vector<double> out(f.size(), std::numeric_limits<double>::quiet_NaN());
  out[0] = 0.0;
  for (std::size_t i = 2; i < f.size(); i += 2) {
    out[i] = out[i - 2] + h / 3.0 * (f[i - 2] + 4.0 * f[i - 1] + f[i]);
  }
  return out;
}

// the column called `name` of a model run
std::vector<double> column(const ModelRun& run, const std::string& name) {
  for (const CsvColumn& c : run.columns()) {
    if (c.name == name) return c.values;
  }
  ADD_FAILURE() << "no column " << name;
  return {};
}

// a measured number in the test report (--gtest_output=xml, or the console's record lines)
void record(const std::string& name, double value) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3e", value);
  ::testing::Test::RecordProperty(name, buf);
}

double largest_abs(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

// --- ideal constraint forces that do work: rheonomic constraints ------------------------------

// A frictionless bead on a horizontal wire through the origin turning at the constant rate
// Omega: r'' = Omega² r, so r = r0 cosh(Omega t) + (v0/Omega) sinh(Omega t), and the wire does
// the work T(t) − T(0), T = ½ m (r'² + Omega² r²).
struct Bead {
  double m = 1.5, Omega = 2.0, r0 = 0.5, v0 = 0.3;
  System system() const {
    const double W = Omega;
    return SystemBuilder({"x", "y"})
        .mass_matrix(m * MatrixXd::Identity(2, 2))
        .add(holonomic("wire", 1,
                       [W](const auto& q, const auto& t, auto& phi) {
                         using std::cos;
                         using std::sin;
                         phi[0] = -q[0] * sin(W * t) + q[1] * cos(W * t);
                       }))
        .build();
  }
  double kinetic(double t) const {
    const double r = r0 * std::cosh(Omega * t) + v0 / Omega * std::sinh(Omega * t);
    const double rd = r0 * Omega * std::sinh(Omega * t) + v0 * std::cosh(Omega * t);
    return 0.5 * m * (rd * rd + Omega * Omega * r * r);
  }
};

class BeadOnRotatingWire : public ::testing::TestWithParam<Integrator> {};

TEST_P(BeadOnRotatingWire, TheWiresWorkIsTheGainOfKineticEnergy) {
  const Bead bead;
  SimulationOptions o;
  o.integrator = GetParam();
  o.t_end = 1.5;
  o.output_every = 0.05;
  const bool bdf = GetParam() == Integrator::kBDF;
  if (!bdf) {
    o.rtol = 1e-11;
    o.atol = 1e-13;
  }
  const Trajectory tr =
      simulate(bead.system(), vec({bead.r0, 0.0}), vec({bead.v0, bead.r0 * bead.Omega}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double T0 = bead.kinetic(0.0), gain = bead.kinetic(o.t_end) - T0;
  ASSERT_GT(gain, 100.0);  // (r grows 10-fold: the wire does a lot of work)
  const double tol = (bdf ? 1e-6 : 1e-9) * gain;
  double worst = 0.0;
  for (Index i = 0; i < tr.samples(); ++i) {
    const std::size_t s = std::size_t(i);
    EXPECT_NEAR(tr.work_ideal[s], bead.kinetic(tr.t[s]) - T0, tol) << "t " << tr.t[s];
    worst = std::max(worst, std::abs(tr.work_ideal[s] - (bead.kinetic(tr.t[s]) - T0)) / gain);
    EXPECT_EQ(tr.work_nonideal[s], 0.0);
    EXPECT_EQ(tr.work_drive[s], 0.0);
    EXPECT_EQ(tr.work_external[s], 0.0);
    EXPECT_EQ(tr.work_control[s], 0.0);
  }
  // the exchanged energy is the wire's work, and the balance holds to the integration error
  EXPECT_NEAR(tr.stats.energy_exchanged, gain, tol);
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, bdf ? 1e-6 : 1e-9);
  EXPECT_NEAR(largest_abs(tr.energy_balance_residual), 0.0, tol);
  record("work_ideal_relative_error", worst);
  record("energy_balance", tr.stats.energy_balance);
  // the old figure raised a false alarm here: E(t) − E(0) is the wire's work
  EXPECT_GT(tr.energy.back() - tr.energy.front(), 100.0);
}

INSTANTIATE_TEST_SUITE_P(Methods, BeadOnRotatingWire,
                         ::testing::Values(Integrator::kDopri5, Integrator::kRKF78,
                                           Integrator::kBDF),
                         [](const auto& p) { return std::string(to_string(p.param)); });

// A pendulum whose length is prescribed, L(t) = L0 + eps sin(w t): the rod does work. work_ideal
// against Simpson's rule on the power q'ᵀ Qc_ideal of the recorded samples.
TEST(EnergyBalance, PendulumOfPrescribedVaryingLength) {
  const double L0 = 1.0, eps = 0.2, w = 3.0, theta0 = 0.4;
  const System sys =
      SystemBuilder({"x", "y"})
          .mass_matrix(MatrixXd::Identity(2, 2))
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) { Q << 0.0, -kG; })
          .potential_energy([](const Eigen::Ref<const VectorXd>& q, double) { return kG * q[1]; })
          .add(holonomic("rod", 1,
                         [=](const auto& q, const auto& t, auto& phi) {
                           using std::sin;
                           using S = std::decay_t<decltype(t)>;
                           const S L = L0 + eps * sin(w * t);
                           phi[0] = q[0] * q[0] + q[1] * q[1] - L * L;
                         }))
          .build();
  // at t = 0: L = L0, L' = eps w along the rod, no swing rate
  const double s = std::sin(theta0), c = std::cos(theta0), Ld = eps * w;
  SimulationOptions o;
  o.t_end = 2.0;
  o.output_every = 1e-3;
  o.rtol = 1e-11;
  o.atol = 1e-13;
  const Trajectory tr = simulate(sys, vec({L0 * s, -L0 * c}), vec({Ld * s, -Ld * c}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.samples(), 2001);
  // the rod's power at each sample, from the recorded q' and Qc_ideal
  std::vector<double> power;
  for (Index i = 0; i < tr.samples(); ++i) {
    const auto v = Trajectory::view(tr.qd, 2).col(i), f = Trajectory::view(tr.Qc_ideal, 2).col(i);
    power.push_back(v.dot(f));
  }
  const std::vector<double> W = simpson(power, o.output_every);
  const double scale = largest_abs(tr.work_ideal);
  ASSERT_GT(scale, 0.5);  // the rod works: of the order of joules
  double worst = 0.0;
  for (std::size_t i = 0; i < W.size(); i += 2) {
    EXPECT_NEAR(tr.work_ideal[i], W[i], 1e-9 * scale) << "t " << tr.t[i];
    worst = std::max(worst, std::abs(tr.work_ideal[i] - W[i]));
  }
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, 1e-9);
  record("work_ideal_vs_simpson", worst);
  record("work_ideal_scale", scale);
  record("energy_balance", tr.stats.energy_balance);
  EXPECT_NEAR(largest_abs(tr.energy_balance_residual), 0.0, 1e-9 * scale);
}

// A conservative pendulum: every channel stays at zero (work_ideal at the drift), the balance
// holds relative to the largest kinetic energy.
TEST(EnergyBalance, ConservativePendulumExchangesNothing) {
  const System sys =
      SystemBuilder({"x", "y"})
          .mass_matrix(MatrixXd::Identity(2, 2))
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) { Q << 0.0, -kG; })
          .potential_energy([](const Eigen::Ref<const VectorXd>& q, double) { return kG * q[1]; })
          .add(holonomic("rod", 1,
                         [](const auto& q, const auto&, auto& phi) {
                           phi[0] = q[0] * q[0] + q[1] * q[1] - 1.0;
                         }))
          .build();
  SimulationOptions o;
  o.t_end = 5.0;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  const Trajectory tr = simulate(sys, vec({1.0, 0.0}), vec({0.0, 0.0}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_NEAR(largest_abs(tr.work_ideal), 0.0, 1e-9);
  EXPECT_EQ(largest_abs(tr.work_nonideal), 0.0);
  EXPECT_EQ(largest_abs(tr.work_drive), 0.0);
  EXPECT_EQ(largest_abs(tr.work_external), 0.0);
  EXPECT_EQ(largest_abs(tr.work_control), 0.0);
  // (the rod's channel integrates λ A q', the velocity drift within each step)
  EXPECT_NEAR(tr.stats.energy_exchanged, 0.0, 1e-7);
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, 1e-9);  // relative to T_max = m g L = 9.81 J
  EXPECT_NEAR(tr.stats.energy_drift, 0.0, 1e-9);
  record("work_ideal", largest_abs(tr.work_ideal));
  record("energy_balance", tr.stats.energy_balance);
}

// --- external forces: SystemBuilder::external_power --------------------------------------------

// A damped oscillator x'' = −k x − c x' (m = 1) declaring its damper's power −c x'²:
// work_external = E(t) − E(0) of the closed-form motion.
TEST(EnergyBalance, DamperWorkIsTheExternalWork) {
  const double k = 4.0, c = 0.3, omega = 2.0, zeta = c / (2 * omega);
  const double wd = omega * std::sqrt(1 - zeta * zeta), B = zeta * omega / wd;
  const System sys =
      SystemBuilder({"x"})
          .mass_matrix(MatrixXd::Identity(1, 1))
          .forces([=](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                      double, Eigen::Ref<VectorXd> Q) { Q[0] = -k * q[0] - c * qd[0]; })
          .potential_energy(
              [=](const Eigen::Ref<const VectorXd>& q, double) { return 0.5 * k * q[0] * q[0]; })
          .external_power([=](const Eigen::Ref<const VectorXd>&,
                              const Eigen::Ref<const VectorXd>& qd,
                              double) { return -c * qd[0] * qd[0]; })
          .build();
  SimulationOptions o;
  o.t_end = 6.0;
  o.output_every = 0.1;
  const Trajectory tr = simulate(sys, vec({1.0}), vec({0.0}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  // x = e^(−ζωt)(cos ω_d t + B sin ω_d t), x' = −e^(−ζωt)(ζωB + ω_d) sin ω_d t
  auto energy = [&](double t) {
    const double e = std::exp(-zeta * omega * t);
    const double x = e * (std::cos(wd * t) + B * std::sin(wd * t));
    const double xd = -e * (zeta * omega * B + wd) * std::sin(wd * t);
    return 0.5 * xd * xd + 0.5 * k * x * x;
  };
  for (Index i = 0; i < tr.samples(); ++i) {
    const std::size_t s = std::size_t(i);
    EXPECT_NEAR(tr.work_external[s], energy(tr.t[s]) - energy(0.0), 1e-8) << "t " << tr.t[s];
  }
  EXPECT_LT(tr.work_external.back(), -1.0);  // most of E(0) = 2 J is gone
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, 1e-8);
  record("energy_balance", tr.stats.energy_balance);
}

// A pendulum whose Q (gravity m g) is not −∂V/∂q of the V it declares (2 m g y): energy appears
// from nowhere, and the run ends with the warning. Declaring the difference as an external power
// (q'ᵀ(Q + ∂V/∂q) = m g y') balances it again.
System inconsistent_pendulum(bool declare_power) {
  SystemBuilder b({"x", "y"});
  b.mass_matrix(MatrixXd::Identity(2, 2))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q << 0.0, -kG; })
      .potential_energy([](const Eigen::Ref<const VectorXd>& q, double) { return 2 * kG * q[1]; })
      .add(holonomic("rod", 1, [](const auto& q, const auto&, auto& phi) {
        phi[0] = q[0] * q[0] + q[1] * q[1] - 1.0;
      }));
  if (declare_power) {
    b.external_power([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>& qd,
                        double) { return kG * qd[1]; });
  }
  return b.build();
}

TEST(EnergyBalance, ForcesInconsistentWithThePotentialEndWithTheWarning) {
  SimulationOptions o;
  o.t_end = 2.0;
  const Trajectory tr = simulate(inconsistent_pendulum(false), vec({1.0, 0.0}), vec({0.0, 0.0}), o);
  EXPECT_EQ(tr.stats.status, Status::kEnergyBalance);
  EXPECT_STREQ(to_string(tr.stats.status), "energy_balance");
  EXPECT_NE(tr.stats.message.find("energy balance: E(t) - E(0) - (sum of the works) = "),
            std::string::npos)
      << tr.stats.message;
  EXPECT_NE(tr.stats.message.find("above the tolerance 1e-06"), std::string::npos);
  EXPECT_NE(tr.stats.message.find(" J at t = "), std::string::npos) << tr.stats.message;
  {
    // in a model's units (SimulationOptions::units), its energy and time: g·mm²/ms², ms
    SimulationOptions mm = o;
    mm.units = UnitSystem{"mm", "g", "ms"};
    const Trajectory t2 =
        simulate(inconsistent_pendulum(false), vec({1.0, 0.0}), vec({0.0, 0.0}), mm);
    EXPECT_NE(t2.stats.message.find(" g·mm²/ms² at t = "), std::string::npos) << t2.stats.message;
    EXPECT_NE(t2.stats.message.find(" ms, "), std::string::npos) << t2.stats.message;
    EXPECT_EQ(t2.stats.message.find(" J "), std::string::npos) << t2.stats.message;
    EXPECT_EQ(t2.stats.energy_balance, tr.stats.energy_balance);  // (labels only)
  }
  EXPECT_DOUBLE_EQ(tr.t.back(), 2.0);  // a warning: the run is complete
  // E − E0 = m g (y − y0) with nothing exchanged: relative to T_max = m g L
  EXPECT_NEAR(tr.stats.energy_balance, 1.0, 1e-6);

  // the same system, declaring the power that V does not account for
  const Trajectory ok = simulate(inconsistent_pendulum(true), vec({1.0, 0.0}), vec({0.0, 0.0}), o);
  ASSERT_EQ(ok.stats.status, Status::kOk) << ok.stats.message;
  EXPECT_NEAR(ok.stats.energy_balance, 0.0, 1e-9);
  for (Index i = 0; i < ok.samples(); ++i) {
    const std::size_t s = std::size_t(i);
    EXPECT_NEAR(ok.work_external[s], kG * ok.q[2 * s + 1], 1e-8);  // m g (y − y0), y0 = 0
  }
}

// A state jump that removes energy — the floor switching on projects a falling particle onto
// itself — is caught; the check can be switched off.
TEST(EnergyBalance, AJumpOfTheStateIsCaught) {
  SystemBuilder b({"x", "y"});
  b.mass_matrix(MatrixXd::Identity(2, 2))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q << 0.0, -kG; })
      .potential_energy([](const Eigen::Ref<const VectorXd>& q, double) { return kG * q[1]; });
  Constraint floor =
      holonomic("floor", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[1]; });
  floor.active_between(0.5, 2.0);
  b.add(floor);
  const System sys = b.build();
  SimulationOptions o;
  o.t_end = 1.0;
  // thrown up at 2 m/s: the vertical motion holds ½ m 2² = 2 J (kinetic plus potential) until
  // the floor puts the particle on it at rest at t = 0.5: E drops by 2 J, with nothing exchanged
  const Trajectory tr = simulate(sys, vec({0.0, 0.0}), vec({1.0, 2.0}), o);
  EXPECT_EQ(tr.stats.status, Status::kEnergyBalance) << tr.stats.message;
  EXPECT_NEAR(tr.energy_balance_residual.back(), -2.0, 1e-8);
  EXPECT_NEAR(tr.stats.energy_exchanged, 0.0, 1e-12);
  // relative to T_max, reached at the sample t = 0.5 just before the jump: ½ m (1² + (2 − g/2)²)
  EXPECT_NEAR(tr.stats.energy_balance, 2.0 / (0.5 * (1 + (2 - kG / 2) * (2 - kG / 2))), 1e-8);
  o.energy_balance_tolerance = std::numeric_limits<double>::infinity();
  const Trajectory off = simulate(sys, vec({0.0, 0.0}), vec({1.0, 2.0}), o);
  EXPECT_EQ(off.stats.status, Status::kOk);
  EXPECT_NEAR(off.stats.energy_balance, tr.stats.energy_balance, 1e-12);
  o.energy_balance_tolerance = 0.0;
  EXPECT_THROW(simulate(sys, vec({0.0, 0.0}), vec({1.0, 2.0}), o), std::invalid_argument);
}

// --- drives, control, model files -------------------------------------------------------------

// The gallery's driven slider-crank: the drive's work is ∫ torque · crank rate dt (Simpson on the
// drive.pin and crank.theta_dot columns), and the balance holds with it.
TEST(EnergyBalance, SliderCrankDriveWork) {
  const Model model = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/slider_crank.yaml");
  SimulationOptions o = model.options;
  o.output_every = 1e-3;
  const ModelRun run = run_model(model, o);
  const Trajectory& tr = run.trajectory;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.samples(), 1001);
  const std::vector<double> tau = column(run, "drive.pin"), rate = column(run, "crank.theta_dot");
  std::vector<double> power;
  for (std::size_t i = 0; i < tau.size(); ++i) power.push_back(tau[i] * rate[i]);
  const std::vector<double> W = simpson(power, o.output_every);
  const double scale = largest_abs(tr.work_drive);
  ASSERT_GT(scale, 1.0);
  double worst = 0.0;
  for (std::size_t i = 0; i < W.size(); i += 2) {
    EXPECT_NEAR(tr.work_drive[i], W[i], 1e-7 * scale) << "t " << tr.t[i];
    worst = std::max(worst, std::abs(tr.work_drive[i] - W[i]));
  }
  record("work_drive_vs_simpson", worst);
  record("work_drive_scale", scale);
  record("energy_balance", tr.stats.energy_balance);
  // the other joints do no work
  EXPECT_NEAR(largest_abs(tr.work_ideal), 0.0, 1e-8 * scale);
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, 1e-8);
}

// A controlled model: work_control is the control's work, and the balance holds with it.
TEST(EnergyBalance, ControlWork) {
  const Model model = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/control_duffing.yaml");
  const ModelRun run = run_model(model);
  const Trajectory& tr = run.trajectory;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const std::vector<double> control_work = column(run, "control_work");
  ASSERT_EQ(control_work.size(), tr.work_control.size());
  for (std::size_t i = 0; i < control_work.size(); ++i) {
    EXPECT_EQ(tr.work_control[i], control_work[i]);
  }
  EXPECT_GT(largest_abs(tr.work_control), 0.1);
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, 1e-8);
}

// A model file's explicit forces beside T are its external forces.
TEST(EnergyBalance, ModelFileForcesAreExternal) {
  const Model model = parse_model(R"(
coordinates: [x]
parameters: {k: 4, c: 0.3, F: 0.5, w: 1.3}
kinetic_energy: 0.5*x_dot^2
potential_energy: 0.5*k*x^2
forces: [-c*x_dot + F*cos(w*t)]
initial: {q: {x: 1}}
simulate: {t_end: 5}
)",
                                  "damped.yaml");
  EXPECT_TRUE(model.system.has_external_power());
  const ModelRun run = run_model(model);
  const Trajectory& tr = run.trajectory;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_GT(largest_abs(tr.work_external), 0.5);
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, 1e-8);
  // a conservative Lagrangian needs no channel
  EXPECT_FALSE(load_model(std::string(UKDYN_EXAMPLES_DIR) + "/double_pendulum.yaml")
                   .system.has_external_power());
}

// The reproducer of the user report: a sphere rolling on a turntable. The turntable's work
// arrives through the rolling constraint (ideal, affine in the velocities): E(10) − E(0) =
// −0.14088 J is work_ideal, and the run is not flagged.
TEST(EnergyBalance, SphereOnTurntableNoFalseAlarm) {
  const Model model = load_model(std::string(UKDYN_TEST_DATA_DIR) + "/sphere_turntable.yaml");
  const ModelRun run = run_model(model);
  const Trajectory& tr = run.trajectory;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_DOUBLE_EQ(tr.t.back(), 10.0);
  EXPECT_NEAR(tr.energy.back() - tr.energy.front(), -0.14088, 1e-5);
  EXPECT_NEAR(tr.work_ideal.back(), -0.14088, 1e-5);
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, 1e-8);
  record("delta_E", tr.energy.back() - tr.energy.front());
  record("work_ideal", tr.work_ideal.back());
  record("energy_balance", tr.stats.energy_balance);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

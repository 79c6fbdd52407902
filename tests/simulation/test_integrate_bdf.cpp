// SPDX-License-Identifier: BSD-3-Clause
// integrate_bdf (SUNDIALS CVODE): a stiff oscillator against its closed form, a Cartesian
// pendulum kept on its constraint by the after-step projection (period from the complete
// elliptic integral), and every way a segment can stop early.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <ukdyn/ukdyn.hpp>

#include "support/random_problem.hpp"

#include "../src/simulation/integrator.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using detail::ConstrainedOde;
using detail::integrate_bdf;
using detail::SegmentHooks;
using detail::SegmentResult;

constexpr double kG = 9.81;
constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// stiff, unconstrained: x'' + c x' + k x = 0 with roots −1 and −1e4

constexpr double kStiffK = 1e4, kStiffC = 1e4 + 1;

System stiff_oscillator() {
  return SystemBuilder(std::vector<std::string>{"x"})
      .mass_matrix(MatrixXd::Identity(1, 1))
      .forces([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 Eigen::Ref<VectorXd> Q) { Q[0] = -kStiffK * q[0] - kStiffC * qd[0]; })
      .build();
}

// x(t) = A e^{−t} + B e^{−1e4 t} with x(0) = 1, x'(0) = 0: A = 1e4/9999, B = −1/9999
double stiff_x(double t) { return 1e4 / 9999 * std::exp(-t) - 1.0 / 9999 * std::exp(-1e4 * t); }
double stiff_xd(double t) { return -1e4 / 9999 * std::exp(-t) + 1e4 / 9999 * std::exp(-1e4 * t); }

TEST(BdfStiff, OverdampedOscillatorMatchesClosedFormInFewSteps) {
  const System sys = stiff_oscillator();
  Workspace ws(sys);
  ConstrainedOde ode(sys, ws);
  std::vector<double> x = {1.0, 0.0, 0.0};

  SimulationOptions options;
  options.rtol = 1e-10;
  options.atol = 1e-12;
  const std::vector<double> outputs = {1e-4, 1e-3, 0.01, 0.1, 0.5, 1.0};
  std::vector<double> seen_t, seen_x, seen_xd;
  SegmentHooks hooks;
  hooks.output = [&](double t, const double* s) {
    seen_t.push_back(t);
    seen_x.push_back(s[0]);
    seen_xd.push_back(s[1]);
    return Status::kOk;
  };
  const SegmentResult r = integrate_bdf(ode, x, 0.0, 1.0, outputs, options, hooks, 0.0);

  ASSERT_EQ(r.status, Status::kOk) << r.message;
  EXPECT_EQ(r.message, "");
  EXPECT_EQ(r.t_reached, 1.0);
  ASSERT_EQ(seen_t.size(), outputs.size());
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const double t = outputs[i];
    EXPECT_EQ(seen_t[i], t);
    // 1e-6 relative to the solution's scale (|x| <= 1, |x'| <= 1)
    EXPECT_NEAR(seen_x[i], stiff_x(t), 1e-6 * std::abs(stiff_x(t))) << "t = " << t;
    EXPECT_NEAR(seen_xd[i], stiff_xd(t), 1e-6 * std::abs(stiff_xd(t)) + 1e-9) << "t = " << t;
  }
  EXPECT_NEAR(x[0], stiff_x(1.0), 1e-6 * stiff_x(1.0));
  EXPECT_NEAR(x[1], stiff_xd(1.0), 1e-6 * std::abs(stiff_xd(1.0)));
  // no constraints, so no non-ideal work
  EXPECT_EQ(x[2], 0.0);

  // an explicit Runge–Kutta method is stable only for h · 1e4 below about 3, i.e. several
  // thousand steps on [0, 1]; BDF is A(α)-stable and follows the slow mode e^{−t}
  EXPECT_GT(r.steps, 10);
  EXPECT_LT(r.steps, 1000);
  EXPECT_GE(r.rejected, 0);
  EXPECT_GT(r.last_step, 0.0);
  EXPECT_LE(r.last_step, 1.0);
}

TEST(BdfStiff, FirstStepAndMaxStepAreHonoured) {
  const System sys = stiff_oscillator();
  Workspace ws(sys);
  ConstrainedOde ode(sys, ws);
  std::vector<double> x = {1.0, 0.0, 0.0};
  SimulationOptions options;
  options.rtol = 1e-8;
  options.atol = 1e-10;
  options.max_step = 0.01;
  SegmentHooks hooks;
  const SegmentResult r = integrate_bdf(ode, x, 0.0, 1.0, {}, options, hooks, 1e-7);
  ASSERT_EQ(r.status, Status::kOk) << r.message;
  // at most 0.01 per step: at least 100 steps
  EXPECT_GE(r.steps, 100);
  EXPECT_LT(r.steps, 1000);
  EXPECT_GT(r.last_step, 0.0);
  EXPECT_LE(r.last_step, 0.01 * (1 + 1e-12));
  EXPECT_NEAR(x[0], stiff_x(1.0), 1e-6 * stiff_x(1.0));
}

TEST(BdfStiff, FirstStepFarTooLargeForTheTransientIsCutDown) {
  // x'(0) = 0 has weight atol = 1e-12 while x''' ≈ 1e8: the local error h² x'''/2 needs
  // h ≈ 1e-10, a millionth of the first step tried, which takes CVODE more than its default
  // seven error test failures to reach
  const System sys = stiff_oscillator();
  Workspace ws(sys);
  ConstrainedOde ode(sys, ws);
  std::vector<double> x = {1.0, 0.0, 0.0};
  SimulationOptions options;
  SegmentHooks hooks;
  const SegmentResult r = integrate_bdf(ode, x, 0.0, 1.0, {}, options, hooks, 1e-3);
  ASSERT_EQ(r.status, Status::kOk) << r.message;
  EXPECT_GE(r.rejected, 7);
  EXPECT_LT(r.steps, 1000);
  EXPECT_NEAR(x[0], stiff_x(1.0), 1e-6 * stiff_x(1.0));
  EXPECT_NEAR(x[1], stiff_xd(1.0), 1e-6 * std::abs(stiff_xd(1.0)));
}

// ---------------------------------------------------------------------------------------------
// the Cartesian pendulum, m = L = 1: x² + y² − 1 = 0, projected after every step

System pendulum() {
  return SystemBuilder(std::vector<std::string>{"x", "y"})
      .mass_matrix(MatrixXd::Identity(2, 2))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) {
        Q[0] = 0.0;
        Q[1] = -kG;
      })
      .potential_energy([](const Eigen::Ref<const VectorXd>& q, double) { return kG * q[1]; })
      .add(holonomic(
          "rod", 1,
          [](const auto& q, const auto&, auto& phi) { phi[0] = q[0] * q[0] + q[1] * q[1] - 1.0; }))
      .build();
}

double energy(const std::vector<double>& s) {
  return 0.5 * (s[2] * s[2] + s[3] * s[3]) + kG * s[1];
}

// released from rest at θ0 from the bottom: x = (sin θ0, −cos θ0, 0, 0, W = 0)
std::vector<double> pendulum_at_rest(double theta0) {
  return {std::sin(theta0), -std::cos(theta0), 0.0, 0.0, 0.0, 0.0};  // W_nonideal, W_ideal
}

// period of the pendulum of amplitude θ0: T = 4 √(L/g) K(sin(θ0/2))
double pendulum_period(double theta0) {
  return 4.0 / std::sqrt(kG) * std::comp_ellint_1(std::sin(theta0 / 2));
}

TEST(BdfProjection, PendulumStaysOnTheRodAndKeepsItsPeriodAndEnergy) {
  const System sys = pendulum();
  Workspace ws(sys), ws_projection(sys);
  ConstrainedOde ode(sys, ws);
  const double theta0 = 1.2, T = pendulum_period(theta0);
  std::vector<double> x = pendulum_at_rest(theta0);
  const double E0 = energy(x);

  SimulationOptions options;
  options.rtol = 1e-10;
  options.atol = 1e-12;

  // after each step: project q, then q' (the M-orthogonal projection), and remember the
  // largest violation left behind
  long calls = 0, moved = 0;
  double worst_phi = 0.0, worst_phid = 0.0;
  VectorXd q(2), qd(2);
  SegmentHooks hooks;
  hooks.after_step = [&](double t, double* s, bool& changed) {
    ++calls;
    q << s[0], s[1];
    qd << s[2], s[3];
    const ProjectionResult p = project_positions(sys, ws_projection, q, t, options.projection);
    const ProjectionResult v = project_velocities(sys, ws_projection, q, qd, t, options.projection);
    if (p.status != Status::kOk) return p.status;
    if (v.status != Status::kOk) return v.status;
    changed = p.iterations > 0 || v.iterations > 0;
    moved += changed ? 1 : 0;
    s[0] = q[0], s[1] = q[1], s[2] = qd[0], s[3] = qd[1];
    worst_phi = std::max(worst_phi, std::abs(q.squaredNorm() - 1.0));
    worst_phid = std::max(worst_phid, std::abs(q.dot(qd)));
    return Status::kOk;
  };
  // at the outputs (dense output between projected steps)
  std::vector<std::vector<double>> samples;
  hooks.output = [&](double, const double* s) {
    samples.emplace_back(s, s + 5);
    return Status::kOk;
  };
  const std::vector<double> outputs = {T / 4, T / 2, 3 * T / 4, T};
  const SegmentResult r = integrate_bdf(ode, x, 0.0, T, outputs, options, hooks, 0.0);
  ASSERT_EQ(r.status, Status::kOk) << r.message;
  EXPECT_EQ(r.t_reached, T);

  // CVODE projects each step before its error test: one call per accepted step and per error
  // test failure
  EXPECT_GE(calls, r.steps);
  EXPECT_LE(calls, r.steps + r.rejected);
  EXPECT_GT(moved, 0);
  // …each leaving the state on the rod to the projection's tolerance times the row's scale
  // class, 10 for this pendulum in SI units (Workspace::phi_scale, docs/simulation.md "Scales
  // and tolerances": 1e-13 · 10 = 1e-12), plus rounding
  const double on_rod = options.projection.tolerance * ws_projection.phi_scale[0];
  EXPECT_EQ(ws_projection.phi_scale[0], 10.0);
  EXPECT_NEAR(worst_phi, 0.0, 2 * on_rod);
  EXPECT_NEAR(worst_phid, 0.0, 2 * options.projection.tolerance * ws_projection.phi_dot_scale[0]);

  // the final state is a projected one: on the rod to 1e-10
  EXPECT_NEAR(x[0] * x[0] + x[1] * x[1], 1.0, 1e-10);
  EXPECT_NEAR(x[0] * x[2] + x[1] * x[3], 0.0, 1e-10);
  // back at the start after one period, through the bottom at T/4 and the far side at T/2
  ASSERT_EQ(samples.size(), 4u);
  const double vmax = std::sqrt(2 * kG * (1 - std::cos(theta0)));  // speed at the bottom
  // (errors seen: 2e-8 in the velocities, 4e-10 in the positions)
  EXPECT_NEAR(samples[0][0], 0.0, 1e-7);
  EXPECT_NEAR(samples[0][1], -1.0, 1e-7);
  EXPECT_NEAR(samples[0][2], -vmax, 1e-7);
  EXPECT_NEAR(samples[1][0], -std::sin(theta0), 1e-7);
  EXPECT_NEAR(samples[1][1], -std::cos(theta0), 1e-7);
  EXPECT_NEAR(samples[2][2], vmax, 1e-7);
  EXPECT_NEAR(x[0], std::sin(theta0), 1e-7);
  EXPECT_NEAR(x[1], -std::cos(theta0), 1e-7);
  EXPECT_NEAR(x[2], 0.0, 1e-7);
  EXPECT_NEAR(x[3], 0.0, 1e-7);
  // the interpolated samples lie on the rod (seen: 3e-12), and the energy ½|q'|² + g y is
  // that of the start to a few hundred times rtol (seen: 1.3e-8 of |E0| = 3.6); the rod does
  // no work, so W stays 0
  for (const auto& s : samples) {
    EXPECT_NEAR(s[0] * s[0] + s[1] * s[1], 1.0, 1e-10);
    EXPECT_NEAR(energy(s), E0, 1e-7);
    EXPECT_NEAR(s[4], 0.0, 1e-12);
  }
  EXPECT_NEAR(energy(x), E0, 1e-7);
}

TEST(BdfProjection, WithoutTheHookTheStateDriftsOffTheRod) {
  // the same run with no projection: the drift that the projection removes is really there
  const System sys = pendulum();
  Workspace ws(sys);
  ConstrainedOde ode(sys, ws);
  const double theta0 = 1.2, T = pendulum_period(theta0);
  std::vector<double> x = pendulum_at_rest(theta0);
  SimulationOptions options;
  options.rtol = 1e-6;
  options.atol = 1e-8;
  SegmentHooks hooks;
  const SegmentResult r = integrate_bdf(ode, x, 0.0, 10 * T, {}, options, hooks, 0.0);
  ASSERT_EQ(r.status, Status::kOk) << r.message;
  EXPECT_GT(std::abs(x[0] * x[0] + x[1] * x[1] - 1.0), 1e-9);
}

// ---------------------------------------------------------------------------------------------
// stopping early

// a particle falling under gravity whose force turns NaN after t = 0.5
System failing_particle() {
  return SystemBuilder(std::vector<std::string>{"y"})
      .mass_matrix(MatrixXd::Identity(1, 1))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double t,
                 Eigen::Ref<VectorXd> Q) {
        Q[0] = t > 0.5 ? std::numeric_limits<double>::quiet_NaN() : -kG;
      })
      .build();
}

TEST(BdfFailure, NonFiniteForceStopsWithTheOdeStatus) {
  const System sys = failing_particle();
  Workspace ws(sys);
  ConstrainedOde ode(sys, ws);
  std::vector<double> x = {0.0, 0.0, 0.0};
  SimulationOptions options;
  options.rtol = 1e-10;
  options.atol = 1e-12;
  options.max_step = 0.01;  // so that the step that meets the failure starts after 0.49
  long outputs_seen = 0;
  SegmentHooks hooks;
  hooks.output = [&](double, const double*) {
    ++outputs_seen;
    return Status::kOk;
  };
  const SegmentResult r =
      integrate_bdf(ode, x, 0.0, 1.0, std::vector<double>{0.25, 0.75}, options, hooks, 0.0);

  EXPECT_EQ(r.status, Status::kNonFiniteInput);
  // the failed evaluations were retried smaller (docs/simulation.md, "Steps that leave the
  // model's domain") until the step could not shrink: the message quotes the last time reached
  EXPECT_FALSE(ode.failed());
  EXPECT_NE(r.message.find("bdf: no step beyond t = 0.49999999"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("non-finite input (NaN or Inf) in Q"), std::string::npos) << r.message;
  EXPECT_NEAR(r.t_reached, 0.5, 1e-9);
  // stopped at the last accepted step, in (0.49, 0.5], after the output at 0.25
  EXPECT_EQ(outputs_seen, 1);
  EXPECT_NEAR(r.t_reached, 0.495, 0.005 + 1e-12);
  // x is the state at t_reached: free fall y = −g t²/2, y' = −g t
  EXPECT_NEAR(x[0], -0.5 * kG * r.t_reached * r.t_reached, 1e-8);
  EXPECT_NEAR(x[1], -kG * r.t_reached, 1e-8);
}

TEST(BdfFailure, AfterStepHookStopsWithItsStatus) {
  const System sys = stiff_oscillator();
  Workspace ws(sys);
  ConstrainedOde ode(sys, ws);
  std::vector<double> x = {1.0, 0.0, 0.0};
  SimulationOptions options;
  SegmentHooks hooks;
  hooks.after_step = [](double t, double*, bool& changed) {
    changed = false;
    return t > 0.3 ? Status::kInconsistentConstraints : Status::kOk;
  };
  const SegmentResult r = integrate_bdf(ode, x, 0.0, 1.0, {}, options, hooks, 0.0);
  EXPECT_EQ(r.status, Status::kInconsistentConstraints);
  // the hook describes its own failure to the driver
  EXPECT_EQ(r.message, "");
  EXPECT_FALSE(ode.failed());
  // the last accepted step ended at or before 0.3; the state is the closed form's there
  EXPECT_NEAR(r.t_reached, 0.15, 0.15 + 1e-12);
  EXPECT_NEAR(x[0], stiff_x(r.t_reached), 1e-6);
}

TEST(BdfFailure, OutputHookStopsWithItsStatus) {
  const System sys = stiff_oscillator();
  Workspace ws(sys);
  ConstrainedOde ode(sys, ws);
  std::vector<double> x = {1.0, 0.0, 0.0};
  SimulationOptions options;
  SegmentHooks hooks;
  hooks.output = [](double t, const double*) {
    return t > 0.4 ? Status::kMassNotSymmetric : Status::kOk;
  };
  const SegmentResult r =
      integrate_bdf(ode, x, 0.0, 1.0, std::vector<double>{0.2, 0.5, 0.8}, options, hooks, 0.0);
  EXPECT_EQ(r.status, Status::kMassNotSymmetric);
  EXPECT_EQ(r.message, "");
  EXPECT_EQ(r.t_reached, 0.5);
  EXPECT_NEAR(x[0], stiff_x(0.5), 1e-6);
}

TEST(BdfFailure, StepLimitReportsCvodesMessage) {
  const System sys = stiff_oscillator();
  Workspace ws(sys);
  ConstrainedOde ode(sys, ws);
  std::vector<double> x = {1.0, 0.0, 0.0};
  SimulationOptions options;
  options.max_steps = 5;
  SegmentHooks hooks;
  const SegmentResult r = integrate_bdf(ode, x, 0.0, 1.0, {}, options, hooks, 0.0);
  EXPECT_EQ(r.status, Status::kIntegratorFailure);
  EXPECT_NE(r.message.find("CVODE CV_TOO_MUCH_WORK at t = "), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("mxstep"), std::string::npos) << r.message;
  EXPECT_FALSE(ode.failed());
  EXPECT_EQ(r.steps, 5);
  EXPECT_GT(r.t_reached, 0.0);
  EXPECT_LT(r.t_reached, 1.0);
  EXPECT_NEAR(x[0], stiff_x(r.t_reached), 1e-6);
}

TEST(BdfFailure, BadToleranceIsRefusedWithTheCallNamed) {
  const System sys = stiff_oscillator();
  Workspace ws(sys);
  ConstrainedOde ode(sys, ws);
  std::vector<double> x = {1.0, 0.0, 0.0};
  SimulationOptions options;
  options.rtol = -1.0;
  SegmentHooks hooks;
  try {
    integrate_bdf(ode, x, 0.0, 1.0, {}, options, hooks, 0.0);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("integrate_bdf: CVodeSStolerances failed (CV_ILL_INPUT"), std::string::npos)
        << what;
  }
}

// ---------------------------------------------------------------------------------------------
// end to end: simulate() with Integrator::kBDF

using testing::vec;

TEST(BdfSimulate, StiffOscillatorThroughSimulate) {
  SimulationOptions o;
  o.integrator = Integrator::kBDF;
  o.t_end = 1.0;
  o.output_every = 0.1;
  const Trajectory tr = simulate(stiff_oscillator(), vec({1.0}), vec({0.0}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.samples(), 11);
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    EXPECT_NEAR(tr.q[std::size_t(i)], stiff_x(t), 1e-6 * stiff_x(t)) << t;
    EXPECT_NEAR(tr.qd[std::size_t(i)], stiff_xd(t), 1e-6 * std::abs(stiff_xd(t)) + 1e-12) << t;
  }
  EXPECT_GT(tr.stats.steps, 10);
  EXPECT_LT(tr.stats.steps, 1000);
  EXPECT_DOUBLE_EQ(tr.stats.t_reached, 1.0);
}

TEST(BdfSimulate, PendulumFromHorizontalKeepsItsRodTensionAndEnergy) {
  SimulationOptions o;
  o.integrator = Integrator::kBDF;
  o.t_end = 5.0;
  o.output_every = 0.05;
  const Trajectory tr = simulate(pendulum(), vec({1.0, 0.0}), vec({0.0, 0.0}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.samples(), 101);
  EXPECT_GT(tr.stats.projections, 0);
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-12);
  EXPECT_NEAR(tr.stats.max_velocity_violation, 0.0, 1e-12);
  // energy to a hundred times rtol (seen: 9e-9, with the tension off by 1.8e-7; with CVODE's
  // error projection, which measures the error the projection keeps, the tension is off by up
  // to 1.3e-6 of its 29 N)
  EXPECT_NEAR(tr.stats.energy_drift, 0.0, 1e-7);
  // tension 3 m g cos θ for release from the horizontal (θ from the downward vertical), to
  // 3e-6 N, 3e-7 of m g (the tension m (g cos θ + L θ'²) carries 2 ΔE)
  for (Index i = 0; i < tr.samples(); ++i) {
    const double x = tr.q[2 * std::size_t(i)], y = tr.q[2 * std::size_t(i) + 1];
    const double tension =
        -(tr.Qc_ideal[2 * std::size_t(i)] * x + tr.Qc_ideal[2 * std::size_t(i) + 1] * y);
    EXPECT_NEAR(tension, 3 * kG * (-y), 3e-6) << tr.t[std::size_t(i)];
  }
}

TEST(BdfSimulate, ConstraintSwitchingRestartsCvodeOnEachSegment) {
  // free fall until t = 1; the floor y = 0 during [1, 2]; free fall again after t = 2
  SystemBuilder b(std::vector<std::string>{"x", "y"});
  b.mass_matrix(MatrixXd::Identity(2, 2))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q << 0.0, -kG; })
      .potential_energy([](const Eigen::Ref<const VectorXd>& q, double) { return kG * q[1]; });
  Constraint floor =
      holonomic("floor", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[1]; });
  floor.active_between(1.0, 2.0);
  b.add(floor);
  SimulationOptions o;
  o.integrator = Integrator::kBDF;
  o.t_end = 3.0;
  o.output_at = {0.5, 1.5, 2.5, 3.0};
  o.output_every = 0.0;
  const Trajectory tr = simulate(b.build(), vec({0.0, 0.0}), vec({1.0, 0.0}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.samples(), 5);  // 0, 0.5, 1.5, 2.5, 3
  auto x = [&](int i) { return tr.q[2 * std::size_t(i)]; };
  auto y = [&](int i) { return tr.q[2 * std::size_t(i) + 1]; };
  // y = −g t²/2 is a quadratic, which BDF of order >= 2 follows to rounding and tolerance
  EXPECT_NEAR(y(1), -0.5 * kG * 0.25, 1e-9);
  EXPECT_NEAR(y(2), 0.0, 1e-12);
  EXPECT_NEAR(tr.Qc_ideal[2 * 2 + 1], kG, 1e-9);  // the floor carries the weight
  EXPECT_NEAR(y(3), -0.5 * kG * 0.25, 1e-9);
  EXPECT_NEAR(y(4), -0.5 * kG * 1.0, 1e-9);
  EXPECT_NEAR(x(4), 3.0, 1e-9);  // horizontal motion untouched throughout
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// simulate(): the driver and the explicit integrators on problems with exact solutions.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include <ukdyn/simulation/simulate.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/oscillator.hpp"
#include "support/random_problem.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81;

using testing::vec;

using test::oscillator;

// a particle in the plane under gravity, optionally on the floor y = 0 during [t0, t1]
System particle(double t0 = 1.0, double t1 = -1.0) {
  SystemBuilder b({"x", "y"});
  b.mass_matrix(MatrixXd::Identity(2, 2))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q << 0.0, -kG; })
      .potential_energy([](const Eigen::Ref<const VectorXd>& q, double) { return kG * q[1]; });
  if (t1 >= t0) {
    Constraint floor =
        holonomic("floor", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[1]; });
    floor.active_between(t0, t1);
    b.add(floor);
  }
  return b.build();
}

System pendulum() {
  return SystemBuilder({"x", "y"})
      .mass_matrix(MatrixXd::Identity(2, 2))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q << 0.0, -kG; })
      .potential_energy([](const Eigen::Ref<const VectorXd>& q, double) { return kG * q[1]; })
      .add(holonomic(
          "rod", 1,
          [](const auto& q, const auto&, auto& phi) { phi[0] = q[0] * q[0] + q[1] * q[1] - 1.0; }))
      .build();
}

class EveryExplicitIntegrator : public ::testing::TestWithParam<Integrator> {};

TEST_P(EveryExplicitIntegrator, HarmonicOscillatorAtOddOutputTimes) {
  SimulationOptions o;
  o.integrator = GetParam();
  o.t_end = 5.0;
  o.output_every = 0.0123;  // not on RK4's step grid: Hermite interpolation
  o.output_at = {std::acos(-1.0)};
  const Trajectory tr = simulate(oscillator(), vec({1.0}), vec({0.0}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_GT(tr.samples(), 400);
  EXPECT_DOUBLE_EQ(tr.t.front(), 0.0);
  EXPECT_DOUBLE_EQ(tr.t.back(), 5.0);
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    EXPECT_NEAR(tr.q[std::size_t(i)], std::cos(t), 1e-9) << to_string(GetParam()) << " t " << t;
    EXPECT_NEAR(tr.qd[std::size_t(i)], -std::sin(t), 1e-9) << t;
    EXPECT_NEAR(tr.qdd[std::size_t(i)], -std::cos(t), 1e-9) << t;
  }
  EXPECT_NEAR(tr.stats.energy_drift, 0.0, 1e-9);
  EXPECT_GT(tr.stats.steps, 0);
  EXPECT_GE(tr.stats.evaluations, tr.stats.steps);
}

INSTANTIATE_TEST_SUITE_P(Methods, EveryExplicitIntegrator,
                         ::testing::Values(Integrator::kRK4, Integrator::kDopri5,
                                           Integrator::kRKF78),
                         [](const auto& p) { return std::string(to_string(p.param)); });

TEST(Simulate, PendulumKeepsItsRodWithProjection) {
  SimulationOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.t_end = 10.0;
  o.output_every = 0.05;
  const Trajectory tr = simulate(pendulum(), vec({1.0, 0.0}), vec({0.0, 0.0}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_NEAR(tr.stats.max_position_violation, 0.0, 1e-12);
  EXPECT_NEAR(tr.stats.max_velocity_violation, 0.0, 1e-12);
  EXPECT_NEAR(tr.stats.energy_drift, 0.0, 1e-9);
  // tension 3 m g cos θ for release from the horizontal (θ from the downward vertical)
  for (Index i = 0; i < tr.samples(); ++i) {
    const double x = tr.q[2 * std::size_t(i)], y = tr.q[2 * std::size_t(i) + 1];
    const double tension =
        -(tr.Qc_ideal[2 * std::size_t(i)] * x + tr.Qc_ideal[2 * std::size_t(i) + 1] * y);
    // (to the integration's energy error: at rtol 1e-10 it loses ~5e-9 J in 10 s, and the
    // tension m (g cos θ + L θ'²) carries twice that)
    EXPECT_NEAR(tension, 3 * kG * (-y), 5e-8) << tr.t[std::size_t(i)];
  }
}

TEST(Simulate, DriftControlMethodsOrderAsExpected) {
  auto run = [](DriftControl d) {
    SimulationOptions o;
    o.t_end = 20.0;
    o.rtol = 1e-6;
    o.atol = 1e-8;
    o.drift = d;
    // (tolerances loose on purpose: the energy balance, to ~1e-5, is not what is compared)
    o.energy_balance_tolerance = std::numeric_limits<double>::infinity();
    return simulate(pendulum(), vec({1.0, 0.0}), vec({0.0, 0.0}), o).stats;
  };
  const RunStatistics none = run(DriftControl::kNone), baum = run(DriftControl::kBaumgarte),
                      proj = run(DriftControl::kProjection);
  ASSERT_EQ(none.status, Status::kOk);
  ASSERT_EQ(baum.status, Status::kOk);
  ASSERT_EQ(proj.status, Status::kOk);
  // loose tolerances let the unstabilized rod drift; Baumgarte bounds it, projection removes it
  EXPECT_GT(none.max_position_violation, 1e-9);
  EXPECT_LT(baum.max_position_violation, none.max_position_violation);
  EXPECT_NEAR(proj.max_position_violation, 0.0, 1e-12);
  EXPECT_GT(proj.projections, 0);
  EXPECT_EQ(none.projections, 0);
}

TEST(Simulate, ConstraintSwitchingOnAnInterval) {
  // free fall until t = 1; the floor y = 0 during [1, 2] (the state is projected onto it when it
  // switches on: y ← 0, y' ← 0); free fall again after t = 2
  SimulationOptions o;
  o.t_end = 3.0;
  o.output_at = {0.5, 1.5, 2.5, 3.0};
  o.output_every = 0.0;
  const Trajectory tr = simulate(particle(1.0, 2.0), vec({0.0, 0.0}), vec({1.0, 0.0}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.samples(), 5);  // 0, 0.5, 1.5, 2.5, 3
  auto y = [&](int i) { return tr.q[2 * std::size_t(i) + 1]; };
  auto x = [&](int i) { return tr.q[2 * std::size_t(i)]; };
  EXPECT_NEAR(y(1), -0.5 * kG * 0.25, 1e-10);
  EXPECT_NEAR(y(2), 0.0, 1e-12);
  EXPECT_NEAR(tr.Qc_ideal[2 * 2 + 1], kG, 1e-10);  // the floor carries the weight
  EXPECT_NEAR(y(3), -0.5 * kG * 0.25, 1e-10);
  EXPECT_NEAR(y(4), -0.5 * kG * 1.0, 1e-10);
  EXPECT_NEAR(x(4), 3.0, 1e-10);  // horizontal motion untouched throughout
}

TEST(Simulate, NonIdealForceActiveOnAnIntervalWithBreakpoints) {
  // a particle on the floor pushed along it by C = F during [1, 2] only: at rest until t = 1,
  // x'' = F on [1, 2], coasting after; the non-ideal work is F · F/2
  const double F = 3.0;
  const System sys =
      SystemBuilder({"x", "y"})
          .mass_matrix(MatrixXd::Identity(2, 2))
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) { Q << 0.0, -kG; })
          .add(holonomic("floor", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[1]; }))
          .add(NonIdealForce(
              "push",
              [F](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double t,
                  const IdealForceInfo&, Eigen::Ref<VectorXd> C) {
                if (t >= 1.0 && t <= 2.0) C[0] = F;
              }))
          .build();
  SimulationOptions o;
  o.t_end = 3.0;
  o.breakpoints = {1.0, 2.0};
  o.output_every = 0.0;
  o.output_at = {0.5, 1.5, 3.0};
  const Trajectory tr = simulate(sys, vec({0.0, 0.0}), vec({0.0, 0.0}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.samples(), 4);
  EXPECT_NEAR(tr.q[2], 0.0, 1e-14);             // t = 0.5: at rest
  EXPECT_NEAR(tr.q[4], 0.5 * F * 0.25, 1e-10);  // t = 1.5
  EXPECT_NEAR(tr.Qc_nonideal[4], F, 1e-12);     // the push is a non-ideal constraint force
  EXPECT_NEAR(tr.q[6], 0.5 * F + F, 1e-10);     // t = 3: F/2 after the push, then F · 1
  EXPECT_NEAR(tr.work_nonideal.back(), 0.5 * F * F, 1e-10);
  EXPECT_NEAR(tr.stats.energy_drift, 0.0, 1e-10);  // E(t) − E(0) = W(t) throughout
}

TEST(Simulate, FailureKeepsTheSamplesRecordedSoFar) {
  const System sys =
      SystemBuilder({"x"})
          .mass_matrix(MatrixXd::Identity(1, 1))
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double t,
                     Eigen::Ref<VectorXd> Q) { Q[0] = t < 0.5 ? 1.0 : std::nan(""); })
          .build();
  SimulationOptions o;
  o.t_end = 1.0;
  o.output_every = 0.1;
  o.max_step = 0.05;  // so the failing step starts within 0.05 of t = 0.5
  const Trajectory tr = simulate(sys, vec({0.0}), vec({0.0}), o);
  EXPECT_EQ(tr.stats.status, Status::kNonFiniteInput);
  EXPECT_NE(tr.stats.message.find("in Q"), std::string::npos) << tr.stats.message;
  EXPECT_NEAR(tr.stats.t_reached, 0.475, 0.025);  // the start of the step that met t = 0.5
  ASSERT_EQ(tr.samples(), 5);  // t = 0, 0.1, …, 0.4: every sample before the failure
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    EXPECT_NEAR(tr.q[std::size_t(i)], 0.5 * t * t, 1e-12) << t;  // x = t²/2
  }
}

TEST(Simulate, InconsistentInitialConditionsAreNamedOrProjected) {
  SimulationOptions o;
  o.t_end = 0.1;
  try {
    simulate(pendulum(), vec({1.1, 0.0}), vec({0.0, 0.3}), o);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("constraint 'rod' (holonomic): position violation 0.21"), std::string::npos)
        << msg;
    EXPECT_NE(msg.find("project_initial"), std::string::npos) << msg;
  }
  o.project_initial = true;
  const Trajectory tr = simulate(pendulum(), vec({1.1, 0.0}), vec({0.0, 0.3}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk);
  EXPECT_NEAR(tr.q[0], 1.0, 1e-12);  // projected radially
  EXPECT_NEAR(tr.qd[1], 0.3, 1e-12);
  EXPECT_TRUE(
      check_initial_conditions(pendulum(), vec({1.0, 0.0}), vec({0.0, 1.0}), 0.0, 1e-12).empty());
}

TEST(Simulate, WorkOfNonIdealForcesBalancesTheEnergy) {
  // a block on the floor with viscous friction: E(t) − E(0) = W_nonideal(t) = −(c/m) ∫ v²
  const System sys =
      SystemBuilder({"x", "y"})
          .mass_matrix(MatrixXd::Identity(2, 2))
          .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) { Q << 0.0, -kG; })
          .potential_energy([](const Eigen::Ref<const VectorXd>& q, double) { return kG * q[1]; })
          .add(holonomic("floor", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[1]; }))
          .add(viscous_friction({.coefficient = 0.5}))
          .build();
  SimulationOptions o;
  o.t_end = 2.0;
  const Trajectory tr = simulate(sys, vec({0.0, 0.0}), vec({2.0, 0.0}), o);
  ASSERT_EQ(tr.stats.status, Status::kOk);
  // v = 2 e^{−t/2}: W = ½ v² − ½ v0² = 2 (e^{−t} − 1)
  EXPECT_NEAR(tr.work_nonideal.back(), 2.0 * (std::exp(-2.0) - 1.0), 1e-9);
  EXPECT_NEAR(tr.stats.energy_drift, 0.0, 1e-9);
}

// a block on a rough incline of angle alpha (coordinates along and across the slope would hide
// nothing: use Cartesian ones), Coulomb friction mu, pushed along +x by F(t) = k t when k > 0
System block(double alpha, double mu, double k = 0.0) {
  return SystemBuilder({"x", "y"})
      .mass_matrix(MatrixXd::Identity(2, 2))
      .forces([k](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double t,
                  Eigen::Ref<VectorXd> Q) { Q << k * t, -kG; })
      .add(holonomic("plane", 1,
                     [alpha](const auto& q, const auto&, auto& phi) {
                       phi[0] =
                           q[1] - q[0] * std::tan(alpha);  // y = x tan(alpha): up the slope is +x
                     }))
      .add(coulomb_friction({.constraint = "plane", .mu = mu, .coordinates = {0, 1}}))
      .build();
}

TEST(StickSlip, BlockSlidingUpARoughInclineStopsAndSticks) {
  const double alpha = 0.3, mu = 0.5, v0 = 2.0;  // mu > tan(alpha): it stays stopped
  const double decel = kG * (std::sin(alpha) + mu * std::cos(alpha));
  const double t_stop = v0 / decel, s_stop = v0 * v0 / (2 * decel);
  SimulationOptions o;
  o.t_end = 2.0;
  o.output_every = 0.0;
  o.output_at = {t_stop - 1e-3, t_stop + 1e-3, 1.5};
  const VectorXd dir = vec({std::cos(alpha), std::sin(alpha)});
  const Trajectory tr = simulate(block(alpha, mu), VectorXd::Zero(2), v0 * dir, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.events, 1);
  ASSERT_EQ(tr.samples(), 5);
  auto s = [&](int i) { return vec({tr.q[2 * i], tr.q[2 * i + 1]}).dot(dir); };
  auto v = [&](int i) { return vec({tr.qd[2 * i], tr.qd[2 * i + 1]}).dot(dir); };
  // just before the stop: still sliding, v = decel · 1e-3, so the stop is at t_stop
  EXPECT_NEAR(v(1), decel * 1e-3, 1e-9);
  EXPECT_NEAR(tr.t[1] + v(1) / decel, t_stop, 1e-10);
  EXPECT_NEAR(s(1), s_stop - 0.5 * decel * 1e-6, 1e-10);
  // after it: at rest at the stop position, held by static friction m g sin(alpha)
  for (int i : {2, 3, 4}) {
    EXPECT_NEAR(v(i), 0.0, 1e-12) << tr.t[i];
    EXPECT_NEAR(s(i), s_stop, 1e-10) << tr.t[i];
  }
  EXPECT_NEAR(vec({tr.Qc_ideal[2 * 4], tr.Qc_ideal[2 * 4 + 1]}).dot(dir), kG * std::sin(alpha),
              1e-9);
}

TEST(StickSlip, BlockSlidingDownDeceleratesToRestAndSticks) {
  // mu > tan(alpha): sliding down, the block decelerates at g (mu cos α − sin α) and stops
  // without its velocity reversing (the regularized law alone would only creep)
  const double alpha = 0.3, mu = 0.8, v0 = 1.0;
  const double decel = kG * (mu * std::cos(alpha) - std::sin(alpha));
  const double t_stop = v0 / decel, s_stop = v0 * v0 / (2 * decel);
  SimulationOptions o;
  o.t_end = 1.0;
  o.output_every = 0.0;
  o.output_at = {0.5 * t_stop, 0.9};
  const VectorXd down = vec({-std::cos(alpha), -std::sin(alpha)});
  const Trajectory tr = simulate(block(alpha, mu), VectorXd::Zero(2), v0 * down, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.events, 1);
  EXPECT_LT(tr.stats.steps, 1000);
  auto s = [&](int i) { return vec({tr.q[2 * i], tr.q[2 * i + 1]}).dot(down); };
  EXPECT_NEAR(s(1), v0 * 0.5 * t_stop - 0.5 * decel * 0.25 * t_stop * t_stop, 1e-10);
  EXPECT_NEAR(s(2), s_stop, 1e-10);  // stuck where it stopped
  EXPECT_NEAR(tr.qd[4], 0.0, 1e-12);
}

TEST(StickSlip, BlockAtRestSlipsWhenThePushExceedsStaticFriction) {
  // horizontal floor, F = k t: sticks until k t_s = mu m g, then x = k (t − t_s)³ / (6 m)
  const double mu = 0.4, k = 2.0, t_slip = mu * kG / k;
  SimulationOptions o;
  o.t_end = t_slip + 1.0;
  o.output_every = 0.0;
  o.output_at = {0.5 * t_slip, t_slip + 0.5};
  const Trajectory tr = simulate(block(0.0, mu, k), VectorXd::Zero(2), VectorXd::Zero(2), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.events, 1);
  ASSERT_EQ(tr.samples(), 4);
  EXPECT_NEAR(tr.q[2], 0.0, 1e-14);                       // stuck at t_slip / 2
  EXPECT_NEAR(tr.Qc_ideal[2], -k * 0.5 * t_slip, 1e-10);  // static friction balances the push
  for (int i : {2, 3}) {
    const double tau = tr.t[i] - t_slip;
    EXPECT_NEAR(tr.q[2 * i], k * tau * tau * tau / 6.0, 1e-9) << tr.t[i];
    EXPECT_NEAR(tr.qd[2 * i], k * tau * tau / 2.0, 1e-9) << tr.t[i];
  }
}

TEST(Simulate, MisuseThrows) {
  SimulationOptions o;
  o.t_end = 0.0;
  EXPECT_THROW(simulate(oscillator(), vec({1.0}), vec({0.0}), o), std::invalid_argument);
  o.t_end = 1.0;
  EXPECT_THROW(simulate(oscillator(), vec({1.0, 2.0}), vec({0.0}), o), std::invalid_argument);
  o.drift_per_constraint["nope"] = ConstraintDrift{};
  EXPECT_THROW(simulate(pendulum(), vec({1.0, 0.0}), vec({0.0, 0.0}), o), std::invalid_argument);
  EXPECT_THROW(integrator_from_string("euler"), std::invalid_argument);
  EXPECT_EQ(integrator_from_string("rkf78"), Integrator::kRKF78);
  EXPECT_EQ(drift_from_string("baumgarte"), DriftControl::kBaumgarte);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

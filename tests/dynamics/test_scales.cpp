// Scale-invariant numerics (issue #29 item 2): rows written with extreme factors, states of
// extreme size, models in millimetres or of astronomical mass give the motion they give in SI
// units, or a clear failure — never a dropped row with status ok. The reproducers of
// ../shared/reproducers/2026-11-28 (constraint_underflow.sh, solve_overflow_rank0.py,
// pendulum_in_mm.sh, mass_scale.sh) as tests, against closed forms and the SI runs.
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/dynamics/projection.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/random_problem.hpp"

namespace ukdyn {
namespace {

using testing::vec;

// the planar pendulum of unit mass in Cartesian coordinates, its rod written as
// factor · (x² + y² − 1) = 0, gravity 9.81 along −y
System pendulum(double factor) {
  return SystemBuilder(2)
      .mass_matrix(MatrixXd::Identity(2, 2))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q << 0.0, -9.81; })
      .add(holonomic("rod", 1,
                     [factor](const auto& q, const auto&, auto& phi) {
                       phi[0] = factor * (q[0] * q[0] + q[1] * q[1] - 1.0);
                     }))
      .build();
}

// FundamentalDecomposition: the rank decision does not depend on the factor a row is written
// with, and the answer is that of the unscaled rows
TEST(Scales, RankDoesNotDependOnTheRowsFactors) {
  const MatrixXd M = vec({2.0, 3.0, 5.0}).asDiagonal();
  MatrixXd A(2, 3);
  A << 1.0, 2.0, 0.5, -1.0, 0.25, 3.0;
  const VectorXd e = vec({0.7, -1.3});
  FundamentalDecomposition ref(3, 2);
  ref.compute(M, A);
  VectorXd dq0(3), Qc0(3), l0(2);
  ref.solve_ideal(e, dq0, Qc0, l0);
  ASSERT_EQ(ref.rank(), 2);
  for (const double f : {1e-170, 1e-160, 1e-8, 1e8, 1e150, 1e170}) {
    SCOPED_TRACE(f);
    // row 0 scaled by f (e_0 with it), row 1 not: the same q'' and Qc; lambda_0 / f
    MatrixXd As = A;
    As.row(0) *= f;
    VectorXd es = e;
    es[0] *= f;
    FundamentalDecomposition d(3, 2);
    d.compute(M, As);
    EXPECT_EQ(d.rank(), 2);
    VectorXd dq(3), Qc(3), l(2);
    d.solve_ideal(es, dq, Qc, l);
    EXPECT_LE((dq - dq0).norm(), 1e-13 * dq0.norm());
    EXPECT_LE((Qc - Qc0).norm(), 1e-13 * Qc0.norm());
    EXPECT_NEAR(l[0] * f, l0[0], 1e-13 * l0.norm());
    EXPECT_NEAR(l[1], l0[1], 1e-13 * l0.norm());
  }
  // an exactly redundant row is still dropped, whatever its factor
  MatrixXd R(3, 3);
  R << A, 1e-170 * A.row(0);
  FundamentalDecomposition d(3, 3);
  d.compute(M, R);
  EXPECT_EQ(d.rank(), 2);
}

// solve_overflow_rank0.py: at q = (c, c), q' = 0 the rod's row (2c, 2c) asks x'' + y'' = 0,
// the answer (g/2, −g/2), whatever c; the rank stays 1 and the status ok. At q = (1e308, 0) the
// row overflows: a non-finite A, reported.
TEST(Scales, HugeStatesKeepTheConstraint) {
  const System sys = pendulum(1.0);
  Workspace ws(sys);
  for (const double c : {1.0, 1e150, 1e154, 1e200, 1e-150, 1e-200}) {
    SCOPED_TRACE(c);
    ASSERT_EQ(forward_dynamics(sys, ws, vec({c, c}), vec({0.0, 0.0}), 0.0), Status::kOk);
    EXPECT_EQ(ws.rank, 1);
    EXPECT_NEAR(ws.qdd[0], 4.905, 1e-12);
    EXPECT_NEAR(ws.qdd[1], -4.905, 1e-12);
    // ‖A q'' − b‖ relative to ‖A‖ ‖q''‖: roundoff (it overflowed to inf before)
    EXPECT_TRUE(std::isfinite(ws.residuals.constraint));
    EXPECT_LE(ws.residuals.constraint, 1e-14 * 2.0 * std::sqrt(2.0) * c * 4.905 * std::sqrt(2.0));
  }
  EXPECT_EQ(forward_dynamics(sys, ws, vec({1e308, 0.0}), vec({0.0, 0.0}), 0.0),
            Status::kNonFiniteInput);
  EXPECT_STREQ(ws.failed_quantity, "A");
}

// constraint_underflow.sh: the factor of the rod (1e-170 underflowed A Aᵀ and dropped it)
TEST(Scales, TinyAndHugeRowFactorsKeepThePendulumOnItsCircle) {
  SimulationOptions o;
  o.t_end = 1.0;
  o.rtol = 1e-9;
  o.atol = 1e-11;
  const Trajectory ref = simulate(pendulum(1.0), vec({1.0, 0.0}), vec({0.0, 0.0}), o);
  ASSERT_EQ(ref.stats.status, Status::kOk);
  for (const double f : {1e-170, 1e-160, 1e-20, 1e20, 1e150}) {
    SCOPED_TRACE(f);
    const Trajectory run = simulate(pendulum(f), vec({1.0, 0.0}), vec({0.0, 0.0}), o);
    ASSERT_EQ(run.stats.status, Status::kOk) << run.stats.message;
    const std::size_t last = 2 * (run.t.size() - 1);
    const double x = run.q[last], y = run.q[last + 1];
    EXPECT_NEAR(std::hypot(x, y), 1.0, 1e-9);
    EXPECT_NEAR(x, ref.q[last], 1e-7);
    EXPECT_NEAR(y, ref.q[last + 1], 1e-7);
    EXPECT_LE(run.stats.steps, 2 * ref.stats.steps);
  }
}

std::string num(double v) {
  std::ostringstream s;
  s << std::setprecision(17) << v;
  return s.str();
}

// the pendulum of pendulum_in_mm.sh in a model file, in metres or millimetres
std::string pendulum_text(double L, double g, double m = 1.0) {
  return "parameters: {m: " + num(m) + ", L: " + num(L) + ", g: " + num(g) +
         "}\ncoordinates: [x, y]\nkinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)\n"
         "potential_energy: m*g*y\nconstraints:\n  - {name: rod, holonomic: x^2 + y^2 - L^2}\n"
         "initial: {q: {x: L}}\nsimulate: {t_end: 2}\n";
}

// pendulum_in_mm.sh: the 1 m pendulum written in millimetres failed at t = 0.001 s (the
// projection tolerance was absolute in mm²); it now gives the motion in metres × 1000
TEST(Scales, PendulumInMillimetres) {
  const Model si = parse_model(pendulum_text(1.0, 9.81), "m.yaml");
  const Model mm = parse_model(pendulum_text(1000.0, 9810.0), "mm.yaml");
  const Trajectory a = simulate(si.system, si.q0, si.qd0, si.options);
  const Trajectory b = simulate(mm.system, mm.q0, mm.qd0, mm.options);
  ASSERT_EQ(a.stats.status, Status::kOk) << a.stats.message;
  ASSERT_EQ(b.stats.status, Status::kOk) << b.stats.message;
  ASSERT_EQ(a.t.size(), b.t.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < a.q.size(); ++i) {
    worst = std::max(worst, std::abs(b.q[i] / 1000.0 - a.q[i]));
  }
  EXPECT_LE(worst, 1e-6);
  EXPECT_LE(b.stats.steps, 2 * a.stats.steps);
  EXPECT_GE(2 * b.stats.steps, a.stats.steps);
}

// mass_scale.sh: the motion does not depend on the mass, nor should the number of steps (the
// work channels took 726,143 steps at 1e20 kg and hit the step limit at 1e30 kg)
TEST(Scales, MassDoesNotChangeTheSteps) {
  const Model one = parse_model(pendulum_text(1.0, 9.81, 1.0), "m.yaml");
  const Trajectory a = simulate(one.system, one.q0, one.qd0, one.options);
  ASSERT_EQ(a.stats.status, Status::kOk) << a.stats.message;
  for (const double m : {1e-20, 1e20, 1e30}) {
    SCOPED_TRACE(m);
    const Model heavy = parse_model(pendulum_text(1.0, 9.81, m), "m.yaml");
    const Trajectory b = simulate(heavy.system, heavy.q0, heavy.qd0, heavy.options);
    ASSERT_EQ(b.stats.status, Status::kOk) << b.stats.message;
    EXPECT_LE(b.stats.steps, 2 * a.stats.steps);
    EXPECT_GE(2 * b.stats.steps, a.stats.steps);
    ASSERT_EQ(a.q.size(), b.q.size());
    for (std::size_t i = 0; i < a.q.size(); ++i) ASSERT_NEAR(b.q[i], a.q[i], 1e-7);
  }
}

// Projections measure each row relative to its scale once set_run_scales has set it: a row
// written × 1e-170 projects as the unscaled one
TEST(Scales, ProjectionIsRelativeToTheRowsScale) {
  for (const double f : {1.0, 1e-170, 1e170}) {
    SCOPED_TRACE(f);
    const System sys = pendulum(f);
    Workspace ws(sys);
    set_run_scales(sys, ws, vec({1.0, 0.0}), vec({0.0, 0.0}), 0.0, 1.0);
    EXPECT_NEAR(ws.phi_scale[0], 2.0 * f, 1e-15 * f);
    EXPECT_EQ(ws.length_scale, 1.0);
    VectorXd q = vec({1.1, 0.2});
    const ProjectionResult r = project_positions(sys, ws, q, 0.0);
    EXPECT_TRUE(r.converged);
    EXPECT_NEAR(std::hypot(q[0], q[1]), 1.0, 1e-11);
  }
}

// `ukdyn check` judges the initial state in the scales of the run it describes (its duration
// included), as simulate does: at q = (1, 0), q' = (5e-8, 1) the rod's phi' = 1e-7 against
// ‖a‖ v = 2 v. Over the model's run of 1 ms, v = ℓ / duration = 1000: relative 5e-11, within
// initial_tolerance (1e-10 and above), and the run starts; the public check without a duration
// takes v = ‖q'‖∞ = 1: relative 5e-8, reported
TEST(Scales, CheckJudgesTheInitialStateInTheRunsScales) {
  const std::string text =
      "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2 + y_dot^2)\npotential_energy: 9.81*y\n"
      "constraints:\n  - {name: rod, holonomic: x^2 + y^2 - 1}\n"
      "initial: {q: {x: 1}, q_dot: {x: 5e-8, y: 1}}\nsimulate: {t_end: 0.001}\n";
  const Model model = parse_model(text, "short.yaml");
  const CheckReport report = check_model(model);
  EXPECT_TRUE(report.initial_violations.empty())
      << (report.initial_violations.empty() ? "" : report.initial_violations.front());
  const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto lines = check_initial_conditions(model.system, model.q0, model.qd0, 0.0,
                                              model.options.initial_tolerance);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines.front().find("'rod'"), std::string::npos) << lines.front();
  // the pendulum in millimetres starts consistent in its own scales
  const Model mm = parse_model(pendulum_text(1000.0, 9810.0), "mm.yaml");
  EXPECT_TRUE(check_model(mm).initial_violations.empty());
}

}  // namespace
}  // namespace ukdyn

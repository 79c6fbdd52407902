// SPDX-License-Identifier: BSD-3-Clause
// The default integrator on stiff problems (SimulationOptions::stiff_switch): dopri5 detects
// stiffness (Hairer–Wanner's test) and goes on with BDF; a non-stiff problem never switches and
// keeps dopri5's trajectory bit for bit; a collapsed step size says why.
#include <algorithm>
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/simulation/simulate.hpp>
#include <ukdyn/ukdyn.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// x'' + c x' + k x = 0 with c = 10001, k = 10000: the eigenvalues of the first-order system are
// −1 and −1e4, so dopri5's step is held at ~3.3e-4 by stability once the fast mode has decayed
// (t ≳ 1e-3), while the solution is as smooth as e^{−t}. From x = 1, x' = 0:
//   x(t) = (1e4 e^{−t} − e^{−1e4 t}) / 9999.
constexpr double kSlow = 1.0, kFast = 1e4;
System stiff_oscillator() {
  return SystemBuilder({"x"})
      .mass_matrix(MatrixXd::Identity(1, 1))
      .forces(
          [](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
             Eigen::Ref<VectorXd> Q) { Q[0] = -kSlow * kFast * q[0] - (kSlow + kFast) * qd[0]; })
      .build();
}
double stiff_exact(double t) {
  return (kFast * std::exp(-kSlow * t) - kSlow * std::exp(-kFast * t)) / (kFast - kSlow);
}

VectorXd one(double v) { return VectorXd::Constant(1, v); }

TEST(Stiffness, SwitchesToBdfOnAStiffSpringDamperAndMatchesTheClosedForm) {
  SimulationOptions o;  // defaults: dopri5 with stiff_switch
  o.t_end = 5.0;
  o.output_every = 0.5;
  const Trajectory tr = simulate(stiff_oscillator(), one(1.0), one(0.0), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.stiff_switches, 1);
  // the fast mode e^{−1e4 t} falls below atol (its amplitude is 1e-4) by ~2e-3 s; 15 stiff
  // steps of ~3e-4 s follow, so the switch comes within the first 2e-2 s, after the transient
  EXPECT_GT(tr.stats.stiff_switch_time, 1e-4);
  EXPECT_LT(tr.stats.stiff_switch_time, 2e-2);
  EXPECT_GT(tr.stats.stiff_steps, 0);
  EXPECT_LT(tr.stats.stiff_steps, tr.stats.steps);
  // every sample against the closed form (BDF at rtol 1e-9: errors of order 1e-8)
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    EXPECT_NEAR(tr.q[std::size_t(i)], stiff_exact(t), 1e-7) << "t = " << t;
  }
  // against dopri5 held at its stability bound: h ≈ 3.3e-4, so ~15000 steps for 5 s
  SimulationOptions plain = o;
  plain.stiff_switch = false;
  const Trajectory slow = simulate(stiff_oscillator(), one(1.0), one(0.0), plain);
  ASSERT_EQ(slow.stats.status, Status::kOk) << slow.stats.message;
  EXPECT_EQ(slow.stats.stiff_switches, 0);
  EXPECT_TRUE(std::isnan(slow.stats.stiff_switch_time));
  EXPECT_NEAR(double(slow.stats.steps), 5.0 / (3.3 / kFast), 0.3 * 5.0 / (3.3 / kFast));
  EXPECT_LT(tr.stats.evaluations * 5, slow.stats.evaluations);
  EXPECT_NEAR(tr.q.back(), slow.q.back(), 1e-7);
}

// The same oscillator with its damper as a non-ideal (viscous) force: then the work W of the
// non-ideal force is integrated too, W' = −c x'² changes fast and smoothly, and the test must
// still see the stiff mode (it leaves W out of h·ρ)
TEST(Stiffness, SwitchesEarlyWhenTheDamperIsANonIdealForce) {
  const System sys =
      SystemBuilder({"x"})
          .mass_matrix(MatrixXd::Identity(1, 1))
          .forces([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>&, double,
                     Eigen::Ref<VectorXd> Q) { Q[0] = -kSlow * kFast * q[0]; })
          .add(viscous_friction({.coefficient = kSlow + kFast}))
          .build();
  SimulationOptions o;
  o.t_end = 5.0;
  o.output_every = 0.5;
  const Trajectory tr = simulate(sys, one(1.0), one(0.0), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_EQ(tr.stats.stiff_switches, 1);
  EXPECT_GT(tr.stats.stiff_switch_time, 1e-4);
  EXPECT_LT(tr.stats.stiff_switch_time, 2e-2);
  for (Index i = 0; i < tr.samples(); ++i) {
    const double t = tr.t[std::size_t(i)];
    EXPECT_NEAR(tr.q[std::size_t(i)], stiff_exact(t), 1e-7) << "t = " << t;
  }
}

TEST(Stiffness, ANonStiffProblemDoesNotSwitchAndKeepsDopri5sTrajectoryBitForBit) {
  // every gallery problem (including Coulomb stick/slip on the incline), on defaults
  for (const std::string& name : gallery::names()) {
    auto ex = gallery::make(name);
    SimulationOptions o;
    o.t_end = std::min(ex.t_end, 5.0);
    ASSERT_TRUE(o.stiff_switch);
    const Trajectory a = simulate(ex.system, ex.q0, ex.qd0, o);
    o.stiff_switch = false;
    const Trajectory b = simulate(ex.system, ex.q0, ex.qd0, o);
    ASSERT_EQ(a.stats.status, Status::kOk) << name << ": " << a.stats.message;
    EXPECT_EQ(a.stats.stiff_switches, 0) << name;
    EXPECT_EQ(a.stats.steps, b.stats.steps) << name;
    EXPECT_EQ(a.stats.evaluations, b.stats.evaluations) << name;
    EXPECT_EQ(a.q, b.q) << name;  // bit for bit
    EXPECT_EQ(a.qd, b.qd) << name;
  }
}

TEST(Stiffness, OtherMethodsNeverSwitch) {
  for (Integrator m : {Integrator::kRK4, Integrator::kRKF78, Integrator::kBDF}) {
    SimulationOptions o;
    o.integrator = m;
    o.t_end = 0.05;
    o.step = 1e-4;
    const Trajectory tr = simulate(stiff_oscillator(), one(1.0), one(0.0), o);
    ASSERT_EQ(tr.stats.status, Status::kOk) << to_string(m) << ": " << tr.stats.message;
    EXPECT_EQ(tr.stats.stiff_switches, 0) << to_string(m);
    EXPECT_NEAR(tr.q.back(), stiff_exact(0.05), 1e-6) << to_string(m);
  }
}

// The reproducer of issue #12: a slider-crank with regularized slider friction (eps 1e-6) that
// comes to rest after ~2.1 s. Plain dopri5 needs ~1.3 M steps for the 2.9 s at rest; the
// default must give BDF's answer at a cost of the same order as BDF's.
TEST(Stiffness, SlowSliderCrankReproducerOnDefaultsAgreesWithBdfAtBdfsCost) {
  const Model model =
      load_model(std::string(UKDYN_TEST_DATA_DIR) + "/slider_crank_friction_slow.yaml");
  SimulationOptions o = model.options;
  o.project_initial = model.project_initial;
  ASSERT_EQ(o.integrator, Integrator::kDopri5);
  const ModelRun defaults = run_model(model, o);
  SimulationOptions ob = o;
  ob.integrator = Integrator::kBDF;
  const ModelRun bdf = run_model(model, ob);
  const RunStatistics &sd = defaults.trajectory.stats, &sb = bdf.trajectory.stats;
  ASSERT_EQ(sd.status, Status::kOk) << sd.message;
  ASSERT_EQ(sb.status, Status::kOk) << sb.message;
  EXPECT_GE(sd.stiff_switches, 1);
  // the switch comes as the mechanism settles (it slides for ~2.1 s)
  EXPECT_GT(sd.stiff_switch_time, 1.0);
  EXPECT_LT(sd.stiff_switch_time, 3.0);
  // the cost: evaluations (not time) within 10× BDF's
  EXPECT_LT(sd.evaluations, 10 * sb.evaluations)
      << "defaults " << sd.evaluations << ", bdf " << sb.evaluations;
  // the same final state: q to 1e-6 (m, rad), q' to 1e-6 (at rest: regularized creep ~eps)
  const Trajectory &td = defaults.trajectory, &tb = bdf.trajectory;
  ASSERT_EQ(td.samples(), tb.samples());
  const std::size_t n = std::size_t(td.n), last = (std::size_t(td.samples()) - 1) * n;
  for (std::size_t c = 0; c < n; ++c) {
    EXPECT_NEAR(td.q[last + c], tb.q[last + c], 1e-6) << td.coordinate_names[c];
    EXPECT_NEAR(td.qd[last + c], tb.qd[last + c], 1e-6) << td.coordinate_names[c];
  }
  // and the energy balance E − E0 = W_friction holds on defaults
  EXPECT_NEAR(sd.energy_drift, 0.0, 1e-5);
}

TEST(Stiffness, ACollapsedStepSizeSaysStiffnessAndWhatToTry) {
  SimulationOptions o;
  o.t_end = 5.0;
  o.stiff_switch = false;
  o.max_steps = 2000;
  const Trajectory tr = simulate(stiff_oscillator(), one(1.0), one(0.0), o);
  ASSERT_EQ(tr.stats.status, Status::kIntegratorFailure);
  const std::string& m = tr.stats.message;
  EXPECT_TRUE(contains(m, "dopri5: step limit reached")) << m;
  EXPECT_TRUE(contains(m, "Likely cause: stiffness")) << m;
  EXPECT_TRUE(contains(m, "integrator: bdf")) << m;
  EXPECT_TRUE(contains(m, "leave stiff_switch on")) << m;
  EXPECT_TRUE(contains(m, " s): the step size is held by stability")) << m;
  // in a model's units (SimulationOptions::units: the times in ms), the same run says ms
  o.units = UnitSystem{"mm", "g", "ms"};
  const std::string ms = simulate(stiff_oscillator(), one(1.0), one(0.0), o).stats.message;
  EXPECT_TRUE(contains(ms, " ms): the step size is held by stability")) << ms;
  EXPECT_TRUE(contains(ms, "Likely cause: stiffness at t = ")) << ms;
  EXPECT_FALSE(contains(ms, " s)")) << ms;
}

// The arm of issue #12 asked to follow a circle partly outside its reach: the tip requirement
// loses rank where the arm stretches, and the message says so instead of only "step size
// underflow".
TEST(Stiffness, AControlledRunWhoseRequirementLostRankSaysSo) {
  const Model model =
      load_model(std::string(UKDYN_TEST_DATA_DIR) + "/arm_circle.yaml", {{"cx", 0.9}, {"R", 0.4}});
  const ModelRun run = run_model(model, model.options);
  const RunStatistics& s = run.trajectory.stats;
  ASSERT_EQ(s.status, Status::kIntegratorFailure) << s.message;
  EXPECT_TRUE(contains(s.message, "Likely cause: the requirements lost rank")) << s.message;
  EXPECT_TRUE(contains(s.message, "Try: a requirement that stays inside the workspace"))
      << s.message;
  EXPECT_FALSE(contains(s.message, "Likely cause: stiffness")) << s.message;
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

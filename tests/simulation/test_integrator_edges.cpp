// SPDX-License-Identifier: BSD-3-Clause
// Integrator edges (issue #29 item 3): the adaptive methods reach t_end for any max_step (the
// landing step is never refused for exceeding max_step by a sliver); the stiffness switch never
// turns a run that dopri5 finishes into a failure (BDF gives up → an explicit method goes on,
// and the notes say so); a sliding mode entered from rest is declared chattering early. The
// references are closed forms.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/simulation/simulate.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/closed_chain.hpp"
#include "support/oscillator.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

VectorXd one(double v) { return VectorXd::Constant(1, v); }

struct MaxStepCase {
  Integrator method;
  double max_step, t_end;
};

class MaxStepLanding : public ::testing::TestWithParam<MaxStepCase> {};

// x'' = −x from (1, 0): x = cos t. With max_step h the adaptive methods take steps of h (the
// oscillator allows far larger ones), and t, summed over T/h steps, ends a few rounding units
// short of t_end: the landing step is then h plus that sliver. It used to be refused as above
// max_step 200 times over ("step size underflow" at t_end − h, exit 1).
TEST_P(MaxStepLanding, ReachesTEndWithEveryStepAtMostMaxStep) {
  const MaxStepCase c = GetParam();
  SimulationOptions o;
  o.integrator = c.method;
  o.t_end = c.t_end;
  o.max_step = c.max_step;
  o.output_every = 0.0;  // t_start and t_end only
  const Trajectory tr = simulate(test::oscillator(), one(1.0), one(0.0), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_DOUBLE_EQ(tr.stats.t_reached, c.t_end);
  EXPECT_DOUBLE_EQ(tr.t.back(), c.t_end);
  EXPECT_NEAR(tr.q.back(), std::cos(c.t_end), 1e-8);
  EXPECT_NEAR(tr.qd.back(), -std::sin(c.t_end), 1e-8);
  // at least T / h steps; at most one more for the split landing (and a handful at the start)
  const double least = c.t_end / c.max_step;
  EXPECT_GE(double(tr.stats.steps), least * (1.0 - 1e-9));
  EXPECT_LE(double(tr.stats.steps), least + 5.0);
  EXPECT_EQ(tr.stats.rejected_steps, 0);
}

INSTANTIATE_TEST_SUITE_P(Methods, MaxStepLanding,
                         ::testing::Values(MaxStepCase{Integrator::kDopri5, 1e-4, 1.0},
                                           MaxStepCase{Integrator::kDopri5, 2e-4, 1.0},
                                           MaxStepCase{Integrator::kDopri5, 1e-3, 2.0},
                                           MaxStepCase{Integrator::kDopri5, 1e-3, 10.0},
                                           MaxStepCase{Integrator::kDopri5, 3e-4, 1.0},
                                           MaxStepCase{Integrator::kRKF78, 1e-4, 1.0},
                                           MaxStepCase{Integrator::kRKF78, 2e-4, 1.0},
                                           MaxStepCase{Integrator::kRKF78, 1e-3, 10.0}),
                         [](const auto& p) {
                           std::string name =
                               std::string(to_string(p.param.method)) + "_h" +
                               std::to_string(int(std::lround(1e5 * p.param.max_step))) + "e5_T" +
                               std::to_string(int(p.param.t_end));
                           return name;
                         });

// V = exp(1000 x) from x = 0.5 at rest: the particle is flung towards −∞ and leaves the wall with
// all its energy E = e^500 as kinetic energy, x' → −√(2 e^500) = −√2 e^250. dopri5 alone runs it
// to the end; the default stiffness switch hands it to BDF, whose Newton iterates leave the
// domain (exp overflows) at t ≈ 1e-112. The run goes on with dopri5 from BDF's last state.
TEST(StiffSwitch, BdfThatLeavesTheDomainFallsBackToDopri5WithANote) {
  const Model m = parse_model(R"(
coordinates: [x]
kinetic_energy: 0.5*x_dot^2
potential_energy: exp(1000*x)
initial: {q: {x: 0.5}}
simulate: {t_end: 0.1}
)");
  const double v_end = -std::sqrt(2.0) * std::exp(250.0);
  SimulationOptions o = m.options;
  ASSERT_TRUE(o.stiff_switch);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_DOUBLE_EQ(tr.stats.t_reached, 0.1);
  EXPECT_NEAR(tr.qd.back() / v_end, 1.0, 1e-5);
  // x(0.1) = 0.5 + v_end (0.1 − t_wall), t_wall the time spent at the wall (~1e-108)
  EXPECT_NEAR(tr.q.back() / (0.1 * v_end), 1.0, 1e-5);
  // the notes say what happened
  bool noted = false;
  for (const std::string& note : tr.stats.notes) {
    noted = noted || (contains(note, "bdf (after the stiffness switch") &&
                      contains(note, "went on with dopri5 without the stiffness switch"));
  }
  EXPECT_TRUE(noted) << (tr.stats.notes.empty() ? std::string("no notes") : tr.stats.notes[0]);
  // the same as dopri5 alone
  o.stiff_switch = false;
  const Trajectory plain = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(plain.stats.status, Status::kOk) << plain.stats.message;
  EXPECT_NEAR(tr.qd.back() / plain.qd.back(), 1.0, 1e-6);
  EXPECT_TRUE(plain.stats.notes.empty());
}

// BDF at rtol 1e-9 on a closed chain of 32 rods (gen_chain.py 32 closed): CVODE gives up part
// way (here at t ≈ 0.29 s; at 0.52 s with samples every 0.01 s: its steps collapse to 1e-307 s,
// every attempt outside the domain), and the run finishes with rkf78 from BDF's last state, with
// a note. Either way (BDF finishing would do) the run reaches t_end on rkf78's motion: the
// reference is rkf78 alone, and the chain's coordinates agree to the tolerances' level.
TEST(BdfFallback, ClosedChainAtTightToleranceFinishes) {
  const Model m = parse_model(test::closed_chain(32), "chain32.yaml");
  SimulationOptions o = m.options;
  o.t_end = 0.6;
  o.output_every = 0.0;
  o.rtol = 1e-9;
  o.integrator = Integrator::kBDF;
  const Trajectory bdf = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(bdf.stats.status, Status::kOk) << bdf.stats.message;
  EXPECT_DOUBLE_EQ(bdf.stats.t_reached, 0.6);
  for (const std::string& note : bdf.stats.notes) {
    if (!contains(note, "bdf failed")) continue;
    EXPECT_TRUE(contains(note, "went on with rkf78 without the stiffness switch")) << note;
  }
  o.integrator = Integrator::kRKF78;
  const Trajectory ref = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(ref.stats.status, Status::kOk) << ref.stats.message;
  const Index n = m.system.coordinate_count();
  for (Index i = 0; i < n; ++i) {
    EXPECT_NEAR(bdf.q[std::size_t((bdf.samples() - 1) * n + i)],
                ref.q[std::size_t((ref.samples() - 1) * n + i)], 1e-6)
        << m.system.coordinate_names()[std::size_t(i)];
  }
}

// x'' = −sign(x') − 0.5 from rest: since |−0.5| < 1, the motion is a sliding mode at x' = 0 from
// the start (Filippov's solution stays at rest): sign(x') turns it back from either side. The run
// ends as chattering (the message docs/model-format.md promises) within kSwitchBurstSpan = 1e-6
// of the run's span and a bounded number of steps; it used to crawl 10⁷ steps (40 s) and then
// blame stiffness. Up to then |x''| <= 1.5, so |x'| <= 1.5e-6 and |x| <= 7.5e-13.
TEST(SlidingMode, FromRestIsDeclaredChatteringEarly) {
  const Model m = parse_model(R"(
coordinates: [x]
kinetic_energy: 0.5*x_dot^2
forces: [-sign(x_dot) - 0.5]
)");
  ASSERT_DOUBLE_EQ(m.options.t_end - m.options.t_start, 1.0);
  SimulationOptions o = m.options;
  o.max_steps = 100000;  // (a crawl fails fast)
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kIntegratorFailure);
  EXPECT_TRUE(contains(tr.stats.message, "chattering: a sliding mode")) << tr.stats.message;
  EXPECT_TRUE(contains(tr.stats.message, "'x_dot'")) << tr.stats.message;
  EXPECT_TRUE(contains(tr.stats.message, "switch_events")) << tr.stats.message;
  EXPECT_FALSE(contains(tr.stats.message, "stiffness")) << tr.stats.message;
  EXPECT_NEAR(tr.stats.t_reached, 0.5e-6, 0.5e-6);
  EXPECT_LE(tr.stats.steps, 20000);
  EXPECT_NEAR(tr.q.back(), 0.0, 7.5e-13);
  EXPECT_NEAR(tr.qd.back(), 0.0, 1.5e-6);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

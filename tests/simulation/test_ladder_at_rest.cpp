// SPDX-License-Identifier: BSD-3-Clause
// A ladder at rest on a rough floor against a rough wall, both unilateral contacts (docs/
// friction.md, "Several contacts"): statically indeterminate, it must stay at rest with forces
// that balance it, in SI, in cm/g/s and in mm/g/ms alike. The wall bears nothing at the
// minimum-norm split of its holding forces (its multiplier there is roundoff, ~1e-15 of either
// sign): its friction cone was once taken from that sign, pointed to a pull, and set the wall
// sliding at t = 0 (its friction in C, in no column: N_f + f_w = m g seemed not to hold, the
// wall's holding force 0; in cm/g/s a spurious floor slip at 0.80 s). Statics of the rod (m, L,
// angle θ to the floor, A on the floor, B on the wall), N_f, N_w the normal forces, f_f the
// floor's friction along x, f_w the wall's along y:
//   f_f + N_w = 0,   N_f + f_w = m g,   N_w sin θ + f_w cos θ = (m g / 2) cos θ   (moments at A),
// and |f_f| <= mu_f N_f, |f_w| <= mu_w N_w. Both stick, the wall's holding force at its limit
// (f_w = mu_w N_w up: the split the run takes) and the floor's inside its cone (8.54 of 9.30 N):
// N_w = (m g / 2) cos θ / (sin θ + mu_w cos θ).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "support/contact_runs.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// a unit system: the length, mass and time units in metres, kilograms and seconds
struct Units {
  const char* name;
  double length, mass, time;
  double force() const { return mass * length / (time * time); }  // in newtons
};

constexpr double kPi = 3.141592653589793;
constexpr double kMass = 5.0, kLength = 2.0, kG = 9.81, kMuF = 0.2, kMuW = 0.3, kTh0 = 1.2;

// the ladder's model in the units u: the same SI numbers converted
std::string ladder(const Units& u) {
  const auto num = [](double v) { return format_number(v); };
  return "parameters: {m: " + num(kMass / u.mass) + ", L: " + num(kLength / u.length) +
         ", g: " + num(kG / u.length * u.time * u.time) + ", mu_f: " + num(kMuF) +
         ", mu_w: " + num(kMuW) + ", th0: " + num(kTh0) + "}\n" +
         testing::ladder_in_coordinates(true) + "simulate: {t_end: " + num(1.0 / u.time) +
         "}\noutput: {every: " + num(0.1 / u.time) + "}\n";
}

void expect_at_rest_and_balanced(const Units& u) {
  SCOPED_TRACE(u.name);
  const Model model = parse_model(ladder(u));
  const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_TRUE(tr.stats.contact_events.empty()) << "no slip, release or impact at rest";
  ASSERT_EQ(tr.unilateral.size(), 2u);
  ASSERT_GE(tr.t.size(), 11u);
  const double F = u.force(), mg = kMass * kG / F, L = kLength / u.length;
  const double c = std::cos(kTh0), s = std::sin(kTh0);
  const double N_w = 0.5 * mg * c / (s + kMuW * c);  // the wall at its limit (closed form)
  // the stick rows of the floor and the wall in lambda (their holding forces along xA and yB)
  const auto stick_row = [&](const std::string& name) {
    std::size_t row = 0;
    for (std::size_t k = 0; k < tr.constraint_names.size(); ++k) {
      if (tr.constraint_names[k] == name) return row;
      row += std::size_t(tr.constraint_rows[k]);
    }
    ADD_FAILURE() << "no constraint " << name;
    return std::size_t(0);
  };
  const std::size_t floor_row = stick_row("stick.coulomb.floor"),
                    wall_row = stick_row("stick.coulomb.wall");
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    SCOPED_TRACE("t = " + std::to_string(tr.t[i]));
    // at rest
    EXPECT_NEAR(testing::coordinate_at(tr, tr.q, "xA", i), L * c, 1e-12 * L);
    EXPECT_NEAR(testing::coordinate_at(tr, tr.q, "yB", i), L * s, 1e-12 * L);
    EXPECT_NEAR(testing::coordinate_at(tr, tr.qd, "xA", i), 0.0, 1e-12 * u.time / u.length);
    const double N_f = tr.lambda_total[2 * i], Nw = tr.lambda_total[2 * i + 1];
    const double f_f = tr.lambda[i * std::size_t(tr.m) + floor_row],
                 f_w = tr.lambda[i * std::size_t(tr.m) + wall_row];
    // both stick: no sliding friction acts
    for (std::size_t j = 0; j < 4; ++j) EXPECT_EQ(tr.Qc_nonideal[4 * i + j], 0.0) << j;
    // the numbers of the closed form, in the run's force unit
    EXPECT_NEAR(Nw, N_w, 1e-9 * mg);
    EXPECT_NEAR(f_f, -N_w, 1e-9 * mg);
    EXPECT_NEAR(f_w, kMuW * N_w, 1e-9 * mg);
    // the balance of forces and of moments at A, and both cones, whatever the split
    EXPECT_NEAR(f_f + Nw, 0.0, 1e-9 * mg);
    EXPECT_NEAR(N_f + f_w, mg, 1e-9 * mg);
    EXPECT_NEAR(Nw * s + f_w * c, 0.5 * mg * c, 1e-9 * mg);
    EXPECT_LE(std::abs(f_f), kMuF * N_f * (1.0 + 1e-12));
    EXPECT_LE(std::abs(f_w), kMuW * Nw * (1.0 + 1e-9));
    EXPECT_GT(Nw, 0.0);
    EXPECT_GT(N_f, 0.0);
  }
  // in SI: N_f 46.488332, N_w 8.538895 (m = 5 kg, θ = 1.2, mu_w = 0.3)
  EXPECT_NEAR(tr.lambda_total[1] * F, 8.538894, 2e-6);
  EXPECT_NEAR(tr.lambda_total[0] * F, 46.488332, 2e-6);
}

TEST(LadderAtRest, StaysAtRestWithTheWallAtItsLimitInSI) {
  expect_at_rest_and_balanced({"SI", 1.0, 1.0, 1.0});
}

TEST(LadderAtRest, StaysAtRestWithTheSameForcesInCentimetresGramsSeconds) {
  expect_at_rest_and_balanced({"cm, g, s", 0.01, 1e-3, 1.0});
}

TEST(LadderAtRest, StaysAtRestWithTheSameForcesInMillimetresGramsMilliseconds) {
  expect_at_rest_and_balanced({"mm, g, ms", 1e-3, 1e-3, 1e-3});
}

// A rigid ladder (planar body: m = 10 kg, half-length l = 1.5 m) sliding down a rough wall on a
// rough floor (mu = 0.9 at both), from θ0 = 0.8 rad at θ' = −1.5 rad/s: friction stops it at
// t_s = 0.2488422 s (an independent integration of its sliding equations with both normal
// forces unknown; a new user's, u24 02). It then rests, statically indeterminate: both contacts
// stick, the wall at its limit (the run's split), N_w (sin θ + mu cos θ) = (m g / 2) cos θ at the
// rest angle, N_f = m g − mu N_w. The minimum-norm split's wall multiplier pulled in mm, g, ms
// (−22.8 N where SI's pushes with 31 N): the wall was released at the stop, bounced 158 times and
// the run failed. Now the same rest in every unit system.
// (the ladder of u24 02 and 03: the body at its centre, at angle pi − th0, turning at W (rad/s,
// its fall: th0 decreases), its ends at ±l; mu at both contacts; t_end, every and an output time
// `at` (none when 0) in seconds)
std::string sliding_ladder(const Units& u, double mu, double W, double t_end, double every,
                           double at = 0.0) {
  const auto num = [](double v) { return format_number(v); };
  return "parameters: {m: " + num(10.0 / u.mass) + ", l: " + num(1.5 / u.length) +
         ", g: " + num(kG / u.length * u.time * u.time) + ", mu: " + num(mu) +
         ", th0: 0.8, W: " + num(W * u.time) +
         "}\n"
         "bodies:\n"
         "  - {name: lad, type: planar, mass: m, inertia: m*l^2/3, position: [l*cos(th0), "
         "l*sin(th0)], angle: pi - th0, velocity: [l*sin(th0)*W, -l*cos(th0)*W], "
         "angular_velocity: W}\n"
         "contacts:\n"
         "  - {name: wall, body: lad, point: [l, 0], plane: {point: [0, 0], normal: [1, 0]}}\n"
         "  - {name: floor, body: lad, point: [-l, 0]}\n"
         "nonideal:\n"
         "  - {friction: coulomb, constraint: wall, mu: mu}\n"
         "  - {friction: coulomb, constraint: floor, mu: mu}\n"
         "forces:\n"
         "  - {type: gravity, g: [0, -g]}\n"
         "simulate: {t_end: " +
         num(t_end / u.time) + "}\noutput: {every: " + num(every / u.time) +
         (at > 0.0 ? ", at: [" + num(at / u.time) + "]" : std::string()) + "}\n";
}

TEST(LadderAtRest, SlidingLadderStopsAndRestsWithTheSameForcesInAnyUnits) {
  for (const Units& u : {Units{"SI", 1.0, 1.0, 1.0}, Units{"mm, g, ms", 1e-3, 1e-3, 1e-3},
                         Units{"cm, g, s", 0.01, 1e-3, 1.0}}) {
    SCOPED_TRACE(u.name);
    const Model model = parse_model(sliding_ladder(u, 0.9, 1.5, 0.5, 0.05));
    const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    // both stop together and stick: two stick events, nothing else
    ASSERT_EQ(tr.stats.contact_events.size(), 2u);
    for (const ContactEvent& ev : tr.stats.contact_events) {
      EXPECT_EQ(ev.kind, ContactEvent::Kind::kStick);
      EXPECT_NEAR(ev.t * u.time, 0.2488422, 1e-6);
    }
    const double F = u.force(), mg = 10.0 * kG / F, mu = 0.9;
    ASSERT_EQ(tr.unilateral.size(), 2u);
    const std::size_t wall = tr.constraint_names[std::size_t(tr.unilateral[0])] == "wall" ? 0 : 1;
    std::size_t rests = 0;
    for (std::size_t i = 0; i < tr.t.size(); ++i) {
      if (tr.t[i] * u.time < 0.25) continue;
      ++rests;
      SCOPED_TRACE("t = " + std::to_string(tr.t[i]));
      const double th = kPi - testing::coordinate_at(tr, tr.q, "lad.theta", i);
      EXPECT_NEAR(testing::coordinate_at(tr, tr.qd, "lad.theta", i) / u.time, 0.0, 1e-9);
      const double c = std::cos(th), s = std::sin(th);
      const double N_w = 0.5 * mg * c / (s + mu * c);
      EXPECT_NEAR(tr.lambda_total[2 * i + wall], N_w, 1e-8 * mg);
      EXPECT_NEAR(tr.lambda_total[2 * i + 1 - wall], mg - mu * N_w, 1e-8 * mg);
    }
    EXPECT_EQ(rests, 6u);  // (t = 0.25, 0.3, …, 0.5 s)
  }
}

// u24 03: the same ladder (m = 10 kg, its ends at ±l = ±1.5 m from its centre: 3 m long) at
// th0 = 0.8 rad to the floor, falling at 2 rad/s with mu = 0.8 at both: both ends slide from the
// start (the foot away from the wall, the top down), and the wall's normal force falls to 0: it
// releases. Each evaluation's friction/normal fixed point contracts slowly there; before its
// Anderson acceleration every integrator failed, "1000 events handled at t = 0.0383". The
// reference: the sliding ladder's equations (three unknowns th'', N_f, N_w; th the angle to the
// floor) integrated until N_w = 0 by tests/data/ladder_both_ends_slide_reference.py (scipy DOP853
// at rtol 1e-13 and Radau at 1e-12 agree to 3e-13 s, 4e-13 rad, 1e-12 rad/s):
//   t_r = 0.0383016607841 s, th = 0.7227208743929, th' = −2.0422005006514 rad/s,
//   N_f = 37.89150684489 N (the tester's own solve_ivp: 0.0383017 s).
TEST(LadderAtRest, LadderSlidingAtBothEndsLeavesTheWallWhenItsNormalForceVanishesInAnyUnits) {
  constexpr double t_r = 0.0383016607841, th_r = 0.7227208743929, w_r = -2.0422005006514;
  constexpr double N_f = 37.89150684489, l = 1.5;
  for (const Units& u : {Units{"SI", 1.0, 1.0, 1.0}, Units{"mm, g, ms", 1e-3, 1e-3, 1e-3},
                         Units{"cm, g, s", 0.01, 1e-3, 1.0}}) {
    SCOPED_TRACE(u.name);
    const Model model = parse_model(sliding_ladder(u, 0.8, 2.0, 0.1, 0.01, t_r));
    const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    // one event: the wall releases at t_r, bearing nothing just before
    ASSERT_EQ(tr.stats.contact_events.size(), 1u);
    const ContactEvent& ev = tr.stats.contact_events[0];
    EXPECT_EQ(ev.kind, ContactEvent::Kind::kRelease);
    EXPECT_EQ(tr.constraint_names[std::size_t(ev.constraint)], "wall");
    EXPECT_NEAR(ev.t * u.time, t_r, 1e-9);
    const double F = u.force();
    EXPECT_NEAR(ev.force_before * F, 0.0, 1e-6 * 10.0 * kG);
    // the state at t_r (continuous there: the release changes no velocity), centre at
    // (l cos th, l sin th), body angle pi − th
    const std::size_t i = testing::sample_at(tr, t_r / u.time);
    const double c = std::cos(th_r), s = std::sin(th_r);
    EXPECT_NEAR(testing::coordinate_at(tr, tr.q, "lad.theta", i), kPi - th_r, 1e-8);
    EXPECT_NEAR(testing::coordinate_at(tr, tr.qd, "lad.theta", i) / u.time, -w_r, 1e-7);
    EXPECT_NEAR(testing::coordinate_at(tr, tr.q, "lad.x", i) * u.length, l * c, 1e-8);
    EXPECT_NEAR(testing::coordinate_at(tr, tr.q, "lad.y", i) * u.length, l * s, 1e-8);
    EXPECT_NEAR(testing::coordinate_at(tr, tr.qd, "lad.x", i) * u.length / u.time, -l * s * w_r,
                1e-7);
    EXPECT_NEAR(testing::coordinate_at(tr, tr.qd, "lad.y", i) * u.length / u.time, l * c * w_r,
                1e-7);
    // the floor's normal force there (the contacts' whole multipliers: unit gap gradients)
    ASSERT_EQ(tr.unilateral.size(), 2u);
    const std::size_t floor = tr.constraint_names[std::size_t(tr.unilateral[0])] == "floor" ? 0 : 1;
    EXPECT_NEAR(tr.lambda_total[2 * i + floor] * F, N_f, 1e-5);
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

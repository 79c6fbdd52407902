// SPDX-License-Identifier: BSD-3-Clause
// Contact events whose cause lies inside one long step (issue #31, u15 06, 08 and 11;
// docs/contact.md, "In a run"): a body at rest or in free fall takes long steps, which saw
// neither a force pulse that lifts a resting ball off the floor (the floor pulled it down with
// −9.81 N instead) nor a floor that moves explicitly with t and sweeps through a falling ball
// (its gap went to −0.44 m). The stages of each step now screen the closed contacts'
// multipliers, and a moving gap is screened at interior points of each step; each case against
// its closed form. And the rest criterion of a second sequence of impacts (a hop after the ball
// came to rest) compares with that sequence's fastest impact, not the drop's.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81;

// the events of kind `kind` in the run, in order
std::vector<ContactEvent> events_of(const Trajectory& tr, ContactEvent::Kind kind) {
  std::vector<ContactEvent> out;
  for (const ContactEvent& e : tr.stats.contact_events) {
    if (e.kind == kind) out.push_back(e);
  }
  return out;
}

// y at the sample nearest t
double y_at(const Trajectory& tr, double t) {
  std::size_t best = 0;
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    if (std::abs(tr.t[i] - t) < std::abs(tr.t[best] - t)) best = i;
  }
  EXPECT_NEAR(tr.t[best], t, 1e-12);
  return tr.q[best * std::size_t(tr.n)];
}

// A ball (m = 1) at rest on the floor (y >= 0), pushed up by F(t) from t = 1. `force` is F.
std::string resting_ball(const std::string& force, double e = 0.0, double y0 = 0.0,
                         double t_end = 2.0) {
  return "parameters: {m: 1, g: 9.81, e: " + std::to_string(e) +
         "}\n"
         "coordinates: [y]\n"
         "kinetic_energy: 0.5*m*y_dot^2\n"
         "potential_energy: m*g*y\n"
         "forces: [" +
         force +
         "]\n"
         "constraints:\n"
         "  - {name: floor, holonomic: y, unilateral: true, restitution: e}\n"
         "initial:\n"
         "  q: {y: " +
         std::to_string(y0) +
         "}\n"
         "simulate: {t_end: " +
         std::to_string(t_end) + "}\n";
}

// u15 06: F0 = 2 m g from t = 1 to 1.2 (a heaviside pulse). Released at 1; y'' = g during the
// pulse: y(1.2) = g/50, y'(1.2) = g/5; apex y = 2 y(1.2) = 0.3924 at t = 1.4; lands at
// 1.2 + (y'(1.2) + sqrt(y'(1.2)² + 2 g y(1.2)))/g = 1.2 + (1 + √2)/5. The step [1, 1.2] between
// the switches sees the pulse only at its stages (at 1.2, heaviside(0) = 1/2: lambda = 0).
TEST(ContactScreen, ForcePulseWithinOneStepLiftsTheRestingBall) {
  for (const char* integrator : {"dopri5", "bdf"}) {
    SCOPED_TRACE(integrator);
    Model m = parse_model(resting_ball("2*m*g*heaviside(t - 1)*heaviside(1.2 - t)"), "<pulse>");
    m.options.integrator =
        std::string(integrator) == "bdf" ? Integrator::kBDF : Integrator::kDopri5;
    m.options.output_at = {1.1, 1.4};
    const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    const auto releases = events_of(tr, ContactEvent::Kind::kRelease);
    const auto impacts = events_of(tr, ContactEvent::Kind::kImpact);
    ASSERT_EQ(releases.size(), 1u);
    ASSERT_GE(impacts.size(), 1u);
    EXPECT_NEAR(releases[0].t, 1.0, 1e-9);
    const double landing = 1.2 + (1.0 + std::sqrt(2.0)) / 5.0;  // 1.68284
    EXPECT_NEAR(impacts[0].t, landing, 1e-6);
    // the approach speed at the landing: sqrt(y'(1.2)² + 2 g y(1.2)) = √2 g/5
    EXPECT_NEAR(impacts[0].speed_before, -std::sqrt(2.0) * kG / 5.0, 1e-5);
    // y(1.1) = g (0.1)²/2 in flight, the apex at 1.4
    EXPECT_NEAR(y_at(tr, 1.1), 0.5 * kG * 0.01, 1e-6);
    EXPECT_NEAR(y_at(tr, 1.4), 2.0 * kG / 50.0, 1e-6);
  }
}

// u15 06: a smooth pulse F0 exp(−((t − 1)/0.1)²), F0 = 3 m g, no switch at all: released where
// F(t) = m g, t = 1 − 0.1 √(ln 3) = 0.895185 (the default run took 6 steps for 2 s and saw none)
TEST(ContactScreen, SmoothPulseReleasesWhereItEqualsTheWeight) {
  Model m = parse_model(resting_ball("3*m*g*exp(-((t - 1)/0.1)^2)"), "<gauss>");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto releases = events_of(tr, ContactEvent::Kind::kRelease);
  ASSERT_GE(releases.size(), 1u);
  EXPECT_NEAR(releases[0].t, 1.0 - 0.1 * std::sqrt(std::log(3.0)), 1e-9);
  // it flies: y'' = F/m − g > 0 until F = m g again at 1 + 0.1 √(ln 3), then lands
  ASSERT_GE(events_of(tr, ContactEvent::Kind::kImpact).size(), 1u);
  EXPECT_GT(events_of(tr, ContactEvent::Kind::kImpact)[0].t, 1.0 + 0.1 * std::sqrt(std::log(3.0)));
}

// u15 07: a block (m = 1) at rest on a rough floor (mu = 0.3, mu_s = 0.4), pushed along x by
// F0 = 2 mu_s m g from t = 1 to 1.2. Slips at 1 (F0 > mu_s m g); x'' = (F0 − mu m g)/m =
// 4.905 during the pulse: x'(1.2) = 0.981, x(1.2) = 0.0981; then decelerates at mu g and stops at
// t = 1.2 + 0.981/(mu g) = 1.5333 at x = 0.0981 + 0.981²/(2 mu g) = 0.2616, and stays. It stayed
// stuck at x = 0, its holding force twice mu_s N.
TEST(ContactScreen, ForcePulseWithinOneStepBreaksTheStaticFriction) {
  Model m = parse_model(
      "parameters: {m: 1, g: 9.81, mu: 0.3, mus: 0.4, F0: 7.848}\n"
      "coordinates: [x, y]\n"
      "kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)\n"
      "potential_energy: m*g*y\n"
      "forces: [F0*heaviside(t - 1)*heaviside(1.2 - t), 0]\n"
      "constraints:\n"
      "  - {name: floor, holonomic: y, unilateral: true}\n"
      "nonideal:\n"
      "  - {friction: coulomb, constraint: floor, mu: mu, mu_static: mus, coordinates: [x]}\n"
      "initial:\n"
      "  q: {x: 0, y: 0}\n"
      "simulate: {t_end: 2}\n",
      "<push>");
  m.options.output_at = {1.1, 1.2, 2.0};
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double a = 2.0 * 0.4 * kG - 0.3 * kG, v1 = 0.2 * a, x1 = 0.5 * a * 0.04;
  const double x_stop = x1 + v1 * v1 / (2.0 * 0.3 * kG);
  EXPECT_NEAR(x_stop, 0.2616, 1e-12);
  // coordinate j (x, y) at the sample nearest t
  auto q_at = [&](double t, std::size_t j) {
    std::size_t best = 0;
    for (std::size_t i = 0; i < tr.t.size(); ++i) {
      if (std::abs(tr.t[i] - t) < std::abs(tr.t[best] - t)) best = i;
    }
    return tr.q[best * std::size_t(tr.n) + j];
  };
  EXPECT_NEAR(q_at(1.1, 0), 0.5 * a * 0.01, 1e-6);
  EXPECT_NEAR(q_at(1.2, 0), x1, 1e-6);
  EXPECT_NEAR(q_at(2.0, 0), x_stop, 1e-6);
  EXPECT_NEAR(q_at(2.0, 1), 0.0, 1e-12);
}

// the zero of f in [lo, hi] (f(lo) > 0 > f(hi)) by bisection, to roundoff
template <class F>
double crossing(F f, double lo, double hi) {
  for (int i = 0; i < 100; ++i) (f(0.5 * (lo + hi)) > 0.0 ? lo : hi) = 0.5 * (lo + hi);
  return lo;
}

// a ball (e = 0.5) from (y0, y0') over a floor h(t) = H exp(−((t − tc)/0.05)²) (the gap y − h(t)
// with explicit t: no state of the run sees the surface), run to t_end
Trajectory over_moving_floor(double H, double tc, double y0, double v0, double t_end) {
  Model m = parse_model(
      "parameters: {m: 1, g: 9.81, H: " + std::to_string(H) + ", tc: " + std::to_string(tc) +
          ", w: 0.05, e: 0.5}\n"
          "coordinates: [y]\n"
          "kinetic_energy: 0.5*m*y_dot^2\n"
          "potential_energy: m*g*y\n"
          "constraints:\n"
          "  - {name: floor, holonomic: y - H*exp(-((t - tc)/w)^2), unilateral: true, "
          "restitution: e}\n"
          "initial:\n"
          "  q: {y: " +
          std::to_string(y0) + "}\n  q_dot: {y: " + std::to_string(v0) +
          "}\n"
          "simulate: {t_end: " +
          std::to_string(t_end) + "}\n",
      "<moving floor>");
  Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  return tr;
}

// u15 11: a ball dropped from 2 m; the floor h(t) = 2 exp(−((t − 0.3)/0.05)²) kicks up under it.
// Closed form: the floor reaches the ball where 2 − g t²/2 = h(t), t = 0.2771562, at an approach
// speed g' = −g t − h'(t) = −32.383 m/s. The steps of the free fall are long; the gap was −0.44 m
// at t = 0.3 and the first impact the plain landing at 0.6386.
TEST(ContactScreen, KickingFloorHitsTheFallingBallAtTheClosedFormTime) {
  auto h = [](double t) { return 2.0 * std::exp(-std::pow((t - 0.3) / 0.05, 2)); };
  const double t = crossing([&](double s) { return 2.0 - 0.5 * kG * s * s - h(s); }, 0.2, 0.3);
  EXPECT_NEAR(t, 0.2771562, 1e-7);
  const Trajectory tr = over_moving_floor(2.0, 0.3, 2.0, 0.0, 0.5);
  const auto impacts = events_of(tr, ContactEvent::Kind::kImpact);
  ASSERT_GE(impacts.size(), 1u);
  EXPECT_NEAR(impacts[0].t, t, 1e-9);
  const double h_dot = h(t) * (-2.0 * (t - 0.3) / 0.0025);
  EXPECT_NEAR(impacts[0].speed_before, -kG * t - h_dot, 1e-6);
  EXPECT_NEAR(impacts[0].speed_before, -32.383, 1e-3);
  // never below the floor: the gap (y − h) at every sample >= −1e-9
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    EXPECT_GE(tr.q[i] - h(tr.t[i]), -1e-9) << "t = " << tr.t[i];
  }
}

// u15 11 bump: a ball thrown up to its apex 4.955 m at t = 1; the floor bumps to 6 m around
// t = 1: hit where 0.05 + g t − g t²/2 = 6 exp(−((t − 1)/0.05)²), t = 0.9781004
TEST(ContactScreen, BumpingFloorHitsTheBallAtItsApex) {
  const double t = crossing(
      [](double s) {
        return 0.05 + kG * s - 0.5 * kG * s * s - 6.0 * std::exp(-std::pow((s - 1.0) / 0.05, 2));
      },
      0.9, 1.0);
  EXPECT_NEAR(t, 0.9781004, 1e-7);
  const Trajectory tr = over_moving_floor(6.0, 1.0, 0.05, kG, 1.2);
  const auto impacts = events_of(tr, ContactEvent::Kind::kImpact);
  ASSERT_GE(impacts.size(), 1u);
  EXPECT_NEAR(impacts[0].t, t, 1e-9);
}

// u15 08: a ball (e = 0.5) dropped from 1 m comes to rest (first impact 4.43 m/s); at t = 2 a
// push of F0 − m g = 1 N for 0.01 s makes it hop: v1 = 0.01 m/s and y1 = 5e-5 m at 2.01, first
// hop impact at 2.01 + t_f at v = √(v1² + 2 g y1), and the accumulation at
// t∞ = 2.01 + t_f + 2 e v/(g (1 − e)). The rest criterion compares with this sequence's fastest
// impact (0.0329 m/s), so it ends the hop ~1e-6 of its bouncing time early, as documented (with
// the drop's 4.43 m/s it stopped it 1.2e-4 early, after 13 impacts, the note counting 35).
TEST(ContactScreen, RestCriterionOfASecondSequenceUsesItsOwnFastestImpact) {
  Model m = parse_model(
      "parameters: {m: 1, g: 9.81, e: 0.5, F0: 10.81}\n"
      "coordinates: [y]\n"
      "kinetic_energy: 0.5*m*y_dot^2\n"
      "potential_energy: m*g*y\n"
      "forces: [F0*heaviside(t - 2)*heaviside(2.01 - t)]\n"
      "constraints:\n"
      "  - {name: floor, holonomic: y, unilateral: true, restitution: e}\n"
      "initial:\n"
      "  q: {y: 1}\n"
      "simulate: {t_end: 2.1, rtol: 1e-10, atol: 1e-12}\n",
      "<hop>");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double e = 0.5, v1 = (10.81 - kG) * 0.01, y1 = 0.5 * (10.81 - kG) * 1e-4;
  const double v = std::sqrt(v1 * v1 + 2.0 * kG * y1), tf = (v1 + v) / kG;
  const double bouncing = 2.0 * e * v / (kG * (1.0 - e)), t_inf = 2.01 + tf + bouncing;
  std::vector<ContactEvent> rests, hop;
  for (const ContactEvent& ev : tr.stats.contact_events) {
    if (ev.kind == ContactEvent::Kind::kRest) rests.push_back(ev);
    if (ev.t > 2.005 && ev.kind != ContactEvent::Kind::kRelease) hop.push_back(ev);
  }
  ASSERT_EQ(rests.size(), 2u);  // the drop's and the hop's
  ASSERT_GE(hop.size(), 2u);
  // the hop: released at 2 (the push is found within its 0.01 s step), first impact as above
  const auto releases = events_of(tr, ContactEvent::Kind::kRelease);
  ASSERT_EQ(releases.size(), 1u);
  EXPECT_NEAR(releases[0].t, 2.0, 1e-9);
  EXPECT_NEAR(hop[0].t, 2.01 + tf, 1e-9);
  EXPECT_NEAR(hop[0].speed_before, -v, 1e-9);
  // the rest: early by (0, 2e-6] of the hop's bouncing time, at an impact below 1e-6 of the
  // hop's first (its fastest)
  const ContactEvent& rest = rests[1];
  EXPECT_GT(t_inf - rest.t, 0.0);
  EXPECT_LT(t_inf - rest.t, 2e-6 * bouncing);
  EXPECT_LT(-rest.speed_before, 1e-6 * v);
  EXPECT_GT(-rest.speed_before, 0.45e-6 * v);  // (the one before it was above: e = 0.5)
  // the hop's note counts this sequence's impacts and names its fastest (the drop's had 4.43)
  const std::string count = " came to rest after " + std::to_string(hop.size()) + " impacts";
  int found = 0;
  for (const std::string& note : tr.stats.notes) {
    found +=
        note.find(count) != std::string::npos && note.find("fastest, 0.0329") != std::string::npos;
  }
  EXPECT_EQ(found, 1) << count;
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

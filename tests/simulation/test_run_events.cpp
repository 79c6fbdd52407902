// SPDX-License-Identifier: BSD-3-Clause
// The stops of Coulomb contacts located under every integrator (src/simulation/run_events.cpp,
// Run::locate_stop; docs/friction.md, "Stops under every integrator"). A block of mass m on a
// rough floor, launched at v0 along x against a push F (towards −x, F < mu_s m g: it holds;
// F > mu_s m g: it reverses), decelerates at a = (F + mu m g) / m and stops at t_s = v0 / a,
// x_s = v0² / (2 a). The stop is located where the speed falls to v_stop = 100 eps, at
// (v0 − v_stop) / a. Under rk4, a stage past the stop saw the friction reversed: with the stop in
// the first half of a step, the step ended at the speed it started with, and the block never
// stopped (it slid on at that speed; the energy balance failed); under rk5 and rkf78 the stop
// was found steps late (1.5 % and 0.4 %, u23 05). Each case in SI and in mm, g, ms (the same
// physics, numbers 10³ apart), under rk4 and rk5 (fixed step 1 ms), dopri5, rkf78 and bdf.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kMass = 2.0, kG = 9.81, kMu = 0.3, kMuS = 0.4;
constexpr double kVStop = 100.0 * 1e-9;  // 100 eps, eps = regularization_velocity's default

// L metres, M kilograms, T seconds per model unit (a force: M L / T² N; a speed: L / T m/s)
struct Units {
  const char* name;
  double L, M, T;
  const char* line;  // the model file's units: line
};
const Units kSI{"SI", 1.0, 1.0, 1.0, ""};
const Units kMm{"mm, g, ms", 1e-3, 1e-3, 1e-3, "units: {length: mm, mass: g, time: ms}\n"};
const Units kKm{"km, t, min", 1e3, 1e3, 60.0, "units: {length: km, mass: t, time: min}\n"};
const Units kCm{"cm, g, s", 1e-2, 1e-3, 1.0, "units: {length: cm, mass: g, time: s}\n"};

const char* const kMethods[] = {"rk4", "rk5", "dopri5", "rkf78", "bdf"};

std::string number(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}

// the block in units u (every argument in SI): pushed towards −x by F + k t, launched at v0,
// run to t_end under `method` (rk4, rk5: step 1 ms), sampled every 10 ms; `friction` adds keys
// to the friction's entry
Model block(const Units& u, const std::string& method, double v0, double F, double k, double t_end,
            const std::string& friction = "") {
  const double force = u.M * u.L / (u.T * u.T);
  const std::string text = std::string(u.line) + "parameters: {m: " + number(kMass / u.M) +
                           ", g: " + number(kG * u.T * u.T / u.L) + ", F: " + number(F / force) +
                           ", k: " + number(k * u.T / force) + ", v0: " + number(v0 * u.T / u.L) +
                           "}\n"
                           "coordinates: [x, y]\n"
                           "kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)\n"
                           "potential_energy: m*g*y\n"
                           "forces: [-F - k*t, 0]\n"
                           "constraints:\n  - {name: floor, holonomic: y}\n"
                           "nonideal:\n  - {friction: coulomb, constraint: floor, mu: " +
                           number(kMu) + ", mu_static: " + number(kMuS) + friction +
                           "}\n"
                           "initial: {q: {x: 0, y: 0}, q_dot: {x: v0, y: 0}}\n"
                           "simulate: {t_end: " +
                           number(t_end / u.T) + ", integrator: " + method +
                           ", step: " + number(1e-3 / u.T) +
                           ", rtol: 1e-10, atol: 1e-12}\n"
                           "output: {every: " +
                           number(1e-2 / u.T) + "}\n";
  return parse_model(text);
}

// x and x' of sample i in SI
double x_at(const Trajectory& tr, std::size_t i, const Units& u) { return tr.q[2 * i] * u.L; }
double v_at(const Trajectory& tr, std::size_t i, const Units& u) {
  return tr.qd[2 * i] * u.L / u.T;
}

std::vector<ContactEvent> of_kind(const Trajectory& tr, ContactEvent::Kind kind) {
  std::vector<ContactEvent> out;
  for (const ContactEvent& e : tr.stats.contact_events)
    if (e.kind == kind) out.push_back(e);
  return out;
}

// Launched at v0 against F < mu_s m g: x = v0 t − a t²/2 until the stop, located at
// (v0 − v_stop)/a, listed as the one stick; then at rest at x_s, x' = 0 exactly (the stick
// constraint holds it), status ok (the energy balance certifies the run). v0 = 3, 3.0009, 3.0017
// put the stop of the free block (F = 0) at 0.37, 0.67 and 0.95 of rk4's 1 ms step (rk4 ended
// the step at v0 below one half, above two thirds it stopped late).
TEST(RunEventsStops, BlockLaunchedOnARoughFloorStopsAtTheClosedFormAndStaysUnderEveryMethod) {
  struct Case {
    double v0, F;
  };
  for (const Units& u : {kSI, kMm}) {
    for (const char* method : kMethods) {
      for (const Case c :
           {Case{3.0, 0.0}, Case{3.0009, 0.0}, Case{3.0017, 0.0}, Case{2.0, 0.35 * kMass * kG}}) {
        SCOPED_TRACE(std::string(u.name) + ", " + method + ", v0 = " + number(c.v0) +
                     ", F = " + number(c.F));
        const double a = (c.F + kMu * kMass * kG) / kMass, t_s = c.v0 / a,
                     x_s = c.v0 * c.v0 / (2 * a);
        if (c.F == 0.0) {
          EXPECT_NEAR(t_s, c.v0 / (kMu * kG), 1e-15 * t_s);  // t_s = v0 / (mu g)
        }
        const Model m = block(u, method, c.v0, c.F, 0.0, 2.0);
        const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
        ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
        EXPECT_TRUE(tr.stats.energy_balance_checked);
        // the stop: one stick, at v = v_stop
        const auto sticks = of_kind(tr, ContactEvent::Kind::kStick);
        ASSERT_EQ(sticks.size(), 1u);
        EXPECT_EQ(tr.stats.contact_events.size(), 1u);
        EXPECT_NEAR(sticks[0].t * u.T, (c.v0 - kVStop) / a, 1e-9 * t_s);
        // (the state handed to the stop is a step of the method to it, whose last stages see the
        // law at v_stop, 5e-5 weaker than mu N: about v_stop, 1.0 to 1.7 v_stop here)
        EXPECT_NEAR(sticks[0].speed_before * u.L / u.T, kVStop, 0.8 * kVStop);
        EXPECT_EQ(tr.stats.stick_refusals, 0);
        // sliding, then at rest at x_s
        double slide_x = 0.0, slide_v = 0.0, rest = 0.0;
        std::size_t resting = 0;
        for (std::size_t i = 0; i < tr.t.size(); ++i) {
          const double t = tr.t[i] * u.T;
          if (t < t_s) {
            slide_x = std::max(slide_x, std::abs(x_at(tr, i, u) - (c.v0 * t - a * t * t / 2)));
            slide_v = std::max(slide_v, std::abs(v_at(tr, i, u) - (c.v0 - a * t)));
          } else {
            ++resting;
            rest = std::max(rest, std::abs(x_at(tr, i, u) - x_s));
            // (0 to roundoff: the stick constraint's q'' is roundoff of the push's size)
            EXPECT_NEAR(v_at(tr, i, u), 0.0, 1e-12 * c.v0) << "t = " << t;
          }
        }
        EXPECT_NEAR(slide_x, 0.0, 1e-9 * x_s);
        EXPECT_NEAR(slide_v, 0.0, 1e-9 * c.v0);
        EXPECT_GT(resting, 90u);
        EXPECT_NEAR(rest, 0.0, 1e-9 * x_s);
      }
    }
  }
}

// Launched at v0 = 2 against F = 0.5 m g > mu_s m g: it stops at t_s = v0/a, a = (F + mu m g)/m,
// cannot stick there (no stick listed: friction cannot hold it), and slides back from x_s at
// a_back = (F − mu m g)/m: x = x_s − a_back (t − t_s)²/2, x' = −a_back (t − t_s). A stop that stuck
// would fail this as surely as one not found fails the test above.
TEST(RunEventsStops, BlockPushedHarderThanStaticFrictionHoldsReversesAtTheClosedFormStop) {
  const double v0 = 2.0, F = 0.5 * kMass * kG;
  const double a = (F + kMu * kMass * kG) / kMass, t_s = v0 / a, x_s = v0 * v0 / (2 * a);
  const double a_back = (F - kMu * kMass * kG) / kMass;
  for (const Units& u : {kSI, kMm}) {
    for (const char* method : kMethods) {
      SCOPED_TRACE(std::string(u.name) + ", " + method);
      const Model m = block(u, method, v0, F, 0.0, 1.0);
      const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
      ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
      EXPECT_TRUE(of_kind(tr, ContactEvent::Kind::kStick).empty());
      EXPECT_TRUE(tr.stats.contact_events.empty());
      EXPECT_EQ(tr.stats.stick_refusals, 0);
      // the stop (at v_stop) and the passage through v = 0: two events
      EXPECT_EQ(tr.stats.events, 2);
      double before = 0.0, after_x = 0.0, after_v = 0.0;
      std::size_t back = 0;
      for (std::size_t i = 0; i < tr.t.size(); ++i) {
        const double t = tr.t[i] * u.T, x = x_at(tr, i, u), v = v_at(tr, i, u);
        if (t < t_s) {
          before = std::max(before, std::abs(x - (v0 * t - a * t * t / 2)));
        } else {
          ++back;
          const double tau = t - t_s;
          after_x = std::max(after_x, std::abs(x - (x_s - a_back * tau * tau / 2)));
          after_v = std::max(after_v, std::abs(v + a_back * tau));
        }
      }
      EXPECT_NEAR(before, 0.0, 1e-9 * x_s);
      EXPECT_GT(back, 60u);
      // (rk4, rk5, rkf78: the passage through v = 0 is located on a step of the method whose last
      // stage sees the regularized law's kink at v_rel = 0, a few ns late: x within 6e-8 x_s, x'
      // within 1e-8 v0 measured; dopri5 and BDF 1e-9)
      const bool interpolated = std::string(method) == "dopri5" || std::string(method) == "bdf";
      EXPECT_NEAR(after_x, 0.0, (interpolated ? 1e-9 : 1e-7) * x_s);
      EXPECT_NEAR(after_v, 0.0, (interpolated ? 1e-9 : 2e-8) * v0);
    }
  }
}

// The release is located as before under every method (a stuck contact's stages see the stick
// constraint past the release, no reversed force): at rest, pushed by k t towards −x, the block
// slips at t_b = mu_s m g / k (one slip listed there, 1e-9) and slides with
// x = −((mu_s − mu) g τ²/2 + k τ³/(6 m)), τ = t − t_b.
TEST(RunEventsStops, BlockAtRestPushedByARampSlipsAtMuStaticMgUnderEveryMethod) {
  const double k = 10.0, t_b = kMuS * kMass * kG / k;
  for (const Units& u : {kSI, kMm}) {
    for (const char* method : kMethods) {
      SCOPED_TRACE(std::string(u.name) + ", " + method);
      const Model m = block(u, method, 0.0, 0.0, k, 1.2);
      const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
      ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
      const auto slips = of_kind(tr, ContactEvent::Kind::kSlip);
      ASSERT_EQ(slips.size(), 1u);
      EXPECT_NEAR(slips[0].t * u.T, t_b, 1e-9 * t_b);
      double err = 0.0;
      std::size_t sliding = 0;
      for (std::size_t i = 0; i < tr.t.size(); ++i) {
        const double t = tr.t[i] * u.T, x = x_at(tr, i, u);
        if (t <= t_b) {
          EXPECT_NEAR(v_at(tr, i, u), 0.0, 1e-12) << "t = " << t;
          err = std::max(err, std::abs(x));
        } else {
          ++sliding;
          const double tau = t - t_b;
          err = std::max(err, std::abs(x + ((kMuS - kMu) * kG * tau * tau / 2 +
                                            k * tau * tau * tau / (6 * kMass))));
        }
      }
      EXPECT_GT(sliding, 30u);
      EXPECT_NEAR(err, 0.0, 1e-9);
    }
  }
}

// u24: the same block in km, t, min stopped 5.7e-7 s before v0 / (mu g): eps, and so v_stop =
// 100 eps, was 1e-9 in the model's velocity unit whatever it was (1 km/min = 16.7 m/s: v_stop
// 1.67e-6 m/s, early by v_stop / (mu g)). Now a friction without regularization_velocity takes
// 1e-9 m/s written in the model's units: (as a URDF's joint-friction regularization does), and
// the block stops at the same (v0 − v_stop) / (mu g), v_stop = 1e-7 m/s, in SI, mm/g/ms, cm/g/s
// and km/t/min — a coordinates model (reader_nonideal.cpp) and a bodies model's contact
// (reader_contacts.cpp) alike.
Model bodies_block(const Units& u, double v0, double t_end) {
  const std::string text =
      std::string(u.line) + "parameters: {m: " + number(kMass / u.M) +
      ", g: " + number(kG * u.T * u.T / u.L) + ", v0: " + number(v0 * u.T / u.L) +
      "}\n"
      "bodies:\n  - {name: b, type: planar, mass: m, inertia: m, position: [0, 0], velocity: "
      "[v0, 0]}\n"
      "forces:\n  - {type: gravity, g: [0, -g]}\n"
      "contacts:\n  - {name: floor, body: b, point: [0, 0]}\n"
      "nonideal:\n  - {friction: coulomb, constraint: floor, mu: " +
      number(kMu) +
      "}\n"
      "simulate: {t_end: " +
      number(t_end / u.T) + ", rtol: 1e-10, atol: 1e-12}\noutput: {every: " + number(0.1 / u.T) +
      "}\n";
  return parse_model(text);
}

TEST(RunEventsStops, BlockStopsAtTheSameTimeInKilometresTonnesMinutesAsInSI) {
  const double v0 = 2.0, t_s = (v0 - kVStop) / (kMu * kG);  // 0.679578593 s
  for (const Units& u : {kSI, kMm, kCm, kKm}) {
    for (const bool bodies : {false, true}) {
      SCOPED_TRACE(std::string(u.name) + (bodies ? ", bodies" : ", coordinates"));
      const Model m = bodies ? bodies_block(u, v0, 1.0) : block(u, "dopri5", v0, 0.0, 0.0, 1.0);
      const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
      ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
      const auto sticks = of_kind(tr, ContactEvent::Kind::kStick);
      ASSERT_EQ(sticks.size(), 1u);
      // (was 0.6795780609 s in km, t, min: 5.66e-7 s early; 3.4e-8 s early in SI, which is
      // v_stop / (mu g): the located stop, not the closed form's v0 / (mu g))
      EXPECT_NEAR(sticks[0].t * u.T, t_s, 1e-10);
      EXPECT_NEAR(sticks[0].t * u.T, v0 / (kMu * kG), 4e-8);
      EXPECT_NEAR(sticks[0].speed_before * u.L / u.T, kVStop, 0.8 * kVStop);
    }
  }
}

// A regularization_velocity written in the file is the model's, as written: 1e-9 km/min stops
// the block at v_stop = 1e-7 km/min = 1.67e-6 m/s, (v0 − v_stop) / (mu g) in those units.
TEST(RunEventsStops, AWrittenRegularizationVelocityIsInTheModelsOwnUnits) {
  const double v0 = 2.0;
  const Model m = block(kKm, "dopri5", v0, 0.0, 0.0, 1.0, ", regularization_velocity: 1e-9");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto sticks = of_kind(tr, ContactEvent::Kind::kStick);
  ASSERT_EQ(sticks.size(), 1u);
  const double v_stop = kVStop * kKm.L / kKm.T;  // in m/s
  EXPECT_NEAR(sticks[0].t * kKm.T, (v0 - v_stop) / (kMu * kG), 1e-10);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// Several rough contacts of one body stopping and holding together (docs/friction.md, "Several
// contacts"), against closed forms: a box on two point contacts (planar) or four corners
// (spatial), mu = 0.3, mu_static = 0.5, m = 3, launched at -1 m/s against a push F at floor
// level stops at t_s = m / (F + mu m g) and stays stuck for F < mu_s m g, its holding forces
// inside both cones and summing to -F (every contact sticks, not only the one whose stop event
// fired); the box at rest pushed by F = k t breaks away at t_b = mu_s m g / k, pushed at its
// centre too (the tipping moment moves N between the ends; a split of the holding force inside
// both cones exists until then, although the minimum-norm one leaves the lighter end's cone at
// 1.308 s).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "support/contact_runs.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81, kMass = 3.0, kMu = 0.3, kMuS = 0.5;

// column `name` of field f (width n) at sample i
constexpr auto* at = &testing::coordinate_at;
// the multipliers of constraint `name` at sample i (its rows; from lambda, or lambda_total's
// unilateral entries when `total`)
std::vector<double> multipliers(const Trajectory& tr, const std::string& name, std::size_t i) {
  Index row = 0;
  for (std::size_t k = 0; k < tr.constraint_names.size(); ++k) {
    if (tr.constraint_names[k] == name) {
      const auto* first = tr.lambda.data() + i * std::size_t(tr.m) + std::size_t(row);
      return {first, first + tr.constraint_rows[k]};
    }
    row += tr.constraint_rows[k];
  }
  ADD_FAILURE() << "no constraint " << name;
  return {};
}
double norm(const std::vector<double>& v) {
  double s = 0.0;
  for (double e : v) s += e * e;
  return std::sqrt(s);
}

// the run of `text` sampled at `times`; it must end ok
Trajectory run_at(const std::string& text, std::vector<double> times) {
  Model m = parse_model(text);
  m.options.output_at = std::move(times);
  Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  return tr;
}

// planar box (half-length a = 0.2, half-height c = 0.05) on its two bottom corners, pushed by
// `force` at the point `point` (body frame), launched at x' = v0
std::string planar_box(const std::string& force, const std::string& point, double v0,
                       double t_end) {
  return "parameters: {m: 3, a: 0.2, c: 0.05, g: 9.81, k: 10, mu: 0.3, mus: 0.5}\n"
         "bodies:\n"
         "  - {name: box, type: planar, mass: m, inertia: m*(4*a^2+4*c^2)/12, position: [0, c],"
         " velocity: [" +
         std::to_string(v0) +
         ", 0]}\n"
         "forces:\n"
         "  - {type: gravity, g: [0, -g]}\n"
         "  - {name: push, type: applied, body: box, point: " +
         point + ", force: [" + force +
         ", 0], torque: 0}\n"
         "contacts:\n"
         "  - {name: left, body: box, point: [-a, -c]}\n"
         "  - {name: right, body: box, point: [a, -c]}\n"
         "nonideal:\n"
         "  - {friction: coulomb, constraint: left, mu: mu, mu_static: mus}\n"
         "  - {friction: coulomb, constraint: right, mu: mu, mu_static: mus}\n"
         "simulate: {t_end: " +
         std::to_string(t_end) + ", rtol: 1e-10, atol: 1e-12}\noutput: {every: 0}\n";
}
// the spatial box (a = 0.2, b = 0.1, c = 0.05) on its four bottom corners, likewise
std::string spatial_box(const std::string& force, const std::string& point, double v0,
                        double t_end) {
  std::string text =
      "parameters: {m: 3, a: 0.2, b: 0.1, c: 0.05, g: 9.81, k: 10, mu: 0.3, mus: 0.5}\n"
      "bodies:\n"
      "  - {name: box, type: rigid, mass: m, inertia: [m*(b^2+c^2)/3, m*(a^2+c^2)/3,"
      " m*(a^2+b^2)/3], position: [0, 0, c], velocity: [" +
      std::to_string(v0) +
      ", 0, 0]}\n"
      "forces:\n"
      "  - {type: gravity, g: [0, 0, -g]}\n"
      "  - {name: push, type: applied, body: box, point: " +
      point + ", force: [" + force +
      ", 0, 0], torque: [0, 0, 0]}\n"
      "contacts:\n"
      "  - {name: c1, body: box, point: [a, b, -c]}\n"
      "  - {name: c2, body: box, point: [-a, b, -c]}\n"
      "  - {name: c3, body: box, point: [a, -b, -c]}\n"
      "  - {name: c4, body: box, point: [-a, -b, -c]}\n"
      "nonideal:\n";
  for (const char* c : {"c1", "c2", "c3", "c4"})
    text += std::string("  - {friction: coulomb, constraint: ") + c + ", mu: mu, mu_static: mus}\n";
  return text + "simulate: {t_end: " + std::to_string(t_end) +
         ", rtol: 1e-10, atol: 1e-12}\noutput: {every: 0}\n";
}

// every contact's holding force (its stick multipliers: kappa = 1 in SI units) inside its cone
// |f| <= mu_s N, and their x components summing to `sum`
void expect_held(const Trajectory& tr, const std::vector<std::string>& contacts, double sum,
                 std::size_t i) {
  double total = 0.0, normal = 0.0;
  for (const std::string& c : contacts) {
    const std::vector<double> f = multipliers(tr, "stick.coulomb." + c, i);
    const double N = multipliers(tr, c, i)[0];
    ASSERT_FALSE(f.empty());
    EXPECT_GT(N, 0.0) << c << " at t = " << tr.t[i];
    EXPECT_LE(norm(f), kMuS * N + 1e-6) << c << " at t = " << tr.t[i];
    total += f[0];
    normal += N;
  }
  EXPECT_NEAR(total, sum, 1e-7 * std::max(1.0, std::abs(sum))) << "t = " << tr.t[i];
  EXPECT_NEAR(normal, kMass * kG, 1e-7) << "t = " << tr.t[i];
}

// launched at -1 m/s against F at floor level: x' = -1 + (F + mu m g) t / m until t_s, then 0
void expect_stops_and_sticks(const Trajectory& tr, double F,
                             const std::vector<std::string>& contacts) {
  const double a = (F + kMu * kMass * kG) / kMass, t_s = 1.0 / a;
  const double x_s = -t_s + 0.5 * a * t_s * t_s;
  EXPECT_GE(tr.stats.events, 1);
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    const double t = tr.t[i];
    const bool sliding = t < t_s;
    EXPECT_NEAR(at(tr, tr.qd, "box.x", i), sliding ? -1.0 + a * t : 0.0, 1e-7) << "t = " << t;
    EXPECT_NEAR(at(tr, tr.q, "box.x", i), sliding ? -t + 0.5 * a * t * t : x_s, 1e-7)
        << "t = " << t;
    if (!sliding) expect_held(tr, contacts, -F, i);
  }
}

TEST(StickSeveralContacts, PlanarBoxStopsAgainstAPushAndBothCornersHold) {
  // F = 6 < mu m g: it would stop anyway; 8 and 10: mu m g < F < mu_s m g (it crept at 1e-9 m/s
  // or slid away when only the corner whose stop fired stuck); 13.5: close to mu_s m g = 14.7
  for (double F : {6.0, 8.0, 10.0, 13.5}) {
    SCOPED_TRACE("F = " + std::to_string(F));
    const double t_s = kMass / (F + kMu * kMass * kG);
    const Trajectory tr = run_at(planar_box(std::to_string(F), "[0, -c]", -1.0, 1.5),
                                 {0.05, t_s - 1e-4, t_s + 1e-4, 0.5, 1.0});
    expect_stops_and_sticks(tr, F, {"left", "right"});
  }
}

TEST(StickSeveralContacts, SpatialBoxOnFourCornersStopsAgainstAPushAndHolds) {
  const double F = 10.0, t_s = kMass / (F + kMu * kMass * kG);
  const Trajectory tr =
      run_at(spatial_box("10", "[0, 0, -c]", -1.0, 1.0), {0.05, t_s - 1e-4, t_s + 1e-4, 0.5, 1.0});
  expect_stops_and_sticks(tr, F, {"c1", "c2", "c3", "c4"});
}

// at rest, pushed by F = k t: stuck until t_b = mu_s m g / k, then x' = (k/2 (t² − t_b²) −
// mu m g (t − t_b)) / m (both ends slide, their normal forces summing to m g)
void expect_breakaway(const Trajectory& tr, const std::vector<std::string>& contacts) {
  const double k = 10.0, t_b = kMuS * kMass * kG / k;
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    const double t = tr.t[i];
    const double v =
        t <= t_b ? 0.0 : (0.5 * k * (t * t - t_b * t_b) - kMu * kMass * kG * (t - t_b)) / kMass;
    if (std::abs(t - t_b) <= 1e-6) {
      // within 1e-6 of t_b: at rest before, moving after (x' = (k t_b − mu m g) / m · 1e-6)
      if (t < t_b) {
        EXPECT_LT(std::abs(at(tr, tr.qd, "box.x", i)), 1e-9) << "t = " << t;
      }
      if (t > t_b) {
        EXPECT_GT(at(tr, tr.qd, "box.x", i), 1e-7) << "t = " << t;
      }
      continue;
    }
    EXPECT_NEAR(at(tr, tr.qd, "box.x", i), v, 1e-6 + 1e-6 * std::abs(v)) << "t = " << t;
    if (t < t_b) expect_held(tr, contacts, -k * t, i);
  }
}

TEST(StickSeveralContacts, PlanarBoxPushedAtItsCentreBreaksAwayAtMuStaticMg) {
  const double t_b = kMuS * kMass * kG / 10.0;
  const std::vector<double> times = {0.6, 1.2, 1.35, 1.45, t_b - 1e-6, t_b + 1e-6, 1.55};
  // at the centre (the minimum-norm split leaves the left end's cone at 1.308 s) and at the floor
  for (const char* point : {"[0, 0]", "[0, -c]"}) {
    SCOPED_TRACE(point);
    const Trajectory tr = run_at(planar_box("k*t", point, 0.0, 1.6), times);
    expect_breakaway(tr, {"left", "right"});
    // at the centre the ends carry m g / 2 ∓ k t c / (2 a) before the breakaway
    if (std::string(point) == "[0, 0]") {
      for (std::size_t i = 0; i < tr.t.size(); ++i) {
        const double t = tr.t[i], shift = 10.0 * t * 0.05 / 0.4;
        if (t >= t_b) continue;
        EXPECT_NEAR(multipliers(tr, "left", i)[0], 0.5 * kMass * kG - shift, 1e-7) << t;
        EXPECT_NEAR(multipliers(tr, "right", i)[0], 0.5 * kMass * kG + shift, 1e-7) << t;
      }
    }
  }
}

TEST(StickSeveralContacts, SpatialBoxPushedAtItsCentreBreaksAwayAtMuStaticMg) {
  const double t_b = kMuS * kMass * kG / 10.0;
  const Trajectory tr = run_at(spatial_box("k*t", "[0, 0, 0]", 0.0, 1.6),
                               {0.6, 1.2, 1.35, 1.45, t_b - 1e-6, t_b + 1e-6, 1.55});
  expect_breakaway(tr, {"c1", "c2", "c3", "c4"});
}

// ---- the coordinate path: a bar in natural coordinates on two rough coordinate contacts --------

// A uniform bar (m = 3, L = 0.4) with its ends A, B on the floor (yA = 0, yB = 0), friction on
// xA and xB (coordinates:), pushed along x by `push` at its centre (half on each end's x), B
// loaded by W downwards: N_A = m g / 2, N_B = m g / 2 + W.
std::string bar(const std::string& push, double v0, double W, double t_end) {
  return "parameters: {m: 3, L: 0.4, g: 9.81, k: 10, mu: 0.3, mus: 0.5, W: " + std::to_string(W) +
         "}\n"
         "coordinates: [xA, yA, xB, yB]\n"
         "kinetic_energy: m/6*(xA_dot^2 + yA_dot^2 + xA_dot*xB_dot + yA_dot*yB_dot + xB_dot^2 +"
         " yB_dot^2)\n"
         "potential_energy: m*g*(yA + yB)/2\n"
         "forces: [(" +
         push + ")/2, 0, (" + push +
         ")/2, -W]\n"
         "constraints:\n"
         "  - {name: rod, holonomic: ((xA - xB)^2 + (yA - yB)^2 - L^2)/(2*L)}\n"
         "  - {name: floor_a, holonomic: yA}\n"
         "  - {name: floor_b, holonomic: yB}\n"
         "nonideal:\n"
         "  - {friction: coulomb, constraint: floor_a, mu: mu, mu_static: mus, coordinates: [xA]}\n"
         "  - {friction: coulomb, constraint: floor_b, mu: mu, mu_static: mus, coordinates: [xB]}\n"
         "initial:\n"
         "  q: {xA: -L/2, yA: 0, xB: L/2, yB: 0}\n"
         "  q_dot: {xA: " +
         std::to_string(v0) + ", yA: 0, xB: " + std::to_string(v0) +
         ", yB: 0}\n"
         "simulate: {t_end: " +
         std::to_string(t_end) + ", rtol: 1e-10, atol: 1e-12}\noutput: {every: 0}\n";
}

TEST(StickSeveralContacts, CoordinatePathBarStopsAgainstAPushAndBreaksAwayUnderARamp) {
  // launched at -1 m/s against F = 10 (mu m g < F < mu_s m g): stops at t_s, both ends hold
  const double F = 10.0, t_s = kMass / (F + kMu * kMass * kG), a = 1.0 / t_s;
  const Trajectory stop = run_at(bar("10", -1.0, 0.0, 1.5), {0.05, t_s - 1e-4, t_s + 1e-4, 1.0});
  for (std::size_t i = 0; i < stop.t.size(); ++i) {
    const double t = stop.t[i];
    EXPECT_NEAR(at(stop, stop.qd, "xA", i), t < t_s ? -1.0 + a * t : 0.0, 1e-7) << "t = " << t;
    if (t < t_s) continue;
    const double fa = multipliers(stop, "stick.coulomb.floor_a", i)[0],
                 fb = multipliers(stop, "stick.coulomb.floor_b", i)[0];
    EXPECT_NEAR(fa + fb, -F, 1e-7) << "t = " << t;
    EXPECT_LE(std::abs(fa), kMuS * 0.5 * kMass * kG + 1e-6) << "t = " << t;
    EXPECT_LE(std::abs(fb), kMuS * 0.5 * kMass * kG + 1e-6) << "t = " << t;
  }
  // at rest under F = k t with B loaded by W = 10: breakaway at mu_s (m g + W) / k (the
  // minimum-norm split, equal, left A's cone at mu_s m g / k = 1.4715 s)
  const double W = 10.0, k = 10.0, load = kMass * kG + W, t_b = kMuS * load / k;
  const Trajectory ramp =
      run_at(bar("k*t", 0.0, W, 2.1), {1.0, 1.5, 1.9, t_b - 1e-6, t_b + 1e-6, 2.1});
  for (std::size_t i = 0; i < ramp.t.size(); ++i) {
    const double t = ramp.t[i], v = at(ramp, ramp.qd, "xA", i);
    if (t < t_b) {
      EXPECT_LT(std::abs(v), 1e-9) << "t = " << t;
      const double fa = multipliers(ramp, "stick.coulomb.floor_a", i)[0],
                   fb = multipliers(ramp, "stick.coulomb.floor_b", i)[0];
      EXPECT_NEAR(fa + fb, -k * t, 1e-7) << "t = " << t;
      EXPECT_LE(std::abs(fa), kMuS * 0.5 * kMass * kG + 1e-6) << "t = " << t;
      EXPECT_LE(std::abs(fb), kMuS * (0.5 * kMass * kG + W) + 1e-6) << "t = " << t;
    } else {
      const double closed = (0.5 * k * (t * t - t_b * t_b) - kMu * load * (t - t_b)) / kMass;
      EXPECT_NEAR(v, closed, 1e-6 + 1e-6 * closed) << "t = " << t;
      if (t < t_b + 1e-5) {
        EXPECT_GT(v, 1e-7) << "t = " << t;
      }
    }
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

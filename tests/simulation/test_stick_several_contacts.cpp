// SPDX-License-Identifier: BSD-3-Clause
// Several rough contacts of one body stopping and holding together (docs/friction.md, "Several
// contacts"), against closed forms: a box on two point contacts (planar) or four corners
// (spatial), mu = 0.3, mu_static = 0.5, m = 3, launched at -1 m/s against a push F at floor
// level stops at t_s = m / (F + mu m g) and stays stuck for F < mu_s m g, its holding forces
// inside both cones and summing to -F (every contact sticks, not only the one whose stop event
// fired); the box at rest pushed by F = k t breaks away at t_b = mu_s m g / k, pushed at its
// centre too (the tipping moment moves N between the ends; a split of the holding force inside
// both cones exists until then, although the minimum-norm one leaves the lighter end's cone at
// 1.308 s). Groups that stop together where only part of them can hold:
// test_stick_partial_hold.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "support/contact_runs.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/modelfile/visual.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81, kMass = 3.0, kMu = 0.3, kMuS = 0.5;

// column `name` of field f (width n) at sample i
constexpr auto* at = &testing::coordinate_at;
constexpr auto* multipliers = &testing::constraint_multipliers;
constexpr auto* norm = &testing::vector_norm;
constexpr auto* run_at = &testing::run_sampled_at;

// the contacts: and nonideal: entries of point contacts (name, point in the body frame) of
// `body`, each with Coulomb friction mu, mu_static mus
std::string rough_contacts(const std::string& body,
                           const std::vector<std::pair<std::string, std::string>>& points) {
  std::string text = "contacts:\n";
  for (const auto& [name, point] : points)
    text += "  - {name: " + name + ", body: " + body + ", point: " + point + "}\n";
  text += "nonideal:\n";
  for (const auto& [name, point] : points)
    text += "  - {friction: coulomb, constraint: " + name + ", mu: mu, mu_static: mus}\n";
  return text;
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
      point + ", force: [" + force + ", 0, 0], torque: [0, 0, 0]}\n" +
      rough_contacts("box", {{"c1", "[a, b, -c]"},
                             {"c2", "[-a, b, -c]"},
                             {"c3", "[a, -b, -c]"},
                             {"c4", "[-a, -b, -c]"}});
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

// ---- several contacts at rest after an impact, decided together ----------------------------

// The planar box (m = 3, a = 0.2, c = 0.05) dropped flat on its two corners from h = 0.2 above
// the floor (restitution 0), moving along x at v0 and pushed along x by F at its centre: it
// lands at t1 = √(2 h / g) with v_z⁻ = g t1 and v_x⁻ = v0 + F t1 / m; the impact's normal
// impulse is m v_z⁻ (both corners stay: ω⁺ = 0, the corners' impulses m v_z⁻ / 2 ∓ ... > 0), and
// its friction stops the slide when m |v_x⁻| <= mu m v_z⁻, else v_x⁺ = v_x⁻ − mu v_z⁻ (mu = 0.3)
std::string dropped_box(double v0, double F) {
  std::string text = planar_box(std::to_string(F), "[0, 0]", v0, 1.0);
  const std::string at_rest = "position: [0, c]";
  text.replace(text.find(at_rest), at_rest.size(), "position: [0, c + 0.2]");
  for (const char* corner : {"point: [-a, -c]}", "point: [a, -c]}"}) {
    const std::string with =
        std::string(corner).substr(0, std::string(corner).size() - 1) + ", restitution: 0}";
    text.replace(text.find(corner), std::string(corner).size(), with);
  }
  return text;
}

TEST(StickSeveralContacts, BoxDroppedFlatStopsAtTheImpactAndBothCornersHoldThePush) {
  // v0 = −0.5 against F = 10: v_x⁻ = 0.173 <= mu v_z⁻ = 0.594, so the impact stops it; at rest
  // the push (mu m g = 8.83 < F < mu_s m g = 14.7; neither corner alone holds it, mu_s N_i <= 8)
  // is held by both corners together, decided jointly right after the impact
  const double F = 10.0, t1 = std::sqrt(2.0 * 0.2 / kG), x1 = -0.5 * t1 + 0.5 * F / kMass * t1 * t1;
  const Trajectory tr = run_at(dropped_box(-0.5, F), {0.5 * t1, t1 + 1e-3, 0.5, 1.0});
  ASSERT_FALSE(tr.stats.contact_events.empty());
  EXPECT_NEAR(tr.stats.contact_events.front().t, t1, 1e-9);
  for (std::size_t i = 1; i < tr.t.size(); ++i) {
    const double t = tr.t[i];
    if (t < t1) {
      EXPECT_NEAR(at(tr, tr.qd, "box.x", i), -0.5 + F / kMass * t, 1e-9) << "t = " << t;
      continue;
    }
    EXPECT_NEAR(at(tr, tr.q, "box.x", i), x1, 1e-9) << "t = " << t;
    EXPECT_NEAR(at(tr, tr.qd, "box.x", i), 0.0, 1e-12) << "t = " << t;
    EXPECT_NEAR(at(tr, tr.qd, "box.y", i), 0.0, 1e-12) << "t = " << t;
    expect_held(tr, {"left", "right"}, -F, i);
  }
}

TEST(StickSeveralContacts, BoxDroppedFlatSlidesThroughTheImpactThenStopsAndSticks) {
  // v0 = 1, no push: v_x⁺ = 1 − mu v_z⁻ = 0.406, then x'' = −mu g until it stops at
  // t1 + v_x⁺ / (mu g), both corners together, and stays
  const double t1 = std::sqrt(2.0 * 0.2 / kG), vz = kG * t1, v1 = 1.0 - kMu * vz;
  const double ts = t1 + v1 / (kMu * kG), xs = t1 + v1 * v1 / (2.0 * kMu * kG);
  const Trajectory tr = run_at(dropped_box(1.0, 0.0), {0.5 * t1, t1 + 1e-3, ts - 1e-3, 0.5, 1.0});
  for (std::size_t i = 1; i < tr.t.size(); ++i) {
    const double t = tr.t[i];
    const double v = t < t1 ? 1.0 : t < ts ? v1 - kMu * kG * (t - t1) : 0.0;
    const double x = t < t1   ? t
                     : t < ts ? t1 + v1 * (t - t1) - 0.5 * kMu * kG * (t - t1) * (t - t1)
                              : xs;
    EXPECT_NEAR(at(tr, tr.qd, "box.x", i), v, 1e-7) << "t = " << t;
    EXPECT_NEAR(at(tr, tr.q, "box.x", i), x, 1e-7) << "t = " << t;
    if (t > ts) expect_held(tr, {"left", "right"}, 0.0, i);
  }
}

// ---- contacts at rest at the start, decided together (docs/friction.md, "Several contacts") ----

// every contact's holding force inside its cone (|f| <= mu_s N, N > 0 or an open contact
// holding nothing; to the split search's 1e-7 of the forces, 5e-6 N on the table); returns the
// sums of the first tangential components and of N
std::pair<double, double> held_sums(const Trajectory& tr, const std::vector<std::string>& contacts,
                                    std::size_t i) {
  double total = 0.0, normal = 0.0;
  for (const std::string& c : contacts) {
    const std::vector<double> f = multipliers(tr, "stick.coulomb." + c, i);
    const double N = multipliers(tr, c, i)[0];
    EXPECT_GE(N, 0.0) << c << " at t = " << tr.t[i];
    EXPECT_LE(norm(f), kMuS * N + 1e-5) << c << " at t = " << tr.t[i];
    total += f.empty() ? 0.0 : f[0];
    normal += N;
  }
  return {total, normal};
}

// A planar box (m = 3, on its two bottom corners) put at rest on a belt that accelerates at A
// from rest (a planar body driven along x by ½ A t²): it rides with the belt, x' = A t, while
// m A <= mu_s m g (4.905) — neither corner alone can hold m A = 12 N at A = 4 (mu_s N = 7.9 and
// 6.8 N), the pair can — and above it slides at x'' = mu g (main slid at mu g for A = 4)
TEST(StickSeveralContacts, BoxAtRestOnAnAcceleratingBeltRidesBelowMuStaticG) {
  for (double A : {2.0, 4.0, 6.0}) {
    SCOPED_TRACE("A = " + std::to_string(A));
    const Trajectory tr = run_at(
        "parameters: {m: 3, M: 10, a: 0.2, c: 0.05, g: 9.81, mu: 0.3, mus: 0.5, A: " +
            std::to_string(A) +
            "}\n"
            "bodies:\n"
            "  - {name: belt, type: planar, mass: M, inertia: 1, position: [0, 0]}\n"
            "  - {name: box, type: planar, mass: m, inertia: m*(4*a^2+4*c^2)/12,"
            " position: [0, c]}\n"
            "joints:\n"
            "  - {name: drive, type: prismatic, parent: ground, child: belt, drive: 0.5*A*t^2}\n"
            "forces:\n"
            "  - {type: gravity, g: [0, -g]}\n"
            "contacts:\n"
            "  - {name: cl, body: box, point: [-a, -c], plane: {body: belt, point: [0, 0],"
            " normal: [0, 1]}}\n"
            "  - {name: cr, body: box, point: [a, -c], plane: {body: belt, point: [0, 0],"
            " normal: [0, 1]}}\n"
            "nonideal:\n"
            "  - {friction: coulomb, constraint: cl, mu: mu, mu_static: mus}\n"
            "  - {friction: coulomb, constraint: cr, mu: mu, mu_static: mus}\n"
            "simulate: {t_end: 1, rtol: 1e-10, atol: 1e-12}\noutput: {every: 0}\n",
        {0.25, 0.5, 1.0});
    const bool rides = A <= kMuS * kG;
    for (std::size_t i = 0; i < tr.t.size(); ++i) {
      const double t = tr.t[i];
      EXPECT_NEAR(at(tr, tr.qd, "box.x", i), (rides ? A : kMu * kG) * t, 1e-8) << "t = " << t;
      EXPECT_NEAR(at(tr, tr.q, "box.x", i), 0.5 * (rides ? A : kMu * kG) * t * t, 1e-8)
          << "t = " << t;
      if (!rides) continue;
      const auto [total, normal] = held_sums(tr, {"cl", "cr"}, i);
      EXPECT_NEAR(std::abs(total), kMass * A, 1e-7) << "t = " << t;
      EXPECT_NEAR(normal, kMass * kG, 1e-7) << "t = " << t;
    }
  }
}

// The table of the u14 reproducers (rigid body m = 10, COM 0.4 above the floor, legs at
// x = −0.5 / 0.3, y = ±0.3, mu = 0.3, mu_s = 0.5 at each), pushed along x at 0.5 height by F, in
// the unit system of `units` with the factors of length, mass and time from SI (lf, mf, tf)
// (plus a ramp k t, at the height h above the centre of mass: 0.1 by default)
std::string table(const std::string& units, double lf, double mf, double tf, double F, double v0,
                  double k = 0.0, double h = 0.1) {
  const double force = mf * lf / (tf * tf);
  auto num = [](double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.17g", v);
    return std::string(b);
  };
  std::string text =
      units + "parameters: {m: " + num(10 * mf) + ", g: " + num(9.81 * lf / (tf * tf)) +
      ", F: " + num(F * force) + ", v0: " + num(v0 * lf / tf) + ", L: " + num(lf) +
      ", k: " + num(k * force / tf) +
      ", mu: 0.3, mus: 0.5}\n"
      "bodies:\n"
      "  - {name: table, type: rigid, mass: m, inertia: [" +
      num(1.2 * mf * lf * lf) + ", " + num(1.5 * mf * lf * lf) + ", " + num(2.0 * mf * lf * lf) +
      "], position: [0, 0, 0.4*L], velocity: [v0, 0, 0]}\n"
      "forces:\n"
      "  - {type: gravity, g: [0, 0, -g]}\n"
      "  - {name: push, type: applied, body: table, point: [0, 0, " +
      num(h) + "*L], force: [F + k*t, 0, 0], torque: [0, 0, 0]}\n" +
      rough_contacts("table", {{"l1", "[-0.5*L, -0.3*L, -0.4*L]"},
                               {"l2", "[-0.5*L, 0.3*L, -0.4*L]"},
                               {"l3", "[0.3*L, -0.3*L, -0.4*L]"},
                               {"l4", "[0.3*L, 0.3*L, -0.4*L]"}});
  return text + "simulate: {t_end: " + num(1.5 * tf) +
         ", rtol: 1e-10, atol: 1e-12}\noutput: {every: 0}\n";
}
const std::vector<std::string> kLegs = {"l1", "l2", "l3", "l4"};
constexpr double kTableMass = 10.0;

// at rest pushed by F = 40 < mu_s m g = 49.05 N: it stays, its legs holding 40 N together inside
// their cones (main slid at (F − mu m g)/m: the most loaded leg alone holds 24.5 N); at
// F = 50 > mu_s m g it slides, x'' = (F − mu m g)/m, straight along x
TEST(StickSeveralContacts, TableAtRestHoldsAPushBelowMuStaticMgAndSlidesAbove) {
  const Trajectory stays = run_at(table("", 1, 1, 1, 40.0, 0.0), {0.5, 1.0, 1.5});
  for (std::size_t i = 0; i < stays.t.size(); ++i) {
    EXPECT_NEAR(at(stays, stays.q, "table.x", i), 0.0, 1e-12) << "t = " << stays.t[i];
    EXPECT_NEAR(at(stays, stays.qd, "table.x", i), 0.0, 1e-12) << "t = " << stays.t[i];
    const auto [total, normal] = held_sums(stays, kLegs, i);
    EXPECT_NEAR(total, -40.0, 1e-7) << "t = " << stays.t[i];
    EXPECT_NEAR(normal, kTableMass * kG, 1e-7) << "t = " << stays.t[i];
  }
  const double a = (50.0 - kMu * kTableMass * kG) / kTableMass;
  const Trajectory slides = run_at(table("", 1, 1, 1, 50.0, 0.0), {0.5, 1.0, 1.5});
  for (std::size_t i = 0; i < slides.t.size(); ++i) {
    const double t = slides.t[i];
    EXPECT_NEAR(at(slides, slides.qd, "table.x", i), a * t, 1e-9) << "t = " << t;
    EXPECT_NEAR(at(slides, slides.q, "table.x", i), 0.5 * a * t * t, 1e-9) << "t = " << t;
    EXPECT_NEAR(at(slides, slides.qd, "table.y", i), 0.0, 1e-9) << "t = " << t;
  }
}

// At rest, pushed by F = k t (k = 50) at the height of the legs through the centre of mass: the
// push and the legs' friction have no moment about the centre of mass, so N = m g stays
// split among the legs as at rest (l1, l2 behind carry 3/8 of it, l3, l4 in front 5/8), and
// a split of the holding forces inside every cone exists while k t <= mu_s m g: the
// breakaway is at t_b = mu_s m g / k = 0.981 s (the minimum-norm split, equal shares of k t,
// leaves the back legs' cones at 3/4 of that, where the split search takes over). Then all
// four slide, x' = (k (t² − t_b²)/2 − mu m g (t − t_b)) / m; t_b is found from x' at t:
// x' = (mu_s − mu) g τ + k τ² / (2 m), τ = t − t_b. In SI and in mm, g, ms.
TEST(StickSeveralContacts, TableUnderARampBreaksAwayAtMuStaticMgInAnyUnits) {
  struct Units {
    std::string line;
    double lf, mf, tf;
  };
  const std::vector<Units> systems = {{"", 1, 1, 1},
                                      {"units: {length: mm, mass: g, time: ms}\n", 1e3, 1e3, 1e3}};
  const double k = 50.0, t_b = kMuS * kTableMass * kG / k;
  const double b = (kMuS - kMu) * kG, c = k / (2 * kTableMass);
  // (1e-9 s either side: at rest, then x' = b 1e-9 within the start of the slide's rounding)
  const std::vector<double> times = {0.5, 0.9, t_b - 1e-9, t_b + 1e-9, 1.2, 1.5};
  std::vector<double> si_x, si_v;
  for (const Units& u : systems) {
    SCOPED_TRACE("length x" + std::to_string(u.lf));
    std::vector<double> scaled;
    for (double t : times) scaled.push_back(t * u.tf);
    const Trajectory tr = run_at(table(u.line, u.lf, u.mf, u.tf, 0.0, 0.0, k, -0.4), scaled);
    // the breakaway: all four legs slip at t_b (measured: 2.0e-12 s late in SI, 2.2e-12 in mm,
    // g, ms, where the split space's null space of the rows taken unscaled put it 1.8e-10 s late
    // — 6e-9 s early with h16's steps; main before h15: 1.4e-7 and 5.3e-7 early)
    int slips = 0;
    for (const ContactEvent& ev : tr.stats.contact_events) {
      if (ev.kind != ContactEvent::Kind::kSlip) continue;
      EXPECT_NEAR(ev.t / u.tf, t_b, 1e-11) << ev.friction;
      ++slips;
    }
    EXPECT_EQ(slips, 4);
    for (std::size_t i = 0; i < tr.t.size(); ++i) {
      const double t = tr.t[i] / u.tf, x = at(tr, tr.q, "table.x", i) / u.lf,
                   v = at(tr, tr.qd, "table.x", i) * u.tf / u.lf;
      EXPECT_NEAR(at(tr, tr.qd, "table.y", i) * u.tf / u.lf, 0.0, 1e-12) << "t = " << t;
      if (u.lf == 1.0) {
        si_x.push_back(x);
        si_v.push_back(v);
      } else if (i < si_x.size()) {
        // the same motion as in SI (to 1e-9 of its size at 1.5 s: 1.7 m/s, 0.5 m)
        EXPECT_NEAR(x, si_x[i], 1e-9 * 0.5) << "t = " << t;
        EXPECT_NEAR(v, si_v[i], 1e-9 * 1.7) << "t = " << t;
      }
      if (t < t_b) {
        EXPECT_NEAR(v, 0.0, 1e-12) << "t = " << t;
      } else if (t < t_b + 1e-6) {
        EXPECT_GT(v, 0.5 * b * (t - t_b)) << "t = " << t;
        EXPECT_LT(v, 1.5 * b * (t - t_b)) << "t = " << t;
      } else {
        // t_b from x' as well (to the integration's accuracy)
        const double tau = 2 * v / (b + std::sqrt(b * b + 4 * c * v));
        EXPECT_NEAR(t - tau, t_b, 1e-9 * t_b) << "t = " << t;
      }
    }
  }
}

// launched at −1 m/s against F = 20 or 40: stops at t_s = m v0/(F + mu m g), x_s = v0 t_s / 2,
// and stays — the same motion in SI, in mm, g, ms and in mm, kg, s (main hung after the stop in
// mm, creeping at 3e-8 mm/ms with one leg holding 15.3 N of 20, or slid off at F = 40: the split
// search, in the multipliers' own metric, found no split there)
TEST(StickSeveralContacts, TableStopAgainstAPushIsTheSameInMmGMsAndMmKgS) {
  struct Units {
    std::string line;
    double lf, mf, tf;
  };
  const std::vector<Units> systems = {{"", 1, 1, 1},
                                      {"units: {length: mm, mass: g, time: ms}\n", 1e3, 1e3, 1e3},
                                      {"units: {length: mm, mass: kg, time: s}\n", 1e3, 1, 1}};
  for (double F : {20.0, 40.0}) {
    const double a = (F + kMu * kTableMass * kG) / kTableMass, t_s = 1.0 / a;
    const double x_s = -0.5 * t_s;
    const std::vector<double> times = {0.05, t_s - 1e-4, t_s + 1e-4, 0.5, 1.5};
    std::vector<double> si_x, si_v;
    for (const Units& u : systems) {
      SCOPED_TRACE("F = " + std::to_string(F) + ", length x" + std::to_string(u.lf) + ", mass x" +
                   std::to_string(u.mf) + ", time x" + std::to_string(u.tf));
      std::vector<double> scaled;
      for (double t : times) scaled.push_back(t * u.tf);
      const Trajectory tr = run_at(table(u.line, u.lf, u.mf, u.tf, F, -1.0), scaled);
      if (u.lf != 1.0) ASSERT_EQ(tr.t.size(), si_x.size());
      for (std::size_t i = 0; i < tr.t.size(); ++i) {
        const double t = tr.t[i] / u.tf, x = at(tr, tr.q, "table.x", i) / u.lf,
                     v = at(tr, tr.qd, "table.x", i) * u.tf / u.lf;
        EXPECT_NEAR(v, t < t_s ? -1.0 + a * t : 0.0, 1e-9) << "t = " << t;
        EXPECT_NEAR(x, t < t_s ? -t + 0.5 * a * t * t : x_s, 1e-9) << "t = " << t;
        if (u.lf == 1.0) {
          si_x.push_back(x);
          si_v.push_back(v);
          continue;
        }
        // the same motion as in SI
        EXPECT_NEAR(x, si_x[i], 1e-9 * std::abs(x_s)) << "t = " << t;
        EXPECT_NEAR(v, si_v[i], 1e-12) << "t = " << t;
      }
      // at rest the legs hold F together (in SI: elsewhere the multipliers are those of rows
      // scaled by the units' class, κ)
      if (u.lf != 1.0) continue;
      const auto [total, normal] = held_sums(tr, kLegs, tr.t.size() - 1);
      EXPECT_NEAR(total, -F, 1e-7);
      EXPECT_NEAR(normal, kTableMass * kG, 1e-7);
    }
  }
}

// A planar box put at rest on its two corners on a rough incline (al = 0.35, tan al = 0.365 <
// mu_s): it stays, each corner's holding force inside its cone and together m g sin al (main:
// the right corner alone held all of it at |f|/N = 0.80 > mu_s, the left one slid at zero
// speed); pushed down the slope by k t it breaks away at t_b = (mu_s cos al − sin al) m g / k
// (main: at 0.14 s instead of 0.746 s), then slides, s' = ((g sin al − mu g cos al)(t − t_b) +
// k (t² − t_b²) / (2 m))
TEST(StickSeveralContacts, BoxAtRestOnAnInclineStaysAndBreaksAwayAtMuStatic) {
  const double al = 0.35, k = 5.0;
  auto model = [&](const std::string& push) {
    return "parameters: {m: 3, a: 0.2, c: 0.05, g: 9.81, al: 0.35, mu: 0.3, mus: 0.5, k: 5}\n"
           "bodies:\n"
           "  - {name: box, type: planar, mass: m, inertia: m*(4*a^2+4*c^2)/12,"
           " position: [-c*sin(al), c*cos(al)], angle: al}\n"
           "forces:\n"
           "  - {type: gravity, g: [0, -g]}\n"
           "  - {name: push, type: applied, body: box, point: [0, -c], force: [" +
           push + "*cos(al), " + push +
           "*sin(al)], torque: 0}\n"
           "contacts:\n"
           "  - {name: cl, body: box, point: [-a, -c], plane: {normal: [-sin(al), cos(al)]}}\n"
           "  - {name: cr, body: box, point: [a, -c], plane: {normal: [-sin(al), cos(al)]}}\n"
           "nonideal:\n"
           "  - {friction: coulomb, constraint: cl, mu: mu, mu_static: mus}\n"
           "  - {friction: coulomb, constraint: cr, mu: mu, mu_static: mus}\n"
           "simulate: {t_end: 1.2, rtol: 1e-10, atol: 1e-12}\noutput: {every: 0}\n";
  };
  const Trajectory rest = run_at(model("0"), {0.5, 1.0});
  for (std::size_t i = 0; i < rest.t.size(); ++i) {
    EXPECT_NEAR(at(rest, rest.qd, "box.x", i), 0.0, 1e-12);
    EXPECT_NEAR(at(rest, rest.qd, "box.y", i), 0.0, 1e-12);
    const auto [total, normal] = held_sums(rest, {"cl", "cr"}, i);
    EXPECT_NEAR(std::abs(total), kMass * kG * std::sin(al), 1e-7);
    EXPECT_NEAR(normal, kMass * kG * std::cos(al), 1e-7);
  }
  const double t_b = (kMuS * std::cos(al) - std::sin(al)) * kMass * kG / k;
  const Trajectory pushed = run_at(model("-k*t"), {0.5, t_b - 1e-6, t_b + 1e-6, 1.0, 1.2});
  for (std::size_t i = 0; i < pushed.t.size(); ++i) {
    const double t = pushed.t[i];
    const double s =
        std::hypot(at(pushed, pushed.qd, "box.x", i), at(pushed, pushed.qd, "box.y", i));
    if (t < t_b) {
      EXPECT_LT(s, 1e-9) << "t = " << t;
      continue;
    }
    const double closed = kG * (std::sin(al) - kMu * std::cos(al)) * (t - t_b) +
                          k * (t * t - t_b * t_b) / (2 * kMass);
    if (t < t_b + 1e-5) {
      EXPECT_GT(s, 1e-7) << "t = " << t;
    } else {
      EXPECT_NEAR(s, closed, 1e-6 + 1e-6 * closed) << "t = " << t;
    }
    // down the slope
    EXPECT_LT(at(pushed, pushed.qd, "box.x", i), 0.0) << "t = " << t;
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

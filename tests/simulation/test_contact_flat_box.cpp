// SPDX-License-Identifier: BSD-3-Clause
// A rigid box resting flat on four coplanar corners (docs/contact.md, "Redundant contacts"): its
// normal rows are redundant, so the split of m g among the corners is indeterminate, and the
// LCP of an event took a vertex — m g on two diagonal corners — about which the box, pushed,
// tipped (u17 01: spurious corner impacts, the energy check failed, or it slid below μ_s m g).
// The least-norm split (the fundamental equation's with all four corners active) is taken
// instead. Against closed forms, in SI and in mm, g, ms, as `shape: box` and as four point
// contacts: m = 2, half-extents 0.2 × 0.1 × 0.05, μ = 0.3, μ_s = 0.4, pushed at its centre by
// F along x. For F < μ_s m g it stays, its friction −F, the front corners (x > 0) carrying
// m g / 4 + F hz / (4 hx) each and the back ones m g / 4 − F hz / (4 hx) (the moment of the
// friction at the floor; the least-norm split is even across y); above, it slides from t = 0
// with x'' = (F − μ m g) / m. And the box dropped flat with e = 0.3, μ = 0.5 (u17 05): 13
// impacts, at rest at t0 (1 + 2e / (1 − e)) = 592.940 ms, in mm as in SI; dropped flat while it
// slides at 5 m/s, each impact sliding through (the vertex's friction on three corners gave it a
// yaw, and its second landing's LCP had no solution), to its stop at μ g.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "support/contact_runs.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kMass = 2.0, kG = 9.81, kMu = 0.3, kMuS = 0.4, kHx = 0.2, kHy = 0.1, kHz = 0.05;

// the units of a run: L metres, M kilograms and T seconds per model unit (forces: M L / T² N)
struct Units {
  const char* name;
  double L, M, T;
  double force() const { return M * L / (T * T); }
};
constexpr Units kSI{"SI", 1.0, 1.0, 1.0}, kMm{"mm, g, ms", 1e-3, 1e-3, 1e-3};

// the box at rest flat on the floor, pushed at its centre by F (newtons) from t = 0, with
// `shape: box` (its bottom corners lid.0 … lid.3) or four point contacts lid_0 … lid_3 at the
// same corners, in units u; sampled every 0.05 s to 0.5 s
std::string pushed_box(double F, bool points, const Units& u) {
  const double L = 1.0 / u.L, M = 1.0 / u.M, T = 1.0 / u.T;
  std::string text = "parameters: {m: " + std::to_string(kMass * M) +
                     ", g: " + std::to_string(kG * L / (T * T)) +
                     ", F: " + std::to_string(F / u.force()) + ", hx: " + std::to_string(kHx * L) +
                     ", hy: " + std::to_string(0.1 * L) + ", hz: " + std::to_string(kHz * L) +
                     "}\n" + (u.L == 1.0 ? "" : "units: {length: mm, mass: g, time: ms}\n") +
                     "bodies:\n"
                     "  - {name: box, type: rigid, mass: m, inertia: [m*(hy^2+hz^2)/3, "
                     "m*(hx^2+hz^2)/3, m*(hx^2+hy^2)/3], position: [0, 0, hz]}\n"
                     "forces:\n"
                     "  - {type: gravity, g: [0, 0, -g]}\n"
                     "  - {name: push, type: applied, body: box, force: [F, 0, 0]}\n";
  if (points) {
    text += "contacts:\n";
    const char* corners[] = {"[-hx, -hy, -hz]", "[hx, -hy, -hz]", "[-hx, hy, -hz]",
                             "[hx, hy, -hz]"};
    for (int c = 0; c < 4; ++c)
      text += "  - {name: lid_" + std::to_string(c) + ", body: box, point: " + corners[c] + "}\n";
    text += "nonideal:\n";
    for (int c = 0; c < 4; ++c)
      text += "  - {friction: coulomb, constraint: lid_" + std::to_string(c) +
              ", mu: 0.3, mu_static: 0.4}\n";
  } else {
    text +=
        "contacts:\n  - {name: lid, body: box, shape: box, size: [hx, hy, hz]}\n"
        "nonideal:\n  - {friction: coulomb, constraint: lid, mu: 0.3, mu_static: 0.4}\n";
  }
  return text + "simulate: {t_end: " + std::to_string(0.5 * T) +
         ", rtol: 1e-10, atol: 1e-12}\noutput: {every: " + std::to_string(0.05 * T) + "}\n";
}

TEST(ContactFlatBox, PushedBelowMuStaticMgStaysWithTheLeastNormSplitOfItsCorners) {
  for (const Units& u : {kSI, kMm}) {
    for (bool points : {false, true}) {
      for (double fraction : {0.5, 0.95}) {
        const double F = fraction * kMuS * kMass * kG;
        SCOPED_TRACE(std::string(u.name) + (points ? ", points" : ", box") +
                     ", F = " + std::to_string(F));
        // (run_model: the stick multipliers in the samples are the holding forces, × kappa)
        const ModelRun run = run_model(parse_model(pushed_box(F, points, u)));
        const Trajectory& tr = run.trajectory;
        ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
        // no impact, release or slip: the corners stick at t = 0 and hold
        for (const ContactEvent& e : tr.stats.contact_events) {
          EXPECT_TRUE(e.kind == ContactEvent::Kind::kStick) << to_string(e.kind) << " at " << e.t;
        }
        ASSERT_EQ(tr.t.size(), 11u);
        for (std::size_t i = 0; i < tr.t.size(); ++i) {
          const double t = tr.t[i] * u.T;
          EXPECT_LE(std::abs(testing::coordinate_at(tr, tr.q, "box.x", i)) * u.L, 1e-12) << t;
          EXPECT_LE(std::abs(testing::coordinate_at(tr, tr.q, "box.z", i) * u.L - kHz), 1e-12) << t;
          double friction = 0.0, normal = 0.0;
          for (int c = 0; c < 4; ++c) {
            // (the box's corner c, as `shape: box` numbers them, or the point contact lid_c)
            const std::string corner = (points ? "lid_" : "lid.") + std::to_string(c);
            const double N = testing::first_multiplier(tr, corner, i) * u.force();
            const double shift = F * kHz / (4.0 * kHx);  // (corners 1 and 3 are at x = +hx)
            EXPECT_NEAR(N, kMass * kG / 4.0 + (c & 1 ? shift : -shift), 1e-9) << corner << t;
            friction += testing::first_multiplier(tr, "stick.coulomb." + corner, i) * u.force();
            normal += N;
          }
          EXPECT_NEAR(friction, -F, 1e-9) << t;
          EXPECT_NEAR(normal, kMass * kG, 1e-9) << t;
        }
      }
    }
  }
}

TEST(ContactFlatBox, PushedAboveMuStaticMgSlidesFromTheStartWithMuMg) {
  const double F = 1.05 * kMuS * kMass * kG, a = (F - kMu * kMass * kG) / kMass;
  for (const Units& u : {kSI, kMm}) {
    for (bool points : {false, true}) {
      SCOPED_TRACE(std::string(u.name) + (points ? ", points" : ", box"));
      const Model m = parse_model(pushed_box(F, points, u));
      const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
      ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
      for (const ContactEvent& e : tr.stats.contact_events) {
        EXPECT_TRUE(e.kind == ContactEvent::Kind::kSlip) << to_string(e.kind) << " at " << e.t;
      }
      for (std::size_t i = 0; i < tr.t.size(); ++i) {
        const double t = tr.t[i] * u.T;
        EXPECT_NEAR(testing::coordinate_at(tr, tr.q, "box.x", i) * u.L, 0.5 * a * t * t, 1e-9) << t;
        EXPECT_NEAR(testing::coordinate_at(tr, tr.qd, "box.x", i) * u.L / u.T, a * t, 1e-9) << t;
        EXPECT_NEAR(testing::coordinate_at(tr, tr.q, "box.z", i) * u.L, kHz, 1e-12) << t;
      }
    }
  }
}

// the box dropped flat from h0 = 0.5 m at (x', y') = (vx, vy) (m/s), e = 0.3, μ = 0.5, in units u,
// sampled every 5 ms to t_end (s)
Trajectory dropped_box(const Units& u, double vx, double t_end, double vy = 0.0) {
  const double L = 1.0 / u.L, M = 1.0 / u.M, T = 1.0 / u.T;
  const auto exact = [](double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.17g", v);
    return std::string(b);
  };
  const Model m = parse_model(
      "parameters: {m: " + std::to_string(kMass * M) + ", g: " + std::to_string(kG * L / (T * T)) +
      ", hx: " + std::to_string(kHx * L) + ", hy: " + std::to_string(0.1 * L) +
      ", hz: " + std::to_string(kHz * L) + ", h0: " + std::to_string(0.5 * L) + ", e: 0.3}\n" +
      (u.L == 1.0 ? "" : "units: {length: mm, mass: g, time: ms}\n") +
      "bodies:\n"
      "  - {name: box, type: rigid, mass: m, inertia: [m*(hy^2+hz^2)/3, m*(hx^2+hz^2)/3, "
      "m*(hx^2+hy^2)/3], position: [0, 0, h0 + hz], velocity: [" +
      exact(vx * L / T) + ", " + exact(vy * L / T) +
      ", 0]}\n"
      "forces:\n  - {type: gravity, g: [0, 0, -g]}\n"
      "contacts:\n  - {name: lid, body: box, shape: box, size: [hx, hy, hz], restitution: e}\n"
      "nonideal:\n  - {friction: coulomb, constraint: lid, mu: 0.5}\n"
      "simulate: {t_end: " +
      std::to_string(t_end * T) +
      ", rtol: 1e-10, atol: 1e-12}\noutput: {every: " + std::to_string(0.005 * T) + "}\n");
  return simulate(m.system, m.q0, m.qd0, m.options);
}

// dropped flat: the impacts at t0 (1 + 2e (1 − eʲ)/(1 − e)) until the rest criterion (13
// impacts: 0.3¹² < 1e-6), at rest at t0 (1 + 2e / (1 − e))
TEST(ContactFlatBox, DroppedFlatWithFrictionRestsAtTheAccumulationPointInAnyUnits) {
  const double e = 0.3, t0 = std::sqrt(2.0 * 0.5 / kG);
  const double t_rest = t0 * (1.0 + 2.0 * e / (1.0 - e));
  for (const Units& u : {kSI, kMm}) {
    SCOPED_TRACE(u.name);
    const Trajectory tr = dropped_box(u, 0.0, 1.0);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    std::set<double> impacts, rests;
    for (const ContactEvent& ev : tr.stats.contact_events) {
      if (ev.kind == ContactEvent::Kind::kImpact) impacts.insert(ev.t * u.T);
      if (ev.kind == ContactEvent::Kind::kRest) rests.insert(ev.t * u.T);
    }
    // (the four corners land together: one instant per impact, and one of rest)
    ASSERT_EQ(impacts.size(), 12u);
    ASSERT_EQ(rests.size(), 1u);
    double expected = t0, flight = 2.0 * e * t0;
    for (double t : impacts) {
      EXPECT_NEAR(t, expected, 1e-9 * t_rest);
      expected += flight;
      flight *= e;
    }
    EXPECT_NEAR(*rests.begin(), t_rest, 1e-6 * t_rest);
    const std::size_t last = tr.t.size() - 1;
    EXPECT_NEAR(testing::coordinate_at(tr, tr.q, "box.z", last) * u.L, kHz, 1e-9);
    EXPECT_NEAR(testing::coordinate_at(tr, tr.q, "box.x", last) * u.L, 0.0, 1e-12);
  }
}

// dropped flat while sliding at vx = 5 m/s: every impact slides through (its friction impulse
// μ (1 + e) m |g'⁻| takes μ (1 + e) |g'⁻| off x'), the 13th plastic (the rest: μ |g'⁻|); then it
// slides to a stop at μ g. x: vx t0, then each flight at its x', then the slide.
TEST(ContactFlatBox, DroppedFlatWhileSlidingSlidesThroughItsImpactsAndStops) {
  const double e = 0.3, mu = 0.5, t0 = std::sqrt(2.0 * 0.5 / kG), v0 = kG * t0;
  double t = t0, x = 5.0 * t0, v = 5.0, approach = v0;
  for (int j = 1; j < 13; ++j) {
    v -= mu * (1.0 + e) * approach;
    approach *= e;
    x += v * 2.0 * approach / kG;
    t += 2.0 * approach / kG;
  }
  v -= mu * approach;  // (the rest: still sliding, at 2.09 m/s)
  const double t_stop = t + v / (mu * kG);
  x += v * v / (2.0 * mu * kG);
  for (const Units& u : {kSI, kMm}) {
    SCOPED_TRACE(u.name);
    const Trajectory tr = dropped_box(u, 5.0, 1.2);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    const std::size_t last = tr.t.size() - 1;
    EXPECT_NEAR(testing::coordinate_at(tr, tr.q, "box.x", last) * u.L, x, 1e-6);
    EXPECT_NEAR(testing::coordinate_at(tr, tr.qd, "box.x", last) * u.L / u.T, 0.0, 1e-9);
    EXPECT_NEAR(testing::coordinate_at(tr, tr.q, "box.y", last) * u.L, 0.0, 1e-9);
    EXPECT_NEAR(testing::coordinate_at(tr, tr.q, "box.z", last) * u.L, kHz, 1e-9);
    // the stop: the last slip-to-stick event
    double stuck = 0.0;
    for (const ContactEvent& ev : tr.stats.contact_events) {
      if (ev.kind == ContactEvent::Kind::kStick) stuck = ev.t * u.T;
    }
    EXPECT_NEAR(stuck, t_stop, 1e-6);
  }
}

// Dropped flat while sliding obliquely, at 30° to x: by symmetry the four corners share the
// landing, and the box must not turn. Each corner's friction impulse goes against its slip (the
// pyramid of friction directions has its first axis along the slip before: the whole cone, where
// the fixed axes ±x, ±y gave −x alone at 10 m/s and the diagonal at 5 m/s), the four together
// μ (1 + e) m v0 =: m Δ while it slides through: v⁺ = (1 − Δ / |v|) v, at 10 and 5 m/s; at 1 m/s
// |v| < Δ: it stops, v⁺ = 0 (Lemke's vertex gave friction on some corners only: a yaw). The
// corners' normal impulses balance the friction's moment. In SI and in mm, g, ms, the same
// impulses (the impact's LCP scaled so that its blocks do not depend on the units).
TEST(ContactFlatBox, DroppedFlatWhileSlidingObliquelyLandsWithoutTurning) {
  const double e = 0.3, mu = 0.5, t0 = std::sqrt(2.0 * 0.5 / kG), v0 = kG * t0;
  const double delta = mu * (1.0 + e) * v0, c = std::cos(std::numbers::pi / 6.0),
               s = std::sin(std::numbers::pi / 6.0);
  for (double speed : {10.0, 5.0, 1.0}) {
    const double vx = speed * c, vy = speed * s;
    const double keep = std::max(1.0 - delta / speed, 0.0);  // (Coulomb: Δ against the slip)
    const double ex = keep * vx, ey = keep * vy;
    std::vector<double> si_impulses;
    for (const Units& u : {kSI, kMm}) {
      SCOPED_TRACE(std::string(u.name) + ", " + std::to_string(speed) + " m/s");
      const Trajectory tr = dropped_box(u, vx, t0 + 0.01, vy);
      ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
      // the first landing: (1 + e) m v0 in all, split so that the friction impulse m (vx − ex,
      // vy − ey) at the floor, hz below the centre, turns the box neither way (least-norm:
      // linear in the corner's x and y) — the corner at (±hx, ±hy) takes
      // (1 + e) m v0 / 4 ± hz m (vx − ex) / (4 hx) ± hz m (vy − ey) / (4 hy)
      std::vector<double> impulses;
      for (const ContactEvent& ev : tr.stats.contact_events) {
        if (ev.kind != ContactEvent::Kind::kImpact) continue;
        EXPECT_NEAR(ev.t * u.T, t0, 1e-9);
        impulses.push_back(ev.impulse * u.force() * u.T);
        // (`shape: box` numbers its bottom corners lid.0 … lid.3: x > 0 for 1, 3, y > 0 for 2, 3)
        const std::string& name = tr.constraint_names[std::size_t(ev.constraint)];
        const int corner = name.back() - '0';
        const double sx = corner & 1 ? 1.0 : -1.0, sy = corner & 2 ? 1.0 : -1.0;
        EXPECT_NEAR(impulses.back(),
                    (1.0 + e) * kMass * v0 / 4.0 + sx * kHz * kMass * (vx - ex) / (4.0 * kHx) +
                        sy * kHz * kMass * (vy - ey) / (4.0 * kHy),
                    1e-9)
            << name;
      }
      ASSERT_EQ(impulses.size(), 4u);
      if (si_impulses.empty()) {
        si_impulses = impulses;
      } else {
        for (std::size_t i = 0; i < 4; ++i)
          EXPECT_NEAR(impulses[i], si_impulses[i], 1e-9 * si_impulses[i]) << i;
      }
      // in flight after it: (ex, ey, e v0 − g (t − t0)), not turning
      const std::size_t last = tr.t.size() - 1;
      const double t = tr.t[last] * u.T, speed_unit = u.L / u.T;
      ASSERT_GT(t, t0);
      EXPECT_NEAR(testing::coordinate_at(tr, tr.qd, "box.x", last) * speed_unit, ex, 1e-9);
      EXPECT_NEAR(testing::coordinate_at(tr, tr.qd, "box.y", last) * speed_unit, ey, 1e-9);
      EXPECT_NEAR(testing::coordinate_at(tr, tr.qd, "box.z", last) * speed_unit,
                  e * v0 - kG * (t - t0), 1e-9);
      for (std::size_t j = 3; j < tr.coordinate_names.size(); ++j) {
        EXPECT_NEAR(tr.qd[last * std::size_t(tr.n) + j] / u.T, 0.0, 1e-12)
            << tr.coordinate_names[j];
      }
    }
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

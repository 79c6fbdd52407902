// SPDX-License-Identifier: BSD-3-Clause
// The rest of an accumulation of impacts (issue #31 item 2, docs/contact.md "Rest"): Housner's
// rocking block, whose plastic impacts on alternate corners accumulate at a finite t∞ and which
// then rests on both corners — each corner's own sequence never ends (every landing of one lifts
// the other), so the rest criterion holds the group (the lifting corner with the landing one) —
// in SI and in millimetres, against t∞ by quadrature of the rocking motion; and the bouncing
// ball of high restitution, whose 13 800 impacts converge: it rests at the same time whatever the
// run's span (the chattering test, 10 000 events within 1e-4 of the span, counted them before).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "support/contact_runs.hpp"
#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/ensemble.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using testing::coordinate_at;
using testing::events_of;

// Housner's block, lengths in `unit`, to t = 3 s (testing::rocking_block_in_coordinates)
std::string rocking_block(const std::string& unit, double b, double h, double g) {
  return testing::rocking_block_in_coordinates(unit, b, h, g) +
         "simulate: {t_end: 3, integrator: dopri5, rtol: 1e-10, atol: 1e-12}\n"
         "output: {every: 0.5}\n";
}

// The rocking motion about a corner, tilt θ: ½ I_O θ'² + m g ρ cos(α − θ) = const, I_O =
// (4/3) m ρ², ρ = √(b² + h²), α = atan(b/h). From an apex θ_a to θ = 0 takes
//   τ(θ_a) = ∫₀^θa dθ / √(2c (cos(α − θ_a) − cos(α − θ))),  c = m g ρ / I_O = 3 g / (4 ρ),
// by θ = θ_a (1 − s²) a smooth integral over s in [0, 1] (Simpson, 800 panels: 1e-13 s). The
// block falls from th0 (τ(th0)), lands at ω₀; each landing leaves at r times the speed, r = 1 −
// (3/2) sin² α, and rises to the apex θ_k of ω_k = r^k ω₀ and back: t∞ = τ(th0) + Σ 2 τ(θ_k).
struct Rocking {
  double alpha, c, r;
  Rocking(double b, double h, double g)
      : alpha(std::atan(b / h)),
        c(3.0 * g / (4.0 * std::hypot(b, h))),
        r(1.0 - 1.5 * std::sin(alpha) * std::sin(alpha)) {}
  double tau(double ta) const {
    const auto f = [&](double s) {
      if (s == 0.0) return 2.0 * ta / std::sqrt(2.0 * c * std::sin(alpha - ta) * ta);
      // cos(α − θ_a) − cos(α − θ_a + θ_a s²), without cancellation
      const double d = 2.0 * std::sin(alpha - ta + 0.5 * ta * s * s) * std::sin(0.5 * ta * s * s);
      return 2.0 * ta * s / std::sqrt(2.0 * c * d);
    };
    const int panels = 800;
    const double step = 1.0 / panels;
    double sum = f(0.0) + f(1.0);
    for (int i = 1; i < panels; ++i) sum += (i % 2 ? 4.0 : 2.0) * f(i * step);
    return sum * step / 3.0;
  }
  // the apex of a launch at angular speed w: 2 sin(α − θ/2) sin(θ/2) = w²/(2c), by fixed point
  double apex(double w) const {
    double ta = w * w / (2.0 * c * std::sin(alpha));
    for (int i = 0; i < 60; ++i)
      ta = 2.0 * std::asin(w * w / (4.0 * c * std::sin(alpha - 0.5 * ta)));
    return ta;
  }
  // the landings' times, the first (k = 0, on the left corner) to the k-th, and t∞ (last)
  std::vector<double> landings(double th0, int count) const {
    const double w0 = std::sqrt(2.0 * c * (std::cos(alpha - th0) - std::cos(alpha)));
    std::vector<double> times{tau(th0)};
    double t = times[0], w = w0;
    for (int k = 1; k < 400; ++k) {
      w *= r;
      const double d = 2.0 * tau(apex(w));
      t += d;
      if (k <= count) times.push_back(t);
      if (d < 1e-18) break;
    }
    times.push_back(t);
    return times;
  }
};

TEST(ContactRest, RockingBlockRestsOnBothCornersAtItsAccumulationPointInSIAndMillimetres) {
  const Rocking housner(0.2, 0.5, 9.81);
  // the rest criterion at landing k (speed ω₀ r^k): below 1e-6 of its corner's fastest, the
  // left's at k = 0 and the right's at k = 1
  int K = 0;
  while (!(std::pow(housner.r, K - K % 2) < 1e-6)) ++K;
  ASSERT_EQ(K, 60);
  const std::vector<double> landing = housner.landings(0.2, K);
  const double t_inf = landing.back();
  EXPECT_NEAR(t_inf, 2.388512697735, 1e-11);  // (the same sum, printed once: a regression guard)
  for (const double l : {1.0, 1000.0}) {
    SCOPED_TRACE(l == 1.0 ? "SI" : "mm");
    const Model model =
        parse_model(rocking_block(l == 1.0 ? "m" : "mm", 0.2 * l, 0.5 * l, 9.81 * l));
    const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_EQ(tr.t.back(), 3.0);
    // the landings, alternately left and right, at the quadrature's times; the K-th a rest of
    // both corners at one instant, 1.7e-6 s before t∞ (the flights left out)
    std::vector<ContactEvent> landings;
    for (const ContactEvent& e : tr.stats.contact_events) {
      if (e.kind == ContactEvent::Kind::kImpact ||
          (e.kind == ContactEvent::Kind::kRest && e.speed_before < 0.0)) {
        landings.push_back(e);
      }
    }
    ASSERT_EQ(landings.size(), std::size_t(K + 1));
    for (int k = 0; k <= K; ++k) {
      const ContactEvent& e = landings[std::size_t(k)];
      EXPECT_EQ(e.constraint, k % 2 ? 2 : 1) << k;
      EXPECT_EQ(e.kind, k < K ? ContactEvent::Kind::kImpact : ContactEvent::Kind::kRest) << k;
      EXPECT_NEAR(e.t, landing[std::size_t(k)], 1e-9) << k;
    }
    const ContactEvent& rest = landings.back();
    EXPECT_GT(t_inf - rest.t, 1e-6);
    EXPECT_LT(t_inf - rest.t, 2e-6);
    const auto rest_left = events_of(tr, 1, ContactEvent::Kind::kRest);
    const auto rest_right = events_of(tr, 2, ContactEvent::Kind::kRest);
    ASSERT_EQ(rest_left.size(), 1u);
    ASSERT_EQ(rest_right.size(), 1u);
    EXPECT_EQ(rest_right[0].t, rest.t);
    EXPECT_EQ(rest_right[0].speed_before, 0.0);  // (it was closed: the pivot)
    // nothing after the rest but the corners' sticks
    for (const ContactEvent& e : tr.stats.contact_events) {
      if (e.t > rest.t) ADD_FAILURE() << "an event after the rest at t = " << e.t;
      if (e.t == rest.t && e.kind != ContactEvent::Kind::kRest) {
        EXPECT_EQ(e.kind, ContactEvent::Kind::kStick);
      }
    }
    // the rest's impulses: of the order of the last landings' (1e-6 of the first), the held
    // corner's pulling
    const double first_impulse = landings[0].impulse;
    EXPECT_GT(rest_left[0].impulse, 0.0);
    EXPECT_LT(rest_left[0].impulse, 1e-5 * first_impulse);
    EXPECT_LT(rest_right[0].impulse, 0.0);
    EXPECT_GT(rest_right[0].impulse, -1e-5 * first_impulse);
    for (const ContactEvent& e : {rest_left[0], rest_right[0]})
      EXPECT_NEAR(e.speed_after, 0.0, 1e-15 * l);
    // at rest on both corners: flat, still, each corner carrying m g / 2
    const std::size_t last = tr.t.size() - 1;
    EXPECT_NEAR(coordinate_at(tr, tr.q, "y1", last), 0.0, 1e-12 * l);
    EXPECT_NEAR(coordinate_at(tr, tr.q, "y2", last), 0.0, 1e-12 * l);
    for (const char* v : {"x1", "y1", "x2", "y2"})
      EXPECT_NEAR(coordinate_at(tr, tr.qd, v, last), 0.0, 1e-12 * l) << v;
    ASSERT_EQ(tr.lambda_total.size(), 2 * tr.t.size());
    EXPECT_NEAR(tr.lambda_total[2 * last], 0.5 * 9.81 * l, 1e-8 * 9.81 * l);
    EXPECT_NEAR(tr.lambda_total[2 * last + 1], 0.5 * 9.81 * l, 1e-8 * 9.81 * l);
    EXPECT_TRUE(tr.stats.energy_balance_checked) << tr.stats.message;
    bool noted = false;
    for (const std::string& note : tr.stats.notes)
      noted = noted || note.find("'right' held at rest") != std::string::npos;
    EXPECT_TRUE(noted);
  }
}

// The same block as a spatial box (quaternion coordinates; `shape: box` on its eight corners,
// Coulomb friction on each) tilted about its bottom edge: it rocks on its two bottom edges, two
// corners landing together — four redundant contacts (rank 3), where Siconos's Lemke finds no
// solution of the friction impact and the least-norm split decides: the landing edge sticks
// (its corners at rest before, their velocity along the normal, with every friction direction)
// and the other edge leaves (its tangential speed the cones' γ). It stopped at the 8th landing
// (t = 2.021 s) and, that fixed, at the 50th, where the pivot edge's g'⁻ of −3e-14 (the roundoff
// of the impact before) counted as approaching. Now it lands as the planar block, at the
// quadrature's times, and rests on its four bottom corners, m g / 4 each.
TEST(ContactRest, SpatialBoxRockingOnItsEdgesRestsAsThePlanarBlock) {
  const Model model = parse_model(R"(
parameters: {m: 1, hx: 0.2, hy: 0.3, hz: 0.5, g: 9.81, th0: 0.2, mu: 1}
bodies:
  - {name: block, type: rigid, mass: m, inertia: [m*(hy^2 + hz^2)/3, m*(hx^2 + hz^2)/3, m*(hx^2 + hy^2)/3],
     position: [-hx*cos(th0) + hz*sin(th0), 0, hx*sin(th0) + hz*cos(th0)],
     orientation: {axis: [0, 1, 0], angle: th0}}
forces:
  - {type: gravity, g: [0, 0, -g]}
contacts:
  - {name: base, body: block, shape: box, size: [hx, hy, hz]}
nonideal:
  - {friction: coulomb, constraint: base, mu: mu}
simulate: {t_end: 3, integrator: dopri5, rtol: 1e-10, atol: 1e-12}
output: {every: 0.5}
)");
  const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const std::vector<double> landing = Rocking(0.2, 0.5, 9.81).landings(0.2, 60);
  // the landings: corners 0 and 2 (x = −hx) at even k, 1 and 3 at odd k, each pair at one instant
  std::vector<ContactEvent> landings;
  for (const ContactEvent& e : tr.stats.contact_events) {
    if (e.kind == ContactEvent::Kind::kImpact ||
        (e.kind == ContactEvent::Kind::kRest && e.speed_before < 0.0)) {
      landings.push_back(e);
    }
  }
  ASSERT_EQ(landings.size(), 2u * 61u);
  const Index base0 = model.system.constraint_index("base.0");
  for (std::size_t k = 0; k <= 60; ++k) {
    const ContactEvent &a = landings[2 * k], &b = landings[2 * k + 1];
    EXPECT_EQ(a.constraint, base0 + Index(k % 2)) << k;
    EXPECT_EQ(b.constraint, base0 + Index(k % 2) + 2) << k;
    EXPECT_EQ(a.t, b.t) << k;
    EXPECT_NEAR(a.t, landing[k], 1e-9) << k;
    EXPECT_EQ(a.kind, k < 60 ? ContactEvent::Kind::kImpact : ContactEvent::Kind::kRest) << k;
  }
  const std::size_t last = tr.t.size() - 1;
  const std::size_t u = tr.unilateral.size();
  for (std::size_t c = 0; c < u; ++c) {
    const std::string& name = tr.constraint_names[std::size_t(tr.unilateral[c])];
    const bool bottom =
        name == "base.0" || name == "base.1" || name == "base.2" || name == "base.3";
    EXPECT_NEAR(tr.lambda_total[last * u + c], bottom ? 9.81 / 4.0 : 0.0, 1e-8) << name;
  }
  for (std::size_t j = 0; j < std::size_t(tr.n); ++j)
    EXPECT_NEAR(tr.qd[last * std::size_t(tr.n) + j], 0.0, 1e-12) << tr.coordinate_names[j];
  EXPECT_TRUE(tr.stats.energy_balance_checked);
}

// A sweep of the block over its initial tilt counts its landings as impacts (the held corner's
// rest is none: 61, K + 1) and gives the rest time as the K-th landing's, on 1 and 2 threads.
TEST(ContactRest, ASweepOfTheRockingBlockCountsItsLandingsAndItsRestTime) {
  EnsembleModel model;
  model.text = rocking_block("m", 0.2, 0.5, 9.81);
  const std::vector<double> tilts = {0.05, 0.2};
  std::vector<EnsembleSample> samples;
  for (double th0 : tilts) {
    EnsembleSample s;
    s.parameters["th0"] = th0;
    samples.push_back(s);
  }
  EnsembleOptions o;
  for (const int threads : {1, 2}) {
    o.threads = threads;
    const EnsembleResult result = run_ensemble(model, samples, o);
    const EnsembleTable table = ensemble_table(result, samples);
    const auto col = [&](const std::string& name) {
      for (const CsvColumn& c : table.numbers)
        if (c.name == name) return c.values;
      ADD_FAILURE() << "no column " << name;
      return std::vector<double>(tilts.size(), std::nan(""));
    };
    const Rocking housner(0.2, 0.5, 9.81);
    for (std::size_t i = 0; i < tilts.size(); ++i) {
      SCOPED_TRACE("th0 = " + std::to_string(tilts[i]) + ", threads " + std::to_string(threads));
      ASSERT_TRUE(result.samples[i].ok()) << result.samples[i].message;
      EXPECT_EQ(col("impacts")[i], 61.0);
      EXPECT_EQ(col("releases")[i], 60.0);
      EXPECT_NEAR(col("rest_time")[i], housner.landings(tilts[i], 60)[60], 1e-9);
    }
  }
}

// A ball (e = 0.999, h0 = 1 m) makes its impacts at t_k = t0 (1 + 2 (e + … + e^k)); the rest
// criterion ends them at about 13 800 (e^k < 1e-6), 1e-6 t∞ before t∞ = t0 (1 + e)/(1 − e) =
// 902.595 s. Its last 10 000 impacts take 20 s, within 1e-4 of a span of 10⁶ s: the chattering
// test stopped that run ("chattering" at t = 902.57), while spans of 10³ and 10⁵ s rested. The
// impacts converge (the newest 4.5e-5 of the oldest's speed): the same rest whatever the span.
TEST(ContactRest, HighRestitutionBallRestsAtTheSameTimeWhateverTheRunsSpan) {
  const double e = 0.999, h0 = 1.0, t0 = std::sqrt(2.0 * h0 / 9.81);
  const double t_inf = t0 * (1.0 + e) / (1.0 - e);
  double first = 0.0;
  for (const double span : {1e3, 1e6}) {
    SCOPED_TRACE(span);
    Model m =
        load_model(std::string(UKDYN_EXAMPLES_DIR) + "/bouncing_ball.yaml", {{"e", e}, {"h0", h0}});
    m.options.t_end = span;
    m.options.output_every = span;
    const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    const auto rests = events_of(tr, 0, ContactEvent::Kind::kRest);
    ASSERT_EQ(rests.size(), 1u);
    EXPECT_LT(rests[0].t, t_inf);
    EXPECT_GT(rests[0].t, t_inf - 2e-6 * t_inf);
    if (first == 0.0) first = rests[0].t;
    // (the runs' steps differ with the span: the same rest to 1e-9 of it)
    EXPECT_NEAR(rests[0].t, first, 1e-9 * t_inf);
  }
}

// Under BDF a flight far below the integrator's tolerance is not followed: CVODE restarts at
// order 1 after every event, whose error on a flight at constant acceleration is h² a / 2 per
// step (the Runge–Kutta methods integrate it exactly). The rocking block's 51st landing came 35
// times faster than its 50th (1.8e-6 m/s) and it rested 2.7e-4 s after t∞; a ball on a table
// vibrating at A sin ωt stalled at steps of 5e-16 s. A landing whose flight rose less than
// 10 rtol of its gap's scale (apex ≈ speed × flight time / 4) now ends the sequence as the rest
// criterion does, noted as such (ContactEvents::set_flight_tolerance): every landing before t∞,
// at the quadrature's times while resolved, no landing faster than the one before; the rest
// within the last resolved flights of t∞, m g / 2 per corner; the table's ball rests as under
// dopri5, in steps of a normal size.
TEST(ContactRest, UnderBdfAnAccumulationEndsWhereItsFlightsFallBelowTheTolerance) {
  const Rocking housner(0.2, 0.5, 9.81);
  const std::vector<double> landing = housner.landings(0.2, 60);
  const double t_inf = landing.back();
  for (const double l : {1.0, 1000.0}) {
    SCOPED_TRACE(l == 1.0 ? "SI" : "mm");
    Model model = parse_model(rocking_block(l == 1.0 ? "m" : "mm", 0.2 * l, 0.5 * l, 9.81 * l));
    model.options.integrator = Integrator::kBDF;
    const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    // (BDF restarts at order 1 at each landing: 5656 steps in SI, 3538 in mm; dopri5 takes 442)
    EXPECT_LT(tr.stats.steps, 8000);
    std::vector<ContactEvent> landings;
    for (const ContactEvent& e : tr.stats.contact_events) {
      if (e.kind == ContactEvent::Kind::kImpact ||
          (e.kind == ContactEvent::Kind::kRest && e.speed_before < 0.0)) {
        landings.push_back(e);
      }
    }
    ASSERT_GE(landings.size(), 30u);
    ASSERT_LE(landings.size(), 61u);
    for (std::size_t k = 0; k < landings.size(); ++k) {
      const ContactEvent& e = landings[k];
      EXPECT_EQ(e.constraint, k % 2 ? 2 : 1) << k;
      EXPECT_LT(e.t, t_inf) << k;
      if (k > 0) {
        EXPECT_LT(-e.speed_before, -landings[k - 1].speed_before) << k;
      }
      // (the first 30 at the quadrature's times, to BDF's tolerance)
      if (k < 30) {
        EXPECT_NEAR(e.t, landing[k], 1e-6) << k;
      }
    }
    const ContactEvent& rest = landings.back();
    EXPECT_EQ(rest.kind, ContactEvent::Kind::kRest);
    EXPECT_GT(t_inf - rest.t, 0.0);
    EXPECT_LT(t_inf - rest.t, 2e-3);
    for (const ContactEvent& e : tr.stats.contact_events) {
      if (e.t > rest.t) ADD_FAILURE() << "an event after the rest at t = " << e.t;
    }
    bool noted = false;
    for (const std::string& note : tr.stats.notes)
      noted = noted || note.find("below what BDF follows at rtol 1e-10") != std::string::npos;
    EXPECT_TRUE(noted);
    const std::size_t last = tr.t.size() - 1;
    EXPECT_NEAR(tr.lambda_total[2 * last], 0.5 * 9.81 * l, 1e-8 * 9.81 * l);
    EXPECT_NEAR(tr.lambda_total[2 * last + 1], 0.5 * 9.81 * l, 1e-8 * 9.81 * l);
  }
  // the ball on the vibrating table (m = 0.1, dropped from 0.3 m, e = 0.5, A = 0.01 m, ω = 20
  // rad/s, the file's default tolerances): dopri5 rests at its 21st landing, 0.7442064768277 s
  // by an independent event-driven integration (scipy's DOP853 at rtol 1e-12 from impact to
  // impact, the same rest rule); BDF now rests within 1e-4 s before it
  const std::string table =
      "parameters: {m: 0.1, g: 9.81, h0: 0.3, e: 0.5, A: 0.01, w: 20}\n"
      "coordinates: [y]\nkinetic_energy: 0.5*m*y_dot^2\npotential_energy: m*g*y\n"
      "constraints:\n"
      "  - {name: table, holonomic: y - A*sin(w*t), unilateral: true, restitution: e}\n"
      "initial: {q: {y: h0}}\nsimulate: {t_end: 1}\noutput: {every: 0}\n";
  Model ball = parse_model(table);
  const Trajectory ref = simulate(ball.system, ball.q0, ball.qd0, ball.options);
  ball.options.integrator = Integrator::kBDF;
  const Trajectory tr = simulate(ball.system, ball.q0, ball.qd0, ball.options);
  ASSERT_EQ(ref.stats.status, Status::kOk) << ref.stats.message;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_LT(tr.stats.steps, 5000);
  const auto rest_ref = events_of(ref, 0, ContactEvent::Kind::kRest);
  const auto rest = events_of(tr, 0, ContactEvent::Kind::kRest);
  ASSERT_EQ(rest_ref.size(), 1u);
  ASSERT_EQ(rest.size(), 1u);
  EXPECT_NEAR(rest_ref[0].t, 0.7442064768277, 1e-9);
  EXPECT_LT(rest[0].t, rest_ref[0].t + 1e-9);
  EXPECT_NEAR(rest[0].t, rest_ref[0].t, 1e-4);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

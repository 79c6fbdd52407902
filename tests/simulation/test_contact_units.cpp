// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts in any units (issues #31 item 3 and #29 item 2): the bouncing ball of the
// examples, written in metres, in millimetres (h0 = 1000, g = 9810) and with masses from 1e-6 to
// 1e6, against the closed forms of its impacts on the default settings of its file. The contact's
// gap and closing-speed thresholds and the rest criterion are relative to the run's scales
// (docs/simulation.md, "Scales and tolerances"), so the impact times are the same in every unit
// system and the speeds scale with the lengths.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

const std::string kBall = std::string(UKDYN_EXAMPLES_DIR) + "/bouncing_ball.yaml";

std::vector<ContactEvent> impacts_of(const Trajectory& tr) {
  std::vector<ContactEvent> out;
  for (const ContactEvent& e : tr.stats.contact_events) {
    if (e.kind == ContactEvent::Kind::kImpact) out.push_back(e);
  }
  return out;
}

// The k-th impact (k = 0, 1, …) of a ball dropped from h0 with restitution e: at
// t_k = t0 (1 + 2 (e + … + e^k)), t0 = sqrt(2 h0 / g), arriving at e^k v0 (v0 = g t0) and
// leaving at e^(k+1) v0. The impacts accumulate at t_inf = t0 (1 + e) / (1 − e).
struct Bounces {
  double t0, v0, e;
  double time(int k) const {
    double sum = 1.0, ek = 1.0;
    for (int j = 1; j <= k; ++j) {
      ek *= e;
      sum += 2.0 * ek;
    }
    return t0 * sum;
  }
  double arrival(int k) const { return v0 * std::pow(e, k); }
  double t_inf() const { return t0 * (1.0 + e) / (1.0 - e); }
};

TEST(ContactUnits, TheBouncingBallsImpactsAreTheSameInEveryUnitSystem) {
  struct Case {
    const char* what;
    double length;  // metres per unit of length
    double mass;    // kg per unit of mass
  };
  for (const double e : {0.3, 0.5, 0.8}) {
    const Trajectory si = run_model(load_model(kBall, {{"e", e}})).trajectory;
    ASSERT_EQ(si.stats.status, Status::kOk) << si.stats.message;
    const std::vector<ContactEvent> si_impacts = impacts_of(si);
    for (const Case c : {Case{"metres", 1.0, 1.0}, Case{"millimetres", 1e-3, 1.0},
                         Case{"kilometres", 1e3, 1.0}, Case{"milligrams", 1.0, 1e-6},
                         Case{"tonnes", 1.0, 1e3}, Case{"millimetres and megagrams", 1e-3, 1e6}}) {
      SCOPED_TRACE(std::string(c.what) + ", e = " + std::to_string(e));
      const double h0 = 1.0 / c.length, g = 9.81 / c.length, m = 0.5 / c.mass;
      const Model model = load_model(kBall, {{"e", e}, {"h0", h0}, {"g", g}, {"m", m}});
      const Trajectory tr = run_model(model).trajectory;
      ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
      const std::vector<ContactEvent> impacts = impacts_of(tr);
      const Bounces b{std::sqrt(2.0 * h0 / g), std::sqrt(2.0 * h0 * g), e};
      // (the closed forms for the first four impacts, well above the rest speed, that fall
      // before t_end = 2 s: three at e = 0.8)
      int checked = 0;
      while (checked < 4 && b.time(checked) < 2.0) ++checked;
      ASSERT_GE(impacts.size(), std::size_t(checked));
      for (int k = 0; k < checked; ++k) {
        const ContactEvent& ik = impacts[std::size_t(k)];
        EXPECT_NEAR(ik.t, b.time(k), 5e-8 * b.time(k)) << "impact " << k;
        EXPECT_NEAR(-ik.speed_before, b.arrival(k), 1e-7 * b.v0) << "impact " << k;
        EXPECT_NEAR(ik.speed_after, b.arrival(k + 1), 1e-7 * b.v0) << "impact " << k;
        // (times to 5e-8, speeds to 1e-7 of v0: the fourth impact at e = 0.3 arrives at 2.7 %
        // of v0, its time 1.0e-8 and its speed 1.9e-8 v0 from the closed form)
        // the kinetic energy lost, (1 − e²) m (e^k v0)² / 2, in the file's units
        const double lost = 0.5 * m * (1.0 - e * e) * b.arrival(k) * b.arrival(k);
        EXPECT_NEAR(-ik.energy_change, lost, 1e-7 * 0.5 * m * b.v0 * b.v0);
      }
      // the same impacts as in metres, to 5e-8 of their time (the late, slow impacts of a Zeno
      // sequence differ by up to 1.6e-8), and as many of them (the rest criterion is relative to
      // the fastest impact)
      EXPECT_EQ(impacts.size(), si_impacts.size());
      for (std::size_t k = 0; k < std::min(impacts.size(), si_impacts.size()); ++k) {
        EXPECT_NEAR(impacts[k].t, si_impacts[k].t, 5e-8 * si_impacts[k].t) << "impact " << k;
      }
      // a comparable number of steps (the metamorphic suite's bound: within 2x)
      EXPECT_LE(tr.stats.steps, 2 * si.stats.steps);
      EXPECT_GE(2 * tr.stats.steps, si.stats.steps);
      // the rest where the impacts accumulate (e = 0.3 and 0.5 within t_end = 2 s): the ball
      // then lies on the floor, y = 0 to the projection's tolerance in the file's lengths
      if (b.t_inf() < 2.0) {
        const ContactEvent& last = tr.stats.contact_events.back();
        EXPECT_EQ(last.kind, ContactEvent::Kind::kRest);
        EXPECT_NEAR(last.t, b.t_inf(), 1e-4 * b.t_inf());
        EXPECT_NEAR(tr.q.back(), 0.0, 1e-9 * h0);
        EXPECT_NEAR(tr.qd.back(), 0.0, 1e-9 * b.v0);
      } else {
        EXPECT_GT(tr.q.back(), 0.0);  // (e = 0.8: still bouncing at t = 2 s, t_inf = 4.06 s)
      }
    }
  }
}

TEST(ContactUnits, TheRestNoteSaysTheRunsTimeUnit) {
  // u16 03: the notes printed bare numbers in a model in mm, g, ms (SimulationOptions::units,
  // which a model file's units: fills)
  Model model = load_model(kBall, {{"e", 0.5}});
  model.unit_system.time = "ms";
  model.options.units.time = "ms";
  const Trajectory tr = run_model(model).trajectory;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  bool said = false;
  for (const std::string& note : tr.stats.notes)
    said = said || (note.find(" ms: contact 'floor' came to rest after ") != std::string::npos &&
                    note.find("(the gap's unit per ms)") != std::string::npos);
  EXPECT_TRUE(said) << (tr.stats.notes.empty() ? "" : tr.stats.notes.front());
}

// A block (m = 2) released sliding down a rough incline (α = 0.3, μ = 0.35 > tan α, μ_s = 0.6,
// a unilateral slope with Coulomb friction) at v0; from t = 6 s a force k (t − 6), k = 10 N/s,
// pushes it down the slope. Closed form: it decelerates at d = g (μ cos α − sin α) = 0.3811 m/s²,
// sticks at s* = v0² / (2 d), and breaks away where m g sin α + k (t − 6) = μ_s m g cos α,
// t_b = 6.5448 s, whatever v0; then s'' = (μ_s − μ) g cos α + k (t − t_b) / m, so
// s(t) − s* = A τ² / 2 + k τ³ / (6 m), τ = t − t_b, A = (μ_s − μ) g cos α. The stick used to
// be refused for removing 1e-14 J (the block at v_stop = 100 eps) against rtol times the run's
// largest kinetic energy, 4e-6 J for v0 = 2 mm/s: the block crept on the regularized law and
// broke away at μ, at 6.076 s, as did the 2 m/s run written in km (g = 9.81e-3 km/s²).
TEST(ContactUnits, SlowSlideOnARoughInclineSticksInAnyUnits) {
  const std::string text = R"(
parameters: {m: 2, g: 9.81, mu: 0.35, mus: 0.6, a: 0.3, v0: 2, k: 10, t1: 6}
coordinates: [x, y]
kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)
potential_energy: m*g*y
forces: [k*(t - t1)*heaviside(t - t1)*cos(a), -k*(t - t1)*heaviside(t - t1)*sin(a)]
constraints:
  - {name: slope, holonomic: y*cos(a) + x*sin(a), unilateral: true}
nonideal:
  - {friction: coulomb, constraint: slope, mu: mu, mu_static: mus, coordinates: [x, y]}
initial:
  q: {x: 0, y: 0}
  q_dot: {x: v0*cos(a), y: -v0*sin(a)}
simulate: {t_end: 7}
output: {every: 0, at: [6, 6.5, 7]}
)";
  const double m = 2.0, a = 0.3, mu = 0.35, mus = 0.6, k_si = 10.0;
  struct Case {
    const char* what;
    double v0_si;   // m/s
    double length;  // metres per unit of length
  };
  for (const Case c : {Case{"2 m/s", 2.0, 1.0}, Case{"2 cm/s", 0.02, 1.0},
                       Case{"2 mm/s", 0.002, 1.0}, Case{"2 m/s in km", 2.0, 1e3}}) {
    SCOPED_TRACE(c.what);
    const double g = 9.81 / c.length, v0 = c.v0_si / c.length, k = k_si / c.length;
    const Model model = parse_model(text, "<string>", {{"g", g}, {"v0", v0}, {"k", k}});
    const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_EQ(tr.stats.stick_refusals, 0);
    // the samples at t = 0, 6, 6.5 and 7 (t_end); s(j): the distance down the slope at the
    // (j + 1)-th
    ASSERT_EQ(tr.t.size(), 4u);
    EXPECT_EQ(tr.t[1], 6.0);
    EXPECT_EQ(tr.t[2], 6.5);
    EXPECT_EQ(tr.t[3], 7.0);
    auto s = [&](std::size_t j) {
      return tr.q[2 * (j + 1)] * std::cos(a) - tr.q[2 * (j + 1) + 1] * std::sin(a);
    };
    const double d = g * (mu * std::cos(a) - std::sin(a)), s_stick = v0 * v0 / (2.0 * d);
    const double tb = 6.0 + m * g * (mus * std::cos(a) - std::sin(a)) / k;
    EXPECT_NEAR(tb, 6.5448, 1e-4);
    const double tau = 7.0 - tb, A = (mus - mu) * g * std::cos(a);
    // at rest where it stopped, at t = 6 and 6.5 (s* = 5.2 m down to 5.2 µm)
    EXPECT_NEAR(s(0), s_stick, 1e-6 * s_stick + 1e-9 / c.length);
    EXPECT_NEAR(s(1), s_stick, 1e-6 * s_stick + 1e-9 / c.length);
    // and sliding from t_b on: 0.3213 m by t = 7
    const double slid = A * tau * tau / 2.0 + k * tau * tau * tau / (6.0 * m);
    EXPECT_NEAR(slid * c.length, 0.3213, 1e-4);
    EXPECT_NEAR(s(2) - s(1), slid, 1e-6 * slid);
  }
}

// The bouncing ball of the repro (e = 0.5, h0 = 1, g = 9.81, default settings) with its gap
// written as 10^k y: the same zero set and motion, a row scale of 10^k, the contact's W of
// 10^(2k) / m. Closed form: impacts at t_j = t0 (3 − 2 e^j), t0 = √(2 h0 / g), until the speed
// e^j v0 falls below 1e-6 of the first, j = 20, where the ball rests: 21 contact events, 20
// impacts and the rest at t_20 = 1.3545701. With k = −90 and below the rest stopped the run ("the
// LCP of the closed contacts has no solution (Siconos lcp_lexicolemke)", W ~ 1e-180): the LCP is
// now solved scaled (ContactLcp::row_scale), and every factor gives the run of y.
TEST(ContactUnits, TheBallsGapMayCarryAnyFactor) {
  auto run = [](const std::string& gap) {
    const Model m = parse_model(R"(
parameters: {m: 0.5, g: 9.81, h0: 1.0, e: 0.5}
coordinates: [y]
kinetic_energy: 0.5*m*y_dot^2
potential_energy: m*g*y
constraints:
  - {name: floor, holonomic: )" +
                                gap + R"(, unilateral: true, restitution: e}
initial: {q: {y: h0}}
simulate: {t_end: 2.0}
output: {every: 0.01}
)");
    return simulate(m.system, m.q0, m.qd0, m.options);
  };
  const double t0 = std::sqrt(2.0 / 9.81), t20 = t0 * (3.0 - 2.0 * std::pow(0.5, 20));
  EXPECT_NEAR(t20, 1.3545701, 1e-7);
  const Trajectory y = run("y");
  ASSERT_EQ(y.stats.status, Status::kOk) << y.stats.message;
  const std::vector<ContactEvent> y_impacts = impacts_of(y);
  ASSERT_EQ(y_impacts.size(), 20u);
  ASSERT_EQ(y.stats.contact_events.size(), 21u);
  ASSERT_EQ(y.stats.contact_events.back().kind, ContactEvent::Kind::kRest);
  const double y_rest = y.stats.contact_events.back().t;
  EXPECT_NEAR(y_rest, t20, 1e-7 * t20);
  for (const int k : {-150, -90, -8, 0, 8}) {
    SCOPED_TRACE("gap 1e" + std::to_string(k) + " y");
    const Trajectory tr = run("1e" + std::to_string(k) + "*y");
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    const std::vector<ContactEvent> impacts = impacts_of(tr);
    ASSERT_EQ(impacts.size(), 20u);
    ASSERT_EQ(tr.stats.contact_events.size(), 21u);
    for (std::size_t j = 0; j < impacts.size(); ++j) {
      EXPECT_NEAR(impacts[j].t, y_impacts[j].t, 1e-9 * y_impacts[j].t) << "impact " << j;
    }
    ASSERT_EQ(tr.stats.contact_events.back().kind, ContactEvent::Kind::kRest);
    EXPECT_NEAR(tr.stats.contact_events.back().t, y_rest, 1e-9 * y_rest);
    EXPECT_NEAR(tr.stats.contact_events.back().t, t20, 1e-7 * t20);
    // at rest on the floor at t_end, carrying m g (λ per unit of the row: m g / 10^k)
    EXPECT_NEAR(tr.q.back(), 0.0, 1e-9);
    EXPECT_NEAR(tr.qd.back(), 0.0, 1e-9);
    EXPECT_NEAR(tr.lambda.back() * std::pow(10.0, k), 0.5 * 9.81, 1e-8 * 0.5 * 9.81);
  }
}

// u23 3: a plank (x, y, θ; m = 0.5 kg, L = 1 m) dropped flat from h0 = 0.05 m onto three
// asymmetric frictionless supports, gaps y + s_i sin θ at s = −0.4, 0.1, 0.45 m, e = 0.5, in SI
// and in mm, g, ms. Closed form: the three hit together at t0 = √(2 h0 / g) (no rotation: the
// impulse's moment vanishes), y' leaves at e v0, and the k-th simultaneous impact at
// t0 (1 + 2 (e + … + e^(k−1))) arrives at e^(k−1) v0; the 21st (e^20 v0 < 1e-6 v0) rests, at
// t0 (3 − 2 e^20) = 0.30289108 s (early on t∞ = 3 t0 by the flights left out, 2 e^20 t0). The
// resting loads are the least-norm split of Σ λ = m g, Σ s λ = 0 (docs/contact.md "Redundant
// contacts"): λ = Bᵀ (B Bᵀ)⁻¹ (m g, 0), B = [1 1 1; s1 s2 s3]. In mm the row norm
// |(1, s cos θ)| ≈ 450 (mm and mm/rad) made the contacts' speed unit 1000 mm/ms: the supports
// leaving the 20th impact at 9.4e-7 mm/ms were closed at once while separating ("60 impacts,
// 0 rests"), on Lemke's vertex 2.5968 / 0 / 2.3082, and with no drift control the plank rose at
// that rate while they pushed m g.
TEST(ContactUnits, PlankOnThreeSupportsRestsAtTheSameTimeWithTheSameLoadsInMm) {
  const std::string text = R"(
parameters: {m: 0.5, L: 1, g: 9.81, h0: 0.05, e: 0.5, s1: -0.4, s2: 0.1, s3: 0.45, T: 0.4}
coordinates: [x, y, th]
kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2) + 0.5*m*L^2/12*th_dot^2
potential_energy: m*g*y
constraints:
  - {name: a, holonomic: y + s1*sin(th), unilateral: true, restitution: e}
  - {name: b, holonomic: y + s2*sin(th), unilateral: true, restitution: e}
  - {name: c, holonomic: y + s3*sin(th), unilateral: true, restitution: e}
initial: {q: {x: 0, y: h0, th: 0}}
simulate: {t_end: T}
output: {every: 0, at: [T]}
)";
  const double e = 0.5, s_si[3] = {-0.4, 0.1, 0.45};
  // the least-norm split (in N: a force in g mm/ms² is one in N)
  const double mg = 0.5 * 9.81, Bs = s_si[0] + s_si[1] + s_si[2];
  const double Bss = s_si[0] * s_si[0] + s_si[1] * s_si[1] + s_si[2] * s_si[2];
  const double det = 3.0 * Bss - Bs * Bs, y1 = mg * Bss / det, y2 = -mg * Bs / det;
  struct Case {
    const char* what;
    double L, M, T;  // metres, kilograms and seconds per unit
    DriftControl drift;
  };
  for (const Case c :
       {Case{"SI", 1.0, 1.0, 1.0, DriftControl::kProjection},
        Case{"mm, g, ms", 1e-3, 1e-3, 1e-3, DriftControl::kProjection},
        Case{"SI, no drift control", 1.0, 1.0, 1.0, DriftControl::kNone},
        Case{"mm, g, ms, no drift control", 1e-3, 1e-3, 1e-3, DriftControl::kNone}}) {
    SCOPED_TRACE(c.what);
    const double g = 9.81 * c.T * c.T / c.L, h0 = 0.05 / c.L;
    Model model = parse_model(text, "<string>",
                              {{"m", 0.5 / c.M},
                               {"L", 1.0 / c.L},
                               {"g", g},
                               {"h0", h0},
                               {"s1", s_si[0] / c.L},
                               {"s2", s_si[1] / c.L},
                               {"s3", s_si[2] / c.L},
                               {"T", 0.4 / c.T}});
    model.options.drift = c.drift;
    const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    const double t0 = std::sqrt(2.0 * h0 / g), v0 = g * t0;
    const double t20 = t0 * (3.0 - 2.0 * std::pow(e, 20));
    // 20 impacts of each support, then each rests, all at the closed-form times
    std::size_t impacts = 0, rests = 0;
    for (const ContactEvent& ev : tr.stats.contact_events) {
      if (ev.kind == ContactEvent::Kind::kImpact) {
        const int k = int(impacts++ / 3);
        double sum = 1.0, ek = 1.0;
        for (int j = 1; j <= k; ++j) sum += 2.0 * (ek *= e);
        EXPECT_NEAR(ev.t, t0 * sum, 1e-9 * t0 * sum) << "impact " << impacts;
        EXPECT_NEAR(-ev.speed_before, v0 * std::pow(e, k), 1e-9 * v0) << "impact " << impacts;
      } else if (ev.kind == ContactEvent::Kind::kRest) {
        ++rests;
        EXPECT_NEAR(ev.t, t20, 1e-9 * t20);
        EXPECT_NEAR(ev.t, 3.0 * t0, 1e-6 * 3.0 * t0);
      } else {
        ADD_FAILURE() << "contact event of kind " << int(ev.kind) << " at t = " << ev.t;
      }
    }
    EXPECT_EQ(impacts, 60u);
    EXPECT_EQ(rests, 3u);
    // at rest on the supports at t_end: y = 0, y' = 0 (it floated up at 9.4e-7 mm/ms), no turn,
    // the loads the least-norm split
    ASSERT_EQ(tr.t.size(), 2u);
    EXPECT_NEAR(tr.q[3 + 1], 0.0, 1e-9 * h0);
    EXPECT_NEAR(tr.qd[3 + 1], 0.0, 1e-12 * v0);
    EXPECT_NEAR(tr.q[3 + 2], 0.0, 1e-12);
    EXPECT_NEAR(tr.qd[3 + 2], 0.0, 1e-12 * v0 / h0);
    ASSERT_EQ(tr.m, 3);
    for (int i = 0; i < 3; ++i) {
      const double split = y1 + s_si[i] * y2;  // 1.93736, 1.60140, 1.36623 N
      EXPECT_NEAR(tr.lambda[3 + std::size_t(i)] * c.M * c.L / (c.T * c.T), split, 1e-9 * split)
          << "support " << i;
    }
  }
}

// u23 3, spatial: a box (2 kg, 200 × 100 × 50 mm) of a rigid body with the `shape: box` contact
// dropped flat from 50 mm, e = 0.5, frictionless, in mm, g, ms: four simultaneous corner impacts
// per bounce, 20 bounces, then the four corners rest at t0 (3 − 2 e^20) = 302.89108 ms and carry
// m g / 4 each (the least-norm split; Lemke's vertex loads two diagonal corners). It made 80
// impacts and no rest, and with no drift control rose at 9.4e-7 mm/ms while the corners pushed.
TEST(ContactUnits, BoxDroppedFlatInMmRestsOnItsFourCorners) {
  Model model = parse_model(R"(
units: {length: mm, mass: g, time: ms}
parameters: {m: 2000, a: 200, b: 100, c: 50, g: 9.81e-3, h0: 50, e: 0.5}
bodies:
  - {name: box, type: rigid, mass: m, inertia: [m*(b^2 + c^2)/3, m*(a^2 + c^2)/3, m*(a^2 + b^2)/3], position: [0, 0, c + h0]}
forces:
  - {type: gravity, g: [0, 0, -g]}
contacts:
  - {name: floor, body: box, shape: box, size: [a, b, c], restitution: e}
simulate: {t_end: 400}
output: {every: 0, at: [400]}
)",
                            "<string>");
  model.options.drift = DriftControl::kNone;
  const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double g = 9.81e-3, t0 = std::sqrt(2.0 * 50.0 / g), v0 = g * t0;
  const double t20 = t0 * (3.0 - 2.0 * std::pow(0.5, 20));
  std::size_t impacts = 0, rests = 0;
  for (const ContactEvent& ev : tr.stats.contact_events) {
    if (ev.kind == ContactEvent::Kind::kImpact) ++impacts;
    if (ev.kind != ContactEvent::Kind::kRest) continue;
    ++rests;
    EXPECT_NEAR(ev.t, t20, 1e-9 * t20);
  }
  EXPECT_EQ(impacts, 80u);
  EXPECT_EQ(rests, 4u);
  // at rest at t_end: z = c = 50 mm, z' = 0, each corner m g / 4 = 4.905 g mm/ms²
  ASSERT_EQ(tr.t.size(), 2u);
  bool found = false;
  for (std::size_t i = 0; i < tr.coordinate_names.size(); ++i) {
    if (tr.coordinate_names[i] != "box.z") continue;
    found = true;
    EXPECT_NEAR(tr.q[std::size_t(tr.n) + i], 50.0, 1e-9 * 50.0);
    EXPECT_NEAR(tr.qd[std::size_t(tr.n) + i], 0.0, 1e-12 * v0);
  }
  EXPECT_TRUE(found);
  // (corners floor.0 … floor.3 at the bottom, floor.4 … floor.7 at the top, open)
  const double quarter = 2000.0 * g / 4.0;
  std::size_t row = 0, corners = 0;
  for (std::size_t k = 0; k < tr.constraint_names.size(); ++k) {
    const std::string& name = tr.constraint_names[k];
    if (name.rfind("floor.", 0) == 0) {
      const bool bottom = name.back() < '4';
      corners += bottom ? 1 : 0;
      EXPECT_NEAR(tr.lambda[std::size_t(tr.m) + row], bottom ? quarter : 0.0, 1e-9 * quarter)
          << name;
    }
    row += std::size_t(tr.constraint_rows[k]);
  }
  EXPECT_EQ(corners, 4u);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

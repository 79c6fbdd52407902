// SPDX-License-Identifier: BSD-3-Clause
// Coulomb friction on unilateral contacts (issue #31, docs/contact.md "Friction"), each against a
// closed form: a block on a rough incline that slides (or sticks, then slips) and lifts off when
// a pull along the normal grows, with no friction once it is off; a rod sliding on a rough floor
// in Painlevé's configuration, below the critical mu (the run's normal force against its closed
// form) and above it (a clear error naming the contact and mu).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "contact/incline_model.hpp"
#include "support/contact_runs.hpp"
#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81;

// the sample of tr at time t (failing when there is none)
std::size_t sample_at(const Trajectory& tr, double t) {
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    if (std::abs(tr.t[i] - t) <= 1e-12 * std::max(1.0, std::abs(t))) return i;
  }
  ADD_FAILURE() << "no sample at t = " << t;
  return 0;
}

// ---- a block on a rough incline, pulled off it ----------------------------------------------

// A block (mass m) on the plane through the origin at angle alpha (y = −x tan alpha; gap
// n = x sin alpha + y cos alpha, the distance along the normal), gravity along −y, pulled along
// the normal by F = k t. The plane pushes with N = m g cos alpha − k t until t* = m g cos alpha /
// k, where the block lifts off. While it slides down the slope (s = x cos alpha − y sin alpha),
// s'' = g (sin alpha − mu cos alpha) + mu k t / m; once off, s'' = g sin alpha and
// n = k (t − t*)³ / (6 m).
const std::string kIncline = std::string(incline::kModel) +
                             "simulate: {t_end: 5, integrator: dopri5, rtol: 1e-11, atol: 1e-13}\n"
                             "output: {every: 0}\n";

struct Incline {
  double m = 2, alpha = 0.5, mu = 0.3, k = 4, v0 = 1;
  double t_star() const { return m * kG * std::cos(alpha) / k; }
  // s and s' while sliding from t0 at s0, v0s (friction mu N)
  double s(double t, double t0, double s0, double v0s) const {
    const double a0 = kG * (std::sin(alpha) - mu * std::cos(alpha));
    const double j = mu * k / m;
    return s0 + v0s * (t - t0) + 0.5 * a0 * (t - t0) * (t - t0) +
           j * (t * t * t - t0 * t0 * t0) / 6.0 - j * t0 * t0 * (t - t0) / 2.0;
  }
  double sd(double t, double t0, double v0s) const {
    const double a0 = kG * (std::sin(alpha) - mu * std::cos(alpha));
    return v0s + a0 * (t - t0) + mu * k / (2.0 * m) * (t * t - t0 * t0);
  }
};

double along(const Trajectory& tr, std::size_t i, double alpha) {
  return tr.q[2 * i] * std::cos(alpha) - tr.q[2 * i + 1] * std::sin(alpha);
}
double along_rate(const Trajectory& tr, std::size_t i, double alpha) {
  return tr.qd[2 * i] * std::cos(alpha) - tr.qd[2 * i + 1] * std::sin(alpha);
}
double normal(const Trajectory& tr, std::size_t i, double alpha) {
  return tr.q[2 * i] * std::sin(alpha) + tr.q[2 * i + 1] * std::cos(alpha);
}

TEST(ContactFriction, BlockSlidesOnARoughInclineThenLiftsOff) {
  const Incline c;
  const double ts = c.t_star();  // 4.3046
  Model m = parse_model(kIncline);
  m.options.output_at = {2.0, ts, 5.0};
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  // one event: the release at t* (no stick/slip event: the block slides all along)
  ASSERT_EQ(tr.stats.contact_events.size(), 1u);
  EXPECT_EQ(tr.stats.contact_events[0].kind, ContactEvent::Kind::kRelease);
  EXPECT_NEAR(tr.stats.contact_events[0].t, ts, 1e-9);
  // at t = 2: sliding with friction mu N, N = m g cos alpha − k t (the plane's multiplier: its
  // row has unit norm)
  const std::size_t i2 = sample_at(tr, 2.0);
  EXPECT_NEAR(normal(tr, i2, c.alpha), 0.0, 1e-12);
  EXPECT_NEAR(along(tr, i2, c.alpha), c.s(2.0, 0.0, 0.0, c.v0), 1e-9);
  EXPECT_NEAR(along_rate(tr, i2, c.alpha), c.sd(2.0, 0.0, c.v0), 1e-9);
  EXPECT_NEAR(tr.lambda[std::size_t(tr.m) * i2], c.m * kG * std::cos(c.alpha) - c.k * 2.0, 1e-8);
  // the friction force: −mu N along the slope (Qc_nonideal on the sliding coordinates)
  const double friction =
      tr.Qc_nonideal[2 * i2] * std::cos(c.alpha) - tr.Qc_nonideal[2 * i2 + 1] * std::sin(c.alpha);
  EXPECT_NEAR(friction, -c.mu * (c.m * kG * std::cos(c.alpha) - c.k * 2.0), 1e-8);
  // at t = 5, off the plane: no friction, s'' = g sin alpha, n = k (t − t*)³ / (6 m)
  const double s_star = c.s(ts, 0.0, 0.0, c.v0), v_star = c.sd(ts, 0.0, c.v0), d = 5.0 - ts;
  const std::size_t i5 = sample_at(tr, 5.0);
  EXPECT_NEAR(along(tr, i5, c.alpha), s_star + v_star * d + 0.5 * kG * std::sin(c.alpha) * d * d,
              1e-8);
  EXPECT_NEAR(normal(tr, i5, c.alpha), c.k * d * d * d / (6.0 * c.m), 1e-9);
  EXPECT_NEAR(tr.Qc_nonideal[2 * i5], 0.0, 1e-12);
  EXPECT_NEAR(tr.Qc_nonideal[2 * i5 + 1], 0.0, 1e-12);
  EXPECT_NEAR(tr.lambda[std::size_t(tr.m) * i5], 0.0, 1e-12);
  EXPECT_EQ(tr.stats.events, 0);
  EXPECT_TRUE(tr.stats.energy_balance_checked);
}

TEST(ContactFriction, BlockSticksThenSlipsThenLiftsOff) {
  // at rest with tan alpha < mu (0.546 < 0.6): it sticks until mu N = m g sin alpha, at
  // t_s = m g (cos alpha − sin alpha / mu) / k, then slides from rest with
  // s'' = mu k (t − t_s) / m, so s = mu k (t − t_s)³ / (6 m), until it lifts off at t*
  Incline c;
  c.mu = 0.6;
  c.v0 = 0.0;
  const double ts = c.m * kG * (std::cos(c.alpha) - std::sin(c.alpha) / c.mu) / c.k;  // 0.3852
  const double t_star = c.t_star();
  Model m = parse_model(kIncline, "<string>", {{"mu", c.mu}, {"v0", 0.0}});
  m.options.output_at = {0.3, 2.0, 5.0};
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  // the slip at t_s, where the holding force m g sin alpha reaches mu_s N (listed with it),
  // then the release at t*
  ASSERT_EQ(tr.stats.contact_events.size(), 2u);
  const ContactEvent& slip = tr.stats.contact_events[0];
  EXPECT_EQ(slip.kind, ContactEvent::Kind::kSlip);
  EXPECT_NEAR(slip.t, ts, 1e-9);
  EXPECT_NEAR(slip.holding_force, c.m * kG * std::sin(c.alpha), 1e-8 * c.m * kG);
  EXPECT_NEAR(slip.friction_limit, c.m * kG * std::sin(c.alpha), 1e-8 * c.m * kG);
  EXPECT_EQ(tr.stats.contact_events[1].kind, ContactEvent::Kind::kRelease);
  EXPECT_NEAR(tr.stats.contact_events[1].t, t_star, 1e-9);
  EXPECT_EQ(tr.stats.events, 1);  // the slip (a located stick/slip event)
  const std::size_t i0 = sample_at(tr, 0.3);
  EXPECT_NEAR(along(tr, i0, c.alpha), 0.0, 1e-12);
  EXPECT_NEAR(along_rate(tr, i0, c.alpha), 0.0, 1e-12);
  const double j = c.mu * c.k / c.m;
  const std::size_t i2 = sample_at(tr, 2.0);
  EXPECT_NEAR(along(tr, i2, c.alpha), j * std::pow(2.0 - ts, 3) / 6.0, 1e-8);
  EXPECT_NEAR(along_rate(tr, i2, c.alpha), j * std::pow(2.0 - ts, 2) / 2.0, 1e-8);
  const double s_star = j * std::pow(t_star - ts, 3) / 6.0,
               v_star = j * std::pow(t_star - ts, 2) / 2.0, d = 5.0 - t_star;
  const std::size_t i5 = sample_at(tr, 5.0);
  EXPECT_NEAR(along(tr, i5, c.alpha), s_star + v_star * d + 0.5 * kG * std::sin(c.alpha) * d * d,
              1e-8);
  EXPECT_NEAR(normal(tr, i5, c.alpha), c.k * d * d * d / (6.0 * c.m), 1e-9);
  EXPECT_TRUE(tr.stats.energy_balance_checked);
}

// ---- Painlevé's paradox -----------------------------------------------------------------------

// A uniform rod (mass m, length L = 2 l) whose end A slides on a rough floor (yA >= 0, friction
// mu on xA), B = A + L (cos th, sin th) above it, translating at v towards −x. With N the floor's
// force and the friction +mu N on A (against the sliding), the rod's equations give A's normal
// acceleration yA'' = (N / m) (1 + 3 cos² th − 3 mu sin th cos th) − g + l sin th th'², so the
// contact's effective compliance turns negative above mu_c = (1 + 3 cos² th) / (3 sin th cos th),
// 4/3 at tan th = 2. Below it, N = m g / (1 + 3 cos² th − 3 mu sin th cos th) at rest (th' = 0);
// above it (with yA'' = −g free) there is no solution: Painlevé's paradox.
constexpr const char* kRod = R"(
parameters: {m: 1, L: 2, g: 9.81, th0: 1.1071487177940904, mu: 0.5, v: 1}
coordinates: [xA, yA, xB, yB]
kinetic_energy: m/6*(xA_dot^2 + yA_dot^2 + xA_dot*xB_dot + yA_dot*yB_dot + xB_dot^2 + yB_dot^2)
potential_energy: m*g*(yA + yB)/2
constraints:
  - {name: rod, holonomic: ((xA - xB)^2 + (yA - yB)^2 - L^2)/(2*L)}
  - {name: floor, holonomic: yA, unilateral: true}
nonideal:
  - {friction: coulomb, constraint: floor, mu: mu, coordinates: [xA]}
initial:
  q: {xA: 0, yA: 0, xB: L*cos(th0), yB: L*sin(th0)}
  q_dot: {xA: -v, xB: -v}
simulate: {t_end: 0.02, integrator: dopri5, rtol: 1e-10, atol: 1e-12}
output: {every: 0.01}
)";

TEST(ContactFriction, PainleveRodBelowTheCriticalMuRunsWithTheClosedFormNormalForce) {
  const double th = std::atan(2.0), c = std::cos(th), s = std::sin(th), l = 1.0, m = 1.0;
  const double mu_c = (1.0 + 3.0 * c * c) / (3.0 * s * c);
  EXPECT_NEAR(mu_c, 4.0 / 3.0, 1e-14);
  const double mu = 0.5 * mu_c;
  const Model model = parse_model(kRod, "<string>", {{"mu", mu}});
  const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_TRUE(tr.stats.contact_events.empty());
  // at the start: N from the closed form, and the rod's accelerations from Newton–Euler with it
  // (friction F = +mu N on A): xG'' = F / m, yG'' = N / m − g, I th'' = −l c N + l s F
  const double N = m * kG / (1.0 + 3.0 * c * c - 3.0 * mu * s * c), F = mu * N;
  const double thdd = (-l * c * N + l * s * F) / (m * l * l / 3.0);
  // A = G − l (c, s): xA'' = xG'' + l s th'' (th' = 0), yA'' = yG'' − l c th''
  EXPECT_NEAR(tr.qdd[0], F / m + l * s * thdd, 1e-8);
  EXPECT_NEAR(tr.qdd[1], N / m - kG - l * c * thdd, 1e-8);
  EXPECT_NEAR(tr.qdd[1], 0.0, 1e-8);  // (A stays on the floor)
  // B = G + l (c, s)
  EXPECT_NEAR(tr.qdd[2], F / m - l * s * thdd, 1e-8);
  EXPECT_NEAR(tr.qdd[3], N / m - kG + l * c * thdd, 1e-8);
}

TEST(ContactFriction, PainleveRodAboveTheCriticalMuIsAClearError) {
  for (const double mu : {1.4, 2.0}) {
    const Model model = parse_model(kRod, "<string>", {{"mu", mu}});
    try {
      simulate(model.system, model.q0, model.qd0, model.options);
      ADD_FAILURE() << "no error at mu = " << mu;
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("Painlevé's paradox at the contact 'floor' (mu = " +
                          std::string(mu == 1.4 ? "1.4" : "2") + ")"),
                std::string::npos)
          << what;
      EXPECT_NE(what.find("the critical mu is 1.333"), std::string::npos) << what;
    }
  }
  // just below the critical mu the run proceeds
  const Model below = parse_model(kRod, "<string>", {{"mu", 1.3}, {"v", 1.0}});
  SimulationOptions o = below.options;
  o.t_end = 1e-3;
  const Trajectory tr = simulate(below.system, below.q0, below.qd0, o);
  EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
}

// ---- Housner's rocking block ------------------------------------------------------------------

// A rectangular block (width 2b, height 2h, mass m) rocks on its corners on a rough floor: tilted
// by th0 on its right corner R and released, it falls back about R (stuck: friction holds it)
// until its left corner L hits the floor (e = 0). The impact's impulse acts at L, so the angular
// momentum about L is kept: I_O w⁺ = (I_G + m (h² − b²)) w⁻ with I_G = m (b² + h²) / 3 and
// I_O = (4/3) m (b² + h²) about a corner, so w⁺ / w⁻ = r = 1 − (3/2) sin² alpha, alpha =
// atan(b / h) (Housner 1963) — with L stuck and R leaving the floor. Natural coordinates: the
// bottom corners L = (x1, y1), R = (x2, y2); the centre G = (L + R)/2 + (h/b) J (R − L)/2, J the
// rotation by +90°.
const std::string kRocking =
    testing::rocking_block_in_coordinates("m", 0.2, 0.5, 9.81) +
    "simulate: {t_end: 0.5, integrator: dopri5, rtol: 1e-11, atol: 1e-13}\n"
    "output: {every: 0}\n";

TEST(ContactFriction, RockingBlockLosesAngularVelocityByHousnersRatio) {
  const double m = 1.0, b = 0.2, h = 0.5, alpha = std::atan(b / h);
  const double r = 1.0 - 1.5 * std::sin(alpha) * std::sin(alpha);
  const Model model = parse_model(kRocking);
  const Trajectory tr = simulate(model.system, model.q0, model.qd0, model.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  // the first events: L's impact, R's release at the same instant
  ASSERT_GE(tr.stats.contact_events.size(), 2u);
  const ContactEvent& hit = tr.stats.contact_events[0];
  const ContactEvent& lift = tr.stats.contact_events[1];
  EXPECT_EQ(hit.constraint, 1);
  EXPECT_EQ(hit.kind, ContactEvent::Kind::kImpact);
  EXPECT_EQ(lift.constraint, 2);
  EXPECT_EQ(lift.kind, ContactEvent::Kind::kRelease);
  EXPECT_EQ(lift.t, hit.t);
  // at theta = 0: y1' = −2 b w⁻ before (about R), y2' = 2 b w⁺ after (about L)
  const double w_minus = -hit.speed_before / (2 * b), w_plus = lift.speed_after / (2 * b);
  EXPECT_GT(w_minus, 0.5);
  EXPECT_NEAR(w_plus / w_minus, r, 1e-10);
  EXPECT_NEAR(hit.speed_after, 0.0, 1e-12);
  // the energy lost: ½ I_O (w⁺² − w⁻²)
  const double I_O = 4.0 / 3.0 * m * (b * b + h * h);
  EXPECT_NEAR(hit.energy_change, 0.5 * I_O * (w_plus * w_plus - w_minus * w_minus),
              1e-10 * I_O * w_minus * w_minus);
  // w⁻ from the energy of the fall about R: ½ I_O w⁻² = m g (y_G(th0) − h), the centre at
  // rho = √(b² + h²) from R, y_G(th0) = rho cos(alpha − th0)
  const double rho = std::sqrt(b * b + h * h), th0 = 0.2;
  const double drop = rho * std::cos(alpha - th0) - h;
  EXPECT_NEAR(0.5 * I_O * w_minus * w_minus, m * kG * drop, 1e-8);
  EXPECT_TRUE(tr.stats.energy_balance_checked);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

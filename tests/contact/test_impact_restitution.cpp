// SPDX-License-Identifier: BSD-3-Clause
// Impacts with friction and the laws of restitution (issue #31 item 2, docs/contact.md "Friction
// at impacts" and "Poisson's restitution"), each against a closed form: a rod whose lower end
// strikes a rough floor, where Newton's law with e = 1 would create energy (the impact is redone
// with the largest restitution that creates none, its closed-form velocities and a note); Newton's
// and Poisson's laws on a smooth floor (the same) and on a rough one (they differ by e W_nt v_t⁻ /
// W_tt); and the errors users meet.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include <Eigen/Core>
#include <Eigen/LU>

#include "ukdyn/core/autodiff.hpp"
#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/dynamics/contact_restitution.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// ---- the rod and its impact in closed form ----------------------------------------------------

// A uniform rod (mass m, length 2l, I_G = m l²/3) in the plane, without gravity, in the
// coordinates of its lower end A = (xa, ya) and its angle phi from the floor: G = A + l (cos phi,
// sin phi). It translates at (u, −v) (phi' = 0, phi = phi0) until A strikes the floor ya = 0
// at t = h / v. At A the normal n = y and the tangent t = x; an impulse p = (p_n, p_t) there
// changes A's velocity (g', x_A') by W p, with the Delassus matrix (c = cos phi, s = sin phi)
//   W_nn = (1 + 3c²)/m,  W_tt = (1 + 3s²)/m,  W_nt = −3 s c / m
// (p_n at A turns the rod by −3 c p_n/(m l), which moves A by l s per unit phi' along x). An
// impact that ends with A stuck (x_A'⁺ = 0, |p_t| <= mu p_n) and g'⁺ = v_n⁺ has p = K (v⁺ − v⁻),
// K = W⁻¹, and T⁺ − T⁻ = ½ (v⁺ᵀ K v⁺ − v⁻ᵀ K v⁻).
struct Rod {
  double m = 1.0, l = 1.0, phi0 = 0.7853981633974483, u = 0.5, v = 1.0, h = 0.1;
  double c() const { return std::cos(phi0); }
  double s() const { return std::sin(phi0); }
  Eigen::Matrix2d W() const {  // (n, t) order
    Eigen::Matrix2d w;
    w << (1 + 3 * c() * c()) / m, -3 * s() * c() / m, -3 * s() * c() / m, (1 + 3 * s() * s()) / m;
    return w;
  }
  Eigen::Vector2d v_minus() const { return {-v, u}; }
  // the impulse that makes A's velocity (v_n⁺, 0): A stuck after
  Eigen::Vector2d stuck_impulse(double vn_plus) const {
    return W().inverse() * (Eigen::Vector2d(vn_plus, 0.0) - v_minus());
  }
  // T⁺ − T⁻ of that impact
  double stuck_energy_change(double vn_plus) const {
    const Eigen::Vector2d vp(vn_plus, 0.0);
    const Eigen::Matrix2d K = W().inverse();
    return 0.5 * (vp.dot(K * vp) - v_minus().dot(K * v_minus()));
  }
  // the velocities after an impulse p = (p_n, p_t) at A: G' = (u, −v) + (p_t, p_n)/m, phi' =
  // (r_GA × p)/I_G = 3 (l s p_t − l c p_n)/(m l²)
  Eigen::Vector3d after(const Eigen::Vector2d& p) const {
    return {u + p[1] / m, -v + p[0] / m, 3.0 * (l * s() * p[1] - l * c() * p[0]) / (m * l * l)};
  }
  // the model file: Newton's or Poisson's law, e, and mu (0: no friction)
  std::string model(double e, double mu, const std::string& law = "newton") const {
    std::string text = "parameters: {m: " + std::to_string(m) + ", l: " + std::to_string(l) +
                       "}\n"
                       "coordinates: [xa, ya, phi]\n"
                       "kinetic_energy: >-\n"
                       "  0.5*m*((xa_dot - l*sin(phi)*phi_dot)^2 + (ya_dot + "
                       "l*cos(phi)*phi_dot)^2) + 0.5*m*l^2/3*phi_dot^2\n"
                       "constraints:\n"
                       "  - {name: floor, holonomic: ya, unilateral: true, restitution: " +
                       std::to_string(e) + ", restitution_law: " + law + "}\n";
    if (mu > 0.0) {
      text += "nonideal:\n  - {friction: coulomb, constraint: floor, mu: " + std::to_string(mu) +
              ", coordinates: [xa]}\n";
    }
    char initial[256];
    std::snprintf(initial, sizeof initial,
                  "initial:\n  q: {xa: 0, ya: %.17g, phi: %.17g}\n"
                  "  q_dot: {xa: %.17g, ya: %.17g, phi: 0}\n",
                  h, phi0, u, -v);
    text += initial;
    text +=
        "simulate: {t_end: 0.15, integrator: dopri5, rtol: 1e-11, atol: 1e-13}\n"
        "output: {every: 0}\n";
    return text;
  }
};

// the run of a model text, and G' and phi' at its end (a free flight after the impact: constant)
struct RodRun {
  Trajectory tr;
  Eigen::Vector3d after;  // (x_G', y_G', phi')
};
RodRun run_rod(const Rod& rod, const std::string& text) {
  const Model model = parse_model(text);
  RodRun r{simulate(model.system, model.q0, model.qd0, model.options), {}};
  EXPECT_EQ(r.tr.stats.status, Status::kOk) << r.tr.stats.message;
  const std::size_t last = r.tr.t.size() - 1, n = 3;
  const double phi = r.tr.q[n * last + 2], w = r.tr.qd[n * last + 2];
  // G' = A' + l phi' (−sin phi, cos phi)
  r.after = {r.tr.qd[n * last] - rod.l * std::sin(phi) * w,
             r.tr.qd[n * last + 1] + rod.l * std::cos(phi) * w, w};
  return r;
}

// ---- item 1: a friction impact that Newton's law would make gain energy -----------------------

// With A stuck after the impact, Newton's law (v_n⁺ = −e v_n⁻) gives T⁺ − T⁻ =
// ½ [(e² − 1) K_nn v_n² − 2 K_nt v_n v_t − K_tt v_t²], positive for e = 1 and 0 < v_t <
// −2 K_nt v_n / K_tt (1.2 v at phi = 45°): at u = 0.5, v = 1 it gains 0.109 with p =
// K (2, −0.5) = (1.0625, 0.4375), inside the cone for mu = 2. The run redoes it with the largest
// restitution that gains nothing: T⁺ = T⁻ at e*² = 1 − (2 K_nt v u − K_tt u²) / (K_nn v²) = 0.65
// (K = [[0.625, 0.375], [0.375, 0.625]] at 45°), e* = 0.806226, A stuck, p = K ((1 + e*) v, −u).
// Below e* Newton's impact stands; above, every e gives e*'s impact: the rebound is continuous in
// e (it was once redone plastic at once, a drop to g'⁺ = 0 just above the threshold).
TEST(ImpactRestitution,
     FrictionImpactThatWouldCreateEnergyIsRedoneWithTheLargestRestitutionThatCreatesNone) {
  const Rod rod;
  const double mu = 2.0;
  const Eigen::Matrix2d K = rod.W().inverse();
  const double e_star = std::sqrt(1.0 - (2.0 * K(0, 1) * rod.v * rod.u - K(1, 1) * rod.u * rod.u) /
                                            (K(0, 0) * rod.v * rod.v));
  EXPECT_NEAR(e_star, std::sqrt(0.65), 1e-12);
  // the construction: Newton's stuck impulse at e = 1 is admissible and gains energy; at e* none
  const Eigen::Vector2d p_newton = rod.stuck_impulse(rod.v);
  ASSERT_LT(std::abs(p_newton[1]), mu * p_newton[0]);
  EXPECT_NEAR(rod.stuck_energy_change(rod.v), 0.109375, 1e-12);
  EXPECT_NEAR(rod.stuck_energy_change(e_star * rod.v), 0.0, 1e-12);
  const Eigen::Vector2d p = rod.stuck_impulse(e_star * rod.v);
  ASSERT_LT(std::abs(p[1]), mu * p[0]);
  const Eigen::Vector3d expected = rod.after(p);
  for (double e : {1.0, 0.9, 0.806227}) {
    SCOPED_TRACE("e = " + std::to_string(e));
    const RodRun r = run_rod(rod, rod.model(e, mu));
    ASSERT_GE(r.tr.stats.contact_events.size(), 1u);
    const ContactEvent& hit = r.tr.stats.contact_events[0];
    EXPECT_EQ(hit.kind, ContactEvent::Kind::kImpact);
    EXPECT_NEAR(hit.t, rod.h / rod.v, 1e-12);
    EXPECT_NEAR(hit.speed_before, -rod.v, 1e-12);
    EXPECT_NEAR(hit.speed_after, e_star * rod.v, 1e-9);
    EXPECT_NEAR(hit.impulse, p[0], 1e-9);
    EXPECT_NEAR(hit.energy_change, 0.0, 1e-9);
    EXPECT_LE(hit.energy_change, 1e-12);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(r.after[i], expected[i], 1e-9) << i;
    // the note says the retry happened, with friction, and the fraction of e kept
    bool noted = false;
    for (const auto& note : r.tr.stats.notes) {
      noted =
          noted || note.find(
                       "an impact with restitution and friction would have created "
                       "energy; it was made with " +
                       format_number(e_star / e, 6) + " of its restitution") != std::string::npos;
    }
    EXPECT_TRUE(noted);
    EXPECT_TRUE(r.tr.stats.energy_balance_checked);
  }
  // below e*: Newton's impact itself, no note
  const double e = 0.8;
  const RodRun below = run_rod(rod, rod.model(e, mu));
  ASSERT_GE(below.tr.stats.contact_events.size(), 1u);
  EXPECT_NEAR(below.tr.stats.contact_events[0].speed_after, e * rod.v, 1e-12);
  EXPECT_NEAR(below.tr.stats.contact_events[0].energy_change, rod.stuck_energy_change(e * rod.v),
              1e-12);
  EXPECT_LT(below.tr.stats.contact_events[0].energy_change, -1e-3);
  for (const auto& note : below.tr.stats.notes)
    EXPECT_EQ(note.find("would have created energy"), std::string::npos) << note;
}

// ---- item 2: Poisson's restitution --------------------------------------------------------------

// Without friction the impulse is along n only and g' is linear in it: the compression impulse
// P_c = v/W_nn, Poisson's total (1 + e) P_c gives g'⁺ = e v, Newton's law itself.
TEST(ImpactRestitution, PoissonAndNewtonAgreeWithoutFriction) {
  const Rod rod;
  const double e = 0.5;
  const RodRun newton = run_rod(rod, rod.model(e, 0.0, "newton"));
  const RodRun poisson = run_rod(rod, rod.model(e, 0.0, "poisson"));
  const double p_n = (1 + e) * rod.v / rod.W()(0, 0);  // 0.6
  const Eigen::Vector3d expected = rod.after({p_n, 0.0});
  ASSERT_GE(poisson.tr.stats.contact_events.size(), 1u);
  ASSERT_GE(newton.tr.stats.contact_events.size(), 1u);
  for (const RodRun* r : {&newton, &poisson}) {
    const ContactEvent& hit = r->tr.stats.contact_events[0];
    EXPECT_NEAR(hit.impulse, 0.6, 1e-12);
    EXPECT_NEAR(hit.speed_after, e * rod.v, 1e-12);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(r->after[i], expected[i], 1e-10) << i;
  }
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(poisson.after[i], newton.after[i], 1e-12) << i;
}

// On the rough floor (mu = 2 >= |W_nt|/W_tt = 0.6: A sticks once its slip stops) with u = 0.5:
// * Newton: p = K (−(1 + e) v_n⁻, −v_t⁻) = K (1.5, −0.5) = (0.75, 0.25), g'⁺ = e v = 0.5;
// * Poisson: compression to g' = 0 with A stuck, P_c = [−K v⁻]_n = 0.4375; restitution e P_c
//   with A stuck (the compliance k_s = W_nn − W_nt²/W_tt = det W / W_tt): g'⁺ = k_s e P_c =
//   −e (v_n⁻ − W_nt v_t⁻/W_tt) = 0.35, so Poisson − Newton = e W_nt v_t⁻ / W_tt = −0.15.
// This is Stronge's (Keller's) Poisson impact: integrated along the impulse, A slips until
// p_s = u/(mu W_tt − W_tn) = 0.077 while g' has only reached −0.577, then sticks for the rest.
// Poisson's T⁺ − T⁻ = ½ (k_s e² P_c² − v⁻ᵀ K v⁻) <= ½ (e² − 1) k_s P_c² < 0.
TEST(ImpactRestitution, PoissonDiffersFromNewtonOnARoughFloorByTheAnalyticAmount) {
  const Rod rod;
  const double e = 0.5, mu = 2.0;
  const Eigen::Matrix2d W = rod.W();
  const double P_c = rod.stuck_impulse(0.0)[0];
  const double k_s = W.determinant() / W(1, 1);
  const double vn_newton = e * rod.v, vn_poisson = k_s * e * P_c;
  EXPECT_NEAR(vn_poisson - vn_newton, e * W(0, 1) * rod.u / W(1, 1), 1e-12);
  EXPECT_NEAR(vn_poisson - vn_newton, -0.15, 1e-12);
  const Eigen::Vector2d p_newton = rod.stuck_impulse(vn_newton);
  const Eigen::Vector2d p_poisson = rod.stuck_impulse(vn_poisson);
  EXPECT_NEAR(p_poisson[0], (1 + e) * P_c, 1e-12);
  ASSERT_LT(std::abs(p_newton[1]), mu * p_newton[0]);
  ASSERT_LT(std::abs(p_poisson[1]), mu * p_poisson[0]);

  const RodRun newton = run_rod(rod, rod.model(e, mu, "newton"));
  const RodRun poisson = run_rod(rod, rod.model(e, mu, "poisson"));
  ASSERT_GE(newton.tr.stats.contact_events.size(), 1u);
  ASSERT_GE(poisson.tr.stats.contact_events.size(), 1u);
  const ContactEvent& hn = newton.tr.stats.contact_events[0];
  const ContactEvent& hp = poisson.tr.stats.contact_events[0];
  EXPECT_NEAR(hn.speed_after, 0.5, 1e-12);
  EXPECT_NEAR(hp.speed_after, 0.35, 1e-12);
  EXPECT_NEAR(hp.speed_after - hn.speed_after, -0.15, 1e-12);
  EXPECT_NEAR(hn.impulse, p_newton[0], 1e-12);
  EXPECT_NEAR(hp.impulse, p_poisson[0], 1e-12);
  // energy is never created: each loss against its closed form, < 0
  EXPECT_NEAR(hn.energy_change, rod.stuck_energy_change(vn_newton), 1e-12);
  EXPECT_NEAR(hp.energy_change, rod.stuck_energy_change(vn_poisson), 1e-12);
  EXPECT_NEAR(hp.energy_change, -0.16484375, 1e-12);
  EXPECT_LT(hp.energy_change, -0.1);
  EXPECT_LT(hn.energy_change, -0.1);
  // no retry was needed
  for (const RodRun* r : {&newton, &poisson}) {
    for (const auto& note : r->tr.stats.notes)
      EXPECT_EQ(note.find("would have created energy"), std::string::npos) << note;
    EXPECT_TRUE(r->tr.stats.energy_balance_checked);
  }
  const Eigen::Vector3d en = rod.after(p_newton), ep = rod.after(p_poisson);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(newton.after[i], en[i], 1e-10) << i;
    EXPECT_NEAR(poisson.after[i], ep[i], 1e-10) << i;
  }
}

// ---- errors -----------------------------------------------------------------------------------

TEST(ImpactRestitution, BadLawOrCoefficientGetsAnErrorWithItsPosition) {
  auto error = [](const std::string& text) {
    try {
      parse_model(text, "rod.yaml");
    } catch (const ModelError& e) {
      return e;
    }
    ADD_FAILURE() << "no error";
    return ModelError("", 0, 0, "");
  };
  const std::string base = "coordinates: [x, y]\nmass_matrix: [[1, 0], [0, 1]]\nconstraints:\n";
  const ModelError law =
      error(base + "  - {name: floor, holonomic: y, unilateral: true, restitution_law: posson}\n");
  EXPECT_EQ(law.line(), 4);
  EXPECT_EQ(law.column(), 68);
  EXPECT_NE(std::string(law.what())
                .find("rod.yaml:4:68: error: the restitution_law of constraint "
                      "'floor' must be newton or poisson, got 'posson'"),
            std::string::npos)
      << law.what();
  const ModelError high =
      error(base +
            "  - {name: floor, holonomic: y, unilateral: true, restitution: 1.5,\n"
            "     restitution_law: poisson}\n");
  EXPECT_EQ(high.line(), 4);
  EXPECT_EQ(high.column(), 64);
  EXPECT_NE(std::string(high.what())
                .find("restitution of constraint 'floor' must lie in [0, 1], "
                      "got 1.5"),
            std::string::npos)
      << high.what();
  const ModelError lone =
      error(base + "  - {name: floor, holonomic: y, restitution_law: poisson}\n");
  EXPECT_NE(std::string(lone.what())
                .find("constraint 'floor' gives a restitution_law but is not "
                      "unilateral"),
            std::string::npos)
      << lone.what();
  // in C++
  auto floor = holonomic("floor", 1, [](const auto& q, const auto&, auto& phi) { phi[0] = q[1]; });
  try {
    with_restitution_law(floor, RestitutionLaw::kPoisson);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("constraint 'floor' is not unilateral"), std::string::npos)
        << e.what();
  }
  floor.unilateral(0.5).stabilize(1.0, 2.0);
  EXPECT_EQ(restitution_law(floor), RestitutionLaw::kNewton);
  const Constraint poisson = with_restitution_law(floor, RestitutionLaw::kPoisson);
  EXPECT_EQ(restitution_law(poisson), RestitutionLaw::kPoisson);
  EXPECT_EQ(std::string(to_string(restitution_law(poisson))), "poisson");
  EXPECT_TRUE(poisson.is_unilateral());
  EXPECT_EQ(poisson.restitution(), 0.5);
  EXPECT_EQ(poisson.name(), "floor");
  EXPECT_EQ(poisson.stabilization().beta, 2.0);
  // back to Newton's: the law's wrapper is replaced, not nested
  EXPECT_EQ(restitution_law(with_restitution_law(poisson, RestitutionLaw::kNewton)),
            RestitutionLaw::kNewton);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// ---- impacts on a moving surface
// ------------------------------------------------------------------

// A ball (m = 0.1) dropped from h = 5 cm at rest onto a table moving as y_p = A sin(w t)
// (A = 1 cm, 10 Hz: up to 0.628 m/s). The first impact is at the root t₁ of
// h − ½ g t² = A sin(w t) (found here by bisection), the ball at −g t₁, the table at
// A w cos(w t₁); Newton's law on the relative speed gives the ball y'⁺ = u − e (y'⁻ − u),
// u the table's speed. The table's motion does work: T⁺ > T⁻ although the contact dissipates
// ½ Λ g'⁻ (1 − e) — once taken for energy created and made plastic (the ball stayed on the table).
struct Table {
  double m = 0.1, g = 9.81, e = 0.5, A = 0.01, w = 20 * M_PI, h = 0.05;
  double t1() const {
    double lo = 0.05, hi = 0.11;  // h − ½ g t² − A sin(w t): > 0 at lo, < 0 at hi
    for (int i = 0; i < 200; ++i) {
      const double mid = 0.5 * (lo + hi);
      (h - 0.5 * g * mid * mid - A * std::sin(w * mid) > 0 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }
  double u(double t) const { return A * w * std::cos(w * t); }
};

void expect_table_impact(const Trajectory& tr, Index k, Index ball_rate, std::size_t n,
                         const Table& tb) {
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  for (const auto& note : tr.stats.notes)
    EXPECT_EQ(note.find("made plastic"), std::string::npos) << note;
  ASSERT_GE(tr.stats.contact_events.size(), 1u);
  const ContactEvent& hit = tr.stats.contact_events[0];
  const double t1 = tb.t1(), v = -tb.g * t1, u = tb.u(t1);
  EXPECT_NEAR(t1, 0.100589306, 1e-9);  // the reproducer's figure (/work/u12, 07)
  EXPECT_EQ(hit.constraint, k);
  EXPECT_EQ(hit.kind, ContactEvent::Kind::kImpact);
  EXPECT_NEAR(hit.t, t1, 1e-10);
  EXPECT_NEAR(hit.speed_before, v - u, 1e-8);
  EXPECT_NEAR(hit.speed_after, -tb.e * (v - u), 1e-8);
  const double v_plus = u - tb.e * (v - u);
  EXPECT_NEAR(v_plus, 1.435222, 1e-6);
  EXPECT_NEAR(hit.energy_change, 0.5 * tb.m * (v_plus * v_plus - v * v), 1e-8);
  EXPECT_GT(hit.energy_change, 0.05);  // the table gave the ball energy
  // the ball's velocity just after (the first sample after t₁ is 1 ms later: − g · 1 ms)
  std::size_t i = 0;
  while (tr.t[i] <= t1) ++i;
  EXPECT_NEAR(tr.qd[n * i + std::size_t(ball_rate)], v_plus - tb.g * (tr.t[i] - t1), 1e-7);
}

TEST(ImpactRestitution, BallHitByAVibratingTableLeavesAtNewtonsRelativeSpeed) {
  const Table tb;
  Model m = parse_model(R"(
parameters: {m: 0.1, g: 9.81, e: 0.5, A: 0.01, w: 62.83185307179586, h: 0.05}
coordinates: [y]
kinetic_energy: 0.5*m*y_dot^2
potential_energy: m*g*y
constraints:
  - {name: table, holonomic: y - A*sin(w*t), unilateral: true, restitution: e}
initial:
  q: {y: h}
simulate: {t_end: 0.2, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0.001}
)");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  expect_table_impact(tr, m.system.constraint_index("table"), 0, 1, tb);
}

// The same table as a driven body: a paddle on a prismatic joint with drive A sin(w t), the ball
// a particle with a sphere contact on the paddle's plane (a plane of a moving body, a rheonomic
// bilateral drive: the impulse's work on the drive is the table's).
TEST(ImpactRestitution, BallHitByADrivenPaddleLeavesAtNewtonsRelativeSpeed) {
  const Table tb;
  Model m = parse_model(R"(
parameters: {A: 0.01, w: 62.83185307179586}
bodies:
  - {name: paddle, type: rigid, mass: 1, inertia: 0.01, position: [0, 0, 0],
     velocity: [0, 0, 0.6283185307179586]}
  - {name: ball, type: particle, mass: 0.1, position: [0, 0, 0.07]}
joints:
  - {type: prismatic, name: slide, parent: ground, child: paddle, drive: A*sin(w*t)}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: hit, body: ball, shape: sphere, radius: 0.02, restitution: 0.5,
     plane: {body: paddle, point: [0, 0, 0], normal: [0, 0, 1]}}
simulate: {t_end: 0.2, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0.001}
)");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  // the ball's z rate: coordinate 7 + 2 (the paddle's 7 first)
  expect_table_impact(tr, m.system.constraint_index("hit"), 9, 10, tb);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

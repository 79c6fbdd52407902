// SPDX-License-Identifier: BSD-3-Clause
// A point or sphere inside a sphere on bodies models (issue #31, docs/contact.md, "Contacts on
// bodies": `sphere: {…, inside: true}`, g = (R − r) − |c − o|), each against a closed form or
// the test's own integration of the motion on the circle ρ = R − r: a frictionless particle
// swinging in a fixed bowl (the pendulum θ'' = −(g/ρ) sin θ, its period with the amplitude's
// correction), a disk on the inside of a vertical circle released where N = 0 at
// cos φ = −(v0² − 2 g ρ)/(3 g ρ) and landing again where its parabola meets the circle, a rough
// ball rolling in a bowl (θ'' = −(5 g/(7 ρ)) sin θ, small-oscillation period 2π √(7ρ/(5g))), the
// row's g, A and b against the world points and finite differences, and the errors.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/multibody/multibody.hpp"
#include "ukdyn/simulation/simulate.hpp"

#include "support/contact_runs.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using mb::Vector3d;
constexpr double kG = 9.81;
constexpr double kPi = 3.14159265358979323846;

using testing::events_of;

// The test's own RK4 of θ'' = f(θ) from (θ0, w0) with step h: θ and θ' at t = k h.
struct Pendulum {
  std::function<double(double)> f;
  double h;
  std::vector<double> th, w;
  Pendulum(std::function<double(double)> acc, double th0, double w0, double step, double t_end)
      : f(std::move(acc)), h(step) {
    double x = th0, v = w0;
    const auto n = std::size_t(std::llround(t_end / h));
    th.push_back(x);
    w.push_back(v);
    for (std::size_t i = 0; i < n; ++i) {
      const double k1 = f(x), l1 = v;
      const double k2 = f(x + 0.5 * h * l1), l2 = v + 0.5 * h * k1;
      const double k3 = f(x + 0.5 * h * l2), l3 = v + 0.5 * h * k2;
      const double k4 = f(x + h * l3), l4 = v + h * k3;
      x += h / 6 * (l1 + 2 * l2 + 2 * l3 + l4);
      v += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      th.push_back(x);
      w.push_back(v);
    }
  }
  // θ at time t, a multiple of h
  double at(double t) const { return th[std::size_t(std::llround(t / h))]; }
  // the times θ' changes sign from + to − (the turning points at θ's maxima) by the cubic
  // Hermite interpolant of θ' (values w, slopes f(θ)) between the steps
  std::vector<double> far_turns() const {
    std::vector<double> out;
    for (std::size_t i = 0; i + 1 < w.size(); ++i) {
      if (!(w[i] > 0 && w[i + 1] <= 0)) continue;
      out.push_back(h * double(i) + hermite_root(w[i], w[i + 1], f(th[i]), f(th[i + 1]), h));
    }
    return out;
  }
  // the root in [0, h] of the Hermite cubic with values y0, y1 and slopes s0, s1 (bisection)
  static double hermite_root(double y0, double y1, double s0, double s1, double h) {
    const auto p = [&](double s) {
      const double u = s / h, u2 = u * u, u3 = u2 * u;
      return (2 * u3 - 3 * u2 + 1) * y0 + (u3 - 2 * u2 + u) * h * s0 + (-2 * u3 + 3 * u2) * y1 +
             (u3 - u2) * h * s1;
    };
    double a = 0, b = h;
    for (int k = 0; k < 80; ++k) {
      const double m = 0.5 * (a + b);
      if ((p(m) > 0) == (y0 > 0))
        a = m;
      else
        b = m;
    }
    return 0.5 * (a + b);
  }
};

// The pendulum's period with the amplitude's correction: T = T0 (1 + θ0²/16 + 11 θ0⁴/3072 +
// 173 θ0⁶/737280 + …), T0 = 2π/ω.
double period(double omega, double th0) {
  const double a2 = th0 * th0;
  return 2 * kPi / omega * (1 + a2 / 16 + 11 * a2 * a2 / 3072 + 173 * a2 * a2 * a2 / 737280);
}

// ---- a frictionless particle swings in a fixed bowl ---------------------------------------------

// A particle carrying a sphere of radius r at rest against the inside of a fixed sphere of radius
// R (centre the origin) at θ0 from the bottom. Its centre moves on the circle ρ = R − r:
// θ'' = −(g/ρ) sin θ, with the wall's normal force m (g cos θ + ρ θ'²) > 0 throughout, so the
// contact stays closed (no event) and the particle swings with the pendulum's period.
TEST(ContactSphereInside, ParticleInABowlSwingsWithThePendulumsPeriod) {
  const double R = 0.5, r = 0.05, rho = R - r, th0 = 0.1, m_ = 2.0, t_end = 3.0;
  Model m = parse_model(
      "parameters: {R: 0.5, r: 0.05, th0: 0.1}\n"
      "bodies:\n"
      "  - {name: bead, type: particle, mass: 2, position: [(R - r)*sin(th0), 0, -(R - "
      "r)*cos(th0)]}\n"
      "forces:\n"
      "  - {type: gravity, g: [0, 0, -9.81]}\n"
      "contacts:\n"
      "  - {name: bowl, body: bead, shape: sphere, radius: r, sphere: {body: ground, radius: R, "
      "inside: true}}\n"
      "simulate: {t_end: 3, integrator: dopri5, rtol: 1e-12, atol: 1e-14}\n"
      "output: {every: 0.01}\n");
  const Index k = m.system.constraint_index("bowl");
  const ModelRun run = run_model(m);
  const Trajectory& tr = run.trajectory;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_TRUE(tr.stats.contact_events.empty());
  const Pendulum p([&](double x) { return -kG / rho * std::sin(x); }, th0, 0.0, 1e-4, t_end);
  // the RK4's period against the series (its turns back at θ0: T, 2T)
  const std::vector<double> turns = p.far_turns();
  ASSERT_GE(turns.size(), 2u);
  const double T = period(std::sqrt(kG / rho), th0);
  EXPECT_NEAR(turns[0], T, 1e-9);
  EXPECT_NEAR(turns[1], 2 * T, 1e-9);
  // the run's centre on the circle at the RK4's angle, its normal force m (g cos θ + ρ θ'²)
  const std::size_t nc = std::size_t(m.system.constraint_count());
  ASSERT_EQ(tr.t.size(), 301u);
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    const double* q = &tr.q[3 * i];
    const double th = p.at(tr.t[i]), w = p.w[std::size_t(std::llround(tr.t[i] / p.h))];
    EXPECT_NEAR(q[0], rho * std::sin(th), 1e-8) << "t = " << tr.t[i];
    EXPECT_NEAR(q[1], 0.0, 1e-12) << "t = " << tr.t[i];
    EXPECT_NEAR(q[2], -rho * std::cos(th), 1e-8) << "t = " << tr.t[i];
    EXPECT_NEAR(tr.lambda[nc * i + std::size_t(k)], m_ * (kG * std::cos(th) + rho * w * w), 1e-7)
        << "t = " << tr.t[i];
  }
  // the viewer's contact point: the sphere's point farthest from the bowl's centre, R (sin θ, 0,
  // −cos θ), and the normal towards the centre, (−sin θ, 0, cos θ)
  const auto column = [&](const std::string& name) -> const std::vector<double>& {
    for (const CsvColumn& c : run.extra_columns) {
      if (c.name == name) return c.values;
    }
    throw std::runtime_error("no column " + name);
  };
  for (const std::size_t i : {std::size_t(0), std::size_t(77), tr.t.size() - 1}) {
    const double th = p.at(tr.t[i]);
    EXPECT_NEAR(column("visual.contact.bowl.x")[i], R * std::sin(th), 1e-8) << i;
    EXPECT_NEAR(column("visual.contact.bowl.z")[i], -R * std::cos(th), 1e-8) << i;
    EXPECT_NEAR(column("visual.contact.bowl.nx")[i], -std::sin(th), 1e-8) << i;
    EXPECT_NEAR(column("visual.contact.bowl.nz")[i], std::cos(th), 1e-8) << i;
  }
  EXPECT_NEAR(tr.energy.back(), tr.energy.front(), 1e-9);
}

// ---- the inside of a vertical circle: release and landing ---------------------------------------

// A planar disk (radius r) on the inside of a fixed circle of radius R in a vertical plane,
// started at the bottom with v0² = 3.5 g ρ (ρ = R − r, between 2 g ρ and 5 g ρ). On the circle
// φ'' = −(g/ρ) sin φ and N = m (v0²/ρ − 2 g + 3 g cos φ), which vanishes at
// cos φ* = −(v0² − 2 g ρ)/(3 g ρ) = −1/2: the contact releases there, at the time the test's own
// RK4 gives, with speed √(−g ρ cos φ*) along the tangent; the centre then flies the parabola
// until it meets the circle |p| = ρ again (the landing impact, e = 0.5).
TEST(ContactSphereInside, DiskInsideAVerticalCircleLeavesWhereTheNormalForceVanishes) {
  const double R = 1.0, r = 0.1, rho = R - r, v0 = std::sqrt(3.5 * kG * rho), e = 0.5;
  Model m = parse_model(
      "parameters: {R: 1, r: 0.1, m: 1.5}\n"
      "bodies:\n"
      "  - {name: disk, type: planar, mass: m, inertia: 0.5*m*r^2, position: [0, -(R - r)], "
      "velocity: [sqrt(3.5*9.81*(R - r)), 0]}\n"
      "forces:\n"
      "  - {type: gravity, g: [0, -9.81]}\n"
      "contacts:\n"
      "  - {name: loop, body: disk, shape: sphere, radius: r, sphere: {radius: R, inside: true}, "
      "restitution: 0.5}\n"
      "simulate: {t_end: 1.5, integrator: dopri5, rtol: 1e-12, atol: 1e-14}\n"
      "output: {every: 0}\n");
  const Index k = m.system.constraint_index("loop");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  // the release by the RK4 of φ'' = −(g/ρ) sin φ from (0, v0/ρ): the root of cos φ − cos φ*
  // within the step by the Hermite cubic of cos φ (slope −sin φ φ')
  const double c_star = -(v0 * v0 - 2 * kG * rho) / (3 * kG * rho);
  const Pendulum p([&](double x) { return -kG / rho * std::sin(x); }, 0.0, v0 / rho, 1e-5, 1.0);
  double t_star = -1.0;
  for (std::size_t i = 0; i + 1 < p.th.size(); ++i) {
    const double y0 = std::cos(p.th[i]) - c_star, y1 = std::cos(p.th[i + 1]) - c_star;
    if (y0 > 0 && y1 <= 0) {
      t_star = p.h * double(i) + Pendulum::hermite_root(y0, y1, -std::sin(p.th[i]) * p.w[i],
                                                        -std::sin(p.th[i + 1]) * p.w[i + 1], p.h);
      break;
    }
  }
  ASSERT_GT(t_star, 0.0);
  const auto releases = events_of(tr, k, ContactEvent::Kind::kRelease);
  ASSERT_GE(releases.size(), 1u);
  EXPECT_NEAR(releases[0].t, t_star, 1e-8);
  // the flight from φ* = 120° at speed √(−g ρ cos φ*) along the tangent (cos φ, sin φ), until
  // |p(t)| = ρ (bisection on the parabola, after it has left the wall)
  const double phi = std::acos(c_star), vs = std::sqrt(-kG * rho * c_star);
  const Vector3d ps(rho * std::sin(phi), -rho * std::cos(phi), 0);
  const Vector3d vs3(vs * std::cos(phi), vs * std::sin(phi), 0);
  const auto at = [&](double s) {
    return Vector3d(ps + vs3 * s - 0.5 * kG * s * s * Vector3d::UnitY());
  };
  double lo = 0.05, hi = 2.0;  // |p| < ρ at lo (inside), > ρ at hi (the parabola leaves)
  ASSERT_LT(at(lo).norm(), rho);
  ASSERT_GT(at(hi).norm(), rho);
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (at(mid).norm() < rho ? lo : hi) = mid;
  }
  const double s_land = 0.5 * (lo + hi);
  const auto impacts = events_of(tr, k, ContactEvent::Kind::kImpact);
  ASSERT_GE(impacts.size(), 1u);
  EXPECT_NEAR(impacts[0].t, t_star + s_land, 1e-7);
  // the speed along the normal at the landing: g' = −u·v, u = p/|p| (the gap closes, < 0)
  const Vector3d v_land = vs3 - kG * s_land * Vector3d::UnitY();
  const double vn = -at(s_land).normalized().dot(v_land);
  EXPECT_NEAR(impacts[0].speed_before, vn, 1e-6);
  EXPECT_NEAR(impacts[0].speed_after, -e * vn, 1e-6);
  // the normal force at the start, m (v0²/ρ + g), and the balance of the energy
  EXPECT_NEAR(tr.lambda[std::size_t(k)], 1.5 * (v0 * v0 / rho + kG), 1e-8);
  EXPECT_NEAR(tr.energy.back() - tr.energy.front(), tr.work_impact.back(), 1e-8);
}

// ---- a rough ball rolls in a bowl ---------------------------------------------------------------

// A rigid ball (radius r, I = 2/5 m r²) put at rest against the inside of a fixed rough sphere
// of radius R at θ0 from the bottom: friction holds its contact point (μ = 1 > the holding
// force's (2/7) tan θ0), so it rolls: (7/5) ρ θ'' = −g sin θ, ρ = R − r, whose small-oscillation
// period is 2π √(7ρ/(5g)) (corrected for the amplitude by the series and by the test's RK4).
TEST(ContactSphereInside, RoughBallRollsInABowlWithSevenFifthsOfThePendulumsInertia) {
  const double R = 0.5, r = 0.1, rho = R - r, th0 = 0.1, t_end = 4.0;
  Model m = parse_model(
      "parameters: {m: 1, R: 0.5, r: 0.1, th0: 0.1}\n"
      "bodies:\n"
      "  - {name: ball, type: rigid, mass: m, inertia: [0.4*m*r^2, 0.4*m*r^2, 0.4*m*r^2], "
      "position: [(R - r)*sin(th0), 0, -(R - r)*cos(th0)]}\n"
      "forces:\n"
      "  - {type: gravity, g: [0, 0, -9.81]}\n"
      "contacts:\n"
      "  - {name: bowl, body: ball, shape: sphere, radius: r, sphere: {body: ground, radius: R, "
      "inside: true}}\n"
      "nonideal:\n"
      "  - {friction: coulomb, constraint: bowl, mu: 1}\n"
      "simulate: {t_end: 4, integrator: dopri5, rtol: 1e-12, atol: 1e-14}\n"
      "output: {every: 0.01}\n");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double omega = std::sqrt(5 * kG / (7 * rho));
  const Pendulum p([&](double x) { return -omega * omega * std::sin(x); }, th0, 0.0, 1e-4, t_end);
  const std::vector<double> turns = p.far_turns();
  ASSERT_GE(turns.size(), 2u);
  const double T = period(omega, th0);
  EXPECT_NEAR(T, 2 * kPi * std::sqrt(7 * rho / (5 * kG)) * (1 + th0 * th0 / 16), 1e-5 * T);
  for (std::size_t i = 0; i < 2; ++i) EXPECT_NEAR(turns[i], double(i + 1) * T, 1e-9 * T);
  // the run's centre at the RK4's angle, to 1e-9 of the amplitude (1.5e-13 rad seen), over 2.7
  // periods
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    const double* q = &tr.q[7 * i];
    EXPECT_NEAR(std::atan2(q[0], -q[2]), p.at(tr.t[i]), 1e-9 * th0) << "t = " << tr.t[i];
    EXPECT_NEAR(std::hypot(q[0], q[2]), rho, 1e-9) << "t = " << tr.t[i];
  }
  // it rolls: no slip event, and the energy stays
  for (const ContactEvent& ev : tr.stats.contact_events)
    ADD_FAILURE() << "event at t = " << ev.t << " on constraint " << ev.constraint;
  EXPECT_NEAR(tr.energy.back(), tr.energy.front(), 1e-9);
}

// ---- the row against the world points and finite differences ------------------------------------

// Two turning rigid bodies, a sphere of radius 0.1 inside one of radius 2 whose centres are off
// the centres of mass: g = (R − r) − |c − o| against the world points, g' = −u·(c' − o'), and A
// and b against differences along the motion.
TEST(ContactSphereInside, GapRowMatchesItsFormulaAndFiniteDifferences) {
  mb::Multibody b;
  const mb::BodyId p =
      b.add_rigid_body("p", 2.0, Vector3d(0.1, 0.2, 0.3), Vector3d(0.1, 0.2, -0.3),
                       Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Vector3d(1, 2, 3).normalized())),
                       Vector3d(0.3, -0.2, 0.1), Vector3d(1.0, 0.5, -2.0));
  const mb::BodyId c =
      b.add_rigid_body("c", 1.0, Vector3d(0.2, 0.1, 0.3), Vector3d(0.6, -0.4, 0.5),
                       Eigen::Quaterniond(Eigen::AngleAxisd(-0.7, Vector3d(-1, 0, 2).normalized())),
                       Vector3d(-0.4, 0.6, 0.2), Vector3d(-1.5, 2.0, 0.7));
  const Vector3d po(0.2, -0.1, 0.05), pc(-0.1, 0.3, 0.2);
  b.add_joint(mb::contact_spheres("pc", p, po, 2.0, c, pc, 0.1, 0.5, mb::SphereSide::kInside));
  const mb::MultibodyModel model = b.build();
  const System& sys = model.system;
  const Index k = sys.constraint_index("pc");
  const VectorXd& q = model.q0;
  const VectorXd& qd = model.qd0;
  const Vector3d cw = mb::world_point(model, q, c, pc), ow = mb::world_point(model, q, p, po);
  ASSERT_LT((cw - ow).norm(), 1.9);
  EXPECT_NEAR(testing::gap_of(sys, k, q, qd)[0], 1.9 - (cw - ow).norm(), 1e-14);
  const double h = 1e-6;
  const VectorXd qp = q + h * qd, qm = q - h * qd;
  const Vector3d dv = (mb::world_point(model, qp, c, pc) - mb::world_point(model, qp, p, po) -
                       mb::world_point(model, qm, c, pc) + mb::world_point(model, qm, p, po)) /
                      (2 * h);
  EXPECT_NEAR(testing::gap_of(sys, k, q, qd)[1], -(cw - ow).normalized().dot(dv), 1e-8);
  testing::check_form_by_differences(sys, k, q, qd, {3, 10}, 1e-8, 1e-5);
}

// ---- errors -------------------------------------------------------------------------------------

TEST(ContactSphereInside, BadInsideContactsGetAClearErrorWithItsPlace) {
  const auto expect = [](const std::string& contact, const std::string& where,
                         const std::string& what) {
    testing::expect_model_error(
        "bodies:\n"
        "  - {name: a, type: particle, mass: 1, position: [0, 0, -0.5]}\n"
        "contacts:\n"
        "  - " +
            contact + "\n",
        where, what);
  };
  expect("{name: c, body: a, shape: sphere, radius: 1, sphere: {radius: 1, inside: true}}", "4:67",
         "contact 'c': a sphere of radius 1 does not fit inside a sphere of radius 1");
  expect("{name: c, body: a, shape: sphere, radius: 0.1, sphere: {radius: 1, inside: yes}}", "4:80",
         "contact 'c' sphere: inside must be true or false");
  expect("{name: c, body: a, shape: sphere, radius: 0.1, sphere: {radius: 1, inside: \"true\"}}",
         "4:80", "contact 'c' sphere: inside must be true or false");
  expect(
      "{name: c, body: a, shape: sphere, radius: 0.1, sphere: {point: [0, 0, 2], radius: 1, "
      "inside: true}}",
      "4:5", "contact 'c': the inner sphere's centre starts outside the other sphere");
  expect(
      "{name: c, body: a, shape: sphere, radius: 0.1, sphere: {point: [0, 0, -0.5], radius: 1, "
      "inside: true}}",
      "4:5", "contact 'c': the spheres' centres coincide at the start");
  // inside: false is the default, a sphere outside the other
  {
    const Model m = parse_model(
        "bodies:\n"
        "  - {name: a, type: particle, mass: 1, position: [0, 0, 2]}\n"
        "contacts:\n"
        "  - {name: c, body: a, shape: sphere, radius: 0.1, sphere: {radius: 1, inside: false}}\n");
    EXPECT_NEAR(testing::gap_of(m.system, 0, m.q0, m.qd0)[0], 0.9, 1e-15);
  }
  // a bowl of R = 1e12 around a particle 0.3 from its centre: the normal is resolved (the
  // centres' test is relative to their positions, not to the radii), the particle falls freely
  // (u17 06: it was refused as "centres coincide")
  {
    Model m = parse_model(
        "bodies:\n"
        "  - {name: a, type: particle, mass: 1, position: [0.1, 0, -0.3]}\n"
        "forces:\n"
        "  - {type: gravity, g: [0, 0, -9.81]}\n"
        "contacts:\n"
        "  - {name: c, body: a, shape: sphere, radius: 0.1, sphere: {radius: 1e12, inside: "
        "true}}\n"
        "simulate: {t_end: 0.1}\n");
    const ModelRun run = run_model(m);
    const Trajectory& tr = run.trajectory;
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    EXPECT_TRUE(tr.stats.contact_events.empty());
    EXPECT_NEAR(tr.q[tr.q.size() - 1], -0.3 - 0.5 * kG * 0.01, 1e-9);
    EXPECT_NEAR(tr.q[tr.q.size() - 3], 0.1, 1e-12);
  }
  // a centre between R − r and R penetrates the wall: the run's inconsistent initial state
  testing::expect_penetrated(
      "bodies:\n"
      "  - {name: a, type: particle, mass: 1, position: [0, 0, -0.95]}\n"
      "contacts:\n"
      "  - {name: c, body: a, shape: sphere, radius: 0.1, sphere: {radius: 1, inside: true}}\n"
      "simulate: {t_end: 0.1}\n",
      "the unilateral constraint 'c' is penetrated: its gap is -0.05");
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

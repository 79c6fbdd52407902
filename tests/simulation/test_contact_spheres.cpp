// SPDX-License-Identifier: BSD-3-Clause
// Contacts of two spheres on bodies models (issue #31, docs/contact.md, "Contacts on bodies":
// `sphere:` in place of `plane:`), each against a closed form or an independent computation:
// a head-on and an oblique collision of two rigid spheres (momentum and Newton's restitution
// along the line of centres), the same in a planar model (circles), a particle sliding off a
// fixed sphere (it leaves at cos θ = (2/3) cos θ₀, its release time against the test's own
// integration of the pendulum equation), Newton's cradle of three and of five rigid spheres,
// the gap row's A and b against finite differences, and the errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

using testing::events_of;

// the column `name` of a model run (gap.<contact>, …)
const CsvColumn& column(const ModelRun& run, const std::string& name) {
  const auto& cols = run.extra_columns;
  const auto it =
      std::find_if(cols.begin(), cols.end(), [&](const CsvColumn& c) { return c.name == name; });
  if (it == cols.end()) throw std::runtime_error("no column " + name);
  return *it;
}

// ---- two rigid spheres collide ----------------------------------------------------------------

// Sphere a (m1, r1) at c_a0 moving at v along x meets sphere b (m2, r2) at rest at the origin,
// no gravity. They touch when |c_a0 + v t| = r1 + r2; the normal is the line of centres
// n = (c_a − c_b)/|c_a − c_b|, and Newton's law with the impulse P n on a (−P n on b) gives
//   P = −(1 + e) μ v_n,  μ = m1 m2 / (m1 + m2),  v_n = v·n (< 0, approaching),
// v_a⁺ = v + (P/m1) n, v_b⁺ = −(P/m2) n, T⁺ − T⁻ = −½ μ (1 − e²) v_n². The centres lie on the
// line of action: no spin.
std::string two_spheres(const std::string& ya, const std::string& za, double e) {
  return "parameters: {m1: 1, m2: 3, r1: 0.1, r2: 0.2, e: " + std::to_string(e) +
         "}\n"
         "bodies:\n"
         "  - {name: a, type: rigid, mass: m1, inertia: [0.4*m1*r1^2, 0.4*m1*r1^2, "
         "0.4*m1*r1^2], position: [-1, " +
         ya + ", " + za +
         "], velocity: [2, 0, 0]}\n"
         "  - {name: b, type: rigid, mass: m2, inertia: [0.4*m2*r2^2, 0.4*m2*r2^2, "
         "0.4*m2*r2^2], position: [0, 0, 0]}\n"
         "contacts:\n"
         "  - {name: ab, body: a, shape: sphere, radius: r1, sphere: {body: b, radius: r2}, "
         "restitution: e}\n"
         "simulate: {t_end: 1, integrator: dopri5, rtol: 1e-11, atol: 1e-13}\n"
         "output: {every: 0}\n";
}

void expect_collision(const Model& m, const Trajectory& tr, const Vector3d& ca0, double e,
                      int dims) {
  const double m1 = 1, m2 = 3, R = 0.3, mu = m1 * m2 / (m1 + m2);
  const Vector3d v(2, 0, 0);
  // contact: (x0 + 2 t)² + y² + z² = R², x0 + 2 t < 0
  const double lateral = ca0.y() * ca0.y() + ca0.z() * ca0.z();
  const double x_hit = -std::sqrt(R * R - lateral);
  const double t_hit = (x_hit - ca0.x()) / v.x();
  const Vector3d n = Vector3d(x_hit, ca0.y(), ca0.z()) / R;
  const double vn = v.dot(n);
  const double P = -(1 + e) * mu * vn;
  const Vector3d va = v + (P / m1) * n, vb = -(P / m2) * n;
  const Index k = m.system.constraint_index("ab");
  const auto impacts = events_of(tr, k, ContactEvent::Kind::kImpact);
  ASSERT_EQ(impacts.size(), 1u);
  EXPECT_NEAR(impacts[0].t, t_hit, 1e-10);
  EXPECT_NEAR(impacts[0].speed_before, vn, 1e-10);
  EXPECT_NEAR(impacts[0].speed_after, -e * vn, 1e-10);
  EXPECT_NEAR(impacts[0].impulse, P, 1e-10);
  EXPECT_NEAR(impacts[0].energy_change, -0.5 * mu * (1 - e * e) * vn * vn, 1e-10);
  // the velocities after: a's and b's translation, no rotation
  const std::size_t nq = std::size_t(m.system.coordinate_count()), last = tr.t.size() - 1;
  const std::size_t per = nq / 2;  // a's coordinates, then b's
  for (int i = 0; i < dims; ++i) {
    EXPECT_NEAR(tr.qd[nq * last + std::size_t(i)], va[i], 1e-10) << "a, axis " << i;
    EXPECT_NEAR(tr.qd[nq * last + per + std::size_t(i)], vb[i], 1e-10) << "b, axis " << i;
  }
  for (std::size_t i = std::size_t(dims); i < per; ++i) {
    EXPECT_NEAR(tr.qd[nq * last + i], 0.0, 1e-10) << "a's rotation rate " << i;
    EXPECT_NEAR(tr.qd[nq * last + per + i], 0.0, 1e-10) << "b's rotation rate " << i;
  }
  EXPECT_NEAR(tr.work_impact.back(), impacts[0].energy_change, 1e-12);
  EXPECT_NEAR(tr.energy.back() - tr.energy.front(), tr.work_impact.back(), 1e-9);
}

TEST(ContactSpheres, HeadOnCollisionMeetsMomentumAndRestitution) {
  const double e = 0.6;
  Model m = parse_model(two_spheres("0", "0", e));
  const Index k = m.system.constraint_index("ab");
  EXPECT_TRUE(m.system.constraint(k).is_unilateral());
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  // closed form: t = 0.35, v_a⁺ = (m1 − e m2)/(m1 + m2) v = −0.4, v_b⁺ = (1 + e) m1/(m1 + m2) v
  expect_collision(m, tr, Vector3d(-1, 0, 0), e, 3);
  const std::size_t last = tr.t.size() - 1;
  EXPECT_NEAR(tr.qd[14 * last], -0.4, 1e-10);
  EXPECT_NEAR(tr.qd[14 * last + 7], 0.8, 1e-10);
  // gap.ab = |c_a − c_b| − (r1 + r2) at every sample
  const ModelRun run = run_model(m);
  const CsvColumn& gap = column(run, "gap.ab");
  ASSERT_EQ(gap.values.size(), run.trajectory.t.size());
  for (std::size_t i = 0; i < run.trajectory.t.size(); ++i) {
    const double* q = &run.trajectory.q[14 * i];
    const Vector3d d = Vector3d(q[0], q[1], q[2]) - Vector3d(q[7], q[8], q[9]);
    EXPECT_NEAR(gap.values[i], d.norm() - 0.3, 1e-12) << "sample " << i;
  }
}

// A cue ball (r = 0.05) at 1 m/s toward an equal ball X away, no gravity, e = 1: they meet at
// t = (X − 2r)/v0 and exchange their velocities. Free flight is so smooth that one step spans
// the whole overlap for X = 2 or 10 (9 steps to t = 20): the gap dips below 0 and back within
// a step, which the run finds at the gap's minimum (its rate turning from falling to rising),
// not only at the steps' ends (a new user's reproducer: the balls passed through each other).
TEST(ContactSpheres, BallsInFreeFlightDoNotPassThroughEachOtherWithinAStep) {
  for (const double X : {0.5, 2.0, 10.0}) {
    Model m = parse_model(R"(
parameters: {X: )" + std::to_string(X) +
                          R"(, m: 0.17, r: 0.05, v0: 1}
bodies:
  - {name: cue, type: rigid, mass: m, inertia: 0.4*m*r^2, position: [0, 0, 0], velocity: [v0, 0, 0]}
  - {name: obj, type: rigid, mass: m, inertia: 0.4*m*r^2, position: [X, 0, 0]}
contacts:
  - {name: hit, body: cue, shape: sphere, radius: r, sphere: {body: obj, radius: r}, restitution: 1}
simulate: {t_end: 20, rtol: 1e-10, atol: 1e-12}
output: {every: 0.01}
)");
    const ModelRun run = run_model(m);
    const Trajectory& tr = run.trajectory;
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    const auto impacts =
        events_of(tr, m.system.constraint_index("hit"), ContactEvent::Kind::kImpact);
    ASSERT_EQ(impacts.size(), 1u) << "X = " << X;
    EXPECT_NEAR(impacts[0].t, X - 0.1, 1e-9) << "X = " << X;
    const std::size_t last = tr.t.size() - 1;
    EXPECT_NEAR(tr.qd[14 * last], 0.0, 1e-10) << "X = " << X;      // the cue stops
    EXPECT_NEAR(tr.qd[14 * last + 7], 1.0, 1e-10) << "X = " << X;  // the other goes on
    const CsvColumn& gap = column(run, "gap.hit");
    EXPECT_GE(*std::min_element(gap.values.begin(), gap.values.end()), -1e-9) << "X = " << X;
  }
}

TEST(ContactSpheres, ObliqueCollisionTurnsOnlyTheVelocityAlongTheLineOfCentres) {
  const double e = 0.8;
  Model m = parse_model(two_spheres("0.15", "0.1", e));
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  expect_collision(m, tr, Vector3d(-1, 0.15, 0.1), e, 3);
}

// The same collision of circles in a planar model: (x, y, θ) per body.
TEST(ContactSpheres, PlanarCirclesCollideAsTheSpheresDo) {
  const double e = 0.8;
  const std::string text =
      "parameters: {m1: 1, m2: 3, r1: 0.1, r2: 0.2, e: 0.8}\n"
      "bodies:\n"
      "  - {name: a, type: planar, mass: m1, inertia: 0.5*m1*r1^2, position: [-1, 0.15], "
      "velocity: [2, 0]}\n"
      "  - {name: b, type: planar, mass: m2, inertia: 0.5*m2*r2^2, position: [0, 0]}\n"
      "contacts:\n"
      "  - {name: ab, body: a, shape: sphere, radius: r1, sphere: {body: b, radius: r2}, "
      "restitution: e}\n"
      "simulate: {t_end: 1, integrator: dopri5, rtol: 1e-11, atol: 1e-13}\n"
      "output: {every: 0}\n";
  Model m = parse_model(text);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  expect_collision(m, tr, Vector3d(-1, 0.15, 0), e, 2);
}

// ---- a particle slides off a fixed sphere -------------------------------------------------------

// A particle carrying a sphere of radius r starts at rest on a fixed frictionless sphere of
// radius R at the angle θ₀ from the top. Its centre moves on the circle of radius ρ = R + r,
// θ'' = (g/ρ) sin θ, and the normal force m (g cos θ − ρ θ'²) = m g (3 cos θ − 2 cos θ₀) vanishes
// at cos θ* = (2/3) cos θ₀: the contact releases there, at the time the test's own RK4 of the
// pendulum equation gives, with speed √(g ρ cos θ*) along the tangent; then free flight.
TEST(ContactSpheres, ParticleSlidingOffAFixedSphereLeavesAtTwoThirdsOfTheStartsCosine) {
  const double R = 1.0, r = 0.05, rho = R + r, th0 = 0.3, m_ = 2.0, t_end = 1.5;
  const std::string text =
      "parameters: {R: 1, r: 0.05, th0: 0.3}\n"
      "bodies:\n"
      "  - {name: bead, type: particle, mass: 2, position: [(R + r)*sin(th0), 0, (R + "
      "r)*cos(th0)]}\n"
      "forces:\n"
      "  - {type: gravity, g: [0, 0, -9.81]}\n"
      "contacts:\n"
      "  - {name: dome, body: bead, shape: sphere, radius: r, sphere: {body: ground, point: [0, "
      "0, 0], radius: R}}\n"
      "simulate: {t_end: 1.5, integrator: dopri5, rtol: 1e-12, atol: 1e-14}\n"
      "output: {every: 0}\n";
  Model m = parse_model(text);
  const Index k = m.system.constraint_index("dome");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto releases = events_of(tr, k, ContactEvent::Kind::kRelease);
  ASSERT_EQ(releases.size(), 1u);
  EXPECT_TRUE(events_of(tr, k, ContactEvent::Kind::kImpact).empty());
  // the release angle and time by the test's own RK4 of θ'' = (g/ρ) sin θ (step 1e-5 s), the
  // crossing of 3 cos θ − 2 cos θ₀ = 0 interpolated linearly within the step
  const double c_star = 2.0 / 3.0 * std::cos(th0);
  const double t_star = testing::pendulum_time_to_cos(kG / rho, th0, c_star, 2.0, 1e-5);
  ASSERT_GT(t_star, 0.0);
  EXPECT_NEAR(releases[0].t, t_star, 1e-8);
  // after the release: free flight from the release point with the release velocity
  const double th_s = std::acos(c_star), v_s = std::sqrt(kG * rho * c_star);
  const Vector3d p_s = rho * Vector3d(std::sin(th_s), 0, std::cos(th_s));
  const Vector3d v_s3 = v_s * Vector3d(std::cos(th_s), 0, -std::sin(th_s));
  const double dt = t_end - releases[0].t;
  const Vector3d p_end = p_s + v_s3 * dt - 0.5 * kG * dt * dt * Vector3d::UnitZ();
  const std::size_t last = tr.t.size() - 1;
  ASSERT_NEAR(tr.t[last], t_end, 1e-12);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(tr.q[3 * last + std::size_t(i)], p_end[i], 1e-7);
  // before the release the dome carries m g (3 cos θ − 2 cos θ₀) along the normal: at the start
  // m g cos θ₀
  const std::size_t nc = std::size_t(m.system.constraint_count());
  EXPECT_NEAR(tr.lambda[std::size_t(k)], m_ * kG * std::cos(th0), 1e-9);
  EXPECT_NEAR(tr.lambda[nc * last + std::size_t(k)], 0.0, 1e-12);
  EXPECT_NEAR(tr.energy.back(), tr.energy.front(), 1e-8);
}

// ---- Newton's cradle of rigid spheres -----------------------------------------------------------

// n equal rigid spheres (radius r) in a row, 1 mm apart, no gravity; the first moves at 1 m/s,
// e = 1: n − 1 impacts in turn, each passing the whole velocity on, and the last sphere leaves
// alone at 1 m/s, the others at rest.
void expect_cradle(int n) {
  std::string text = "parameters: {r: 0.05}\nbodies:\n";
  for (int b = 0; b < n; ++b) {
    text += "  - {name: s" + std::to_string(b) +
            ", type: rigid, mass: 0.2, inertia: [0.4*0.2*r^2, 0.4*0.2*r^2, 0.4*0.2*r^2], "
            "position: [" +
            std::to_string(b) + "*(2*r + 0.001), 0, 0]" + (b == 0 ? ", velocity: [1, 0, 0]" : "") +
            "}\n";
  }
  text += "contacts:\n";
  for (int b = 1; b < n; ++b) {
    text += "  - {name: c" + std::to_string(b) + ", body: s" + std::to_string(b) +
            ", shape: sphere, radius: r, sphere: {body: s" + std::to_string(b - 1) +
            ", radius: r}, restitution: 1}\n";
  }
  text +=
      "simulate: {t_end: 0.05, integrator: dopri5, rtol: 1e-11, atol: 1e-13}\noutput: {every: "
      "0}\n";
  const Model m = parse_model(text);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.stats.contact_events.size(), std::size_t(n - 1));
  for (int b = 1; b < n; ++b) {
    const ContactEvent& ev = tr.stats.contact_events[std::size_t(b - 1)];
    EXPECT_EQ(ev.constraint, m.system.constraint_index("c" + std::to_string(b)));
    // each gap of 1 mm closes at 1 m/s: the b-th impact at b ms
    EXPECT_NEAR(ev.t, 1e-3 * b, 1e-12) << "impact " << b;
    EXPECT_NEAR(ev.speed_before, -1.0, 1e-12) << "impact " << b;
    EXPECT_NEAR(ev.speed_after, 1.0, 1e-12) << "impact " << b;
  }
  const std::size_t last = tr.t.size() - 1, nq = 7 * std::size_t(n);
  for (int b = 0; b < n; ++b)
    EXPECT_NEAR(tr.qd[nq * last + 7 * std::size_t(b)], b == n - 1 ? 1.0 : 0.0, 1e-12)
        << "sphere " << b;
  EXPECT_NEAR(tr.work_impact.back(), 0.0, 1e-12);
}

TEST(ContactSpheres, NewtonsCradleOfThreeRigidSpheresSendsTheLastOneOff) { expect_cradle(3); }
TEST(ContactSpheres, NewtonsCradleOfFiveRigidSpheresSendsTheLastOneOff) { expect_cradle(5); }

// ---- the gap row against finite differences -----------------------------------------------------

// Two turning rigid bodies whose spheres' centres are off their centres of mass: g = |c − o| −
// (r1 + r2) against the world points, and A and b against differences of g along the motion.
TEST(ContactSpheres, GapRowMatchesItsFormulaAndFiniteDifferences) {
  mb::Multibody b;
  const mb::BodyId p =
      b.add_rigid_body("p", 2.0, Vector3d(0.1, 0.2, 0.3), Vector3d(0.1, 0.2, -0.3),
                       Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Vector3d(1, 2, 3).normalized())),
                       Vector3d(0.3, -0.2, 0.1), Vector3d(1.0, 0.5, -2.0));
  const mb::BodyId c =
      b.add_rigid_body("c", 1.0, Vector3d(0.2, 0.1, 0.3), Vector3d(1.1, -0.4, 0.5),
                       Eigen::Quaterniond(Eigen::AngleAxisd(-0.7, Vector3d(-1, 0, 2).normalized())),
                       Vector3d(-0.4, 0.6, 0.2), Vector3d(-1.5, 2.0, 0.7));
  const Vector3d po(0.2, -0.1, 0.05), pc(-0.1, 0.3, 0.2);
  b.add_joint(mb::contact_spheres("pc", p, po, 0.2, c, pc, 0.1, 0.5));
  const mb::MultibodyModel model = b.build();
  const System& sys = model.system;
  const Index k = sys.constraint_index("pc");
  const VectorXd& q = model.q0;
  const VectorXd& qd = model.qd0;
  const Vector3d cw = mb::world_point(model, q, c, pc), ow = mb::world_point(model, q, p, po);
  EXPECT_NEAR(testing::gap_of(sys, k, q, qd)[0], (cw - ow).norm() - 0.3, 1e-14);
  // g' = u·(v_c − v_o) by a central difference of the world points along q + s q'
  const double h = 1e-6;
  const VectorXd qp = q + h * qd, qm = q - h * qd;
  const Vector3d dv = (mb::world_point(model, qp, c, pc) - mb::world_point(model, qp, p, po) -
                       mb::world_point(model, qm, c, pc) + mb::world_point(model, qm, p, po)) /
                      (2 * h);
  EXPECT_NEAR(testing::gap_of(sys, k, q, qd)[1], (cw - ow).normalized().dot(dv), 1e-8);
  testing::check_form_by_differences(sys, k, q, qd, {3, 10}, 1e-8, 1e-5);
  // coincident centres have no normal: refused at the build, naming the contact
  mb::Multibody same;
  const mb::BodyId s1 = same.add_particle("s1", 1.0, Vector3d(0, 0, 1));
  const mb::BodyId s2 = same.add_particle("s2", 1.0, Vector3d(0, 0, 1));
  same.add_joint(
      mb::contact_spheres("touch", s1, Vector3d::Zero(), 0.1, s2, Vector3d::Zero(), 0.1));
  try {
    (void)same.build();
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("contact 'touch': the spheres' centres coincide"),
              std::string::npos)
        << e.what();
  }
}

// ---- errors -------------------------------------------------------------------------------------

TEST(ContactSpheres, BadSphereContactsGetAClearErrorWithItsPlace) {
  const auto expect = [](const std::string& contact, const std::string& where,
                         const std::string& what) {
    testing::expect_model_error(
        "bodies:\n"
        "  - {name: a, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 1]}\n"
        "  - {name: b, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 3]}\n"
        "contacts:\n"
        "  - " +
            contact + "\n",
        where, what);
  };
  expect(
      "{name: c, body: a, shape: sphere, radius: 0.1, sphere: {body: b, radius: 0.1}, plane: {}}",
      "5:60", "contact 'c': a contact is with a plane or with a sphere, not both");
  expect("{name: c, body: a, shape: box, size: [0.1, 0.1, 0.1], sphere: {body: b, radius: 0.1}}",
         "5:67", "contact 'c': a box against a sphere is not supported");
  expect("{name: c, body: a, shape: sphere, radius: 0.1, sphere: {body: a, radius: 0.1}}", "5:67",
         "contact 'c' sphere: the sphere is on the contact's own body");
  expect("{name: c, body: a, shape: sphere, radius: 0.1, sphere: {body: b}}", "5:60",
         "contact 'c' sphere needs 'radius'");
  expect("{name: c, body: a, shape: sphere, radius: 0.1, sphere: {body: b, radius: -1}}", "5:78",
         "contact 'c' sphere radius must be > 0");
  expect(
      "{name: c, body: a, shape: sphere, radius: 0.1, sphere: {body: b, radius: 1, normal: [0, "
      "0, 1]}}",
      "5:81", "unknown key 'normal' in contact 'c' sphere");
  expect("{name: c, body: a, shape: sphere, radius: 0.1, sphere: {body: nobody, radius: 1}}",
         "5:67", "unknown body 'nobody'");
  expect("{name: c, body: a, shape: sphere, radius: 0.1, sphere: [b, 1]}", "5:60",
         "contact 'c' sphere must be a mapping");
  // friction between two spheres: taken (its stick rows on both bodies' 14 coordinates;
  // tests/simulation/test_contact_bodies_friction.cpp checks it)
  {
    const Model m = parse_model(
        "bodies:\n"
        "  - {name: a, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 1]}\n"
        "  - {name: b, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 3]}\n"
        "contacts:\n"
        "  - {name: c, body: a, shape: sphere, radius: 0.1, sphere: {body: b, radius: 0.1}}\n"
        "nonideal:\n"
        "  - {friction: coulomb, constraint: c, mu: 0.3}\n");
    const Constraint& stick = m.system.constraint(m.system.constraint_index("stick.coulomb.c"));
    EXPECT_EQ(stick.rows(), 2);
    EXPECT_EQ(stick.model().columns().size(), 14u);
  }
  // the spheres overlap at the start: the run's inconsistent initial state names the contact
  testing::expect_penetrated(
      "bodies:\n"
      "  - {name: a, type: particle, mass: 1, position: [0, 0, 0]}\n"
      "  - {name: b, type: particle, mass: 1, position: [0, 0, 0.15]}\n"
      "contacts:\n"
      "  - {name: c, body: b, shape: sphere, radius: 0.1, sphere: {body: a, radius: 0.1}}\n"
      "simulate: {t_end: 0.1}\n",
      "the unilateral constraint 'c' is penetrated: its gap is -0.05");
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

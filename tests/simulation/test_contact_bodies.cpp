// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts on bodies models (issue #31, docs/contact.md, "Contacts on bodies"), each
// against a closed form or an independent computation: a rigid sphere dropped on the ground
// (impact times, apex heights e^(2k) (h0 − r) + r, rest), a planar rod falling flat on two
// corner contacts (a simultaneous impact), Newton's cradle of three particles with sphere
// contacts, a tilted disk (its gap row's A and b against finite differences, its impact against
// the impulse's closed form), a contact on a plane fixed on a moving body (g against the
// formula), and the errors of the contacts: section.
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

using testing::check_form_by_differences;
using testing::events_of;
using testing::gap_of;
using testing::sample_at;

// the energy balance of a run holds, and its impacts' work is the sum of their T⁺ − T⁻
void expect_energy_balance(const Trajectory& tr, double tol) {
  EXPECT_TRUE(tr.stats.energy_balance_checked);
  ASSERT_EQ(tr.work_impact.size(), tr.t.size());
  double sum = 0.0;
  for (const auto& e : tr.stats.contact_events) sum += e.energy_change;
  EXPECT_NEAR(tr.work_impact.back(), sum, tol);
  EXPECT_NEAR(tr.energy.back() - tr.energy.front(), tr.work_impact.back(), tol);
}

// ---- a rigid sphere dropped on the ground -----------------------------------------------------

// A sphere of radius r, centre at h0, falls on the ground z = 0: its gap is z − r, so the closed
// forms of the generalized bouncing ball hold with the drop H = h0 − r: the k-th impact at
// t_k = t0 + (2 v0 / g) Σ_{j=1..k} e^j (t0 = √(2 H / g), v0 = g t0), the centre's apexes
// e^(2k) H + r, the rest at t∞ = t0 (1 + e) / (1 − e), then the ground carries m g.
constexpr const char* kSphere = R"(
parameters: {m: 0.5, r: 0.1, h0: 1, e: 0.5}
bodies:
  - {name: ball, type: rigid, mass: m, inertia: [0.4*m*r^2, 0.4*m*r^2, 0.4*m*r^2],
     position: [0, 0, h0]}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: floor, body: ball, shape: sphere, radius: r, restitution: e}
simulate: {t_end: 2, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0}
)";

TEST(ContactBodies, SphereDroppedOnTheGroundBouncesAsTheClosedFormSays) {
  const double e = 0.5, h0 = 1.0, r = 0.1, m_ = 0.5, H = h0 - r;
  Model m = parse_model(kSphere);
  const Index floor = m.system.constraint_index("floor");
  EXPECT_TRUE(m.system.constraint(floor).is_unilateral());
  EXPECT_EQ(m.system.constraint(floor).restitution(), e);
  const double t0 = std::sqrt(2.0 * H / kG);
  const double t_inf = t0 * (1.0 + e) / (1.0 - e);
  const std::vector<double> apex_t = testing::bounce_apex_times(e, t0, kG, 4);
  m.options.output_at = apex_t;
  m.options.output_at.push_back(1.9);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto impacts = events_of(tr, floor, ContactEvent::Kind::kImpact);
  const auto rests = events_of(tr, floor, ContactEvent::Kind::kRest);
  ASSERT_GE(impacts.size(), 10u);
  ASSERT_EQ(rests.size(), 1u);
  testing::expect_bounces(impacts, e, t0, kG, m_, 10);
  const std::size_t nq = 7;  // ball.x, y, z, u0..u3
  for (std::size_t k = 0; k < apex_t.size(); ++k) {
    const std::size_t i = sample_at(tr, apex_t[k]);
    EXPECT_NEAR(tr.q[nq * i + 2], std::pow(e, 2.0 * double(k + 1)) * H + r, 1e-8) << "apex " << k;
    EXPECT_NEAR(tr.qd[nq * i + 2], 0.0, 1e-7) << "apex " << k;
  }
  EXPECT_NEAR(rests[0].t, t_inf, 2e-6 * t_inf);
  // at rest: the centre at r, the ground carries m g (the unit constraint's multiplier is 0)
  const std::size_t last = sample_at(tr, 1.9);
  EXPECT_NEAR(tr.q[nq * last + 2], r, 1e-10);
  EXPECT_NEAR(tr.qd[nq * last + 2], 0.0, 1e-10);
  const std::size_t nc = std::size_t(m.system.constraint_count());
  EXPECT_NEAR(tr.lambda[nc * last + std::size_t(floor)], m_ * kG, 1e-8);
  // all of m g H is lost in the impacts
  EXPECT_NEAR(tr.work_impact.back(), -m_ * kG * H, 1e-8);
  expect_energy_balance(tr, 1e-8);
  // the run's columns (`ukdyn run`, Python): gap.floor = z − r at every sample, beside
  // lambda.floor, as a generalized model's unilateral constraint has
  const ModelRun run = run_model(m);
  const auto& cols = run.extra_columns;
  const auto gap = std::find_if(cols.begin(), cols.end(),
                                [](const CsvColumn& c) { return c.name == "gap.floor"; });
  ASSERT_NE(gap, cols.end());
  ASSERT_EQ(gap->values.size(), run.trajectory.t.size());
  for (std::size_t i = 0; i < run.trajectory.t.size(); ++i)
    EXPECT_NEAR(gap->values[i], run.trajectory.q[nq * i + 2] - r, 1e-12) << "sample " << i;
}

// ---- a planar rod falling flat on two contacts
// ---------------------------------------------------

// A rod (mass m, length L) held horizontal at height h0 falls on its two ends (point contacts at
// (∓L/2, 0)): both gaps close at t0 = √(2 h0 / g), a simultaneous impact. The impact LCP has the
// unique solution of equal impulses ½ m (1 + e) v0 (the rod's W = A M⁻¹ Aᵀ is regular), so the
// rod leaves at e v0 without turning and rises to e² h0; the impacts accumulate at
// t∞ = t0 (1 + e) / (1 − e), and the rod rests on both ends, each carrying m g / 2.
constexpr const char* kRod = R"(
parameters: {m: 2, L: 1, h0: 0.5, e: 0.5}
bodies:
  - {name: rod, type: planar, mass: m, inertia: m*L^2/12, position: [0, h0]}
forces:
  - {type: gravity, g: [0, -9.81]}
contacts:
  - {name: left, body: rod, point: [-L/2, 0], restitution: e}
  - {name: right, body: rod, point: [L/2, 0], restitution: e,
     plane: {body: ground, point: [3, 0], normal: [0, 2]}}
simulate: {t_end: 1.5, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0}
)";

TEST(ContactBodies, RodFallingFlatOnTwoContactsLeavesWithoutTurning) {
  const double e = 0.5, h0 = 0.5, m_ = 2.0;
  Model m = parse_model(kRod);
  const Index left = m.system.constraint_index("left"), right = m.system.constraint_index("right");
  const double t0 = std::sqrt(2.0 * h0 / kG), v0 = kG * t0;
  const double t_inf = t0 * (1.0 + e) / (1.0 - e);
  const double apex = t0 + e * v0 / kG;
  m.options.output_at = {apex, 1.4};
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  for (Index k : {left, right}) {
    const auto impacts = events_of(tr, k, ContactEvent::Kind::kImpact);
    ASSERT_GE(impacts.size(), 5u);
    EXPECT_NEAR(impacts[0].t, t0, 1e-9);
    EXPECT_NEAR(impacts[0].speed_before, -v0, 1e-8);
    EXPECT_NEAR(impacts[0].speed_after, e * v0, 1e-8);
    EXPECT_NEAR(impacts[0].impulse, 0.5 * m_ * (1 + e) * v0, 1e-8);
  }
  // at the apex: y = e² h0, no rotation
  const std::size_t i = sample_at(tr, apex);
  EXPECT_NEAR(tr.q[3 * i + 1], e * e * h0, 1e-8);
  EXPECT_NEAR(tr.q[3 * i + 2], 0.0, 1e-10);
  EXPECT_NEAR(tr.qd[3 * i + 1], 0.0, 1e-7);
  EXPECT_NEAR(tr.qd[3 * i + 2], 0.0, 1e-10);
  // at rest on both ends after t∞
  const std::size_t last = sample_at(tr, 1.4);
  EXPECT_GT(1.4, t_inf);
  EXPECT_NEAR(tr.q[3 * last + 1], 0.0, 1e-9);
  const std::size_t nc = std::size_t(m.system.constraint_count());
  EXPECT_NEAR(tr.lambda[nc * last + std::size_t(left)], 0.5 * m_ * kG, 1e-7);
  EXPECT_NEAR(tr.lambda[nc * last + std::size_t(right)], 0.5 * m_ * kG, 1e-7);
  EXPECT_NEAR(tr.work_impact.back(), -m_ * kG * h0, 1e-7);
  expect_energy_balance(tr, 1e-8);
}

// ---- Newton's cradle of particles ------------------------------------------------------------

// Three particles carrying spheres of radius ½ on the x axis, gaps 1e-3; each contact is the
// sphere of the next particle against the plane x = ½ (normal +x) of the previous one, so the
// gap is x_{i+1} − x_i − 1, the generalized cradle's. With e = 1 the velocities are exchanged:
// the last ball leaves at v = 1, the others rest, momentum and energy are kept.
constexpr const char* kCradle = R"(
parameters: {m: 0.2}
bodies:
  - {name: b1, type: particle, mass: m, position: [0, 0, 0], velocity: [1, 0, 0]}
  - {name: b2, type: particle, mass: m, position: [1.001, 0, 0]}
  - {name: b3, type: particle, mass: m, position: [2.002, 0, 0]}
contacts:
  - {name: c1, body: b2, shape: sphere, radius: 0.5, restitution: 1,
     plane: {body: b1, point: [0.5, 0, 0], normal: [1, 0, 0]}}
  - {name: c2, body: b3, shape: sphere, radius: 0.5, restitution: 1,
     plane: {body: b2, point: [0.5, 0, 0], normal: [1, 0, 0]}}
simulate: {t_end: 0.1, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0}
)";

TEST(ContactBodies, NewtonsCradleOfParticlesExchangesTheVelocities) {
  const Model m = parse_model(kCradle);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  ASSERT_EQ(tr.stats.contact_events.size(), 2u);
  EXPECT_NEAR(tr.stats.contact_events[0].t, 1e-3, 1e-12);
  EXPECT_EQ(tr.stats.contact_events[0].constraint, m.system.constraint_index("c1"));
  EXPECT_EQ(tr.stats.contact_events[1].constraint, m.system.constraint_index("c2"));
  for (const auto& ev : tr.stats.contact_events) EXPECT_NEAR(ev.speed_after, 1.0, 1e-12);
  const std::size_t last = tr.t.size() - 1;
  for (std::size_t b = 0; b < 3; ++b) {
    EXPECT_NEAR(tr.qd[9 * last + 3 * b], b == 2 ? 1.0 : 0.0, 1e-12) << "ball " << b + 1;
  }
  EXPECT_NEAR(tr.work_impact.back(), 0.0, 1e-12);
  expect_energy_balance(tr, 1e-12);
}

// ---- a tilted disk: its gap row against finite differences and its impact ---------------------

// A thin disk (radius R, mass m, J = (m R²/4, m R²/4, m R²/2)), its axis tilted by beta from the
// vertical: s = n·a = cos beta, its lowest point R sin beta below the centre.
struct Disk {
  mb::MultibodyModel model;
  mb::BodyId disk = 0;
  Index row = -1;
};

Disk tilted_disk(double beta, double z0, double e, const Vector3d& v0, const Vector3d& w0) {
  const double m = 1.5, R = 0.2;
  mb::Multibody b;
  const mb::BodyId d = b.add_rigid_body(
      "coin", m, Vector3d(m * R * R / 4, m * R * R / 4, m * R * R / 2), Vector3d(0.1, -0.2, z0),
      Eigen::Quaterniond(Eigen::AngleAxisd(beta, Vector3d::UnitX())), v0, w0);
  b.set_gravity(Vector3d(0, 0, -kG));
  b.add_joint(mb::contact_disk("floor", mb::kGround, mb::Frame{}, d, mb::Frame{}, R, e));
  Disk out{b.build(), d, -1};
  out.row = out.model.system.constraint_index("floor");
  return out;
}

TEST(ContactBodies, DiskGapRowMatchesItsFormulaAndFiniteDifferences) {
  const double beta = 0.5, R = 0.2, z0 = 0.7;
  const Disk d = tilted_disk(beta, z0, 0.3, Vector3d(0.3, -0.1, 0.2), Vector3d(1.0, -2.0, 3.0));
  const System& sys = d.model.system;
  const VectorXd& q = d.model.q0;
  const VectorXd& qd = d.model.qd0;
  // g = z − R sin(beta) at the start
  EXPECT_NEAR(gap_of(sys, d.row, q, qd)[0], z0 - R * std::sin(beta), 1e-14);
  // g' = v_z + (w × rho)_z, rho = R (s a − n) / h the lowest point's offset
  const Vector3d n = Vector3d::UnitZ();
  const Vector3d a = Eigen::AngleAxisd(beta, Vector3d::UnitX()) * Vector3d::UnitZ();
  const double s = n.dot(a), hh = std::sqrt(1 - s * s);
  const Vector3d rho = R * (s * a - n) / hh;
  EXPECT_NEAR(gap_of(sys, d.row, q, qd)[1], 0.2 + Vector3d(1.0, -2.0, 3.0).cross(rho).z(), 1e-13);
  check_form_by_differences(sys, d.row, q, qd, {3}, 1e-8, 1e-5);
  // a disk lying flat is refused at the build, naming the contact
  try {
    tilted_disk(0.0, z0, 0.3, Vector3d::Zero(), Vector3d::Zero());
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("contact 'floor': the disk lies flat"), std::string::npos)
        << e.what();
  }
}

// Dropped tilted without spin, the disk touches at t0 = √(2 (z0 − R sin beta) / g). The impulse
// P n at the lowest point rho gives g'⁺ = −e g'⁻: P = −(1 + e) g'⁻ / (1/m + (rho × n)ᵀ I_W⁻¹
// (rho × n)), and T⁺ − T⁻ from the velocities it sets.
// A frictionless coin dropped tilted lands on its rim (a plastic impact), then turns flat
// within about 10 ms: a disk lying flat on its plane (|n·a| = 1) has no single lowest point, and
// its gap row's A and b grow without bound (r s / h, r s'² / h³ with h → 0). The run stops
// there, keeps its samples, and names the contact and why — it once said only that "the LCP of
// the closed contacts has no solution".
TEST(ContactBodies, CoinThatTurnsFlatStopsNamingTheDiskContact) {
  const Model m = parse_model(R"(
bodies:
  - {name: coin, type: rigid, mass: 0.01, inertia: [2e-6, 2e-6, 4e-6], position: [0, 0, 0.05],
     orientation: {axis: [1, 0, 0], angle: 0.3}}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: rim, body: coin, shape: disk, radius: 0.02}
simulate: {t_end: 0.5}
)");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  EXPECT_NE(tr.stats.status, Status::kOk);
  EXPECT_NE(tr.stats.message.find("'rim'"), std::string::npos) << tr.stats.message;
  EXPECT_NE(tr.stats.message.find("lies flat"), std::string::npos) << tr.stats.message;
  // the impact: the rim's lowest point, 0.02 sin 0.3 above the centre's height at contact,
  // reached after a free fall from 0.05: t = sqrt(2 (0.05 − 0.02 sin 0.3) / g)
  const auto impacts = events_of(tr, m.system.constraint_index("rim"), ContactEvent::Kind::kImpact);
  ASSERT_GE(impacts.size(), 1u);
  const double t_impact = std::sqrt(2.0 * (0.05 - 0.02 * std::sin(0.3)) / kG);
  EXPECT_NEAR(impacts[0].t, t_impact, 1e-9);
  // the samples up to the failure are kept
  ASSERT_GE(tr.t.size(), 2u);
  EXPECT_GT(tr.t.back(), t_impact);
  EXPECT_LT(tr.t.back(), 0.12);
}

TEST(ContactBodies, TiltedDiskDroppedOnTheGroundMeetsTheImpulseClosedForm) {
  const double beta = 0.6, R = 0.2, z0 = 0.5, e = 0.3, m_ = 1.5;
  const Disk d = tilted_disk(beta, z0, e, Vector3d::Zero(), Vector3d::Zero());
  SimulationOptions o;
  o.integrator = Integrator::kDopri5;
  o.rtol = 1e-11;
  o.atol = 1e-13;
  const double t0 = std::sqrt(2.0 * (z0 - R * std::sin(beta)) / kG);
  o.t_end = t0 + 0.02;
  const Trajectory tr = simulate(d.model.system, d.model.q0, d.model.qd0, o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto impacts = events_of(tr, d.row, ContactEvent::Kind::kImpact);
  ASSERT_EQ(impacts.size(), 1u);
  EXPECT_NEAR(impacts[0].t, t0, 1e-9);
  const double v0 = kG * t0;
  EXPECT_NEAR(impacts[0].speed_before, -v0, 1e-8);
  EXPECT_NEAR(impacts[0].speed_after, e * v0, 1e-8);
  const Vector3d n = Vector3d::UnitZ();
  const Eigen::Matrix3d Rot = Eigen::AngleAxisd(beta, Vector3d::UnitX()).toRotationMatrix();
  const Vector3d a = Rot.col(2);
  const double s = n.dot(a);
  const Vector3d rho = R * (s * a - n) / std::sqrt(1 - s * s);
  const Eigen::Matrix3d I_W =
      Rot * Vector3d(m_ * R * R / 4, m_ * R * R / 4, m_ * R * R / 2).asDiagonal() * Rot.transpose();
  const Vector3d rn = rho.cross(n);
  const double P = (1 + e) * v0 / (1.0 / m_ + rn.dot(I_W.inverse() * rn));
  EXPECT_NEAR(impacts[0].impulse, P, 1e-8);
  const Vector3d dv = P / m_ * n, w = I_W.inverse() * (rn * P);
  const double dT =
      0.5 * m_ * ((Vector3d(0, 0, -v0) + dv).squaredNorm() - v0 * v0) + 0.5 * w.dot(I_W * w);
  EXPECT_NEAR(impacts[0].energy_change, dT, 1e-8);
  expect_energy_balance(tr, 1e-8);
}

// ---- a plane fixed on a moving body ------------------------------------------------------------

// A particle's sphere against a plane fixed on a rigid body that moves and turns: at any state
// g = n_W · (c_W − o_W) − r with n_W = R_WB n_B, o_W = p_WB + R_WB o_B, and A, b by differences.
TEST(ContactBodies, ContactOnAPlaneOfAMovingBodyMatchesItsFormula) {
  mb::Multibody b;
  const Eigen::Quaterniond u0(Eigen::AngleAxisd(0.4, Vector3d(1, 2, -1).normalized()));
  const mb::BodyId table =
      b.add_rigid_body("table", 3.0, Vector3d(0.3, 0.4, 0.5), Vector3d(0.2, 0.1, -0.3), u0,
                       Vector3d(0.5, -0.4, 0.3), Vector3d(-1.0, 0.7, 2.0));
  const mb::BodyId ball = b.add_particle("ball", 0.5, Vector3d(0.4, -0.3, 1.2), Vector3d(1, 2, 3));
  const Vector3d o_B(0.1, 0.2, 0.15), n_B = Vector3d(0.2, -0.1, 1.0).normalized();
  const double r = 0.05;
  b.add_joint(
      mb::contact("on_table", table, mb::Frame::with_z(o_B, n_B), ball, Vector3d::Zero(), r, 0.4));
  const mb::MultibodyModel model = b.build();
  const Index k = model.system.constraint_index("on_table");
  EXPECT_EQ(model.system.constraint(k).restitution(), 0.4);
  const VectorXd& q = model.q0;
  const VectorXd& qd = model.qd0;
  const mb::Pose P = mb::body_pose(model, q, table);
  const Vector3d n_W = P.R_WB * n_B, o_W = P.p_WB + P.R_WB * o_B;
  const Vector3d c_W = mb::world_point(model, q, ball, Vector3d::Zero());
  EXPECT_NEAR(gap_of(model.system, k, q, qd)[0], n_W.dot(c_W - o_W) - r, 1e-14);
  // g' = n_W · (v_c − v_o) + (w × n_W) · (c − o), v_o = v_B + w × (o_W − p_WB)
  const auto [v_B, w] = mb::body_velocity(model, q, qd, table);
  const Vector3d v_o = v_B + w.cross(o_W - P.p_WB);
  const double gd = n_W.dot(Vector3d(1, 2, 3) - v_o) + w.cross(n_W).dot(c_W - o_W);
  EXPECT_NEAR(gap_of(model.system, k, q, qd)[1], gd, 1e-13);
  check_form_by_differences(model.system, k, q, qd, {3}, 1e-8, 1e-5);
}

// ---- the contacts: section's errors ------------------------------------------------------------

TEST(ContactBodies, BadContactsGetAClearErrorWithItsPlace) {
  auto message = [](const std::string& contacts) {
    const std::string text =
        "bodies:\n"
        "  - {name: ball, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 1]}\n"
        "  - {name: dot, type: particle, mass: 1, position: [0, 0, 1]}\n"
        "joints:\n"
        "  - {name: pin, type: spherical, parent: ground, child: dot, parent_point: [0, 0, 1]}\n"
        "contacts:\n" +
        contacts;
    try {
      parse_model(text);
    } catch (const ModelError& e) {
      return std::to_string(e.line()) + ":" + std::to_string(e.column()) + " " + e.message() +
             " | " + e.hint();
    } catch (const std::exception& e) {
      return std::string("not a ModelError: ") + e.what();
    }
    return std::string("no error");
  };
  const auto expect = [&](const std::string& contacts, const std::string& where,
                          const std::string& text) {
    const std::string got = message(contacts);
    EXPECT_EQ(got.rfind(where + " ", 0), 0u) << got;
    EXPECT_NE(got.find(text), std::string::npos) << got;
  };
  expect("  - {name: f, body: ball, radius: 0.1}\n", "7:35", "contact 'f': a point has no radius");
  expect("  - {name: f, body: ball, shape: sphere}\n", "7:5", "needs 'radius'");
  expect("  - {name: f, body: ball, shape: sphere, radius: 0}\n", "7:50",
         "contact 'f' radius must be > 0");
  expect("  - {name: f, body: ball, shape: cube}\n", "7:34", "unknown shape 'cube'");
  expect("  - {name: f, body: bal}\n", "7:21", "unknown body 'bal'");
  expect("  - {name: f, body: ball, radiuss: 1}\n", "7:27", "unknown key 'radiuss' in contact 'f'");
  expect("  - {name: f, body: ball, shape: sphere, radius: 1, axis: [1, 0, 0]}\n", "7:59",
         "axis is for a disk, not a sphere");
  expect("  - {name: f, body: ball, plane: {normal: [0, 0, 0]}}\n", "7:43", "the normal is zero");
  expect("  - {name: f, body: ball, restitution: 1.5}\n", "7:40",
         "the restitution must lie in [0, 1], got 1.5");
  expect("  - {name: f, body: ball, restitution_law: kepler}\n", "7:44",
         "must be newton or poisson");
  expect("  - {name: pin, body: ball}\n", "7:12", "contact 'pin': a joint has this name");
  expect("  - {name: f, body: ball}\n  - {name: f, body: ball}\n", "8:12",
         "contact 'f' is declared twice");
  expect("  - {name: f, body: dot, shape: disk, radius: 1}\n", "7:33",
         "a particle has no orientation");
  expect("  - {name: f, body: ball, shape: disk, radius: 1}\n", "7:5",
         "contact 'f': the disk lies flat on its plane at the start");
  // friction at a body's contact slides the contact point: coordinates: refused there
  // (test_contact_bodies_friction.cpp has the motion and the other errors)
  try {
    parse_model(std::string(kSphere) +
                "nonideal:\n  - {friction: coulomb, constraint: floor, mu: 0.3, coordinates: "
                "[ball_x]}\n");
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 13);
    EXPECT_NE(e.message().find("a bodies model's contact friction slides the contact point"),
              std::string::npos)
        << e.message();
  }
  // generalized coordinates: a contact is a constraint
  try {
    parse_model("coordinates: [y]\nmass_matrix: [[1]]\ncontacts: []\n");
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(e.message().find("'contacts' goes with bodies: or robot:"), std::string::npos);
  }
  // a penetrating start names the contact
  Model m = parse_model(kSphere, "<string>", {{"h0", 0.05}});
  try {
    simulate(m.system, m.q0, m.qd0, m.options);
    ADD_FAILURE() << "no error";
  } catch (const InconsistentInitialState& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "the unilateral constraint 'floor' is penetrated: its gap is -0.05"),
              std::string::npos)
        << e.what();
  }
}

// Poisson's law goes through: a sphere with restitution_law: poisson, no friction, bounces as
// with Newton's (both give g'⁺ = −e g'⁻ without friction).
TEST(ContactBodies, PoissonsLawIsKeptOnTheContactsConstraint) {
  std::string text = kSphere;
  text.replace(text.find("restitution: e}"), 15, "restitution: e, restitution_law: poisson}");
  Model m = parse_model(text);
  const Index floor = m.system.constraint_index("floor");
  EXPECT_EQ(restitution_law(m.system.constraint(floor)), RestitutionLaw::kPoisson);
  m.options.t_end = 0.8;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto impacts = events_of(tr, floor, ContactEvent::Kind::kImpact);
  ASSERT_GE(impacts.size(), 1u);
  const double v0 = std::sqrt(2.0 * kG * 0.9);
  EXPECT_NEAR(impacts[0].speed_after, 0.5 * v0, 1e-8);
  expect_energy_balance(tr, 1e-8);
}

// A gap with an offset, y − r (the gap of every sphere), has the roundoff of y near r: a flight
// may start a few ulps below 0. Before, the next impact was then sought below −1e-9 (kTouchGap),
// so every flight fell that much further than it rose and an accumulation of impacts never came
// to rest (the run hit its step limit at t∞); now it is sought below where the flight started,
// and the ball rests at t∞ = t0 (1 + e) / (1 − e), t0 = √(2 (h0 − r) / g), as without offset.
TEST(ContactBodies, GapWithAnOffsetComesToRestAtTheAccumulationPoint) {
  const Model m = parse_model(R"(
parameters: {m: 0.5, g: 9.81, h0: 1, e: 0.5}
coordinates: [y]
kinetic_energy: 0.5*m*y_dot^2
potential_energy: m*g*y
constraints:
  - {name: floor, holonomic: y - 0.1, unilateral: true, restitution: e}
initial: {q: {y: h0}}
simulate: {t_end: 1.5, integrator: dopri5, rtol: 1e-11, atol: 1e-13, max_steps: 100000}
output: {every: 0}
)");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const double t0 = std::sqrt(2.0 * 0.9 / kG), t_inf = 3.0 * t0;
  const auto impacts = events_of(tr, 0, ContactEvent::Kind::kImpact);
  const auto rests = events_of(tr, 0, ContactEvent::Kind::kRest);
  EXPECT_EQ(impacts.size(), 20u);
  ASSERT_EQ(rests.size(), 1u);
  EXPECT_NEAR(rests[0].t, t_inf, 2e-6 * t_inf);
  // every flight rises and falls alike: the speed halves at each impact
  for (std::size_t k = 1; k < impacts.size(); ++k) {
    EXPECT_NEAR(impacts[k].speed_before, -impacts[k - 1].speed_after,
                1e-6 * impacts[k - 1].speed_after)
        << "impact " << k;
  }
  EXPECT_NEAR(tr.q.back(), 0.1, 1e-12);
  expect_energy_balance(tr, 1e-8);
}

// The viewer's contacts: (visual:) name a bodies model's contacts as a generalized model's
// unilateral constraints: the contact point and normal become the run's visual.contact.* columns.
TEST(ContactBodies, TheViewerDrawsABodysContact) {
  const Model m = parse_model(std::string(kSphere) +
                              "visual: {contacts: {floor: {at: [ball_x, ball_y, ball_z - r], "
                              "normal: [0, 0, 1]}}}\n");
  ASSERT_EQ(m.visual.contacts.size(), 1u);
  EXPECT_EQ(m.visual.contacts[0].name, "floor");
  EXPECT_EQ(m.visual.contacts[0].dimensions, 3);
  try {
    parse_model(std::string(kSphere) +
                "visual: {contacts: {wall: {at: [0, 0, 0], normal: [1, 0, "
                "0]}}}\n");
    ADD_FAILURE() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(e.message().find("visual contact 'wall': there is no unilateral constraint"),
              std::string::npos)
        << e.message();
    EXPECT_NE(e.hint().find("the unilateral constraints are floor"), std::string::npos) << e.hint();
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

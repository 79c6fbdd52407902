// SPDX-License-Identifier: BSD-3-Clause
// A sphere's (or point's) contact with a box on bodies models (issue #31, docs/contact.md, "A
// sphere against a box": `box:` in a contact; mb::contact_sphere_box), each against a closed
// form or an independent computation: the gap row's g against the world geometry and its A and
// b against finite differences, in the regions of a face, an edge and a corner, spatial and
// planar; a ball tipping off a fixed box's edge (it pivots about the edge and leaves at
// cos θ = (2/3) cos θ₀); a ball dropped onto a box's corner (the impulse along the line from the
// corner); a ball striking a free box off its centre line (the impulse and the spin of the
// effective mass); a ball launched on a rough box's top face (it rolls from t* = 2 v0/(7 μ g));
// and the errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

using Eigen::Matrix3d;
using mb::Vector3d;
constexpr double kG = 9.81;

using testing::events_of;

// ω_z of a rigid body from its quaternion u and rate u': 2 (u0 u3' − u0' u3 + u1 u2' − u2 u1')
double omega_z(const double* u, const double* ud) {
  return 2.0 * (u[0] * ud[3] - ud[0] * u[3] + u[1] * ud[2] - u[2] * ud[1]);
}

// ---- the gap row --------------------------------------------------------------------------------

// A box (half-extents h, turned within its body p) and a sphere (radius r on body c), both turning
// rigid bodies: g = |u − clamp(u, −h, h)| − r from the world points (u the sphere's centre in the
// box's axes), and A and b against differences of g along the motion; with the centre over a
// face (one axis beyond the box), an edge (two) and a corner (three).
TEST(ContactSphereBox, GapRowMatchesTheGeometryAndFiniteDifferences) {
  const double r = 0.1;
  const Vector3d halves[] = {{2.0, 2.0, 0.05}, {2.0, 0.05, 0.05}, {0.05, 0.05, 0.05}};
  for (int region = 0; region < 3; ++region) {
    mb::Multibody b;
    const mb::BodyId p =
        b.add_rigid_body("p", 2.0, Vector3d(0.1, 0.2, 0.3), Vector3d(0.05, 0.02, 0.0),
                         Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Vector3d(1, 2, 3).normalized())),
                         Vector3d(0.3, -0.2, 0.1), Vector3d(1.0, 0.5, -2.0));
    const mb::BodyId c = b.add_rigid_body(
        "c", 1.0, Vector3d(0.2, 0.1, 0.3), Vector3d(0.3, 0.4, 0.5),
        Eigen::Quaterniond(Eigen::AngleAxisd(-0.2, Vector3d(-1, 0, 2).normalized())),
        Vector3d(-0.4, 0.6, 0.2), Vector3d(-1.5, 2.0, 0.7));
    mb::Frame box = mb::Frame::at(Vector3d(0.02, -0.01, 0.05));
    box.R = Eigen::AngleAxisd(0.3, Vector3d(0.2, -1, 0.5).normalized()).toRotationMatrix();
    const Vector3d pc(-0.01, 0.03, 0.02), h = halves[region];
    b.add_joint(mb::contact_sphere_box("sb", p, box, h, c, pc, r, 0.5));
    const mb::MultibodyModel model = b.build();
    const System& sys = model.system;
    const Index k = sys.constraint_index("sb");
    EXPECT_TRUE(sys.constraint(k).is_unilateral());
    const VectorXd& q = model.q0;
    const VectorXd& qd = model.qd0;
    // the world geometry: the centre in the box's axes, its excess beyond each face
    const Vector3d cw = mb::world_point(model, q, c, pc), ow = mb::world_point(model, q, p, box.p);
    const Matrix3d R = mb::body_pose(model, q, p).R_WB.toRotationMatrix() * box.R;
    const Vector3d u = R.transpose() * (cw - ow);
    const Vector3d m = (u.cwiseAbs() - h).cwiseMax(0.0);
    int beyond = 0;
    for (int i = 0; i < 3; ++i) beyond += m[i] > 0.0 ? 1 : 0;
    ASSERT_EQ(beyond, region + 1) << "the pose is not in the region " << region;
    EXPECT_NEAR(testing::gap_of(sys, k, q, qd)[0], m.norm() - r, 1e-14);
    // g' by a central difference of the gap along q + h q'
    const double step = 1e-6;
    const double fd = (testing::gap_of(sys, k, q + step * qd, qd)[0] -
                       testing::gap_of(sys, k, q - step * qd, qd)[0]) /
                      (2 * step);
    EXPECT_NEAR(testing::gap_of(sys, k, q, qd)[1], fd, 1e-8) << "region " << region;
    testing::check_form_by_differences(sys, k, q, qd, {3, 10}, 1e-8, 1e-5);
  }
}

// The same in a planar model: a rectangle (half-extents hx, hy, turned by its body's angle and
// its own) and a circle, beyond an edge (one axis) and a corner (two).
TEST(ContactSphereBox, PlanarGapRowMatchesTheGeometryAndFiniteDifferences) {
  const double r = 0.1;
  const Vector3d halves[] = {{2.0, 0.05, 0.0}, {0.05, 0.05, 0.0}};
  for (int region = 0; region < 2; ++region) {
    mb::Multibody b;
    const mb::BodyId p = b.add_planar_body("p", 2.0, 0.3, {0.05, 0.02, 0.4}, {0.3, -0.2, 1.1});
    const mb::BodyId c = b.add_planar_body("c", 1.0, 0.2, {0.3, 0.5, -0.2}, {-0.4, 0.6, -0.8});
    const mb::Frame box = mb::Frame::planar(0.02, -0.01, 0.3);
    const Vector3d pc(-0.01, 0.03, 0.0), h = halves[region];
    b.add_joint(mb::contact_sphere_box("sb", p, box, h, c, pc, r));
    const mb::MultibodyModel model = b.build();
    const System& sys = model.system;
    const Index k = sys.constraint_index("sb");
    const VectorXd& q = model.q0;
    const VectorXd& qd = model.qd0;
    const Vector3d cw = mb::world_point(model, q, c, pc), ow = mb::world_point(model, q, p, box.p);
    const double th = q[2] + 0.3;
    const Eigen::Vector2d d = (cw - ow).head<2>();
    const Eigen::Vector2d u(std::cos(th) * d.x() + std::sin(th) * d.y(),
                            -std::sin(th) * d.x() + std::cos(th) * d.y());
    const Eigen::Vector2d m = (u.cwiseAbs() - h.head<2>()).cwiseMax(0.0);
    ASSERT_EQ(int((m.array() > 0.0).count()), region + 1) << "region " << region;
    EXPECT_NEAR(testing::gap_of(sys, k, q, qd)[0], m.norm() - r, 1e-14);
    testing::check_form_by_differences(sys, k, q, qd, {}, 1e-8, 1e-5);
  }
}

// ---- a ball tips off a box's edge ---------------------------------------------------------------

// A frictionless ball (radius r, a particle) rests against the edge x = hx, z = 0 of a fixed box
// (the ground's, its top face z = 0) at the angle θ₀ from the vertical through the edge. Its
// nearest box point stays on the edge, so its centre moves on the circle of radius r about it,
// θ'' = (g/r) sin θ, and the normal force m g (3 cos θ − 2 cos θ₀) vanishes at
// cos θ* = (2/3) cos θ₀: it leaves there, at the time the test's own RK4 gives, with the speed
// sqrt(g r cos θ*), then flies freely.
TEST(ContactSphereBox, BallTippingOffABoxsEdgeLeavesAtTwoThirdsOfTheStartsCosine) {
  const double hx = 0.5, r = 0.05, th0 = 0.25, mass = 2.0, t_end = 0.6;
  const Model m = parse_model(R"(
parameters: {hx: 0.5, r: 0.05, th0: 0.25}
bodies:
  - {name: ball, type: particle, mass: 2, position: [hx + r*sin(th0), 0.1, r*cos(th0)]}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: edge, body: ball, shape: sphere, radius: r,
     box: {body: ground, point: [0, 0, -0.3], size: [hx, 0.4, 0.3]}}
simulate: {t_end: 0.6, integrator: dopri5, rtol: 1e-12, atol: 1e-14}
output: {every: 0}
)");
  // the normal from the box to the ball
  testing::expect_tips_off_edge(m, "edge", 0, Vector3d(hx, 0.1, 0), r, th0, mass, kG, t_end, 1.0);
}

// ---- a ball dropped onto a box's corner ---------------------------------------------------------

// A ball (a particle, radius r) falls from rest at height z0 over the point (hx + δx, hy + δy) of a
// fixed box's top corner (hx, hy, 0): it touches the corner when its centre is at
// z_c = sqrt(r² − δx² − δy²), at t = sqrt(2 (z0 − z_c)/g), with the normal
// n = (δx, δy, z_c)/r from the corner. Newton's impulse P n, P = −(1 + e) m v_n, v_n = −g t z_c/r,
// gives v⁺ = v⁻ + (P/m) n and ΔT = −½ (1 − e²) m v_n².
TEST(ContactSphereBox, BallDroppedOnABoxsCornerBouncesAlongTheLineFromTheCorner) {
  const double mass = 0.3, r = 0.05, z0 = 0.2, e = 0.7, dx = 0.02, dy = 0.015;
  const double hx = 0.4, hy = 0.3;
  const Model m = parse_model(R"(
bodies:
  - {name: ball, type: particle, mass: 0.3, position: [0.42, 0.315, 0.2]}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: corner, body: ball, shape: sphere, radius: 0.05, restitution: 0.7,
     box: {body: ground, point: [0, 0, -0.25], size: [0.4, 0.3, 0.25]}}
simulate: {t_end: 0.25, integrator: dopri5, rtol: 1e-12, atol: 1e-14}
output: {every: 0}
)");
  const Index k = m.system.constraint_index("corner");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto impacts = events_of(tr, k, ContactEvent::Kind::kImpact);
  ASSERT_EQ(impacts.size(), 1u);
  const double zc = std::sqrt(r * r - dx * dx - dy * dy);
  const double t_hit = std::sqrt(2.0 * (z0 - zc) / kG), v = kG * t_hit;
  const Vector3d n = Vector3d(dx, dy, zc) / r;
  const double vn = -v * n.z(), P = -(1.0 + e) * mass * vn;
  EXPECT_NEAR(impacts[0].t, t_hit, 1e-10);
  EXPECT_NEAR(impacts[0].speed_before, vn, 1e-9);
  EXPECT_NEAR(impacts[0].speed_after, -e * vn, 1e-9);
  EXPECT_NEAR(impacts[0].impulse, P, 1e-9);
  EXPECT_NEAR(impacts[0].energy_change, -0.5 * (1 - e * e) * mass * vn * vn, 1e-10);
  // just after the impact
  std::size_t i = 0;
  while (i < tr.t.size() && tr.t[i] <= impacts[0].t) ++i;
  ASSERT_LT(i, tr.t.size());
  const double dt = tr.t[i] - impacts[0].t;
  const Vector3d v_after = Vector3d(0, 0, -v) + (P / mass) * n;
  EXPECT_NEAR(tr.qd[3 * i], v_after.x(), 1e-9);
  EXPECT_NEAR(tr.qd[3 * i + 1], v_after.y(), 1e-9);
  EXPECT_NEAR(tr.qd[3 * i + 2], v_after.z() - kG * dt, 1e-7);
  EXPECT_GT(v_after.x(), 0.1);  // (thrown off the corner, not straight up)
  (void)hx;
  (void)hy;
  EXPECT_NEAR(tr.work_impact.back(), impacts[0].energy_change, 1e-12);
  EXPECT_NEAR(tr.energy.back() - tr.energy.front(), tr.work_impact.back(), 1e-9);
}

// ---- a ball strikes a free box off its centre line ----------------------------------------------

// No gravity. A ball (particle m, radius r) moving at −v along x strikes the +x face of a free box
// (mass M, inertia diag(I), half-extents hx, hy, hz, at rest) at the height y0 off the box's
// centre line. The normal is x, the lever a = (hx, y0, 0), a × n = (0, 0, −y0):
//   1/m_eff = 1/m + 1/M + y0²/I_zz,  P = (1 + e) m_eff v,
// the ball leaves at −v + P/m, the box at −P/M along x spinning at ω_z = P y0/I_zz; the box's
// momentum and angular momentum about the origin balance the ball's.
TEST(ContactSphereBox, BallStrikingAFreeBoxOffItsCentreLineGivesTheEffectiveMassImpulse) {
  const double m = 0.5, M = 2.0, Izz = 0.03, r = 0.05, v = 3.0, y0 = 0.06, e = 0.6;
  const double hx = 0.2;
  const Model mod = parse_model(R"(
bodies:
  - {name: crate, type: rigid, mass: 2, inertia: [0.01, 0.02, 0.03], position: [0, 0, 0]}
  - {name: ball, type: particle, mass: 0.5, position: [0.6, 0.06, 0], velocity: [-3, 0, 0]}
contacts:
  - {name: strike, body: ball, shape: sphere, radius: 0.05, restitution: 0.6,
     box: {body: crate, size: [0.2, 0.1, 0.1]}}
simulate: {t_end: 0.2, integrator: dopri5, rtol: 1e-12, atol: 1e-14}
output: {every: 0}
)");
  const Index k = mod.system.constraint_index("strike");
  const Trajectory tr = simulate(mod.system, mod.q0, mod.qd0, mod.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto impacts = events_of(tr, k, ContactEvent::Kind::kImpact);
  ASSERT_GE(impacts.size(), 1u);
  const double t_hit = (0.6 - hx - r) / v;
  const double m_eff = 1.0 / (1.0 / m + 1.0 / M + y0 * y0 / Izz);
  const double P = (1.0 + e) * m_eff * v;
  EXPECT_NEAR(impacts[0].t, t_hit, 1e-10);
  EXPECT_NEAR(impacts[0].speed_before, -v, 1e-9);
  EXPECT_NEAR(impacts[0].speed_after, e * v, 1e-9);
  EXPECT_NEAR(impacts[0].impulse, P, 1e-9);
  EXPECT_NEAR(impacts[0].energy_change, -0.5 * (1 - e * e) * m_eff * v * v, 1e-10);
  // just after the impact (the crate's coordinates 0..6, the ball's 7..9)
  std::size_t i = 0;
  while (i < tr.t.size() && tr.t[i] <= impacts[0].t) ++i;
  ASSERT_LT(i, tr.t.size());
  if (impacts.size() > 1) {
    ASSERT_GT(impacts[1].t, tr.t[i]);
  }
  const double* qd = &tr.qd[10 * i];
  EXPECT_NEAR(qd[7], -v + P / m, 1e-9);
  EXPECT_NEAR(qd[8], 0.0, 1e-9);
  EXPECT_NEAR(qd[0], -P / M, 1e-9);
  EXPECT_NEAR(qd[1], 0.0, 1e-9);
  EXPECT_NEAR(omega_z(&tr.q[10 * i + 3], qd + 3), P * y0 / Izz, 1e-8);
  EXPECT_GT(P * y0 / Izz, 1.0);  // (a real spin)
  // the momentum along x: m (−v) before, the same after
  EXPECT_NEAR(m * qd[7] + M * qd[0], -m * v, 1e-9);
  EXPECT_NEAR(tr.energy[i] - tr.energy.front(), impacts[0].energy_change, 1e-9);
}

// ---- a ball launched on a rough box's top face --------------------------------------------------

// A ball (m, r, I = 2/5 m r²) resting on the top face of a big fixed box (the ground's), launched
// along x at v0 without spin: it slides with v = v0 − μ g t while ω_y = 5 μ g t/(2 r) grows, rolls
// from t* = 2 v0/(7 μ g) at 5/7 v0; friction work −m v0²/7.
TEST(ContactSphereBox, BallOnARoughBoxsFaceRollsFromTheClosedFormInstant) {
  Model m = parse_model(R"(
parameters: {m: 0.5, r: 0.1, v0: 2, mu: 0.2}
bodies:
  - {name: ball, type: rigid, mass: m, inertia: [0.4*m*r^2, 0.4*m*r^2, 0.4*m*r^2],
     position: [0, 0, r], velocity: [v0, 0, 0]}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: top, body: ball, shape: sphere, radius: r, box: {body: ground, point: [1, 0, -0.5],
     size: [5, 2, 0.5]}}
nonideal:
  - {friction: coulomb, constraint: top, mu: mu}
simulate: {t_end: 0.5, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0}
)");
  testing::expect_rolls_from_closed_form(m, "top", 0, 0.5, 0.1, 2.0, 0.2, kG);
}

// ---- a ball rolls over a rough box's edge -------------------------------------------------------

// A ball (m = 2, r = 0.1, I = 2/5 m r²) rolls at v0 = 0.5 along the top face z = 1 of a fixed box
// (μ = 0.5) and over its edge x = 0.5 (reached at 0.04 s): it pivots rolling about the edge until
// the friction it needs, 2/7 m g sin θ, exceeds μ N = μ (m g cos θ − m r θ'²), slips, and leaves
// the edge where N = 0. The instants of an independent integration (scipy's solve_ivp at rtol
// 1e-12 of the pivoting and sliding phases: u22's pA/ref.py), slip at 0.14570716583 s and leave
// at 0.17003200588 s; then it flies, its centre crossing the level of the box's top face (where
// the normal passes along the x axis of the contact's first tangents: it took steps of 2.8e-17 s
// forever there, u22 04) to the end: x' and ω constant, z' falling at g.
TEST(ContactSphereBox, BallRollingOverARoughBoxsEdgeSlipsLeavesAndFlies) {
  const Model m = parse_model(R"(
parameters: {m: 2, r: 0.1, h: 0.5, v0: 0.5, x0: 0.48, mu: 0.5}
bodies:
  - {name: ball, type: rigid, mass: m, inertia: 0.4*m*r^2,
     position: [x0, 0, 2*h + r], velocity: [v0, 0, 0], angular_velocity: [0, v0/r, 0]}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: edge, body: ball, shape: sphere, radius: r,
     box: {body: ground, point: [0, 0, h], size: [h, h, h]}}
nonideal:
  - {friction: coulomb, constraint: edge, mu: mu}
simulate: {t_end: 0.6, output_at: [0.3, 0.6]}
)");
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  double slip = -1.0, leave = -1.0;
  for (const ContactEvent& ev : tr.stats.contact_events) {
    if (ev.kind == ContactEvent::Kind::kSlip && slip < 0.0) slip = ev.t;
    if (ev.kind == ContactEvent::Kind::kRelease && leave < 0.0) leave = ev.t;
  }
  EXPECT_NEAR(slip, 0.14570716583, 1e-8);
  EXPECT_NEAR(leave, 0.17003200588, 1e-8);
  const auto sample = [&](double t) {
    const auto at = std::find(tr.t.begin(), tr.t.end(), t);
    EXPECT_NE(at, tr.t.end()) << t;
    return std::size_t(at - tr.t.begin());
  };
  const std::size_t a = sample(0.3), b = sample(0.6);
  const auto q = [&](const char* name, std::size_t i) {
    return testing::coordinate_at(tr, tr.q, name, i);
  };
  const auto qd = [&](const char* name, std::size_t i) {
    return testing::coordinate_at(tr, tr.qd, name, i);
  };
  EXPECT_LT(q("ball.z", b), 1.0);        // (below the top face's level)
  EXPECT_GT(q("ball.x", b), 0.5 + 0.1);  // (beyond the edge by more than r: free)
  EXPECT_NEAR(qd("ball.x", b), qd("ball.x", a), 1e-9);
  EXPECT_NEAR(qd("ball.z", b) - qd("ball.z", a), -kG * 0.3, 1e-9);
  EXPECT_NEAR(q("ball.x", b) - q("ball.x", a), 0.3 * qd("ball.x", a), 1e-9);
  // the spin about y, 2 (u0 u2' − u0' u2 + u3 u1' − u1 u3'), constant in flight
  const auto omega_y = [&](std::size_t i) {
    return 2.0 * (q("ball.u0", i) * qd("ball.u2", i) - qd("ball.u0", i) * q("ball.u2", i) +
                  q("ball.u3", i) * qd("ball.u1", i) - q("ball.u1", i) * qd("ball.u3", i));
  };
  EXPECT_NEAR(omega_y(b), omega_y(a), 1e-9);
  EXPECT_GT(omega_y(a), 0.5 / 0.1);  // (spun up by the edge's rolling)
}

// ---- errors -------------------------------------------------------------------------------------

TEST(ContactSphereBox, BadSphereBoxContactsGetAClearErrorWithItsPlace) {
  const std::string head =
      "bodies:\n"
      "  - {name: a, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 1]}\n"
      "  - {name: b, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 3]}\n"
      "contacts:\n"
      "  - ";
  testing::expect_model_error(
      head + "{name: c, body: a, shape: disk, radius: 0.1, box: {body: b, size: [1, 1, 1]}}\n",
      "5:55", "contact 'c': a disk against a box is not supported");
  testing::expect_model_error(head +
                                  "{name: c, body: a, shape: sphere, radius: 0.1, box: {body: b, "
                                  "size: [1, 1, 1]}, sphere: {body: b, radius: 1}}\n",
                              "5:57", "a contact is with a plane, a sphere or a box, not several");
  testing::expect_model_error(
      head + "{name: c, body: a, shape: sphere, radius: 0.1, box: {body: b, size: [1, 0, 1]}}\n",
      "5:73", "contact 'c' box: the half-extents must be > 0, got 0");
  testing::expect_model_error(
      head + "{name: c, body: a, shape: sphere, radius: 0.1, box: {body: a, size: [1, 1, 1]}}\n",
      "5:64", "contact 'c' box: the box is on the contact's own body");
  testing::expect_model_error(
      head + "{name: c, body: a, shape: sphere, radius: 0.1, box: {body: b}}\n", "5:57",
      "contact 'c' box needs 'size'");
  // the sphere's centre inside the box at the start: no normal, refused at the build
  mb::Multibody inside;
  const mb::BodyId d = inside.add_rigid_body("d", 1.0, Vector3d(1, 1, 1), Vector3d(0.1, 0, 0),
                                             Eigen::Quaterniond::Identity());
  inside.add_joint(mb::contact_sphere_box("touch", mb::kGround, mb::Frame::at(Vector3d::Zero()),
                                          Vector3d(0.5, 0.5, 0.5), d, Vector3d::Zero(), 0.05));
  try {
    (void)inside.build();
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("contact 'touch': the sphere's centre lies inside the "
                                         "box at the start"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

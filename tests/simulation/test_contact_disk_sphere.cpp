// SPDX-License-Identifier: BSD-3-Clause
// A thin disk's contact with a sphere on bodies models (issue #31, docs/contact.md, "Contacts on
// bodies": `shape: disk` with `sphere:`; mb::contact_disk_sphere), each against a closed form
// or an independent computation: the gap row's g against the world geometry and its A and b
// against finite differences, on the disk's face and beyond its rim; a ball tipping off a fixed
// disk's edge (it pivots about the edge point and leaves at cos θ = (2/3) cos θ₀); a coin
// dropped flat onto a fixed sphere below its edge (the impulse along the normal through the
// edge point, the spin it gives) and below its face (a straight bounce); a ball launched on a
// rough disk's face (it rolls from t* = 2 v0/(7 μ g)); and the errors.
#include <gtest/gtest.h>

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

// ---- the gap row --------------------------------------------------------------------------------

// A disk (radius R, axis k on body c) and a sphere (radius r on body p), both turning rigid
// bodies: g = sqrt(s² + m²) − r from the world points (s = k·(c − o), m = max(|w| − R, 0),
// w = (c − o) − s k), and A and b against differences of g along the motion; on the face
// (the sphere's centre over the disk) and beyond the rim.
TEST(ContactDiskSphere, GapRowMatchesTheGeometryAndFiniteDifferences) {
  const double R = 0.3, r = 0.1;
  for (const bool rim : {false, true}) {
    mb::Multibody b;
    const mb::BodyId p =
        b.add_rigid_body("p", 2.0, Vector3d(0.1, 0.2, 0.3),
                         rim ? Vector3d(0.6, 0.1, 0.3) : Vector3d(0.05, 0.02, 0.3),
                         Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Vector3d(1, 2, 3).normalized())),
                         Vector3d(0.3, -0.2, 0.1), Vector3d(1.0, 0.5, -2.0));
    const mb::BodyId c = b.add_rigid_body(
        "c", 1.0, Vector3d(0.2, 0.1, 0.3), Vector3d(0.0, 0.0, 0.0),
        Eigen::Quaterniond(Eigen::AngleAxisd(-0.2, Vector3d(-1, 0, 2).normalized())),
        Vector3d(-0.4, 0.6, 0.2), Vector3d(-1.5, 2.0, 0.7));
    const Vector3d po(0.02, -0.01, 0.05), pc(-0.01, 0.03, 0.02);
    const Vector3d axis = Vector3d(0.1, -0.2, 1.0).normalized();
    b.add_joint(mb::contact_disk_sphere("dc", p, po, r, c, mb::Frame::with_z(pc, axis), R, 0.5));
    const mb::MultibodyModel model = b.build();
    const System& sys = model.system;
    const Index k = sys.constraint_index("dc");
    EXPECT_TRUE(sys.constraint(k).is_unilateral());
    const VectorXd& q = model.q0;
    const VectorXd& qd = model.qd0;
    // the world geometry
    const Vector3d cw = mb::world_point(model, q, c, pc), ow = mb::world_point(model, q, p, po);
    const Vector3d kw = mb::body_pose(model, q, c).R_WB.toRotationMatrix() * axis;
    const Vector3d d = cw - ow;
    const double s = kw.dot(d), rho = (d - s * kw).norm();
    ASSERT_EQ(rho > R, rim) << "the pose is not on the " << (rim ? "rim" : "face");
    const double m = std::max(rho - R, 0.0);
    EXPECT_NEAR(testing::gap_of(sys, k, q, qd)[0], std::sqrt(s * s + m * m) - r, 1e-14);
    // g' by a central difference of the gap along q + h q'
    const double h = 1e-6;
    const double fd =
        (testing::gap_of(sys, k, q + h * qd, qd)[0] - testing::gap_of(sys, k, q - h * qd, qd)[0]) /
        (2 * h);
    EXPECT_NEAR(testing::gap_of(sys, k, q, qd)[1], fd, 1e-8);
    testing::check_form_by_differences(sys, k, q, qd, {3, 10}, 1e-8, 1e-5);
  }
}

// ---- a ball tips off a disk's edge --------------------------------------------------------------

// A frictionless ball (radius r, a particle) rests against the edge of a fixed horizontal disk
// (radius R, axis z, welded to the ground) at the angle θ₀ from the vertical through the edge
// point (R, 0, 0). Its nearest disk point stays that edge point, so its centre moves on the
// circle of radius r about it, θ'' = (g/r) sin θ, and the normal force m g (3 cos θ − 2 cos θ₀)
// vanishes at cos θ* = (2/3) cos θ₀: it leaves there, at the time the test's own RK4 gives, with
// the speed sqrt(g r cos θ*), then flies freely.
TEST(ContactDiskSphere, BallTippingOffADisksEdgeLeavesAtTwoThirdsOfTheStartsCosine) {
  const double R = 0.5, r = 0.05, th0 = 0.25, mass = 2.0, t_end = 0.6;
  const Model m = parse_model(R"(
parameters: {R: 0.5, r: 0.05, th0: 0.25}
bodies:
  - {name: plate, type: rigid, mass: 3, inertia: [1, 1, 2], position: [0, 0, 0]}
  - {name: ball, type: particle, mass: 2, position: [R + r*sin(th0), 0, r*cos(th0)]}
joints:
  - {name: hold, type: weld, parent: ground, child: plate}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: edge, body: plate, shape: disk, radius: R, axis: [0, 0, 1], sphere: {body: ball, radius: r}}
simulate: {t_end: 0.6, integrator: dopri5, rtol: 1e-12, atol: 1e-14}
output: {every: 0}
)");
  // the ball's x, y, z after the plate's 7 coordinates; the normal from the ball to the disk
  testing::expect_tips_off_edge(m, "edge", 7, Vector3d(R, 0, 0), r, th0, mass, kG, t_end, -1.0);
}

// ---- a coin dropped onto a fixed sphere ---------------------------------------------------------

// A flat coin (m, radius R, axis z; I = m R²/4 about a diameter) falls from rest at height z0
// onto a fixed sphere of radius ρ_s centred at o = (R + δ, 0, 0), beyond its edge: it touches at
// its edge point (R, 0, z) when z_c = sqrt(ρ_s² − δ²), at t = sqrt(2 (z0 − z_c)/g), with the
// normal n = (−δ, 0, z_c)/ρ_s through the edge point. The impulse P n at the lever a = (R, 0, 0):
//   1/m_eff = 1/m + |a × n|²/I,  P = −(1 + e) m_eff v_n,  v_n = n·v⁻ = −g t z_c/ρ_s,
// v⁺ = v⁻ + (P/m) n, ω⁺ = (P/I) a × n (about y), ΔT = −½ (1 − e²) m_eff v_n².
// Below the face's centre (o = 0) it bounces straight: v⁺ = −e v⁻, no spin.
TEST(ContactDiskSphere, CoinDroppedOnASphereBounceAndSpinAsTheImpulseLawSays) {
  const double mass = 0.2, R = 0.1, rs = 0.05, z0 = 0.3, e = 0.5;
  for (const double delta : {0.0, 0.02}) {
    const bool edge = delta > 0.0;
    const double ox = edge ? R + delta : 0.0;
    const Model m = parse_model(R"(
parameters: {m: 0.2, R: 0.1, e: 0.5}
bodies:
  - {name: coin, type: rigid, mass: m, inertia: [m*R^2/4, m*R^2/4, m*R^2/2], position: [0, 0, 0.3]}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: hit, body: coin, shape: disk, radius: R, axis: [0, 0, 1],
     sphere: {body: ground, point: [)" +
                                std::to_string(ox) +
                                R"(, 0, 0], radius: 0.05}, restitution: e}
simulate: {t_end: 0.25, integrator: dopri5, rtol: 1e-12, atol: 1e-14}
output: {every: 0}
)");
    const Index k = m.system.constraint_index("hit");
    const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
    ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    const auto impacts = events_of(tr, k, ContactEvent::Kind::kImpact);
    ASSERT_EQ(impacts.size(), 1u) << "delta " << delta;
    const double zc = edge ? std::sqrt(rs * rs - delta * delta) : rs;
    const double t_hit = std::sqrt(2.0 * (z0 - zc) / kG), v = kG * t_hit;
    const Vector3d n = edge ? Vector3d(Vector3d(-delta, 0, zc) / rs) : Vector3d(Vector3d::UnitZ());
    const Vector3d a = edge ? Vector3d(R, 0, 0) : Vector3d::Zero();
    const double I = mass * R * R / 4.0;
    const double m_eff = 1.0 / (1.0 / mass + a.cross(n).squaredNorm() / I);
    const double vn = -v * n.z();
    const double P = -(1.0 + e) * m_eff * vn;
    EXPECT_NEAR(impacts[0].t, t_hit, 1e-10) << "delta " << delta;
    EXPECT_NEAR(impacts[0].speed_before, vn, 1e-9) << "delta " << delta;
    EXPECT_NEAR(impacts[0].speed_after, -e * vn, 1e-9) << "delta " << delta;
    EXPECT_NEAR(impacts[0].impulse, P, 1e-9) << "delta " << delta;
    EXPECT_NEAR(impacts[0].energy_change, -0.5 * (1 - e * e) * m_eff * vn * vn, 1e-10)
        << "delta " << delta;
    // just after the impact: the velocity and the spin ω = (P/I) a × n
    std::size_t i = 0;
    while (i < tr.t.size() && tr.t[i] <= impacts[0].t) ++i;
    ASSERT_LT(i, tr.t.size());
    const double dt = tr.t[i] - impacts[0].t;
    const Vector3d v_after = Vector3d(0, 0, -v) + (P / mass) * n;
    EXPECT_NEAR(tr.qd[7 * i], v_after.x(), 1e-9) << "delta " << delta;
    EXPECT_NEAR(tr.qd[7 * i + 2], v_after.z() - kG * dt, 1e-7) << "delta " << delta;
    // ω_y = 2 (u0 u2' − u0' u2 + u3 u1' − u1 u3')
    const double* u = &tr.q[7 * i + 3];
    const double* ud = &tr.qd[7 * i + 3];
    const double wy = 2.0 * (u[0] * ud[2] - ud[0] * u[2] + u[3] * ud[1] - u[1] * ud[3]);
    EXPECT_NEAR(wy, (P / I) * a.cross(n).y(), 1e-8) << "delta " << delta;
    if (edge) {
      EXPECT_GT(std::abs(wy), 1.0);  // (a real spin)
    }
    EXPECT_NEAR(tr.work_impact.back(), impacts[0].energy_change, 1e-12);
    EXPECT_NEAR(tr.energy.back() - tr.energy.front(), tr.work_impact.back(), 1e-9);
  }
}

// ---- a ball launched on a rough disk's face -----------------------------------------------------

// A ball (m, r, I = 2/5 m r²) resting on the face of a big fixed disk (welded; axis z, its face
// the plane z = 0), launched along x at v0 without spin: it slides with v = v0 − μ g t while
// ω_y = 5 μ g t/(2 r) grows, rolls from t* = 2 v0/(7 μ g) at 5/7 v0; friction work −m v0²/7.
TEST(ContactDiskSphere, BallOnARoughDisksFaceRollsFromTheClosedFormInstant) {
  Model m = parse_model(R"(
parameters: {m: 0.5, r: 0.1, v0: 2, mu: 0.2}
bodies:
  - {name: plate, type: rigid, mass: 3, inertia: [1, 1, 2], position: [0, 0, 0]}
  - {name: ball, type: rigid, mass: m, inertia: [0.4*m*r^2, 0.4*m*r^2, 0.4*m*r^2],
     position: [0, 0, r], velocity: [v0, 0, 0]}
joints:
  - {name: hold, type: weld, parent: ground, child: plate}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: face, body: plate, shape: disk, radius: 5, axis: [0, 0, 1], sphere: {body: ball, radius: r}}
nonideal:
  - {friction: coulomb, constraint: face, mu: mu}
simulate: {t_end: 0.5, integrator: dopri5, rtol: 1e-11, atol: 1e-13}
output: {every: 0}
)");
  testing::expect_rolls_from_closed_form(m, "face", 7, 0.5, 0.1, 2.0, 0.2, kG);
}

// ---- errors -------------------------------------------------------------------------------------

TEST(ContactDiskSphere, BadDiskSphereContactsGetAClearErrorWithItsPlace) {
  const std::string head =
      "bodies:\n"
      "  - {name: a, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 1]}\n"
      "  - {name: b, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 3]}\n"
      "  - {name: p, type: particle, mass: 1, position: [0, 0, 3]}\n"
      "contacts:\n"
      "  - ";
  testing::expect_model_error(
      head +
          "{name: c, body: a, shape: disk, radius: 0.1, sphere: {body: b, radius: 3, "
          "inside: true}}\n",
      "6:87", "contact 'c': a disk inside a sphere is not supported");
  testing::expect_model_error(
      head +
          "{name: c, body: a, shape: box, size: [0.1, 0.1, 0.1], sphere: {body: b, radius: "
          "1}}\n",
      "6:67", "contact 'c': a box against a sphere is not supported");
  testing::expect_model_error(
      head + "{name: c, body: p, shape: disk, radius: 0.1, sphere: {body: b, radius: 1}}\n", "6:31",
      "a particle has no orientation, so it cannot carry a disk");
  // the sphere's centre on the disk's rim at the start: no normal, refused at the build
  mb::Multibody rimmed;
  const mb::BodyId d = rimmed.add_rigid_body("d", 1.0, Vector3d(1, 1, 1), Vector3d::Zero(),
                                             Eigen::Quaterniond::Identity());
  rimmed.add_joint(mb::contact_disk_sphere("touch", mb::kGround, Vector3d(0.1, 0, 0), 0.0, d,
                                           mb::Frame::at(Vector3d::Zero()), 0.1));
  try {
    (void)rimmed.build();
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("contact 'touch': the sphere's centre lies on the disk's "
                                         "rim at the start"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

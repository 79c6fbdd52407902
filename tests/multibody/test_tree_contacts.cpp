// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts on a kinematic tree (tree::contact_constraint, issue #31 item 3): A and b
// against differences of the gap (a world floor, a tilted world plane, a plane on a moving link of
// the 7-DOF arm), the gap of a plane fixed on another link against its formula written out by
// hand at several poses, and a two-link arm whose tip hits the floor: the velocity jump against
// q'⁺ = q'⁻ − (1 + e) M⁻¹Jᵀ (J q'⁻) / (J M⁻¹Jᵀ) computed here from mass_matrix and
// frame_jacobian, the tip's normal speed after −e times before, the energy balance certified.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/multibody/tree_closures.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::tree {
namespace UKDYN_TEST_FILE {

const std::string kData = UKDYN_TEST_DATA_DIR;

// a rotation about y by a (x → (cos a, 0, −sin a), z → (sin a, 0, cos a))
Matrix3d rot_y(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitY()).toRotationMatrix(); }

// the plane frame whose z axis is the unit normal n (any x, y ⊥ n)
LinkFrame plane_frame(Index link, const Vector3d& p, const Vector3d& n) {
  const Vector3d z = n.normalized();
  const Vector3d seed = std::abs(z.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
  const Vector3d x = (seed - z * z.dot(seed)).normalized();
  LinkFrame f{link, p, Matrix3d::Identity()};
  f.R << x, z.cross(x), z;
  return f;
}

// A against central differences of the gap along q' (g' = A q'), and b against the second
// difference of g along q(t) = q + q' t + q'' t²/2: g'' = A q'' − b
void expect_acceleration_form_consistent(const Constraint& c, const VectorXd& q,
                                         const VectorXd& qd) {
  const Index n = q.size();
  auto scratch = c.model().make_scratch(n);
  MatrixXd A(1, n);
  VectorXd b(1), pos(1), vel(1);
  c.model().acceleration_form(q, qd, 0.0, scratch.get(), A, b);
  c.model().violation(q, qd, 0.0, scratch.get(), pos, vel);
  EXPECT_NEAR((A * qd - vel).norm(), 0.0, 1e-13 * (1.0 + vel.norm()));
  const double h = 1e-5;
  VectorXd gp(1), gm(1), g0(1), unused(1);
  const VectorXd zero = VectorXd::Zero(n);
  // g' by central differences along q'
  c.model().violation(q + qd * h, zero, 0.0, scratch.get(), gp, unused);
  c.model().violation(q - qd * h, zero, 0.0, scratch.get(), gm, unused);
  EXPECT_NEAR((gp[0] - gm[0]) / (2 * h), vel[0], 1e-8 * (1.0 + std::abs(vel[0])));
  // g'' along a motion with q'' = linspace(−1, 1.5)
  const VectorXd qdd = VectorXd::LinSpaced(n, -1.0, 1.5);
  const double k = 1e-4;
  c.model().violation(q + qd * k + qdd * (k * k / 2), zero, 0.0, scratch.get(), gp, unused);
  c.model().violation(q - qd * k + qdd * (k * k / 2), zero, 0.0, scratch.get(), gm, unused);
  c.model().violation(q, zero, 0.0, scratch.get(), g0, unused);
  const double second = (gp[0] - 2.0 * g0[0] + gm[0]) / (k * k);
  const double expected = (A * qdd)[0] - b[0];
  EXPECT_NEAR(second, expected, 1e-5 * (1.0 + std::abs(expected)));
  // (b is not trivially zero here: the test means something)
  EXPECT_GT(std::abs(b[0]), 1e-3);
}

TEST(TreeContacts, AccelerationFormAgreesWithDifferencesOfTheGap) {
  const Tree panda = load_urdf(kData + "/panda_arm.urdf");
  const Index tool = panda.link_index("panda_tool"), l3 = panda.link_index("panda_link3");
  VectorXd q(7), qd(7);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd << 0.4, -0.3, 0.5, 0.2, -0.6, 0.3, 0.7;
  const LinkPoint tip{tool, Vector3d(0.01, 0.02, 0.05)};
  // the world floor, a tilted world plane, a plane on link 3 (moving: n' and n'' enter A and b)
  for (const LinkFrame& plane :
       {plane_frame(-1, Vector3d::Zero(), Vector3d::UnitZ()),
        plane_frame(-1, Vector3d(0.3, -0.1, 0.2), Vector3d(0.3, -0.5, 1.0)),
        plane_frame(l3, Vector3d(0.05, 0.1, -0.02), Vector3d(0.2, 1.0, -0.4))}) {
    const Constraint c = contact_constraint(panda, "touch", tip, 0.02, plane, 0.3);
    EXPECT_TRUE(c.is_unilateral());
    EXPECT_EQ(c.restitution(), 0.3);
    EXPECT_EQ(c.rows(), 1);
    expect_acceleration_form_consistent(c, q, qd);
  }
}

TEST(TreeContacts, GapOfAPlaneOnAnotherLinkMatchesItsFormula) {
  // the two-link arm: shoulder at (0, 0, 0.7), upper 0.5 m, fore 0.4 m, hinges about y
  const Tree arm = load_urdf(kData + "/contact_arm.urdf");
  const Index upper = arm.link_index("upper"), fore = arm.link_index("fore");
  const double r = 0.03, a = 0.4;
  const Vector3d o_L(0.2, 0.0, 0.05), n_L = rot_y(a) * Vector3d::UnitZ();
  const Constraint c = contact_constraint(arm, "touch", {fore, Vector3d(0.4, 0, 0)}, r,
                                          plane_frame(upper, o_L, n_L));
  auto scratch = c.model().make_scratch(2);
  VectorXd g(1), gd(1);
  const Vector3d shoulder(0, 0, 0.7);
  for (const auto& pose : {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(0.3, -1.2),
                           Eigen::Vector2d(-0.7, 2.1), Eigen::Vector2d(1.9, 0.4)}) {
    const VectorXd q = pose, qd = Eigen::Vector2d(0.8, -1.1);
    c.model().violation(q, qd, 0.0, scratch.get(), g, gd);
    // by hand: n_W = R_y(q1 + a) e_z, o_W, the tip's centre
    const double q1 = pose[0], q2 = pose[1];
    const Vector3d n_W(std::sin(q1 + a), 0.0, std::cos(q1 + a));
    const Vector3d o_W = shoulder + rot_y(q1) * o_L;
    const Vector3d tip =
        shoulder + rot_y(q1) * Vector3d(0.5, 0, 0) + rot_y(q1 + q2) * Vector3d(0.4, 0, 0);
    EXPECT_NEAR(g[0], n_W.dot(tip - o_W) - r, 1e-14) << "q = " << pose.transpose();
    // g' = ∂g/∂q1 q1' + ∂g/∂q2 q2' by central differences of the formula
    const auto gap = [&](double a1, double a2) {
      const Vector3d n(std::sin(a1 + a), 0.0, std::cos(a1 + a));
      const Vector3d t =
          shoulder + rot_y(a1) * Vector3d(0.5, 0, 0) + rot_y(a1 + a2) * Vector3d(0.4, 0, 0);
      return n.dot(t - (shoulder + rot_y(a1) * o_L)) - r;
    };
    const double h = 1e-6;
    const double rate =
        (gap(q1 + 0.8 * h, q2 - 1.1 * h) - gap(q1 - 0.8 * h, q2 + 1.1 * h)) / (2 * h);
    EXPECT_NEAR(gd[0], rate, 1e-8) << "q = " << pose.transpose();
    // the gap depends on q2 only through the tip (the plane moves with the upper link): at
    // q2 = 0 the tip lies on the upper link's x axis, g = n_L · ((0.9, 0, 0) − o_L) − r
    if (pose[1] == 0.0) EXPECT_NEAR(g[0], n_L.dot(Vector3d(0.9, 0, 0) - o_L) - r, 1e-14);
  }
}

TEST(TreeContacts, RefusesBadArgumentsNamingTheContact) {
  const Tree arm = load_urdf(kData + "/contact_arm.urdf");
  const Index fore = arm.link_index("fore");
  const LinkFrame floor{};
  const auto message = [&](auto&& make) {
    try {
      make();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([&] {
              contact_constraint(arm, "tip", {fore, Vector3d::Zero()}, -0.1, floor);
            }).find("'tip': the radius must be"),
            std::string::npos);
  EXPECT_NE(message([&] {
              contact_constraint(arm, "tip", {-1, Vector3d::Zero()}, 0.1, floor);
            }).find("both points are on the world"),
            std::string::npos);
  EXPECT_NE(message([&] {
              contact_constraint(arm, "tip", {fore, Vector3d::Zero()}, 0.1, floor, 1.5);
            }).find("restitution must lie in [0, 1]"),
            std::string::npos);
  LinkFrame skew = floor;
  skew.R(0, 0) = 2.0;
  EXPECT_NE(message([&] {
              contact_constraint(arm, "tip", {fore, Vector3d::Zero()}, 0.1, skew);
            }).find("not a rotation"),
            std::string::npos);
}

// the two-link arm released from rest, horizontal: the forearm's tip (a sphere, r = 0.03) hits
// the floor z = 0 with e = 0.5
TEST(TreeContacts, TwoLinkArmTipImpactMatchesTheImpulseFormula) {
  const Tree arm = load_urdf(kData + "/contact_arm.urdf");
  const Index fore = arm.link_index("fore");
  const double r = 0.03, e = 0.5;
  const Vector3d tip_L(0.4, 0, 0);
  SystemBuilder sb = system_builder(arm);
  sb.add(contact_constraint(arm, "floor", {fore, tip_L}, r, LinkFrame{}, e));
  const System sys = sb.build();
  const VectorXd q0 = VectorXd::Zero(2), qd0 = VectorXd::Zero(2);
  SimulationOptions opt;
  opt.t_end = 0.6;
  opt.rtol = 1e-11;
  opt.atol = 1e-13;
  opt.output_every = 0.0;
  const Trajectory first = simulate(sys, q0, qd0, opt);
  ASSERT_EQ(first.stats.status, Status::kOk) << first.stats.message;
  ASSERT_FALSE(first.stats.contact_events.empty());
  const ContactEvent hit = first.stats.contact_events.front();
  ASSERT_EQ(hit.kind, ContactEvent::Kind::kImpact);
  EXPECT_LT(hit.speed_before, -0.5);  // (a real impact)
  EXPECT_NEAR(hit.speed_after, -e * hit.speed_before, 1e-10);
  // the states just before and after it
  const double dt = 1e-9;
  opt.output_at = {hit.t - dt, hit.t + dt};
  const Trajectory tr = simulate(sys, q0, qd0, opt);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  std::size_t i = 0;
  while (i < tr.t.size() && tr.t[i] < hit.t - 2 * dt) ++i;
  ASSERT_LT(i + 1, tr.t.size());
  ASSERT_NEAR(tr.t[i], hit.t - dt, 1e-15);
  ASSERT_NEAR(tr.t[i + 1], hit.t + dt, 1e-15);
  const VectorXd q = Eigen::Map<const VectorXd>(&tr.q[2 * i], 2);
  const VectorXd before = Eigen::Map<const VectorXd>(&tr.qd[2 * i], 2);
  const VectorXd after = Eigen::Map<const VectorXd>(&tr.qd[2 * (i + 1)], 2);
  // the tip touches the floor there: its height is r
  TreeData d(arm);
  forward_kinematics(arm, q, d);
  EXPECT_NEAR(world_point(d, fore, tip_L).z(), r, 1e-8);
  // J = e_zᵀ J_v(tip), M from the composite-rigid-body pass, the impulse formula
  Eigen::Matrix<double, 6, Eigen::Dynamic> Jf(6, 2);
  frame_jacobian(arm, d, fore, tip_L, Jf);
  const Eigen::RowVectorXd J = Jf.row(5);
  MatrixXd M(2, 2);
  mass_matrix(arm, q, d, M);
  const VectorXd MinvJt = M.llt().solve(J.transpose());
  const VectorXd expected = before - (1.0 + e) * MinvJt * J.dot(before) / J.dot(MinvJt);
  // (the samples are 1e-9 s from the impact: q'' · 1e-9 ≈ 1e-8)
  EXPECT_NEAR((after - expected).norm(), 0.0, 1e-7 * before.norm());
  EXPECT_NEAR(J.dot(before), hit.speed_before, 1e-7);
  EXPECT_NEAR(J.dot(after), -e * J.dot(before), 1e-7);
  // the energy lost at the impact ½ (1 − e²) (J q'⁻)² / (J M⁻¹ Jᵀ), and the run's balance
  EXPECT_NEAR(hit.energy_change,
              -0.5 * (1.0 - e * e) * hit.speed_before * hit.speed_before / J.dot(MinvJt),
              1e-7 * std::abs(hit.energy_change));  // (J, M at the sample 1e-9 s before)
  EXPECT_TRUE(tr.stats.energy_balance_checked);
  double sum = 0.0;
  for (const auto& ev : tr.stats.contact_events) sum += ev.energy_change;
  EXPECT_NEAR(tr.work_impact.back(), sum, 1e-9);
  EXPECT_NEAR(tr.energy.back() - tr.energy.front(), tr.work_impact.back(), 1e-7);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::tree

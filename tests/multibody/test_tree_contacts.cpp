// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts on a kinematic tree (tree::contact_constraint, issue #31 item 3): A and b
// against differences of the gap (a world floor, a tilted world plane, a plane on a moving link of
// the 7-DOF arm), the gap of a plane fixed on another link against its formula written out by
// hand at several poses, and a two-link arm whose tip hits the floor: the velocity jump against
// q'⁺ = q'⁻ − (1 + e) M⁻¹Jᵀ (J q'⁻) / (J M⁻¹Jᵀ) computed here from mass_matrix and
// frame_jacobian, the tip's normal speed after −e times before, the energy balance certified.
// Disks (tree::disk_contact_constraint): A and b against fourth-order differences of the gap at
// random states of the 7-DOF arm and the gap against the lowest of the rim's points; a tilted
// disk on a slider dropped on the floor: its impact time in closed form and the velocity jump
// against the impulse formula; the same disk on a floating base against a bodies model's disk.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/multibody/multibody.hpp"
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

// a run's first contact event, an impact, and the states 1e-9 s on either side of it (the
// samples output_at puts there)
struct AroundImpact {
  ContactEvent hit;           // the first contact event
  double t = 0.0;             // the sample before it
  VectorXd q, before, after;  // q there, q' there and at the sample after the impact
  Trajectory run;             // the run with those two samples
};
void around_first_impact(const System& sys, const VectorXd& q0, const VectorXd& qd0,
                         SimulationOptions opt, AroundImpact& out) {
  const Index n = q0.size();
  const Trajectory first = simulate(sys, q0, qd0, opt);
  ASSERT_EQ(first.stats.status, Status::kOk) << first.stats.message;
  ASSERT_FALSE(first.stats.contact_events.empty());
  out.hit = first.stats.contact_events.front();
  ASSERT_EQ(out.hit.kind, ContactEvent::Kind::kImpact);
  const double dt = 1e-9;
  opt.output_at = {out.hit.t - dt, out.hit.t + dt};
  out.run = simulate(sys, q0, qd0, opt);
  const Trajectory& tr = out.run;
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  std::size_t i = 0;
  while (i < tr.t.size() && tr.t[i] < out.hit.t - 2 * dt) ++i;
  ASSERT_LT(i + 1, tr.t.size());
  ASSERT_NEAR(tr.t[i], out.hit.t - dt, 1e-15);
  ASSERT_NEAR(tr.t[i + 1], out.hit.t + dt, 1e-15);
  out.t = tr.t[i];
  out.q = Eigen::Map<const VectorXd>(&tr.q[std::size_t(n) * i], n);
  out.before = Eigen::Map<const VectorXd>(&tr.qd[std::size_t(n) * i], n);
  out.after = Eigen::Map<const VectorXd>(&tr.qd[std::size_t(n) * (i + 1)], n);
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
  // the states just before and after the first impact
  AroundImpact s;
  ASSERT_NO_FATAL_FAILURE(around_first_impact(sys, q0, qd0, opt, s));
  const ContactEvent& hit = s.hit;
  EXPECT_LT(hit.speed_before, -0.5);  // (a real impact)
  EXPECT_NEAR(hit.speed_after, -e * hit.speed_before, 1e-10);
  const Trajectory& tr = s.run;
  const VectorXd &q = s.q, &before = s.before, &after = s.after;
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

// ---- disks ----------------------------------------------------------------------------------

// g and g' of a one-row constraint at (q, q')
Eigen::Vector2d gap_and_rate(const Constraint& c, ConstraintScratch* s, const VectorXd& q,
                             const VectorXd& qd) {
  VectorXd pos(1), vel(1);
  c.model().violation(q, qd, 0.0, s, pos, vel);
  return {pos[0], vel[0]};
}

TEST(TreeContacts, DiskAccelerationFormAgreesWithDifferencesOfTheGap) {
  const Tree panda = load_urdf(kData + "/panda_arm.urdf");
  const Index tool = panda.link_index("panda_tool"), l3 = panda.link_index("panda_link3");
  const LinkDisk disk{tool, Vector3d(0.01, 0.02, 0.05), Vector3d(0.3, -0.2, 1.0), 0.04};
  const std::vector<LinkFrame> planes = {
      plane_frame(-1, Vector3d::Zero(), Vector3d::UnitZ()),
      plane_frame(-1, Vector3d(0.3, -0.1, 0.2), Vector3d(0.3, -0.5, 1.0)),
      plane_frame(l3, Vector3d(0.05, 0.1, -0.02), Vector3d(0.2, 1.0, -0.4))};
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto random = [&](double scale) {
    VectorXd v(7);
    for (Index i = 0; i < 7; ++i) v[i] = scale * u(rng);
    return v;
  };
  TreeData d(panda);
  int checked = 0;
  for (int trial = 0; trial < 5; ++trial) {
    const VectorXd q = random(1.5), qd = random(1.0), qdd = random(2.0);
    for (const LinkFrame& plane : planes) {
      const Constraint c = disk_contact_constraint(panda, "rim", disk, plane, q, 0.3);
      EXPECT_TRUE(c.is_unilateral());
      EXPECT_EQ(c.restitution(), 0.3);
      auto scratch = c.model().make_scratch(7);
      MatrixXd A(1, 7);
      VectorXd b(1);
      c.model().acceleration_form(q, qd, 0.0, scratch.get(), A, b);
      const Eigen::Vector2d g = gap_and_rate(c, scratch.get(), q, qd);
      // the gap: the lowest of the rim's points above the plane, from forward kinematics
      forward_kinematics(panda, q, d);
      const Vector3d c_W = world_point(d, tool, disk.centre);
      const Vector3d a_W = d.R_WL[std::size_t(tool)] * disk.axis.normalized();
      const Matrix3d R_o = plane.link < 0 ? plane.R : Matrix3d(d.R_WL[std::size_t(l3)] * plane.R);
      const Vector3d o_W = plane.link < 0 ? plane.p : world_point(d, l3, plane.p);
      const Vector3d n_W = R_o.col(2);
      const Vector3d e1 = a_W.unitOrthogonal(), e2 = a_W.cross(e1);
      double lowest = 1e300;
      for (int k = 0; k < 20000; ++k) {
        const double phi = 2.0 * M_PI * k / 20000.0;
        const Vector3d rim = c_W + disk.radius * (std::cos(phi) * e1 + std::sin(phi) * e2);
        lowest = std::min(lowest, n_W.dot(rim - o_W));
      }
      EXPECT_NEAR(g[0], lowest, 1e-9);
      // g' = A q', and g' against differences of g along q' (fourth order)
      const VectorXd zero = VectorXd::Zero(7);
      const auto gap = [&](double t) {
        return gap_and_rate(c, scratch.get(), q + qd * t + qdd * (t * t / 2), zero)[0];
      };
      EXPECT_NEAR((A * qd)[0], g[1], 1e-13 * (1.0 + std::abs(g[1])));
      const double h = 1e-3;
      const double rate = (-gap(2 * h) + 8 * gap(h) - 8 * gap(-h) + gap(-2 * h)) / (12 * h);
      EXPECT_NEAR(rate, g[1], 1e-7 * (1.0 + std::abs(g[1])));
      // g'' = A q'' − b along q(t) = q + q' t + q'' t²/2 (fourth order)
      const double second =
          (-gap(2 * h) + 16 * gap(h) - 30 * gap(0) + 16 * gap(-h) - gap(-2 * h)) / (12 * h * h);
      const double expected = (A * qdd)[0] - b[0];
      EXPECT_NEAR(second, expected, 1e-7 * (1.0 + std::abs(expected)))
          << "trial " << trial << ", plane on link " << plane.link;
      // (b is not trivially zero: the test means something)
      EXPECT_GT(std::abs(b[0]), 1e-3);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 15);
}

TEST(TreeContacts, DiskRefusesBadArgumentsNamingTheContact) {
  const Tree rig = load_urdf(kData + "/contact_slider_disk.urdf");
  const Index wheel = rig.link_index("wheel");
  const auto message = [&](const LinkDisk& disk, const VectorXd& q0) {
    try {
      disk_contact_constraint(rig, "rim", disk, LinkFrame{}, q0);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const VectorXd tilted = Eigen::Vector2d(0.0, 0.3);
  // flat at the start: q0 with the wheel's axis along the floor's normal, |n·a| = 1
  const std::string flat =
      message({wheel, Vector3d::Zero(), Vector3d::UnitZ(), 0.2}, VectorXd::Zero(2));
  EXPECT_NE(flat.find("constraint 'rim': the disk lies flat on its plane at the start"),
            std::string::npos)
      << flat;
  EXPECT_EQ(message({wheel, Vector3d::Zero(), Vector3d::UnitZ(), 0.2}, tilted), "no error");
  EXPECT_NE(message({wheel, Vector3d::Zero(), Vector3d::UnitZ(), 0.0}, tilted)
                .find("'rim': the disk's radius must be a finite number > 0"),
            std::string::npos);
  EXPECT_NE(message({wheel, Vector3d::Zero(), Vector3d::Zero(), 0.2}, tilted)
                .find("'rim': the disk's axis must be a finite, nonzero vector"),
            std::string::npos);
  EXPECT_NE(message({wheel, Vector3d::Zero(), Vector3d::UnitZ(), 0.2}, VectorXd::Zero(3))
                .find("'rim': q0 must hold 2 finite coordinates"),
            std::string::npos);
}

// the slider's disk (contact_slider_disk.urdf: carriage 2 kg on a vertical slider from 0.5 m,
// wheel 1.5 kg, radius 0.2, turning about x at the carriage's origin), tilted by β about x and
// released from rest: it falls freely (its centre of mass on the hinge: no torque) until the
// rim's lowest point, r sin β below the centre, meets the floor at t₀ = √(2 (0.5 − r sin β) / g);
// there g = z_c − r sin θ, so J = [1, −r cos β], and the jump is the impulse formula
TEST(TreeContacts, TiltedDiskOnASliderMeetsTheImpulseFormula) {
  const Tree rig = load_urdf(kData + "/contact_slider_disk.urdf");
  const Index wheel = rig.link_index("wheel");
  const double beta = 0.5, r = 0.2, e = 0.4, g = 9.81;
  const VectorXd q0 = Eigen::Vector2d(0.0, beta), qd0 = VectorXd::Zero(2);
  SystemBuilder sb = system_builder(rig);
  const Constraint rim = disk_contact_constraint(
      rig, "rim", {wheel, Vector3d::Zero(), Vector3d::UnitZ(), r}, LinkFrame{}, q0, e);
  sb.add(rim);
  const System sys = sb.build();
  SimulationOptions opt;
  opt.integrator = Integrator::kDopri5;
  opt.rtol = 1e-11;
  opt.atol = 1e-13;
  const double t0 = std::sqrt(2.0 * (0.5 - r * std::sin(beta)) / g);
  opt.t_end = t0 + 0.01;
  opt.output_every = 0.0;
  // the first impact and the states just before and after it
  AroundImpact s;
  ASSERT_NO_FATAL_FAILURE(around_first_impact(sys, q0, qd0, opt, s));
  const ContactEvent& hit = s.hit;
  EXPECT_NEAR(hit.t, t0, 1e-9);
  EXPECT_NEAR(hit.speed_before, -g * t0, 1e-8);
  EXPECT_NEAR(hit.speed_after, -e * hit.speed_before, 1e-10);
  const Trajectory& tr = s.run;
  const VectorXd &q = s.q, &before = s.before, &after = s.after;
  // free fall before it: q = (−g t²/2, β), q' = (−g t, 0)
  EXPECT_NEAR(q[0], -0.5 * g * s.t * s.t, 1e-9);
  EXPECT_NEAR(q[1], beta, 1e-10);
  EXPECT_NEAR(before[0], -g * s.t, 1e-8);
  EXPECT_NEAR(before[1], 0.0, 1e-10);
  // the disk row's J (A at the contact pose) and its closed form
  auto scratch = rim.model().make_scratch(2);
  MatrixXd A(1, 2);
  VectorXd b(1);
  rim.model().acceleration_form(q, before, 0.0, scratch.get(), A, b);
  const Eigen::RowVectorXd J = A.row(0);
  EXPECT_NEAR(J[0], 1.0, 1e-12);
  EXPECT_NEAR(J[1], -r * std::cos(q[1]), 1e-12);
  // q'⁺ = q'⁻ − (1 + e) M⁻¹Jᵀ (J q'⁻) / (J M⁻¹Jᵀ), M from the composite-rigid-body pass
  TreeData d(rig);
  MatrixXd M(2, 2);
  mass_matrix(rig, q, d, M);
  EXPECT_NEAR(M(0, 0), 3.5, 1e-12);  // (the carriage and the wheel)
  EXPECT_NEAR(M(1, 1), 0.015, 1e-12);
  const VectorXd MinvJt = M.llt().solve(J.transpose());
  const VectorXd expected = before - (1.0 + e) * MinvJt * J.dot(before) / J.dot(MinvJt);
  EXPECT_NEAR((after - expected).norm(), 0.0, 1e-7 * before.norm());
  EXPECT_GT(std::abs(after[1]), 1.0);  // (the impact spins the wheel)
  EXPECT_NEAR(hit.energy_change,
              -0.5 * (1.0 - e * e) * hit.speed_before * hit.speed_before / J.dot(MinvJt),
              1e-7 * std::abs(hit.energy_change));
  EXPECT_NEAR(tr.energy.back() - tr.energy.front(), tr.work_impact.back(), 1e-7);
}

// a coin (1.5 kg, radius 0.2) on a floating base, dropped tilted with a velocity and a spin,
// against the same coin as a rigid body of a bodies model (mb::contact_disk): the same
// coordinates (x, y, z, u0 … u3), the same first impact and the same motion after it
TEST(TreeContacts, DiskOnAFloatingBaseAgreesWithTheSameDiskOnABody) {
  const double m = 1.5, R = 0.2, beta = 0.6, z0 = 0.5, e = 0.3;
  const Vector3d inertia(m * R * R / 4, m * R * R / 4, m * R * R / 2);
  const Vector3d v0(0.3, -0.2, 0.4), w0(1.5, -2.0, 4.0);
  // the bodies model
  mb::Multibody bodies;
  const mb::BodyId coin =
      bodies.add_rigid_body("coin", m, inertia, Vector3d(0.1, -0.2, z0),
                            Eigen::Quaterniond(Eigen::AngleAxisd(beta, Vector3d::UnitX())), v0, w0);
  bodies.set_gravity(Vector3d(0, 0, -9.81));
  bodies.add_joint(mb::contact_disk("floor", mb::kGround, mb::Frame{}, coin, mb::Frame{}, R, e));
  const mb::MultibodyModel body_model = bodies.build();
  // the robot: one floating link with the same inertia
  std::vector<Link> links(1);
  links[0].name = "coin";
  links[0].joint.name = "free";
  links[0].joint.kind = JointKind::kFloating;
  links[0].inertial.mass = m;
  links[0].inertial.I_com = inertia.asDiagonal();
  const Tree tree("coin", links);
  ASSERT_EQ(tree.coordinate_count(), 7);
  ASSERT_EQ(body_model.system.coordinate_count(), 7);
  const VectorXd q0 = body_model.q0, qd0 = body_model.qd0;
  SystemBuilder sb = system_builder(tree);
  sb.add(disk_contact_constraint(tree, "floor", {0, Vector3d::Zero(), Vector3d::UnitZ(), R},
                                 LinkFrame{}, q0, e));
  const System robot = sb.build();
  // the same gap at the start
  const Index k_body = body_model.system.constraint_index("floor");
  const Index k_robot = robot.constraint_index("floor");
  {
    auto s1 = body_model.system.constraint(k_body).model().make_scratch(7);
    auto s2 = robot.constraint(k_robot).model().make_scratch(7);
    const Eigen::Vector2d g1 =
        gap_and_rate(body_model.system.constraint(k_body), s1.get(), q0, qd0);
    const Eigen::Vector2d g2 = gap_and_rate(robot.constraint(k_robot), s2.get(), q0, qd0);
    EXPECT_NEAR(g1[0], z0 - R * std::sin(beta), 1e-14);
    EXPECT_NEAR((g1 - g2).norm(), 0.0, 1e-13);
  }
  SimulationOptions opt;
  opt.integrator = Integrator::kDopri5;
  opt.rtol = 1e-11;
  opt.atol = 1e-13;
  opt.t_end = 0.45;
  opt.output_every = 0.05;
  const Trajectory a = simulate(body_model.system, q0, qd0, opt);
  const Trajectory b = simulate(robot, q0, qd0, opt);
  ASSERT_EQ(a.stats.status, Status::kOk) << a.stats.message;
  ASSERT_EQ(b.stats.status, Status::kOk) << b.stats.message;
  ASSERT_FALSE(a.stats.contact_events.empty());
  ASSERT_EQ(a.stats.contact_events.size(), b.stats.contact_events.size());
  const ContactEvent& ha = a.stats.contact_events.front();
  const ContactEvent& hb = b.stats.contact_events.front();
  ASSERT_EQ(ha.kind, ContactEvent::Kind::kImpact);
  ASSERT_EQ(hb.kind, ContactEvent::Kind::kImpact);
  EXPECT_GT(ha.t, 0.15);  // (the impact lies inside the run, samples after it)
  EXPECT_NEAR(hb.t, ha.t, 1e-8);
  EXPECT_NEAR(hb.speed_before, ha.speed_before, 1e-8);
  EXPECT_NEAR(hb.speed_after, ha.speed_after, 1e-8);
  EXPECT_NEAR(hb.impulse, ha.impulse, 1e-8);
  EXPECT_NEAR(hb.energy_change, ha.energy_change, 1e-8);
  // the states sample by sample, after the impact too
  ASSERT_EQ(a.t.size(), b.t.size());
  int after = 0;
  for (std::size_t s = 0; s < a.t.size(); ++s) {
    ASSERT_NEAR(a.t[s], b.t[s], 1e-15);
    const Eigen::Map<const VectorXd> qa(&a.q[7 * s], 7), qb(&b.q[7 * s], 7);
    const Eigen::Map<const VectorXd> va(&a.qd[7 * s], 7), vb(&b.qd[7 * s], 7);
    EXPECT_NEAR((qa - qb).norm(), 0.0, 1e-8) << "t = " << a.t[s];
    EXPECT_NEAR((va - vb).norm(), 0.0, 1e-8) << "t = " << a.t[s];
    if (a.t[s] > ha.t) ++after;
  }
  EXPECT_GE(after, 3);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn::tree

// SPDX-License-Identifier: BSD-3-Clause
// A requirement that lifts a body off a tilted contact (issue #31; defect 01 of session 16;
// docs/contact.md "Contacts under control"): the requirement row duplicates the closed contact's
// row but for roundoff — a gap n·(x, y) with n tilted against the coordinates, or a two-link arm's
// tip height — so with the contact held its row of X = A_r P is ~1e-17, not 0. The law's rank
// decision is relative to the largest row, and a lone such row counted as rank 1: the control
// answered e / 1e-17 and the run diverged at t = 5e-7 s (from t1 = 0.5: a step size underflow;
// the arm: a hang at 1e-9 s). Against the closed form: the release at the start of the lift, then
// the gap = c (t − t1)³ exactly, the particle sliding down the slope with s'' = g sin a, the
// control along the normal, F_n = m (6 c (t − t1) + g cos a), the contact force 0.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "ukdyn/control/control.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/ukdyn.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr double kG = 9.81, kM = 2.0, kC = 2.0;
// ControlOptions::feasibility_tolerance (default)
constexpr double kTol = 1e-8;

// A particle (m = 2) resting on the incline n·(x, y) >= 0, n = (sin a, cos a), its gap required
// to open as c (t − t1)³ from t1 (an active: interval when t1 > 0).
std::string incline(double al, double t1) {
  const std::string lift = t1 > 0.0 ? "c*(t - t1)^3, active: [t1, 2]" : "c*t^3";
  return "parameters: {m: 2, g: 9.81, c: 2, al: " + std::to_string(al) +
         ", t1: " + std::to_string(t1) +
         "}\n"
         "coordinates: [x, y]\n"
         "kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)\n"
         "potential_energy: m*g*y\n"
         "constraints:\n"
         "  - {name: floor, holonomic: x*sin(al) + y*cos(al), unilateral: true}\n"
         "control:\n"
         "  requirements:\n"
         "    - {name: pz, holonomic: x*sin(al) + y*cos(al) - " +
         lift +
         ", dynamics: {omega: 20, zeta: 1}}\n"
         "  law: gauss\n"
         "simulate: {t_end: 1, integrator: dopri5, rtol: 1e-10, atol: 1e-12}\n"
         "output: {every: 0.05}\n";
}

ControlledTrajectory run(const Model& m) {
  return simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
}

// The run ends ok with its requirements met and one contact event, a release: its time (NaN
// otherwise).
double the_release(const ControlledTrajectory& r) {
  const Trajectory& p = r.plant;
  EXPECT_EQ(p.stats.status, Status::kOk) << p.stats.message;
  EXPECT_EQ(r.control.not_met, 0);
  EXPECT_EQ(p.stats.contact_events.size(), 1u);
  if (p.stats.status != Status::kOk || p.stats.contact_events.size() != 1u) return std::nan("");
  EXPECT_EQ(p.stats.contact_events[0].kind, ContactEvent::Kind::kRelease);
  return p.stats.contact_events[0].t;
}

// The arms below (L1 = 0.5, L2 = 0.4, pivot at H = 0.5): the tip's height H − L1 sin j1 −
// L2 sin(j1 + j2) is c (t − t1)³ from t1 on (0 before), and the contact carries a load before
// t1, none after.
void expect_tip_lifted(const Trajectory& p, double t1) {
  const double H = 0.5, L1 = 0.5, L2 = 0.4;
  for (Index j = 0; j < p.samples(); ++j) {
    const double t = p.t[std::size_t(j)], tau = std::max(0.0, t - t1);
    const double j1 = p.q[std::size_t(2 * j)], j2 = p.q[std::size_t(2 * j + 1)];
    EXPECT_NEAR(H - L1 * std::sin(j1) - L2 * std::sin(j1 + j2), kC * tau * tau * tau, 1e-9)
        << "t = " << t;
    if (tau > 0.0) {
      EXPECT_NEAR(p.lambda[std::size_t(j)], 0.0, 1e-12) << "t = " << t;
    } else {
      EXPECT_GT(p.lambda[std::size_t(j)], 0.0) << "t = " << t;
    }
  }
}

void expect_incline_closed_form(double al, double t1) {
  SCOPED_TRACE("a = " + std::to_string(al) + ", t1 = " + std::to_string(t1));
  const Model m = parse_model(incline(al, t1));
  const ControlledTrajectory r = run(m);
  const Trajectory& p = r.plant;
  // the release at the start of the lift: the requirement row, which the held contact decides,
  // counts as met while its e = 6 c (t − t1) is within 100 tol of its terms ‖A_r‖ ‖a_p‖ (a_p =
  // g sin a down the slope: the drift allowance of a row a contact holds, solve_law_on), i.e.
  // t − t1 = 100 tol g sin a / (6 c (1 − 101 tol)) — 3.9e-7 s at a = 0.5, 8.2e-13 s at 1e-6
  const double t_release = the_release(r);
  ASSERT_FALSE(std::isnan(t_release));
  const double delay = 100.0 * kTol * kG * std::sin(al) / (6.0 * kC * (1.0 - 101.0 * kTol));
  EXPECT_NEAR(t_release - t1, delay, 1e-3 * delay + 1e-14);
  ASSERT_EQ(p.samples(), 21);
  const double s = std::sin(al), c = std::cos(al);
  for (Index j = 0; j < p.samples(); ++j) {
    const double t = p.t[std::size_t(j)], tau = std::max(0.0, t - t1);
    const std::size_t i = std::size_t(2 * j);
    const double x = p.q[i], y = p.q[i + 1];
    // the gap c τ³; down the slope g sin a t²/2 (nothing resists the slide)
    EXPECT_NEAR(s * x + c * y, kC * tau * tau * tau, 1e-10) << "t = " << t;
    EXPECT_NEAR(c * x - s * y, 0.5 * kG * s * t * t, 1e-10) << "t = " << t;
    const double Fx = r.Qc_control[i], Fy = r.Qc_control[i + 1];
    if (tau > 0.0) {
      // lifted: F_n = m (6 c τ + g cos a), none along the slope, the contact open
      EXPECT_NEAR(s * Fx + c * Fy, kM * (6.0 * kC * tau + kG * c), 1e-7) << "t = " << t;
      EXPECT_NEAR(c * Fx - s * Fy, 0.0, 1e-7) << "t = " << t;
      EXPECT_NEAR(p.lambda[std::size_t(j)], 0.0, 1e-12) << "t = " << t;
    } else {
      // on the incline: no control, the contact carries m g cos a
      EXPECT_NEAR(std::hypot(Fx, Fy), 0.0, 1e-9) << "t = " << t;
      EXPECT_NEAR(p.lambda[std::size_t(j)], kM * kG * c, 1e-9) << "t = " << t;
    }
  }
}

TEST(ControlLift, RequirementLiftsAParticleOffAnInclineFromTheStart) {
  expect_incline_closed_form(0.5, 0.0);
}

TEST(ControlLift, RequirementLiftsAParticleOffANearlyLevelInclineFromTheStart) {
  expect_incline_closed_form(1e-6, 0.0);
}

TEST(ControlLift, RequirementActiveFromHalfASecondLiftsAParticleOffAnIncline) {
  expect_incline_closed_form(0.5, 0.5);
}

// A two-link arm (generalized coordinates j1, j2; links L1 = 0.5, L2 = 0.4 of masses 2 and 1,
// uniform rods) hanging from a pivot at height H = 0.5 above a table, its tip resting on it
// (j1 = 1), the tip's height required to rise as c t³. The tip leaves the table at the start and
// follows c t³ (to t = 0.6: 0.43 m, within the arm's reach H + L1 + L2 = 1.4 m).
constexpr const char* kArm = R"(
parameters: {L1: 0.5, L2: 0.4, H: 0.5, q10: 1.0, g: 9.81, c: 2, m1: 2, m2: 1}
coordinates: [j1, j2]
kinetic_energy: >-
  0.5*(m1*L1^2/3 + m2*L2^2/12 + m2*(L1^2 + L2^2/4 + L1*L2*cos(j2)))*j1_dot^2
  + (m2*L2^2/12 + m2*(L2^2/4 + L1*L2/2*cos(j2)))*j1_dot*j2_dot
  + 0.5*(m2*L2^2/3)*j2_dot^2
potential_energy: g*(m1*(H - L1/2*sin(j1)) + m2*(H - L1*sin(j1) - L2/2*sin(j1 + j2)))
constraints:
  - {name: tip, holonomic: H - L1*sin(j1) - L2*sin(j1 + j2), unilateral: true}
initial:
  q: {j1: q10, j2: asin((H - L1*sin(q10))/L2) - q10}
control:
  requirements:
    - {name: pz, holonomic: H - L1*sin(j1) - L2*sin(j1 + j2) - c*t^3, dynamics: {omega: 20, zeta: 1}}
  law: gauss
simulate: {t_end: 0.6, integrator: dopri5, rtol: 1e-10, atol: 1e-12}
output: {every: 0.05}
)";

TEST(ControlLift, RequirementLiftsATwoLinkArmsTipOffTheTable) {
  const ControlledTrajectory r = run(parse_model(kArm));
  // the release at the start (the drift allowance 100 tol ‖A_r‖ ‖a_p‖ / (6 c): 1.4e-6 s)
  const double t_release = the_release(r);
  EXPECT_GT(t_release, 0.0);
  EXPECT_LT(t_release, 3e-6);
  ASSERT_EQ(r.plant.samples(), 13);
  expect_tip_lifted(r.plant, 0.0);
}

// The same arm as a URDF robot (tests/data/arm_lift.urdf: the links above as rods, the pivot at
// z = H) whose tip point rests on the ground plane z = 0 (contacts:), its height required to rise
// as c (t − t1)³ from t1 = 0.5 (active:): the tip slides on the ground until t1, then is lifted
// (the robot's tree engine and the contact's point kinematics; was: "non-finite input … in Q" at
// t = 0.507 while the run stopped at 0.5).
constexpr const char* kRobotArm = R"(
parameters: {L1: 0.5, L2: 0.4, H: 0.5, q10: 1.0, g: 9.81, c: 2, t1: 0.5}
robot: {urdf: arm_lift.urdf, gravity: [0, 0, -g]}
contacts:
  - {name: tip, link: fore, point: [L2, 0, 0]}
initial:
  q: {j1: q10, j2: asin((H - L1*sin(q10))/L2) - q10}
control:
  requirements:
    - {name: pz, holonomic: H - L1*sin(j1) - L2*sin(j1 + j2) - c*(t - t1)^3, active: [t1, 2],
       dynamics: {omega: 20, zeta: 1}}
  law: gauss
simulate: {t_end: 1, integrator: dopri5, rtol: 1e-10, atol: 1e-12}
output: {every: 0.05}
)";

TEST(ControlLift, RequirementActiveFromHalfASecondLiftsARobotsTipOffTheGround) {
  const ControlledTrajectory r =
      run(parse_model(kRobotArm, std::string(UKDYN_TEST_DATA_DIR) + "/arm_lift.yaml"));
  // the release just after t1 (the drift allowance, as above); the tip slides on the ground
  // (which carries a load) until then
  const double t_release = the_release(r);
  EXPECT_GT(t_release, 0.5);
  EXPECT_LT(t_release, 0.5 + 3e-6);
  ASSERT_EQ(r.plant.samples(), 21);
  expect_tip_lifted(r.plant, 0.5);
}

// The robot arm above with joint damping and friction (0.1 N m s, 0.05 N m) and a Coulomb tip
// (mu = 1) resting on the ground, lifted from t1 = 0.5 s, in SI (tests/data/arm_lift_jf.urdf)
// and in mm, g, ms (arm_lift_jf_mm.urdf: the same arm, its numbers scaled; u16's reproducer). The
// control's effort ∫ |Qc|² dt is 10⁹ times its SI number in mm, g, ms; weighed with the
// velocities' atol, its jump at the release asked for steps below the roundoff of t ("dopri5:
// step size underflow at t = 500.0003174869367"). Each of the control's integrals is now weighed
// in a unit of its own (simulate_controlled's quadrature_units).
std::string lifted_arm(bool mm, double atol, const std::string& integrator = "dopri5") {
  const std::string units = mm ? "1000" : "1";  // mm per length unit (also ms per time unit)
  return std::string("parameters: {") +
         (mm ? "L1: 500, L2: 400, H: 500, g: 9.81e-3, c: 2e-6, t1: 500"
             : "L1: 0.5, L2: 0.4, H: 0.5, g: 9.81, c: 2, t1: 0.5") +
         ", q10: 1.0, mu: 1}\nunits: " +
         (mm ? "{length: mm, mass: g, time: ms}" : "{length: m, mass: kg, time: s}") +
         "\nrobot: {urdf: " + (mm ? "arm_lift_jf_mm.urdf, urdf_units: model" : "arm_lift_jf.urdf") +
         R"(, gravity: [0, 0, -g]}
contacts:
  - {name: tip, link: fore, point: [L2, 0, 0], restitution: 0}
nonideal:
  - {friction: coulomb, constraint: tip, mu: mu}
initial:
  q: {j1: q10, j2: asin((H - L1*sin(q10))/L2) - q10}
control:
  requirements:
    - {name: pz, holonomic: H - L1*sin(j1) - L2*sin(j1 + j2) - c*(t - t1)^3, active: [t1, )" +
         (mm ? "2000], dynamics: {omega: 0.02" : "2], dynamics: {omega: 20") + R"(, zeta: 1}}
  law: gauss
simulate: {t_end: )" +
         (mm ? "1000" : "1") + ", integrator: " + integrator +
         ", rtol: 1e-10, atol: " + format_number(atol) +
         "}\noutput: {every: " + (mm ? "50" : "0.05") + "}\n";
}

ControlledTrajectory lifted_arm_run(bool mm, double atol,
                                    const std::string& integrator = "dopri5") {
  return run(parse_model(lifted_arm(mm, atol, integrator),
                         std::string(UKDYN_TEST_DATA_DIR) + "/arm.yaml"));
}

// the mm run `b` is the SI run `a` scaled, to `tol` relative to each quantity's largest value:
// the release's time, the angles, the control's effort (× 10⁹ in g² mm⁴ ms⁻³) and work (× 10³)
// at every sample
void expect_scaled(const ControlledTrajectory& a, const ControlledTrajectory& b, double tol) {
  const double t_a = the_release(a), t_b = the_release(b);
  EXPECT_NEAR(t_b / 1e3, t_a, tol * t_a);
  EXPECT_GT(t_a, 0.5);  // (the drift allowance, as above)
  EXPECT_LT(t_a, 0.5 + 3e-6);
  ASSERT_EQ(a.plant.samples(), 21);
  ASSERT_EQ(b.plant.samples(), 21);
  const double effort = a.control_effort.back(), work = a.control_work.back();
  // (the lift's effort and work, about 6.7 N² m² s and 1.9 J)
  EXPECT_NEAR(effort, 6.68, 0.05);
  EXPECT_NEAR(work, 1.90, 0.05);
  for (std::size_t j = 0; j < 21; ++j) {
    EXPECT_NEAR(b.plant.t[j] / 1e3, a.plant.t[j], 1e-15) << j;
    EXPECT_NEAR(b.plant.q[2 * j], a.plant.q[2 * j], tol * 2.0) << "t = " << a.plant.t[j];
    EXPECT_NEAR(b.plant.q[2 * j + 1], a.plant.q[2 * j + 1], tol * 3.0) << "t = " << a.plant.t[j];
    EXPECT_NEAR(b.control_effort[j] / 1e9, a.control_effort[j], tol * effort)
        << "t = " << a.plant.t[j];
    EXPECT_NEAR(b.control_work[j] / 1e3, a.control_work[j], tol * work) << "t = " << a.plant.t[j];
    EXPECT_NEAR(b.plant.work_control[j] / 1e3, a.plant.work_control[j], tol * work)
        << "t = " << a.plant.t[j];
  }
}

TEST(ControlLift, RobotArmLiftedOffAFrictionalGroundRunsAsInSIInMillimetresGramsMilliseconds) {
  // the reproducer's atol: 1e-12 in SI, 1e-9 in mm (1e-12 m; on the angles 1000 times the SI
  // run's), so the mm run is the SI one to what that tolerance allows (measured: 4.6e-11 of the
  // release's time, 1.6e-9 of the angles, 7.3e-9 of the effort, 8.7e-9 of the work)
  const ControlledTrajectory si = lifted_arm_run(false, 1e-12);
  const ControlledTrajectory mm = lifted_arm_run(true, 1e-9);
  ASSERT_EQ(mm.plant.stats.status, Status::kOk) << mm.plant.stats.message;
  expect_scaled(si, mm, 3e-8);
}

// The same lift under BDF (CVODE). Its quadratures were weighed as before their units (the
// effort as q, atol): in mm, g, ms the effort's integrand, ~0 until the release and weighed at
// atol, jumps by ~1e7 there, and CVODE's error test asked for steps below the roundoff of
// t = 500.0003 ms: no progress (2.1e6 steps, half rejected, in 60 s). Now each quadrature is
// weighed in its unit (quadrature_units) as the explicit methods do, and the mm run is the SI run
// scaled (measured: 577 steps in mm, 686 in SI; the releases 500.0003174806 ms and
// 0.5000003174891 s; angles, effort and work within 8e-9 of their largest values).
TEST(ControlLift, RobotArmLiftedOffAFrictionalGroundUnderBdfRunsAsInSIInMillimetresGramsMs) {
  const ControlledTrajectory si = lifted_arm_run(false, 1e-12, "bdf");
  const ControlledTrajectory mm = lifted_arm_run(true, 1e-9, "bdf");
  ASSERT_EQ(si.plant.stats.status, Status::kOk) << si.plant.stats.message;
  ASSERT_EQ(mm.plant.stats.status, Status::kOk) << mm.plant.stats.message;
  // (BDF's steps stop at the release as dopri5's do: the same instant to its event tolerance)
  const ControlledTrajectory explicit_si = lifted_arm_run(false, 1e-12);
  EXPECT_NEAR(the_release(si), the_release(explicit_si), 1e-9);
  expect_scaled(si, mm, 1e-7);
}

// ---- a failed run names the failure of its last step
// ---------------------------------------------

// A two-link arm (tests/data/arm2_circle.urdf, a new user's, u20 04) whose tip (a sphere of
// r = 0.02) is made to trace the circle x = 0.6 + 0.15 cos 2t, z = 0.62 + 0.15 sin 2t, which dips
// below a table at z = 0.55: the tip's centre reaches 0.57 where sin 2t = −1/3, at
// t* = (π + asin(1/3))/2 = 1.7407148 s, and the requirement then needs the table to pull: the
// run stops there and says so, at that time. (A trial evaluation at t = 0 had failed the same
// way, and its time was the one said.) The same arm lifted off the table and then driven out
// of reach diverges at 2.06 s: the run says that, not a pulling contact of an earlier trial
// evaluation (it named 'tip' at 0.84 s, where the contact was still closed).
TEST(ControlLift, AFailedRunSaysTheFailureOfItsLastStepNotOfAnEarlierTrial) {
  const std::string head = R"(
robot: {urdf: arm2_circle.urdf}
simulate: {t_end: 4}
)";
  const Model dip = parse_model(head + R"(
parameters: {cx: 0.6, cz: 0.62, R: 0.15, W: 2}
initial:
  q: {shoulder: -0.28496459, elbow: 1.49990363}
control:
  requirements:
    - name: tip
      pose: {link: fore, point: [0.5, 0, 0], position: [cx + R*cos(W*t), 0, cz + R*sin(W*t)]}
      dynamics: {omega: 10, zeta: 1}
contacts:
  - {name: pad, link: fore, point: [0.5, 0, 0], shape: sphere, radius: 0.02,
     plane: {body: ground, point: [0, 0, 0.55], normal: [0, 0, 1]}}
)",
                                std::string(UKDYN_TEST_DATA_DIR) + "/arm2_circle.yaml");
  const ControlledTrajectory r = run(dip);
  const double t_star = (std::numbers::pi + std::asin(1.0 / 3.0)) / 2.0;
  EXPECT_NEAR(r.plant.stats.t_reached, t_star, 1e-6);
  const std::string& msg = r.plant.stats.message;
  // the controller failed, not the inputs (it was "non-finite input": its NaN force in Q), and
  // summary.json (so `ukdyn run` and Python's Result.status, which read the same name) says so
  EXPECT_EQ(r.plant.stats.status, Status::kControlFailed) << msg;
  EXPECT_STREQ(to_string(r.plant.stats.status), "control failed");
  const std::string summary = summary_json(r.plant, dip.options);
  EXPECT_NE(summary.find("\"status\": \"control failed\""), std::string::npos) << summary;
  EXPECT_EQ(summary.find("non-finite"), std::string::npos) << summary;
  EXPECT_NE(msg.find("the controller failed: at t = " + format_number(r.plant.stats.t_reached, 6) +
                     " s the requirement row 'tip.2' can be met only if the contact 'pad' pulls"),
            std::string::npos)
      << msg;
  EXPECT_EQ(msg.find("at t = 0 s"), std::string::npos) << msg;
  const Model lift = parse_model(head + R"y(
parameters: {x0: 0.8, A: 0.1, W: 3}
initial:
  q: {shoulder: -0.046637383911816946, elbow: 1.2044927781043431}
control:
  requirements:
    - name: tip2
      pose: {link: fore, point: [0.5, 0, 0], position: [x0 + A*sin(W*t), 0, "0.57 + if(t - 1, (t - 1)^3, 0)"]}
      dynamics: {omega: 10, zeta: 1}
contacts:
  - {name: tip, link: fore, point: [0.5, 0, 0], shape: sphere, radius: 0.02,
     plane: {body: ground, point: [0, 0, 0.55], normal: [0, 0, 1]}}
)y",
                                 std::string(UKDYN_TEST_DATA_DIR) + "/arm2_circle.yaml");
  const ControlledTrajectory l = run(lift);
  EXPECT_EQ(l.plant.stats.status, Status::kIntegratorFailure) << l.plant.stats.message;
  // out of reach: x = 0.8 + 0.1 sin 3t, z = 0.57 + (t − 1)³ leaves the shoulder's 1.1 m near 2 s
  EXPECT_GT(l.plant.stats.t_reached, 1.9);
  EXPECT_LT(l.plant.stats.t_reached, 2.2);
  EXPECT_EQ(l.plant.stats.message.find("pulls"), std::string::npos) << l.plant.stats.message;
  EXPECT_NE(l.plant.stats.message.find("diverges"), std::string::npos) << l.plant.stats.message;
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// The control: section of model files (issue #6, item 5): the gallery's controlled examples run by
// run_model() as `ukdyn run` runs them, checked against the closed-form error dynamics and the
// optimality of the weighted law; and the located errors of bad control sections.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "ukdyn/control/control.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"

#include "support/error_dynamics.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

using test::second_order_error;

Model load_example(const std::string& name) {
  return load_model(std::string(UKDYN_EXAMPLES_DIR) + "/" + name + ".yaml");
}

// the run's column `name` (fails the test when missing)
std::vector<double> column(const ModelRun& run, const std::string& name) {
  for (const auto& c : run.columns()) {
    if (c.name == name) return c.values;
  }
  ADD_FAILURE() << "no column " << name;
  return std::vector<double>(std::size_t(run.trajectory.samples()), 0.0);
}

ModelRun run_ok(const Model& m) {
  ModelRun r = run_model(m);
  EXPECT_TRUE(r.controlled) << m.file;
  EXPECT_EQ(r.trajectory.stats.status, Status::kOk) << m.file << ": " << r.trajectory.stats.message;
  EXPECT_NEAR(r.trajectory.t.back(), m.options.t_end, 1e-12) << m.file;
  EXPECT_EQ(r.control.not_met, 0) << m.file;
  return r;
}

TEST(ModelControl, DuffingErrorIsOnePlusTTimesExpMinusTwoT) {
  const Model m = load_example("control_duffing");
  ASSERT_TRUE(m.controller);
  const ModelRun r = run_ok(m);
  const auto e = column(r, "error.track");
  const auto x = column(r, "x");
  const auto Qc = column(r, "Qc_control.x");
  ASSERT_GT(e.size(), 400u);
  double worst = 0.0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    const double t = r.trajectory.t[i];
    EXPECT_NEAR(e[i], (1 + t) * std::exp(-2 * t), 1e-8) << t;
    EXPECT_NEAR(x[i] - std::sin(t), e[i], 1e-14) << t;  // the column is the expression's value
    worst = std::max(worst, std::abs(e[i] - (1 + t) * std::exp(-2 * t)));
  }
  RecordProperty("max_error_deviation", std::to_string(worst));
  // the Gauss force for a single unit-mass coordinate is the whole required force:
  // Qc = x_d'' + 4 e' ... checked at t = 0 by hand: x'' must be −sin 0 − 4 e'(0) − 4 e(0) = 0,
  // and Q(0) = −0.3·0 + 1 − 1 + 0.5 = 0.5, so Qc(0) = −0.5
  EXPECT_NEAR(Qc[0], -0.5, 1e-9);
  // effort and work columns: effort = ∫ Qc² dt grows, and is at least the trapezoid's lower
  // neighbourhood of the sampled integral
  const auto effort = column(r, "control_effort");
  double trapezoid = 0.0;
  for (std::size_t i = 1; i < Qc.size(); ++i) {
    trapezoid +=
        0.5 * (Qc[i] * Qc[i] + Qc[i - 1] * Qc[i - 1]) * (r.trajectory.t[i] - r.trajectory.t[i - 1]);
  }
  EXPECT_NEAR(effort.back(), trapezoid, 1e-3 * trapezoid);
}

// A holonomic requirement written as actual − desired(t) gets its desired value as the output
// expression desired_<row> (the plots draw it against actual = desired + error): for the Duffing
// oscillator desired_track = sin(t), and x − desired_track is error.track
TEST(ModelControl, DesiredValueOfARequirementIsAnOutput) {
  const ModelRun r = run_ok(load_example("control_duffing"));
  const auto d = column(r, "desired_track"), x = column(r, "x"), e = column(r, "error.track");
  ASSERT_EQ(d.size(), x.size());
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double t = r.trajectory.t[i];
    EXPECT_NEAR(d[i], std::sin(t), 1e-15) << t;
    EXPECT_NEAR(x[i] - d[i], e[i], 1e-14) << t;
  }
  // rows of several, a term of the parameters, a row with no term of t alone (none), a row of t
  // alone (none), and a name the file gives itself (the file's expression, once)
  const Model m = parse_model(R"(
parameters: {a: 2}
coordinates: [x, y]
mass_matrix: [[1, 0], [0, 1]]
control:
  requirements:
    - {name: p, holonomic: [x - a - 0.5*t^2, x*y], dynamics: {omega: 1, zeta: 1}}
    - {name: s, holonomic: y - cos(t), dynamics: {omega: 1, zeta: 1}}
    - {name: v, nonholonomic: x_dot + y_dot - 3*t, dynamics: {rate: 2}}
output:
  expressions: {desired_s: 7}
)");
  EXPECT_EQ(m.output_names, (std::vector<std::string>{"desired_s", "desired_p_0", "desired_v"}));
  // their values at t = 2, x = 0.3, y = 0.4: 7 (the file's), a + t²/2 = 4, 3 t = 6
  Trajectory tr;
  tr.n = 2;
  tr.t = {2.0};
  tr.q = {0.3, 0.4};
  tr.qd = {0.1, 0.2};
  const auto values = evaluate_output_expressions(m, tr);
  ASSERT_EQ(values.size(), 3u);
  EXPECT_NEAR(values[0][0], 7.0, 1e-15);
  EXPECT_NEAR(values[1][0], 4.0, 1e-15);
  EXPECT_NEAR(values[2][0], 6.0, 1e-15);
}

TEST(ModelControl, TriplePendulumJointsFollowTheirErrorDynamics) {
  const Model m = load_example("control_triple_pendulum");
  const ModelRun r = run_ok(m);
  // e_i(0) = q_i(0) − path_i(0), e_i'(0) = q_i'(0) − 0.2 (every path has slope 0.2 at 0)
  const double q0[3] = {0.3, -0.2, 0.5}, qd0[3] = {0.0, 0.4, -0.3};
  const double path0[3] = {0.0, 0.1, -0.1};
  double worst = 0.0;
  for (int i = 0; i < 3; ++i) {
    const auto e = column(r, "error.joint" + std::to_string(i + 1));
    for (std::size_t j = 0; j < e.size(); ++j) {
      const double t = r.trajectory.t[j];
      const double expected = second_order_error(0.7, 3.0, q0[i] - path0[i], qd0[i] - 0.2, t);
      EXPECT_NEAR(e[j], expected, 1e-8) << "joint " << i + 1 << ", t = " << t;
      worst = std::max(worst, std::abs(e[j] - expected));
    }
  }
  RecordProperty("max_error_deviation", std::to_string(worst));
  // the plant's energy balance with the control's work (as simulate_controlled measures it)
  EXPECT_NEAR(r.trajectory.stats.energy_drift, 0.0, 1e-8);
}

// The arm of arm_circle.yaml as bodies and joints, actuated at its joints (issue #16 item 6c):
// the tip error follows its closed form, and the joint torques are those of the same arm in
// relative joint angles (an independent model: there Qc_control.q1 is the shoulder torque and
// Qc_control.q2 the elbow's; here the shoulder torque acts on link1 and the elbow's on link2
// and, opposite, on link1). Both requirement rows fix both degrees of freedom, so the torques
// are unique.
TEST(ModelControl, MultibodyArmActuatedAtItsJointsMatchesTheJointAngleModel) {
  const std::string dir = UKDYN_TEST_DATA_DIR;
  SimulationOptions o;
  const Model bodies = load_model(dir + "/arm_circle_bodies.yaml");
  ASSERT_TRUE(bodies.controller);
  EXPECT_FALSE(bodies.controller->fully_actuated());
  EXPECT_EQ(bodies.controller->actuators(), 2);
  const ModelRun rb = run_ok(bodies);
  Model angles = load_model(dir + "/arm_circle.yaml");
  angles.options = bodies.options;
  angles.options.t_end = bodies.options.t_end;
  const ModelRun ra = run_ok(angles);
  ASSERT_EQ(rb.trajectory.t.size(), ra.trajectory.t.size());
  // e(0) = tip(0) − (cx + R, cy), e'(0) = −(0, R W); critically damped with ω = 4
  const double L1 = 0.6, L2 = 0.5, a1 = 0.2, a2 = 1.4;
  const double ex0 = L1 * std::cos(a1) + L2 * std::cos(a2) - 0.85;
  const double ey0 = L1 * std::sin(a1) + L2 * std::sin(a2) - 0.2;
  const auto ex = column(rb, "error.tip.0"), ey = column(rb, "error.tip.1");
  const auto t1 = column(rb, "Qc_control.link1.theta"), t2 = column(rb, "Qc_control.link2.theta");
  const auto fx = column(rb, "Qc_control.link2.x");
  const auto q1 = column(ra, "Qc_control.q1"), q2 = column(ra, "Qc_control.q2");
  for (std::size_t i = 0; i < ex.size(); ++i) {
    const double t = rb.trajectory.t[i];
    EXPECT_NEAR(ex[i], second_order_error(1.0, 4.0, ex0, 0.0, t), 1e-8) << t;
    EXPECT_NEAR(ey[i], second_order_error(1.0, 4.0, ey0, -0.5, t), 1e-8) << t;
    // shoulder = Qc(link1.theta) + elbow, elbow = Qc(link2.theta); no force on a centre of mass
    EXPECT_NEAR(t1[i] + t2[i], q1[i], 1e-6 * (1 + std::abs(q1[i]))) << t;
    EXPECT_NEAR(t2[i], q2[i], 1e-6 * (1 + std::abs(q2[i]))) << t;
    EXPECT_EQ(fx[i], 0.0) << t;
  }
  // the shoulder holds the arm up against gravity: about 7.7 … 11.1 N m (the report's range)
  EXPECT_NEAR(t1[0] + t2[0], q1[0], 1e-9);
  EXPECT_GT(q1[0], 5.0);
}

// The reproducer's spellings of the bodies' coordinates both work: the same torques as the
// joints give (their columns span the same space), and errors name the choices.
TEST(ModelControl, MultibodyActuatedAcceptsBothSpellingsAndRefusesOtherJoints) {
  std::ifstream in(std::string(UKDYN_TEST_DATA_DIR) + "/arm_circle_bodies.yaml");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto with = [&](const std::string& list) {
    std::string t = text;
    const std::string key = "actuated: [shoulder, elbow]";
    t.replace(t.find(key), key.size(), "actuated: " + list);
    return t;
  };
  const Model joints = parse_model(text, "arm.yaml");
  Workspace ws(joints.system);
  for (const std::string list :
       {"[link1_theta, link2_theta]", "[link1.theta, link2.theta]", "[shoulder, link2_theta]"}) {
    const Model m = parse_model(with(list), "arm.yaml");
    ASSERT_TRUE(m.controller) << list;
    EXPECT_EQ(m.controller->actuators(), 2) << list;
    SimulationOptions o = m.options;
    o.t_end = 0.5;
    const ModelRun a = run_model(m, o), b = run_model(joints, o);
    EXPECT_EQ(a.trajectory.stats.status, Status::kOk) << list;
    EXPECT_EQ(a.control.not_met, 0) << list;
    const auto ta = column(a, "Qc_control.link1.theta"), tb = column(b, "Qc_control.link1.theta");
    ASSERT_EQ(ta.size(), tb.size());
    for (std::size_t i = 0; i < ta.size(); ++i)
      EXPECT_NEAR(ta[i], tb[i], 1e-7 * (1 + std::abs(tb[i]))) << list;
  }
  const auto error = [&](const std::string& list) -> std::string {
    try {
      parse_model(with(list), "arm.yaml");
    } catch (const ModelError& e) {
      return e.what();
    }
    return "";
  };
  std::string e = error("[wrist]");
  EXPECT_NE(e.find("arm.yaml:26:14: error: actuated: 'wrist' is not a coordinate or a joint "
                   "(hint: the coordinates and joints are link1_x, link1_y, link1_theta, link2_x, "
                   "link2_y, link2_theta, shoulder, elbow)"),
            std::string::npos)
      << e;
  e = error("[shoulder, shoulder]");
  EXPECT_NE(e.find("arm.yaml:26:24: error: actuated: 'shoulder' is listed twice"),
            std::string::npos)
      << e;
  e = error("[link2.theta, link2_theta]");
  EXPECT_NE(e.find("error: actuated: 'link2_theta' is listed twice"), std::string::npos) << e;
}

// A joint that cannot be actuated with a constant actuation matrix is refused at its name.
TEST(ModelControl, MultibodyJointsThatCannotBeActuatedAreLocatedErrors) {
  const std::string base = R"(parameters: {m: 1}
bodies:
  - {name: a, type: planar, mass: m, inertia: 0.1, position: [1, 0]}
  - {name: b, type: planar, mass: m, inertia: 0.1, position: [2, 0]}
joints:
  - {name: pin, type: revolute, parent: ground, child: a, child_point: [-1, 0]}
  - {name: slide, type: prismatic, parent: a, child: b}
  - {name: rod, type: distance, parent: ground, child: b, parent_point: [0, 0], length: 2}
control:
  requirements: [{name: r, holonomic: a_theta - t}]
)";
  const auto error = [&](const std::string& list) -> std::string {
    try {
      parse_model(base + "  actuated: " + list + "\n", "j.yaml");
    } catch (const ModelError& e) {
      return e.what();
    }
    return "";
  };
  std::string e = error("[rod]");
  EXPECT_NE(e.find("j.yaml:11:14: error: actuated: joint 'rod' is a distance joint: only "
                   "revolute and prismatic joints have a coordinate of their own to actuate"),
            std::string::npos)
      << e;
  e = error("[pin, slide]");
  EXPECT_NE(e.find("j.yaml:11:19: error: actuated: joint 'slide' is a prismatic joint between "
                   "two bodies"),
            std::string::npos)
      << e;
}

// A prismatic joint on the ground, actuated: a block on a slide inclined at 30° under gravity,
// its position required to follow s(t) = 0.5 t²; the actuator force is u = m s'' + m g sin 30°
// along the slide (the closed form), the Gauss law puts nothing elsewhere.
TEST(ModelControl, MultibodyPrismaticJointOnTheGroundIsActuatedAlongItsSlide) {
  // the joint point (0.1, 0.2) of the block turned by 0.25 is r = (rx, ry) from its centre,
  // and starts at the origin (s = 0)
  const Model m = parse_model(R"(parameters: {m: 2, g: 9.81, a: pi/6, th: 0.25,
  rx: 0.1*cos(th) - 0.2*sin(th), ry: 0.1*sin(th) + 0.2*cos(th)}
bodies:
  - {name: block, type: planar, mass: m, inertia: 0.1, angle: th, position: [-rx, -ry]}
joints:
  - {name: slide, type: prismatic, parent: ground, child: block, parent_angle: a,
     child_angle: a - th, child_point: [0.1, 0.2]}
forces:
  - {type: gravity, g: [0, -g]}
control:
  requirements:
    - {name: s, holonomic: (block_x + rx)*cos(a) + (block_y + ry)*sin(a) - 0.5*t^2,
       dynamics: {omega: 3}}
  actuated: [slide]
simulate: {t_end: 1}
output: {every: 0.1}
)",
                              "p.yaml");
  const ModelRun r = run_ok(m);
  const auto fx = column(r, "Qc_control.block.x"), fy = column(r, "Qc_control.block.y");
  const auto tz = column(r, "Qc_control.block.theta");
  const auto e = column(r, "error.s");
  const double pi = std::numbers::pi, u = 2 * 1.0 + 2 * 9.81 * 0.5;
  const double rx = 0.1 * std::cos(0.25) - 0.2 * std::sin(0.25);
  const double ry = 0.1 * std::sin(0.25) + 0.2 * std::cos(0.25);
  ASSERT_EQ(fx.size(), 11u);
  for (std::size_t i = 0; i < fx.size(); ++i) {
    EXPECT_NEAR(e[i], 0.0, 1e-9);
    EXPECT_NEAR(fx[i], u * std::cos(pi / 6), 1e-8);
    EXPECT_NEAR(fy[i], u * std::sin(pi / 6), 1e-8);
    EXPECT_NEAR(tz[i], u * (rx * std::sin(pi / 6) - ry * std::cos(pi / 6)), 1e-8);
  }
}

TEST(ModelControl, TipRequirementWeightedLawIsOptimalAmongAdmissibleControls) {
  const Model m = load_example("control_triple_pendulum_tip");
  ASSERT_TRUE(m.controller);
  EXPECT_EQ(m.controller->law(), ControlLaw::kWeighted);
  const ModelRun r = run_ok(m);
  // both rows follow e'' + 4 e' + 4 e = 0 from the initial error (tip at rest at t = 0)
  const double L[3] = {1.0, 0.9, 0.8}, q0[3] = {0.5, 0.3, 0.1};
  double x0 = 0.0, y0 = 0.0;
  for (int i = 0; i < 3; ++i) {
    x0 += L[i] * std::sin(q0[i]);
    y0 -= L[i] * std::cos(q0[i]);
  }
  const double e0[2] = {x0 - 0.8, y0 + 1.7}, e1[2] = {-0.3, 0.0};  // d/dt of the path at 0
  for (int k = 0; k < 2; ++k) {
    const auto e = column(r, "error.tip." + std::to_string(k));
    for (std::size_t j = 0; j < e.size(); ++j) {
      EXPECT_NEAR(e[j], second_order_error(1.0, 2.0, e0[k], e1[k], r.trajectory.t[j]), 1e-8);
    }
  }
  // optimality: at states along the run, no admissible control (one that meets the
  // requirement: X Qc = e) has a lower cost Qcᵀ N Qc than the law's; random admissible ones
  // are Qc + z with z in the null space of X
  ControlWorkspace cws(*m.controller);
  const Eigen::Matrix3d N = Eigen::Vector3d(1, 4, 9).asDiagonal();
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  const Trajectory& tr = r.trajectory;
  for (Index j = 0; j < tr.samples(); j += 50) {
    const VectorXd q = Eigen::Map<const VectorXd>(tr.q.data() + 3 * j, 3);
    const VectorXd qd = Eigen::Map<const VectorXd>(tr.qd.data() + 3 * j, 3);
    compute_control(*m.controller, cws, q, qd, tr.t[std::size_t(j)]);
    ASSERT_EQ(cws.status, ControlStatus::kOk);
    const VectorXd Qc = cws.Qc_control;
    EXPECT_LT((cws.X * Qc - cws.e).norm(), 1e-9 * (1 + cws.e.norm()));
    const Eigen::JacobiSVD<MatrixXd> svd(cws.X, Eigen::ComputeFullV);
    const VectorXd z0 = svd.matrixV().col(2);  // X has rank 2: its null space is one direction
    EXPECT_LT((cws.X * z0).norm(), 1e-12 * (1 + cws.X.norm()));
    const double cost = Qc.dot(N * Qc);
    for (int k = 0; k < 20; ++k) {
      const VectorXd other = Qc + normal(rng) * z0;
      EXPECT_GE(other.dot(N * other), cost * (1 - 1e-12));
    }
    // first-order optimality: N Qc is orthogonal to the admissible directions
    EXPECT_NEAR(z0.dot(N * Qc), 0.0, 1e-9 * (1 + (N * Qc).norm()));
  }
}

TEST(ModelControl, SpacecraftAttitudeErrorDecaysAsPrescribedAndTheNormHolds) {
  const Model m = load_example("control_spacecraft");
  const ModelRun r = run_ok(m);
  // e(0) = vec(conj(d0) ⊗ u0) with d0 = identity: the vector part of u0; e'(0) =
  // vec(conj(d0') ⊗ u0 + u0') with d0' = (θ'(0)/2) (0, n), θ'(0) = 0.6, n = (1, 2, 2)/3
  const double c = std::cos(0.25), s = std::sin(0.25);
  const Eigen::Vector4d u0(c, 0, 0, s);
  const Eigen::Vector4d ud0(-0.15 * s, 0.05 * c + 0.1 * s, -0.1 * c + 0.05 * s, 0.15 * c);
  const Eigen::Vector3d n(1.0 / 3, 2.0 / 3, 2.0 / 3);
  const Eigen::Vector3d dv = 0.3 * n;  // vector part of d0'
  // conj(d0') ⊗ u0 = (0, −dv) ⊗ u0: vector part −u0_0 dv − dv × u0_v
  const Eigen::Vector3d uv = u0.tail<3>();
  const Eigen::Vector3d e0 = uv;
  const Eigen::Vector3d e1 = -u0[0] * dv - dv.cross(uv) + ud0.tail<3>();
  const auto u_0 = column(r, "u0"), u_1 = column(r, "u1"), u_2 = column(r, "u2"),
             u_3 = column(r, "u3");
  for (int k = 0; k < 3; ++k) {
    const auto e = column(r, "error.attitude." + std::to_string(k));
    for (std::size_t j = 0; j < e.size(); ++j) {
      EXPECT_NEAR(e[j], second_order_error(1.0, 2.0, e0[k], e1[k], r.trajectory.t[j]), 1e-8)
          << "row " << k << ", t = " << r.trajectory.t[j];
    }
  }
  for (std::size_t j = 0; j < u_0.size(); ++j) {
    const double norm =
        std::sqrt(u_0[j] * u_0[j] + u_1[j] * u_1[j] + u_2[j] * u_2[j] + u_3[j] * u_3[j]);
    EXPECT_NEAR(norm, 1.0, 1e-11);
  }
  // the Gauss control is a pure body torque: it does no work on the norm, uᵀ Qc = 0
  const auto Q0 = column(r, "Qc_control.u0"), Q1 = column(r, "Qc_control.u1"),
             Q2 = column(r, "Qc_control.u2"), Q3 = column(r, "Qc_control.u3");
  for (std::size_t j = 0; j < Q0.size(); ++j) {
    const double dot = u_0[j] * Q0[j] + u_1[j] * Q1[j] + u_2[j] * Q2[j] + u_3[j] * Q3[j];
    EXPECT_NEAR(
        dot, 0.0,
        1e-10 * (1 + std::abs(Q0[j]) + std::abs(Q1[j]) + std::abs(Q2[j]) + std::abs(Q3[j])));
  }
}

TEST(ModelControl, GyroscopeSlaveSynchronizesAndOnlyTheSlaveIsActuated) {
  const Model m = load_example("control_gyroscopes");
  const ModelRun r = run_ok(m);
  const auto e = column(r, "error.sync"), Qm = column(r, "Qc_control.master");
  for (std::size_t j = 0; j < e.size(); ++j) {
    // e(0) = −0.3 − 1, e'(0) = 0.8 + 0.5
    EXPECT_NEAR(e[j], second_order_error(0.8, 4.0, -1.3, 1.3, r.trajectory.t[j]), 1e-8);
    EXPECT_EQ(Qm[j], 0.0);
  }
}

TEST(ModelControl, RobustTermKeepsTheErrorInsideItsBoundWhereTheNominalControlDoesNot) {
  const std::string path = std::string(UKDYN_EXAMPLES_DIR) + "/control_uncertain_duffing.yaml";
  Model robust = load_model(path);
  robust.options.t_end = 21.0;
  const ModelRun r = run_ok(robust);
  const auto e = column(r, "error.track"), bound = column(r, "error_bound.track");
  // V(0) = (β² + 2α²) e² + 2α e e' + e'² with α = β = 2, e(0) = 1, e'(0) = −1: bound(0) = sqrt(9/8)
  EXPECT_NEAR(bound.front(), std::sqrt(9.0 / 8.0), 1e-12);
  double bound_late = 0.0;
  for (std::size_t j = 0; j < e.size(); ++j) {
    EXPECT_LE(std::abs(e[j]), bound[j]) << r.trajectory.t[j];
    if (r.trajectory.t[j] >= 14.0) bound_late = std::max(bound_late, bound[j]);
  }
  // the same file without the robust term: steady error amplitude 0.2 / |4.8 − 1 + 4.8 i|
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find("  robust:");
  ASSERT_NE(at, std::string::npos);
  text.erase(at, text.find('\n', at) - at + 1);
  Model nominal = parse_model(text, "nominal-only");
  nominal.options.t_end = 21.0;
  const ModelRun n = run_ok(nominal);
  const auto en = column(n, "error.track");
  double peak = 0.0;
  for (std::size_t j = 0; j < en.size(); ++j) {
    if (n.trajectory.t[j] >= 14.0) peak = std::max(peak, std::abs(en[j]));
  }
  EXPECT_NEAR(peak, 0.2 / std::hypot(3.8, 4.8), 2e-4);
  EXPECT_GT(peak, 3.0 * bound_late);
  RecordProperty("robust_bound_late", std::to_string(bound_late));
  RecordProperty("nominal_peak_late", std::to_string(peak));
}

// A model with a valid plant and the given control section.
std::string with_control(const std::string& control) {
  return "parameters: {m: 1}\n"
         "coordinates: [x, y]\n"
         "kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)\n"
         "constraints:\n"
         "  - {name: line, holonomic: y - x}\n"
         "initial: {q: {x: 0, y: 0}, q_dot: {x: 0, y: 0}}\n"
         "control:\n" +
         control;
}

// parse_model must throw a ModelError at (line, column) whose message contains `what`
void expect_error(const std::string& control, int line, int column, const std::string& what) {
  try {
    parse_model(with_control(control), "c.yaml");
    ADD_FAILURE() << "no error for:\n" << control;
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.column(), column) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

// A requirement's name is unique among the plant's constraints, joints and contacts and the
// other requirements, in a bodies model as in a robot's (u22 08: a bodies model accepted a
// requirement named like its contact; tests/modelfile/test_model_robot_contacts.cpp has the
// robot's), refused at the requirement's name with what holds the name
TEST(ModelControl, ARequirementNamedLikeAContactOrJointIsRefusedNamingIt) {
  const std::string bodies = R"(bodies:
  - {name: ball, type: rigid, mass: 1, inertia: 0.004, position: [0.5, 0, 0.1]}
  - {name: arm, type: rigid, mass: 1, inertia: 0.004, position: [0, 0, 2]}
joints:
  - {name: pivot, type: spherical, parent: ground, child: arm, parent_point: [0, 0, 2]}
contacts:
  - {name: floor, body: ball, shape: sphere, radius: 0.1}
  - {name: feet, body: arm, shape: box, size: [0.1, 0.1, 0.1]}
control:
  requirements:
)";
  const auto expect_taken = [&](const std::string& name, const std::string& holder) {
    try {
      parse_model(bodies + "    - {name: " + name + ", holonomic: ball_x - 0.5}\n", "b.yaml");
      ADD_FAILURE() << "no error for " << name;
    } catch (const ModelError& e) {
      EXPECT_EQ(e.message(), "the name '" + name + "' is taken by " + holder) << e.what();
      EXPECT_EQ(e.line(), 11) << e.what();
      EXPECT_EQ(e.column(), 14) << e.what();
      EXPECT_NE(e.hint().find("unique among the model's constraints, joints, contacts and "
                              "requirements"),
                std::string::npos)
          << e.hint();
    }
  };
  expect_taken("floor", "the contact 'floor'");
  expect_taken("feet", "the contact 'feet'");  // (a box entry: its corners are feet.0 … feet.7)
  expect_taken("pivot", "the joint 'pivot'");
  // a name of its own is read
  const Model m = parse_model(bodies + "    - {name: track, holonomic: ball_x - 0.5}\n", "b.yaml");
  ASSERT_TRUE(m.controller);
  EXPECT_EQ(m.controller->requirement_count(), 1);
}

TEST(ModelControl, BadControlSectionsAreLocatedErrors) {
  // (the control section starts on line 8)
  expect_error("  requirements: [{name: r, holonomic: x - t}]\n  gains: 3\n", 9, 3,
               "unknown key 'gains' in control");
  expect_error("  law: gauss\n", 8, 3, "control needs a list of requirements");
  expect_error("  requirements: [{holonomic: x - t}]\n", 8, 18, "a requirement is a mapping");
  expect_error("  requirements: [{name: line, holonomic: x - t}]\n", 8, 25,
               "the name 'line' is taken");
  expect_error("  requirements: [{name: r, holonomic: x - t, dynamics: {rate: 2}}]\n", 8, 56,
               "rate: gives first-order error dynamics");
  expect_error("  requirements: [{name: r, nonholonomic: x_dot - 1, dynamics: {omega: 2}}]\n", 8,
               63, "its error dynamics are first order");
  // (found by the fuzzer: ErrorDynamics' own range check escaped as std::invalid_argument)
  expect_error("  requirements: [{name: r, holonomic: x - t, dynamics: {omega: 0, zeta: 1}}]\n", 8,
               56, "omega and zeta must be > 0, got omega = 0");
  expect_error("  requirements: [{name: r, nonholonomic: x_dot - 1, dynamics: {rate: -1}}]\n", 8,
               63, "the rate must be > 0");
  expect_error("  requirements: [{name: r, holonomic: x - t, dynamics: {alpha: -1}}]\n", 8, 56,
               "the dynamics of requirement 'r'");
  expect_error("  requirements: [{name: r, holonomic: x - q}]\n", 8, 43,
               "in requirement 'r': unknown name 'q'");
  expect_error("  requirements: [{name: r, holonomic: x - t}]\n  law: lqr\n", 9, 8,
               "unknown law 'lqr'");
  expect_error("  requirements: [{name: r, holonomic: x - t}]\n  law: weighted\n", 9, 8,
               "law: weighted needs the weight N");
  expect_error("  requirements: [{name: r, holonomic: x - t}]\n  law: weighted\n  N: [[1, 0]]\n",
               10, 6, "N must be a list of 2 rows");
  expect_error("  requirements: [{name: r, holonomic: x - t}]\n  actuated: [z]\n", 9, 14,
               "'z' is not a coordinate");
  expect_error("  requirements: [{name: r, holonomic: x - t}]\n  nominal: {k: 2}\n", 9, 13,
               "the model has no parameter 'k'");
  expect_error("  requirements: [{name: r, holonomic: x - t}]\n  robust: {bound: 1}\n", 9, 11,
               "robust needs boundary_layer");
  // the builder's own checks, located at their keys and in the model file's words (from a new
  // user's report: they pointed at requirements: and named ukdyn::ControllerBuilder::build)
  expect_error(
      "  requirements: [{name: r, holonomic: x - t}]\n  law: weighted\n"
      "  N: [[1, 0], [0, -1]]\n",
      10, 6, "c.yaml:10:6: error: the weight N must be positive definite");
  expect_error(
      "  requirements: [{name: r, holonomic: x - t, dynamics: {omega: 2}}]\n"
      "  robust: {bound: 0.1, boundary_layer: 0}\n",
      9, 40, "robust boundary_layer must be > 0");
  expect_error(
      "  requirements: [{name: r, holonomic: x - t, dynamics: {omega: 2}}]\n"
      "  robust: {bound: -1, boundary_layer: 0.1}\n",
      9, 19, "robust bound must be >= 0");
  expect_error(
      "  requirements: [{name: r, holonomic: x - t, dynamics: {omega: 2}}]\n"
      "  robust: {gain_uncertainty: 1, boundary_layer: 0.1}\n",
      9, 30, "robust gain_uncertainty must be in [0, 1)");
  // a plant that is fine with a nominal parameter that is not: the error says nominal
  expect_error("  requirements: [{name: r, holonomic: x - t}]\n  nominal: {m: -1}\n", 3, 17,
               "with the controller's nominal parameters (control: nominal: {m: -1}): ");
  for (const char* bad : {"{omega: -1}", "{omega: 2, zeta: 0}"}) {
    try {
      parse_model(with_control(std::string("  requirements: [{name: r, holonomic: x - t, "
                                           "dynamics: ") +
                               bad + "}]\n"),
                  "c.yaml");
      ADD_FAILURE() << bad;
    } catch (const ModelError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.find("ErrorDynamics"), std::string::npos) << what;
      EXPECT_NE(what.find("omit dynamics: for none"), std::string::npos) << what;
    }
  }
}

TEST(ModelControl, NominalParametersReachTheControllerOnlyAndSetOverridesThePlant) {
  // plant m = 1 (or --set m=2), controller m = 1.2: the controller's model is read separately
  const std::string path = std::string(UKDYN_EXAMPLES_DIR) + "/control_uncertain_duffing.yaml";
  const Model plant1 = load_model(path), plant2 = load_model(path, {{"m", 2.0}});
  VectorXd q(1), qd(1);
  q << 0.3;
  qd << 0.1;
  MatrixXd M1(1, 1), M2(1, 1), Mc(1, 1);
  plant1.system.mass_matrix(q, 0.0, M1);
  plant2.system.mass_matrix(q, 0.0, M2);
  plant1.controller->model().mass_matrix(q, 0.0, Mc);
  EXPECT_EQ(M1(0, 0), 1.0);
  EXPECT_EQ(M2(0, 0), 2.0);
  EXPECT_EQ(Mc(0, 0), 1.2);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

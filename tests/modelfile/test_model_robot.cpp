// SPDX-License-Identifier: BSD-3-Clause
// Robot model files (modelfile/reader_urdf.cpp): a .urdf read alone as a model, a model file
// that names a URDF and adds torques, a loop closure, initial state by joint name, parameters
// and a joint-space control requirement, weld and revolute loops, non-ideal forces, the example
// robots (a closed-chain leg under task-space control with friction on several threads, a
// humanoid, a mobile manipulator), and the errors a user meets, located.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>

#include <Eigen/Dense>

#include "ukdyn/control/control.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/multibody/tree_closures.hpp"
#include "ukdyn/simulation/ensemble.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

const std::string kData = UKDYN_TEST_DATA_DIR;
const std::string kPanda = kData + "/panda_arm.urdf";

// a model file next to the URDF (the urdf: path is relative to it)
Model robot_model(const std::string& text) { return parse_model(text, kData + "/robot.yaml"); }

// M(q) and Q(q, q', t) of a system
MatrixXd M_of(const System& s, const VectorXd& q) {
  MatrixXd M(s.coordinate_count(), s.coordinate_count());
  s.mass_matrix(q, 0.0, M);
  return M;
}
VectorXd Q_of(const System& s, const VectorXd& q, const VectorXd& qd, double t) {
  VectorXd Q(s.coordinate_count());
  s.forces(q, qd, t, Q);
  return Q;
}

// ModelError's message and position
struct Failure {
  std::string text;
  int line = -1;
};
Failure failure_of(const std::string& model_text) {
  try {
    robot_model(model_text);
  } catch (const ModelError& e) {
    return {e.message() + " | " + e.hint(), e.line()};
  }
  return {"no error", -1};
}

TEST(ModelRobot, AUrdfAloneIsARobotWithGravityAndNoTorque) {
  const Model m = load_model(kPanda);
  ASSERT_NE(m.robot, nullptr);
  ASSERT_EQ(m.system.coordinate_count(), 7);
  EXPECT_EQ(m.system.coordinate_names()[3], "panda_joint4");
  EXPECT_EQ(m.system.constraint_count(), 0);
  EXPECT_NEAR(m.q0.norm(), 0.0, 0.0);  // the neutral pose
  // the same dynamics as tree::make_system of the same file: M and Q at a state
  const tree::Tree arm = tree::load_urdf(kPanda);
  const System direct = tree::make_system(arm);
  VectorXd q(7), qd(7);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd << 0.4, -0.3, 0.5, 0.2, -0.6, 0.3, 0.7;
  EXPECT_NEAR((M_of(m.system, q) - M_of(direct, q)).norm(), 0.0, 0.0);
  EXPECT_NEAR((Q_of(m.system, q, qd, 0.0) - Q_of(direct, q, qd, 0.0)).norm(), 0.0, 0.0);
  // gravity acts: with the arm at rest Q = −g(q), nonzero on the shoulder
  EXPECT_GT(std::abs(Q_of(m.system, q, VectorXd::Zero(7), 0.0)[1]), 1.0);
}

TEST(ModelRobot, GravityKeepsTheJointsOrderSoInitialGoesToTheNamedJoint) {
  // u17 04: a base with two children (a platform on px; a carriage on bx carrying bz): with
  // gravity: the tree was rebuilt from its links, which reversed the children's order, and the
  // initial state named bx landed on px
  for (const char* gravity : {"", ", gravity: [0, 0, -1.62]"}) {
    SCOPED_TRACE(gravity);
    const Model m = robot_model(std::string("robot: {urdf: block_platform.urdf") + gravity +
                                "}\ninitial: {q: {bx: 0.25}, q_dot: {bx: 2, px: -1}}\n");
    const std::vector<std::string> names = m.system.coordinate_names();
    ASSERT_EQ(names.size(), 3u);
    const auto at = [&](const char* name) {
      return Index(std::find(names.begin(), names.end(), name) - names.begin());
    };
    ASSERT_LT(at("bx"), 3);
    ASSERT_LT(at("px"), 3);
    EXPECT_EQ(m.q0[at("bx")], 0.25);
    EXPECT_EQ(m.qd0[at("bx")], 2.0);
    EXPECT_EQ(m.qd0[at("px")], -1.0);
    EXPECT_EQ(m.q0[at("px")], 0.0);
    EXPECT_EQ(m.qd0[at("bz")], 0.0);
  }
  // and the same order as without gravity (the URDF's)
  EXPECT_EQ(robot_model("robot: {urdf: block_platform.urdf, gravity: [0, 0, -1.62]}\n")
                .system.coordinate_names(),
            robot_model("robot: {urdf: block_platform.urdf}\n").system.coordinate_names());
}

TEST(ModelRobot, AModelFileAddsTorquesALoopInitialStateAndParameters) {
  // the rod's anchor 0.3 m above the tool in the initial pose
  const tree::Tree arm = tree::load_urdf(kPanda);
  tree::TreeData d(arm);
  VectorXd q0(7);
  q0 << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  tree::forward_kinematics(arm, q0, d);
  const Eigen::Vector3d anchor =
      tree::world_point(d, arm.link_index("panda_tool"), {0, 0, 0}) + Eigen::Vector3d(0, 0, 0.3);
  char point[128];
  std::snprintf(point, sizeof point, "[%.17g, %.17g, %.17g]", anchor.x(), anchor.y(), anchor.z());
  const std::string text = R"(name: held arm
parameters: {k: 2.5, len: 0.3}
robot:
  urdf: panda_arm.urdf
  gravity: [0, 0, -9.81]
  torques: {panda_joint1: k*sin(t), panda_joint7: -0.1*panda_joint7_dot}
  loops:
    - {name: rod, type: distance, link_a: panda_tool, link_b: world,
       point_b: )" + std::string(point) +
                           R"(, length: len}
initial:
  q: {panda_joint1: 0.3, panda_joint2: -0.5, panda_joint3: 0.8, panda_joint4: -1.9,
      panda_joint5: 0.4, panda_joint6: 1.7, panda_joint7: -0.6}
simulate: {t_end: 0.3}
)";
  const Model m = robot_model(text);
  ASSERT_EQ(m.system.constraint_count(), 1);
  EXPECT_EQ(m.system.constraint(0).name(), "rod");
  EXPECT_NEAR(m.q0[3], -1.9, 0.0);
  // Q = τ − D q' − h with τ = [k sin t, 0, …, −0.1 q7']
  VectorXd qd(7), h(7), D(7);
  qd << 0.4, -0.3, 0.5, 0.2, -0.6, 0.3, 0.7;
  tree::bias_forces(arm, m.q0, qd, d, h);
  for (Index j = 0; j < 7; ++j) D[j] = arm.link(j + 1).joint.damping;
  VectorXd expected = -h - D.cwiseProduct(qd);
  expected[0] += 2.5 * std::sin(1.0);
  expected[6] += -0.1 * qd[6];
  EXPECT_NEAR((Q_of(m.system, m.q0, qd, 1.0) - expected).norm(), 0.0, 1e-12);
  // the rod holds the tool at its length from the anchor
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  for (Index s = 0; s < tr.samples(); s += 10) {
    tree::forward_kinematics(arm, Eigen::Map<const VectorXd>(tr.q.data() + s * 7, 7), d);
    const double len =
        (tree::world_point(d, arm.link_index("panda_tool"), {0, 0, 0}) - anchor).norm();
    EXPECT_NEAR(len, 0.3, 1e-9);
  }
  // --set of a parameter changes the loop
  EXPECT_EQ(parse_model(text, kData + "/robot.yaml", {{"len", 0.31}}).parameters.at("len"), 0.31);
}

TEST(ModelRobot, JointSpaceControlOfARobotModelFile) {
  const Model m = robot_model(R"(robot: {urdf: panda_arm.urdf}
control:
  requirements:
    - {name: swing, holonomic: panda_joint1 - 0.5*sin(t), dynamics: {omega: 10, zeta: 1}}
    - {name: elbow, holonomic: panda_joint4 + 1.5, dynamics: {omega: 10, zeta: 1}}
initial:
  q: {panda_joint4: -1.5}
  q_dot: {panda_joint1: 0.5}
simulate: {t_end: 0.5, rtol: 1e-11, atol: 1e-13}
)");
  ASSERT_NE(m.controller, nullptr);
  const ControlledTrajectory run =
      simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  for (Index s = 0; s < run.samples(); ++s) {
    EXPECT_NEAR(run.plant.q[std::size_t(s * 7)], 0.5 * std::sin(run.plant.t[std::size_t(s)]), 1e-8);
    EXPECT_NEAR(run.plant.q[std::size_t(s * 7 + 3)], -1.5, 1e-8);
  }
}

// a robot model's run notes the limits it left (the Panda's neutral pose is outside joint 4's
// range [−3.0718, −0.0698]), streamed or not, from the positions and the control torques
TEST(ModelRobot, ARunNotesTheJointAndEffortLimitsItLeaves) {
  const Model m = load_model(kPanda);
  SimulationOptions options = m.options;
  options.t_end = 0.2;
  const ModelRun run = run_model(m, options);
  ASSERT_FALSE(run.trajectory.stats.notes.empty());
  const std::string& first = run.trajectory.stats.notes[0];
  EXPECT_EQ(first.rfind("joint 'panda_joint4' exceeds its upper limit -0.0698 by ", 0), 0u)
      << first;
  EXPECT_NE(first.find("(first at t = 0 s"), std::string::npos) << first;
  EXPECT_NE(first.find(" rad (first"), std::string::npos) << first;
  {
    // in the model's units (units: {time: ms}): its times in ms
    const Model ms = robot_model("robot: {urdf: panda_arm.urdf}\nunits: {time: ms}\n");
    SimulationOptions o = ms.options;
    o.t_end = 0.2;
    const ModelRun r = run_model(ms, o);
    ASSERT_FALSE(r.trajectory.stats.notes.empty());
    const std::string& note = r.trajectory.stats.notes[0];
    EXPECT_NE(note.find("(first at t = 0 ms, worst at t = "), std::string::npos) << note;
    EXPECT_EQ(note.find(" s)"), std::string::npos) << note;
  }
  const ModelRun streamed = run_model(
      m, options, [](const ModelRun&) {}, 7);
  EXPECT_EQ(streamed.trajectory.stats.notes, run.trajectory.stats.notes);
  // under control: the torques that hold joint 4 at −1.5 against gravity exceed an effort of 12
  // (joint 2's is 87; the Panda's forearm joints 5–7 have 12) only where the file says
  const Model held = robot_model(R"(robot: {urdf: panda_arm.urdf, gravity: [0, 0, -60]}
control:
  requirements:
    - {name: pose, holonomic: [panda_joint2 - 1, panda_joint4 + 1.5], dynamics: {omega: 10}}
initial: {q: {panda_joint2: 1, panda_joint4: -1.5}}
simulate: {t_end: 0.1}
)");
  const ModelRun c = run_model(held, held.options);
  ASSERT_EQ(c.trajectory.stats.status, Status::kOk) << c.trajectory.stats.message;
  bool effort_noted = false;
  for (const std::string& note : c.trajectory.stats.notes)
    effort_noted = effort_noted || note.find("exceeds its effort limit 87") != std::string::npos;
  EXPECT_TRUE(effort_noted);
}

// task-space tracking written in a model file: the tool follows a circle while turning about
// the world's z axis (its quaternion u(t) = rot_z(θ(t)) ⊗ u0), a posture row takes the
// redundancy; checked against forward kinematics of the motion achieved
TEST(ModelRobot, APoseRequirementTracksTheToolInTaskSpace) {
  const tree::Tree arm = tree::load_urdf(kPanda);
  tree::TreeData d(arm);
  VectorXd q0(7);
  q0 << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  tree::forward_kinematics(arm, q0, d);
  const Index tool = arm.link_index("panda_tool");
  const Eigen::Vector3d p0 = tree::world_point(d, tool, {0, 0, 0});
  const Eigen::Quaterniond u0(d.R_WL[std::size_t(tool)]);
  char text[2048];
  // θ = 0.3 (1 − cos 2πt), c = cos(θ/2), s = sin(θ/2); p = p0 + 0.05 [1 − cos 2πt, sin 2πt ·
  // (1 − cos 2πt), 0]: at rest at t = 0
  std::snprintf(text, sizeof text, R"(parameters: {x0: %.17g, y0: %.17g, z0: %.17g,
  w0: %.17g, a0: %.17g, b0: %.17g, c0: %.17g}
robot: {urdf: panda_arm.urdf}
control:
  requirements:
    - name: tool
      pose:
        link: panda_tool
        position: [x0 + 0.05*(1 - cos(2*pi*t)), y0 + 0.05*sin(2*pi*t)*(1 - cos(2*pi*t)), z0]
        orientation:
          - cos(0.15*(1 - cos(2*pi*t)))*w0 - sin(0.15*(1 - cos(2*pi*t)))*c0
          - cos(0.15*(1 - cos(2*pi*t)))*a0 - sin(0.15*(1 - cos(2*pi*t)))*b0
          - cos(0.15*(1 - cos(2*pi*t)))*b0 + sin(0.15*(1 - cos(2*pi*t)))*a0
          - cos(0.15*(1 - cos(2*pi*t)))*c0 + sin(0.15*(1 - cos(2*pi*t)))*w0
      dynamics: {omega: 20, zeta: 1}
    - {name: posture, holonomic: panda_joint3 - 0.8, dynamics: {omega: 20, zeta: 1}}
initial:
  q: {panda_joint1: 0.3, panda_joint2: -0.5, panda_joint3: 0.8, panda_joint4: -1.9,
      panda_joint5: 0.4, panda_joint6: 1.7, panda_joint7: -0.6}
simulate: {t_end: 1, rtol: 1e-11, atol: 1e-13}
)",
                p0.x(), p0.y(), p0.z(), u0.w(), u0.x(), u0.y(), u0.z());
  const Model m = robot_model(text);
  const ModelRun run = run_model(m);
  ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
  EXPECT_EQ(run.control.not_met, 0);
  double worst_p = 0, worst_R = 0, travel = 0;
  for (Index s = 0; s < run.trajectory.samples(); ++s) {
    const double t = run.trajectory.t[std::size_t(s)], c = std::cos(2 * M_PI * t);
    const Eigen::Vector3d want =
        p0 + 0.05 * Eigen::Vector3d(1 - c, std::sin(2 * M_PI * t) * (1 - c), 0);
    const Eigen::Matrix3d R_want =
        Eigen::AngleAxisd(0.3 * (1 - c), Eigen::Vector3d::UnitZ()) * u0.toRotationMatrix();
    tree::forward_kinematics(arm, Eigen::Map<const VectorXd>(run.trajectory.q.data() + s * 7, 7),
                             d);
    worst_p = std::max(worst_p, (tree::world_point(d, tool, {0, 0, 0}) - want).norm());
    worst_R = std::max(worst_R,
                       Eigen::AngleAxisd(R_want.transpose() * d.R_WL[std::size_t(tool)]).angle());
    travel = std::max(travel, (want - p0).norm());
  }
  EXPECT_GT(travel, 0.09);
  EXPECT_NEAR(worst_p, 0.0, 1e-8);
  EXPECT_NEAR(worst_R, 0.0, 1e-8);
  std::printf("model-file task-space tracking: position %.2e m, orientation %.2e rad\n", worst_p,
              worst_R);
  // what a pose requirement refuses
  EXPECT_NE(failure_of("coordinates: [x]\nkinetic_energy: x_dot^2/2\ncontrol:\n  requirements:\n"
                       "    - {name: p, pose: {link: a, position: [0, 0, t]}}\n")
                .text.find("a pose requirement needs a robot:"),
            std::string::npos);
  EXPECT_NE(failure_of("robot: {urdf: panda_arm.urdf}\ncontrol:\n  requirements:\n"
                       "    - {name: p, pose: {link: panda_tool, position: [0, 0, t],"
                       " orientation: [1, 0, 0, 1]}}\n")
                .text.find("orientation must be a unit quaternion, its norm at t = 0 is 1.414"),
            std::string::npos);
  EXPECT_NE(
      failure_of("robot: {urdf: panda_arm.urdf}\ncontrol:\n  requirements:\n"
                 "    - {name: p, pose: {link: panda_tool, position: [panda_joint1, 0, t]}}\n")
          .text.find("position may depend on t and the parameters only, not on "
                     "'panda_joint1'"),
      std::string::npos);
}

std::string write_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / name;
  std::ofstream(path) << text;
  return path.string();
}

// A q'' = b of every constraint of a system at a state (rows stacked)
std::pair<MatrixXd, VectorXd> acceleration_forms(const System& s, const VectorXd& q,
                                                 const VectorXd& qd) {
  Index m = 0;
  for (Index k = 0; k < s.constraint_count(); ++k) m += s.constraint(k).rows();
  MatrixXd A(m, q.size());
  VectorXd b(m);
  Index row = 0;
  for (Index k = 0; k < s.constraint_count(); ++k) {
    const Constraint& c = s.constraint(k);
    auto scratch = c.model().make_scratch(q.size());
    c.model().acceleration_form(q, qd, 0.0, scratch.get(), A.middleRows(row, c.rows()),
                                b.segment(row, c.rows()));
    row += c.rows();
  }
  return {A, b};
}

// weld and revolute loops in a model file are the C++ closures (tree::weld_constraint,
// tree::revolute_constraint) with the frames the file gives: rpy as URDF's, axis_b = axis_a
TEST(ModelRobot, WeldAndRevoluteLoops) {
  const Model m = robot_model(R"(robot:
  urdf: panda_arm.urdf
  loops:
    - {name: glue, type: weld, link_a: panda_tool, point_a: [0, 0, 0.05], rpy_a: [0.1, 0.2, 0.3],
       link_b: panda_link3, point_b: [0.1, 0, 0.2]}
    - {name: hinge, type: revolute, link_a: panda_link5, point_a: [0, 0.1, 0], axis_a: [0, 1, 1],
       link_b: world, point_b: [0.3, 0.1, 0.4]}
)");
  ASSERT_EQ(m.system.constraint_count(), 2);
  EXPECT_EQ(m.system.constraint(0).rows(), 6);
  EXPECT_EQ(m.system.constraint(1).rows(), 5);
  const tree::Tree arm = tree::load_urdf(kPanda);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  SystemBuilder sb = tree::system_builder(arm);
  sb.add(tree::weld_constraint(arm, "glue", {arm.link_index("panda_tool"), {0, 0, 0.05}, R},
                               {arm.link_index("panda_link3"), {0.1, 0, 0.2}}));
  sb.add(tree::revolute_constraint(arm, "hinge", {arm.link_index("panda_link5"), {0, 0.1, 0}},
                                   {0, 1, 1}, {-1, {0.3, 0.1, 0.4}}, {0, 1, 1}));
  const System direct = sb.build();
  VectorXd q(7), qd(7);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd << 0.4, -0.3, 0.5, 0.2, -0.6, 0.3, 0.7;
  const auto [A, b] = acceleration_forms(m.system, q, qd);
  const auto [A_direct, b_direct] = acceleration_forms(direct, q, qd);
  EXPECT_NEAR((A - A_direct).norm(), 0.0, 0.0);
  EXPECT_NEAR((b - b_direct).norm(), 0.0, 0.0);
  EXPECT_GT(A.norm(), 1.0);
  // keys of another type, a hinge without its axis
  Failure f = failure_of(
      "robot:\n  urdf: panda_arm.urdf\n  loops:\n    - {name: a, type: revolute, link_a: "
      "panda_tool,\n       link_b: world, rpy_a: [0, 0, 1]}\n");
  EXPECT_NE(f.text.find("loop 'a': rpy_a is for weld loops only"), std::string::npos) << f.text;
  EXPECT_EQ(f.line, 5);
  f = failure_of(
      "robot:\n  urdf: panda_arm.urdf\n  loops:\n    - {name: a, type: revolute, link_a: "
      "panda_tool, link_b: world}\n");
  EXPECT_NE(f.text.find("loop 'a' needs axis_a"), std::string::npos) << f.text;
  f = failure_of(
      "robot:\n  urdf: panda_arm.urdf\n  loops:\n    - {name: a, type: hinge, link_a: "
      "panda_tool, link_b: world}\n");
  EXPECT_NE(f.text.find("type must be point, distance, revolute or weld"), std::string::npos)
      << f.text;
}

// nonideal: on a robot, as in any model file: a viscous friction on joint 1 and a force given by
// its C on joint 2 act as joint dampers of the same coefficients would (an independent route:
// the tree's own damping), and the run's energy balance accounts for their work
TEST(ModelRobot, NonIdealForcesOnARobot) {
  const Model m = robot_model(R"(robot: {urdf: panda_arm.urdf}
parameters: {c2: 0.3}
nonideal:
  - {friction: viscous, c: 0.7, coordinates: [panda_joint1]}
  - {C: [0, -c2*panda_joint2_dot, 0, 0, 0, 0, 0]}
initial:
  q: {panda_joint4: -1.5}
  q_dot: {panda_joint1: 1.0, panda_joint2: -0.5}
simulate: {t_end: 0.3}
)");
  ASSERT_EQ(m.system.nonideal_count(), 2);
  std::vector<tree::Link> links;
  const tree::Tree arm = tree::load_urdf(kPanda);
  for (Index i = 0; i < arm.link_count(); ++i) links.push_back(arm.link(i));
  links[1].joint.damping += 0.7;
  links[2].joint.damping += 0.3;
  const System damped = tree::make_system(tree::Tree("damped", links, arm.gravity()));
  Workspace ws(m.system), ws_damped(damped);
  VectorXd q(7), qd(7);
  q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
  qd << 0.4, -0.3, 0.5, 0.2, -0.6, 0.3, 0.7;
  ASSERT_EQ(forward_dynamics(m.system, ws, q, qd, 0.0), Status::kOk);
  ASSERT_EQ(forward_dynamics(damped, ws_damped, q, qd, 0.0), Status::kOk);
  EXPECT_NEAR((ws.qdd - ws_damped.qdd).cwiseAbs().maxCoeff(), 0.0,
              1e-12 * ws_damped.qdd.cwiseAbs().maxCoeff());
  EXPECT_NEAR(ws.Qc_nonideal[0], -0.7 * qd[0], 1e-15);
  EXPECT_NEAR(ws.Qc_nonideal[1], -0.3 * qd[1], 1e-15);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  EXPECT_LT(tr.work_nonideal.back(), -1e-3);  // the friction did work
  EXPECT_NEAR(tr.stats.energy_balance, 0.0, 1e-6);
}

// ---- the example robots (examples/models/, their URDFs in examples/robots/) ----------------

const std::string kExamples = UKDYN_EXAMPLES_DIR;

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// issue #30 item 6, combined: a closed chain (the four-bar knee, a revolute loop) with joint
// friction (URDF's Coulomb friction on the hip, viscous friction from nonideal: on the knee)
// under exact task-space control of the foot, as an ensemble over the path's size on 1 and on 3
// threads: the same bits whichever thread ran a sample, each sample's foot on its path and its
// loop closed; and one run checked against the path and the loop independently (forward
// kinematics of the tree)
TEST(ModelRobot, ClosedChainLegWithFrictionUnderTaskSpaceControlOnSeveralThreads) {
  const std::string file = kExamples + "/leg_four_bar_knee.yaml";
  const EnsembleModel em{read_text(file), file, {}, {}};
  std::vector<EnsembleSample> samples;
  for (double r : {0.02, 0.03, 0.04, 0.05}) samples.push_back({{{"r", r}}, {}, {}});
  EnsembleOptions one, three;
  one.threads = 1;
  three.threads = 3;
  one.at = three.at = {0.5, 1.0, 2.0};
  const EnsembleResult a = run_ensemble(em, samples, one), b = run_ensemble(em, samples, three);
  ASSERT_EQ(a.samples.size(), 4u);
  ASSERT_EQ(b.samples.size(), 4u);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    ASSERT_TRUE(a.samples[k].ok()) << a.samples[k].message;
    ASSERT_TRUE(b.samples[k].ok()) << b.samples[k].message;
    EXPECT_TRUE(a.samples[k].controlled);
    EXPECT_EQ(a.samples[k].values, b.samples[k].values);  // bit for bit
    EXPECT_EQ(a.samples[k].stats.steps, b.samples[k].stats.steps);
    EXPECT_EQ(a.samples[k].control.not_met, 0);
    EXPECT_NEAR(a.samples[k].stats.max_position_violation, 0.0, 1e-9);
  }
  // samples differ (the parameter reached the runs)
  EXPECT_NE(a.samples[0].values, a.samples[3].values);
  // one run, checked independently
  const Model m = load_model(file);
  ASSERT_NE(m.controller, nullptr);
  ASSERT_NE(m.robot, nullptr);
  EXPECT_EQ(m.system.nonideal_count(), 2);  // the hip's (URDF) and the knee's (nonideal:)
  const ControlledTrajectory run =
      simulate_controlled(*m.controller, m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(run.plant.stats.status, Status::kOk) << run.plant.stats.message;
  const tree::Tree& leg = *m.robot;
  tree::TreeData d(leg);
  const Index n = leg.coordinate_count(), foot = leg.link_index("foot"),
              back = leg.link_index("back_bar"), shin = leg.link_index("shin");
  double worst_foot = 0, worst_loop = 0, travel = 0, friction_work = 0;
  const double r = 0.04, h = 0.03, w = M_PI;
  for (Index s = 0; s < run.samples(); ++s) {
    const double t = run.plant.t[std::size_t(s)];
    tree::forward_kinematics(leg, Eigen::Map<const VectorXd>(run.plant.q.data() + s * n, n), d);
    const Eigen::Vector3d want(-0.29 + r * (1 - std::cos(w * t)), 0,
                               0.313 + h * std::pow(std::sin(w * t), 2));
    const Eigen::Vector3d foot_W = tree::world_point(d, foot, Eigen::Vector3d::Zero());
    worst_foot = std::max(worst_foot, (foot_W - want).norm());
    travel = std::max(travel, (want - Eigen::Vector3d(-0.29, 0, 0.313)).norm());
    worst_loop = std::max(worst_loop, (tree::world_point(d, back, {0.03, 0, -0.074}) -
                                       tree::world_point(d, shin, {-0.01, 0, -0.037}))
                                          .norm());
  }
  friction_work = run.plant.work_nonideal.back();
  EXPECT_GT(travel, 0.05);
  EXPECT_NEAR(worst_foot, 0.0, 1e-8);
  EXPECT_NEAR(worst_loop, 0.0, 1e-10);
  EXPECT_LT(friction_work, -1e-3);  // the friction took energy, which the control supplied
  std::printf("leg: foot on its path to %.2e m, loop closed to %.2e m, friction work %.4f J\n",
              worst_foot, worst_loop, friction_work);
}

// the humanoid in zero gravity: its momentum stays zero (it starts at rest and only internal
// torques act), so its centre of mass stays put, while the pelvis turns
TEST(ModelRobot, HumanoidInZeroGravityKeepsItsMomentumAndTurns) {
  const Model m = load_model(kExamples + "/humanoid_zero_gravity.yaml");
  ASSERT_NE(m.robot, nullptr);
  const tree::Tree& body = *m.robot;
  ASSERT_EQ(body.coordinate_count(), 33);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  tree::TreeData d(body);
  const Index n = 33;
  tree::forward_kinematics(body, m.q0, d);
  const Eigen::Vector3d g0 = tree::center_of_mass(body, d);
  double worst_p = 0, worst_g = 0, scale = 0;
  for (Index s = 0; s < tr.samples(); ++s) {
    const Eigen::Map<const VectorXd> q(tr.q.data() + s * n, n), qd(tr.qd.data() + s * n, n);
    const tree::Vector6d p = tree::momentum(body, q, qd, d);
    worst_p = std::max(worst_p, p.cwiseAbs().maxCoeff());
    worst_g = std::max(worst_g, (tree::center_of_mass(body, d) - g0).norm());
    scale = std::max(scale, qd.tail(26).cwiseAbs().maxCoeff());
  }
  const Eigen::Map<const VectorXd> q_end(tr.q.data() + (tr.samples() - 1) * n, n);
  const Eigen::Quaterniond u(q_end[3], q_end[4], q_end[5], q_end[6]);
  EXPECT_GT(scale, 1.0);  // the limbs moved fast
  EXPECT_NEAR(worst_p, 0.0, 1e-6);
  EXPECT_NEAR(worst_g, 0.0, 1e-7);
  EXPECT_GT(Eigen::AngleAxisd(u).angle(), 0.01);  // yet the body turned
  std::printf("humanoid: |momentum| <= %.2e, centre of mass moved %.2e m, pelvis turned %.3f rad\n",
              worst_p, worst_g, Eigen::AngleAxisd(u).angle());
}

// the mobile manipulator's wheels roll without slipping: each wheel's contact point (its centre
// − R z) has zero velocity, computed from the tree's frame Jacobian, not from the constraints
TEST(ModelRobot, MobileManipulatorWheelsRollWithoutSlipping) {
  const Model m = load_model(kExamples + "/mobile_manipulator.yaml");
  ASSERT_NE(m.robot, nullptr);
  const tree::Tree& robot = *m.robot;
  const Index n = robot.coordinate_count();
  ASSERT_EQ(n, 8);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  tree::TreeData d(robot);
  Eigen::Matrix<double, 6, Eigen::Dynamic> J(6, n);
  double worst = 0, speed = 0, turned = 0;
  for (Index s = 0; s < tr.samples(); ++s) {
    const Eigen::Map<const VectorXd> q(tr.q.data() + s * n, n), qd(tr.qd.data() + s * n, n);
    tree::forward_kinematics(robot, q, d);
    for (const char* wheel : {"wheel_left", "wheel_right"}) {
      const Index l = robot.link_index(wheel);
      // the contact point, R below the wheel's centre, in the wheel's frame
      const Eigen::Vector3d down = d.R_WL[std::size_t(l)].transpose() * Eigen::Vector3d(0, 0, -0.1);
      tree::frame_jacobian(robot, d, l, down, J);
      worst = std::max(worst, (J.bottomRows<3>() * qd).norm());
    }
    speed = std::max(speed, qd.head<2>().norm());
    turned = std::max(turned, std::abs(q[2]));
  }
  EXPECT_GT(speed, 0.3);   // it drove
  EXPECT_GT(turned, 0.3);  // and turned
  EXPECT_NEAR(worst, 0.0, 1e-7);
}

TEST(ModelRobot, ErrorsNameTheFileTheLineAndTheLinkOrJoint) {
  // a link the URDF lacks, located at the loop's link
  Failure f = failure_of(
      "robot:\n  urdf: panda_arm.urdf\n  loops:\n    - {name: a, type: point, link_a: hand,"
      " link_b: world}\n");
  EXPECT_NE(f.text.find("loop 'a': no link 'hand' in "), std::string::npos) << f.text;
  EXPECT_NE(f.text.find("the links are world, panda_link0"), std::string::npos) << f.text;
  EXPECT_EQ(f.line, 4);
  // a missing URDF, at urdf:
  f = failure_of("name: x\nrobot: {urdf: nothere.urdf}\n");
  EXPECT_NE(f.text.find("nothere.urdf: no such file"), std::string::npos) << f.text;
  EXPECT_EQ(f.line, 2);
  // what a URDF cannot be mixed with
  f = failure_of("robot: {urdf: panda_arm.urdf}\nbodies: {}\n");
  EXPECT_NE(f.text.find("'bodies' does not go with 'robot:'"), std::string::npos) << f.text;
  EXPECT_EQ(f.line, 2);
  // a torque on a joint the robot does not have
  f = failure_of("robot: {urdf: panda_arm.urdf, torques: {elbow: 1}}\n");
  EXPECT_NE(f.text.find("unknown coordinate 'elbow'"), std::string::npos) << f.text;
  f = failure_of("robot: {urdf: panda_arm.urdf, colour: red}\n");
  EXPECT_NE(f.text.find("unknown key 'colour' in robot"), std::string::npos) << f.text;
  f = failure_of(
      "robot:\n  urdf: panda_arm.urdf\n  loops: [{name: r, type: distance, link_a: panda_tool,"
      " link_b: world}]\n");
  EXPECT_NE(f.text.find("loop 'r' needs length"), std::string::npos) << f.text;
  // a URDF alone with an unknown joint type and a moving link without inertia: the file and the
  // joint or link
  const std::string planar = write_file(
      "ukdyn_robot_planar.urdf",
      "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"><inertial><mass value=\"1\"/>"
      "<inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link>"
      "<joint name=\"slide\" type=\"planar\"><parent link=\"a\"/><child link=\"b\"/>"
      "<axis xyz=\"0 0 1\"/></joint></robot>\n");
  try {
    load_model(planar);
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.file(), planar);
    EXPECT_NE(e.message().find("joint 'slide' (child link 'b'): joint type 'planar' is not "
                               "supported"),
              std::string::npos)
        << e.message();
  }
  const std::string noinertia =
      write_file("ukdyn_robot_noinertia.urdf",
                 "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/>"
                 "<joint name=\"hinge\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/>"
                 "<axis xyz=\"0 0 1\"/></joint></robot>\n");
  try {
    load_model(noinertia);
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(e.message().find("link 'b' moves (joint 'hinge') but has no <inertial>"),
              std::string::npos)
        << e.message();
  }
  const std::string broken = write_file("ukdyn_robot_broken.urdf", "<robot name=\"r\"><link");
  try {
    load_model(broken);
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_NE(e.message().find("not a valid URDF"), std::string::npos) << e.message();
  }
}

// URDF joint friction is regularized at 1e-6 rad/s in the model's units (repro u13/04: it was
// 1e-6 per model time unit, 1e-3 rad/s in ms, and the arm in mm, g, ms hit the table 6.7e-7 later
// than in SI). A two-link arm (elbow friction 0.02 N m, shoulder damping 0.05 N m s) released
// horizontal hits a table with its tip sphere: first impact at 0.2650392564974 s by an
// independent integration (scipy Radau, eps = 1e-6 rad/s); the same arm in mm, g, ms with
// units: {length: mm, mass: g, time: ms} hits at the same time to 1e-9 relative, and
// robot: friction_regularization: sets eps (the SI arm at 1e-3 rad/s is the mm arm without
// units:, whose eps is 1e-6 rad/ms).
TEST(ModelRobot, UrdfFrictionRegularizationIsInTheModelsUnits) {
  const auto first_impact = [](const std::string& text) {
    const Model m = robot_model(text);
    const ModelRun run = run_model(m);
    EXPECT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
    const auto& events = run.trajectory.stats.contact_events;
    EXPECT_FALSE(events.empty());
    return events.empty() ? std::pair(0.0, 0.0) : std::pair(events[0].t, events[0].speed_before);
  };
  const std::string si = R"(
robot: {urdf: arm2_friction.urdf}
contacts:
  - {name: tip, link: fore, point: [0.35, 0, 0], shape: sphere, radius: 0.02, restitution: 0.5,
     plane: {body: ground, point: [0, 0, 0.2], normal: [0, 0, 1]}}
simulate: {t_end: 0.3, rtol: 1e-10, atol: 1e-12}
output: {every: 0.01}
)";
  const std::string mm = R"(
robot: {urdf: arm2_friction_mm.urdf, urdf_units: model, gravity: [0, 0, -9.81e-3]}
contacts:
  - {name: tip, link: fore, point: [350, 0, 0], shape: sphere, radius: 20, restitution: 0.5,
     plane: {body: ground, point: [0, 0, 200], normal: [0, 0, 1]}}
simulate: {t_end: 300, rtol: 1e-10, atol: 1e-12}
output: {every: 10}
)";
  const auto [t_si, v_si] = first_impact(si);
  const auto [t_mm, v_mm] = first_impact(mm + "units: {length: mm, mass: g, time: ms}\n");
  EXPECT_NEAR(t_si, 0.2650392564974, 1e-11);
  EXPECT_NEAR(t_mm * 1e-3, t_si, 1e-9 * t_si);
  // (mm/ms is m/s; the speed at the impact to 5e-9, the runs' error at rtol 1e-10: it was 2.8e-6
  // off)
  EXPECT_NEAR(v_mm, v_si, 5e-9 * std::abs(v_si));
  // the mm arm without units: (eps = 1e-6 rad/ms = 1e-3 rad/s) is the SI arm at 1e-3 rad/s
  const auto [t_mm3, v_mm3] = first_impact(mm);
  std::string si3 = si;
  si3.replace(si3.find("urdf: arm2_friction.urdf"), 24,
              "urdf: arm2_friction.urdf, friction_regularization: 1e-3");
  const auto [t_si3, v_si3] = first_impact(si3);
  EXPECT_NEAR(t_mm3 * 1e-3, t_si3, 1e-9 * t_si3);
  EXPECT_NEAR(std::abs(t_si3 - t_si), 6.7e-7 * t_si, 1e-7 * t_si);  // (the repro's difference)
  (void)v_mm3;
  (void)v_si3;
  // a regularization that is not a finite number > 0 is refused where it is written
  try {
    robot_model("robot: {urdf: arm2_friction.urdf, friction_regularization: 0}\n");
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 1);
    EXPECT_NE(e.message().find("friction_regularization must be a finite number > 0, got 0"),
              std::string::npos)
        << e.message();
  }
}

// The same robot in SI units and in mm, g, ms runs the same steps on default settings (u18 03):
// a two-link arm (tests/data/arm2_hit*.urdf: joint damping 0.05 / 0.02 N m s and Coulomb joint
// friction 0.1 / 0.05 N m, or neither) released horizontal at its neutral pose q = 0 hits a
// table at z = 0.6 m with its tip sphere, e = 0.5. A state at q = 0 gives no length, so the
// integrators' rate unit on q' comes from the model's time unit (1 in s, 1e-3 in ms: it was 1 in
// both, 1000 times looser in ms), the first step tried is 1e-3 s in it (it was 1e-3 ms), and
// the work channels' energy unit is the power of 1000 itself (it was 1024 for 1000): the mm
// arm took 206 steps against 268 and hit 1.2e-6 ms off, against 8.3e-9 ms. First impact by an
// independent integration (SymPy Lagrangian, DOP853 at rtol 1e-12, the friction regularized as
// documented): t₁ = 264.5106362701 ms; the frictionless arm's is compared between the units.
TEST(ModelRobot, AnArmInMillimetresGramsAndMillisecondsRunsTheStepsOfSI) {
  const std::string table = R"(
contacts:
  - {name: tip, link: fore, point: [L, 0, 0], shape: sphere, radius: R, restitution: 0.5,
     plane: {body: ground, point: [0, 0, H], normal: [0, 0, 1]}}
initial:
  q: {shoulder: 0, elbow: 0}
)";
  const auto text = [&](bool mm, bool friction) {
    std::string t = std::string("robot: {urdf: arm2_hit") + (friction ? "" : "_free") +
                    (mm ? "_mm.urdf, urdf_units: model, gravity: [0, 0, -9.81e-3]}" : ".urdf}") +
                    table +
                    (mm ? "simulate: {t_end: 1500}\noutput: {every: 10}\n"
                          "units: {length: mm, mass: g, time: ms}\n"
                        : "simulate: {t_end: 1.5}\n");
    const auto put = [&](const std::string& key, const char* si, const char* in_mm) {
      const std::size_t at = t.find(key);
      t.replace(at, key.size(), mm ? in_mm : si);
    };
    put("L,", "0.5,", "500,");
    put("R,", "0.02,", "20,");
    put("H]", "0.6]", "600]");
    return t;
  };
  for (const bool friction : {true, false}) {
    SCOPED_TRACE(friction ? "with joint friction" : "without");
    const ModelRun si = run_model(robot_model(text(false, friction)));
    const ModelRun mm = run_model(robot_model(text(true, friction)));
    ASSERT_EQ(si.trajectory.stats.status, Status::kOk) << si.trajectory.stats.message;
    ASSERT_EQ(mm.trajectory.stats.status, Status::kOk) << mm.trajectory.stats.message;
    // (the accepted steps: the same count; the rejected ones may differ by roundoff after the
    // arm comes to rest on the table at 0.548 s, where its joint friction's regularized sign
    // decides them: 62 against 60 with joint friction)
    EXPECT_EQ(mm.trajectory.stats.steps, si.trajectory.stats.steps);
    EXPECT_NEAR(double(mm.trajectory.stats.rejected_steps),
                double(si.trajectory.stats.rejected_steps), 3.0);
    const auto& e_si = si.trajectory.stats.contact_events;
    const auto& e_mm = mm.trajectory.stats.contact_events;
    ASSERT_FALSE(e_si.empty());
    ASSERT_EQ(e_mm.size(), e_si.size());
    const double t1 = e_si[0].t;
    EXPECT_NEAR(e_mm[0].t * 1e-3, t1, 1e-9 * t1);
    if (friction) EXPECT_NEAR(t1, 0.2645106362701, 1e-10 * t1);  // (the SI run as before)
    for (std::size_t k = 0; k < e_si.size(); ++k)
      EXPECT_NEAR(e_mm[k].t * 1e-3, e_si[k].t, 1e-9 * e_si[k].t) << "event " << k;
  }
}

// A URDF is SI by its specification (u21 03): in a model with units: its numbers are converted
// into the model's, so the same file runs the same motion in any units. tests/data/arm2_friction
// .urdf (joint damping 0.05 N m s, Coulomb joint friction 0.02 N m) released from rest: in mm, g,
// ms (gravity left to its default) and in km, t, h its shoulder and elbow follow the SI run
// (1e-9 relative, at rtol 1e-11); the tree read in mm, g, ms is the hand-scaled
// arm2_friction_mm.urdf read as it is (urdf_units: model): masses x1e3, centres and origins
// x1e3, inertias x1e9, damping x1e6, friction x1e3 (1e-12 relative); a visual's size and origin
// x1e3. Before, the mm arm was 1000 times smaller and heavier-pulled: 1.717 rad at 300 ms
// against SI's 1.000 rad at 0.3 s.
TEST(ModelRobot, AnSIUrdfRunsTheSameMotionInAnyUnits) {
  const auto final_q = [](const std::string& text, double t_end) {
    Model m = robot_model(text);
    m.options.t_end = t_end;
    m.options.rtol = 1e-11;
    m.options.atol = 1e-13;
    const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
    EXPECT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
    const std::size_t n = std::size_t(m.system.coordinate_count()), last = tr.t.size() - 1;
    return Eigen::Vector2d(tr.q[n * last], tr.q[n * last + 1]);
  };
  const std::string initial = "initial:\n  q: {shoulder: 0.2, elbow: -0.4}\n";
  const Eigen::Vector2d si = final_q("robot: {urdf: arm2_friction.urdf}\n" + initial, 0.3);
  const Eigen::Vector2d mm = final_q(
      "robot: {urdf: arm2_friction.urdf}\n" + initial + "units: {length: mm, mass: g, time: ms}\n",
      300.0);
  const Eigen::Vector2d km = final_q(
      "robot: {urdf: arm2_friction.urdf}\n" + initial + "units: {length: km, mass: t, time: h}\n",
      0.3 / 3600.0);
  EXPECT_GT(std::abs(si[0] - 0.2), 0.3);  // (it swings)
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(mm[i], si[i], 1e-9 * std::abs(si[i])) << "joint " << i;
    EXPECT_NEAR(km[i], si[i], 1e-9 * std::abs(si[i])) << "joint " << i;
  }
  // the tree in mm, g, ms against the hand-scaled file read as it is
  const Model a =
      robot_model("robot: {urdf: arm2_friction.urdf}\nunits: {length: mm, mass: g, time: ms}\n");
  const Model b = robot_model(
      "robot: {urdf: arm2_friction_mm.urdf, urdf_units: model}\n"
      "units: {length: mm, mass: g, time: ms}\n");
  ASSERT_EQ(a.robot->link_count(), b.robot->link_count());
  const auto close = [](double x, double y) { return std::abs(x - y) <= 1e-12 * std::abs(y); };
  for (Index i = 0; i < a.robot->link_count(); ++i) {
    const tree::Link& la = a.robot->link(i);
    const tree::Link& lb = b.robot->link(i);
    EXPECT_TRUE(close(la.inertial.mass, lb.inertial.mass)) << la.name;
    EXPECT_LE((la.inertial.com - lb.inertial.com).norm(), 1e-12 * (1.0 + lb.inertial.com.norm()));
    EXPECT_LE((la.inertial.I_com - lb.inertial.I_com).norm(), 1e-12 * lb.inertial.I_com.norm())
        << la.name;
    EXPECT_LE((la.joint.p_PJ - lb.joint.p_PJ).norm(), 1e-12 * (1.0 + lb.joint.p_PJ.norm()));
    EXPECT_TRUE(close(la.joint.damping, lb.joint.damping)) << la.name;
    EXPECT_TRUE(close(la.joint.friction, lb.joint.friction)) << la.name;
  }
  EXPECT_NEAR(a.robot->gravity().z(), -9.81e-3, 1e-15);
  // and the file written in them (urdf_units: model): Earth's gravity in mm/ms² still, not
  // 9.81 mm/ms² (u22 01: 1000 g, a pendulum √1000 times too fast)
  EXPECT_NEAR(b.robot->gravity().z(), -9.81e-3, 1e-15);
  // a visual's origin and size in the model's length unit
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("ukdyn_urdf_units_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "boxed.urdf") << R"(<?xml version="1.0"?>
<robot name="boxed">
  <link name="base"/>
  <link name="arm">
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <visual><origin xyz="0.1 0 0.05"/><geometry><box size="0.2 0.04 0.03"/></geometry></visual>
  </link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="30" velocity="2"/></joint>
</robot>
)";
  const Model v = parse_model("robot: {urdf: boxed.urdf}\nunits: {length: mm, mass: g, time: ms}\n",
                              (dir / "m.yaml").string());
  ASSERT_EQ(v.visual.robot.size(), 1u);
  EXPECT_NEAR(v.visual.robot[0].size.x(), 200.0, 1e-12);
  EXPECT_NEAR(v.visual.robot[0].size.z(), 30.0, 1e-12);
  EXPECT_NEAR(v.visual.robot[0].p_LV.x(), 100.0, 1e-12);
  // a revolute joint's effort (N m: x1e3 in g mm²/ms²) and velocity limit (rad/s: x1e-3)
  EXPECT_NEAR(v.robot->link(1).joint.effort, 30.0 * 1e3, 1e-9);
  EXPECT_NEAR(v.robot->link(1).joint.velocity, 2e-3, 1e-15);
  EXPECT_NEAR(v.robot->link(1).joint.upper, 1.0, 0.0);
  std::filesystem::remove_all(dir);
  // urdf_units: neither si nor model is refused where it is written
  try {
    robot_model("robot: {urdf: arm2_friction.urdf, urdf_units: mm}\n");
    FAIL() << "no error";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 1);
    EXPECT_NE(e.message().find("robot urdf_units must be si or model, got 'mm'"), std::string::npos)
        << e.message();
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// A robotics user's findings on robot model files (modelfile/reader_urdf.cpp, run.cpp; u20 07,
// 08, 01): URDF names that are not identifiers written as such in an expression, the
// messages of a distance loop of length 0, of gravity in other units, of a missing URDF and of
// a comma inside a flow list; velocity and torques: effort limits noted by a run; <mimic> in a
// model; a URDF's errors at their place in it, alone and in a model file (u23 07).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "ukdyn/core/format.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

const std::filesystem::path kDir = std::filesystem::temp_directory_path() / "ukdyn_robot_messages";

// the two-link arm of u20's reproducers (SI), with a joint's name, limits and mimic as given
std::string arm_urdf(const std::string& elbow_name, const std::string& shoulder_limit,
                     const std::string& elbow_extra = "") {
  return R"(<?xml version="1.0"?>
<robot name="arm2">
  <link name="base"/>
  <link name="upper"><inertial><origin xyz="0.3 0 0"/><mass value="1.5"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.045" iyz="0" izz="0.045"/></inertial></link>
  <link name="fore"><inertial><origin xyz="0.25 0 0"/><mass value="1.0"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <origin xyz="0 0 1.0"/><axis xyz="0 1 0"/>
    )" + shoulder_limit +
         R"(</joint>
  <joint name=")" +
         elbow_name + R"(" type="continuous"><parent link="upper"/><child link="fore"/>
    <origin xyz="0.6 0 0"/><axis xyz="0 1 0"/>)" +
         elbow_extra + R"(</joint>
</robot>
)";
}

// the model `text` next to the URDF `urdf` (robot: {urdf: arm.urdf})
Model model_with(const std::string& urdf, const std::string& text) {
  std::filesystem::create_directories(kDir);
  std::ofstream(kDir / "arm.urdf") << urdf;
  return parse_model(text, (kDir / "robot.yaml").string());
}

struct Failure {
  std::string message, hint;
  int line = -1, column = -1;
};
Failure failure_of(const std::string& urdf, const std::string& text) {
  try {
    model_with(urdf, text);
  } catch (const ModelError& e) {
    return {e.message(), e.hint(), e.line(), e.column()};
  }
  return {"no error", "", -1, -1};
}

const std::string kLimit = R"(<limit lower="-3" upper="3" effort="50" velocity="10"/>)";

// u20 07: "hip-1" in an expression read as hip − 1 whenever a joint "hip" exists
TEST(RobotNames, AUrdfNameThatIsNoIdentifierIsRefusedWhereAnExpressionWritesIt) {
  const std::string urdf = arm_urdf("shoulder-1", kLimit);
  Failure f = failure_of(urdf, "robot: {urdf: arm.urdf}\noutput: {expressions: {h: shoulder-1}}\n");
  EXPECT_EQ(f.message,
            "in output expression 'h': 'shoulder-1' is the robot's coordinate 'shoulder-1' (a "
            "URDF name), which expressions write shoulder_1 (as written it would read as "
            "arithmetic on other names)")
      << f.message;
  EXPECT_EQ(f.line, 2);
  EXPECT_EQ(f.column, 27);  // at the name
  EXPECT_NE(f.hint.find("write shoulder_1 for the joint"), std::string::npos) << f.hint;
  f = failure_of(
      urdf, "robot: {urdf: arm.urdf}\nconstraints:\n  - {name: tie, holonomic: 2*shoulder-1}\n");
  EXPECT_NE(f.message.find("'shoulder-1' is the robot's coordinate"), std::string::npos)
      << f.message;
  EXPECT_EQ(f.line, 3);
  // the identifier, and the subtraction written with spaces, are what they say
  const Model m =
      model_with(urdf,
                 "robot: {urdf: arm.urdf}\noutput: {expressions: {h: shoulder_1, d: shoulder - 1, "
                 "e: shoulder-10}}\ninitial: {q: {shoulder_1: 0.25}}\n");
  EXPECT_EQ(m.system.coordinate_names()[1], "shoulder-1");
  EXPECT_EQ(m.q0[1], 0.25);
  const ModelRun run = run_model(m, [&] {
    SimulationOptions o = m.options;
    o.t_end = 0.01;
    return o;
  }());
  ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
  const auto column = [&](const std::string& name) -> double {
    for (const CsvColumn& c : run.extra_columns) {
      if (c.name == name) return c.values.front();
    }
    ADD_FAILURE() << "no column " << name;
    return NAN;
  };
  EXPECT_EQ(column("h"), 0.25);
  EXPECT_EQ(column("d"), -1.0);
  EXPECT_EQ(column("e"), -10.0);
}

// u20 08 (c)–(g): the messages say what to do
TEST(RobotMessages, LoopGravityMissingFileAndCommaSayWhatToDo) {
  const std::string urdf = arm_urdf("elbow", kLimit);
  Failure f = failure_of(urdf,
                         "robot: {urdf: arm.urdf, loops: [{name: l, type: distance, link_a: "
                         "fore, link_b: world, length: 0}]}\n");
  EXPECT_NE(f.message.find("loop 'l': a distance loop of length 0 holds the two points together"),
            std::string::npos)
      << f.message;
  EXPECT_EQ(f.hint, "use type: point for two points held together (3 rows)");
  EXPECT_EQ(f.message.find("point_constraint"), std::string::npos) << f.message;
  f = failure_of(urdf,
                 "robot: {urdf: arm.urdf, loops: [{name: l, type: distance, link_a: "
                 "fore, link_b: world, length: -0.5}]}\n");
  EXPECT_NE(f.message.find("length must be a finite number > 0, got -0.5"), std::string::npos)
      << f.message;
  // gravity in the model's units: 9.81 m/s² = 0.00981 mm/ms²
  f = failure_of(urdf,
                 "units: {length: mm, mass: g, time: ms}\nrobot: {urdf: arm.urdf, gravity: "
                 "[0, -9.81e-3]}\n");
  EXPECT_EQ(f.message, "robot gravity must be a list of 3 numbers (mm/ms²), got 2 items");
  EXPECT_EQ(f.hint, "gravity: [0, 0, -0.00981] (9.81 m/s² in mm/ms²)");
  f = failure_of(urdf, "robot: {urdf: arm.urdf, gravity: 9.81}\n");
  EXPECT_EQ(f.message, "robot gravity must be a list of 3 numbers (m/s²)");
  EXPECT_EQ(f.hint, "gravity: [0, 0, -9.81]");
  // a URDF that is not there
  f = failure_of(urdf, "robot: {urdf: nothere.urdf}\n");
  EXPECT_NE(f.message.find("nothere.urdf: no such file"), std::string::npos) << f.message;
  EXPECT_EQ(f.hint, "urdf: is relative to the model file's directory (" + kDir.string() +
                        "); check the name and its directory");
  // if(c, a, b) in a flow list: YAML made 5 items of 3
  f = failure_of(urdf, R"(robot: {urdf: arm.urdf}
control:
  requirements:
    - name: tip
      pose: {link: fore, point: [0.5, 0, 0], position: [0.8, 0, 0.57 + if(t - 1, (t - 1)^3, 0)]}
      dynamics: {omega: 10, zeta: 1}
)");
  EXPECT_NE(f.message.find("position must be a list of 3 expressions, got 5 items"),
            std::string::npos)
      << f.message;
  EXPECT_NE(f.hint.find("quote an expression that holds commas"), std::string::npos) << f.hint;
}

// u20 08 (a), (b): URDF's velocity limit and a torques: entry beyond effort are noted by the run
// (measured against the run's own samples: the largest |q'| and the constant torque)
TEST(RobotMessages, ARunNotesVelocityLimitsAndTorquesBeyondEffort) {
  const Model m =
      model_with(arm_urdf("elbow", R"(<limit lower="-3" upper="3" effort="50" velocity="0.5"/>)"),
                 "robot: {urdf: arm.urdf, torques: {shoulder: 80, elbow: -0.5}}\n");
  SimulationOptions o = m.options;
  o.t_end = 0.3;
  const ModelRun run = run_model(m, o);
  ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
  const auto& tr = run.trajectory;
  double fastest = 0.0, when = 0.0, first = -1.0;
  for (std::size_t s = 0; s < tr.t.size(); ++s) {
    const double w = std::abs(tr.qd[2 * s]);
    if (w > 0.5 && first < 0) first = tr.t[s];
    if (w > fastest) fastest = w, when = tr.t[s];
  }
  ASSERT_GT(fastest, 0.6);
  const auto has = [&](const std::string& text) {
    return std::any_of(tr.stats.notes.begin(), tr.stats.notes.end(),
                       [&](const std::string& n) { return n.find(text) != std::string::npos; });
  };
  EXPECT_TRUE(has("joint 'shoulder' exceeds its effort limit 50 by 30 N·m (first at t = 0 s"))
      << ::testing::PrintToString(tr.stats.notes);
  EXPECT_TRUE(has("joint 'shoulder' exceeds its velocity limit 0.5 by " +
                  format_number(fastest - 0.5, 4) + " rad/s (first at t = " +
                  format_number(first, 6) + " s, worst at t = " + format_number(when, 6) + " s)"))
      << ::testing::PrintToString(tr.stats.notes);
  EXPECT_FALSE(has("joint 'elbow'")) << ::testing::PrintToString(tr.stats.notes);  // no limit
}

// u23 07: a URDF's errors at their place in the URDF — given alone (`ukdyn run arm.urdf`: the
// error is the URDF's own, file:line:column) and in a model file (at its urdf: key, the URDF's
// place in the message): an element never closed, and a <mimic> of no joint
TEST(RobotMessages, UrdfErrorsAreLocatedInTheUrdf) {
  // the fore link (line 6, column 3) without its </link>: the joints are read into it, and
  // </robot> (line 13) comes first
  std::string unclosed = arm_urdf("elbow", kLimit);
  unclosed.erase(unclosed.find("</link>", unclosed.find("<link name=\"fore\">")), 7);
  const std::string unclosed_what =
      "not a valid URDF: <link name=\"fore\"> is not closed (no </link> before </robot> at 13:1)";
  // the elbow's <mimic> at line 12, column 47
  const std::string mimic = arm_urdf("elbow", kLimit, R"(<mimic joint="nosuch"/>)");
  const std::string mimic_what = "joint 'elbow' mimics 'nosuch': no joint 'nosuch' in 'arm2'";
  struct Case {
    std::string urdf, what;
    int line, column;
  };
  for (const Case& c : {Case{unclosed, unclosed_what, 6, 3}, Case{mimic, mimic_what, 12, 47}}) {
    // alone
    std::filesystem::create_directories(kDir);
    const std::string alone = (kDir / "alone.urdf").string();
    std::ofstream(alone) << c.urdf;
    try {
      load_model(alone);
      ADD_FAILURE() << "no error: " << c.what;
    } catch (const ModelError& e) {
      EXPECT_EQ(e.file(), alone);
      EXPECT_EQ(e.line(), c.line) << e.what();
      EXPECT_EQ(e.column(), c.column) << e.what();
      EXPECT_EQ(e.message(), c.what);
      EXPECT_EQ(std::string(e.what()), alone + ":" + std::to_string(c.line) + ":" +
                                           std::to_string(c.column) + ": error: " + c.what);
    }
    // in a model file: at urdf: (line 1, column 15), the URDF's place in the message
    const Failure f = failure_of(c.urdf, "robot: {urdf: arm.urdf}\n");
    EXPECT_EQ(f.line, 1);
    EXPECT_EQ(f.column, 15);
    EXPECT_EQ(f.message, (kDir / "arm.urdf").string() + ":" + std::to_string(c.line) + ":" +
                             std::to_string(c.column) + ": " + c.what);
    EXPECT_EQ(f.hint, "the line:column after the URDF's name is the element at fault in the URDF");
  }
}

// u20 01: <mimic> in a model: the constraint "<joint>.mimic" holds over a run, its neutral pose
// meets it, and lambda of the row is the coupling torque
TEST(RobotMimic, AMimicJointIsAConstraintOfTheModel) {
  const Model m = model_with(
      arm_urdf("elbow", kLimit, R"(<mimic joint="shoulder" multiplier="2" offset="0.1"/>)"),
      "robot: {urdf: arm.urdf}\n");
  ASSERT_EQ(m.system.constraint_count(), 1);
  EXPECT_EQ(m.system.constraint(0).name(), "elbow.mimic");
  EXPECT_EQ(m.q0[1], 0.1);
  SimulationOptions o = m.options;
  o.t_end = 0.5;
  const ModelRun run = run_model(m, o);
  ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
  const auto& tr = run.trajectory;
  const std::size_t last = tr.t.size() - 1;
  EXPECT_GT(std::abs(tr.q[2 * last]), 0.05);  // it fell
  EXPECT_NEAR(tr.q[2 * last + 1], 2 * tr.q[2 * last] + 0.1, 1e-8);
  EXPECT_NEAR(tr.qd[2 * last + 1], 2 * tr.qd[2 * last], 1e-7);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

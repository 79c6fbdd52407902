// SPDX-License-Identifier: BSD-3-Clause
// URDF import beyond the tree's passes (multibody/tree/urdf.cpp, mimic.cpp, description.cpp):
// <mimic> as a holonomic constraint against the closed form of the reduced 1-DOF arm, hostile
// mimics refused naming the joint, a 20 000-link chain loaded in linear time (its subtree masses
// against n·m), the errors of a bad <inertial> (urdfdom's own message, located), and every
// error at its file:line:column: malformed XML, names that name nothing, bad values (u23 07).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/simulation/simulate.hpp"

#include "support/urdf_errors.hpp"

using namespace ukdyn;
using namespace ukdyn::tree;

namespace UKDYN_TEST_FILE {

std::string write_file(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("ukdyn_tree_urdf_" + name + ".urdf");
  std::ofstream(path) << text;
  return path.string();
}

std::string urdf(const std::string& body) {
  return "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n" + body + "</robot>\n";
}

// the message of loading a refused URDF file
constexpr auto* load_error = &ukdyn::testing::urdf_load_error;

// ---- <mimic> ----

// the planar arm of Tree.DoublePendulumMatchesClosedForm (joints about y, links hanging along
// −z) with the elbow following the shoulder: q2 = mult·q1 + offset
struct MimicArm {
  double m1 = 1.3, m2 = 0.7, L1 = 0.9, c1 = 0.4, c2 = 0.35, I1 = 0.05, I2 = 0.02, g = 9.81;
  double mult = -0.6, offset = 0.4;
  Tree tree() const {
    Link a, b;
    a.name = "upper";
    a.joint.name = "shoulder";
    a.joint.kind = JointKind::kRevolute;
    a.joint.axis = Vector3d::UnitY();
    a.inertial.mass = m1;
    a.inertial.com = Vector3d(0, 0, -c1);
    a.inertial.I_com = Eigen::Vector3d(0.3, I1, 0.3).asDiagonal();
    b.name = "lower";
    b.parent = "upper";
    b.joint.name = "elbow";
    b.joint.kind = JointKind::kRevolute;
    b.joint.axis = Vector3d::UnitY();
    b.joint.p_PJ = Vector3d(0, 0, -L1);
    b.joint.mimic = "shoulder";
    b.joint.mimic_multiplier = mult;
    b.joint.mimic_offset = offset;
    b.inertial.mass = m2;
    b.inertial.com = Vector3d(0, 0, -c2);
    b.inertial.I_com = Eigen::Vector3d(0.2, I2, 0.2).asDiagonal();
    return Tree("mimic_arm", {a, b});
  }
  // the reduced system in θ = q1 (Lagrange with q2 = mult θ + offset substituted):
  // M_r(θ) θ'' + ½ M_r'(θ) θ'² + V'(θ) = 0
  double M11(double q2) const {
    return I1 + I2 + m1 * c1 * c1 + m2 * (L1 * L1 + c2 * c2 + 2 * L1 * c2 * std::cos(q2));
  }
  double M12(double q2) const { return I2 + m2 * (c2 * c2 + L1 * c2 * std::cos(q2)); }
  double M22() const { return I2 + m2 * c2 * c2; }
  double Mr(double th) const {
    const double q2 = mult * th + offset;
    return M11(q2) + 2 * mult * M12(q2) + mult * mult * M22();
  }
  double theta_dd(double th, double thd) const {
    const double q2 = mult * th + offset;
    const double dMr = -2 * m2 * L1 * c2 * mult * (1 + mult) * std::sin(q2);
    const double dV =
        g * ((m1 * c1 + m2 * L1) * std::sin(th) + m2 * c2 * (1 + mult) * std::sin(th + q2));
    return -(0.5 * dMr * thd * thd + dV) / Mr(th);
  }
  // the coupling torque λ on the elbow: its own equation M21 q1'' + M22 q2'' + h2 = λ
  double coupling(double th, double thd) const {
    const double q2 = mult * th + offset, tdd = theta_dd(th, thd);
    const double h2 = m2 * L1 * c2 * std::sin(q2) * thd * thd + m2 * g * c2 * std::sin(th + q2);
    return M12(q2) * tdd + M22() * mult * tdd + h2;
  }
  double energy(double th, double thd) const {
    const double q2 = mult * th + offset;
    return 0.5 * Mr(th) * thd * thd -
           g * (m1 * c1 * std::cos(th) + m2 * (L1 * std::cos(th) + c2 * std::cos(th + q2)));
  }
};

TEST(TreeMimic, ArmFollowsTheClosedFormOfItsReducedSystem) {
  const MimicArm arm;
  const Tree tree = arm.tree();
  ASSERT_EQ(tree.mimics().size(), 1u);
  const System sys = make_system(tree);
  ASSERT_EQ(sys.constraint_count(), 1);
  EXPECT_EQ(sys.constraint(0).name(), "elbow.mimic");
  // the neutral pose meets the mimic: q2 = offset
  EXPECT_EQ(tree.neutral()[1], arm.offset);
  Workspace ws(sys);
  for (const auto& [th, thd] :
       std::initializer_list<std::pair<double, double>>{{0.3, 1.1}, {-1.2, -0.4}, {2.5, 2.0}}) {
    VectorXd q(2), qd(2);
    q << th, arm.mult * th + arm.offset;
    qd << thd, arm.mult * thd;
    ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
    const double tdd = arm.theta_dd(th, thd), lambda = arm.coupling(th, thd);
    EXPECT_NEAR(ws.qdd[0], tdd, 1e-12 * (1 + std::abs(tdd)));
    EXPECT_NEAR(ws.qdd[1], arm.mult * tdd, 1e-12 * (1 + std::abs(tdd)));
    // Qc = Aᵀ λ, A = [−mult, 1]: λ on the elbow, −mult λ on the shoulder
    EXPECT_NEAR(ws.Qc[1], lambda, 1e-12 * (1 + std::abs(lambda)));
    EXPECT_NEAR(ws.Qc[0], -arm.mult * lambda, 1e-12 * (1 + std::abs(lambda)));
  }
  // 1 s of motion from rest at θ = 0.8 against RK4 of the reduced equation (h = 1e-4 s)
  VectorXd q0(2), qd0 = VectorXd::Zero(2);
  q0 << 0.8, arm.mult * 0.8 + arm.offset;
  SimulationOptions options;
  options.t_end = 1.0;
  options.rtol = 1e-11;
  options.atol = 1e-13;
  const Trajectory tr = simulate(sys, q0, qd0, options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  double th = 0.8, thd = 0.0;
  const double h = 1e-4;
  for (int k = 0; k < 10000; ++k) {
    const auto f = [&](double x, double v) { return std::pair{v, arm.theta_dd(x, v)}; };
    const auto [a1, b1] = f(th, thd);
    const auto [a2, b2] = f(th + 0.5 * h * a1, thd + 0.5 * h * b1);
    const auto [a3, b3] = f(th + 0.5 * h * a2, thd + 0.5 * h * b2);
    const auto [a4, b4] = f(th + h * a3, thd + h * b3);
    th += h / 6 * (a1 + 2 * a2 + 2 * a3 + a4);
    thd += h / 6 * (b1 + 2 * b2 + 2 * b3 + b4);
  }
  const std::size_t last = tr.t.size() - 1;
  ASSERT_NEAR(tr.t[last], 1.0, 1e-12);
  EXPECT_NEAR(tr.q[2 * last], th, 1e-8);
  EXPECT_NEAR(tr.qd[2 * last], thd, 1e-7);
  EXPECT_GT(std::abs(th - 0.8), 0.1);  // it moved
  // the mimic held and the energy conserved (an ideal, scleronomic row does no work)
  EXPECT_NEAR(tr.q[2 * last + 1], arm.mult * tr.q[2 * last] + arm.offset, 1e-9);
  EXPECT_NEAR(arm.energy(tr.q[2 * last], tr.qd[2 * last]), arm.energy(0.8, 0.0), 1e-8);
}

// a chain of mimics (j3 follows j2 follows j1) read from a URDF, with its defaults (multiplier
// 1, offset 0 when not given): the neutral pose meets both, the rows are independent
TEST(TreeMimic, ChainsOfMimicsAreReadFromUrdf) {
  const std::string inertial =
      "<inertial><origin xyz=\"0 0 -0.2\"/><mass value=\"1\"/><inertia ixx=\"0.01\" ixy=\"0\" "
      "ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"/></inertial>";
  std::string body = "<link name=\"base\"/>";
  for (const char* l : {"a", "b", "c"})
    body += std::string("<link name=\"") + l + "\">" + inertial + "</link>";
  body +=
      "<joint name=\"j1\" type=\"continuous\"><parent link=\"base\"/><child link=\"a\"/>"
      "<axis xyz=\"0 1 0\"/></joint>"
      "<joint name=\"j2\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/>"
      "<origin xyz=\"0 0 -0.4\"/><axis xyz=\"0 1 0\"/><mimic joint=\"j1\" multiplier=\"2\" "
      "offset=\"0.1\"/></joint>"
      "<joint name=\"j3\" type=\"prismatic\"><parent link=\"b\"/><child link=\"c\"/>"
      "<origin xyz=\"0 0 -0.4\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" "
      "effort=\"0\" velocity=\"1\"/><mimic joint=\"j2\"/></joint>";
  const Tree tree = load_urdf(write_file("mimic_chain", urdf(body)));
  ASSERT_EQ(tree.mimics().size(), 2u);
  const VectorXd q0 = tree.neutral();
  EXPECT_EQ(q0[0], 0.0);
  EXPECT_EQ(q0[1], 0.1);  // 2·0 + 0.1
  EXPECT_EQ(q0[2], 0.1);  // 1·0.1 + 0
  const System sys = make_system(tree);
  ASSERT_EQ(sys.constraint_count(), 2);
  EXPECT_EQ(sys.constraint(1).name(), "j3.mimic");
  // q2'' = 2 q1'', q3'' = q2'' at a moving state; both rows independent (1 DOF left)
  Workspace ws(sys);
  VectorXd q(3), qd(3);
  q << 0.4, 0.9, 0.9;
  qd << 0.7, 1.4, 1.4;
  ASSERT_EQ(forward_dynamics(sys, ws, q, qd, 0.0), Status::kOk);
  EXPECT_NEAR(ws.qdd[1], 2 * ws.qdd[0], 1e-12 * (1 + std::abs(ws.qdd[0])));
  EXPECT_NEAR(ws.qdd[2], ws.qdd[1], 1e-12 * (1 + std::abs(ws.qdd[1])));
  EXPECT_GT(std::abs(ws.qdd[0]), 0.1);
}

TEST(TreeMimic, HostileMimicsAreRefusedNamingTheJoint) {
  const std::string inertial =
      "<inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" "
      "iyz=\"0\" izz=\"0.1\"/></inertial>";
  const auto arm = [&](const std::string& j2_type, const std::string& mimic1,
                       const std::string& mimic2) {
    return urdf("<link name=\"base\"/><link name=\"a\">" + inertial + "</link><link name=\"b\">" +
                inertial +
                "</link><joint name=\"j1\" type=\"continuous\"><parent link=\"base\"/>"
                "<child link=\"a\"/><axis xyz=\"0 1 0\"/>" +
                mimic1 + "</joint><joint name=\"j2\" type=\"" + j2_type +
                "\"><parent link=\"a\"/><child link=\"b\"/><origin xyz=\"0 0 -1\"/>"
                "<axis xyz=\"0 1 0\"/>" +
                mimic2 + "</joint>");
  };
  const auto error = [&](const std::string& name, const std::string& text) {
    return load_error(write_file(name, text));
  };
  std::string e = error("mimic_unknown", arm("continuous", "", "<mimic joint=\"j9\"/>"));
  EXPECT_NE(e.find("joint 'j2' mimics 'j9': no joint 'j9' in 'r'"), std::string::npos) << e;
  EXPECT_EQ(e.find("ukdyn::tree::Tree"), std::string::npos) << e;
  e = error("mimic_self", arm("continuous", "", "<mimic joint=\"j2\"/>"));
  EXPECT_NE(e.find("joint 'j2' mimics 'j2': a joint cannot mimic itself"), std::string::npos) << e;
  e = error("mimic_cycle",
            arm("continuous", "<mimic joint=\"j2\" multiplier=\"0.5\"/>", "<mimic joint=\"j1\"/>"));
  EXPECT_NE(e.find("a cycle of mimics 'j1' → 'j2' → 'j1'"), std::string::npos) << e;
  e = error("mimic_fixed", arm("fixed", "", "<mimic joint=\"j1\"/>"));
  EXPECT_NE(e.find("joint 'j2' mimics 'j1': joint 'j2' is fixed"), std::string::npos) << e;
  e = error("mimic_nan", arm("continuous", "", "<mimic joint=\"j1\" multiplier=\"nan\"/>"));
  // (urdfdom refuses some spellings itself: either message names the joint)
  EXPECT_NE(e.find("j2"), std::string::npos) << e;
  EXPECT_TRUE(e.find("must be finite, got nan and 0") != std::string::npos ||
              e.find("not a valid URDF") != std::string::npos)
      << e;
  e = error("mimic_inf", arm("continuous", "", "<mimic joint=\"j1\" offset=\"inf\"/>"));
  EXPECT_NE(e.find("j2"), std::string::npos) << e;
  // in C++: the same checks by the tree (a non-finite multiplier directly)
  MimicArm bad;
  bad.mult = INFINITY;
  try {
    (void)bad.tree();
    ADD_FAILURE() << "an infinite multiplier was accepted";
  } catch (const std::invalid_argument& x) {
    EXPECT_NE(std::string(x.what()).find("joint 'elbow' mimics 'shoulder': its multiplier and "
                                         "offset must be finite, got inf and 0.4"),
              std::string::npos)
        << x.what();
  }
}

// ---- size: a long chain loads in linear time ----

// u20 03: the subtree-mass check walked every later link's ancestors, O(n³) on a chain (4000
// links 50 s); one reverse pass now. No timing here: the chain loads and its subtree masses
// are the closed forms (n − k)·m.
TEST(TreeSize, ALongChainLoadsWithItsSubtreeMasses) {
  const int n = 20000;
  const double m = 0.01;
  std::string text = "<?xml version=\"1.0\"?>\n<robot name=\"big\">\n<link name=\"l0\"/>\n";
  text.reserve(std::size_t(n) * 330);
  for (int i = 1; i <= n; ++i) {
    const std::string s = std::to_string(i), p = std::to_string(i - 1);
    text += "<link name=\"l" + s +
            "\"><inertial><origin xyz=\"0 0 -0.05\"/><mass value=\"0.01\"/><inertia ixx=\"1e-5\" "
            "ixy=\"0\" ixz=\"0\" iyy=\"1e-5\" iyz=\"0\" izz=\"1e-5\"/></inertial></link>\n"
            "<joint name=\"j" +
            s + "\" type=\"continuous\"><parent link=\"l" + p + "\"/><child link=\"l" + s +
            "\"/><origin xyz=\"0 0 -0.1\"/><axis xyz=\"0 1 0\"/></joint>\n";
  }
  text += "</robot>\n";
  const Tree tree = load_urdf(write_file("chain20000", text));
  ASSERT_EQ(tree.coordinate_count(), n);
  ASSERT_EQ(tree.link_count(), n + 1);  // l0 welded to the world
  EXPECT_EQ(tree.link(0).name, "l0");
  EXPECT_EQ(tree.link(n).name, "l" + std::to_string(n));
  for (const Index k : {Index(0), Index(1), Index(2), Index(n / 2), Index(n - 1), Index(n)}) {
    // link 0 is l0 (massless, all n links below it), link k >= 1 is l_k: l_k … l_n
    const double expected = double(k == 0 ? n : n - k + 1) * m;
    EXPECT_NEAR(tree.subtree_mass(k), expected, 1e-12 * expected) << k;
  }
  EXPECT_NEAR(total_mass(tree), n * m, 1e-12 * n * m);
}

// ---- a bad <inertial> ----

// u20 02: urdfdom logs an error for an <inertial> it cannot read and returns the link with a
// zero inertial, which read as "mass 0.000000"; its message is now the error, located at the
// link's <inertial> (u23 07: it was the link), and numbers print as format_number's
TEST(UrdfInertial, BadInertialsGiveUrdfdomsMessageAtTheLink) {
  const std::string joint =
      "<joint name=\"j1\" type=\"continuous\"><parent link=\"base\"/><child link=\"l1\"/>"
      "<axis xyz=\"0 1 0\"/></joint>\n";
  const auto arm = [&](const std::string& inertial) {
    return urdf("<link name=\"base\"/>\n<link name=\"l1\">\n  " + inertial + "\n</link>\n" + joint);
  };
  const std::string I =
      "<inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/>";
  struct Case {
    const char* name;
    std::string inertial, message;
  };
  const Case cases[] = {
      {"text_mass", "<inertial><mass value=\"heavy\"/>" + I + "</inertial>",
       "Inertial: mass [heavy] is not a float"},
      {"inf_mass", "<inertial><mass value=\"inf\"/>" + I + "</inertial>",
       "Inertial: mass [inf] is not a float"},
      {"nan_origin", "<inertial><origin xyz=\"0 nan 0\"/><mass value=\"1\"/>" + I + "</inertial>",
       "Unable to parse component [nan] to a double"},
      {"no_mass", "<inertial>" + I + "</inertial>", "Inertial element must have a mass element"},
      {"partial",
       "<inertial><mass value=\"1\"/><inertia ixx=\"0.1\" iyy=\"0.1\" izz=\"0.1\"/>"
       "</inertial>",
       "inertia element missing ixy attribute"},
  };
  for (const Case& c : cases) {
    const std::string path = write_file(std::string("inertial_") + c.name, arm(c.inertial));
    const std::string e = load_error(path);
    // "…: <path>:5:3: not a valid URDF: <urdfdom's message>; Could not parse inertial element
    // for Link [l1]" (the link's <inertial> on line 5, column 3)
    EXPECT_NE(e.find(path + ":5:3: not a valid URDF: "), std::string::npos) << c.name << ": " << e;
    EXPECT_NE(e.find(c.message), std::string::npos) << c.name << ": " << e;
    EXPECT_NE(e.find("Link [l1]"), std::string::npos) << c.name << ": " << e;
    EXPECT_EQ(e.find("0.000000"), std::string::npos) << c.name << ": " << e;
  }
  // numbers as format_number's, the tree's class name not in the text
  std::string e = load_error(
      write_file("tiny_nonpd",
                 arm("<inertial><mass value=\"1e-9\"/><inertia ixx=\"-1e-9\" ixy=\"0\" ixz=\"0\" "
                     "iyy=\"1e-9\" iyz=\"0\" izz=\"1e-9\"/></inertial>")));
  EXPECT_NE(e.find("link 'l1': the inertia of a moving link must be positive definite (mass "
                   "1e-09, principal moments -"),
            std::string::npos)
      << e;
  EXPECT_EQ(e.find("0.000000"), std::string::npos) << e;
  e = load_error(write_file(
      "tiny_damping",
      urdf("<link name=\"base\"/><link name=\"l1\"><inertial><mass value=\"1\"/>" + I +
           "</inertial></link><joint name=\"j1\" type=\"continuous\"><parent link=\"base\"/>"
           "<child link=\"l1\"/><axis xyz=\"0 1 0\"/><dynamics damping=\"-1e-9\"/></joint>")));
  EXPECT_NE(e.find("link 'l1' (joint 'j1'): damping must be >= 0, got -1e-09"), std::string::npos)
      << e;
  EXPECT_EQ(e.find("ukdyn::tree::Tree"), std::string::npos) << e;
}

// ---- every error at its file:line:column (u23 07) ----

// the full message of loading `text` as a URDF file: "ukdyn::tree::load_urdf: <path>:" is
// replaced by "@" (the rest, "<line>:<column>: <what>", is what a test asserts)
std::string located_error(const std::string& name, const std::string& text,
                          const UnitScale& scale = {}) {
  const std::string path = write_file("located_" + name, text);
  std::string e;
  try {
    load_urdf(path, Vector3d(0, 0, -9.81), scale);
    e = "(no error)";
  } catch (const std::invalid_argument& x) {
    e = x.what();
  }
  const std::string who = "ukdyn::tree::load_urdf: " + path + ":";
  if (e.rfind(who, 0) == 0) e.replace(0, who.size(), "@");
  return e;
}

// u23 07 (a): XML that TinyXML (under urdfdom) refused without a place, or read without a word
// (text or a second element after the root, a stray end tag, a NUL byte), refused at its place;
// an element never closed at its own start tag; columns count characters, a tab as one
TEST(UrdfLocated, MalformedXmlIsRefusedAtItsPlace) {
  const std::string form = " (a URDF is <robot name=\"…\"> … </robot>)";
  struct Case {
    const char* name;
    std::string text, error;
  };
  const Case cases[] = {
      {"unclosed", "<?xml version=\"1.0\"?>\n<robot name=\"r\">\n  <link name=\"a\">\n</robot>\n",
       "@3:3: not a valid URDF: <link name=\"a\"> is not closed (no </link> before </robot> at "
       "4:1)"},
      {"unclosed_inner",
       "<robot name=\"r\">\n\t<link name=\"a\">\n\t\t<visual>\n\t</link>\n</robot>\n",
       "@3:3: not a valid URDF: <visual> is not closed (no </visual> before </link> at 4:2)"},
      {"unclosed_at_end", "<robot name=\"r\">\n  <link name=\"a\"/>\n  <link name=\"b\">\n",
       "@3:3: not a valid URDF: <link name=\"b\"> is not closed (no </link> before the end of the "
       "file)"},
      {"unclosed_utf8",
       "<robot name=\"r\">\n  <link name=\"\xC3\xA9\"/><link name=\"a\">\n</robot>\n",
       "@2:19: not a valid URDF: <link name=\"a\"> is not closed (no </link> before </robot> at "
       "3:1)"},
      {"unclosed_crlf", "<robot name=\"r\">\r\n  <link name=\"a\">\r\n</robot>\r\n",
       "@2:3: not a valid URDF: <link name=\"a\"> is not closed (no </link> before </robot> at "
       "3:1)"},
      {"text_after_root", "<robot name=\"r\">\n  <link name=\"a\"/>\n</robot>\ngarbage here\n",
       "@4:1: not a valid URDF: 'garbage here' after the root element <robot name=\"r\"> at 1:1 "
       "(only comments may follow it)"},
      {"second_root", "<robot name=\"r\"><link name=\"a\"/></robot>\n  <robot name=\"s\"/>\n",
       "@2:3: not a valid URDF: a second root element <robot name=\"s\"> after <robot name=\"r\"> "
       "at 1:1 (a URDF file holds one <robot>)"},
      {"stray_end_tag", "<robot name=\"r\"><link name=\"a\"/></robot>\n</robot>\n",
       "@2:1: not a valid URDF: an end tag </robot> with no element open"},
      {"empty", "", "@1:1: not a valid URDF: the file is empty" + form},
      {"blank", "\n  \n", "@1:1: not a valid URDF: the file is empty" + form},
      {"binary_nul", std::string("\x89PNG\r\n\x1A\n\0\0\0\rIHDR", 16),
       "@3:1: not a valid URDF: the file holds a NUL byte (binary data, not XML)"},
      {"binary", "\x89PNG\x1A\xFF garbage",
       "@1:1: not a valid URDF: no XML element: the file begins with '\\x89PNG\\x1A\\xFF garbage'" +
           form},
      {"text_before_root", "\n  some text\n<robot name=\"r\"/>\n",
       "@2:3: not a valid URDF: no XML element: the file begins with 'some text'" + form},
      {"declaration_only", "<?xml version=\"1.0\"?>\n",
       "@1:1: not a valid URDF: no root element" + form},
      {"not_robot", "<?xml version=\"1.0\"?>\n<robt name=\"r\"><link name=\"a\"/></robt>\n",
       "@2:1: not a valid URDF: the root element is <robt name=\"r\">, not <robot>"},
      {"open_comment", "<robot name=\"r\">\n  <link name=\"a\"/>\n  <!-- to do\n</robot>\n",
       "@3:3: not a valid URDF: a comment <!-- is not closed (no --> before the end of the file)"},
      {"repeated_attribute", "<robot name=\"r\">\n  <link name=\"a\" name=\"b\"/>\n</robot>\n",
       "@2:18: not a valid URDF: the XML parser (TinyXML): \"Error parsing Element.\" at "
       "'name=\"b\"/>'"},
  };
  for (const Case& c : cases) EXPECT_EQ(located_error(c.name, c.text), c.error) << c.name;
  // a DOCTYPE and comments around the root are XML, and read
  const std::string I =
      "<inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" "
      "izz=\"0.1\"/></inertial>";
  EXPECT_EQ(located_error("doctype",
                          "<?xml version=\"1.0\"?>\n<!DOCTYPE robot>\n<!-- before -->\n<robot "
                          "name=\"r\"><link name=\"base\"/><link name=\"a\">" +
                              I +
                              "</link><joint name=\"j\" type=\"continuous\"><parent "
                              "link=\"base\"/><child link=\"a\"/></joint></robot>\n<!-- after "
                              "-->\n"),
            "(no error)");
}

// the two-link arm of the located errors, one element a line (line numbers on the right);
// `with` replaces a line's text
std::string located_arm(std::initializer_list<std::pair<std::string, std::string>> with = {}) {
  const std::string I =
      "<inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" "
      "izz=\"0.1\"/></inertial>";
  std::string text =
      "<?xml version=\"1.0\"?>\n"                    //  1
      "<robot name=\"r\">\n"                         //  2
      "  <link name=\"base\"/>\n"                    //  3
      "  <link name=\"a\">\n"                        //  4
      "    INERTIAL_A\n"                             //  5
      "  </link>\n"                                  //  6
      "  <link name=\"b\">\n"                        //  7
      "    INERTIAL_B\n"                             //  8
      "  </link>\n"                                  //  9
      "  <joint name=\"j1\" type=\"continuous\">\n"  // 10
      "    <parent link=\"base\"/>\n"                // 11
      "    <child link=\"a\"/>\n"                    // 12
      "    <axis xyz=\"0 1 0\"/>\n"                  // 13
      "    EXTRA_1\n"                                // 14
      "  </joint>\n"                                 // 15
      "  <joint name=\"j2\" type=\"continuous\">\n"  // 16
      "    <parent link=\"a\"/>\n"                   // 17
      "    <child link=\"b\"/>\n"                    // 18
      "    <origin xyz=\"0 0 -1\"/>\n"               // 19
      "    <axis xyz=\"0 1 0\"/>\n"                  // 20
      "    EXTRA_2\n"                                // 21
      "  </joint>\n"                                 // 22
      "</robot>\n";                                  // 23
  std::vector<std::pair<std::string, std::string>> all(with);
  all.emplace_back("INERTIAL_A", I);
  all.emplace_back("INERTIAL_B", I);
  all.emplace_back("EXTRA_1", "");
  all.emplace_back("EXTRA_2", "");
  for (const auto& [from, to] : all) {
    const std::size_t at = text.find(from);
    if (at != std::string::npos) text.replace(at, from.size(), to);
  }
  return text;
}

// u23 07 (b): a name that names nothing (a <mimic>'s joint, a joint's parent or child link), a
// mimic of itself and a cycle of mimics, at the element that names it
TEST(UrdfLocated, NamesAreLocatedWhereTheyAreUsed) {
  struct Case {
    const char* name;
    std::string text, error;
  };
  const std::string fails = "not a valid URDF: ";
  const Case cases[] = {
      {"mimic_unknown", located_arm({{"EXTRA_2", "<mimic joint=\"nosuch\"/>"}}),
       "@21:5: joint 'j2' mimics 'nosuch': no joint 'nosuch' in 'r'"},
      {"mimic_self", located_arm({{"EXTRA_2", "<mimic joint=\"j2\"/>"}}),
       "@21:5: joint 'j2' mimics 'j2': a joint cannot mimic itself"},
      {"mimic_cycle",
       located_arm({{"EXTRA_1", "<mimic joint=\"j2\" multiplier=\"0.5\"/>"},
                    {"EXTRA_2", "<mimic joint=\"j1\"/>"}}),
       "@14:5: joint 'j1': a cycle of mimics 'j1' → 'j2' → 'j1' (each joint follows the next; "
       "one of them must follow none)"},
      {"mimic_empty", located_arm({{"EXTRA_2", "<mimic joint=\"\"/>"}}),
       "@21:5: joint 'j2' (child link 'b'): its <mimic> names no joint (joint=\"…\")"},
      {"mimic_no_joint", located_arm({{"EXTRA_2", "<mimic multiplier=\"2\"/>"}}),
       "@21:5: " + fails +
           "joint mimic: no mimic joint specified; Could not parse mimic element for joint  [j2]; "
           "joint xml is not initialized correctly"},
      {"mimic_fixed",
       located_arm(
           {{"<joint name=\"j2\" type=\"continuous\">", "<joint name=\"j2\" type=\"fixed\">"},
            {"EXTRA_2", "<mimic joint=\"j1\"/>"}}),
       "@21:5: joint 'j2' mimics 'j1': joint 'j2' is fixed (a mimic relates two joints of one "
       "coordinate: revolute, continuous, prismatic)"},
      {"child_unknown", located_arm({{"<child link=\"b\"/>", "<child link=\"nosuch\"/>"}}),
       "@18:5: " + fails + "Failed to build tree: child link [nosuch] of joint [j2] not found"},
      {"duplicate_link", located_arm({{"<link name=\"b\">", "<link name=\"a\">"}}),
       "@7:3: " + fails + "link 'a' is not unique."},
  };
  for (const Case& c : cases) EXPECT_EQ(located_error(c.name, c.text), c.error) << c.name;
  // (urdfdom's message for an unknown parent goes on with advice: its start)
  const std::string e = located_error(
      "parent_unknown", located_arm({{"<parent link=\"a\"/>", "<parent link=\"nosuch\"/>"}}));
  EXPECT_EQ(e.rfind("@17:5: " + fails +
                        "Failed to build tree: parent link [nosuch] of joint [j2] not found.",
                    0),
            0u)
      << e;
}

// u23 07 (c): a missing required attribute, a NaN, a negative mass, an inertia that is not
// positive definite, limits the wrong way round, negative damping: at the element that holds it;
// in mm/g/ms as in SI (the place does not depend on the units; the numbers said are the file's,
// or the model's units for the tree's checks)
TEST(UrdfLocated, BadValuesAreLocatedAtTheirElement) {
  const std::string fails = "not a valid URDF: ";
  const std::string I_b =
      "<inertial><mass value=\"M\"/><inertia ixx=\"0.1\" ixy=\"XY\" ixz=\"0\" "
      "iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/></inertial>";
  const auto inertial_b = [&](const std::string& mass, const std::string& ixy) {
    std::string s = I_b;
    s.replace(s.find("\"M\""), 3, "\"" + mass + "\"");
    s.replace(s.find("\"XY\""), 4, "\"" + ixy + "\"");
    return s;
  };
  struct Case {
    const char* name;
    std::string text, error;
  };
  const Case cases[] = {
      {"no_type", located_arm({{"<joint name=\"j2\" type=\"continuous\">", "<joint name=\"j2\">"}}),
       "@16:3: " + fails +
           "joint [j2] has no type, check to see if it's a reference.; joint xml is not "
           "initialized correctly"},
      {"no_ixy",
       located_arm({{"INERTIAL_B",
                     "<inertial><mass value=\"1\"/><inertia ixx=\"0.1\" iyy=\"0.1\" "
                     "izz=\"0.1\"/></inertial>"}}),
       "@8:5: " + fails +
           "Inertial: inertia element missing ixy attribute; Could not parse inertial element "
           "for Link [b]"},
      {"no_limit",
       located_arm(
           {{"<joint name=\"j2\" type=\"continuous\">", "<joint name=\"j2\" type=\"revolute\">"}}),
       "@16:3: " + fails +
           "Joint [j2] is of type REVOLUTE but it does not specify limits; joint xml is not "
           "initialized correctly"},
      {"nan_origin", located_arm({{"<origin xyz=\"0 0 -1\"/>", "<origin xyz=\"0 nan -1\"/>"}}),
       "@19:5: " + fails +
           "Unable to parse component [nan] to a double (while parsing a vector value); "
           "Malformed parent origin element for joint [j2]; joint xml is not initialized "
           "correctly"},
      {"nan_axis",
       located_arm({{"<axis xyz=\"0 1 0\"/>\n    EXTRA_2", "<axis xyz=\"0 nan 0\"/>\n"}}),
       "@20:5: " + fails +
           "Malformed axis element for joint [j2]: Unable to parse component [nan] to a double "
           "(while parsing a vector value); joint xml is not initialized correctly"},
      {"nan_mimic", located_arm({{"EXTRA_2", "<mimic joint=\"j1\" multiplier=\"nan\"/>"}}),
       "@21:5: " + fails +
           "multiplier value (nan) is not a valid float; Could not parse mimic element for joint "
           " [j2]; joint xml is not initialized correctly"},
      {"negative_mass", located_arm({{"INERTIAL_B", inertial_b("-1", "0")}}),
       "@8:5: link 'b': the inertia of a moving link must be positive definite (mass -1, "
       "principal moments 0.1, 0.1, 0.1)"},
      {"inverted_limit",
       located_arm(
           {{"<joint name=\"j2\" type=\"continuous\">", "<joint name=\"j2\" type=\"revolute\">"},
            {"EXTRA_2", "<limit lower=\"1\" upper=\"-1\" effort=\"1\" velocity=\"1\"/>"}}),
       "@21:5: joint 'j2' (child link 'b'): its <limit> has lower = 1 > upper = -1 (swap them: "
       "lower <= upper)"},
      {"zero_axis",
       located_arm({{"<axis xyz=\"0 1 0\"/>\n    EXTRA_2", "<axis xyz=\"0 0 0\"/>\n"}}),
       "@20:5: link 'b' (joint 'j2'): the joint axis is zero or not finite"},
  };
  const UnitScale mm_g_ms{1000, 1000, 1000};
  for (const Case& c : cases) {
    EXPECT_EQ(located_error(c.name, c.text), c.error) << c.name;
    EXPECT_EQ(located_error(c.name, c.text, mm_g_ms), c.error) << c.name << " (mm, g, ms)";
  }
  // an inertia that is not positive definite: the principal moments of [[0.1, 0.2], [0.2, 0.1]]
  // and 0.1 are 0.1 ∓ 0.2 and 0.1 (to roundoff)
  std::string e = located_error("not_pd", located_arm({{"INERTIAL_B", inertial_b("1", "0.2")}}));
  const std::string head =
      "@8:5: link 'b': the inertia of a moving link must be positive definite (mass 1, principal "
      "moments ";
  ASSERT_EQ(e.rfind(head, 0), 0u) << e;
  double moments[3] = {0, 0, 0};
  ASSERT_EQ(
      std::sscanf(e.c_str() + head.size(), "%lf, %lf, %lf)", &moments[0], &moments[1], &moments[2]),
      3)
      << e;
  EXPECT_NEAR(moments[0], -0.1, 1e-15);
  EXPECT_NEAR(moments[1], 0.1, 1e-15);
  EXPECT_NEAR(moments[2], 0.3, 1e-15);
  // the tree's checks say the model's units: damping -0.5 N m s is -5e5 g mm²/ms (1e3 g/kg,
  // 1e6 mm²/m², 1e-3 s/ms)
  const std::string damped = located_arm({{"EXTRA_2", "<dynamics damping=\"-0.5\"/>"}});
  EXPECT_EQ(located_error("damping", damped),
            "@21:5: link 'b' (joint 'j2'): damping must be >= 0, got -0.5");
  EXPECT_EQ(located_error("damping", damped, mm_g_ms),
            "@21:5: link 'b' (joint 'j2'): damping must be >= 0, got -5e+05");
}

}  // namespace UKDYN_TEST_FILE

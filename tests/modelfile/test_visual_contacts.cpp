// SPDX-License-Identifier: BSD-3-Clause
// The contacts the viewer draws without `visual: contacts:` (src/modelfile/visual_contacts.cpp,
// issue #31 item 5): a robot's contact (examples/models/arm_hits_floor.yaml) is in the scene and
// its columns visual.contact.<name>.* are the forward kinematics of the link point at every
// sample (tree::forward_kinematics, and its height the gap's column); a bodies model's
// (bouncing_ball_bodies.yaml, which no longer writes a visual: contacts: entry) has the very
// columns the hand-written entry gave; a disk's point is its rim's lowest one; a hand-written entry
// of the same name replaces the drawn one.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/modelfile/visual.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

const std::string kExamples = UKDYN_EXAMPLES_DIR;
const std::string kData = UKDYN_TEST_DATA_DIR;

const CsvColumn& column(const ModelRun& run, const std::string& name) {
  for (const CsvColumn& c : run.extra_columns) {
    if (c.name == name) return c;
  }
  throw std::invalid_argument("no column " + name);
}

int count_columns(const ModelRun& run, const std::string& name) {
  int k = 0;
  for (const CsvColumn& c : run.extra_columns) k += c.name == name;
  return k;
}

// the scene's contacts: name → dimensions
std::map<std::string, int> scene_contacts(const Model& m) {
  const nlohmann::json scene = nlohmann::json::parse(viewer_scene_json(m));
  std::map<std::string, int> out;
  if (!scene.contains("contacts")) return out;
  for (const auto& c : scene["contacts"]) out[c["name"].get<std::string>()] = c["dimensions"];
  return out;
}

std::string text_of(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(VisualContacts, RobotContactIsTheForwardKinematicsOfItsLinkPoint) {
  const Model m = load_model(kExamples + "/arm_hits_floor.yaml");
  EXPECT_EQ(scene_contacts(m), (std::map<std::string, int>{{"fingertip", 3}}));
  const ModelRun run = run_model(m);
  ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
  ASSERT_FALSE(run.trajectory.stats.contact_events.empty());
  const tree::Tree& arm = *m.robot;
  const Index fore = arm.link_index("fore"), n = arm.coordinate_count();
  tree::TreeData d(arm);
  const std::string base = "visual.contact.fingertip.";
  const Index N = run.trajectory.samples();
  ASSERT_GT(N, 100);
  for (Index i = 0; i < N; ++i) {
    const Eigen::Map<const VectorXd> q(run.trajectory.q.data() + i * n, n);
    tree::forward_kinematics(arm, q, d);
    // the ball's (r = 0.03) point nearest the floor z = 0, and the floor's normal
    const Eigen::Vector3d p =
        tree::world_point(d, fore, Eigen::Vector3d(0.4, 0, 0)) - 0.03 * Eigen::Vector3d::UnitZ();
    const std::size_t s = std::size_t(i);
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(column(run, base + "xyz"[a]).values[s], p[a], 1e-12) << "sample " << i;
      EXPECT_EQ(column(run, base + "n" + "xyz"[a]).values[s], a == 2 ? 1.0 : 0.0);
    }
    // its height is the gap
    EXPECT_NEAR(column(run, base + "z").values[s], column(run, "gap.fingertip").values[s], 1e-12);
  }
}

TEST(VisualContacts, BodiesContactHasTheColumnsItsHandWrittenEntryHad) {
  const std::string path = kExamples + "/bouncing_ball_bodies.yaml";
  const std::string text = text_of(path);
  // the example has no visual: contacts: entry; the one it had before it was drawn alone
  const std::string trails = "  trails: [ball]\n";
  ASSERT_NE(text.find(trails), std::string::npos);
  ASSERT_EQ(text.find("contacts:\n    floor"), std::string::npos);
  std::string by_hand_text = text;
  by_hand_text.insert(by_hand_text.find(trails) + trails.size(),
                      "  contacts:\n    floor: {at: [ball_x, ball_y, ball_z - r], normal: [0, 0, "
                      "1]}\n");
  const Model by_hand = parse_model(by_hand_text, path), drawn = parse_model(text, path);
  EXPECT_EQ(scene_contacts(by_hand), (std::map<std::string, int>{{"floor", 3}}));
  EXPECT_EQ(scene_contacts(drawn), (std::map<std::string, int>{{"floor", 3}}));
  // the hand-written entry replaced the drawn one: its expressions give the columns, once
  ASSERT_EQ(by_hand.visual.contacts.size(), 1u);
  EXPECT_FALSE(by_hand.visual.contacts[0].geometry);
  ASSERT_EQ(drawn.visual.contacts.size(), 1u);
  EXPECT_TRUE(drawn.visual.contacts[0].geometry);
  const ModelRun a = run_model(by_hand), b = run_model(drawn);
  ASSERT_EQ(a.trajectory.samples(), b.trajectory.samples());
  const Index N = a.trajectory.samples(), n = a.trajectory.n;
  for (const char* part : {"x", "y", "z", "nx", "ny", "nz"}) {
    const std::string name = std::string("visual.contact.floor.") + part;
    EXPECT_EQ(count_columns(a, name), 1) << name;
    EXPECT_EQ(count_columns(b, name), 1) << name;
    for (Index i = 0; i < N; ++i)
      EXPECT_NEAR(column(b, name).values[std::size_t(i)], column(a, name).values[std::size_t(i)],
                  1e-12)
          << name << ", sample " << i;
  }
  // and they are the ball's lowest point (ball_x, ball_y, ball_z − r)
  for (Index i = 0; i < N; ++i) {
    const double* q = b.trajectory.q.data() + i * n;
    EXPECT_NEAR(column(b, "visual.contact.floor.z").values[std::size_t(i)], q[2] - 0.1, 1e-12);
    EXPECT_EQ(column(b, "visual.contact.floor.x").values[std::size_t(i)], q[0]);
  }
}

// a disk on the slider (contact_slider_disk.urdf), tilted: its point is on the rim, (p − c) ⊥ a
// and |p − c| = r, at the height of the gap above the floor
TEST(VisualContacts, DiskOnARobotIsDrawnAtItsRimsLowestPoint) {
  const Model m = parse_model(R"(
robot: {urdf: contact_slider_disk.urdf}
contacts:
  - {name: rim, link: wheel, shape: disk, radius: 0.2, restitution: 0.4}
initial: {q: {tilt: 0.5}}
simulate: {t_end: 0.35}
output: {every: 0.01}
)",
                              kData + "/robot.yaml");
  EXPECT_EQ(scene_contacts(m), (std::map<std::string, int>{{"rim", 3}}));
  const ModelRun run = run_model(m);
  ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
  const tree::Tree& rig = *m.robot;
  const Index wheel = rig.link_index("wheel");
  tree::TreeData d(rig);
  for (Index i = 0; i < run.trajectory.samples(); ++i) {
    const Eigen::Map<const VectorXd> q(run.trajectory.q.data() + i * 2, 2);
    tree::forward_kinematics(rig, q, d);
    const Eigen::Vector3d c = tree::world_point(d, wheel, Eigen::Vector3d::Zero());
    const Eigen::Vector3d a = d.R_WL[std::size_t(wheel)].col(2);
    const std::size_t s = std::size_t(i);
    const Eigen::Vector3d p(column(run, "visual.contact.rim.x").values[s],
                            column(run, "visual.contact.rim.y").values[s],
                            column(run, "visual.contact.rim.z").values[s]);
    EXPECT_NEAR((p - c).dot(a), 0.0, 1e-12);
    EXPECT_NEAR((p - c).norm(), 0.2, 1e-12);
    EXPECT_NEAR(p.z(), column(run, "gap.rim").values[s], 1e-12);
    // (the lowest: the rim's point at the centre's height minus r sin(tilt))
    EXPECT_NEAR(p.z(), c.z() - 0.2 * std::sin(std::abs(q[1])), 1e-12);
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

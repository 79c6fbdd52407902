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

#include "ukdyn/core/format.hpp"
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

// Coulomb friction at a contact point (ContactKinematics) is drawn from the columns
// visual.contact.<name>.fx, .fy (, .fz) that run_model writes: the friction force in the world,
// f = −mu N v/|v| while the contact slides, the stick constraint's multipliers along the
// contact's tangents while it holds. The scene's friction entry reads them with the identity map.
double friction_column(const ModelRun& run, const std::string& contact, const char* part,
                       std::size_t i) {
  return column(run, "visual.contact." + contact + ".f" + part).values[i];
}

void expect_identity_friction(const Model& m, const std::string& contact, int dims) {
  const nlohmann::json scene = nlohmann::json::parse(viewer_scene_json(m));
  for (const auto& c : scene.at("contacts")) {
    if (c.at("name") != contact) continue;
    ASSERT_TRUE(c.contains("friction")) << contact;
    const auto& f = c.at("friction");
    ASSERT_EQ(f.at("columns").size(), std::size_t(dims));
    for (int a = 0; a < dims; ++a) {
      EXPECT_EQ(f.at("columns")[std::size_t(a)],
                nlohmann::json::array({"visual.contact." + contact + ".f" + "xyz"[a]}));
      for (int b = 0; b < dims; ++b)
        EXPECT_EQ(f.at("map")[std::size_t(a)][std::size_t(b)].get<double>(), a == b ? 1.0 : 0.0);
    }
    return;
  }
  ADD_FAILURE() << "no contact " << contact << " in the scene";
}

TEST(VisualContacts, FrictionAtAContactPointIsItsWorldForceSlidingAndHeld) {
  constexpr double g = 9.81;
  {
    // examples/models/ball_rolls_after_sliding.yaml (m = 6, v0 = 4, mu = 0.2; its hand-written
    // visual: contacts: entry keeps the friction's axes): f = (−mu m g, 0, 0) until the sphere
    // rolls at t* = 2 v0 / (7 mu g), then (nearly) none
    const Model m = load_model(kExamples + "/ball_rolls_after_sliding.yaml");
    expect_identity_friction(m, "floor", 3);
    // drawn once, as a contact (not also as a joint with its ideal share reaction.floor.*)
    EXPECT_TRUE(nlohmann::json::parse(viewer_scene_json(m)).at("joints").empty());
    const ModelRun run = run_model(m);
    ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
    const double t_star = 2.0 * 4.0 / (7.0 * 0.2 * g);
    int sliding = 0, rolling = 0;
    for (std::size_t i = 0; i < run.trajectory.t.size(); ++i) {
      const double t = run.trajectory.t[i];
      if (std::abs(t - t_star) < 1e-3) continue;
      const double fx = t < t_star ? -0.2 * 6.0 * g : 0.0;
      (t < t_star ? sliding : rolling)++;
      EXPECT_NEAR(friction_column(run, "floor", "x", i), fx, 1e-9) << "t = " << t;
      EXPECT_NEAR(friction_column(run, "floor", "y", i), 0.0, 1e-12) << "t = " << t;
      EXPECT_NEAR(friction_column(run, "floor", "z", i), 0.0, 1e-12) << "t = " << t;
    }
    EXPECT_GT(sliding, 20);
    EXPECT_GT(rolling, 20);
  }
  {
    // the same ball in mm, g, s (a new user's: its stuck contact drifts at ~1e-7 mm/s, above
    // 100 eps = 1e-7, and the column read the full sliding friction while it rolled)
    const std::string text = text_of(kExamples + "/ball_rolls_after_sliding.yaml");
    const std::string si = "parameters: {m: 6, r: 0.11, g: 9.81, v0: 4, mu: 0.2}";
    ASSERT_NE(text.find(si), std::string::npos);
    std::string mm = text;
    mm.replace(mm.find(si), si.size(), "parameters: {m: 6000, r: 110, g: 9810, v0: 4000, mu: 0.2}");
    const Model m = parse_model(mm, kExamples + "/ball_rolls_after_sliding.yaml");
    const ModelRun run = run_model(m);
    ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
    const double t_star = 2.0 * 4.0 / (7.0 * 0.2 * g), full = 0.2 * 6000.0 * 9810.0;
    int rolling = 0;
    for (std::size_t i = 0; i < run.trajectory.t.size(); ++i) {
      const double t = run.trajectory.t[i];
      if (std::abs(t - t_star) < 1e-3) continue;
      rolling += t > t_star;
      EXPECT_NEAR(friction_column(run, "floor", "x", i), t < t_star ? -full : 0.0, 1e-9 * full)
          << "t = " << t;
    }
    EXPECT_GT(rolling, 20);
  }
  {
    // a solid sphere (m = 1, r = 0.1) at rest, pushed at its centre by F = 2: it rolls, held
    // by the stick constraint, x'' = 5 F / (7 m), and the floor's friction is −2 F / 7 — in
    // metres and in millimetres (L = 1000: the stick rows' unit kappa is not 1 there)
    for (const double L : {1.0, 1000.0}) {
      const std::string l = std::to_string(L);
      const Model m = parse_model(R"(
parameters: {m: 1, r: 0.1*)" + l + R"(, F: 2*)" +
                                  l + R"(}
bodies:
  - {name: ball, type: rigid, mass: m, inertia: [0.4*m*r^2, 0.4*m*r^2, 0.4*m*r^2], position: [0, 0, r]}
forces:
  - {type: gravity, g: [0, 0, -9.81*)" +
                                  l + R"(]}
  - {name: push, type: applied, body: ball, point: [0, 0, 0], force: [F, 0, 0], torque: [0, 0, 0]}
contacts:
  - {name: floor, body: ball, shape: sphere, radius: r}
nonideal:
  - {friction: coulomb, constraint: floor, mu: 0.3}
simulate: {t_end: 1, rtol: 1e-10, atol: 1e-12}
output: {every: 0.1}
)");
      expect_identity_friction(m, "floor", 3);
      const ModelRun run = run_model(m);
      ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
      ASSERT_GT(run.trajectory.t.size(), 5u);
      for (std::size_t i = 0; i < run.trajectory.t.size(); ++i) {
        EXPECT_NEAR(friction_column(run, "floor", "x", i), -2.0 * 2.0 * L / 7.0, 1e-9 * L)
            << "L = " << L << ", sample " << i;
        EXPECT_NEAR(friction_column(run, "floor", "y", i), 0.0, 1e-12 * L) << i;
        EXPECT_NEAR(friction_column(run, "floor", "z", i), 0.0, 1e-12 * L) << i;
        EXPECT_NEAR(run.trajectory.qd[i * std::size_t(run.trajectory.n)],
                    5.0 * 2.0 * L / 7.0 * run.trajectory.t[i], 1e-9 * L);
      }
    }
  }
  {
    // a planar rod (m = 2) sliding flat on its two ends: each end's friction is −mu m g / 2
    // along x until it stops at v0 / (mu g), two components (a planar contact)
    const Model m = parse_model(R"(
parameters: {m: 2, L: 1, v0: 1.5, mu: 0.3}
bodies:
  - {name: rod, type: planar, mass: m, inertia: m*L^2/12, position: [0, 0], velocity: [v0, 0]}
forces:
  - {type: gravity, g: [0, -9.81]}
contacts:
  - {name: left, body: rod, point: [-L/2, 0]}
  - {name: right, body: rod, point: [L/2, 0]}
nonideal:
  - {friction: coulomb, constraint: left, mu: mu}
  - {friction: coulomb, constraint: right, mu: mu}
simulate: {t_end: 1, rtol: 1e-11, atol: 1e-13}
output: {every: 0.01}
)");
    expect_identity_friction(m, "left", 2);
    const ModelRun run = run_model(m);
    ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
    EXPECT_EQ(count_columns(run, "visual.contact.left.fz"), 0);
    const double t_stop = 1.5 / (0.3 * g);
    for (std::size_t i = 0; i < run.trajectory.t.size(); ++i) {
      const double t = run.trajectory.t[i];
      if (std::abs(t - t_stop) < 1e-3) continue;
      for (const char* end : {"left", "right"}) {
        EXPECT_NEAR(friction_column(run, end, "x", i), t < t_stop ? -0.3 * g : 0.0, 1e-9)
            << end << ", t = " << t;
        EXPECT_NEAR(friction_column(run, end, "y", i), 0.0, 1e-12) << end << ", t = " << t;
      }
    }
  }
  {
    // tests/data/rolling_wheel.urdf in joint coordinates (test_contact_bodies_friction.cpp):
    // N = 3 g, f = −mu N along x until it rolls at t* = v0 / (3.75 mu g)
    const Model m = parse_model(R"(
robot: {urdf: rolling_wheel.urdf}
parameters: {v0: 1.2, mu: 0.25}
contacts:
  - {name: floor, link: wheel, shape: sphere, radius: 0.1}
nonideal:
  - {friction: coulomb, constraint: floor, mu: mu}
initial:
  q_dot: {x: v0}
simulate: {t_end: 0.5, rtol: 1e-11, atol: 1e-13}
output: {every: 0.01}
)",
                                kData + "/robot.yaml");
    expect_identity_friction(m, "floor", 3);
    const ModelRun run = run_model(m);
    ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
    const double t_star = 1.2 / (3.75 * 0.25 * g);
    for (std::size_t i = 0; i < run.trajectory.t.size(); ++i) {
      const double t = run.trajectory.t[i];
      if (std::abs(t - t_star) < 1e-3) continue;
      EXPECT_NEAR(friction_column(run, "floor", "x", i), t < t_star ? -0.25 * 3.0 * g : 0.0, 1e-9)
          << "t = " << t;
      EXPECT_NEAR(friction_column(run, "floor", "y", i), 0.0, 1e-12) << "t = " << t;
      EXPECT_NEAR(friction_column(run, "floor", "z", i), 0.0, 1e-12) << "t = " << t;
    }
  }
}

// The same columns at the contacts whose friction slides two bodies' material points against
// each other (mb::detail::relative_contact_kinematics): the plane of a driven belt, a disk's
// rim, and a ball on a fixed ball, whose axes turn with the plane's body or the line of centres.
TEST(VisualContacts, FrictionOnMovingPlanesDisksAndSpheresIsDrawnInTheWorld) {
  constexpr double g = 9.81;
  {
    // a box (m = 2) dropped on a belt driven at V = 1.2: each corner's friction pushes it on at
    // mu m g / 2 until it rides at t* = V / (mu g), then none
    const Model m = parse_model(R"(
parameters: {m: 2, L: 0.4, h: 0.1, V: 1.2, mu: 0.3}
bodies:
  - {name: belt, type: planar, mass: 5, inertia: 1, position: [0, 0], velocity: [V, 0]}
  - {name: box, type: planar, mass: m, inertia: m*(L^2 + 4*h^2)/12, position: [0, h]}
joints:
  - {name: slide, type: prismatic, parent: ground, child: belt, drive: V*t}
forces:
  - {type: gravity, g: [0, -9.81]}
contacts:
  - {name: rear, body: box, point: [-L/2, -h], plane: {body: belt, normal: [0, 1]}}
  - {name: front, body: box, point: [L/2, -h], plane: {body: belt, normal: [0, 1]}}
nonideal:
  - {friction: coulomb, constraint: rear, mu: mu}
  - {friction: coulomb, constraint: front, mu: mu}
simulate: {t_end: 0.8, rtol: 1e-11, atol: 1e-13}
output: {every: 0.01}
)");
    expect_identity_friction(m, "front", 2);
    const ModelRun run = run_model(m);
    ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
    const double t_star = 1.2 / (0.3 * g);
    for (std::size_t i = 0; i < run.trajectory.t.size(); ++i) {
      const double t = run.trajectory.t[i];
      if (std::abs(t - t_star) < 1e-3) continue;
      // (the friction's moment shifts the corners' normal forces by ± h mu m g / L, but their
      // frictions sum to mu m g)
      const double sum =
          friction_column(run, "rear", "x", i) + friction_column(run, "front", "x", i);
      EXPECT_NEAR(sum, t < t_star ? 0.3 * 2.0 * g : 0.0, 1e-7) << "t = " << t;
      EXPECT_NEAR(friction_column(run, "front", "y", i), 0.0, 1e-12) << "t = " << t;
    }
  }
  {
    // a coin (m = 0.4) on its rim launched at v0 = 1.5: −mu m g along x until it rolls at
    // t* = v0 / (3 mu g)
    const Model m = parse_model(R"(
parameters: {m: 0.4, r: 0.12, v0: 1.5, mu: 0.2}
bodies:
  - {name: coin, type: rigid, mass: m, inertia: [m*r^2/4, m*r^2/2, m*r^2/4],
     position: [0, 0, r], velocity: [v0, 0, 0]}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: floor, body: coin, shape: disk, radius: r, axis: [0, 1, 0]}
nonideal:
  - {friction: coulomb, constraint: floor, mu: mu}
simulate: {t_end: 0.5, rtol: 1e-11, atol: 1e-13}
output: {every: 0.01}
)");
    expect_identity_friction(m, "floor", 3);
    const ModelRun run = run_model(m);
    ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
    const double t_star = 1.5 / (3.0 * 0.2 * g);
    for (std::size_t i = 0; i < run.trajectory.t.size(); ++i) {
      const double t = run.trajectory.t[i];
      if (std::abs(t - t_star) < 1e-3) continue;
      EXPECT_NEAR(friction_column(run, "floor", "x", i), t < t_star ? -0.2 * 0.4 * g : 0.0, 1e-8)
          << "t = " << t;
      EXPECT_NEAR(friction_column(run, "floor", "y", i), 0.0, 1e-10) << "t = " << t;
      EXPECT_NEAR(friction_column(run, "floor", "z", i), 0.0, 1e-10) << "t = " << t;
    }
  }
  {
    // a small ball (m = 0.2, r = 0.05) rolling off a fixed ball (R = 0.5) while held: at the
    // angle θ from the top the friction is 2/7 m g sin θ up the slope, −(cos θ, −sin θ), across
    // the line of centres
    const Model m = parse_model(R"(
parameters: {m: 0.2, r: 0.05, R: 0.5, w0: 0.05, mu: 0.3}
bodies:
  - {name: ball, type: planar, mass: m, inertia: 0.4*m*r^2, position: [0, R + r],
     velocity: [(R + r)*w0, 0], angular_velocity: -(R + r)*w0/r}
forces:
  - {type: gravity, g: [0, -9.81]}
contacts:
  - {name: dome, body: ball, shape: sphere, radius: r, sphere: {body: ground, radius: R}}
nonideal:
  - {friction: coulomb, constraint: dome, mu: mu}
simulate: {t_end: 0.6, rtol: 1e-11, atol: 1e-13}
output: {every: 0.01}
)");
    expect_identity_friction(m, "dome", 2);
    const ModelRun run = run_model(m);
    ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
    const Index n = run.trajectory.n;
    int held = 0;
    for (std::size_t i = 0; i < run.trajectory.t.size(); ++i) {
      const double* q = run.trajectory.q.data() + std::ptrdiff_t(i) * n;
      const double th = std::atan2(q[0], q[1]);
      if (th > 0.55) break;  // (it slips near 0.617 rad at mu = 0.3)
      ++held;
      const double f = 2.0 / 7.0 * 0.2 * g * std::sin(th);
      EXPECT_NEAR(friction_column(run, "dome", "x", i), -f * std::cos(th), 1e-7) << "θ = " << th;
      EXPECT_NEAR(friction_column(run, "dome", "y", i), f * std::sin(th), 1e-7) << "θ = " << th;
    }
    EXPECT_GT(held, 20);
  }
}

// A contact at rest at t = 0 that cannot stick slides from the start along its slip hint: its
// friction acts at the full magnitude in the t = 0 sample too (repro u14/03: that sample read 0,
// the stick constraint's multipliers, which are off). A ball (m = 2, mu = 0.2) at rest on a deck
// accelerating at A = 14 > 7/2 mu_s g: f = mu m g = 3.924 along +x at every sample; a box (m = 3)
// on two corners on a belt accelerating at A = 6 > mu_s g: the corners' frictions sum to
// mu m g = 8.829 along +x.
TEST(VisualContacts, FrictionOfAContactSlidingFromRestActsAtTheFirstSample) {
  constexpr double g = 9.81;
  {
    const Model m = parse_model(R"(
parameters: {m: 2, r: 0.1, M: 20, g: 9.81, A: 14, mu: 0.2, mus: 0.3}
bodies:
  - {name: deck, type: rigid, mass: M, inertia: [1, 1, 1], position: [0, 0, 0]}
  - {name: ball, type: rigid, mass: m, inertia: 0.4*m*r^2, position: [0, 0, r]}
joints:
  - {name: slide, type: prismatic, parent: ground, child: deck, parent_axis: [1, 0, 0], child_axis: [1, 0, 0], drive: 0.5*A*t^2}
forces:
  - {type: gravity, g: [0, 0, -g]}
contacts:
  - {name: c, body: ball, shape: sphere, radius: r, plane: {body: deck, point: [0, 0, 0], normal: [0, 0, 1]}}
nonideal:
  - {friction: coulomb, constraint: c, mu: mu, mu_static: mus}
simulate: {t_end: 0.2}
output: {every: 0.01}
)");
    const ModelRun run = run_model(m);
    ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
    ASSERT_GT(run.trajectory.t.size(), 10u);
    EXPECT_EQ(run.trajectory.t[0], 0.0);
    for (std::size_t i = 0; i < run.trajectory.t.size(); ++i) {
      EXPECT_NEAR(friction_column(run, "c", "x", i), 0.2 * 2.0 * g, 1e-9) << "sample " << i;
      EXPECT_NEAR(friction_column(run, "c", "y", i), 0.0, 1e-12) << "sample " << i;
      EXPECT_NEAR(friction_column(run, "c", "z", i), 0.0, 1e-12) << "sample " << i;
    }
  }
  {
    const Model m = parse_model(R"(
parameters: {m: 3, M: 10, a: 0.2, c: 0.05, g: 9.81, A: 6, mu: 0.3, mus: 0.5}
bodies:
  - {name: belt, type: planar, mass: M, inertia: 1, position: [0, 0]}
  - {name: box, type: planar, mass: m, inertia: m*(4*a^2+4*c^2)/12, position: [0, c]}
joints:
  - {name: drive, type: prismatic, parent: ground, child: belt, drive: 0.5*A*t^2}
forces:
  - {type: gravity, g: [0, -g]}
contacts:
  - {name: cl, body: box, point: [-a, -c], plane: {body: belt, point: [0, 0], normal: [0, 1]}}
  - {name: cr, body: box, point: [a, -c], plane: {body: belt, point: [0, 0], normal: [0, 1]}}
nonideal:
  - {friction: coulomb, constraint: cl, mu: mu, mu_static: mus}
  - {friction: coulomb, constraint: cr, mu: mu, mu_static: mus}
simulate: {t_end: 0.2}
output: {every: 0.01}
)");
    const ModelRun run = run_model(m);
    ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
    ASSERT_GT(run.trajectory.t.size(), 10u);
    for (std::size_t i = 0; i < run.trajectory.t.size(); ++i) {
      const double sum = friction_column(run, "cl", "x", i) + friction_column(run, "cr", "x", i);
      EXPECT_NEAR(sum, 0.3 * 3.0 * g, 1e-9) << "sample " << i;
      EXPECT_NEAR(friction_column(run, "cl", "y", i), 0.0, 1e-12) << "sample " << i;
    }
  }
}

// The stick columns lambda.stick.coulomb.<c>.0/.1 of a contact-point friction are the holding
// force in the model's force unit (u15 03): a ball (m, r, I = 2/5 m r²) put at rest on a
// turntable turning at Om, r0 from the axis, rolls, and the table holds it with
// (2/7) m Om² r0 at all times — in SI (kappa = 1), in mm/g/ms (kappa = 1000: the force unit
// g·mm/ms² is N) and in SI for the same model 1000 times larger (kappa = 1000 again, from the
// quaternion's columns). Before: the columns were the force / kappa, 1e-3 of it in the last two.
TEST(VisualContacts, StickColumnsAreTheHoldingForceInForceUnits) {
  struct Case {
    const char* parameters;
    const char* units;
    double t_end, force;
    const char* force_unit;
  };
  const Case cases[] = {
      {"{m: 0.5, r: 0.05, g: 9.81, Om: 2, r0: 0.1, M: 10, R: 1, h: 0.05, mu: 0.5}", "", 2.0,
       2.0 / 7.0 * 0.5 * 4.0 * 0.1, "N"},
      {"{m: 500, r: 50, g: 9.81e-3, Om: 0.002, r0: 100, M: 10000, R: 1000, h: 50, mu: 0.5}",
       "units: {length: mm, mass: g, time: ms}", 2000.0, 2.0 / 7.0 * 0.5 * 4.0 * 0.1, "g·mm/ms²"},
      {"{m: 0.5, r: 50, g: 9.81, Om: 0.002, r0: 100, M: 10, R: 1000, h: 50, mu: 0.5}", "", 2000.0,
       2.0 / 7.0 * 0.5 * 4e-6 * 100.0, "N"},
  };
  for (const Case& k : cases) {
    const Model m = parse_model(std::string("parameters: ") + k.parameters + "\n" + k.units + R"(
bodies:
  - {name: table, type: rigid, mass: M, inertia: [M*(3*R^2 + 4*h^2)/12, M*(3*R^2 + 4*h^2)/12, M*R^2/2],
     position: [0, 0, -h], angular_velocity: [0, 0, Om]}
  - {name: ball, type: rigid, mass: m, inertia: 0.4*m*r^2, position: [r0, 0, r], velocity: [0, Om*r0, 0]}
joints:
  - {name: spin, type: revolute, parent: ground, child: table, parent_point: [0, 0, -h], drive: Om*t}
forces:
  - {type: gravity, g: [0, 0, -g]}
contacts:
  - {name: c, body: ball, shape: sphere, radius: r, plane: {body: table, point: [0, 0, h], normal: [0, 0, 1]}}
nonideal:
  - {friction: coulomb, constraint: c, mu: mu}
simulate: {t_end: )" + format_number(k.t_end) +
                                R"(, rtol: 1e-10, atol: 1e-12}
output: {every: )" + format_number(k.t_end / 20) +
                                "}\n");
    const ModelRun run = run_model(m);
    ASSERT_EQ(run.trajectory.stats.status, Status::kOk) << run.trajectory.stats.message;
    const std::vector<CsvColumn> all = run.columns();
    const auto values = [&](const std::string& name) -> const std::vector<double>& {
      for (const CsvColumn& c : all)
        if (c.name == name) return c.values;
      throw std::invalid_argument("no column " + name);
    };
    const auto &f0 = values("lambda.stick.coulomb.c.0"), &f1 = values("lambda.stick.coulomb.c.1");
    ASSERT_GT(f0.size(), 10u);
    for (std::size_t i = 0; i < f0.size(); ++i) {
      EXPECT_NEAR(std::hypot(f0[i], f1[i]), k.force, 1e-6 * k.force) << k.parameters << ", " << i;
      // the world's friction column is the same force
      EXPECT_NEAR(std::hypot(friction_column(run, "c", "x", i), friction_column(run, "c", "y", i)),
                  k.force, 1e-6 * k.force)
          << k.parameters << ", " << i;
    }
    // labelled with the force unit (summary.json's units, Model.units)
    std::map<std::string, std::string> units;
    for (const auto& [name, unit] : contact_gap_units(m)) units[name] = unit;
    EXPECT_EQ(units["lambda.stick.coulomb.c.0"], k.force_unit);
    EXPECT_EQ(units["lambda.stick.coulomb.c.1"], k.force_unit);
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

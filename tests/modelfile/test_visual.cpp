// SPDX-License-Identifier: BSD-3-Clause
// The model file's visual: entries and the viewer's scene (modelfile/visual.hpp,
// src/modelfile/reader_visual.cpp, src/modelfile/visual.cpp): the points' columns are their
// expressions' values, the scene says what the file says, and errors are located.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <string>

#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/modelfile/visual.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

const CsvColumn& column(const ModelRun& run, const std::string& name) {
  for (const CsvColumn& c : run.extra_columns) {
    if (c.name == name) return c;
  }
  throw std::invalid_argument("no column " + name);
}

std::string error_of(const std::string& text) {
  try {
    parse_model(text, "v.yaml");
  } catch (const ModelError& e) {
    return e.what();
  }
  return "no error";
}

constexpr const char* kPendulum = R"(coordinates: [x, y]
parameters: {L: 2}
kinetic_energy: 0.5*(x_dot^2 + y_dot^2)
potential_energy: 9.81*y
constraints:
  - {name: rod, holonomic: (x^2 + y^2 - L^2)/(2*L)}
initial: {q: {x: L, y: 0}}
simulate: {t_end: 0.5}
output: {every: 0.1, expressions: {r: sqrt(x^2 + y^2)}}
visual:
  points:
    pivot: {at: [0, 0], color: grey}
    bob: {at: [x, y + L], color: "#00ff00", radius: L/20}
  links: [[pivot, bob]]
  trails: [bob]
)";

TEST(ModelVisual, PointsAreColumnsAfterTheOutputs) {
  const Model m = parse_model(kPendulum, "v.yaml");
  ASSERT_EQ(m.output_names, std::vector<std::string>{"r"});  // the outputs alone
  const std::vector<std::string> columns = {"visual.pivot.x", "visual.pivot.y", "visual.bob.x",
                                            "visual.bob.y"};
  EXPECT_EQ(m.visual.columns, columns);
  const ModelRun run = run_model(m);
  // the last columns, in order, after r
  const std::size_t n = run.extra_columns.size();
  ASSERT_GE(n, 5u);
  EXPECT_EQ(run.extra_columns[n - 5].name, "r");
  for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(run.extra_columns[n - 4 + k].name, columns[k]);
  const auto& x = run.trajectory.q;
  const Index samples = run.trajectory.samples();
  for (Index i = 0; i < samples; ++i) {
    EXPECT_EQ(column(run, "visual.bob.x").values[std::size_t(i)], x[std::size_t(2 * i)]);
    EXPECT_NEAR(column(run, "visual.bob.y").values[std::size_t(i)], x[std::size_t(2 * i + 1)] + 2,
                1e-15);
    EXPECT_EQ(column(run, "visual.pivot.x").values[std::size_t(i)], 0.0);
  }
}

TEST(ModelVisual, SceneOfAModelInCoordinates) {
  const auto scene = nlohmann::json::parse(viewer_scene_json(parse_model(kPendulum, "v.yaml")));
  EXPECT_TRUE(scene["planar"].get<bool>());
  EXPECT_TRUE(scene["bodies"].empty());
  ASSERT_EQ(scene["points"].size(), 2u);
  EXPECT_EQ(scene["points"][0]["color"], "#7f7f7f");  // grey
  EXPECT_EQ(scene["points"][1]["color"], "#00ff00");
  EXPECT_DOUBLE_EQ(scene["points"][1]["radius"].get<double>(), 0.1);  // L/20
  EXPECT_EQ(scene["links"], nlohmann::json::parse(R"([["pivot", "bob"]])"));
  EXPECT_EQ(scene["trails"], nlohmann::json::parse(R"(["bob"])"));
  // the coordinate each component is exactly (the viewer draws its forces there), else null
  EXPECT_EQ(scene["points"][0]["coordinates"], nlohmann::json::parse("[null, null]"));
  EXPECT_EQ(scene["points"][1]["coordinates"], nlohmann::json::parse(R"(["x", null])"));
  EXPECT_EQ(scene["points"][1]["expressions"], nlohmann::json::parse(R"(["x", "y + L"])"));
}

TEST(ModelVisual, FramesAreColumns) {
  const Model m = parse_model(
      "coordinates: [x, th]\nkinetic_energy: 0.5*(x_dot^2 + th_dot^2)\nsimulate: {t_end: 0.1}\n"
      "initial: {q_dot: {x: 1, th: 2}}\n"
      "visual: {frames: {cart: {at: [x, 0], angle: th, size: 0.5},\n"
      "                  top: {at: [0, 0, x], quaternion: [cos(th/2), 0, 0, sin(th/2)]}}}\n",
      "v.yaml");
  const std::vector<std::string> columns = {
      "visual.cart.x", "visual.cart.y", "visual.cart.angle", "visual.top.x",  "visual.top.y",
      "visual.top.z",  "visual.top.qw", "visual.top.qx",     "visual.top.qy", "visual.top.qz"};
  EXPECT_EQ(m.visual.columns, columns);
  const ModelRun run = run_model(m);
  const auto& q = run.trajectory.q;
  for (Index i = 0; i < run.trajectory.samples(); ++i) {
    const double th = q[std::size_t(2 * i + 1)];
    EXPECT_EQ(column(run, "visual.cart.angle").values[std::size_t(i)], th);
    EXPECT_NEAR(column(run, "visual.top.qz").values[std::size_t(i)], std::sin(th / 2), 1e-15);
  }
  const auto scene = nlohmann::json::parse(viewer_scene_json(m));
  EXPECT_FALSE(scene["planar"].get<bool>());  // a quaternion frame: spatial
  ASSERT_EQ(scene["frames"].size(), 2u);
  EXPECT_DOUBLE_EQ(scene["frames"][0]["size"].get<double>(), 0.5);
  EXPECT_TRUE(scene["frames"][1]["quaternion"].get<bool>());
}

TEST(ModelVisual, SceneOfBodiesAndJoints) {
  const Model m = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/heavy_top.yaml");
  const auto scene = nlohmann::json::parse(viewer_scene_json(m));
  EXPECT_FALSE(scene["planar"].get<bool>());
  ASSERT_EQ(scene["bodies"].size(), 1u);
  const auto& top = scene["bodies"][0];
  EXPECT_EQ(top["kind"], "rigid");
  EXPECT_DOUBLE_EQ(top["inertia"][2].get<double>(), 0.08);  // I3
  ASSERT_EQ(top["visual"].size(), 2u);
  EXPECT_EQ(top["visual"][0]["shape"], "cylinder");
  EXPECT_EQ(top["visual"][0]["axis"], "z");
  EXPECT_DOUBLE_EQ(top["visual"][1]["offset"][2].get<double>(), -0.25);  // -l/2
  ASSERT_EQ(scene["joints"].size(), 1u);
  EXPECT_EQ(scene["joints"][0]["parent"], "ground");
  EXPECT_EQ(scene["joints"][0]["child"], "top");
  EXPECT_DOUBLE_EQ(scene["joints"][0]["child_point"][2].get<double>(), -0.5);  // -l
  EXPECT_FALSE(scene["joints"][0].contains("axis"));  // a spherical joint has no axis
  // each coordinate's unit (the page labels forces by them): m for x, y, z; 1 for u0 … u3
  EXPECT_EQ(scene["coordinates"][0], "top.x");
  EXPECT_EQ(scene["coordinate_units"],
            nlohmann::json::parse(R"(["m", "m", "m", "1", "1", "1", "1"])"));
  EXPECT_EQ(scene["trails"], nlohmann::json::parse(R"(["top"])"));
}

TEST(ModelVisual, ErrorsAreLocated) {
  EXPECT_EQ(error_of("bodies:\n  - {name: b, type: particle, mass: 1, visual: {shape: cone}}\n"),
            "v.yaml:2:56: error: body 'b' visual: unknown shape 'cone' (hint: box, cylinder, "
            "capsule or sphere)");
  EXPECT_EQ(error_of("bodies:\n  - {name: b, type: particle, mass: 1,\n"
                     "     visual: {shape: sphere, radius: -1}}\n"),
            "v.yaml:3:38: error: body 'b' visual radius must be > 0, got -1");
  EXPECT_EQ(error_of("coordinates: [x]\nkinetic_energy: x_dot^2/2\nvisual: {points: {p: [x]}}\n"),
            "v.yaml:3:22: error: visual point 'p' must be [x, y] or [x, y, z] (expressions of the "
            "coordinates and t) (hint: bob: [L*sin(theta), -L*cos(theta)])");
  EXPECT_EQ(
      error_of("coordinates: [x]\nkinetic_energy: x_dot^2/2\nvisual: {meshes: []}\n"),
      "v.yaml:3:10: error: unknown key 'meshes' in visual (hint: the keys are contacts, frames, "
      "links, points, trails)");
  EXPECT_EQ(
      error_of("coordinates: [x]\nkinetic_energy: x_dot^2/2\n"
               "visual: {frames: {f: {at: [x, 0]}}}\n"),
      "v.yaml:3:22: error: visual frame 'f' needs either angle (about z) or quaternion [w, x, "
      "y, z] (hint: {hoop: {at: [x, y], angle: theta, size: 0.3}})");
  // a contact's normal that is zero (it gives no direction to draw the force along), at its
  // list; one that only vanishes somewhere is kept (0*x + x is not identically 0)
  const std::string ball =
      "coordinates: [x, y]\nkinetic_energy: (x_dot^2 + y_dot^2)/2\n"
      "constraints:\n  - {name: floor, holonomic: y, unilateral: true}\n";
  EXPECT_EQ(error_of(ball + "visual: {contacts: {floor: {at: [x, y], normal: [0, 0]}}}\n"),
            "v.yaml:5:49: error: visual contact 'floor': normal is zero; it must give the "
            "direction the contact pushes (hint: {floor: {at: [x, y - r], normal: [0, 1]}})");
  EXPECT_EQ(error_of(ball + "visual: {contacts: {floor: {at: [x, y], normal: [0*x, x - x]}}}\n"),
            "v.yaml:5:49: error: visual contact 'floor': normal is zero; it must give the "
            "direction the contact pushes (hint: {floor: {at: [x, y - r], normal: [0, 1]}})");
  EXPECT_EQ(error_of(ball + "visual: {contacts: {floor: {at: [x, y], normal: [0, x]}}}\n"),
            "no error");
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

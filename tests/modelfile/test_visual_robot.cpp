// SPDX-License-Identifier: BSD-3-Clause
// A robot's visual geometry and loops for the viewer (multibody/tree_visual.hpp,
// src/multibody/tree/urdf_visual.cpp, src/modelfile/visual_robot.cpp): each <visual> of
// tests/data/visual_robot/visual_shapes.urdf with the file's numbers, its place in the world by
// the tree's own forward kinematics against the pose worked out by hand, the mesh files read
// only beside the URDF, and the loops of the model file.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <unistd.h>

#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/visual.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/multibody/tree_visual.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

namespace fs = std::filesystem;
using tree::LinkVisual;

const std::string kDir = std::string(UKDYN_TEST_DATA_DIR) + "/visual_robot";
const std::string kUrdf = kDir + "/visual_shapes.urdf";

void expect_vector(const Eigen::Vector3d& v, double x, double y, double z, double tol = 1e-15) {
  EXPECT_NEAR(v.x(), x, tol);
  EXPECT_NEAR(v.y(), y, tol);
  EXPECT_NEAR(v.z(), z, tol);
}

Eigen::Vector3d json_vector(const nlohmann::json& j) {
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

TEST(UrdfVisuals, EachShapeHasTheFilesOriginSizeAndMaterial) {
  const std::vector<LinkVisual> v = tree::load_urdf_visuals(kUrdf);
  ASSERT_EQ(v.size(), 8u);
  // base: the box of the red material (a material given by name), at z = 0.05
  EXPECT_EQ(v[0].link, "base");
  EXPECT_EQ(v[0].name, "plinth");
  EXPECT_EQ(v[0].shape, LinkVisual::Shape::kBox);
  expect_vector(v[0].size, 0.4, 0.3, 0.1);
  expect_vector(v[0].p_LV, 0, 0, 0.05);
  EXPECT_EQ(v[0].color, "#ff0000");
  EXPECT_DOUBLE_EQ(v[0].opacity, 1.0);
  // base: the OBJ mesh beside the URDF, scale 1 (URDF's default)
  EXPECT_EQ(v[1].link, "base");
  EXPECT_EQ(v[1].shape, LinkVisual::Shape::kMesh);
  EXPECT_EQ(fs::path(v[1].mesh_file), fs::canonical(kDir + "/meshes/square.obj"));
  expect_vector(v[1].size, 1, 1, 1);
  expect_vector(v[1].p_LV, 0.15, 0, 0.1);
  // base: the COLLADA mesh (file://, relative), its scale and the green material
  EXPECT_EQ(v[2].mesh, "file://meshes/triangle.dae");
  EXPECT_EQ(fs::path(v[2].mesh_file), fs::canonical(kDir + "/meshes/triangle.dae"));
  expect_vector(v[2].size, 1, 1, 2);
  EXPECT_EQ(v[2].color, "#008000");
  // arm: the cylinder (radius, length), half transparent blue
  EXPECT_EQ(v[3].link, "arm");
  EXPECT_EQ(v[3].shape, LinkVisual::Shape::kCylinder);
  expect_vector(v[3].size, 0.05, 0.6, 0.0);
  expect_vector(v[3].p_LV, 0, 0, 0.3);
  EXPECT_EQ(v[3].color, "#0000ff");
  EXPECT_DOUBLE_EQ(v[3].opacity, 0.5);
  // hand: the sphere with no material, the mesh found, the mesh not found
  EXPECT_EQ(v[4].link, "hand");
  EXPECT_EQ(v[4].shape, LinkVisual::Shape::kSphere);
  EXPECT_DOUBLE_EQ(v[4].size.x(), 0.08);
  expect_vector(v[4].p_LV, 0.1, 0, 0);
  EXPECT_EQ(v[4].color, "");
  EXPECT_EQ(v[5].shape, LinkVisual::Shape::kMesh);
  EXPECT_EQ(v[5].mesh, "package://visual_robot/meshes/tetra.stl");
  EXPECT_EQ(fs::path(v[5].mesh_file), fs::canonical(kDir + "/meshes/tetra.stl"));
  EXPECT_EQ(v[5].mesh_problem, "");
  expect_vector(v[5].size, 2, 2, 2);
  EXPECT_EQ(v[6].mesh, "meshes/</script><script>window.pwned=1</script><!--.stl");
  EXPECT_EQ(v[6].mesh_file, "");
  EXPECT_EQ(v[6].mesh_problem, "no such file beside the URDF");
  for (const LinkVisual& x : v) EXPECT_NEAR(x.R_LV.norm(), 1.0, 1e-15);
}

TEST(UrdfVisuals, MeshFilesAreReadOnlyBesideTheUrdf) {
  // pkg/urdf/robot.urdf, pkg/meshes/part.stl, and a file outside the package
  const fs::path root = fs::temp_directory_path() / ("ukdyn_mesh_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root / "pkg" / "urdf" / "near");
  fs::create_directories(root / "pkg" / "meshes");
  const fs::path urdf = root / "pkg" / "urdf" / "robot.urdf";
  for (const fs::path& p : {urdf, root / "pkg" / "meshes" / "part.stl",
                            root / "pkg" / "urdf" / "near" / "beside.stl", root / "secret.stl"})
    std::ofstream(p) << "solid x\nendsolid x\n";
  fs::create_symlink(root / "secret.stl", root / "pkg" / "urdf" / "near" / "link.stl");
  std::string problem;
  // ROS's layout: package://pkg/… in the package's directory, an ancestor of the URDF's
  EXPECT_EQ(tree::find_mesh_file(urdf, "package://pkg/meshes/part.stl", problem),
            fs::canonical(root / "pkg" / "meshes" / "part.stl"));
  EXPECT_EQ(problem, "");
  // a package that is no ancestor: its path beside the URDF
  EXPECT_EQ(tree::find_mesh_file(urdf, "package://other/near/beside.stl", problem),
            fs::canonical(root / "pkg" / "urdf" / "near" / "beside.stl"));
  EXPECT_EQ(tree::find_mesh_file(urdf, "near/beside.stl", problem),
            fs::canonical(root / "pkg" / "urdf" / "near" / "beside.stl"));
  EXPECT_EQ(tree::find_mesh_file(urdf, "file://near/beside.stl", problem),
            fs::canonical(root / "pkg" / "urdf" / "near" / "beside.stl"));
  // nothing outside: .., an absolute path, a symbolic link out, another scheme
  for (const std::string& name :
       {std::string("../../secret.stl"), (root / "secret.stl").string(),
        "file://" + (root / "secret.stl").string(), std::string("near/link.stl"),
        std::string("package://pkg/../secret.stl")}) {
    EXPECT_EQ(tree::find_mesh_file(urdf, name, problem), fs::path()) << name;
    EXPECT_EQ(problem,
              "outside the URDF's directory (the viewer reads meshes beside the URDF only)")
        << name;
  }
  EXPECT_EQ(tree::find_mesh_file(urdf, "https://example.com/part.stl", problem), fs::path());
  EXPECT_EQ(problem, "not a file the viewer reads (package://, file:// or a path beside the URDF)");
  EXPECT_EQ(tree::find_mesh_file(urdf, "meshes/none.stl", problem), fs::path());
  EXPECT_EQ(problem, "no such file beside the URDF");
  fs::remove_all(root);
}

TEST(UrdfVisuals, TheScenePlacesEachShapeWhereTheUrdfSays) {
  const Model model = load_model(kDir + "/visual_shapes.yaml");
  const auto scene = nlohmann::json::parse(viewer_scene_json(model));
  const nlohmann::json& robot = scene["robot"];
  const nlohmann::json& visuals = robot["visuals"];
  ASSERT_EQ(visuals.size(), 8u);
  // the link of each visual by its index in the scene's links
  const auto link_of = [&](const nlohmann::json& v) {
    return robot["links"][v["link"].get<std::size_t>()]["name"].get<std::string>();
  };
  EXPECT_EQ(link_of(visuals[0]), "base");
  EXPECT_EQ(visuals[0]["shape"], "box");
  expect_vector(json_vector(visuals[0]["size"]), 0.4, 0.3, 0.1);
  EXPECT_EQ(visuals[0]["color"], "#ff0000");
  EXPECT_EQ(link_of(visuals[3]), "arm");
  EXPECT_EQ(visuals[3]["shape"], "cylinder");
  EXPECT_DOUBLE_EQ(visuals[3]["radius"].get<double>(), 0.05);
  EXPECT_DOUBLE_EQ(visuals[3]["length"].get<double>(), 0.6);
  EXPECT_DOUBLE_EQ(visuals[3]["opacity"].get<double>(), 0.5);
  EXPECT_EQ(link_of(visuals[4]), "hand");
  EXPECT_EQ(visuals[4]["shape"], "sphere");
  EXPECT_DOUBLE_EQ(visuals[4]["radius"].get<double>(), 0.08);
  // each centre in the world at the initial pose (shoulder 0.5 rad about y, elbow 0) by the
  // tree's forward kinematics, against the pose worked out by hand: the shoulder at z = 0.1,
  // the hand's frame 0.6 up the arm turned by 90° about z, so its x is the world's y
  tree::TreeData data(*model.robot);
  tree::forward_kinematics(*model.robot, model.q0, data);
  const auto world = [&](const nlohmann::json& v) {
    const Index i = v["link"].get<Index>();
    return Eigen::Vector3d(data.p_WL[std::size_t(i)] +
                           data.R_WL[std::size_t(i)] * json_vector(v["p"]));
  };
  const double s = std::sin(0.5), c = std::cos(0.5);
  expect_vector(world(visuals[0]), 0, 0, 0.05, 1e-15);
  expect_vector(world(visuals[1]), 0.15, 0, 0.1, 1e-15);
  EXPECT_EQ(visuals[1]["format"], "obj");
  EXPECT_EQ(visuals[2]["format"], "dae");
  expect_vector(world(visuals[3]), 0.3 * s, 0, 0.1 + 0.3 * c, 1e-15);
  expect_vector(world(visuals[4]), 0.6 * s, 0.1, 0.1 + 0.6 * c, 1e-15);
  // the cylinder's axis (the visual's z) is the arm's: turned by 0.5 rad about y
  const nlohmann::json& q = visuals[3]["r"];
  const Eigen::Quaterniond r(q[0].get<double>(), q[1].get<double>(), q[2].get<double>(),
                             q[3].get<double>());
  const Eigen::Vector3d axis = data.R_WL[std::size_t(visuals[3]["link"].get<Index>())] *
                               r.toRotationMatrix() * Eigen::Vector3d::UnitZ();
  expect_vector(axis, s, 0, c, 1e-15);
  // the STL mesh embedded (base64 of its bytes, "solid tetra" first); the other one named
  // as the URDF names it, with the reason it is not drawn, and no file
  EXPECT_EQ(visuals[5]["format"], "stl");
  // square.obj, triangle.dae, tetra.stl: each file once, the tetrahedron shown twice
  ASSERT_EQ(robot["meshes"].size(), 3u);
  EXPECT_EQ(visuals[7]["file"], 2);
  EXPECT_EQ(visuals[1]["file"], 0);
  EXPECT_EQ(visuals[2]["file"], 1);
  ASSERT_EQ(visuals[5]["file"], 2);
  const std::string tetra = robot["meshes"][2].get<std::string>();
  EXPECT_EQ(tetra.substr(0, 12), "c29saWQgdGV0");  // "solid tet"
  std::ifstream in(kDir + "/meshes/tetra.stl", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(tetra.size(), (bytes.size() + 2) / 3 * 4);
  expect_vector(json_vector(visuals[5]["scale"]), 2, 2, 2);
  EXPECT_EQ(visuals[6]["mesh"], "meshes/</script><script>window.pwned=1</script><!--.stl");
  EXPECT_EQ(visuals[6]["problem"], "no such file beside the URDF");
  EXPECT_FALSE(visuals[6].contains("file"));
  EXPECT_FALSE(visuals[6].contains("format"));
  // the loop: the hand's sphere centre to the floor point below it, the world's index -1
  ASSERT_EQ(robot["loops"].size(), 1u);
  const nlohmann::json& loop = robot["loops"][0];
  EXPECT_EQ(loop["name"], "tether");
  EXPECT_EQ(loop["type"], "distance");
  EXPECT_EQ(robot["links"][loop["a"].get<std::size_t>()]["name"], "hand");
  EXPECT_EQ(loop["b"], -1);
  expect_vector(json_vector(loop["point_a"]), 0.1, 0, 0);
  expect_vector(json_vector(loop["point_b"]), 0.6 * s, 0.1, 0, 1e-15);
}

TEST(UrdfVisuals, ARobotWithoutVisualsHasNoVisualsInItsScene) {
  const Model model = load_model(std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf");
  const auto scene = nlohmann::json::parse(viewer_scene_json(model));
  EXPECT_FALSE(scene["robot"].contains("visuals"));
  EXPECT_FALSE(scene["robot"].contains("loops"));
  EXPECT_EQ(scene["robot"]["links"].size(), std::size_t(model.robot->link_count()));
}

// A robot's contact in its scene (u15 09): its link and point (the page draws a rod from the
// link's frame to it: a last link without a child or a <visual> ends there) and its plane, a
// point and the unit normal in the plane's link's frame (-1: the world), drawn as a patch
TEST(UrdfVisuals, ARobotsContactsHaveTheirLinkPointAndPlaneInTheScene) {
  const Model model = parse_model(R"(
robot: {urdf: arm2_table.urdf}
contacts:
  - {name: tip, link: l2, point: [0.35, 0, 0], shape: sphere, radius: 0.025,
     plane: {body: ground, point: [0, 0, 0.3], normal: [0, 0, 2]}}
initial: {q: {j1: 0.6, j2: -0.9}}
)",
                                  std::string(UKDYN_TEST_DATA_DIR) + "/arm.yaml");
  const auto robot = nlohmann::json::parse(viewer_scene_json(model))["robot"];
  ASSERT_EQ(robot["contacts"].size(), 1u);
  const nlohmann::json& c = robot["contacts"][0];
  EXPECT_EQ(c["name"], "tip");
  EXPECT_EQ(robot["links"][c["link"].get<std::size_t>()]["name"], "l2");
  expect_vector(json_vector(c["point"]), 0.35, 0, 0);
  EXPECT_EQ(c["plane_link"], -1);
  expect_vector(json_vector(c["plane_point"]), 0, 0, 0.3);
  expect_vector(json_vector(c["plane_normal"]), 0, 0, 1);  // (unit)
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

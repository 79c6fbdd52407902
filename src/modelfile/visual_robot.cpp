// SPDX-License-Identifier: BSD-3-Clause
// The robot's part of the viewer's scene: its links' joints (the page computes the frames by
// forward kinematics), its URDF visual geometry with the mesh files embedded, its loops.
#include "modelfile/visual_robot.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::detail {
namespace {

nlohmann::json vector3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
nlohmann::json quaternion(const Eigen::Quaterniond& r) { return {r.w(), r.x(), r.y(), r.z()}; }

// RFC 4648 base64 of `bytes`
std::string base64(const std::string& bytes) {
  static const char* const kDigits =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const auto byte = [&](std::size_t k) {
      return k < bytes.size() ? unsigned(static_cast<unsigned char>(bytes[k])) : 0u;
    };
    const unsigned v = byte(i) << 16 | byte(i + 1) << 8 | byte(i + 2);
    out += kDigits[v >> 18 & 63];
    out += kDigits[v >> 12 & 63];
    out += i + 1 < bytes.size() ? kDigits[v >> 6 & 63] : '=';
    out += i + 2 < bytes.size() ? kDigits[v & 63] : '=';
  }
  return out;
}

// the mesh's format ("stl", "obj", "dae") and its file: the index of its base64 text in
// `meshes` (each file once, however many visuals show it; `index` maps a file to its place), or
// the problem
void embed_mesh(const tree::LinkVisual& v, nlohmann::json& j, nlohmann::json& meshes,
                std::map<std::string, std::size_t>& index) {
  if (v.mesh_file.empty()) {
    j["problem"] = v.mesh_problem;
    return;
  }
  std::string ext = std::filesystem::path(v.mesh_file).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (ext != ".stl" && ext != ".obj" && ext != ".dae") {
    j["problem"] = "its format (" + ext + ") is not one the viewer reads (STL, OBJ, COLLADA)";
    return;
  }
  j["format"] = ext.substr(1);
  if (const auto known = index.find(v.mesh_file); known != index.end()) {
    j["file"] = known->second;
    return;
  }
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(v.mesh_file, ec);
  if (ec || bytes > kMaxMeshBytes) {
    j.erase("format");
    j["problem"] = ec ? "it cannot be read" : "it is larger than the viewer embeds (16 MiB)";
    return;
  }
  std::ifstream in(v.mesh_file, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) {
    j.erase("format");
    j["problem"] = "it cannot be read";
    return;
  }
  index[v.mesh_file] = meshes.size();
  j["file"] = meshes.size();
  meshes.push_back(base64(text));
}

}  // namespace

nlohmann::json robot_scene(const Model& model) {
  const tree::Tree& tr = *model.robot;
  const std::vector<std::string>& names = tr.coordinate_names();
  // each link's joint, parents first — its origin in the parent's frame, kind, axis and
  // coordinates — from which the page computes the links' frames (tree::forward_kinematics)
  nlohmann::json links = nlohmann::json::array();
  for (Index i = 0; i < tr.link_count(); ++i) {
    const tree::Link& l = tr.link(i);
    nlohmann::json coordinates = nlohmann::json::array();
    for (int k = 0; k < tr.dofs(i); ++k)
      coordinates.push_back(names[std::size_t(tr.offset(i) + k)]);
    links.push_back({{"name", l.name},
                     {"parent", tr.parent(i)},
                     {"joint", l.joint.name},
                     {"kind", tree::joint_kind_name(l.joint.kind)},
                     {"p", vector3(l.joint.p_PJ)},
                     {"r", quaternion(l.joint.R_PJ)},
                     {"axis", vector3(l.joint.axis)},
                     {"coordinates", coordinates}});
  }
  nlohmann::json robot = {{"name", tr.name()}, {"links", links}};
  // a link by name: its index, -1 for the world (URDF's "world" root is no link of the tree)
  const auto link_index = [&](const std::string& name) -> Index {
    for (Index i = 0; i < tr.link_count(); ++i)
      if (tr.link(i).name == name) return i;
    return -1;
  };
  // the URDF's visual geometry, in its link's frame
  nlohmann::json visuals = nlohmann::json::array(), meshes = nlohmann::json::array();
  std::map<std::string, std::size_t> mesh_index;
  for (const tree::LinkVisual& v : model.visual.robot) {
    nlohmann::json j = {{"link", link_index(v.link)},
                        {"link_name", v.link},
                        {"shape", tree::visual_shape_name(v.shape)},
                        {"p", vector3(v.p_LV)},
                        {"r", quaternion(v.R_LV)}};
    if (!v.name.empty()) j["name"] = v.name;
    switch (v.shape) {
      case tree::LinkVisual::Shape::kBox:
        j["size"] = vector3(v.size);
        break;
      case tree::LinkVisual::Shape::kCylinder:
        j["radius"] = v.size[0];
        j["length"] = v.size[1];
        break;
      case tree::LinkVisual::Shape::kSphere:
        j["radius"] = v.size[0];
        break;
      case tree::LinkVisual::Shape::kMesh:
        j["mesh"] = v.mesh;
        j["scale"] = vector3(v.size);
        embed_mesh(v, j, meshes, mesh_index);
        break;
    }
    if (!v.color.empty()) {
      j["color"] = v.color;
      j["opacity"] = v.opacity;
    }
    visuals.push_back(j);
  }
  if (!visuals.empty()) robot["visuals"] = visuals;
  if (!meshes.empty()) robot["meshes"] = meshes;
  // the loops: the page draws each from link_a's frame through the points to link_b's
  nlohmann::json loops = nlohmann::json::array();
  for (const VisualLoop& l : model.visual.loops) {
    loops.push_back({{"name", l.name},
                     {"type", l.type},
                     {"a", link_index(l.link_a)},
                     {"point_a", vector3(l.point_a)},
                     {"b", link_index(l.link_b)},
                     {"point_b", vector3(l.point_b)}});
  }
  if (!loops.empty()) robot["loops"] = loops;
  // the contacts: a rod from the link's frame to each contact's point (a last link has no child
  // frame to end at) and each contact's plane (its point and normal in its link's frame, -1 the
  // world), which the page draws as a patch
  nlohmann::json contacts = nlohmann::json::array();
  for (const VisualContact& c : model.visual.contacts) {
    if (c.link < 0 && c.plane_normal.isZero(0.0)) continue;
    contacts.push_back({{"name", c.name},
                        {"link", c.link},
                        {"point", vector3(c.link_point)},
                        {"plane_link", c.plane_link},
                        {"plane_point", vector3(c.plane_point)},
                        {"plane_normal", vector3(c.plane_normal)}});
  }
  if (!contacts.empty()) robot["contacts"] = contacts;
  return robot;
}

}  // namespace ukdyn::detail

// SPDX-License-Identifier: BSD-3-Clause
// A URDF's visual geometry (multibody/tree_visual.hpp): each link's <visual> elements through
// urdfdom, and the mesh files they name, looked for beside the URDF only.
#include "ukdyn/multibody/tree_visual.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <urdf_model/model.h>

#include "urdf_parse.hpp"

namespace ukdyn::tree {

namespace fs = std::filesystem;

namespace {

// whether `file` (canonical) lies under the directory `dir` (canonical)
bool is_under(const fs::path& file, const fs::path& dir) {
  const auto [d, f] = std::mismatch(dir.begin(), dir.end(), file.begin(), file.end());
  return d == dir.end() && f != file.end();
}

// "#rrggbb" of a colour's r, g, b in [0, 1]
std::string hex_color(double r, double g, double b) {
  const auto byte = [](double v) { return int(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); };
  char text[8];
  std::snprintf(text, sizeof text, "#%02x%02x%02x", byte(r), byte(g), byte(b));
  return text;
}

LinkVisual link_visual(const std::string& link, const urdf::Visual& v, const fs::path& urdf,
                       double length) {
  LinkVisual out;
  out.link = link;
  out.name = v.name;
  out.p_LV = {v.origin.position.x, v.origin.position.y, v.origin.position.z};
  const urdf::Rotation& r = v.origin.rotation;
  out.R_LV = Eigen::Quaterniond(r.w, r.x, r.y, r.z).normalized();
  switch (v.geometry->type) {
    case urdf::Geometry::BOX: {
      const auto& box = static_cast<const urdf::Box&>(*v.geometry);
      out.shape = LinkVisual::Shape::kBox;
      out.size = {box.dim.x, box.dim.y, box.dim.z};
      break;
    }
    case urdf::Geometry::CYLINDER: {
      const auto& c = static_cast<const urdf::Cylinder&>(*v.geometry);
      out.shape = LinkVisual::Shape::kCylinder;
      out.size = {c.radius, c.length, 0.0};
      break;
    }
    case urdf::Geometry::SPHERE:
      out.shape = LinkVisual::Shape::kSphere;
      out.size = {static_cast<const urdf::Sphere&>(*v.geometry).radius, 0.0, 0.0};
      break;
    case urdf::Geometry::MESH: {
      const auto& m = static_cast<const urdf::Mesh&>(*v.geometry);
      out.shape = LinkVisual::Shape::kMesh;
      out.size = {m.scale.x, m.scale.y, m.scale.z};
      out.mesh = m.filename;
      const fs::path file = find_mesh_file(urdf, m.filename, out.mesh_problem);
      if (!file.empty()) out.mesh_file = file.string();
      break;
    }
  }
  // the material's colour (urdfdom resolves a material given by name to the robot's)
  // SI to the model's length unit: the origin and the sizes (a mesh's scale too: its file is in
  // metres, as URDF's)
  out.p_LV *= length;
  out.size *= length;
  if (v.material) {
    const urdf::Color& c = v.material->color;
    out.color = hex_color(c.r, c.g, c.b);
    out.opacity = std::clamp(double(c.a), 0.0, 1.0);
  }
  return out;
}

}  // namespace

const char* visual_shape_name(LinkVisual::Shape shape) {
  switch (shape) {
    case LinkVisual::Shape::kBox:
      return "box";
    case LinkVisual::Shape::kCylinder:
      return "cylinder";
    case LinkVisual::Shape::kSphere:
      return "sphere";
    case LinkVisual::Shape::kMesh:
      return "mesh";
  }
  return "box";
}

fs::path find_mesh_file(const fs::path& urdf, const std::string& name, std::string& problem) {
  std::error_code ec;
  const fs::path dir = fs::weakly_canonical(fs::absolute(urdf, ec).parent_path(), ec);
  // the candidates: (file, the directory it must lie under)
  std::vector<std::pair<fs::path, fs::path>> candidates;
  const std::string package = "package://", file_scheme = "file://";
  if (name.rfind(package, 0) == 0) {
    const std::string rest = name.substr(package.size());
    const std::size_t slash = rest.find('/');
    const std::string pkg = rest.substr(0, slash);
    const fs::path inside =
        slash == std::string::npos ? fs::path() : fs::path(rest.substr(slash + 1));
    for (fs::path a = dir; !a.empty(); a = a.parent_path()) {
      if (a.filename() == pkg) {
        candidates.emplace_back(a / inside, a);
        break;
      }
      if (a == a.parent_path()) break;
    }
    candidates.emplace_back(dir / inside, dir);
  } else if (name.find("://") != std::string::npos && name.rfind(file_scheme, 0) != 0) {
    problem = "not a file the viewer reads (package://, file:// or a path beside the URDF)";
    return {};
  } else {
    const fs::path p(name.rfind(file_scheme, 0) == 0 ? name.substr(file_scheme.size()) : name);
    candidates.emplace_back(p.is_absolute() ? p : dir / p, dir);
  }
  for (const auto& [file, root] : candidates) {
    const fs::path found = fs::weakly_canonical(file, ec);
    if (ec || !fs::is_regular_file(found, ec)) continue;
    if (!is_under(found, root)) {
      problem = "outside the URDF's directory (the viewer reads meshes beside the URDF only)";
      return {};
    }
    problem.clear();
    return found;
  }
  problem = "no such file beside the URDF";
  return {};
}

std::vector<LinkVisual> load_urdf_visuals(const std::string& path, double length) {
  const urdf::ModelInterfaceSharedPtr model =
      detail::parse_urdf_file(path, "ukdyn::tree::load_urdf_visuals: " + path + ": ").model;
  std::vector<LinkVisual> out;
  // depth first from the root, children in order (the tree's order)
  std::vector<urdf::LinkConstSharedPtr> stack;
  if (const urdf::LinkConstSharedPtr root = model->getRoot()) stack.push_back(root);
  while (!stack.empty()) {
    const urdf::LinkConstSharedPtr l = stack.back();
    stack.pop_back();
    for (auto c = l->child_links.rbegin(); c != l->child_links.rend(); ++c) stack.push_back(*c);
    for (const urdf::VisualSharedPtr& v : l->visual_array) {
      if (v && v->geometry) out.push_back(link_visual(l->name, *v, path, length));
    }
  }
  return out;
}

}  // namespace ukdyn::tree

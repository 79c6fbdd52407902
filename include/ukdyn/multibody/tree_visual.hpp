// SPDX-License-Identifier: BSD-3-Clause
/// @file multibody/tree_visual.hpp
/// A robot's visual geometry: the `<visual>` elements of a URDF's links (box, cylinder, sphere,
/// mesh), kept apart from the tree as Pinocchio keeps its GeometryModel apart from its Model.
/// Description only: no pass of the dynamics reads it; the browser viewer draws it
/// (docs/viewer.md, docs/robots.md "In the viewer").
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace ukdyn::tree {

/// One `<visual>` of a URDF link, in the link's frame.
struct LinkVisual {
  /// The geometry: URDF's `<box>`, `<cylinder>` (its axis the visual frame's z), `<sphere>`,
  /// `<mesh>`.
  enum class Shape { kBox, kCylinder, kSphere, kMesh };

  std::string link;           ///< the link's name (the tree's, or the URDF's "world" root)
  std::string name;           ///< the visual's `name` attribute; may be empty
  Shape shape = Shape::kBox;  ///< which geometry (its size: `size`)
  Eigen::Vector3d p_LV = Eigen::Vector3d::Zero();  ///< `<origin xyz>`: the visual's origin in L
  Eigen::Quaterniond R_LV = Eigen::Quaterniond::Identity();  ///< `<origin rpy>`: V to L
  /// box: its edges along the visual's x, y, z; cylinder: (radius, length, 0); sphere:
  /// (radius, 0, 0); mesh: its scale along x, y, z
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  std::string mesh;          ///< mesh: the file name as the URDF writes it (package://, …)
  std::string mesh_file;     ///< mesh: the file found (see find_mesh_file); empty when none
  std::string mesh_problem;  ///< mesh: why no file was found; empty when one was
  std::string color;         ///< the material's colour "#rrggbb"; empty when it has none
  double opacity = 1.0;      ///< the material's alpha, in [0, 1]
};

/// The `<visual>` elements of every link of the URDF file at `path`, links parents first (depth
/// first from the root, as the tree orders them), each link's visuals in the file's order; a mesh's
/// file is looked for by find_mesh_file. A material given by name is the robot's `<material>` of
/// that name (urdfdom resolves it).
/// @throws std::invalid_argument naming the file when it cannot be read or is not a URDF
/// (as load_urdf). `length`: the model's length units per metre (UnitScale::length), by which
/// origins and sizes are converted from URDF's metres (a mesh's scale too: its vertices are
/// metres). Cost: one parse of the file and one look-up per mesh.
std::vector<LinkVisual> load_urdf_visuals(const std::string& path, double length = 1.0);

/// The file of a URDF mesh named `name` by the URDF file `urdf`, looked for only beside the
/// URDF (so that a model file can never make the viewer read a file elsewhere):
/// * `package://pkg/rest`: `A/rest` for the URDF's directory or the nearest ancestor `A` of it
///   named `pkg` (ROS's layout, pkg/urdf/robot.urdf and pkg/meshes/…), else `rest` in the
///   URDF's directory;
/// * `file://path` or a plain path: relative to the URDF's directory (an absolute one as is).
/// The file must exist, be a regular file and lie, after resolving `..` and symbolic links,
/// under the directory it was looked for in. Returns its absolute path, or an empty path with
/// `problem` saying why (no absolute path in it: it is shown in the page).
/// Cost: a few file-system look-ups.
std::filesystem::path find_mesh_file(const std::filesystem::path& urdf, const std::string& name,
                                     std::string& problem);

/// URDF's name of a visual's shape: "box", "cylinder", "sphere" or "mesh".
const char* visual_shape_name(LinkVisual::Shape shape);

}  // namespace ukdyn::tree

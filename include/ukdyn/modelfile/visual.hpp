// SPDX-License-Identifier: BSD-3-Clause
/// @file modelfile/visual.hpp
/// How a model is drawn by the browser viewer (`ukdyn run --viewer`, Python's Result.show();
/// docs/viewer.md): the `visual:` entries of a model file, and the scene description the page
/// generator (python/ukdyn/viewer.py) reads beside trajectory.csv.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/multibody/tree_visual.hpp"

namespace ukdyn {

struct Model;

/// One solid drawn with a body (`visual:` of a body entry), in body coordinates.
struct VisualShape {
  std::string shape;  ///< "box", "cylinder", "capsule" or "sphere"
  /// box: the edges along the body's x, y, z; cylinder, capsule: (radius, length, 0) with the
  /// length along `axis`; sphere: (radius, 0, 0)
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  char axis = 'x';                                   ///< cylinder, capsule: 'x', 'y' or 'z'
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< its centre in body coordinates
  std::string color;                                 ///< "#rrggbb"; empty: the viewer's choice
};

/// A point of a model in coordinates (`visual: points:`): its position is the output columns
/// `visual.<name>.x`, `.y` (and `.z` when three expressions are given), which the reader adds
/// after the model's output expressions.
struct VisualPoint {
  std::string name;     ///< its name under `visual: points:` (columns `visual.<name>.x` …)
  int dimensions = 2;   ///< 2 (z = 0) or 3
  double radius = 0.0;  ///< of its sphere; 0: the viewer's choice
  std::string color;    ///< "#rrggbb"; empty: the viewer's choice
  /// per component: the index of the coordinate the expression is exactly (`bob: [x, y]`), or
  /// -1 (an expression of the coordinates); the viewer draws that coordinate's forces there
  std::vector<int> coordinates;
  std::vector<std::string> expressions;  ///< per component: the expression's text
};

/// A frame of a model in coordinates (`visual: frames:`), drawn as three axes: its origin is
/// the columns `visual.<name>.x`, `.y` (, `.z`), its orientation `visual.<name>.angle` (about z,
/// planar) or `visual.<name>.qw`, `.qx`, `.qy`, `.qz` (a quaternion, normalized by the viewer).
struct VisualFrame {
  std::string name;         ///< its name under `visual: frames:` (columns `visual.<name>.x` …)
  int dimensions = 2;       ///< of the origin: 2 (z = 0) or 3
  bool quaternion = false;  ///< orientation by quaternion (else by angle about z)
  double size = 0.0;        ///< the axes' length; 0: the viewer's choice
};

/// A unilateral contact drawn by the viewer (`visual: contacts:`, docs/contact.md): its point
/// is the columns `visual.contact.<name>.x`, `.y` (, `.z`), the direction its force pushes the
/// system `visual.contact.<name>.nx`, `.ny` (, `.nz`; normalized by the viewer); the force's
/// magnitude is the constraint's multiplier `lambda.<name>` (the normal force when the gap is a
/// distance), and its impacts are marked there. A bodies or robot model's `contacts:` entry is
/// drawn without `visual: contacts:` (a hand-written entry of its name replaces it): the reader
/// knows its point, and run_model computes the same columns from `geometry` at each sample.
struct VisualContact {
  /// The contact's point (a point's; a sphere's point nearest the plane, c − r n; a disk's
  /// rim's lowest point, c − r (n − s a) / |n − s a|, s = n · a) and the plane's unit normal n,
  /// world frame, at q (n). Must not change anything (a description's).
  using Geometry = std::function<void(const Eigen::Ref<const Eigen::VectorXd>& q,
                                      Eigen::Vector3d& point, Eigen::Vector3d& normal)>;
  std::string name;    ///< the unilateral constraint's name
  int dimensions = 2;  ///< 2 (z = 0) or 3
  /// a `contacts:` entry's point and normal, from which run_model computes the columns; null:
  /// they are `visual: contacts:` expressions (outputs of Model::output_program)
  Geometry geometry;
  /// The world axes of the contact's Coulomb friction at a contact point at q: columns n_W,
  /// t_1, t_2 of ContactKinematicsFn (a planar contact: n_W, t_1 and a zero third column), from
  /// which run_model writes the friction force f_W = Σ f_i t_i as the columns
  /// `visual.contact.<name>.fx`, `.fy` (, `.fz`). Null: no friction arrow at this contact.
  using Axes =
      std::function<void(const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Matrix3d& axes)>;
  Axes axes;  ///< the friction's world axes at q (see Axes); null: no friction arrow
  /// A robot's contact (robot_visual_contact), which the viewer's scene draws with the robot:
  /// the link its point (a sphere's or disk's centre) is on (-1: none, not a robot's contact)
  /// and the point in the link's frame — a rod from the link's frame to it, so that a last link
  /// without `<visual>` is drawn up to its contact — and its plane: the plane's link (-1: the
  /// world), a point of it and its unit normal in that link's frame, drawn as a patch.
  int link = -1;
  Eigen::Vector3d link_point = Eigen::Vector3d::Zero();    ///< the point, in link's frame
  int plane_link = -1;                                     ///< the plane's link (-1: the world)
  Eigen::Vector3d plane_point = Eigen::Vector3d::Zero();   ///< in plane_link's frame
  Eigen::Vector3d plane_normal = Eigen::Vector3d::Zero();  ///< unit, in plane_link's frame; 0: none
};

/// A loop closure of a robot (`robot: loops:`), drawn by the viewer as a dashed line from
/// link_a's frame through its point and link_b's point to link_b's frame (docs/robots.md).
struct VisualLoop {
  std::string name;    ///< the loop's (the constraint's) name
  std::string type;    ///< "point", "distance", "revolute" or "weld"
  std::string link_a;  ///< the first link's name ("world": the world)
  std::string link_b;  ///< the second link's name ("world": the world)
  Eigen::Vector3d point_a = Eigen::Vector3d::Zero();  ///< in link_a's frame
  Eigen::Vector3d point_b = Eigen::Vector3d::Zero();  ///< in link_b's frame
};

/// The `visual:` information of a model. Immutable after the reader fills it.
struct ModelVisual {
  /// multibody models: each body's solids by body name (none: drawn as its equivalent box)
  std::vector<std::pair<std::string, std::vector<VisualShape>>> bodies;
  /// models in coordinates: the points, and the links (pairs of point names) drawn between them
  std::vector<VisualPoint> points;
  /// models in coordinates: the links drawn between the points, as pairs of point names
  std::vector<std::pair<std::string, std::string>> links;
  /// models in coordinates: the frames drawn (`visual: frames:`)
  std::vector<VisualFrame> frames;
  /// the unilateral contacts drawn: a bodies or robot model's `contacts:` (with their
  /// geometry), then `visual: contacts:`
  std::vector<VisualContact> contacts;
  /// the points' and frames' columns, `visual.<name>.x` …: the outputs of Model::output_program
  /// after the output expressions (the last columns of trajectory.csv)
  std::vector<std::string> columns;
  /// the points (coordinate models) or bodies (multibody models) whose paths are drawn
  std::vector<std::string> trails;
  /// a robot's URDF visual geometry (tree::load_urdf_visuals) and its loop closures
  std::vector<tree::LinkVisual> robot;
  /// a robot's loop closures (`robot: loops:`), drawn as dashed lines
  std::vector<VisualLoop> loops;
};

/// The scene description of `model` as JSON text, for the page generator: the bodies (kind,
/// mass, principal inertias, solids), the joints (type, parent, child and their points), the
/// points, links and trails of `visual:`, the control's requirements; a robot's links (their
/// joints), their URDF visuals (a mesh's file embedded once, base64, when it is found and is
/// STL, OBJ or COLLADA of at most kMaxMeshBytes; else the reason it is not drawn) and its loops.
/// Cost O(bodies + joints + bytes of the meshes).
std::string viewer_scene_json(const Model& model);

/// The largest mesh file the viewer embeds in its page (bytes).
inline constexpr std::size_t kMaxMeshBytes = 16u << 20;

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// The scene description of a model for the browser viewer (modelfile/visual.hpp): what the page
// generator (python/ukdyn/viewer.py) needs beside trajectory.csv to draw the model.
#include "ukdyn/modelfile/visual.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/QR>
#include <nlohmann/json.hpp>

#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/multibody/multibody.hpp"
#include "ukdyn/multibody/tree.hpp"

#include "modelfile/visual_robot.hpp"

namespace ukdyn {
namespace {

nlohmann::json vector3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

const char* kind_name(mb::BodyKind kind) {
  switch (kind) {
    case mb::BodyKind::kParticle:
      return "particle";
    case mb::BodyKind::kPlanar:
      return "planar";
    case mb::BodyKind::kRigid:
      return "rigid";
  }
  return "particle";
}

nlohmann::json shape_json(const VisualShape& s) {
  nlohmann::json j = {{"shape", s.shape}, {"offset", vector3(s.offset)}};
  if (s.shape == "box") {
    j["size"] = vector3(s.size);
  } else {
    j["radius"] = s.size[0];
    if (s.shape != "sphere") {
      j["length"] = s.size[1];
      j["axis"] = std::string(1, s.axis);
    }
  }
  if (!s.color.empty()) j["color"] = s.color;
  return j;
}

// the output program's outputs at (q, q' = 0, t) (evaluate_output_expressions' inputs)
std::vector<double> outputs_at(const Model& model, const VectorXd& q, double t) {
  const expr::Program& p = model.output_program;
  const std::size_t n = std::size_t(q.size());
  std::vector<double> in(std::size_t(p.inputs()), 0.0), out(std::size_t(p.outputs())),
      scratch(std::size_t(p.scratch_size()));
  std::copy_n(q.data(), n, in.begin());
  in[2 * n] = t;
  p.evaluate(in.data(), out.data(), scratch.data());
  return out;
}

// The friction drawn at visual contact c (docs/viewer.md, "`visual:` in a model file"): the
// Coulomb contact on its constraint, the columns of the generalized friction force Q_f on each
// sliding coordinate (visual.contact.<name>.Qf.<coordinate>, run_model's: Qc_nonideal.<coordinate>
// while it slides, the stick constraint's whole multiplier while it sticks), and the map F =
// (J_cᵀ)⁺ Q_f to the contact point's axes, J_c = ∂(at)/∂(sliding coordinates) by central
// differences at the initial state (constant for the Cartesian sliding coordinates that
// docs/friction.md asks for) of the point's expressions, or of its geometry (a contacts: entry's).
// Null when no Coulomb contact sits on c.
nlohmann::json contact_friction(const Model& model, const VisualContact& c) {
  const System& sys = model.system;
  Index constraint = -1;
  for (Index k = 0; k < sys.constraint_count(); ++k)
    if (sys.constraint(k).name() == c.name) constraint = k;
  const FrictionContact* fc = nullptr;
  for (const FrictionContact& f : sys.friction_contacts())
    if (f.normal_constraint == constraint && f.mu > 0.0) fc = &f;
  if (!fc) return nullptr;
  const std::string stick = sys.constraint(fc->stick_constraint).name();
  static const char* axes[] = {"x", "y", "z"};
  // the scene's entry: the columns summed per sliding component, and their map to the axes
  const auto entry = [&](nlohmann::json columns, nlohmann::json map) -> nlohmann::json {
    return {{"name", stick.substr(std::string("stick.").size())},
            {"mu", fc->mu},
            {"columns", std::move(columns)},
            {"map", std::move(map)}};
  };
  if (fc->kinematics) {
    // a contact point's friction (ContactKinematics): its force J_Pᵀ f on the coordinates does
    // not map back from them; run_model writes f itself, visual.contact.<name>.fx, ... (the
    // contact's axes known, VisualContact::axes)
    if (!c.axes) return nullptr;
    nlohmann::json map = nlohmann::json::array(), columns = nlohmann::json::array();
    for (int a = 0; a < c.dimensions; ++a) {
      nlohmann::json row = nlohmann::json::array();
      for (int b = 0; b < c.dimensions; ++b) row.push_back(a == b ? 1.0 : 0.0);
      map.push_back(row);
      columns.push_back({"visual.contact." + c.name + ".f" + axes[a]});
    }
    return entry(std::move(columns), std::move(map));
  }
  const std::size_t nc = fc->coordinates.size();
  // the outputs of the contact point's axes
  std::vector<std::size_t> at;
  for (int a = 0; a < c.dimensions; ++a) {
    const std::string column = "visual.contact." + c.name + "." + axes[a];
    const auto& vc = model.visual.columns;
    at.push_back(model.output_names.size() +
                 std::size_t(std::find(vc.begin(), vc.end(), column) - vc.begin()));
  }
  // the contact point at q: its geometry (a contacts: entry), or its output expressions
  const double t0 = model.options.t_start;
  const auto point_at = [&](const VectorXd& q) {
    Eigen::Vector3d p = Eigen::Vector3d::Zero(), n;
    if (c.geometry) {
      c.geometry(q, p, n);
    } else {
      const std::vector<double> out = outputs_at(model, q, t0);
      for (int a = 0; a < c.dimensions; ++a) p[a] = out[at[std::size_t(a)]];
    }
    return p;
  };
  // J_c (dimensions × nc) by central differences
  MatrixXd J(c.dimensions, Index(nc));
  for (std::size_t j = 0; j < nc; ++j) {
    const Index i = fc->coordinates[j];
    const double h = 1e-6 * std::max(1.0, std::abs(model.q0[i]));
    VectorXd plus = model.q0, minus = model.q0;
    plus[i] += h;
    minus[i] -= h;
    const Eigen::Vector3d up = point_at(plus), down = point_at(minus);
    for (int a = 0; a < c.dimensions; ++a) J(a, Index(j)) = (up[a] - down[a]) / (2 * h);
  }
  // F = (J_cᵀ)⁺ Q_f, rounded to 8 digits (a Cartesian coordinate maps by exactly 1)
  const MatrixXd F =
      Eigen::CompleteOrthogonalDecomposition<MatrixXd>(J.transpose()).pseudoInverse();
  nlohmann::json map = nlohmann::json::array(), columns = nlohmann::json::array();
  for (int a = 0; a < c.dimensions; ++a) {
    nlohmann::json row = nlohmann::json::array();
    for (std::size_t j = 0; j < nc; ++j) row.push_back(std::round(F(a, Index(j)) * 1e8) / 1e8);
    map.push_back(row);
  }
  for (std::size_t j = 0; j < nc; ++j) {
    const std::string coordinate = sys.coordinate_names()[std::size_t(fc->coordinates[j])];
    columns.push_back({"visual.contact." + c.name + ".Qf." + coordinate});
  }
  return entry(std::move(columns), std::move(map));
}

}  // namespace

const std::string& output_column_name(const Model& model, std::size_t k) {
  return k < model.output_names.size() ? model.output_names[k]
                                       : model.visual.columns.at(k - model.output_names.size());
}

std::string viewer_scene_json(const Model& model) {
  nlohmann::json scene = {{"model", model.name}, {"coordinates", model.system.coordinate_names()}};
  // each coordinate's unit (m, rad, 1, a file's units:; "" when not known): the page's units
  scene["coordinate_units"] = model.coordinate_units;
  // bodies: kind, mass, principal inertias (the equivalent box when no solid is declared)
  nlohmann::json bodies = nlohmann::json::array(), joints = nlohmann::json::array();
  bool planar = true;
  if (model.multibody) {
    const mb::MultibodyModel& m = *model.multibody;
    for (const mb::BodyInfo& b : m.bodies) {
      nlohmann::json body = {{"name", b.name},
                             {"kind", kind_name(b.kind)},
                             {"mass", b.mass},
                             {"inertia", vector3(b.inertia)}};
      if (b.kind != mb::BodyKind::kPlanar) planar = false;
      for (const auto& [name, shapes] : model.visual.bodies) {
        if (name != b.name) continue;
        nlohmann::json list = nlohmann::json::array();
        for (const VisualShape& s : shapes) list.push_back(shape_json(s));
        body["visual"] = list;
      }
      bodies.push_back(body);
    }
    // joints: the points of its frames on the parent and the child (body coordinates); the
    // reaction columns reaction.<joint>.* are the force at the child's point
    const auto body_name = [&](mb::BodyId id) {
      return id == mb::kGround ? std::string("ground") : m.bodies.at(std::size_t(id)).name;
    };
    for (const mb::JointInfo& j : m.joints) {
      // (a contact is drawn as a contact, with its whole normal force lambda_total and its
      // friction, not as a joint with its ideal share reaction.<contact>.*)
      if (mb::is_contact(j.type)) continue;
      joints.push_back({{"name", j.name},
                        {"type", mb::to_string(j.type)},
                        {"parent", body_name(j.parent)},
                        {"child", body_name(j.child)},
                        {"parent_point", vector3(j.frame_parent.p)},
                        {"child_point", vector3(j.frame_child.p)},
                        {"planar", j.planar}});
      // the joint's axis, for the page's joint axes: a revolute joint's about the child frame's
      // z, a prismatic's along the parent frame's x (planar) or z, a cylindrical's the parent z;
      // in the coordinates of the body named by "axis_on"
      if (j.type == mb::JointType::kRevolute) {
        joints.back()["axis"] = vector3(j.frame_child.R.col(2));
        joints.back()["axis_on"] = "child";
      } else if (j.type == mb::JointType::kPrismatic || j.type == mb::JointType::kCylindrical) {
        const bool along_x = j.planar && j.type == mb::JointType::kPrismatic;
        joints.back()["axis"] = vector3(j.frame_parent.R.col(along_x ? 0 : 2));
        joints.back()["axis_on"] = "parent";
      }
    }
  }
  scene["bodies"] = bodies;
  scene["joints"] = joints;
  nlohmann::json points = nlohmann::json::array(), links = nlohmann::json::array();
  for (const VisualPoint& p : model.visual.points) {
    nlohmann::json point = {{"name", p.name}, {"dimensions", p.dimensions}};
    if (p.dimensions == 3) planar = false;
    if (p.radius > 0.0) point["radius"] = p.radius;
    if (!p.color.empty()) point["color"] = p.color;
    // the coordinate each component is exactly (null: an expression), and the expressions
    const std::vector<std::string>& names = model.system.coordinate_names();
    nlohmann::json coordinates = nlohmann::json::array();
    for (const int c : p.coordinates) {
      if (c >= 0 && std::size_t(c) < names.size()) {
        coordinates.push_back(names[std::size_t(c)]);
      } else {
        coordinates.push_back(nullptr);
      }
    }
    point["coordinates"] = coordinates;
    point["expressions"] = p.expressions;
    points.push_back(point);
  }
  for (const auto& [a, b] : model.visual.links) links.push_back({a, b});
  nlohmann::json frames = nlohmann::json::array();
  for (const VisualFrame& f : model.visual.frames) {
    nlohmann::json frame = {
        {"name", f.name}, {"dimensions", f.dimensions}, {"quaternion", f.quaternion}};
    if (f.dimensions == 3 || f.quaternion) planar = false;
    if (f.size > 0.0) frame["size"] = f.size;
    frames.push_back(frame);
  }
  scene["frames"] = frames;
  nlohmann::json contacts = nlohmann::json::array();
  for (const VisualContact& c : model.visual.contacts) {
    if (c.dimensions == 3) planar = false;
    nlohmann::json contact = {{"name", c.name}, {"dimensions", c.dimensions}};
    if (nlohmann::json friction = contact_friction(model, c); !friction.is_null())
      contact["friction"] = std::move(friction);
    contacts.push_back(contact);
  }
  scene["points"] = points;
  scene["links"] = links;
  scene["trails"] = model.visual.trails;
  if (!contacts.empty()) scene["contacts"] = contacts;
  // a robot (robot: or a .urdf): its links, visuals and loops (modelfile/visual_robot.cpp)
  if (model.robot) {
    scene["robot"] = detail::robot_scene(model);
    planar = false;
  }
  scene["planar"] = planar;
  scene["controlled"] = bool(model.controller);
  return scene.dump();
}

}  // namespace ukdyn

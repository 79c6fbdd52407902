// SPDX-License-Identifier: BSD-3-Clause
// contacts: in a robot model file (docs/robots.md, "Contacts"; the syntax shared with bodies
// models, docs/contact.md): each entry one unilateral gap between a link's point, sphere or disk
// and a plane on the world or on another link (tree::contact_constraint,
// tree::disk_contact_constraint):
//   contacts:
//     - name: tip                  required, unique among the constraints and loops
//       link: fore                 the link the point or sphere is fixed on
//       point: [0.4, 0, 0]         in the link's frame (default its origin); a disk's centre
//       shape: sphere              point (default) | sphere | disk
//       radius: 0.03               sphere, disk: required, > 0; point: not allowed
//       axis: [0, 0, 1]            disk only: the normal of its face in the link's frame
//                                  (default the link's z axis); not flat on its plane at q0
//       plane: {link: base, point: [0, 0, 0], normal: [0, 0, 1]}   default: the world's z = 0,
//                                  normal +z (body: ground or link: world for the world)
//       restitution: 0.5           Newton's e in [0, 1] (default 0)
//       restitution_law: newton    or poisson
#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/contact_restitution.hpp"
#include "ukdyn/multibody/multibody.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/multibody/tree_closures.hpp"

#include "modelfile/reader.hpp"
#include "modelfile/visual_contacts.hpp"

namespace ukdyn::model_reader {

namespace {

// (the keys a robot's contact takes; `body` is read only to say that it names a link instead)
const std::vector<std::string> kRobotContactKeys = {
    "name", "link", "point", "shape", "radius", "axis", "plane", "restitution", "restitution_law"};
const std::vector<std::string> kRobotPlaneKeys = {"link", "body", "point", "normal"};

constexpr const char* kRobotContactExample =
    "{name: tip, link: fore, point: [0.4, 0, 0], shape: sphere, radius: 0.03, restitution: 0.5}";

// "did you mean 'radius'? " for a key within two edits of a known one (Levenshtein), else ""
std::string robot_contact_key_hint(const std::string& key, const std::vector<std::string>& known) {
  std::string best;
  std::size_t best_d = 3;
  for (const std::string& k : known) {
    std::vector<std::size_t> row(k.size() + 1);
    for (std::size_t j = 0; j <= k.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= key.size(); ++i) {
      std::size_t diag = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= k.size(); ++j) {
        const std::size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (key[i - 1] == k[j - 1] ? 0 : 1)});
        diag = up;
      }
    }
    if (row[k.size()] < best_d && row[k.size()] < key.size()) best_d = row[k.size()], best = k;
  }
  return best.empty() ? std::string() : "did you mean '" + best + "'? ";
}

}  // namespace

void Reader::read_robot_contacts(const YAML::Node& root, const tree::Tree& robot,
                                 const std::string& urdf, std::set<std::string>& names,
                                 SystemBuilder& builder, std::vector<VisualContact>& drawn) {
  const YAML::Node cs = root["contacts"];
  if (!cs) return;
  if (!cs.IsSequence())
    fail(cs, "contacts must be a list", std::string("contacts: [") + kRobotContactExample + "]");
  // the names of the constraints: section's entries (a contact's name must differ)
  std::set<std::string> constraints;
  for (const std::string& c : constraint_names(root)) constraints.insert(c);
  // a hint naming a link of this robot (its last: most often the tip), not an example's
  const std::string link_hint = robot.link_count() > 0
                                    ? "link: " + robot.link(robot.link_count() - 1).name
                                    : "link: <a link>";
  // a link welded to the world: fixed joints only between it and the world (or the world itself)
  const auto welded = [&](Index i) {
    for (; i >= 0; i = robot.parent(i))
      if (robot.link(i).joint.kind != tree::JointKind::kFixed) return false;
    return true;
  };
  const auto link_of = [&](const YAML::Node& l, const std::string& what) -> Index {
    if (!l.IsScalar()) fail(l, what + ": a link is named by a string", link_hint);
    if (l.Scalar() == "world") return -1;
    try {
      return robot.link_index(l.Scalar());
    } catch (const std::invalid_argument&) {
      std::vector<std::string> links;
      for (Index i = 0; i < robot.link_count(); ++i) links.push_back(robot.link(i).name);
      fail(l, what + ": no link '" + l.Scalar() + "' in " + urdf,
           "the links are world, " + join(links));
    }
  };
  std::shared_ptr<const tree::Tree> shared;  // the robot, for the drawn contacts
  // the start a disk must not lie flat at: the neutral pose, with initial: q's values (read
  // again, with the same checks, by read_initial)
  const auto initial_q = [&]() {
    VectorXd q = robot.neutral();
    const YAML::Node init = root["initial"];
    if (init && init.IsMap() && init["q"] && init["q"].IsMap()) {
      for (const auto& kv : init["q"]) q[coordinate(kv.first)] = number(kv.second, "initial q");
    }
    return q;
  };
  for (const auto& c : cs) {
    if (!c.IsMap()) fail(c, "a contact is a mapping", std::string("e.g. ") + kRobotContactExample);
    const YAML::Node nm = c["name"];
    if (!nm || !nm.IsScalar() || !is_identifier(nm.Scalar()))
      fail(nm ? nm : c, "a contact needs a name (an identifier)", "name: tip");
    const std::string name = nm.Scalar(), what = "contact '" + name + "'";
    // the shape first: a bodies model's shape (box, with its size:) is named as the shape
    // that a robot lacks, not as an unknown key
    const std::string shape = c["shape"] ? c["shape"].Scalar() : "point";
    if (shape != "point" && shape != "sphere" && shape != "disk")
      fail(c["shape"], what + ": shape must be point, sphere or disk, got '" + shape + "'",
           shape == "box" ? "a robot's contacts are points, spheres and disks on links: a box "
                            "link touches at its corners, one point contact each"
                          : "shape: sphere, radius: 0.05");
    for (const auto& kv : c) {
      const std::string key = kv.first.Scalar();
      if (key != "body" && std::find(kRobotContactKeys.begin(), kRobotContactKeys.end(), key) ==
                               kRobotContactKeys.end())
        fail(kv.first, "unknown key '" + key + "' in " + what,
             robot_contact_key_hint(key, kRobotContactKeys) + "the keys are " +
                 join(kRobotContactKeys));
    }
    if (constraints.count(name) || !names.insert(name).second)
      fail(nm, what + ": the name is taken by another constraint, loop or contact",
           "each contact names its own unilateral constraint");
    // a list of 3 numbers
    const auto vector3 = [&](const YAML::Node& v, const std::string& key, const char* hint) {
      if (!v.IsSequence() || v.size() != 3)
        fail(v, what + ": " + key + " must be a list of 3 numbers", hint);
      tree::Vector3d x;
      for (std::size_t i = 0; i < 3; ++i) x[Index(i)] = number(v[i], what + " " + key);
      return x;
    };
    // the point or sphere on its link
    if (c["body"])
      fail(c["body"], what + ": a robot's contact names its link, not a body",
           c["body"].IsScalar() ? "link: " + c["body"].Scalar() : link_hint);
    if (!c["link"]) fail(c, what + " needs link: the link its point is fixed on", link_hint);
    tree::LinkPoint at{link_of(c["link"], what), tree::Vector3d::Zero()};
    if (at.link < 0)
      fail(c["link"], what + ": the contact's point must be on a link, not the world",
           link_hint + " (the plane may be on the world: plane: {body: ground})");
    if (const YAML::Node p = c["point"])
      at.p = vector3(p, "point", "[x, y, z] in the link's frame");
    tree::Vector3d axis = tree::Vector3d::UnitZ();
    if (const YAML::Node a = c["axis"]) {
      if (shape != "disk")
        fail(a, what + ": axis is for disks only", "a sphere or a point has no axis");
      axis = vector3(a, "axis", "[0, 0, 1]: the normal of the disk's face in the link's frame");
      if (!(axis.norm() > 1e-12))
        fail(a, what + ": the disk's axis is zero", "axis: [0, 0, 1] in the link's frame");
    }
    double radius = 0.0;
    if (shape == "point" && c["radius"])
      fail(c["radius"], what + ": a point has no radius", "shape: sphere, radius: 0.05");
    if (shape != "point") {
      if (!c["radius"]) fail(c, what + ": a " + shape + " needs radius:", "radius: 0.05");
      radius = number(c["radius"], what + " radius");
      if (!(radius > 0.0) || !std::isfinite(radius))
        fail(c["radius"], what + ": radius must be > 0, got " + format_number(radius, 3),
             "radius: 0.05");
    }
    // the plane: the world's z = 0 by default
    tree::LinkFrame plane;
    tree::Vector3d normal = tree::Vector3d::UnitZ();
    if (const YAML::Node pl = c["plane"]) {
      if (!pl.IsMap())
        fail(pl, what + ": plane must be a mapping",
             "plane: {body: ground, point: [0, 0, 0], normal: [0, 0, 1]}");
      for (const auto& kv : pl) {
        const std::string key = kv.first.Scalar();
        if (std::find(kRobotPlaneKeys.begin(), kRobotPlaneKeys.end(), key) == kRobotPlaneKeys.end())
          fail(kv.first, "unknown key '" + key + "' in the plane of " + what,
               robot_contact_key_hint(key, kRobotPlaneKeys) + "the keys are " +
                   join(kRobotPlaneKeys));
      }
      if (pl["link"] && pl["body"])
        fail(pl["body"], what + ": the plane names link: or body:, not both", "link: base");
      if (const YAML::Node b = pl["body"]) {
        if (b.Scalar() != "ground" && b.Scalar() != "world")
          fail(b,
               what + ": a robot's plane is on the ground or on a link, got body '" + b.Scalar() +
                   "'",
               "body: ground, or link: <a link of the URDF>");
      }
      if (const YAML::Node l = pl["link"]) plane.link = link_of(l, what + "'s plane");
      if (const YAML::Node p = pl["point"])
        plane.p = vector3(p, "point", "[x, y, z] of the plane, in its link's frame");
      if (const YAML::Node n = pl["normal"]) {
        normal = vector3(n, "normal", "[0, 0, 1]: the side the contact stays on");
        if (!(normal.norm() > 1e-12))
          fail(n, what + ": the plane's normal is zero",
               "normal: [0, 0, 1], the side the contact stays on");
      }
    }
    if (plane.link >= 0 && plane.link == at.link)
      fail(c["plane"], what + ": the plane is on the contact's own link (the gap never changes)",
           "put the plane on another link or the world");
    if (welded(at.link) && welded(plane.link))
      fail(c["link"],
           what + ": link '" + robot.link(at.link).name + "' and the plane are both welded to " +
               "the world (only fixed joints between them and it): the gap never changes",
           "put the contact on a link that moves, or the plane on one");
    // the plane's frame: z along the normal
    plane.R = mb::Frame::with_z(plane.p, normal).R;
    // Newton's e and the law
    const auto [e, law] = read_restitution(c["restitution"], c["restitution_law"], what);
    try {
      Constraint k = shape == "disk"
                         ? tree::disk_contact_constraint(robot, name, {at.link, at.p, axis, radius},
                                                         plane, initial_q(), e)
                         : tree::contact_constraint(robot, name, at, radius, plane, e);
      // (Coulomb friction there slides the contact point: read_nonideal)
      if (shape == "disk") {
        point_contacts_[name] = [robot_copy = robot, name, at, axis, radius, plane]() {
          return tree::disk_contact_kinematics(robot_copy, name, {at.link, at.p, axis, radius},
                                               plane);
        };
      } else {
        point_contacts_[name] = [robot_copy = robot, name, at, radius, plane]() {
          return tree::contact_kinematics(robot_copy, name, at, radius, plane);
        };
      }
      if (law != RestitutionLaw::kNewton) k = with_restitution_law(k, law);
      builder.add(std::move(k));
      constraint_names_.push_back(name);
      // the viewer draws it (modelfile/visual_contacts.cpp)
      if (!shared) shared = std::make_shared<const tree::Tree>(robot);
      drawn.push_back(detail::robot_visual_contact(
          name, shared, at, shape == "disk" ? &axis : nullptr, radius, plane));
    } catch (const std::invalid_argument& err) {
      std::string m = err.what();
      if (const auto k = m.find(": "); k != std::string::npos) m.erase(0, k + 2);
      fail(c, m);
    }
  }
}

}  // namespace ukdyn::model_reader
// SPDX-License-Identifier: BSD-3-Clause
// The contacts: section of a multibody model (docs/model-format.md, "Contacts"; docs/contact.md,
// "Contacts on bodies"): each entry is one unilateral gap of a point, sphere or disk of a body
// with a plane fixed on the ground or on another body, added as mb::contact / mb::contact_disk.
// Every error names the contact and the key (file:line:column) and gives a hint.
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "ukdyn/core/format.hpp"
#include "ukdyn/multibody/multibody.hpp"

#include "modelfile/reader_multibody.hpp"

namespace ukdyn::model_reader {

void MultibodyReader::read_contacts() {
  const YAML::Node cs = root_["contacts"];
  if (!cs) return;
  const std::string example = "- {name: floor, body: ball, shape: sphere, radius: 0.1}";
  if (!cs.IsSequence()) r_.fail(cs, "contacts must be a list", example);
  const bool planar_model = bodies_.front().kind == BodyKind::kPlanar;
  const int dims = planar_model ? 2 : 3;
  for (const auto& c : cs) {
    check_map(c, "a contact", "{name: floor, body: ball, shape: sphere, radius: 0.1}");
    const YAML::Node nn = require(c, "name", "a contact", "name: floor");
    const std::string name = name_of(c, "a contact", "");
    const std::string what = "contact '" + name + "'";
    // unique among the constraints: the joints' names and the other contacts'
    for (const auto& j : joints_) {
      if (j.name == name)
        r_.fail(nn, what + ": a joint has this name",
                "a contact names its constraint: choose a name no joint or contact has");
    }
    for (const auto& o : contacts_) {
      if (o.name == name)
        r_.fail(nn, what + " is declared twice",
                "a contact names its constraint: make the names unique");
    }
    check_keys(c,
               {"name", "body", "point", "shape", "radius", "axis", "plane", "restitution",
                "restitution_law"},
               what);
    // the body, its point and its shape
    const YAML::Node bn = require(c, "body", what, "body: ball");
    const BodyId b = body(bn, what + " body");
    if (b == kGround)
      r_.fail(bn, what + ": the ground cannot touch a plane", "body: the name of a moving body");
    const BodyKind kind = bodies_[std::size_t(b)].kind;
    const Vector3d p = c["point"] ? vec(c["point"], what + " point", dims, dims) : Vector3d::Zero();
    std::string shape = "point";
    if (const YAML::Node sn = c["shape"]) {
      shape = sn.IsScalar() ? sn.Scalar() : std::string();
      if (shape != "point" && shape != "sphere" && shape != "disk")
        r_.fail(sn, what + ": unknown shape '" + shape + "'", "point, sphere or disk");
    }
    double radius = 0.0;
    const YAML::Node rn = c["radius"];
    if (shape == "point" && rn)
      r_.fail(rn, what + ": a point has no radius",
              "shape: sphere (or disk) with radius:, or leave radius out");
    if (shape != "point")
      radius = positive(require(c, "radius", what + " (a " + shape + ")", "radius: 0.1"),
                        what + " radius");
    const YAML::Node an = c["axis"];
    if (an && shape != "disk")
      r_.fail(an, what + ": axis is for a disk, not a " + shape, "shape: disk, axis: [0, 0, 1]");
    if (an && planar_model)
      r_.fail(an, what + ": a disk in a planar model is a circle in the plane: it has no axis",
              "leave axis out");
    const bool disk = shape == "disk" && !planar_model;
    if (disk && kind == BodyKind::kParticle)
      r_.fail(c["shape"], what + ": a particle has no orientation, so it cannot carry a disk",
              "declare the body with type: rigid, or use shape: sphere");
    Frame disk_frame = Frame::at(p);
    if (disk && an) {
      const Vector3d a = vec(an, what + " axis", 3, 3);
      if (!(a.norm() > 0.0)) r_.fail(an, what + ": the axis is zero", "axis: [0, 0, 1]");
      disk_frame = Frame::with_z(p, a);
    }
    // the plane: a point and a normal on a body (default the ground through the origin)
    BodyId plane_body = kGround;
    Vector3d o = Vector3d::Zero(), n = planar_model ? Vector3d::UnitY() : Vector3d::UnitZ();
    if (const YAML::Node pl = c["plane"]) {
      const std::string pw = what + " plane";
      check_map(pl, pw, "{body: ground, point: [0, 0, 0], normal: [0, 0, 1]}");
      check_keys(pl, {"body", "point", "normal"}, pw);
      if (pl["body"]) plane_body = body(pl["body"], pw + " body");
      if (plane_body == b)
        r_.fail(pl["body"], pw + ": the plane is on the contact's own body",
                "a plane of another body, or of the ground");
      if (pl["point"]) o = vec(pl["point"], pw + " point", dims, dims);
      if (const YAML::Node nv = pl["normal"]) {
        n = vec(nv, pw + " normal", dims, dims);
        if (!(n.norm() > 0.0))
          r_.fail(nv, pw + ": the normal is zero",
                  planar_model ? "normal: [0, 1]" : "normal: [0, 0, 1]");
      }
    }
    if (plane_body != kGround && planar(plane_body) != planar(b))
      r_.fail(c["plane"]["body"], what +
                                      ": the plane's body and the contact's body are not both "
                                      "planar or both spatial");
    // plane frame: normal = its z axis (spatial) or y axis (planar: x axis = (n_y, −n_x))
    const Frame plane =
        planar_model ? Frame::planar(o.x(), o.y(), std::atan2(-n.x(), n.y())) : Frame::with_z(o, n);
    // restitution and its law
    double e = 0.0;
    if (const YAML::Node en = c["restitution"]) {
      e = r_.number(en, what + " restitution");
      if (!(e >= 0.0 && e <= 1.0))
        r_.fail(en, what + ": the restitution must lie in [0, 1], got " + brief(e),
                "restitution: 0.5");
    }
    RestitutionLaw law = RestitutionLaw::kNewton;
    if (const YAML::Node ln = c["restitution_law"]) {
      const std::string l = ln.IsScalar() ? ln.Scalar() : std::string();
      if (l == "poisson")
        law = RestitutionLaw::kPoisson;
      else if (l != "newton")
        r_.fail(ln, what + ": the restitution_law must be newton or poisson, got '" + l + "'",
                "restitution_law: poisson   (Poisson's: the restitution impulse is e times the "
                "compression's)");
    }
    mb::Joint j = disk ? mb::contact_disk(name, plane_body, plane, b, disk_frame, radius, e)
                       : mb::contact(name, plane_body, plane, b, p, radius, e);
    j.restitution_law = law;
    builder_.add_joint(std::move(j));
    contacts_.push_back(
        {name, disk ? mb::JointType::kContactDisk : mb::JointType::kContact, c, radius});
    r_.positions_.constraints[name] = Reader::position(c);
  }
}

}  // namespace ukdyn::model_reader

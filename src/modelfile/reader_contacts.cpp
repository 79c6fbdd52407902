// SPDX-License-Identifier: BSD-3-Clause
// The contacts: section of a multibody model (docs/model-format.md, "Contacts"; docs/contact.md,
// "Contacts on bodies"): each entry is one unilateral gap of a point, sphere or disk of a body
// with a plane fixed on the ground or on another body, added as mb::contact / mb::contact_disk,
// or of a point or sphere outside a sphere of another body or of the ground (mb::contact_spheres).
// Every error names the contact and the key (file:line:column) and gives a hint.
#include <algorithm>
#include <cmath>
#include <optional>
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
               {"name", "body", "point", "shape", "radius", "axis", "plane", "sphere",
                "restitution", "restitution_law"},
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
    // the other surface: a sphere of another body (or of the ground), or a plane
    const YAML::Node sp = c["sphere"];
    if (sp && c["plane"])
      r_.fail(sp, what + ": a contact is with a plane or with a sphere, not both",
              "leave out plane: or sphere:");
    if (sp && disk)
      r_.fail(sp, what + ": a disk against a sphere is not supported",
              "shape: sphere (or point) for a contact with a sphere");
    BodyId other = kGround;
    Vector3d o_sphere = Vector3d::Zero();
    double other_radius = 0.0;
    if (sp) {
      const std::string sw = what + " sphere";
      check_map(sp, sw, "{body: ball2, point: [0, 0, 0], radius: 0.1}");
      check_keys(sp, {"body", "point", "radius"}, sw);
      if (sp["body"]) other = body(sp["body"], sw + " body");
      if (other == b)
        r_.fail(sp["body"], sw + ": the sphere is on the contact's own body",
                "a sphere of another body, or of the ground");
      if (other != kGround && planar(other) != planar(b))
        r_.fail(sp["body"], what +
                                ": the sphere's body and the contact's body are not both "
                                "planar or both spatial");
      if (sp["point"]) o_sphere = vec(sp["point"], sw + " point", dims, dims);
      other_radius = positive(require(sp, "radius", sw, "radius: 0.1"), sw + " radius");
    }
    // or the plane: a point and a normal on a body (default the ground through the origin)
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
    mb::Joint j = sp     ? mb::contact_spheres(name, other, o_sphere, other_radius, b, p, radius, e)
                  : disk ? mb::contact_disk(name, plane_body, plane, b, disk_frame, radius, e)
                         : mb::contact(name, plane_body, plane, b, p, radius, e);
    j.restitution_law = law;
    contacts_.push_back({name, j.type, c, radius});
    builder_.add_joint(std::move(j));
    r_.positions_.constraints[name] = Reader::position(c);
  }
}

// nonideal: of a bodies model — Coulomb friction at its contacts (docs/contact.md, "Friction at a
// body's contact"): each entry {friction: coulomb, constraint: <contact>, mu, mu_static,
// regularization_velocity} slides the contact point (mb::Multibody::add_contact_friction). What
// is not supported is refused where it is written: coordinates: (the contact point is the
// sliding velocity), surface_velocity:, viscous or given C. A plane of a moving body, a disk's
// rim point and two spheres take friction too: the sliding velocity is then the relative
// velocity of the two material points at the contact point.
void MultibodyReader::read_contact_frictions() {
  const YAML::Node ns = root_["nonideal"];
  if (!ns) return;
  const std::string example = "- {friction: coulomb, constraint: floor, mu: 0.3}";
  if (!ns.IsSequence()) r_.fail(ns, "nonideal must be a list", example);
  std::set<std::string> seen;
  for (const auto& f : ns) {
    check_map(f, "a non-ideal force", example);
    if (f["coordinates"])
      r_.fail(f["coordinates"],
              "a bodies model's contact friction slides the contact point itself: it takes no "
              "coordinates",
              "leave coordinates out: the sliding velocity is the velocity of the body's point "
              "at the contact, tangent to the plane (docs/contact.md)");
    if (f["surface_velocity"])
      r_.fail(f["surface_velocity"],
              "a surface velocity under a body's contact is not supported yet",
              "leave surface_velocity out (a moving surface: put the plane on a driven body, "
              "plane: {body: <it>}; docs/contact.md)");
    const YAML::Node law = require(f, "friction", "a non-ideal force", "friction: coulomb");
    if (!law.IsScalar() || law.Scalar() != "coulomb")
      r_.fail(law,
              "a bodies model's nonideal: takes Coulomb friction at its contacts only, not '" +
                  (law.IsScalar() ? law.Scalar() : std::string("?")) + "'",
              "friction: coulomb, constraint: <a contact>; a joint's friction goes under the "
              "joint (friction: {mu: ..}), a damper under forces:");
    check_keys(f, {"friction", "constraint", "mu", "mu_static", "regularization_velocity"},
               "a contact's friction");
    const YAML::Node cn = require(f, "constraint", "a contact's friction", "constraint: floor");
    const std::string name = cn.IsScalar() ? cn.Scalar() : std::string();
    const auto c = std::find_if(contacts_.begin(), contacts_.end(),
                                [&](const JointDecl& d) { return d.name == name; });
    if (c == contacts_.end())
      r_.fail(cn, "Coulomb friction on '" + name + "', which is no contact",
              "constraint: the name of an entry of contacts:");
    const std::string what = "the friction at contact '" + name + "'";
    if (!seen.insert(name).second)
      r_.fail(cn, what + " is declared twice", "one coulomb friction per contact");
    const double mu = r_.friction_coefficient(require(f, "mu", what, "mu: 0.3"), what + " mu");
    std::optional<double> mu_static;
    if (const YAML::Node ms = f["mu_static"]) {
      mu_static = r_.friction_coefficient(ms, what + " mu_static");
      if (!(*mu_static >= mu))
        r_.fail(ms,
                what + ": mu_static must be >= mu = " + brief(mu) + ", got " + brief(*mu_static),
                "the static coefficient is at least the kinetic one");
    }
    double eps = 1e-9;
    if (const YAML::Node en = f["regularization_velocity"])
      eps = positive(en, what + " regularization_velocity");
    builder_.add_contact_friction(name, mu, mu_static, eps);
  }
}

}  // namespace ukdyn::model_reader

// SPDX-License-Identifier: BSD-3-Clause
// The contacts: section of a multibody model (docs/model-format.md, "Contacts"; docs/contact.md,
// "Contacts on bodies"): each entry is one unilateral gap of a point, sphere or disk of a body
// with a plane fixed on the ground or on another body, added as mb::contact / mb::contact_disk,
// or of a point or sphere outside (or, inside: true, inside) a sphere of another body or of the
// ground (mb::contact_spheres), or of a disk outside such a sphere (mb::contact_disk_sphere), or
// of a point or sphere outside a box of another body or of the ground (mb::contact_sphere_box).
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
    // unique among the constraints: the joints' names and the other contacts' (and the boxes':
    // a box's corners are <name>.<k>, which no identifier is, and its friction names the box)
    for (const auto& j : joints_) {
      if (j.name == name)
        r_.fail(nn, what + ": a joint has this name",
                "a contact names its constraint: choose a name no joint or contact has");
    }
    for (const auto& o : contacts_) {
      if (o.name == name || o.box == name)
        r_.fail(nn, what + " is declared twice",
                "a contact names its constraint: make the names unique");
    }
    check_keys(c,
               {"name", "body", "point", "shape", "radius", "size", "axis", "plane", "sphere",
                "box", "restitution", "restitution_law"},
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
      if (shape != "point" && shape != "sphere" && shape != "disk" && shape != "box")
        r_.fail(sn, what + ": unknown shape '" + shape + "'", "point, sphere, disk or box");
    }
    double radius = 0.0;
    const YAML::Node rn = c["radius"];
    if ((shape == "point" || shape == "box") && rn)
      r_.fail(rn, what + ": a " + shape + " has no radius",
              shape == "box" ? "a box has size: [hx, hy, hz], its half-extents"
                             : "shape: sphere (or disk) with radius:, or leave radius out");
    const std::vector<Vector3d> corners = box_corners(c, what, shape, p, kind, dims);
    if (shape != "point" && shape != "box")
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
    // the other surface: a sphere or a box of another body (or of the ground), or a plane
    const YAML::Node bx = c["box"];
    if (bx && (c["plane"] || c["sphere"]))
      r_.fail(bx, what + ": a contact is with a plane, a sphere or a box, not several",
              "keep one of plane:, sphere: and box:");
    if (bx && shape != "point" && shape != "sphere")
      r_.fail(bx, what + ": a " + shape + " against a box is not supported",
              "shape: sphere (or point) for a contact with a box");
    BodyId box_body = kGround;
    Frame box_frame;
    Vector3d box_half = Vector3d::Zero();
    if (bx) {
      const std::string bw = what + " box";
      check_map(bx, bw, "{body: crate, point: [0, 0, 0], size: [0.2, 0.1, 0.05]}");
      check_keys(bx, {"body", "point", "size", "orientation"}, bw);
      if (bx["body"]) box_body = body(bx["body"], bw + " body");
      if (box_body == b)
        r_.fail(bx["body"], bw + ": the box is on the contact's own body",
                "a box of another body, or of the ground");
      if (box_body != kGround && planar(box_body) != planar(b))
        r_.fail(bx["body"], what +
                                ": the box's body and the contact's body are not both planar or "
                                "both spatial");
      const Vector3d centre =
          bx["point"] ? vec(bx["point"], bw + " point", dims, dims) : Vector3d::Zero();
      const YAML::Node hn =
          require(bx, "size", bw, planar_model ? "size: [0.2, 0.1]" : "size: [0.2, 0.1, 0.05]");
      box_half = vec(hn, bw + " size", dims, dims);
      for (int i = 0; i < dims; ++i) {
        if (!(box_half[i] > 0.0))
          r_.fail(hn, bw + ": the half-extents must be > 0, got " + brief(box_half[i]),
                  "size: the box's half-extents along its axes");
      }
      if (const YAML::Node on = bx["orientation"]) {
        if (planar_model) {
          box_frame = Frame::planar(centre.x(), centre.y(), r_.number(on, bw + " orientation"));
        } else {
          box_frame = Frame::at(centre);
          box_frame.R = orientation(on, bw + " orientation").toRotationMatrix();
        }
      } else {
        box_frame = Frame::at(centre);
      }
    }
    // the other surface: a sphere of another body (or of the ground), or a plane
    const YAML::Node sp = c["sphere"];
    if (sp && c["plane"])
      r_.fail(sp, what + ": a contact is with a plane or with a sphere, not both",
              "leave out plane: or sphere:");
    if (sp && shape == "box")
      r_.fail(sp, what + ": a box against a sphere is not supported",
              "shape: sphere (or point, or disk) for a contact with a sphere");
    BodyId other = kGround;
    Vector3d o_sphere = Vector3d::Zero();
    double other_radius = 0.0;
    mb::SphereSide side = mb::SphereSide::kOutside;
    if (sp) {
      const std::string sw = what + " sphere";
      check_map(sp, sw, "{body: ball2, point: [0, 0, 0], radius: 0.1}");
      check_keys(sp, {"body", "point", "radius", "inside"}, sw);
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
      if (const YAML::Node in = sp["inside"]) {
        // inside: true keeps the contact's point or sphere inside this one (a ball in a bowl)
        const std::string t = in.IsScalar() && in.Tag() != "!" ? in.Scalar() : std::string();
        if (t != "true" && t != "false")
          r_.fail(in, sw + ": inside must be true or false", "inside: true   (unquoted)");
        if (t == "true" && disk)
          r_.fail(in, what + ": a disk inside a sphere is not supported",
                  "shape: sphere (a ball in a bowl), or leave inside out for a disk outside the "
                  "sphere");
        if (t == "true") side = mb::SphereSide::kInside;
        if (t == "true" && !(radius < other_radius))
          r_.fail(sp["radius"],
                  what + ": a " + shape + " of radius " + brief(radius) +
                      " does not fit inside a sphere of radius " + brief(other_radius),
                  "inside: true needs the sphere's radius larger than the contact's");
      }
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
    if (!corners.empty()) {
      // a box: one point contact per corner, <name>.<k>, each with the entry's restitution
      for (std::size_t k = 0; k < corners.size(); ++k) {
        const std::string corner = name + "." + std::to_string(k);
        mb::Joint j = mb::contact(corner, plane_body, plane, b, corners[k], 0.0, e);
        j.restitution_law = law;
        contacts_.push_back({corner, j.type, c, 0.0, name});
        builder_.add_joint(std::move(j));
        r_.positions_.constraints[corner] = Reader::position(c);
      }
      continue;
    }
    mb::Joint j =
        bx ? mb::contact_sphere_box(name, box_body, box_frame, box_half, b, p, radius, e)
        : sp && disk
            ? mb::contact_disk_sphere(name, other, o_sphere, other_radius, b, disk_frame, radius, e)
        : sp   ? mb::contact_spheres(name, other, o_sphere, other_radius, b, p, radius, e, side)
        : disk ? mb::contact_disk(name, plane_body, plane, b, disk_frame, radius, e)
               : mb::contact(name, plane_body, plane, b, p, radius, e);
    j.restitution_law = law;
    contacts_.push_back({name, j.type, c, radius});
    builder_.add_joint(std::move(j));
    r_.positions_.constraints[name] = Reader::position(c);
  }
}

// shape: box, size: [hx, hy, hz] (planar [hx, hy]): its half-extents along the body's axes,
// centred at the contact's point p; its corners p + (±hx, ±hy, ±hz), corner k taking + on x if
// bit 0 of k is set, on y if bit 1, on z if bit 2 (planar: 4 corners, bits 0 and 1). None for
// another shape, which may not give size:.
std::vector<Vector3d> MultibodyReader::box_corners(const YAML::Node& c, const std::string& what,
                                                   const std::string& shape, const Vector3d& p,
                                                   BodyKind kind, int dims) {
  const YAML::Node sz = c["size"];
  if (shape != "box") {
    if (sz)
      r_.fail(sz, what + ": size is for a box, not a " + shape,
              "shape: box, size: [hx, hy, hz] (half-extents), or leave size out");
    return {};
  }
  if (kind == BodyKind::kParticle)
    r_.fail(c["shape"], what + ": a particle has no orientation, so it cannot carry a box",
            "declare the body with type: rigid, or use shape: point");
  const YAML::Node req = require(c, "size", what + " (a box)",
                                 dims == 2 ? "size: [0.2, 0.1]" : "size: [0.2, 0.1, 0.05]");
  const Vector3d half = vec(req, what + " size", dims, dims);
  for (int i = 0; i < dims; ++i) {
    if (!(half[i] > 0.0))
      r_.fail(req[std::size_t(i)],
              what + ": the box's half-extents must be > 0, got " + brief(half[i]),
              dims == 2 ? "size: [hx, hy]" : "size: [hx, hy, hz]");
  }
  std::vector<Vector3d> corners;
  for (int k = 0; k < (1 << dims); ++k) {
    Vector3d s = Vector3d::Zero();
    for (int i = 0; i < dims; ++i) s[i] = (k >> i) & 1 ? half[i] : -half[i];
    corners.push_back(p + s);
  }
  return corners;
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
    // the contact, or every corner of the box of that name
    std::vector<std::string> targets;
    for (const JointDecl& d : contacts_) {
      if (d.name == name || d.box == name) targets.push_back(d.name);
    }
    if (targets.empty())
      r_.fail(cn, "Coulomb friction on '" + name + "', which is no contact",
              "constraint: the name of an entry of contacts:");
    const std::string what = "the friction at contact '" + name + "'";
    for (const std::string& t : targets) {
      if (!seen.insert(t).second)
        r_.fail(cn, what + " is declared twice" + (t == name ? "" : " (at '" + t + "')"),
                "one coulomb friction per contact (one on a box gives each of its corners one)");
    }
    const double mu = r_.friction_coefficient(require(f, "mu", what, "mu: 0.3"), what + ": mu");
    std::optional<double> mu_static;
    if (const YAML::Node ms = f["mu_static"]) {
      mu_static = r_.friction_coefficient(ms, what + ": mu_static");
      if (!(*mu_static >= mu))
        r_.fail(ms,
                what + ": mu_static must be >= mu = " + brief(mu) + ", got " + brief(*mu_static),
                "the static coefficient is at least the kinetic one");
    }
    double eps = r_.default_regularization_velocity(root_);
    if (const YAML::Node en = f["regularization_velocity"])
      eps = positive(en, what + " regularization_velocity");
    for (const std::string& t : targets) {
      builder_.add_contact_friction(t, mu, mu_static, eps);
      // (the entry a run's refusal of the contact points at, by its stick constraint's name:
      // "stick." and the friction's, coulomb.<contact> as coulomb_friction names it)
      r_.positions_.constraints["stick.coulomb." + t] = Reader::position(f);
    }
  }
}

}  // namespace ukdyn::model_reader

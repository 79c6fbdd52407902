// SPDX-License-Identifier: BSD-3-Clause
// Multibody model files: bodies:, joints: and forces: (docs/model-format.md, "Multibody
// models"). The sections are turned into calls of the multibody layer (multibody/multibody.hpp):
//   bodies:   add_particle / add_planar_body / add_rigid_body with their initial state
//   joints:   revolute, prismatic, …, gear, rolling_disk, rolling_sphere (+ drive, friction)
//   forces:   gravity, spring_damper, torsion_spring, applied
// Numbers are expressions of the parameters; a drive is an expression of t, differentiated
// twice symbolically; an applied force is an expression of the coordinates (<body>_x, …), their
// velocities and t, compiled once. Every error names file:line:column and gives a hint.
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "ukdyn/core/format.hpp"
#include "ukdyn/multibody/multibody.hpp"

#include "modelfile/reader_multibody.hpp"
#include "modelfile/visual_contacts.hpp"

namespace ukdyn::model_reader {

namespace {

// the keys of a generalized-coordinate model that a multibody model replaces
const std::vector<std::string> kGeneralizedKeys = {
    "coordinates", "kinetic_energy", "potential_energy", "mass_matrix", "constraints", "nonideal"};

// coordinate suffixes per body kind (System's "<body>.<suffix>", the file's "<body>_<suffix>")
std::vector<std::string> suffixes(BodyKind kind) {
  switch (kind) {
    case BodyKind::kParticle:
      return {"x", "y", "z"};
    case BodyKind::kPlanar:
      return {"x", "y", "theta"};
    case BodyKind::kRigid:
      return {"x", "y", "z", "u0", "u1", "u2", "u3"};
  }
  return {};
}

const char* kind_name(BodyKind kind) {
  switch (kind) {
    case BodyKind::kParticle:
      return "particle";
    case BodyKind::kPlanar:
      return "planar";
    case BodyKind::kRigid:
      return "rigid";
  }
  return "";
}

struct JointKind {
  const char* name;
  mb::JointType type;
};
const JointKind kJointKinds[] = {
    {"revolute", mb::JointType::kRevolute},
    {"prismatic", mb::JointType::kPrismatic},
    {"weld", mb::JointType::kWeld},
    {"distance", mb::JointType::kDistance},
    {"point_on_line", mb::JointType::kPointOnLine},
    {"spherical", mb::JointType::kSpherical},
    {"cylindrical", mb::JointType::kCylindrical},
    {"universal", mb::JointType::kUniversal},
    {"planar", mb::JointType::kPlanar},
    {"point_on_plane", mb::JointType::kPointOnPlane},
    {"gear", mb::JointType::kGear},
    {"rolling_disk", mb::JointType::kRollingDisk},
    {"rolling_sphere", mb::JointType::kRollingSphere},
};

std::string joint_kind_list() {
  std::vector<std::string> names;
  for (const auto& k : kJointKinds) names.emplace_back(k.name);
  return join(names);
}

}  // namespace

const YAML::Node& MultibodyReader::check_map(const YAML::Node& node, const std::string& what,
                                             const std::string& example) {
  if (!node.IsMap()) r_.fail(node, what + " must be a mapping", "e.g. " + example);
  return node;
}

void MultibodyReader::check_keys(const YAML::Node& map, const std::set<std::string>& keys,
                                 const std::string& what) {
  for (const auto& kv : map) {
    const std::string key = kv.first.Scalar();
    if (!keys.count(key)) {
      r_.fail(kv.first, "unknown key '" + key + "' in " + what,
              "the keys are " + join(std::vector<std::string>(keys.begin(), keys.end())));
    }
  }
}

YAML::Node MultibodyReader::require(const YAML::Node& map, const std::string& key,
                                    const std::string& what, const std::string& example) {
  const YAML::Node v = map[key];
  if (!v) r_.fail(map, what + " needs '" + key + "'", "e.g. " + example);
  return v;
}

std::string MultibodyReader::name_of(const YAML::Node& map, const std::string& what,
                                     const std::string& fallback) {
  const YAML::Node n = map["name"];
  if (!n) return fallback;
  if (!n.IsScalar() || !is_identifier(n.Scalar()))
    r_.fail(n,
            what + ": the name '" + (n.IsScalar() ? n.Scalar() : std::string()) +
                "' is not an identifier",
            "letters, digits and _, not starting with a digit");
  return n.Scalar();
}

double MultibodyReader::positive(const YAML::Node& node, const std::string& what) {
  const double v = r_.number(node, what);
  if (!(v > 0.0)) r_.fail(node, what + " must be > 0, got " + brief(v));
  return v;
}

double MultibodyReader::non_negative(const YAML::Node& node, const std::string& what) {
  const double v = r_.number(node, what);
  if (!(v >= 0.0)) r_.fail(node, what + " must be >= 0, got " + brief(v));
  return v;
}

// [x, y] (z = 0) or [x, y, z], each a number
Vector3d MultibodyReader::vec(const YAML::Node& node, const std::string& what, int min_entries,
                              int max_entries) {
  const std::string shape =
      min_entries == max_entries
          ? format_number(min_entries) + " numbers"
          : format_number(min_entries) + " or " + format_number(max_entries) + " numbers";
  if (!node.IsSequence() || int(node.size()) < min_entries || int(node.size()) > max_entries) {
    r_.fail(node, what + " must be a list of " + shape,
            max_entries == 2 ? "[x, y]: planar bodies move in the (x, y) plane" : "[x, y, z]");
  }
  Vector3d v = Vector3d::Zero();
  for (std::size_t i = 0; i < node.size(); ++i) v[Index(i)] = r_.number(node[i], what);
  return v;
}

// {axis: [x, y, z], angle: a} or {quaternion: [w, x, y, z]}
Eigen::Quaterniond MultibodyReader::orientation(const YAML::Node& node, const std::string& what) {
  const std::string example = "{axis: [0, 1, 0], angle: 0.5} or {quaternion: [1, 0, 0, 0]}";
  check_map(node, what, example);
  check_keys(node, {"axis", "angle", "quaternion"}, what);
  if (node["quaternion"]) {
    if (node["axis"] || node["angle"])
      r_.fail(node, what + ": give either quaternion or axis and angle, not both", example);
    const YAML::Node q = node["quaternion"];
    if (!q.IsSequence() || q.size() != 4)
      r_.fail(q, what + ": quaternion must be a list of 4 numbers [w, x, y, z]",
              "the scalar part first; it is normalized");
    Eigen::Quaterniond u(r_.number(q[0], what), r_.number(q[1], what), r_.number(q[2], what),
                         r_.number(q[3], what));
    if (!(u.norm() > 0.0)) r_.fail(q, what + ": the quaternion is zero");
    return u.normalized();
  }
  const YAML::Node axis = require(node, "axis", what, example);
  const Vector3d a = vec(axis, what + " axis", 3, 3);
  if (!(a.norm() > 0.0)) r_.fail(axis, what + ": the axis is zero");
  const double angle = node["angle"] ? r_.number(node["angle"], what + " angle") : 0.0;
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, a.normalized()));
}

// a body by name ("ground": the world)
BodyId MultibodyReader::body(const YAML::Node& node, const std::string& what) {
  if (!node.IsScalar()) r_.fail(node, what + " must be the name of a body or ground");
  const std::string& name = node.Scalar();
  if (name == "ground") return kGround;
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    if (bodies_[i].name == name) return BodyId(i);
  }
  std::vector<std::string> names;
  for (const auto& b : bodies_) names.push_back(b.name);
  r_.fail(node, what + ": unknown body '" + name + "'",
          names.empty()
              ? std::string("the only body is ground")
              : "the bodies are " + join(names) + (names.size() > 1 ? "," : "") + " and ground");
}

// the frame <side>_point with <side>_angle (planar) or <side>_axis | <side>_orientation
Frame MultibodyReader::frame(const YAML::Node& j, const std::string& side, bool planar_joint,
                             const std::string& what) {
  const Vector3d p = point(j, side + "_point", planar_joint, what);
  const YAML::Node angle = j[side + "_angle"], axis = j[side + "_axis"],
                   orient = j[side + "_orientation"];
  if (planar_joint) {
    if (axis || orient)
      r_.fail(axis ? axis : orient,
              what + " is planar: its frames turn about z by " + side + "_angle",
              side + "_angle: 0.5 (radians)");
    return Frame::planar(p.x(), p.y(),
                         angle ? r_.number(angle, what + " " + side + "_angle") : 0.0);
  }
  if (angle)
    r_.fail(angle,
            what + " is spatial: give " + side + "_axis (the frame's z axis) or " + side +
                "_orientation",
            "_angle is for joints between planar bodies");
  if (axis && orient)
    r_.fail(orient, what + ": give " + side + "_axis or " + side + "_orientation, not both");
  if (axis) {
    const Vector3d a = vec(axis, what + " " + side + "_axis", 3, 3);
    if (!(a.norm() > 0.0)) r_.fail(axis, what + ": " + side + "_axis is zero");
    return Frame::with_z(p, a);
  }
  Frame f = Frame::at(p);
  if (orient) f.R = orientation(orient, what + " " + side + "_orientation").toRotationMatrix();
  return f;
}

// a point of a joint's body: [x, y] on a planar joint, [x, y, z] otherwise; default the origin
Vector3d MultibodyReader::point(const YAML::Node& j, const std::string& key, bool planar_joint,
                                const std::string& what) {
  const YAML::Node p = j[key];
  if (!p) return Vector3d::Zero();
  return planar_joint ? vec(p, what + " " + key, 2, 2) : vec(p, what + " " + key, 3, 3);
}

// f(t) and its two derivatives, symbolic, as one program over the inputs
mb::MotionFn MultibodyReader::drive(const YAML::Node& node, const std::string& what) {
  ExpressionSet& set = *r_.set_;
  const Expr f = r_.expression(node, what + " drive");
  for (const Index k : set.inputs_of(f)) {
    const std::string& name = set.input_names()[std::size_t(k)];
    if (name != "t") {
      r_.fail(node, what + ": a drive is a function of time, but depends on '" + name + "'",
              "write the prescribed angle or slide with t and the parameters, e.g. 2*pi*t");
    }
  }
  r_.note_switches({f});
  const Expr fd = set.diff(f, "t"), fdd = set.diff(fd, "t");
  const Program p = r_.compile({f, fd, fdd}, node, what + " drive and its derivatives");
  const InputLayout layout = r_.layout_;
  // (its signature carries no scratch: buffers of the call, evaluate_local)
  return [p, layout](double t) {
    Vector3d value;
    evaluate_local(
        p, layout.size(), [&](double* in) { in[2 * layout.n] = t; },
        [&](const double* v) { value = Vector3d(v[0], v[1], v[2]); });
    return value;
  };
}

// force [fx, fy(, fz)] and torque (tz, or [tx, ty, tz]) as expressions of (q, q', t)
mb::WrenchFn MultibodyReader::wrench(const YAML::Node& f, bool planar_body,
                                     const std::string& what) {
  ExpressionSet& set = *r_.set_;
  std::vector<Expr> out(6, set.constant(0.0));
  if (const YAML::Node F = f["force"]) {
    const int dims = planar_body ? 2 : 3;
    if (!F.IsSequence() || int(F.size()) != dims)
      r_.fail(F, what + ": force must be a list of " + format_number(dims) + " expressions",
              planar_body ? "[Fx, Fy] on a planar body" : "[Fx, Fy, Fz]");
    for (int i = 0; i < dims; ++i) out[std::size_t(i)] = r_.expression(F[i], what + " force");
  }
  if (const YAML::Node T = f["torque"]) {
    if (planar_body) {
      if (!T.IsScalar())
        r_.fail(T, what + ": the torque on a planar body is one expression (about z)",
                "torque: 0.5*sin(t)");
      out[5] = r_.expression(T, what + " torque");
    } else {
      if (!T.IsSequence() || T.size() != 3)
        r_.fail(T, what + ": torque must be a list of 3 expressions", "[Tx, Ty, Tz]");
      for (int i = 0; i < 3; ++i) out[3 + std::size_t(i)] = r_.expression(T[i], what + " torque");
    }
  }
  r_.note_switches(out);
  const Program p = r_.compile(out, f, what);
  const InputLayout layout = r_.layout_;
  // (its signature carries no scratch: buffers of the call, evaluate_local)
  return [p, layout](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                     double t) {
    mb::Wrench w;
    evaluate_local(
        p, layout.size(), [&](double* in) { layout.fill(in, q, qd, t); },
        [&](const double* v) {
          w.force = Vector3d(v[0], v[1], v[2]);
          w.torque = Vector3d(v[3], v[4], v[5]);
        });
    return w;
  };
}

mb::JointFriction MultibodyReader::friction(const YAML::Node& node, const std::string& what) {
  const std::string example = "{mu: 0.1, radius: 0.01, viscous: 0.05}";
  check_map(node, what + " friction", example);
  check_keys(node, {"mu", "radius", "viscous", "regularization"}, what + " friction");
  mb::JointFriction fr;
  if (node["mu"]) fr.mu = r_.friction_coefficient(node["mu"], what + " friction mu");
  if (node["radius"]) fr.radius = non_negative(node["radius"], what + " friction radius");
  if (node["viscous"]) fr.viscous = non_negative(node["viscous"], what + " friction viscous");
  if (node["regularization"])
    fr.regularization = positive(node["regularization"], what + " friction regularization");
  return fr;
}

// ---------------------------------------------------------------------------------------------

void MultibodyReader::refuse_generalized_keys() {
  for (const auto& kv : root_) {
    const std::string key = kv.first.Scalar();
    if (std::find(kGeneralizedKeys.begin(), kGeneralizedKeys.end(), key) !=
        kGeneralizedKeys.end()) {
      // (nonideal: with the contacts' Coulomb friction: read_contact_frictions)
      if (key == "nonideal" && root_["contacts"]) continue;
      r_.fail(kv.first, "'" + key + "' does not go with 'bodies:'",
              "a multibody model's coordinates, mass matrix and constraints come from its "
              "bodies and joints; write the model either with bodies: or with coordinates:");
    }
  }
}

// names and kinds of the bodies → the coordinates <body>_x, … and their velocities
void MultibodyReader::declare_bodies() {
  const YAML::Node bs = root_["bodies"];
  if (!bs.IsSequence() || bs.size() == 0)
    r_.fail(bs, "bodies must be a non-empty list",
            "- {name: link, type: planar, mass: 1, inertia: 0.1, position: [0, 0]}");
  std::set<std::string> coordinates;
  for (const auto& b : bs) {
    check_map(b, "a body", "{name: link, type: planar, mass: 1, inertia: 0.1}");
    const YAML::Node n = require(b, "name", "a body", "{name: link, type: planar, ...}");
    const std::string& name = n.Scalar();
    if (!n.IsScalar() || !is_identifier(name))
      r_.fail(n, "body name '" + name + "' is not an identifier",
              "letters, digits and _: it names the coordinates " + name + "_x, …");
    if (name == "ground") r_.fail(n, "'ground' is the world, not a body", "choose another name");
    for (const auto& other : bodies_) {
      if (other.name == name) r_.fail(n, "body '" + name + "' is declared twice");
    }
    const YAML::Node t = require(b, "type", "body '" + name + "'", "type: planar");
    BodyKind kind = BodyKind::kParticle;
    if (t.Scalar() == "particle")
      kind = BodyKind::kParticle;
    else if (t.Scalar() == "planar")
      kind = BodyKind::kPlanar;
    else if (t.Scalar() == "rigid")
      kind = BodyKind::kRigid;
    else
      r_.fail(t, "body '" + name + "': unknown type '" + t.Scalar() + "'",
              "particle, planar or rigid");
    if (!bodies_.empty() &&
        (kind == BodyKind::kPlanar) != (bodies_.front().kind == BodyKind::kPlanar)) {
      r_.fail(t,
              "body '" + name + "' is " + kind_name(kind) + " but '" + bodies_.front().name +
                  "' is " + kind_name(bodies_.front().kind),
              "a model is planar (planar bodies only) or spatial (rigid bodies and particles)");
    }
    bodies_.push_back({name, kind, b});
    for (const auto& s : suffixes(kind)) {
      const std::string c = name + "_" + s;
      if (c == "t" || r_.parameters_.count(c))
        r_.fail(n, "body '" + name + "': its coordinate '" + c + "' is also a parameter",
                "rename the body or the parameter");
      r_.coordinates_.push_back(c);
      r_.velocities_.push_back(c + "_dot");
      r_.chain_.emplace_back(c, c + "_dot");
    }
  }
}

void MultibodyReader::read_bodies() {
  for (const BodyDecl& d : bodies_) {
    const YAML::Node& b = d.node;
    const std::string what = "body '" + d.name + "'";
    switch (d.kind) {
      case BodyKind::kParticle: {
        check_keys(b, {"name", "type", "mass", "position", "velocity", "visual"},
                   "particle '" + d.name + "'");
        const double m = positive(require(b, "mass", what, "mass: 1"), what + " mass");
        const Vector3d p =
            b["position"] ? vec(b["position"], what + " position", 3, 3) : Vector3d::Zero();
        const Vector3d v =
            b["velocity"] ? vec(b["velocity"], what + " velocity", 3, 3) : Vector3d::Zero();
        builder_.add_particle(d.name, m, p, v);
        break;
      }
      case BodyKind::kPlanar: {
        check_keys(b,
                   {"name", "type", "mass", "inertia", "position", "angle", "velocity",
                    "angular_velocity", "visual"},
                   "planar body '" + d.name + "'");
        const double m = positive(require(b, "mass", what, "mass: 1"), what + " mass");
        const double I = positive(require(b, "inertia", what, "inertia: m*L^2/12"),
                                  what + " inertia (about the centre of mass)");
        const Vector3d p =
            b["position"] ? vec(b["position"], what + " position", 2, 2) : Vector3d::Zero();
        const Vector3d v =
            b["velocity"] ? vec(b["velocity"], what + " velocity", 2, 2) : Vector3d::Zero();
        const double angle = b["angle"] ? r_.number(b["angle"], what + " angle") : 0.0;
        const double w = b["angular_velocity"]
                             ? r_.number(b["angular_velocity"], what + " angular_velocity")
                             : 0.0;
        builder_.add_planar_body(d.name, m, I, Vector3d(p.x(), p.y(), angle),
                                 Vector3d(v.x(), v.y(), w));
        break;
      }
      case BodyKind::kRigid: {
        if (b["J0"]) {
          r_.fail(b["J0"],
                  what +
                      ": J0 (a fictitious inertia of the quaternion) is no longer "
                      "needed: the singular quaternion mass matrix is used with the unit-norm "
                      "constraint",
                  "remove the J0 line");
        }
        check_keys(b,
                   {"name", "type", "mass", "inertia", "position", "orientation", "velocity",
                    "angular_velocity", "visual"},
                   "rigid body '" + d.name + "'");
        const double m = positive(require(b, "mass", what, "mass: 1"), what + " mass");
        const YAML::Node In = require(b, "inertia", what, "inertia: [A, A, C]");
        Vector3d J;
        if (In.IsScalar()) {
          J.setConstant(r_.number(In, what + " inertia"));
        } else {
          J = vec(In, what + " inertia", 3, 3);
        }
        for (int i = 0; i < 3; ++i) {
          if (!(J[i] > 0.0))
            r_.fail(In, what + ": every principal inertia must be > 0, got " + brief(J[i]),
                    "[J1, J2, J3] about the centre of mass, along the body axes");
        }
        const double slack = 1e-12 * J.sum();  // a thin disk has J1 + J2 = J3 exactly
        if (!(J[0] + J[1] + slack >= J[2] && J[1] + J[2] + slack >= J[0] &&
              J[0] + J[2] + slack >= J[1])) {
          r_.fail(In, what + ": the principal inertias violate the triangle inequality",
                  "no mass distribution has J1 + J2 < J3");
        }
        const Vector3d p =
            b["position"] ? vec(b["position"], what + " position", 3, 3) : Vector3d::Zero();
        const Vector3d v =
            b["velocity"] ? vec(b["velocity"], what + " velocity", 3, 3) : Vector3d::Zero();
        const Vector3d w = b["angular_velocity"]
                               ? vec(b["angular_velocity"], what + " angular_velocity", 3, 3)
                               : Vector3d::Zero();
        const Eigen::Quaterniond u = b["orientation"]
                                         ? orientation(b["orientation"], what + " orientation")
                                         : Eigen::Quaterniond::Identity();
        builder_.add_rigid_body(d.name, m, J, p, u, v, w);
        break;
      }
    }
  }
}

// names and types of the joints (a gear may name a joint declared after it)
void MultibodyReader::declare_joints() {
  const YAML::Node js = root_["joints"];
  if (!js) return;
  if (!js.IsSequence())
    r_.fail(js, "joints must be a list",
            "- {name: pin, type: revolute, parent: ground, child: link, child_point: [-0.5, 0]}");
  int index = 0;
  for (const auto& j : js) {
    ++index;
    check_map(j, "a joint", "{name: pin, type: revolute, parent: ground, child: link}");
    const YAML::Node t = require(j, "type", "a joint", "type: revolute");
    const JointKind* kind = nullptr;
    for (const auto& k : kJointKinds) {
      if (t.IsScalar() && t.Scalar() == k.name) kind = &k;
    }
    if (!kind)
      r_.fail(t, "unknown joint type '" + (t.IsScalar() ? t.Scalar() : std::string()) + "'",
              "the types are " + joint_kind_list());
    const std::string name =
        name_of(j, "a joint", std::string(kind->name) + "_" + format_number(index));
    for (const auto& other : joints_) {
      if (other.name == name)
        r_.fail(j["name"] ? j["name"] : j, "joint '" + name + "' is declared twice",
                "joint names name their constraints: make them unique");
    }
    joints_.push_back({name, kind->type, j});
    r_.positions_.constraints[name] = Reader::position(j);
  }
}

void MultibodyReader::read_joints() {
  const std::set<std::string> two_body = {"name",  "type",         "parent",
                                          "child", "parent_point", "child_point"};
  for (const JointDecl& d : joints_) {
    const YAML::Node& j = d.node;
    const std::string what = "joint '" + d.name + "'";
    const std::string type_name = mb::to_string(d.type);
    // gears: two revolute joints by name
    if (d.type == mb::JointType::kGear) {
      check_keys(j, {"name", "type", "a", "b", "ratio"}, what);
      const std::string example = "{type: gear, a: pin1, b: pin2, ratio: 2}";
      std::string ab[2];
      for (int s = 0; s < 2; ++s) {
        const YAML::Node n = require(j, s == 0 ? "a" : "b", what, example);
        ab[s] = n.Scalar();
        if (ab[s] == d.name) r_.fail(n, what + " refers to itself", "a and b name revolute joints");
        const auto it = std::find_if(joints_.begin(), joints_.end(),
                                     [&](const JointDecl& o) { return o.name == ab[s]; });
        if (it == joints_.end()) {
          std::vector<std::string> names;
          for (const auto& o : joints_) {
            if (o.type == mb::JointType::kRevolute) names.push_back(o.name);
          }
          r_.fail(n, what + ": no joint '" + ab[s] + "'",
                  names.empty() ? "a gear couples two revolute joints"
                                : "the revolute joints are " + join(names));
        }
        if (it->type != mb::JointType::kRevolute)
          r_.fail(n, what + ": '" + ab[s] + "' is a " + mb::to_string(it->type) +
                         " joint, not revolute");
      }
      if (ab[0] == ab[1]) r_.fail(j["b"], what + ": a and b are the same joint");
      const double ratio = r_.number(require(j, "ratio", what, example), what + " ratio");
      if (ratio == 0.0) r_.fail(j["ratio"], what + ": the ratio must not be 0");
      builder_.add_joint(mb::gear(d.name, ab[0], ab[1], ratio));
      continue;
    }
    // rolling contacts on the plane z = 0: one body
    if (d.type == mb::JointType::kRollingDisk || d.type == mb::JointType::kRollingSphere) {
      const bool disk = d.type == mb::JointType::kRollingDisk;
      check_keys(j,
                 disk ? std::set<std::string>{"name", "type", "body", "radius", "axis"}
                      : std::set<std::string>{"name", "type", "body", "radius"},
                 what);
      const std::string example = "{type: " + type_name + ", body: wheel, radius: R}";
      const YAML::Node bn = require(j, "body", what, example);
      const BodyId b = body(bn, what);
      if (b == kGround || bodies_[std::size_t(b)].kind != BodyKind::kRigid)
        r_.fail(bn, what + ": a rolling " + (disk ? "disk" : "sphere") + " is a rigid body",
                "declare it with type: rigid");
      const double R = positive(require(j, "radius", what, example), what + " radius");
      if (disk) {
        Frame f;
        if (const YAML::Node a = j["axis"]) {
          const Vector3d axis = vec(a, what + " axis", 3, 3);
          if (!(axis.norm() > 0.0)) r_.fail(a, what + ": the axis is zero");
          f = Frame::with_z(Vector3d::Zero(), axis);
        }
        builder_.add_joint(mb::rolling_disk(d.name, b, R, f));
      } else {
        builder_.add_joint(mb::rolling_sphere(d.name, b, R));
      }
      continue;
    }
    // two bodies
    std::set<std::string> keys = two_body;
    const bool framed = d.type != mb::JointType::kDistance && d.type != mb::JointType::kSpherical;
    if (framed) {
      keys.insert({"parent_angle", "parent_axis", "parent_orientation"});
      if (d.type != mb::JointType::kPointOnLine && d.type != mb::JointType::kPointOnPlane)
        keys.insert({"child_angle", "child_axis", "child_orientation"});
    }
    if (d.type == mb::JointType::kDistance) keys.insert("length");
    const bool drivable = d.type == mb::JointType::kRevolute ||
                          d.type == mb::JointType::kPrismatic ||
                          d.type == mb::JointType::kCylindrical;
    if (drivable) keys.insert("drive");
    if (d.type == mb::JointType::kRevolute || d.type == mb::JointType::kPrismatic)
      keys.insert("friction");
    check_keys(j, keys, type_name + " " + what);
    const std::string example =
        "{name: pin, type: " + type_name + ", parent: ground, child: link, ...}";
    const YAML::Node pn = require(j, "parent", what, example),
                     cn = require(j, "child", what, example);
    const BodyId parent = body(pn, what + " parent"), child = body(cn, what + " child");
    if (parent == child)
      r_.fail(cn,
              what + " joins " +
                  (child == kGround ? std::string("the ground") : "body '" + cn.Scalar() + "'") +
                  " to itself",
              "parent and child are two different bodies (or one of them the ground)");
    const bool is_planar = planar(parent) || planar(child);
    for (BodyId b : {parent, child}) {
      if (b != kGround && bodies_[std::size_t(b)].kind == BodyKind::kParticle &&
          d.type != mb::JointType::kSpherical && d.type != mb::JointType::kDistance &&
          d.type != mb::JointType::kPointOnLine && d.type != mb::JointType::kPointOnPlane) {
        r_.fail(j["type"],
                what + ": a particle has no orientation: a " + type_name + " joint cannot hold '" +
                    bodies_[std::size_t(b)].name + "'",
                "particles take spherical, distance, point_on_line and point_on_plane joints");
      }
    }
    if (is_planar && d.type != mb::JointType::kRevolute && d.type != mb::JointType::kPrismatic &&
        d.type != mb::JointType::kWeld && d.type != mb::JointType::kDistance &&
        d.type != mb::JointType::kPointOnLine) {
      r_.fail(j["type"], what + ": a " + type_name + " joint is spatial, not between planar bodies",
              "planar joints: revolute, prismatic, weld, distance, point_on_line, gear");
    }
    mb::Joint joint;
    switch (d.type) {
      case mb::JointType::kDistance: {
        const double L = positive(require(j, "length", what, "length: 1"), what + " length");
        joint = mb::distance(d.name, parent, point(j, "parent_point", is_planar, what), child,
                             point(j, "child_point", is_planar, what), L);
        break;
      }
      case mb::JointType::kSpherical:
        joint = mb::spherical(d.name, parent, point(j, "parent_point", is_planar, what), child,
                              point(j, "child_point", is_planar, what));
        break;
      case mb::JointType::kPointOnLine:
        joint = mb::point_on_line(d.name, parent, frame(j, "parent", is_planar, what), child,
                                  point(j, "child_point", is_planar, what));
        break;
      case mb::JointType::kPointOnPlane:
        joint = mb::point_on_plane(d.name, parent, frame(j, "parent", is_planar, what), child,
                                   point(j, "child_point", is_planar, what));
        break;
      default: {
        const Frame fp = frame(j, "parent", is_planar, what),
                    fc = frame(j, "child", is_planar, what);
        switch (d.type) {
          case mb::JointType::kRevolute:
            joint = mb::revolute(d.name, parent, fp, child, fc);
            break;
          case mb::JointType::kPrismatic:
            joint = mb::prismatic(d.name, parent, fp, child, fc);
            break;
          case mb::JointType::kWeld:
            joint = mb::weld(d.name, parent, fp, child, fc);
            break;
          case mb::JointType::kCylindrical:
            joint = mb::cylindrical(d.name, parent, fp, child, fc);
            break;
          case mb::JointType::kUniversal:
            joint = mb::universal(d.name, parent, fp, child, fc);
            break;
          default:
            joint = mb::planar_joint(d.name, parent, fp, child, fc);
            break;
        }
      }
    }
    if (const YAML::Node dr = j["drive"]) joint.drive = drive(dr, what);
    if (const YAML::Node fr = j["friction"]) joint.friction = friction(fr, what);
    builder_.add_joint(std::move(joint));
  }
}

void MultibodyReader::read_forces() {
  const YAML::Node fs = root_["forces"];
  if (!fs) return;
  if (!fs.IsSequence())
    r_.fail(fs, "forces of a multibody model must be a list of force elements",
            "- {type: gravity, g: [0, -9.81]}");
  const bool planar_model = bodies_.front().kind == BodyKind::kPlanar;
  const int dims = planar_model ? 2 : 3;
  bool gravity = false;
  std::set<std::string> names;
  int index = 0;
  for (const auto& f : fs) {
    ++index;
    if (!f.IsMap())
      r_.fail(f, "a force element must be a mapping",
              "in a model with bodies:, forces: lists force elements, e.g. {type: gravity, g: "
              "[0, -9.81]}; generalized forces need coordinates:");
    const YAML::Node t = require(f, "type", "a force element", "type: spring_damper");
    const std::string& type = t.Scalar();
    const std::string name = name_of(f, "a force element", type + "_" + format_number(index));
    if (!names.insert(name).second)
      r_.fail(f["name"] ? f["name"] : f, "force '" + name + "' is declared twice");
    const std::string what = "force '" + name + "'";
    if (type == "gravity") {
      check_keys(f, {"name", "type", "g"}, what);
      if (gravity) r_.fail(t, "gravity is given twice", "one gravity element per model");
      gravity = true;
      builder_.set_gravity(
          vec(require(f, "g", what, planar_model ? "g: [0, -9.81]" : "g: [0, 0, -9.81]"),
              what + " g", dims, dims));
    } else if (type == "spring_damper") {
      check_keys(f, {"name", "type", "a", "point_a", "b", "point_b", "k", "c", "length"}, what);
      const std::string example = "{type: spring_damper, a: link, b: ground, k: 100, length: 0.5}";
      const BodyId a = body(require(f, "a", what, example), what + " a"),
                   b = body(require(f, "b", what, example), what + " b");
      if (a == b) r_.fail(f["b"], what + " joins a body to itself");
      const Vector3d pa =
          f["point_a"] ? vec(f["point_a"], what + " point_a", dims, dims) : Vector3d::Zero();
      const Vector3d pb =
          f["point_b"] ? vec(f["point_b"], what + " point_b", dims, dims) : Vector3d::Zero();
      const double k = non_negative(require(f, "k", what, example), what + " k");
      const double c = f["c"] ? non_negative(f["c"], what + " c") : 0.0;
      const double L = f["length"] ? non_negative(f["length"], what + " length") : 0.0;
      builder_.add_force(mb::spring_damper(name, a, pa, b, pb, k, c, L));
      springs_.push_back(SpringDecl{f, what, a, b, pa, pb});
    } else if (type == "torsion_spring") {
      check_keys(f, {"name", "type", "a", "b", "k", "c", "angle"}, what);
      if (!planar_model)
        r_.fail(t, what + ": torsion springs join planar bodies", "use a planar model");
      const std::string example = "{type: torsion_spring, a: ground, b: link, k: 10}";
      const BodyId a = body(require(f, "a", what, example), what + " a"),
                   b = body(require(f, "b", what, example), what + " b");
      if (a == b) r_.fail(f["b"], what + " joins a body to itself");
      const double k = non_negative(require(f, "k", what, example), what + " k");
      const double c = f["c"] ? non_negative(f["c"], what + " c") : 0.0;
      const double angle = f["angle"] ? r_.number(f["angle"], what + " angle") : 0.0;
      builder_.add_force(mb::torsion_spring(name, a, b, k, c, angle));
    } else if (type == "applied") {
      check_keys(f, {"name", "type", "body", "point", "force", "torque"}, what);
      const YAML::Node bn = require(f, "body", what, "{type: applied, body: link, force: [1, 0]}");
      const BodyId b = body(bn, what + " body");
      if (b == kGround) r_.fail(bn, what + ": a force on the ground does nothing");
      const Vector3d p =
          f["point"] ? vec(f["point"], what + " point", dims, dims) : Vector3d::Zero();
      builder_.add_force(mb::applied(name, b, p, wrench(f, planar_model, what)));
    } else {
      r_.fail(t, "unknown force type '" + type + "'",
              "gravity, spring_damper, torsion_spring or applied");
    }
  }
}

// the switches of the applied forces' and the drives' sign, abs, min, max, heaviside and if
// (Reader::switches), evaluated in buffers of the call as the forces are
void MultibodyReader::add_switches() {
  std::vector<std::string> names;
  Program p;
  if (!r_.switches(names, p)) return;
  const InputLayout layout = r_.layout_;
  builder_.set_switching_functions(
      std::move(names),
      [p, layout](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                  double t, CallableScratch*, Eigen::Ref<VectorXd> out) {
        evaluate_local(
            p, layout.size(), [&](double* in) { layout.fill(in, q, qd, t); },
            [&](const double* v) { std::copy(v, v + out.size(), out.data()); });
      });
}

Model MultibodyReader::read() {
  refuse_generalized_keys();
  declare_bodies();
  r_.make_expression_set(root_, {});
  read_bodies();
  declare_joints();
  read_joints();
  read_forces();
  read_contacts();
  read_contact_frictions();
  add_switches();
  const auto build = [&]() -> mb::MultibodyModel {
    try {
      return builder_.build();
    } catch (const std::invalid_argument& e) {
      // what the reader does not check itself (it checks names, kinds and values above)
      std::string message = e.what();
      const std::string prefix = "ukdyn::mb::Multibody::build: ";
      if (message.rfind(prefix, 0) == 0) message.erase(0, prefix.size());
      YAML::Node at = root_["joints"] ? root_["joints"] : root_["bodies"];
      for (const auto& d : joints_) {
        if (message.find("'" + d.name + "'") != std::string::npos) at = d.node;
      }
      for (const auto& d : contacts_) {
        if (message.find("contact '" + d.name + "'") != std::string::npos) at = d.node;
      }
      r_.fail(at, message);
    }
  };
  auto built = std::make_shared<mb::MultibodyModel>(build());
  // the generated names follow the System's coordinates one to one
  if (built->system.coordinate_names().size() != r_.coordinates_.size())
    r_.fail(root_["bodies"],
            "internal: the bodies have " + format_number(built->system.coordinate_names().size()) +
                " coordinates, the reader named " + format_number(r_.coordinates_.size()));
  // a spring-damper whose points coincide at the start: the direction of its force is undefined
  // (it would exert nothing there, whatever its rest length)
  for (const SpringDecl& sd : springs_) {
    const Vector3d pa = mb::world_point(*built, built->q0, sd.a, sd.pa);
    const Vector3d pb = mb::world_point(*built, built->q0, sd.b, sd.pb);
    if ((pa - pb).norm() <= 1e-12 * (1.0 + pa.norm())) {
      r_.fail(sd.node,
              sd.what + ": its two points coincide in the initial pose (at [" + brief(pa.x()) +
                  ", " + brief(pa.y()) + ", " + brief(pa.z()) +
                  "]), where the direction of a spring-damper's force is undefined",
              "move a body (position:) or an attachment point (point_a:, point_b:) so that the "
              "spring has a length");
    }
  }
  Model model{.system = built->system};
  model.q0 = built->q0;
  model.qd0 = built->qd0;
  // the contacts drawn by the viewer: each contacts: entry's point and normal at q
  for (const JointDecl& d : contacts_) {
    model.visual.contacts.push_back(detail::bodies_visual_contact(
        built, built->joints.at(std::size_t(built->joint(d.name))), d.radius));
  }
  model.multibody = std::move(built);
  return model;
}

Model Reader::read_multibody(const YAML::Node& root) { return MultibodyReader(*this, root).read(); }

}  // namespace ukdyn::model_reader

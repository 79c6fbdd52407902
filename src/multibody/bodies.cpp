// SPDX-License-Identifier: BSD-3-Clause
// The Multibody builder: bodies and their coordinates, mass blocks and initial state; joint and
// force factories; build(), which turns bodies, joints and forces into a System.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "multibody/internal.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn::mb {

using detail::BodyRef;
using detail::Row;

Frame Frame::planar(double x, double y, double angle) {
  return {Vector3d(x, y, 0.0), Eigen::AngleAxisd(angle, Vector3d::UnitZ()).toRotationMatrix()};
}

Frame Frame::with_z(const Vector3d& p, const Vector3d& axis) {
  if (!(axis.norm() > 0.0)) {
    throw std::invalid_argument("ukdyn::mb::Frame::with_z: the axis must not be zero");
  }
  const Vector3d z = axis.normalized();
  // x: the coordinate axis least aligned with z, made orthogonal
  Vector3d x = std::abs(z.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
  x = (x - x.dot(z) * z).normalized();
  Frame f;
  f.p = p;
  f.R.col(0) = x;
  f.R.col(1) = z.cross(x);
  f.R.col(2) = z;
  return f;
}

const char* to_string(JointType type) {
  switch (type) {
    case JointType::kRevolute:
      return "revolute";
    case JointType::kPrismatic:
      return "prismatic";
    case JointType::kWeld:
      return "weld";
    case JointType::kDistance:
      return "distance";
    case JointType::kPointOnLine:
      return "point_on_line";
    case JointType::kSpherical:
      return "spherical";
    case JointType::kCylindrical:
      return "cylindrical";
    case JointType::kUniversal:
      return "universal";
    case JointType::kPlanar:
      return "planar";
    case JointType::kPointOnPlane:
      return "point_on_plane";
    case JointType::kGear:
      return "gear";
    case JointType::kRollingDisk:
      return "rolling_disk";
    case JointType::kRollingSphere:
      return "rolling_sphere";
    case JointType::kContact:
      return "contact";
    case JointType::kContactDisk:
      return "contact_disk";
    case JointType::kContactSpheres:
      return "contact_spheres";
    case JointType::kContactDiskSphere:
      return "contact_disk_sphere";
    case JointType::kContactSphereBox:
      return "contact_sphere_box";
  }
  return "unknown";
}

namespace {
Joint make_joint(std::string name, JointType type, BodyId parent, const Frame& fp, BodyId child,
                 const Frame& fc) {
  Joint j;
  j.name = std::move(name);
  j.type = type;
  j.parent = parent;
  j.child = child;
  j.frame_parent = fp;
  j.frame_child = fc;
  return j;
}
}  // namespace

Joint revolute(std::string n, BodyId p, const Frame& fp, BodyId c, const Frame& fc) {
  return make_joint(std::move(n), JointType::kRevolute, p, fp, c, fc);
}
Joint prismatic(std::string n, BodyId p, const Frame& fp, BodyId c, const Frame& fc) {
  return make_joint(std::move(n), JointType::kPrismatic, p, fp, c, fc);
}
Joint weld(std::string n, BodyId p, const Frame& fp, BodyId c, const Frame& fc) {
  return make_joint(std::move(n), JointType::kWeld, p, fp, c, fc);
}
Joint distance(std::string n, BodyId p, const Vector3d& pp, BodyId c, const Vector3d& pc,
               double length) {
  Joint j = make_joint(std::move(n), JointType::kDistance, p, Frame::at(pp), c, Frame::at(pc));
  j.length = length;
  return j;
}
Joint point_on_line(std::string n, BodyId p, const Frame& fp, BodyId c, const Vector3d& pc) {
  return make_joint(std::move(n), JointType::kPointOnLine, p, fp, c, Frame::at(pc));
}
Joint spherical(std::string n, BodyId p, const Vector3d& pp, BodyId c, const Vector3d& pc) {
  return make_joint(std::move(n), JointType::kSpherical, p, Frame::at(pp), c, Frame::at(pc));
}
Joint cylindrical(std::string n, BodyId p, const Frame& fp, BodyId c, const Frame& fc) {
  return make_joint(std::move(n), JointType::kCylindrical, p, fp, c, fc);
}
Joint universal(std::string n, BodyId p, const Frame& fp, BodyId c, const Frame& fc) {
  return make_joint(std::move(n), JointType::kUniversal, p, fp, c, fc);
}
Joint planar_joint(std::string n, BodyId p, const Frame& fp, BodyId c, const Frame& fc) {
  return make_joint(std::move(n), JointType::kPlanar, p, fp, c, fc);
}
Joint point_on_plane(std::string n, BodyId p, const Frame& fp, BodyId c, const Vector3d& pc) {
  return make_joint(std::move(n), JointType::kPointOnPlane, p, fp, c, Frame::at(pc));
}
Joint gear(std::string n, std::string a, std::string b, double ratio) {
  Joint j;
  j.name = std::move(n);
  j.type = JointType::kGear;
  j.gear_a = std::move(a);
  j.gear_b = std::move(b);
  j.ratio = ratio;
  return j;
}
Joint rolling_disk(std::string n, BodyId disk, double radius, const Frame& axis_frame) {
  Joint j = make_joint(std::move(n), JointType::kRollingDisk, kGround, {}, disk, axis_frame);
  j.radius = radius;
  return j;
}
Joint rolling_sphere(std::string n, BodyId sphere, double radius) {
  Joint j = make_joint(std::move(n), JointType::kRollingSphere, kGround, {}, sphere, {});
  j.radius = radius;
  return j;
}

Joint contact(std::string n, BodyId plane_body, const Frame& plane, BodyId body,
              const Vector3d& p_body, double radius, double restitution) {
  Joint j =
      make_joint(std::move(n), JointType::kContact, plane_body, plane, body, Frame::at(p_body));
  j.radius = radius;
  j.restitution = restitution;
  return j;
}
Joint contact_disk(std::string n, BodyId plane_body, const Frame& plane, BodyId body,
                   const Frame& disk, double radius, double restitution) {
  Joint j = make_joint(std::move(n), JointType::kContactDisk, plane_body, plane, body, disk);
  j.radius = radius;
  j.restitution = restitution;
  return j;
}
Joint contact_spheres(std::string n, BodyId other_body, const Vector3d& p_other,
                      double other_radius, BodyId body, const Vector3d& p_body, double radius,
                      double restitution, SphereSide side) {
  Joint j = make_joint(std::move(n), JointType::kContactSpheres, other_body, Frame::at(p_other),
                       body, Frame::at(p_body));
  j.radius = radius;
  j.other_radius = other_radius;
  j.side = side;
  j.restitution = restitution;
  return j;
}
Joint contact_disk_sphere(std::string n, BodyId other_body, const Vector3d& p_other,
                          double other_radius, BodyId body, const Frame& disk, double radius,
                          double restitution) {
  Joint j = make_joint(std::move(n), JointType::kContactDiskSphere, other_body, Frame::at(p_other),
                       body, disk);
  j.radius = radius;
  j.other_radius = other_radius;
  j.restitution = restitution;
  return j;
}
Joint contact_sphere_box(std::string n, BodyId other_body, const Frame& box, const Vector3d& half,
                         BodyId body, const Vector3d& p_body, double radius, double restitution) {
  Joint j = make_joint(std::move(n), JointType::kContactSphereBox, other_body, box, body,
                       Frame::at(p_body));
  j.radius = radius;
  j.box_half = half;
  j.restitution = restitution;
  return j;
}

Force spring_damper(std::string name, BodyId a, const Vector3d& pa, BodyId b, const Vector3d& pb,
                    double k, double c, double rest_length) {
  Force f;
  f.name = std::move(name);
  f.type = ForceType::kSpringDamper;
  f.body_a = a;
  f.body_b = b;
  f.point_a = pa;
  f.point_b = pb;
  f.stiffness = k;
  f.damping = c;
  f.rest = rest_length;
  return f;
}
Force torsion_spring(std::string name, BodyId a, BodyId b, double k, double c, double theta0) {
  Force f;
  f.name = std::move(name);
  f.type = ForceType::kTorsionSpring;
  f.body_a = a;
  f.body_b = b;
  f.stiffness = k;
  f.damping = c;
  f.rest = theta0;
  return f;
}
Force applied(std::string name, BodyId body, const Vector3d& p, WrenchFn fn) {
  Force f;
  f.name = std::move(name);
  f.type = ForceType::kApplied;
  f.body_a = body;
  f.point_a = p;
  f.wrench = std::move(fn);
  return f;
}

// ---------------------------------------------------------------------------------------------

struct Multibody::Impl {
  struct Body {
    BodyInfo info;
    VectorXd q0, qd0;  // the body's coordinates and velocities
  };
  std::vector<Body> bodies;
  std::vector<Joint> joints;
  std::vector<Force> forces;
  Vector3d g = Vector3d::Zero();
  Index n = 0;
  std::vector<std::string> switch_names;
  SwitchScratchFn switches;
  struct ContactFriction {
    std::string contact;
    double mu;
    std::optional<double> mu_static;
    double eps;
  };
  std::vector<ContactFriction> contact_frictions;
};

Multibody::Multibody() : impl_(std::make_unique<Impl>()) {}
Multibody::~Multibody() = default;
Multibody::Multibody(const Multibody& o) : impl_(std::make_unique<Impl>(*o.impl_)) {}
Multibody& Multibody::operator=(const Multibody& o) {
  impl_ = std::make_unique<Impl>(*o.impl_);
  return *this;
}

namespace {
void require_positive(double x, const std::string& who, const char* what) {
  if (!(x > 0.0) || !std::isfinite(x)) {
    std::ostringstream os;
    os << "ukdyn::mb::Multibody::" << who << ": " << what << " must be > 0, got " << x;
    throw std::invalid_argument(os.str());
  }
}
}  // namespace

Multibody& Multibody::add_contact_friction(std::string contact, double mu,
                                           std::optional<double> mu_static,
                                           double regularization_velocity) {
  impl_->contact_frictions.push_back({std::move(contact), mu, mu_static, regularization_velocity});
  return *this;
}

BodyId Multibody::add_particle(std::string name, double mass, const Vector3d& p0,
                               const Vector3d& v0) {
  require_positive(mass, "add_particle('" + name + "')", "mass");
  Impl::Body b;
  b.info = {std::move(name), BodyKind::kParticle, impl_->n, 3, mass, Vector3d::Zero()};
  b.q0 = p0;
  b.qd0 = v0;
  impl_->n += 3;
  impl_->bodies.push_back(std::move(b));
  return BodyId(impl_->bodies.size()) - 1;
}

BodyId Multibody::add_planar_body(std::string name, double mass, double inertia,
                                  const Vector3d& pose0, const Vector3d& vel0) {
  require_positive(mass, "add_planar_body('" + name + "')", "mass");
  require_positive(inertia, "add_planar_body('" + name + "')", "inertia");
  Impl::Body b;
  b.info = {std::move(name), BodyKind::kPlanar, impl_->n, 3, mass, Vector3d(0, 0, inertia)};
  b.q0 = pose0;
  b.qd0 = vel0;
  impl_->n += 3;
  impl_->bodies.push_back(std::move(b));
  return BodyId(impl_->bodies.size()) - 1;
}

BodyId Multibody::add_rigid_body(std::string name, double mass, const Vector3d& inertia,
                                 const Vector3d& r0, const Quaterniond& u0, const Vector3d& v0,
                                 const Vector3d& w0) {
  const std::string who = "add_rigid_body('" + name + "')";
  require_positive(mass, who, "mass");
  for (int i = 0; i < 3; ++i) require_positive(inertia[i], who, "each principal inertia");
  if (!(u0.norm() > 0.0)) {
    throw std::invalid_argument("ukdyn::mb::Multibody::" + who + ": the quaternion is zero");
  }
  const Quaterniond u = u0.normalized();
  Impl::Body b;
  b.info = {std::move(name), BodyKind::kRigid, impl_->n, 7, mass, inertia};
  b.q0.resize(7);
  b.qd0.resize(7);
  b.q0 << r0, u.w(), u.x(), u.y(), u.z();
  // u' = ½ (0, ω_W) ⊗ u = ½ (−ω·e, u0 ω + ω × e)
  const Vector3d e(u.x(), u.y(), u.z());
  b.qd0 << v0, -0.5 * w0.dot(e), 0.5 * (u.w() * w0 + w0.cross(e));
  impl_->n += 7;
  impl_->bodies.push_back(std::move(b));
  return BodyId(impl_->bodies.size()) - 1;
}

Multibody& Multibody::add_joint(Joint joint) {
  impl_->joints.push_back(std::move(joint));
  return *this;
}
Multibody& Multibody::add_force(Force force) {
  impl_->forces.push_back(std::move(force));
  return *this;
}
Multibody& Multibody::set_gravity(const Vector3d& g) {
  impl_->g = g;
  return *this;
}

Multibody& Multibody::set_switching_functions(std::vector<std::string> names, SwitchScratchFn fn) {
  impl_->switch_names = std::move(names);
  impl_->switches = std::move(fn);
  return *this;
}

std::vector<bool> MultibodyModel::angle_coordinates() const {
  std::vector<bool> angles(std::size_t(system.coordinate_count()), false);
  for (const BodyInfo& b : bodies) {
    // (x, y, theta): theta (a quaternion's components are weighed as lengths)
    if (b.kind == BodyKind::kPlanar) angles[std::size_t(b.offset + 2)] = true;
  }
  return angles;
}

BodyId MultibodyModel::body(std::string_view name) const {
  std::string list;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (bodies[i].name == name) return BodyId(i);
    list += (list.empty() ? "" : ", ") + bodies[i].name;
  }
  throw std::invalid_argument("ukdyn::mb::MultibodyModel::body: no body '" + std::string(name) +
                              "' (known: " + list + ")");
}

Index MultibodyModel::joint(std::string_view name) const {
  std::string list;
  for (std::size_t i = 0; i < joints.size(); ++i) {
    if (joints[i].name == name) return Index(i);
    list += (list.empty() ? "" : ", ") + joints[i].name;
  }
  throw std::invalid_argument("ukdyn::mb::MultibodyModel::joint: no joint '" + std::string(name) +
                              "' (known: " + list + ")");
}

// ---------------------------------------------------------------------------------------------

MultibodyModel Multibody::build() const {
  const Impl& d = *impl_;
  const std::string who = "ukdyn::mb::Multibody::build: ";
  if (d.n == 0) throw std::invalid_argument(who + "no bodies");
  struct {  // everything of the MultibodyModel but its System (which has no default state)
    VectorXd q0, qd0;
    std::vector<BodyInfo> bodies;
    std::vector<JointInfo> joints;
  } out;
  std::vector<std::string> names;
  out.q0.resize(d.n);
  out.qd0.resize(d.n);
  for (const auto& b : d.bodies) {
    out.bodies.push_back(b.info);
    out.q0.segment(b.info.offset, b.info.size) = b.q0;
    out.qd0.segment(b.info.offset, b.info.size) = b.qd0;
    const char* const particle[] = {".x", ".y", ".z"};
    const char* const planar[] = {".x", ".y", ".theta"};
    const char* const rigid[] = {".x", ".y", ".z", ".u0", ".u1", ".u2", ".u3"};
    const char* const* suffix = b.info.kind == BodyKind::kParticle
                                    ? particle
                                    : (b.info.kind == BodyKind::kPlanar ? planar : rigid);
    for (Index i = 0; i < b.info.size; ++i) names.push_back(b.info.name + suffix[i]);
  }
  SystemBuilder sb(names);
  // mass blocks: m I3 (particle), diag(m, m, I) (planar), m I3 + 4 E_vᵀ J E_v (rigid)
  for (const BodyInfo& b : out.bodies) {
    if (b.kind == BodyKind::kPlanar) {
      sb.mass_block(b.offset,
                    Eigen::Vector3d(b.mass, b.mass, b.inertia.z()).asDiagonal().toDenseMatrix());
    } else {
      sb.mass_block(b.offset, b.mass * MatrixXd::Identity(3, 3));
    }
    if (b.kind == BodyKind::kRigid) {
      const Index o = b.offset + 3;
      const Vector3d J = b.inertia;
      // singular (rank 3) by construction: the unit-norm constraint "<body>.unit" completes it
      sb.singular_mass_block(
          o, 4, [o, J](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> Mk) {
            detail::quaternion_mass(q.segment<4>(o), J, Mk);
          });
    }
  }
  // the per-workspace memo of the bodies' rotations, which the forces and the joints share
  const Index body_count = Index(out.bodies.size());
  sb.scratch([body_count]() -> std::unique_ptr<CallableScratch> {
    return std::make_unique<detail::PoseCache>(body_count);
  });
  sb.forces(detail::make_forces(out.bodies, d.forces, d.g));
  sb.potential_energy(detail::make_potential(out.bodies, d.forces, d.g));
  if (PowerScratchFn power = detail::make_external_power(out.bodies, d.forces)) {
    sb.external_power(std::move(power));
  }
  if (d.switches) sb.switching_functions(d.switch_names, d.switches);
  Index k = 0;  // constraint count
  // unit quaternions
  for (const BodyInfo& b : out.bodies) {
    if (b.kind != BodyKind::kRigid) continue;
    sb.add(Constraint(b.name + ".unit", ConstraintKind::kHolonomic, 1,
                      std::make_shared<detail::UnitQuaternionModel>(b.offset + 3)));
    ++k;
  }
  // joints
  const auto check_body = [&](BodyId id, const Joint& j) {
    if (id != kGround && (id < 0 || id >= BodyId(out.bodies.size()))) {
      throw std::invalid_argument(who + "joint '" + j.name + "': unknown body " +
                                  format_number(id));
    }
  };
  Index friction_count = 0;
  for (const Joint& j : d.joints) {
    JointInfo info;
    info.name = j.name;
    info.type = j.type;
    info.parent = j.parent;
    info.child = j.child;
    info.frame_parent = j.frame_parent;
    info.frame_child = j.frame_child;
    info.side = j.side;
    info.box_half = j.box_half;
    info.friction_law = j.friction;
    if (j.type == JointType::kGear) {
      const auto find = [&](const std::string& name) {
        const auto it = std::find_if(d.joints.begin(), d.joints.end(),
                                     [&](const Joint& o) { return o.name == name; });
        if (it == d.joints.end() || it->type != JointType::kRevolute) {
          throw std::invalid_argument(who + "gear '" + j.name + "': '" + name +
                                      "' is not a revolute joint of the model");
        }
        return *it;
      };
      const Joint ja = find(j.gear_a), jb = find(j.gear_b);
      const auto planar_body = [&](BodyId id) {
        return id != kGround && out.bodies[std::size_t(id)].kind == BodyKind::kPlanar;
      };
      if (!planar_body(ja.parent) && !planar_body(ja.child)) {
        // spatial revolute joints: at velocity level
        sb.add(detail::spatial_gear(
            j, ja, detail::body_ref(out.bodies, ja.parent), detail::body_ref(out.bodies, ja.child),
            jb, detail::body_ref(out.bodies, jb.parent), detail::body_ref(out.bodies, jb.child)));
        info.constraints.push_back(k++);
        out.joints.push_back(std::move(info));
        continue;
      }
      // angle_a − ratio angle_b = its initial value, angle = theta_C − theta_P
      Row r;
      r.kind = Row::kLinear;
      std::vector<BodyRef> slots;
      double c0 = 0.0;
      for (int s = 0; s < 2; ++s) {
        const std::string& name = s == 0 ? j.gear_a : j.gear_b;
        const double coef = s == 0 ? 1.0 : -j.ratio;
        const auto it = std::find_if(d.joints.begin(), d.joints.end(),
                                     [&](const Joint& o) { return o.name == name; });
        if (it == d.joints.end() || it->type != JointType::kRevolute) {
          throw std::invalid_argument(who + "gear '" + j.name + "': '" + name +
                                      "' is not a revolute joint of the model");
        }
        for (int side = 0; side < 2; ++side) {
          const BodyId id = side == 0 ? it->child : it->parent;
          const double sign = side == 0 ? coef : -coef;
          if (id == kGround) continue;
          const BodyRef ref = detail::body_ref(out.bodies, id);
          if (ref.kind != BodyKind::kPlanar) {
            throw std::invalid_argument(who + "gear '" + j.name + "': joint '" + name +
                                        "' is not between planar bodies");
          }
          const Index i = ref.offset + 2;
          auto t = std::find_if(r.terms.begin(), r.terms.end(),
                                [i](const auto& p) { return p.first == i; });
          if (t == r.terms.end()) {
            r.terms.push_back({i, sign});
            slots.push_back(ref);
          } else {
            t->second += sign;
          }
          c0 += sign * out.q0[i];
        }
      }
      r.c.c0 = c0;
      info.planar = true;
      sb.add(Constraint(j.name, ConstraintKind::kHolonomic, 1,
                        std::make_shared<detail::JointModel>(slots, std::vector<Row>{r})));
      info.constraints.push_back(k++);
      out.joints.push_back(std::move(info));
      continue;
    }
    check_body(j.parent, j);
    check_body(j.child, j);
    if (j.parent == j.child) {
      throw std::invalid_argument(who + "joint '" + j.name + "' joins a body to itself");
    }
    const BodyRef P = detail::body_ref(out.bodies, j.parent);
    const BodyRef C = detail::body_ref(out.bodies, j.child);
    if (j.type == JointType::kRollingDisk || j.type == JointType::kRollingSphere) {
      for (Constraint& c : detail::rolling_constraints(j, C)) {
        sb.add(std::move(c));
        info.constraints.push_back(k++);
      }
      out.joints.push_back(std::move(info));
      continue;
    }
    // planar joints join planar bodies (and the ground); spatial joints the others
    const bool p_planar = !P.ground() && P.kind == BodyKind::kPlanar;
    const bool c_planar = !C.ground() && C.kind == BodyKind::kPlanar;
    if ((!P.ground() && !C.ground() && p_planar != c_planar)) {
      throw std::invalid_argument(who + "joint '" + j.name +
                                  "' joins a planar body to a spatial one");
    }
    info.planar = p_planar || c_planar;
    if (is_contact(j.type)) {
      sb.add(detail::contact_constraint(j, P, C, info.planar, out.q0));
      info.constraints.push_back(k++);
      out.joints.push_back(std::move(info));
      continue;
    }
    const bool has_particle = (!P.ground() && P.kind == BodyKind::kParticle) ||
                              (!C.ground() && C.kind == BodyKind::kParticle);
    if (has_particle && j.type != JointType::kSpherical && j.type != JointType::kDistance &&
        j.type != JointType::kPointOnLine && j.type != JointType::kPointOnPlane) {
      throw std::invalid_argument(who + "joint '" + j.name + "': a particle has no orientation; " +
                                  "it takes spherical, distance, point_on_line and "
                                  "point_on_plane joints only, not " +
                                  to_string(j.type));
    }
    if (j.type == JointType::kDistance && !(j.length > 0.0)) {
      throw std::invalid_argument(who + "joint '" + j.name + "': the length must be > 0");
    }
    std::vector<Row> rows =
        info.planar ? detail::planar_joint_rows(j, P, C) : detail::spatial_joint_rows(j, P, C);
    const Index nrows = Index(rows.size());
    sb.add(Constraint(
        j.name, ConstraintKind::kHolonomic, nrows,
        std::make_shared<detail::JointModel>(std::vector<BodyRef>{P, C}, std::move(rows))));
    info.constraints.push_back(k++);
    if (j.drive && !info.planar && j.type == JointType::kRevolute) {
      sb.add(detail::spatial_revolute_drive(j, P, C).mark_drive());
      info.drive = k;
      info.constraints.push_back(k++);
    } else if (j.drive) {
      Row r = info.planar ? detail::planar_drive_row(j, P, C) : detail::spatial_drive_row(j, P, C);
      sb.add(Constraint(j.name + ".drive", ConstraintKind::kHolonomic, 1,
                        std::make_shared<detail::JointModel>(std::vector<BodyRef>{P, C},
                                                             std::vector<Row>{std::move(r)}))
                 .mark_drive());
      info.drive = k;
      info.constraints.push_back(k++);
    }
    if (j.friction.enabled()) {
      sb.add(detail::joint_friction_force(j, P, C, j.name, info.planar));
      info.friction = friction_count++;
    }
    out.joints.push_back(std::move(info));
  }
  // force elements: their bodies and callables
  for (const Force& f : d.forces) {
    for (BodyId id : {f.body_a, f.body_b}) {
      if (id != kGround && (id < 0 || id >= BodyId(out.bodies.size()))) {
        throw std::invalid_argument(who + "force '" + f.name + "': unknown body " +
                                    format_number(id));
      }
    }
    if (f.type == ForceType::kApplied && !f.wrench) {
      throw std::invalid_argument(who + "force '" + f.name + "': empty wrench callable");
    }
    if (f.type == ForceType::kTorsionSpring) {
      // between two oriented bodies of one kind (planar, or rigid and the ground)
      const BodyKind none = BodyKind::kParticle;
      const BodyKind ka = f.body_a == kGround ? none : out.bodies[std::size_t(f.body_a)].kind;
      const BodyKind kb = f.body_b == kGround ? none : out.bodies[std::size_t(f.body_b)].kind;
      const bool particle = (f.body_a != kGround && ka == BodyKind::kParticle) ||
                            (f.body_b != kGround && kb == BodyKind::kParticle);
      const bool mixed = f.body_a != kGround && f.body_b != kGround && ka != kb;
      if (particle || mixed || f.body_a == f.body_b) {
        throw std::invalid_argument(who + "torsion spring '" + f.name +
                                    "' must join two different planar bodies or two rigid "
                                    "bodies (or one and the ground)");
      }
      const bool spatial = ka == BodyKind::kRigid || kb == BodyKind::kRigid;
      if (spatial && f.rest != 0.0) {
        throw std::invalid_argument(who + "torsion spring '" + f.name +
                                    "': between rigid bodies the rest orientation is the "
                                    "bodies' aligned frames (theta0 must be 0)");
      }
    }
  }
  // Coulomb friction at contacts: the contact point's kinematics (after the joints' frictions,
  // whose indices among the non-ideal forces stay theirs)
  for (const Impl::ContactFriction& cf : d.contact_frictions) {
    const std::string what = who + "friction at contact '" + cf.contact + "'";
    const auto j = std::find_if(d.joints.begin(), d.joints.end(),
                                [&](const Joint& x) { return x.name == cf.contact; });
    if (j == d.joints.end() || !is_contact(j->type))
      throw std::invalid_argument(what + ": there is no contact of that name");
    const BodyRef P = detail::body_ref(out.bodies, j->parent);
    const BodyRef C = detail::body_ref(out.bodies, j->child);
    const bool planar = C.kind == BodyKind::kPlanar || (!P.ground() && P.kind == BodyKind::kPlanar);
    CoulombFriction spec;
    spec.constraint = cf.contact;
    spec.mu = cf.mu;
    spec.mu_static = cf.mu_static;
    spec.regularization_velocity = cf.eps;
    // a point or sphere (or a planar model's disk, a circle) on a plane of the ground: the
    // contact point's own velocity; on a plane of a moving body, a spatial disk's rim point,
    // two spheres: the relative velocity of the material points there
    const bool ground_plane = P.ground() && (j->type == JointType::kContact ||
                                             (planar && j->type == JointType::kContactDisk));
    spec.kinematics = ground_plane ? detail::contact_kinematics(*j, C, planar)
                                   : detail::relative_contact_kinematics(*j, P, C, planar, out.q0);
    sb.add(coulomb_friction(spec));
  }
  return MultibodyModel{sb.build(),
                        std::move(out.q0),
                        std::move(out.qd0),
                        std::move(out.bodies),
                        std::move(out.joints),
                        d.g};
}

}  // namespace ukdyn::mb

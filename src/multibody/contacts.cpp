// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts of bodies with a plane or a sphere (docs/contact.md, "Contacts on
// bodies"): the gap row of a point or sphere on a plane (the point_on_plane / point_on_line row
// with the offset c0 = radius), of a thin disk on a plane (a row of its own, Row::kDisk), of a
// sphere outside a sphere (Row::kNorm, |c − o| − (r1 + r2)) or inside one (the same row with the
// sign −1 and the length R − r: (R − r) − |c − o|), of a sphere outside a box (Row::kSphereBox,
// the distance to the box less the radius) — all in closed form in
// kinematics.cpp — and the checks build() makes before it adds them as unilateral constraints
// (the factories mb::contact, mb::contact_disk and mb::contact_spheres: bodies.cpp, with the
// other joints'); and the contact point's kinematics for Coulomb friction there
// (ContactKinematics, docs/contact.md, "Friction at a body's contact"): of a point or sphere on
// a plane of the ground, and relative to the other body's material point otherwise.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "multibody/disk_point.hpp"
#include "multibody/internal.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn::mb::detail {

Row contact_row(const Joint& j, bool planar) {
  if (j.type == JointType::kContactSpheres) {
    // g = |c − o| − (r_C + r_P), c and o the spheres' centres; inside: g = (r_P − r_C) − |c − o|
    Row r;
    r.kind = Row::kNorm;
    r.a = VecExpr::diff(0, j.frame_parent.p, 1, j.frame_child.p);
    const bool inside = j.side == SphereSide::kInside;
    r.length = inside ? j.other_radius - j.radius : j.radius + j.other_radius;
    r.sign = inside ? -1.0 : 1.0;
    return r;
  }
  if (j.type == JointType::kContactDiskSphere) {
    // g = sqrt(s² + m²) − r_P: a = c − o (the disk's centre from the sphere's), its axis on C
    Row r;
    r.kind = Row::kDiskSphere;
    r.a = VecExpr::diff(0, j.frame_parent.p, 1, j.frame_child.p);
    r.axis = VecExpr::body_vector(1, j.frame_child.R.col(2));
    r.length = j.radius;
    r.sphere = j.other_radius;
    return r;
  }
  if (j.type == JointType::kContactSphereBox) {
    // g = sqrt(Σ m_i²) − r: a = c − o (the sphere's centre from the box's), the box's axes on P
    Row r;
    r.kind = Row::kSphereBox;
    r.a = VecExpr::diff(0, j.frame_parent.p, 1, j.frame_child.p);
    r.box_axes = planar ? 2 : 3;
    for (int i = 0; i < r.box_axes; ++i)
      r.box[i] = VecExpr::body_vector(0, j.frame_parent.R.col(i));
    r.half = j.box_half;
    r.length = j.radius;
    return r;
  }
  // d = c − o (the contact's point, or the disk's centre, relative to the plane's point) and the
  // plane's normal n: F_P's z axis (spatial) or y axis (planar)
  Row r;
  r.a = VecExpr::diff(0, j.frame_parent.p, 1, j.frame_child.p);
  r.b = VecExpr::body_vector(0, j.frame_parent.R.col(planar ? 1 : 2));
  if (j.type == JointType::kContactDisk && !planar) {
    // g = n·d − r sqrt(1 − (n·a)²), a the disk's axis
    r.kind = Row::kDisk;
    r.axis = VecExpr::body_vector(1, j.frame_child.R.col(2));
    r.length = j.radius;
    return r;
  }
  // g = n·d − r
  r.kind = Row::kDot;
  r.c.c0 = j.radius;
  return r;
}

}  // namespace ukdyn::mb::detail

namespace ukdyn::mb::detail {

namespace {
// At q: d = c − o, the contact's point (a disk's centre) on C less the plane's point or the
// sphere's centre on P, and k, C's frame_child z axis (a disk's axis), in the world (values
// only). Cost O(1).
void centres_at(const Joint& j, const BodyRef& P, const BodyRef& C, const VectorXd& q, VecKin& d,
                VecKin& k) {
  const VectorXd v = VectorXd::Zero(q.size());
  add_body_vector(C, q, v, j.frame_child.p, true, 1.0, d, nullptr, false);
  add_body_vector(P, q, v, j.frame_parent.p, true, -1.0, d, nullptr, false);
  add_body_vector(C, q, v, j.frame_child.R.col(2), false, 1.0, k, nullptr, false);
}

// At q: the gap of a sphere against a box (values only): d = c − o as centres_at's, the box's
// axes on P. Cost O(1).
SphereBoxGap sphere_box_at(const Joint& j, const BodyRef& P, const BodyRef& C, const VectorXd& q,
                           bool planar) {
  const VectorXd v = VectorXd::Zero(q.size());
  VecKin d, unused, axes[3];
  centres_at(j, P, C, q, d, unused);
  const int n = planar ? 2 : 3;
  for (int i = 0; i < n; ++i)
    add_body_vector(P, q, v, j.frame_parent.R.col(i), false, 1.0, axes[i], nullptr, false);
  return sphere_box_gap(d, axes, n, j.box_half, j.radius, false);
}
}  // namespace

Constraint contact_constraint(const Joint& j, const BodyRef& P, const BodyRef& C, bool planar,
                              const VectorXd& q0) {
  const std::string who = "ukdyn::mb::Multibody::build: contact '" + j.name + "'";
  const bool disk_sphere = j.type == JointType::kContactDiskSphere;
  const bool disk = j.type == JointType::kContactDisk || disk_sphere;
  const bool spheres = j.type == JointType::kContactSpheres || disk_sphere;
  if (C.ground()) {
    throw std::invalid_argument(who + ": its body is the ground (a contact holds a body)");
  }
  if (!(j.radius >= 0.0) || !std::isfinite(j.radius) || (disk && !(j.radius > 0.0))) {
    throw std::invalid_argument(who + ": the radius must be " + (disk ? "> 0" : ">= 0") + ", got " +
                                format_number(j.radius, 3));
  }
  if (spheres && (!(j.other_radius >= 0.0) || !std::isfinite(j.other_radius))) {
    throw std::invalid_argument(who + ": the other sphere's radius must be >= 0, got " +
                                format_number(j.other_radius, 3));
  }
  if (spheres && j.side == SphereSide::kInside && !(j.radius < j.other_radius)) {
    throw std::invalid_argument(who + ": a sphere of radius " + format_number(j.radius, 3) +
                                " does not fit inside one of radius " +
                                format_number(j.other_radius, 3) +
                                " (inside: the other sphere's radius must be the larger)");
  }
  if (spheres && P.id == C.id) {
    throw std::invalid_argument(who + ": both " +
                                (disk_sphere ? "the disk and the sphere" : "spheres") +
                                " are on one body (a contact is between two)");
  }
  if (disk_sphere && planar) {
    throw std::invalid_argument(who +
                                ": a disk in a planar model is a circle: use a sphere contact "
                                "(contact_spheres) with its radius");
  }
  if (j.type == JointType::kContactSphereBox) {
    const Vector3d& h = j.box_half;
    if (!(h.head(planar ? 2 : 3).minCoeff() > 0.0) || !h.head(planar ? 2 : 3).allFinite()) {
      throw std::invalid_argument(who + ": the box's half-extents must be finite and > 0, got [" +
                                  format_number(h.x(), 3) + ", " + format_number(h.y(), 3) +
                                  (planar ? "" : ", " + format_number(h.z(), 3)) + "]");
    }
    if (P.id == C.id) {
      throw std::invalid_argument(who +
                                  ": the sphere and the box are on one body (a contact is "
                                  "between two)");
    }
    // the sphere's centre in (or on) the box has no normal: refused at the start
    if (sphere_box_at(j, P, C, q0, planar).inside) {
      throw std::invalid_argument(
          who +
          ": the sphere's centre lies inside the box at the start: the contact has no normal "
          "there; place the sphere apart (its gap, the distance from its centre to the box "
          "minus its radius, must be >= 0)");
    }
  }
  if (!(j.restitution >= 0.0 && j.restitution <= 1.0)) {
    throw std::invalid_argument(who + ": the restitution must lie in [0, 1], got " +
                                format_number(j.restitution, 3));
  }
  if (j.drive || j.friction.enabled()) {
    throw std::invalid_argument(who +
                                ": a contact takes no drive and no joint friction (Coulomb "
                                "friction at a contact: docs/contact.md)");
  }
  if (disk && !planar && C.kind != BodyKind::kRigid) {
    throw std::invalid_argument(who + ": a disk has an axis, so its body must be rigid, not a " +
                                "particle (a particle takes a point or sphere contact)");
  }
  Row row = contact_row(j, planar);
  if (row.kind == Row::kDisk) {
    // a disk lying flat has no single lowest point (h = 0): refused at the start
    const Vector3d n = rotation_WB(P, q0) * j.frame_parent.R.col(2);
    const Vector3d a = rotation_WB(C, q0) * j.frame_child.R.col(2);
    const double s = n.dot(a);
    if (std::abs(s) > 1.0 - 1e-6) {
      throw std::invalid_argument(
          who + ": the disk lies flat on its plane at the start (|n·a| = " +
          format_number(std::abs(s), 9) +
          "): it has no single lowest point there; tilt it (orientation:) or model it as a "
          "point contact at each of a few rim points");
    }
  }
  if (row.kind == Row::kNorm) {
    // coincident centres have no normal: refused at the start; inside, so is a centre outside
    // the other sphere (|c − o| > R: on its far side, not a small penetration)
    // (coincident to the roundoff of the centres' positions, whatever the radii: a bowl of
    // R = 1e12 around a ball 0.3 from its centre has a normal)
    const Vector3d c = body_vector_generic<double>(C, q0, j.frame_child.p, true);
    const Vector3d o = body_vector_generic<double>(P, q0, j.frame_parent.p, true);
    const Vector3d d = c - o;
    const bool inside = row.sign < 0.0;
    if (!(d.norm() > 1e-12 * std::max({c.norm(), o.norm(), 1e-300}))) {
      throw std::invalid_argument(
          who + ": the spheres' centres coincide at the start: the contact has no normal there; " +
          (inside ? "move the inner sphere off the other's centre (its gap (R − r) − |c − o| "
                    "must be >= 0)"
                  : "place the spheres apart (their gap |c − o| − (r1 + r2) must be >= 0)"));
    }
    if (inside && d.norm() > j.other_radius) {
      throw std::invalid_argument(
          who + ": the inner sphere's centre starts outside the other sphere (|c − o| = " +
          format_number(d.norm(), 6) + " > R = " + format_number(j.other_radius, 6) +
          "); place it inside (|c − o| <= R − r), or leave inside out for a sphere that stays "
          "outside");
    }
  }
  if (row.kind == Row::kDiskSphere) {
    // the sphere's centre on the disk's rim has no normal: refused at the start
    VecKin e, k;
    centres_at(j, P, C, q0, e, k);
    const DiskSphereGap d = disk_sphere_gap(e, k, j.radius, j.other_radius, false);
    if (!(d.g + j.other_radius > 1e-12 * std::max({j.radius, e.x.norm(), 1e-300}))) {
      throw std::invalid_argument(
          who +
          ": the sphere's centre lies on the disk's rim at the start: the contact has no "
          "normal there; place the sphere apart (its gap, the distance from its centre to "
          "the disk minus its radius, must be >= 0)");
    }
  }
  Constraint c(j.name, ConstraintKind::kHolonomic, 1,
               std::make_shared<JointModel>(std::vector<BodyRef>{P, C}, std::vector<Row>{row}));
  c.unilateral(j.restitution);
  if (j.restitution_law != RestitutionLaw::kNewton) c = with_restitution_law(c, j.restitution_law);
  return c;
}

}  // namespace ukdyn::mb::detail

namespace ukdyn::mb::detail {

ContactKinematics contact_kinematics(const Joint& j, const BodyRef& C, bool planar) {
  // the plane's unit normal n and tangents t_i in the world (a ground plane: constant)
  const Matrix3d& R = j.frame_parent.R;
  const Vector3d n = R.col(planar ? 1 : 2).normalized();
  const Vector3d t1 = R.col(0).normalized(), t2 = planar ? Vector3d::Zero() : R.col(1).normalized();
  const Vector3d p = j.frame_child.p;  // the sphere's centre (or the point) on the body
  const Vector3d a = -j.radius * n;    // from the centre to the contact point
  ContactKinematics kin;
  kin.tangents = planar ? 1 : 2;
  for (Index i = 0; i < C.size(); ++i) kin.columns.push_back(C.offset + i);
  const BodyRef body = C;
  // J = [n; t_i]ᵀ J_P and bias = [n; t_i]ᵀ J_P' q' with v_P = v(centre) + ω × a:
  //   particle: J_P = I, bias 0 (its point does not turn);
  //   planar:   J_P = [e_x, e_y, e_z × (R p + a)], bias −θ'² R p (ω' = 0 at θ'' = 0);
  //   rigid:    J_P = [I, D(u, p) − 2 [a]× G_v(u)], bias 2 R(u') p (ω' = 2 G_v(u') u' = 0)
  kin.evaluate = [body, n, t1, t2, p, a, planar](const Eigen::Ref<const VectorXd>& q,
                                                 const Eigen::Ref<const VectorXd>& qd, double,
                                                 ConstraintScratch*, Eigen::Ref<MatrixXd> J,
                                                 Eigen::Ref<VectorXd> bias) {
    Eigen::Matrix<double, 3, 7> JP = Eigen::Matrix<double, 3, 7>::Zero();
    Vector3d g = Vector3d::Zero();
    const Index o = body.offset;
    switch (body.kind) {
      case BodyKind::kParticle:
        JP.leftCols<3>().setIdentity();
        break;
      case BodyKind::kPlanar: {
        const double th = q[o + 2], w = qd[o + 2], c = std::cos(th), sn = std::sin(th);
        const Vector3d rp(c * p.x() - sn * p.y(), sn * p.x() + c * p.y(), 0.0);
        const Vector3d arm = rp + a;
        JP(0, 0) = 1.0;
        JP(1, 1) = 1.0;
        JP(0, 2) = -arm.y();
        JP(1, 2) = arm.x();
        g = -w * w * rp;
        break;
      }
      case BodyKind::kRigid: {
        const Vector4d u = q.segment<4>(o + 3), ud = qd.segment<4>(o + 3);
        Matrix3d A;  // [a]×
        A << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
        JP.leftCols<3>().setIdentity();
        JP.rightCols<4>() = rotate_jacobian(u, p) - 2.0 * A * G_v(u);
        g = 2.0 * rotate(ud, p);
        break;
      }
    }
    const Index cols = J.cols();
    J.row(0) = n.transpose() * JP.leftCols(cols);
    J.row(1) = t1.transpose() * JP.leftCols(cols);
    bias[0] = n.dot(g);
    bias[1] = t1.dot(g);
    if (!planar) {
      J.row(2) = t2.transpose() * JP.leftCols(cols);
      bias[2] = t2.dot(g);
    }
  };
  return kin;
}

}  // namespace ukdyn::mb::detail

namespace ukdyn::mb::detail {

namespace {
// J_ω (3 × 7) of body b's angular velocity ω = J_ω q' (the body's coordinates): planar e_z on
// θ, rigid 2 G_v(u) (as the ground-plane kinematics take it), none for a particle or the ground
Eigen::Matrix<double, 3, 7> omega_jacobian(const BodyRef& b, const Eigen::Ref<const VectorXd>& q) {
  Eigen::Matrix<double, 3, 7> Jw = Eigen::Matrix<double, 3, 7>::Zero();
  if (b.ground()) return Jw;
  if (b.kind == BodyKind::kPlanar) Jw(2, 2) = 1.0;
  if (b.kind == BodyKind::kRigid) Jw.rightCols<4>() = 2.0 * G_v(q.segment<4>(b.offset + 3));
  return Jw;
}
}  // namespace

namespace {
// |e·n| beyond which a sphere's tangents are taken from the world axis least aligned with n
// instead of e (cos 25.8°: |e × n| >= 0.436, the rate of t_1 at most 2.3 |n'|)
constexpr double kTangentSwitch = 0.9;
}  // namespace

ContactKinematics relative_contact_kinematics(const Joint& j, const BodyRef& P, const BodyRef& C,
                                              bool planar, const VectorXd& q0) {
  // the plane's normal and tangents on P, the plane's point on P, the centre (and a disk's axis)
  // on C
  const Matrix3d& R = j.frame_parent.R;
  const Vector3d nP = R.col(planar ? 1 : 2).normalized();
  const Vector3d t1P = R.col(0).normalized(),
                 t2P = planar ? Vector3d::Zero() : R.col(1).normalized();
  const Vector3d pP = j.frame_parent.p, pC = j.frame_child.p, kC = j.frame_child.R.col(2);
  const bool disk = j.type == JointType::kContactDisk && !planar;
  const bool disk_sphere = j.type == JointType::kContactDiskSphere;
  const bool spheres = j.type == JointType::kContactSpheres;
  const bool sphere_box = j.type == JointType::kContactSphereBox;
  const int box_axes = planar ? 2 : 3;
  const Matrix3d box_R = j.frame_parent.R;
  const Vector3d box_half = j.box_half;
  // (a sphere inside the other: n = −d/|d|, towards the centre o)
  const double r = j.radius, r_P = j.other_radius;
  const double side = j.side == SphereSide::kInside ? -1.0 : 1.0;
  // two spheres: n = ±d/|d| and t_1 = e × n/|e × n|, t_2 = n × t_1 from the world axis e least
  // aligned with n at the start (planar: t_1 = n × e_z); where n comes near e, the axis least
  // aligned with n then (a disk and a sphere: n from disk_sphere_gap, the same tangents)
  Vector3d e = Vector3d::UnitZ();
  if ((spheres || disk_sphere || sphere_box) && !planar) {
    VecKin d0, k0;
    centres_at(j, P, C, q0, d0, k0);
    const Vector3d n0 = disk_sphere  ? disk_sphere_gap(d0, k0, r, r_P, false).n
                        : sphere_box ? sphere_box_at(j, P, C, q0, planar).n
                                     : d0.x;
    Index axis = 0;
    n0.cwiseAbs().minCoeff(&axis);
    e = Vector3d::Unit(axis);
  }
  // columns: the two bodies' coordinates, increasing; each body's first local column
  ContactKinematics kin;
  kin.tangents = planar ? 1 : 2;
  const bool p_first = P.offset < C.offset;
  for (const BodyRef* b : {p_first ? &P : &C, p_first ? &C : &P})
    for (Index i = 0; i < b->size(); ++i) kin.columns.push_back(b->offset + i);
  BodyRef Pl = P, Cl = C;
  Pl.local = p_first ? 0 : C.size();
  Cl.local = p_first ? P.size() : 0;
  kin.evaluate = [Pl, Cl, nP, t1P, t2P, pP, pC, kC, e, r, r_P, side, planar, disk, disk_sphere,
                  spheres, sphere_box, box_axes, box_R,
                  box_half](const Eigen::Ref<const VectorXd>& q,
                            const Eigen::Ref<const VectorXd>& qd, double, ConstraintScratch*,
                            Eigen::Ref<MatrixXd> J, Eigen::Ref<VectorXd> bias) {
    // n, t_i (vectors of P), p (P's point), c (C's centre), k (the disk's axis): value, rate,
    // Jacobian and bias
    VecKin n, t1, t2, p, c, k;
    add_body_vector(Pl, q, qd, pP, true, 1.0, p);
    add_body_vector(Cl, q, qd, pC, true, 1.0, c);
    if (disk || disk_sphere) add_body_vector(Cl, q, qd, kC, false, 1.0, k);
    // (a disk and a sphere, a sphere and a box) d = c − p with its Jacobian and bias
    VecKin dk{VecKin::Unset{}};
    if (disk_sphere || sphere_box) {
      dk.x = c.x - p.x;
      dk.v = c.v - p.v;
      dk.J = c.J - p.J;
      dk.g = c.g - p.g;
    }
    DiskSphereGap ds;
    if (disk_sphere) ds = disk_sphere_gap(dk, k, r, r_P, true);
    SphereBoxGap sb;
    if (sphere_box) {
      VecKin axes[3];  // the box's axes on P
      for (int i = 0; i < box_axes; ++i)
        add_body_vector(Pl, q, qd, box_R.col(i), false, 1.0, axes[i]);
      sb = sphere_box_gap(dk, axes, box_axes, box_half, r, true);
    }
    if (spheres || disk_sphere || sphere_box) {
      // n = ±d/|d| (a disk: disk_sphere_gap's) and its rate; t_i from e (values and rates;
      // their J and g are not needed)
      if (disk_sphere) {
        n.x = ds.n;
        n.v = ds.n_rate;
      } else if (sphere_box) {
        n.x = sb.n;
        n.v = sb.n_rate;
      } else {
        const Vector3d d = c.x - p.x, dd = c.v - p.v;
        const double len = d.norm();
        const Vector3d u = d / len;
        n.x = side * u;
        n.v = side * (dd - u.dot(dd) * u) / len;
      }
      if (planar) {
        t1.x = n.x.cross(Vector3d::UnitZ());
        t1.v = n.v.cross(Vector3d::UnitZ());
      } else {
        // (e, or where n comes within 25.8° of it — a ball rolling over a box's edge, from its top
        // face, e = x, to its side face, n = x: NaN, u22 04 — the world axis least aligned
        // with n now: the tangents turn by a step there, the friction and the stick rows do not)
        Vector3d e_n = e;
        if (std::abs(e.dot(n.x)) > kTangentSwitch) {
          Index axis = 0;
          n.x.cwiseAbs().minCoeff(&axis);
          e_n = Vector3d::Unit(axis);
        }
        const Vector3d w = e_n.cross(n.x), wd = e_n.cross(n.v);
        const double wl = w.norm();
        t1.x = w / wl;
        t1.v = (wd - t1.x.dot(wd) * t1.x) / wl;
        t2.x = n.x.cross(t1.x);
        t2.v = n.v.cross(t1.x) + n.x.cross(t1.v);
      }
    } else {
      add_body_vector(Pl, q, qd, nP, false, 1.0, n);
      add_body_vector(Pl, q, qd, t1P, false, 1.0, t1);
      if (!planar) add_body_vector(Pl, q, qd, t2P, false, 1.0, t2);
    }
    // the two bodies' J_ω on the local columns and their ω
    JacobianRow JwP = JacobianRow::Zero(), JwC = JacobianRow::Zero();
    Eigen::Matrix<double, kMaxCols, 1> v = Eigen::Matrix<double, kMaxCols, 1>::Zero();
    if (!Pl.ground()) {
      JwP.middleCols(Pl.local, Pl.size()) = omega_jacobian(Pl, q).leftCols(Pl.size());
      v.segment(Pl.local, Pl.size()) = qd.segment(Pl.offset, Pl.size());
    }
    JwC.middleCols(Cl.local, Cl.size()) = omega_jacobian(Cl, q).leftCols(Cl.size());
    v.segment(Cl.local, Cl.size()) = qd.segment(Cl.offset, Cl.size());
    const Vector3d wP = JwP * v, wC = JwC * v;
    // a: the centre to the contact point, −r n (point, sphere) or −r m/|m| with m = n − s k,
    // s = n·k (a disk's rim point most opposed to n), and its rate a' along q'
    const Vector3d d = c.x - p.x, dd = c.v - p.v;
    Vector3d a = -r * n.x, ad = -r * n.v;
    double s = 0.0, sd = 0.0;  // n·k and its rate (the disk's row below)
    if (disk) {
      s = n.x.dot(k.x);
      sd = n.v.dot(k.x) + n.x.dot(k.v);
      disk_lowest_point(n.x, n.v, k.x, k.v, r, a, ad);
    }
    if (disk_sphere) {
      // the disk's point nearest the sphere's centre
      a = ds.a;
      ad = ds.a_rate;
    }
    // v_rel = c' + ω_C × a − p' − ω_P × (d + a), its Jacobian and its rate at q'' = 0 (ω' = 0
    // there: planar θ'' = 0, rigid 2 G_v(u') u' = 0)
    const Vector3d arm = d + a;
    const Vector3d v_rel = dd + wC.cross(a) - wP.cross(arm);
    Matrix3d Ac, Arm;  // [a]×, [d + a]×
    Ac << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
    Arm << 0, -arm.z(), arm.y(), arm.z(), 0, -arm.x(), -arm.y(), arm.x(), 0;
    const JacobianRow Jrel = c.J - p.J - Ac * JwC + Arm * JwP;
    const Vector3d a_rel = c.g - p.g + wC.cross(ad) - wP.cross(dd + ad);
    // row 0: the gap's gradient, g = n·d − r (point, sphere), n·d − r sqrt(1 − s²) (disk),
    // |d| − (r + r_P) (two spheres: n = d/|d|, ∂n/∂q d = 0) or (r_P − r) − |d| (inside:
    // n = −d/|d|), and its bias g'' at q'' = 0
    const Index cols = J.cols();
    Eigen::Matrix<double, 1, kMaxCols> g_q = n.x.transpose() * (c.J - p.J);
    bias[0] = n.x.dot(c.g - p.g) + n.v.dot(dd);
    if (disk_sphere) {
      // g = sqrt(s² + m²) − r_P (disk_sphere_gap: g'' = A q'' − b)
      g_q = ds.A;
      bias[0] = -ds.b;
    } else if (sphere_box) {
      // g = sqrt(Σ m_i²) − r (sphere_box_gap: g'' = A q'' − b)
      g_q = sb.A;
      bias[0] = -sb.b;
    } else if (!spheres) {
      g_q += d.transpose() * n.J;
      bias[0] += n.g.dot(d) + n.v.dot(dd);
    }
    if (disk) {
      // f(s) = −r sqrt(1 − s²): f' = r s / sqrt(1 − s²), f'' = r / (1 − s²)^(3/2)
      const double h = std::sqrt(1.0 - s * s), f1 = r * s / h, f2 = r / (h * h * h);
      const double sdd = n.g.dot(k.x) + 2.0 * n.v.dot(k.v) + n.x.dot(k.g);
      g_q += f1 * (k.x.transpose() * n.J + n.x.transpose() * k.J);
      bias[0] += f2 * sd * sd + f1 * sdd;
    }
    J.row(0) = g_q.leftCols(cols);
    J.row(1) = (t1.x.transpose() * Jrel).leftCols(cols);
    bias[1] = t1.v.dot(v_rel) + t1.x.dot(a_rel);
    if (!planar) {
      J.row(2) = (t2.x.transpose() * Jrel).leftCols(cols);
      bias[2] = t2.v.dot(v_rel) + t2.x.dot(a_rel);
    }
  };
  return kin;
}

}  // namespace ukdyn::mb::detail

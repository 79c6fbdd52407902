// SPDX-License-Identifier: BSD-3-Clause
// Rolling without slipping of a thin disk or a sphere (a rigid body) on the plane z = 0: the
// contact height (holonomic) and the contact point's horizontal velocity (nonholonomic). A and b
// come from forward-mode automatic differentiation of these functions on the body's seven
// coordinates only (LocalAutodiffModel), so their cost does not depend on the system's size.
#include <stdexcept>

#include "multibody/internal.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn::mb::detail {
namespace {

// the disk's axis a = R(u) n and the vector c from the centre to the contact point,
// c = −R h / |h| with h = e_z − (a · e_z) a (the steepest descent in the disk's plane)
template <class S, class V>
Vec3<S> disk_contact(const V& q, const Vector3d& n, double radius) {
  const S& w = q[3];
  Vec3<S> e;
  e << q[4], q[5], q[6];
  const Vec3<S> nv = n.cast<S>();
  const Vec3<S> a = (w * w - e.dot(e)) * nv + (2.0 * e.dot(nv)) * e + (2.0 * w) * e.cross(nv);
  Vec3<S> h = -a[2] * a;
  h[2] += 1.0;
  using std::sqrt;
  const S norm = sqrt(h.dot(h));
  return (-radius / norm) * h;
}

// ω_W = 2 (u0 e' − u0' e + e × e')
template <class S, class V>
Vec3<S> omega_world(const V& q, const V& qd) {
  Vec3<S> e, ed;
  e << q[4], q[5], q[6];
  ed << qd[4], qd[5], qd[6];
  const S& w = q[3];
  const S& wd = qd[3];
  return 2.0 * (w * ed - wd * e + e.cross(ed));
}

}  // namespace

std::vector<Constraint> rolling_constraints(const Joint& j, const BodyRef& C) {
  if (C.ground() || C.kind != BodyKind::kRigid) {
    throw std::invalid_argument("ukdyn::mb::Multibody::build: joint '" + j.name +
                                "': a rolling contact needs a rigid body as its child");
  }
  if (!(j.radius > 0.0)) {
    throw std::invalid_argument("ukdyn::mb::Multibody::build: joint '" + j.name +
                                "': the radius must be > 0, got " + format_number(j.radius));
  }
  std::vector<Index> cols;
  for (Index i = 0; i < 7; ++i) cols.push_back(C.offset + i);
  const double R = j.radius;
  std::vector<Constraint> out;
  if (j.type == JointType::kRollingDisk) {
    const Vector3d n = j.frame_child.R.col(2);
    // height: z of the contact point = r_z + c_z = 0
    auto height = [n, R](const auto& q, const auto&, auto& phi) {
      using S = typename std::decay_t<decltype(phi)>::Scalar;
      const Vec3<S> c = disk_contact<S>(q, n, R);
      phi[0] = q[2] + c[2];
    };
    // no slip: (r' + ω × c)_xy = 0
    auto slip = [n, R](const auto& q, const auto& qd, const auto&, auto& psi) {
      using S = typename std::decay_t<decltype(psi)>::Scalar;
      const Vec3<S> c = disk_contact<S>(q, n, R);
      const Vec3<S> vp = omega_world<S>(q, qd).cross(c);
      psi[0] = qd[0] + vp[0];
      psi[1] = qd[1] + vp[1];
    };
    out.emplace_back(j.name + ".contact", ConstraintKind::kHolonomic, 1,
                     std::make_shared<LocalAutodiffModel>(
                         cols, std::make_shared<ad::HolonomicModel<decltype(height)>>(1, height)));
    out.emplace_back(j.name, ConstraintKind::kNonholonomic, 2,
                     std::make_shared<LocalAutodiffModel>(
                         cols, std::make_shared<ad::NonholonomicModel<decltype(slip)>>(2, slip)));
    return out;
  }
  // sphere: r_z = R (closed form), (r' + ω × (−R e_z))_xy = (x' − R ω_y, y' + R ω_x) = 0
  Row h;
  h.kind = Row::kLinear;
  h.terms = {{C.offset + 2, 1.0}};
  h.c.c0 = R;
  out.emplace_back(j.name + ".contact", ConstraintKind::kHolonomic, 1,
                   std::make_shared<JointModel>(std::vector<BodyRef>{C}, std::vector<Row>{h}));
  auto slip = [R](const auto& q, const auto& qd, const auto&, auto& psi) {
    using S = typename std::decay_t<decltype(psi)>::Scalar;
    const Vec3<S> w = omega_world<S>(q, qd);
    psi[0] = qd[0] - R * w[1];
    psi[1] = qd[1] + R * w[0];
  };
  out.emplace_back(j.name, ConstraintKind::kNonholonomic, 2,
                   std::make_shared<LocalAutodiffModel>(
                       cols, std::make_shared<ad::NonholonomicModel<decltype(slip)>>(2, slip)));
  return out;
}

}  // namespace ukdyn::mb::detail

// SPDX-License-Identifier: BSD-3-Clause
// Joint-angle constraints of spatial revolute joints: a prescribed angle (rheonomic, holonomic)
// and a gear between two joints (velocity level). The angle of F_C about z_P is
// atan2((x_P × x_C) · z_P, x_P · x_C), not a dot product, so these rows are written once as
// generic functions and differentiated by forward-mode AD on the bodies' own coordinates
// (LocalAutodiffModel): the cost does not depend on the system's size.
#include <algorithm>
#include <stdexcept>

#include "multibody/internal.hpp"

namespace ukdyn::mb::detail {
namespace {

// the bodies' coordinates (each body once, by increasing offset) and the bodies re-based on them
std::vector<BodyRef> localize(const std::vector<BodyRef>& bodies, std::vector<Index>& cols) {
  std::vector<Index> order;
  for (const BodyRef& b : bodies) {
    if (!b.ground()) order.push_back(b.offset);
  }
  std::sort(order.begin(), order.end());
  order.erase(std::unique(order.begin(), order.end()), order.end());
  std::vector<BodyRef> out = bodies;
  cols.clear();
  for (Index o : order) {
    const Index local = Index(cols.size());
    Index size = 0;
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      if (bodies[i].offset == o) {
        out[i].offset = local;
        size = bodies[i].size();
      }
    }
    for (Index i = 0; i < size; ++i) cols.push_back(o + i);
  }
  return out;
}

// ω_W of a body at generic (q, q'): rigid 2 (u0 e' − u0' e + e × e'), planar (0, 0, theta')
template <class S, class V>
Vec3<S> omega_generic(const BodyRef& b, const V& q, const V& qd) {
  Vec3<S> w;
  w.setZero();
  if (b.ground() || b.kind == BodyKind::kParticle) return w;
  const Index o = b.offset;
  if (b.kind == BodyKind::kPlanar) {
    w[2] = qd[o + 2];
    return w;
  }
  Vec3<S> e, ed;
  e << q[o + 4], q[o + 5], q[o + 6];
  ed << qd[o + 4], qd[o + 5], qd[o + 6];
  const S& u0 = q[o + 3];
  const S& u0d = qd[o + 3];
  return 2.0 * (u0 * ed - u0d * e + e.cross(ed));
}

void require_spatial_revolute(const Joint& j, const BodyRef& P, const BodyRef& C,
                              const char* what) {
  const auto rigid_or_ground = [](const BodyRef& b) {
    return b.ground() || b.kind == BodyKind::kRigid;
  };
  if (j.type != JointType::kRevolute || !rigid_or_ground(P) || !rigid_or_ground(C)) {
    throw std::invalid_argument("ukdyn::mb::Multibody::build: joint '" + j.name + "': " + what +
                                " needs a revolute joint between rigid bodies (or the ground)");
  }
}

}  // namespace

Constraint spatial_revolute_drive(const Joint& j, const BodyRef& P, const BodyRef& C) {
  require_spatial_revolute(j, P, C, "an angle drive");
  std::vector<Index> cols;
  const std::vector<BodyRef> loc = localize({P, C}, cols);
  const BodyRef Pl = loc[0], Cl = loc[1];
  const Vector3d xPb = j.frame_parent.R.col(0), zPb = j.frame_parent.R.col(2);
  const Vector3d xCb = j.frame_child.R.col(0);
  const auto motion = std::make_shared<const MotionFn>(j.drive);
  // phi = the angle error wrapped to (−pi, pi): with se = sin(angle − f), ce = cos(angle − f)
  // (times the same positive factor r = sqrt(se² + ce²)), by the half angle:
  // phi = 2 asin(se / sqrt(2 r (r + ce))). (Eigen's AD atan2 allocates: its derivative vector is
  // dynamic; its AD has no atan.)
  auto f = [Pl, Cl, xPb, zPb, xCb, motion](const auto& q, const auto& t, auto& phi) {
    using S = typename std::decay_t<decltype(phi)>::Scalar;
    using std::asin;
    using std::cos;
    using std::sin;
    using std::sqrt;
    const Vec3<S> xp = body_vector_generic<S>(Pl, q, xPb, false);
    const Vec3<S> zp = body_vector_generic<S>(Pl, q, zPb, false);
    const Vec3<S> xc = body_vector_generic<S>(Cl, q, xCb, false);
    const S c = xp.dot(xc), s = xp.cross(xc).dot(zp);
    // f(t) to second order about the value of t (all a second-order forward pass sees)
    const double t0 = value_of(t);
    const Vector3d F = (*motion)(t0);
    const S dt = t - t0;
    const S fa = F[0] + F[1] * dt + 0.5 * F[2] * dt * dt;
    const S cf = cos(fa), sf = sin(fa);
    const S se = s * cf - c * sf, ce = c * cf + s * sf;
    const S r = sqrt(se * se + ce * ce);
    phi[0] = 2.0 * asin(se / sqrt(2.0 * r * (r + ce)));
  };
  return Constraint(j.name + ".drive", ConstraintKind::kHolonomic, 1,
                    std::make_shared<LocalAutodiffModel>(
                        cols, std::make_shared<ad::HolonomicModel<decltype(f)>>(1, f)));
}

Constraint spatial_gear(const Joint& gear, const Joint& a, const BodyRef& Pa, const BodyRef& Ca,
                        const Joint& b, const BodyRef& Pb, const BodyRef& Cb) {
  require_spatial_revolute(a, Pa, Ca, "a spatial gear");
  require_spatial_revolute(b, Pb, Cb, "a spatial gear");
  std::vector<Index> cols;
  const std::vector<BodyRef> loc = localize({Pa, Ca, Pb, Cb}, cols);
  const Vector3d za = a.frame_parent.R.col(2), zb = b.frame_parent.R.col(2);
  const double ratio = gear.ratio;
  // psi = (ω_Ca − ω_Pa) · z_Pa − ratio (ω_Cb − ω_Pb) · z_Pb
  auto f = [loc, za, zb, ratio](const auto& q, const auto& qd, const auto&, auto& psi) {
    using S = typename std::decay_t<decltype(psi)>::Scalar;
    const Vec3<S> axis_a = body_vector_generic<S>(loc[0], q, za, false);
    const Vec3<S> axis_b = body_vector_generic<S>(loc[2], q, zb, false);
    const S wa = (omega_generic<S>(loc[1], q, qd) - omega_generic<S>(loc[0], q, qd)).dot(axis_a);
    const S wb = (omega_generic<S>(loc[3], q, qd) - omega_generic<S>(loc[2], q, qd)).dot(axis_b);
    psi[0] = wa - ratio * wb;
  };
  return Constraint(gear.name, ConstraintKind::kNonholonomic, 1,
                    std::make_shared<LocalAutodiffModel>(
                        cols, std::make_shared<ad::NonholonomicModel<decltype(f)>>(1, f)));
}

}  // namespace ukdyn::mb::detail

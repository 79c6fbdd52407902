// SPDX-License-Identifier: BSD-3-Clause
// Force elements: gravity, spring-dampers between body points, torsional springs, applied
// wrenches, the quaternions' velocity terms (gyroscopic), and joint friction (non-ideal).
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "multibody/internal.hpp"
#include "ukdyn/core/system.hpp"

namespace ukdyn::mb::detail {
namespace {

// world position and velocity of body point s (a planar body's cos and sin from the cache)
std::pair<Vector3d, Vector3d> point_state(const BodyRef& b, const Eigen::Ref<const VectorXd>& q,
                                          const Eigen::Ref<const VectorXd>& qd, const Vector3d& s,
                                          PoseCache* cache) {
  VecKin k;
  add_body_vector(b, q, qd, s, true, 1.0, k, cache);
  return {k.x, k.v};
}

struct ForceData {
  std::vector<BodyInfo> bodies;
  std::vector<Force> forces;
  std::vector<BodyRef> a, b;  // per force
  Vector3d g;
  VectorXd Q_gravity;           // (n) the gravity part of Q, as make_forces would sum it on zero
  std::vector<BodyInfo> rigid;  // the rigid bodies (their quaternions' velocity terms)
};

std::shared_ptr<const ForceData> force_data(const std::vector<BodyInfo>& bodies,
                                            const std::vector<Force>& forces, const Vector3d& g) {
  auto d = std::make_shared<ForceData>();
  d->bodies = bodies;
  d->forces = forces;
  d->g = g;
  for (const Force& f : forces) {
    d->a.push_back(body_ref(bodies, f.body_a));
    d->b.push_back(body_ref(bodies, f.body_b));
  }
  // gravity m g on each centre of mass, added to zeros exactly as each evaluation did before
  Index n = 0;
  for (const BodyInfo& b : bodies) n = std::max(n, b.offset + b.size);
  d->Q_gravity = VectorXd::Zero(n);
  for (const BodyInfo& b : bodies) {
    const Index o = b.offset;
    if (b.kind == BodyKind::kPlanar) {
      d->Q_gravity[o] += b.mass * g.x();
      d->Q_gravity[o + 1] += b.mass * g.y();
    } else {
      d->Q_gravity.segment<3>(o) += b.mass * g;
    }
    if (b.kind == BodyKind::kRigid) d->rigid.push_back(b);
  }
  return d;
}

// relative rotation of b with respect to a as a world-frame rotation vector theta n (|theta| <=
// pi): R_WB(b) = R_WB(a) R(n_a, theta), n = R_WB(a) n_a
Vector3d relative_rotation_W(const BodyRef& A, const BodyRef& B,
                             const Eigen::Ref<const VectorXd>& q, PoseCache* cache) {
  const Matrix3d Ra = rotation_WB(A, q, cache);
  const Eigen::AngleAxisd rel(Matrix3d(Ra.transpose() * rotation_WB(B, q, cache)));
  return Ra * (rel.angle() * rel.axis());
}

bool spatial(const BodyRef& A, const BodyRef& B) {
  return A.kind == BodyKind::kRigid || B.kind == BodyKind::kRigid;
}

}  // namespace

ForceScratchFn make_forces(const std::vector<BodyInfo>& bodies, const std::vector<Force>& forces,
                           const Vector3d& g) {
  auto d = force_data(bodies, forces, g);
  return [d](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double t,
             CallableScratch* scratch, Eigen::Ref<VectorXd> Q) {
    PoseCache* const cache = pose_cache(scratch);
    // gravity m g on each centre of mass (summed once); the quaternions' velocity terms
    Q = d->Q_gravity;
    for (const BodyInfo& b : d->rigid) {
      const Index o = b.offset;
      Q.segment<4>(o + 3) +=
          quaternion_velocity_force(q.segment<4>(o + 3), qd.segment<4>(o + 3), b.inertia);
    }
    for (std::size_t i = 0; i < d->forces.size(); ++i) {
      const Force& f = d->forces[i];
      const BodyRef &A = d->a[i], &B = d->b[i];
      switch (f.type) {
        case ForceType::kSpringDamper: {
          // F on b = −(k (l − l0) + c l') n,  n = (x_b − x_a)/l
          const auto [xa, va] = point_state(A, q, qd, f.point_a, cache);
          const auto [xb, vb] = point_state(B, q, qd, f.point_b, cache);
          const Vector3d dx = xb - xa;
          const double l = dx.norm();
          if (l == 0.0) break;
          const Vector3d n = dx / l;
          const double ld = n.dot(vb - va);
          const Vector3d F = -(f.stiffness * (l - f.rest) + f.damping * ld) * n;
          add_point_force(B, q, f.point_b, F, Q, cache);
          add_point_force(A, q, f.point_a, -F, Q, cache);
          break;
        }
        case ForceType::kTorsionSpring: {
          if (spatial(A, B)) {
            // rigid bodies: torque on b = −k theta n − c (omega_b − omega_a), the gradient of
            // V = ½ k theta² (an isotropic rotational spring; about a revolute joint's axis
            // it is the joint's torsion spring)
            const Vector3d w = angular_velocity_W(B, q, qd) - angular_velocity_W(A, q, qd);
            const Vector3d T = -f.stiffness * relative_rotation_W(A, B, q, cache) - f.damping * w;
            add_torque(B, q, T, Q);
            add_torque(A, q, -T, Q);
            break;
          }
          // planar: torque on b = −k (theta_b − theta_a − theta0) − c (theta_b' − theta_a')
          const double th =
              (B.ground() ? 0.0 : q[B.offset + 2]) - (A.ground() ? 0.0 : q[A.offset + 2]);
          const double w =
              (B.ground() ? 0.0 : qd[B.offset + 2]) - (A.ground() ? 0.0 : qd[A.offset + 2]);
          const double T = -f.stiffness * (th - f.rest) - f.damping * w;
          add_torque(B, q, Vector3d(0, 0, T), Q);
          add_torque(A, q, Vector3d(0, 0, -T), Q);
          break;
        }
        case ForceType::kApplied: {
          const Wrench w = f.wrench(q, qd, t);
          add_point_force(A, q, f.point_a, w.force, Q, cache);
          add_torque(A, q, w.torque, Q);
          break;
        }
      }
    }
  };
}

PotentialScratchFn make_potential(const std::vector<BodyInfo>& bodies,
                                  const std::vector<Force>& forces, const Vector3d& g) {
  auto d = force_data(bodies, forces, g);
  return [d](const Eigen::Ref<const VectorXd>& q, double, CallableScratch* scratch) {
    PoseCache* const cache = pose_cache(scratch);
    // V = −Σ m g · r + Σ ½ k (l − l0)² + Σ ½ k (dtheta − theta0)²
    double V = 0.0;
    for (const BodyInfo& b : d->bodies) {
      const Vector3d r = b.kind == BodyKind::kPlanar ? Vector3d(q[b.offset], q[b.offset + 1], 0.0)
                                                     : Vector3d(q.segment<3>(b.offset));
      V -= b.mass * d->g.dot(r);
    }
    for (std::size_t i = 0; i < d->forces.size(); ++i) {
      const Force& f = d->forces[i];
      if (f.type == ForceType::kSpringDamper) {
        // the points' positions (their velocities, at q' = q here, are not used)
        const double l = (point_state(d->b[i], q, q, f.point_b, cache).first -
                          point_state(d->a[i], q, q, f.point_a, cache).first)
                             .norm();
        V += 0.5 * f.stiffness * (l - f.rest) * (l - f.rest);
      } else if (f.type == ForceType::kTorsionSpring && spatial(d->a[i], d->b[i])) {
        V += 0.5 * f.stiffness * relative_rotation_W(d->a[i], d->b[i], q, cache).squaredNorm();
      } else if (f.type == ForceType::kTorsionSpring) {
        const BodyRef &A = d->a[i], &B = d->b[i];
        const double th =
            (B.ground() ? 0.0 : q[B.offset + 2]) - (A.ground() ? 0.0 : q[A.offset + 2]);
        V += 0.5 * f.stiffness * (th - f.rest) * (th - f.rest);
      }
    }
    return V;
  };
}

PowerScratchFn make_external_power(const std::vector<BodyInfo>& bodies,
                                   const std::vector<Force>& forces) {
  bool any = false;
  for (const Force& f : forces) any = any || f.type == ForceType::kApplied || f.damping != 0.0;
  if (!any) return {};
  auto d = force_data(bodies, forces, Vector3d::Zero());
  return [d](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double t,
             CallableScratch* scratch) {
    PoseCache* const cache = pose_cache(scratch);
    // P = Σ −c l'² (spring-dampers) + Σ −c |ω_b − ω_a|² (torsion) + Σ F · v_p + T · ω (applied)
    double P = 0.0;
    for (std::size_t i = 0; i < d->forces.size(); ++i) {
      const Force& f = d->forces[i];
      const BodyRef &A = d->a[i], &B = d->b[i];
      switch (f.type) {
        case ForceType::kSpringDamper: {
          if (f.damping == 0.0) break;
          const auto [xa, va] = point_state(A, q, qd, f.point_a, cache);
          const auto [xb, vb] = point_state(B, q, qd, f.point_b, cache);
          const double l = (xb - xa).norm();
          if (l == 0.0) break;
          const double ld = (xb - xa).dot(vb - va) / l;
          P -= f.damping * ld * ld;
          break;
        }
        case ForceType::kTorsionSpring: {
          if (f.damping == 0.0) break;
          if (spatial(A, B)) {
            P -= f.damping *
                 (angular_velocity_W(B, q, qd) - angular_velocity_W(A, q, qd)).squaredNorm();
            break;
          }
          const double w =
              (B.ground() ? 0.0 : qd[B.offset + 2]) - (A.ground() ? 0.0 : qd[A.offset + 2]);
          P -= f.damping * w * w;
          break;
        }
        case ForceType::kApplied: {
          if (A.ground()) break;
          const Wrench w = f.wrench(q, qd, t);
          P += w.force.dot(point_state(A, q, qd, f.point_a, cache).second) +
               w.torque.dot(angular_velocity_W(A, q, qd));
          break;
        }
      }
    }
    return P;
  };
}

// ---- joint friction ----------------------------------------------------------------------

void joint_friction_C(const Joint& j, const BodyRef& P, const BodyRef& C, bool planar, Index k,
                      const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                      const IdealForceInfo& ideal, Eigen::Ref<VectorXd> out) {
  // N = |reaction force| on the child (on the parent when the child is the ground)
  const auto share = ideal.reaction(k);  // the joint's whole reaction
  const BodyRef& on = C.ground() ? P : C;
  const double N = on.kind == BodyKind::kPlanar ? std::hypot(share[on.offset], share[on.offset + 1])
                                                : share.segment<3>(on.offset).norm();
  const JointFriction& fr = j.friction;
  const double eps = fr.regularization;
  PoseCache* const cache = pose_cache(ideal.scratch());
  const Matrix3d R_P = rotation_WB(P, q, cache);
  if (j.type == JointType::kRevolute) {
    // relative rate w about the axis; torque T = −(mu r N w / sqrt(w² + eps²) + c w) on C
    const Vector3d axis = planar ? Vector3d::UnitZ() : Vector3d(R_P * j.frame_parent.R.col(2));
    const double w = (angular_velocity_W(C, q, qd) - angular_velocity_W(P, q, qd)).dot(axis);
    const double T = -(fr.mu * fr.radius * N * w / std::sqrt(w * w + eps * eps) + fr.viscous * w);
    add_torque(C, q, T * axis, out);
    add_torque(P, q, -T * axis, out);
    return;
  }
  // prismatic: sliding rate along the axis (x_P planar, z_P spatial); force at the frames'
  // origins, which lie on the axis line (no couple)
  const Vector3d axis = R_P * j.frame_parent.R.col(planar ? 0 : 2);
  VecKin kc, kp;
  add_body_vector(C, q, qd, j.frame_child.p, true, 1.0, kc, cache);
  add_body_vector(P, q, qd, j.frame_parent.p, true, 1.0, kp, cache);
  // velocity of the parent's material point at o_C: v_P(o_P) + ω_P × (o_C − o_P)
  const Vector3d vP = kp.v + angular_velocity_W(P, q, qd).cross(kc.x - kp.x);
  const double w = (kc.v - vP).dot(axis);
  const double F = -(fr.mu * N * w / std::sqrt(w * w + eps * eps) + fr.viscous * w);
  add_point_force(C, q, j.frame_child.p, F * axis, out, cache);
  add_point_force(P, q, j.frame_parent.p, -F * axis, out, cache);
}

NonIdealForce joint_friction_force(const Joint& j, const BodyRef& P, const BodyRef& C,
                                   const std::string& constraint, bool planar) {
  if (j.type != JointType::kRevolute && j.type != JointType::kPrismatic) {
    throw std::invalid_argument("ukdyn::mb::Multibody::build: joint '" + j.name +
                                "': friction needs a revolute or prismatic joint, got " +
                                to_string(j.type));
  }
  const JointFriction& fr = j.friction;
  if (!(fr.mu >= 0.0) || !(fr.radius >= 0.0) || !(fr.viscous >= 0.0) ||
      !(fr.regularization > 0.0)) {
    throw std::invalid_argument("ukdyn::mb::Multibody::build: joint '" + j.name +
                                "': friction needs mu, radius, viscous >= 0 and "
                                "regularization > 0");
  }
  return NonIdealForce(
      j.name + ".friction",
      NonIdealForce::Binder([j, P, C, constraint, planar](const System& sys) -> NonIdealFn {
        const Index k = sys.constraint_index(constraint);
        return [j, P, C, planar, k](const Eigen::Ref<const VectorXd>& q,
                                    const Eigen::Ref<const VectorXd>& qd, double,
                                    const IdealForceInfo& ideal, Eigen::Ref<VectorXd> out) {
          joint_friction_C(j, P, C, planar, k, q, qd, ideal, out);
        };
      }));
}

}  // namespace ukdyn::mb::detail

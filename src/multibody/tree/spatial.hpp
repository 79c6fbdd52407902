// SPDX-License-Identifier: BSD-3-Clause
// Spatial (6-D) algebra of the tree passes in fixed-size Eigen types (Featherstone's notation,
// motion [ω; v] and force [n; f]), and the joint models: X_i(q), S_i(q) and c_i = S_i' q'.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree::detail {

/// Refuses a TreeData of another tree and vectors of the wrong size, naming `who`.
void check_sizes(const char* who, const Tree& tree, const TreeData& d, Index q_size);

/// M(q) by the CRBA from the kinematics in d (forward_kinematics at q already run): the passes
/// of mass_matrix after its checks. Cost O(n · depth).
void mass_matrix_from_kinematics(const Tree& tree, TreeData& d, Eigen::Ref<MatrixXd> M);

/// τ = M q'' + h by the RNEA from the kinematics in d (forward_kinematics at q already run);
/// q'' = 0 when qdd is null: the passes of inverse_dynamics after its checks. c, when not null
/// ((links), sized): receives each moving link's velocity-product acceleration c_i + v_i × S_i
/// q'_i (the term a J' q' pass adds to X_i a_λ; a link without joint coordinates keeps its
/// entry). Cost O(links).
void rnea_from_kinematics(const Tree& tree, const Eigen::Ref<const VectorXd>& qd,
                          const Eigen::Ref<const VectorXd>* qdd, TreeData& d,
                          Eigen::Ref<VectorXd> tau, TreeData::Aligned<Vector6d>* c = nullptr);

/// frame_bias_acceleration from the kinematics in d (forward_kinematics at q already run): its
/// outward pass after its checks. c_known, when not null: an RNEA at this q and q' ran on d and
/// left every link's velocity in d.v and its velocity products in *c_known (the c of
/// rnea_from_kinematics; KinematicsCache::velocities_at), so only a_i = X_i a_λ + c_i is
/// computed (the same bits: the same sums of the same terms); otherwise d.v of the links
/// 0 … link is written. Cost O(depth).
Vector6d frame_bias_from_kinematics(const Tree& tree, const Eigen::Ref<const VectorXd>& qd,
                                    TreeData& d, Index link, const Vector3d& p_L,
                                    const TreeData::Aligned<Vector6d>* c_known = nullptr);

/// [x]×, the cross-product matrix.
inline Matrix3d skew(const Vector3d& x) {
  Matrix3d m;
  m << 0, -x.z(), x.y(), x.z(), 0, -x.x(), -x.y(), x.x(), 0;
  return m;
}

/// The spatial inertia about a frame's origin of mass m at com c with inertia I_c about c:
///   [I_c − m [c]×², m [c]×; −m [c]×, m 1].
inline Matrix6d spatial_inertia(double m, const Vector3d& c, const Matrix3d& I_c) {
  const Matrix3d C = skew(c);
  Matrix6d I;
  I.topLeftCorner<3, 3>() = I_c - m * C * C;
  I.topRightCorner<3, 3>() = m * C;
  I.bottomLeftCorner<3, 3>() = -m * C;
  I.bottomRightCorner<3, 3>() = m * Matrix3d::Identity();
  return I;
}

/// X m: motion m in λ coordinates to L coordinates, X = (E, r): [E ω; E (v − r × ω)].
inline Vector6d motion_to_child(const Matrix3d& E, const Vector3d& r, const Vector6d& m) {
  Vector6d out;
  out.head<3>() = E * m.head<3>();
  out.tail<3>() = E * (m.tail<3>() - r.cross(m.head<3>()));
  return out;
}

/// Xᵀ f: force f in L coordinates to λ coordinates: [Eᵀ n + r × Eᵀ f; Eᵀ f].
inline Vector6d force_to_parent(const Matrix3d& E, const Vector3d& r, const Vector6d& f) {
  Vector6d out;
  out.tail<3>() = E.transpose() * f.tail<3>();
  out.head<3>() = E.transpose() * f.head<3>() + r.cross(out.tail<3>());
  return out;
}

/// Xᵀ F for a 6 × k block of forces (columns), as force_to_parent.
template <class Block>
inline void forces_to_parent(const Matrix3d& E, const Vector3d& r, Block&& F) {
  for (Index c = 0; c < F.cols(); ++c) {
    const Vector6d f = F.col(c);
    F.col(c) = force_to_parent(E, r, f);
  }
}

/// Xᵀ I X: an inertia in L coordinates seen from λ's origin, in λ coordinates. A rigid or
/// composite spatial inertia is I = [A, [h]×; −[h]×, m 1] (h = m c, its first moment), so with
/// h̃ = Eᵀ h and A' = Eᵀ A E in λ axes (the parallel-axis theorem, [a]×[b]× = b aᵀ − (a·b) 1):
///   Xᵀ I X = [A' − (r h̃ᵀ + h̃ rᵀ) − m r rᵀ + (2 h̃·r + m r·r) 1,  [h']×;  −[h']×,  m 1],
///   h' = h̃ + m r.
/// About 90 multiplications (A' 45, the rest 45) where the two 6 × 6 products take 430; the upper
/// left block is computed on and below its diagonal and mirrored (exactly symmetric).
inline Matrix6d inertia_to_parent(const Matrix3d& E, const Vector3d& r, const Matrix6d& I) {
  const double m = I(3, 3);
  const Vector3d h(I(2, 4), I(0, 5), I(1, 3));  // [h]× = the upper right block
  const Matrix3d A = I.topLeftCorner<3, 3>();
  const Vector3d ht = E.transpose() * h;
  // A' = Eᵀ A E (t = A E; A'_ij = E_iᵀ t_j for i >= j)
  Matrix3d t;
  t.noalias() = A * E;
  const double s = 2.0 * ht.dot(r) + m * r.squaredNorm();
  Matrix6d out;
  for (int j = 0; j < 3; ++j) {
    for (int i = j; i < 3; ++i) {
      const double v = E.col(i).dot(t.col(j)) - (r[i] * ht[j] + ht[i] * r[j]) - m * r[i] * r[j] +
                       (i == j ? s : 0.0);
      out(i, j) = v;
      out(j, i) = v;
    }
  }
  const Vector3d hp = ht + m * r;
  out.topRightCorner<3, 3>() = skew(hp);
  out.bottomLeftCorner<3, 3>() = -out.topRightCorner<3, 3>();
  out.bottomRightCorner<3, 3>() = m * Matrix3d::Identity();
  return out;
}

/// I x for a rigid or composite spatial inertia I = [A, [h]×; −[h]×, m 1] (as inertia_to_parent):
/// [A x_ω + h × x_v; m x_v − h × x_ω], 24 multiplications where the 6 × 6 product takes 36.
inline Vector6d inertia_times(const Matrix6d& I, const Vector6d& x) {
  const double m = I(3, 3);
  const Vector3d h(I(2, 4), I(0, 5), I(1, 3));
  const Vector3d w = x.head<3>(), v = x.tail<3>();
  Vector6d out;
  out.head<3>().noalias() = I.topLeftCorner<3, 3>() * w;
  out.head<3>() += h.cross(v);
  out.tail<3>() = m * v - h.cross(w);
  return out;
}

/// The entry that S_i of a 1-DOF joint picks (S_i = e_k, k in 0..5) when its axis is a unit
/// vector of the joint's frame, as nearly every URDF's: products with S_i are then that entry or
/// column. −1 for other axes and other joints. O(1).
inline int subspace_pick(const Tree& tree, Index i) {
  const Joint& j = tree.link(i).joint;
  const int base = j.kind == JointKind::kPrismatic ? 3 : 0;
  if (j.kind != JointKind::kRevolute && j.kind != JointKind::kContinuous && base == 0) return -1;
  const Vector3d& a = j.axis;
  for (int k = 0; k < 3; ++k) {
    if (a[k] == 1.0 && a[(k + 1) % 3] == 0.0 && a[(k + 2) % 3] == 0.0) return base + k;
  }
  return -1;
}

/// A floating joint's S_i (6 × 7) as a fixed-size matrix, so that its products are inline.
inline Eigen::Map<const Eigen::Matrix<double, 6, 7>> floating_subspace(const TreeData::S6& S) {
  return Eigen::Map<const Eigen::Matrix<double, 6, 7>>(S.data());
}

/// v_J = S_i q'_i of joint i (n_i coordinates from o): zero for a fixed joint, a column times the
/// rate for a 1-DOF joint, a fixed-size product for a floating one. O(n_i).
inline Vector6d joint_velocity(const TreeData::S6& S, const Eigen::Ref<const VectorXd>& qd, Index o,
                               int ni) {
  switch (ni) {
    case 0:
      return Vector6d::Zero();
    case 1:
      return S.col(0) * qd[o];
    case 7:
      return floating_subspace(S) * qd.segment<7>(o);
    default:
      return S * qd.segment(o, ni);
  }
}

/// v ×* f, the spatial cross product of a motion with a force.
inline Vector6d cross_force(const Vector6d& v, const Vector6d& f) {
  Vector6d out;
  out.head<3>() = v.head<3>().cross(f.head<3>()) + v.tail<3>().cross(f.tail<3>());
  out.tail<3>() = v.head<3>().cross(f.tail<3>());
  return out;
}

/// v × m, the spatial cross product of two motions.
inline Vector6d cross_motion(const Vector6d& v, const Vector6d& m) {
  Vector6d out;
  out.head<3>() = v.head<3>().cross(m.head<3>());
  out.tail<3>() = v.head<3>().cross(m.tail<3>()) + v.tail<3>().cross(m.head<3>());
  return out;
}

/// E(u) of a quaternion (u0 scalar): ω_L = 2 E(u) u' (the rigid body's map of multibody.hpp).
inline Eigen::Matrix<double, 3, 4> quaternion_E(const Eigen::Vector4d& u) {
  Eigen::Matrix<double, 3, 4> E;
  E << -u[1], u[0], u[3], -u[2],  //
      -u[2], -u[3], u[0], u[1],   //
      -u[3], u[2], -u[1], u[0];
  return E;
}

/// The velocity-product acceleration c_i = S_i' q'_i of joint i (zero but for a floating
/// joint, whose linear part is R_WLᵀ p' and so changes with R: c = [0; −ω_L × R_WLᵀ p']).
inline Vector6d joint_bias(const Tree& tree, const TreeData& d, Index i,
                           const Eigen::Ref<const VectorXd>& qd) {
  Vector6d c = Vector6d::Zero();
  if (tree.link(i).joint.kind == JointKind::kFloating) {
    const auto& S = d.S[std::size_t(i)];
    const auto qdi = qd.segment<7>(tree.offset(i));
    const Vector3d w = S.topRows<3>() * qdi;
    const Vector3d v = S.bottomRows<3>() * qdi;
    c.tail<3>() = -w.cross(v);
  }
  return c;
}

}  // namespace ukdyn::tree::detail

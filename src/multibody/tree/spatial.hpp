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
/// q'' = 0 when qdd is null: the passes of inverse_dynamics after its checks. Cost O(links).
void rnea_from_kinematics(const Tree& tree, const Eigen::Ref<const VectorXd>& qd,
                          const Eigen::Ref<const VectorXd>* qdd, TreeData& d,
                          Eigen::Ref<VectorXd> tau);

/// frame_bias_acceleration from the kinematics in d (forward_kinematics at q already run): its
/// outward pass after its checks. Cost O(depth).
Vector6d frame_bias_from_kinematics(const Tree& tree, const Eigen::Ref<const VectorXd>& qd,
                                    TreeData& d, Index link, const Vector3d& p_L);

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

/// Xᵀ I X: an inertia in L coordinates seen from λ's origin, in λ coordinates. With
/// I = [A B; Bᵀ C] rotated to λ axes (A' = Eᵀ A E, …) and T = [1 0; −[r]× 1]:
///   Tᵀ I' T = [A' − B'[r]× + [r]× (B'ᵀ − C'[r]×),  B' + [r]× C';  B'ᵀ − C'[r]×,  C'].
/// About 250 multiplications instead of the two 6 × 6 products' 430: the blocks are copied to
/// fixed 3 × 3 matrices (Eigen then multiplies them inline), and C' = C, since the lower right
/// block of a rigid body's spatial inertia (and of a composite one) is m 1.
inline Matrix6d inertia_to_parent(const Matrix3d& E, const Vector3d& r, const Matrix6d& I) {
  const Matrix3d Et = E.transpose();
  const Matrix3d I_A = I.topLeftCorner<3, 3>(), I_B = I.topRightCorner<3, 3>();
  Matrix3d t, A, B;
  t.noalias() = Et * I_A;
  A.noalias() = t * E;
  t.noalias() = Et * I_B;
  B.noalias() = t * E;
  const Matrix3d C = I.bottomRightCorner<3, 3>();
  const Matrix3d rx = skew(r);
  const Matrix3d lower = B.transpose() - C * rx;  // B'ᵀ − C'[r]×
  Matrix6d out;
  out.topLeftCorner<3, 3>() = A - B * rx + rx * lower;
  out.topRightCorner<3, 3>() = lower.transpose();
  out.bottomLeftCorner<3, 3>() = lower;
  out.bottomRightCorner<3, 3>() = C;
  return out;
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

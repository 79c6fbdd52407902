// SPDX-License-Identifier: BSD-3-Clause
// Centre of mass and momentum of a tree: p_WG, its Jacobian J_G, and [k_O; l] from an outward
// velocity pass (Featherstone 2008, section 2.13: h_i = I_i v_i, summed in world coordinates).
#include <stdexcept>
#include <string>

#include "multibody/tree/spatial.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {

double total_mass(const Tree& tree) {
  double m = 0.0;
  for (Index i = 0; i < tree.link_count(); ++i) m += tree.link(i).inertial.mass;
  return m;
}

Vector3d center_of_mass(const Tree& tree, const TreeData& d) {
  detail::check_sizes("ukdyn::tree::center_of_mass", tree, d, tree.coordinate_count());
  // p_WG = Σ m_i p_W(com_i) / Σ m_i
  Vector3d sum = Vector3d::Zero();
  for (Index i = 0; i < tree.link_count(); ++i) {
    const Inertial& in = tree.link(i).inertial;
    sum += in.mass * world_point(d, i, in.com);
  }
  const double m = total_mass(tree);
  return m > 0.0 ? Vector3d(sum / m) : Vector3d::Zero();
}

void com_jacobian(const Tree& tree, const TreeData& d,
                  Eigen::Ref<Eigen::Matrix<double, 3, Eigen::Dynamic>> J) {
  detail::check_sizes("ukdyn::tree::com_jacobian", tree, d, J.cols());
  J.setZero();
  const double m = total_mass(tree);
  if (!(m > 0.0)) return;
  // J_G = Σ_i m_i J_v(com_i) / m: each link's com is moved by the columns of its ancestors,
  // v = R_Wj S_v + (R_Wj S_ω) × (p_W(com_i) − p_Wj)
  for (Index i = 0; i < tree.link_count(); ++i) {
    const Inertial& in = tree.link(i).inertial;
    if (in.mass == 0.0) continue;
    const Vector3d p_WC = world_point(d, i, in.com);
    const double w_i = in.mass / m;
    for (Index j = i; j >= 0; j = tree.parent(j)) {
      const std::size_t k = std::size_t(j);
      const Matrix3d& R = d.R_WL[k];
      const Vector3d arm = p_WC - d.p_WL[k];
      for (int c = 0; c < tree.dofs(j); ++c) {
        const Vector3d w = R * d.S[k].col(c).head<3>();
        J.col(tree.offset(j) + c) += w_i * (R * d.S[k].col(c).tail<3>() + w.cross(arm));
      }
    }
  }
}

Vector6d momentum(const Tree& tree, const Eigen::Ref<const VectorXd>& q,
                  const Eigen::Ref<const VectorXd>& qd, TreeData& d) {
  const char* who = "ukdyn::tree::momentum";
  detail::check_sizes(who, tree, d, q.size());
  detail::check_sizes(who, tree, d, qd.size());
  forward_kinematics(tree, q, d);
  Vector6d out = Vector6d::Zero();
  for (Index i = 0; i < tree.link_count(); ++i) {
    const std::size_t k = std::size_t(i);
    const Index p = tree.parent(i);
    // v_i = X_i v_λ + S_i q'_i (link coordinates, [ω; v at L's origin])
    const Vector6d vJ = d.S[k] * qd.segment(tree.offset(i), tree.dofs(i));
    d.v[k] =
        p < 0 ? vJ : Vector6d(detail::motion_to_child(d.E[k], d.r[k], d.v[std::size_t(p)]) + vJ);
    // h_i = I_i v_i about L's origin; in the world about its origin: [R n + p_WL × R f; R f]
    const Vector6d h = tree.spatial_inertia(i) * d.v[k];
    const Vector3d f_W = d.R_WL[k] * h.tail<3>();
    out.head<3>() += d.R_WL[k] * h.head<3>() + d.p_WL[k].cross(f_W);
    out.tail<3>() += f_W;
  }
  return out;
}

}  // namespace ukdyn::tree

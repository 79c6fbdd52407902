// SPDX-License-Identifier: BSD-3-Clause
// Forward kinematics of a tree: joint transforms X_i(q), subspaces S_i(q), world poses; the
// frame Jacobian of a link point.
#include <cmath>
#include <stdexcept>
#include <string>

#include "multibody/tree/spatial.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {

namespace detail {

void check_sizes(const char* who, const Tree& tree, const TreeData& d, Index q_size) {
  if (d.tree_size != tree.link_count()) {
    throw std::invalid_argument(std::string(who) + ": the TreeData was made for a tree of " +
                                std::to_string(d.tree_size) + " links, this one has " +
                                std::to_string(tree.link_count()) +
                                " (make one TreeData per tree)");
  }
  if (q_size != tree.coordinate_count()) {
    throw std::invalid_argument(std::string(who) + ": expected vectors of " +
                                std::to_string(tree.coordinate_count()) + " coordinates, got " +
                                std::to_string(q_size));
  }
}

}  // namespace detail

void forward_kinematics(const Tree& tree, const Eigen::Ref<const VectorXd>& q, TreeData& d) {
  detail::check_sizes("ukdyn::tree::forward_kinematics", tree, d, q.size());
  // (every pass runs this one: the joints must be those the data was made for, too)
  for (Index i = 0; i < tree.link_count(); ++i) {
    if (d.dofs[std::size_t(i)] != tree.dofs(i)) {
      throw std::invalid_argument(
          "ukdyn::tree::forward_kinematics: the TreeData was made for a tree with other joints "
          "(make one TreeData per tree)");
    }
  }
  for (Index i = 0; i < tree.link_count(); ++i) {
    const std::size_t k = std::size_t(i);
    const Joint& j = tree.link(i).joint;
    const Matrix3d& R_PJ = tree.joint_rotation(i);
    Matrix3d R_PL = R_PJ;    // the joint's rotation λ → L
    Vector3d p_PL = j.p_PJ;  // the origin of L in λ coordinates
    auto& S = d.S[k];
    const Index o = tree.offset(i);
    switch (j.kind) {
      case JointKind::kFixed:
        break;
      case JointKind::kRevolute:
      case JointKind::kContinuous:
        // rotation by q about the axis; S = [axis; 0]
        if (const int a = detail::subspace_pick(tree, i); a >= 0) {
          // about the joint frame's axis a: columns b, c = the next two of R_PJ turn by q
          // (R_PJ R_a(q), without forming R_a)
          double s, c;
          ::sincos(q[o], &s, &c);
          const int b = (a + 1) % 3, e = (a + 2) % 3;
          R_PL.col(b) = c * R_PJ.col(b) + s * R_PJ.col(e);
          R_PL.col(e) = c * R_PJ.col(e) - s * R_PJ.col(b);
        } else {
          R_PL = R_PJ * Eigen::AngleAxisd(q[o], j.axis).toRotationMatrix();
        }
        S.col(0) << j.axis, Vector3d::Zero();
        break;
      case JointKind::kPrismatic:
        // translation by q along the axis; S = [0; axis]
        p_PL = j.p_PJ + R_PJ * (j.axis * q[o]);
        S.col(0) << Vector3d::Zero(), j.axis;
        break;
      case JointKind::kFloating: {
        // pose in the world; S = [0, 2 E(u); R_WLᵀ, 0]  (ω_L = 2 E(u) u', v_L = R_WLᵀ p')
        const Eigen::Vector4d u = q.segment<4>(o + 3);
        R_PL = Eigen::Quaterniond(u[0], u[1], u[2], u[3]).normalized().toRotationMatrix();
        p_PL = q.segment<3>(o);
        S.setZero();
        S.block<3, 4>(0, 3) = 2.0 * detail::quaternion_E(u);
        S.block<3, 3>(3, 0) = R_PL.transpose();
        break;
      }
    }
    d.E[k] = R_PL.transpose();
    d.r[k] = p_PL;
    // world pose: R_WL = R_Wλ R_λL, p_WL = p_Wλ + R_Wλ p_λL
    const Index p = tree.parent(i);
    if (p < 0) {
      d.R_WL[k] = R_PL;
      d.p_WL[k] = p_PL;
    } else {
      d.R_WL[k] = d.R_WL[std::size_t(p)] * R_PL;
      d.p_WL[k] = d.p_WL[std::size_t(p)] + d.R_WL[std::size_t(p)] * p_PL;
    }
  }
}

Vector3d world_point(const TreeData& d, Index link, const Vector3d& p_L) {
  if (link < 0 || link >= d.tree_size) {
    throw std::invalid_argument("ukdyn::tree::world_point: link " + std::to_string(link) +
                                " out of range [0, " + std::to_string(d.tree_size) + ")");
  }
  return d.p_WL[std::size_t(link)] + d.R_WL[std::size_t(link)] * p_L;
}

void frame_jacobian(const Tree& tree, const TreeData& d, Index link, const Vector3d& p_L,
                    Eigen::Ref<Eigen::Matrix<double, 6, Eigen::Dynamic>> J) {
  const char* who = "ukdyn::tree::frame_jacobian";
  detail::check_sizes(who, tree, d, J.cols());
  const Vector3d p_WP = world_point(d, link, p_L);
  J.setZero();
  // each ancestor's columns: ω = R_Wj S_ω, v_P = R_Wj S_v + ω × (p_WP − p_Wj)
  for (Index j = link; j >= 0; j = tree.parent(j)) {
    const std::size_t k = std::size_t(j);
    const Matrix3d& R = d.R_WL[k];
    const Vector3d arm = p_WP - d.p_WL[k];
    for (int c = 0; c < tree.dofs(j); ++c) {
      const Vector3d w = R * d.S[k].col(c).head<3>();
      J.col(tree.offset(j) + c) << w, R * d.S[k].col(c).tail<3>() + w.cross(arm);
    }
  }
}

}  // namespace ukdyn::tree

// SPDX-License-Identifier: BSD-3-Clause
// Inverse dynamics and bias forces of a tree by recursive Newton–Euler (Featherstone 2008,
// algorithm 5.1), gravity as a fictitious acceleration of the world; the same outward pass
// gives a frame's velocity-product acceleration J' q'.
#include <stdexcept>
#include <string>

#include "multibody/tree/spatial.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {

namespace {

// τ = M q'' + h; q'' = 0 when qdd is null
void rnea(const Tree& tree, const Eigen::Ref<const VectorXd>& q,
          const Eigen::Ref<const VectorXd>& qd, const Eigen::Ref<const VectorXd>* qdd, TreeData& d,
          Eigen::Ref<VectorXd> tau) {
  const char* who = "ukdyn::tree::inverse_dynamics";
  detail::check_sizes(who, tree, d, q.size());
  detail::check_sizes(who, tree, d, qd.size());
  detail::check_sizes(who, tree, d, tau.size());
  if (qdd) detail::check_sizes(who, tree, d, qdd->size());
  forward_kinematics(tree, q, d);
  detail::rnea_from_kinematics(tree, qd, qdd, d, tau);
}

// the outward pass of rnea_from_kinematics; kKeepC: c_i + v_i × vJ also into *c (a template
// parameter, so that the RNEA without c is the same loop as before it existed)
template <bool kKeepC>
void rnea_outward(const Tree& tree, const Eigen::Ref<const VectorXd>& qd,
                  const Eigen::Ref<const VectorXd>* qdd, TreeData& d,
                  TreeData::Aligned<Vector6d>* c) {
  // the world's acceleration −g stands for gravity
  Vector6d a0;
  a0 << Vector3d::Zero(), -tree.gravity();
  // outward: v_i = X_i v_λ + S_i q'_i, a_i = X_i a_λ + S_i q''_i + c_i + v_i × S_i q'_i,
  // f_i = I_i a_i + v_i ×* I_i v_i
  for (Index i = 0; i < tree.link_count(); ++i) {
    const std::size_t k = std::size_t(i);
    const Index p = tree.parent(i);
    const int ni = tree.dofs(i);
    const Index o = tree.offset(i);
    const Vector6d vJ = detail::joint_velocity(d.S[k], qd, o, ni);
    if (p < 0) {
      d.v[k] = vJ;
      d.a[k] = detail::motion_to_child(d.E[k], d.r[k], a0);
    } else {
      d.v[k] = detail::motion_to_child(d.E[k], d.r[k], d.v[std::size_t(p)]) + vJ;
      d.a[k] = detail::motion_to_child(d.E[k], d.r[k], d.a[std::size_t(p)]);
    }
    if (ni > 0) {
      if (qdd && ni == 1) d.a[k] += d.S[k].col(0) * (*qdd)[o];
      if (qdd && ni > 1) d.a[k].noalias() += d.S[k] * qdd->segment(o, ni);
      if constexpr (kKeepC) {
        // (a += c_i, c_i kept: the same sums as a += joint bias + v × vJ)
        Vector6d& ck = (*c)[k];
        ck = detail::joint_bias(tree, d, i, qd) + detail::cross_motion(d.v[k], vJ);
        d.a[k] += ck;
      } else {
        d.a[k] += detail::joint_bias(tree, d, i, qd) + detail::cross_motion(d.v[k], vJ);
      }
    }
    const Matrix6d& I = tree.spatial_inertia(i);
    d.f[k] = detail::inertia_times(I, d.a[k]) +
             detail::cross_force(d.v[k], detail::inertia_times(I, d.v[k]));
  }
}

}  // namespace

void detail::rnea_from_kinematics(const Tree& tree, const Eigen::Ref<const VectorXd>& qd,
                                  const Eigen::Ref<const VectorXd>* qdd, TreeData& d,
                                  Eigen::Ref<VectorXd> tau, TreeData::Aligned<Vector6d>* c) {
  if (c != nullptr) {
    rnea_outward<true>(tree, qd, qdd, d, c);
  } else {
    rnea_outward<false>(tree, qd, qdd, d, nullptr);
  }
  // inward: τ_i = S_iᵀ f_i, f_λ += X_iᵀ f_i
  for (Index i = tree.link_count(); i-- > 0;) {
    const std::size_t k = std::size_t(i);
    const int ni = tree.dofs(i);
    if (ni == 1) tau[tree.offset(i)] = d.S[k].col(0).dot(d.f[k]);
    if (ni == 7) {
      tau.segment<7>(tree.offset(i)).noalias() =
          detail::floating_subspace(d.S[k]).transpose() * d.f[k];
    } else if (ni > 1) {
      tau.segment(tree.offset(i), ni).noalias() = d.S[k].transpose() * d.f[k];
    }
    const Index p = tree.parent(i);
    if (p >= 0) d.f[std::size_t(p)] += detail::force_to_parent(d.E[k], d.r[k], d.f[k]);
  }
}

Vector6d frame_bias_acceleration(const Tree& tree, const Eigen::Ref<const VectorXd>& q,
                                 const Eigen::Ref<const VectorXd>& qd, TreeData& d, Index link,
                                 const Vector3d& p_L) {
  const char* who = "ukdyn::tree::frame_bias_acceleration";
  detail::check_sizes(who, tree, d, q.size());
  detail::check_sizes(who, tree, d, qd.size());
  if (link < 0 || link >= tree.link_count()) {
    throw std::invalid_argument(std::string(who) + ": link " + std::to_string(link) +
                                " out of range [0, " + std::to_string(tree.link_count()) + ")");
  }
  forward_kinematics(tree, q, d);
  return detail::frame_bias_from_kinematics(tree, qd, d, link, p_L);
}

Vector6d detail::frame_bias_from_kinematics(const Tree& tree, const Eigen::Ref<const VectorXd>& qd,
                                            TreeData& d, Index link, const Vector3d& p_L,
                                            const TreeData::Aligned<Vector6d>* c_known) {
  // outward, as the RNEA's with q'' = 0 and no gravity (every link: the ancestors come first);
  // v_i and c_i + v_i × vJ as the RNEA's, unless it left them in d.v and c_known
  for (Index i = 0; i <= link; ++i) {
    const std::size_t k = std::size_t(i);
    const Index p = tree.parent(i);
    const int ni = tree.dofs(i);
    if (p < 0) {
      d.a[k].setZero();
    } else {
      d.a[k] = detail::motion_to_child(d.E[k], d.r[k], d.a[std::size_t(p)]);
    }
    if (c_known) {
      if (ni > 0) d.a[k] += (*c_known)[k];
      continue;
    }
    const Vector6d vJ = detail::joint_velocity(d.S[k], qd, tree.offset(i), ni);
    if (p < 0) {
      d.v[k] = vJ;
    } else {
      d.v[k] = detail::motion_to_child(d.E[k], d.r[k], d.v[std::size_t(p)]) + vJ;
    }
    if (ni > 0) d.a[k] += detail::joint_bias(tree, d, i, qd) + detail::cross_motion(d.v[k], vJ);
  }
  // spatial to classical at the point: a_p = a_v + ω × v_O + ω' × p + ω × (ω × p)
  const std::size_t k = std::size_t(link);
  const Vector3d w = d.v[k].head<3>(), wd = d.a[k].head<3>();
  const Vector3d a_p =
      d.a[k].tail<3>() + w.cross(d.v[k].tail<3>()) + wd.cross(p_L) + w.cross(w.cross(p_L));
  Vector6d out;
  out << d.R_WL[k] * wd, d.R_WL[k] * a_p;
  return out;
}

void inverse_dynamics(const Tree& tree, const Eigen::Ref<const VectorXd>& q,
                      const Eigen::Ref<const VectorXd>& qd, const Eigen::Ref<const VectorXd>& qdd,
                      TreeData& data, Eigen::Ref<VectorXd> tau) {
  rnea(tree, q, qd, &qdd, data, tau);
}

void bias_forces(const Tree& tree, const Eigen::Ref<const VectorXd>& q,
                 const Eigen::Ref<const VectorXd>& qd, TreeData& data, Eigen::Ref<VectorXd> h) {
  rnea(tree, q, qd, nullptr, data, h);
}

}  // namespace ukdyn::tree

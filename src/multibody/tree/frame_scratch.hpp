// SPDX-License-Identifier: BSD-3-Clause
// The per-workspace buffers of the constraints between tree frames (frame_constraints.cpp) and
// of the contact-point kinematics for friction (contact_kinematics.cpp): the forward kinematics
// kept at the last q (shared with the tree system's workspace or its own), two points'
// Jacobians, and the point kinematics both files read from them.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "multibody/tree/kinematics_cache.hpp"
#include "multibody/tree/spatial.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/multibody/tree_closures.hpp"

namespace ukdyn::tree::detail {

using Jacobian = Eigen::Matrix<double, 6, Eigen::Dynamic>;

// per workspace: the forward kinematics (its own, or those of the tree system's workspace it is
// evaluated with: detail::shared_kinematics) and the two points' Jacobians
struct FrameScratch final : ConstraintScratch {
  // shared: the kinematics cache of a tree system's scratch (same kinematics), or null
  FrameScratch(const Tree& tree, detail::KinematicsCache* shared)
      : own(shared != nullptr ? nullptr : std::make_unique<detail::KinematicsCache>(tree)),
        kinematics(shared != nullptr ? *shared : *own),
        data(kinematics.data),
        Ja(6, tree.coordinate_count()),
        Jb(6, tree.coordinate_count()),
        qd_omega(tree.coordinate_count()) {
    // (the RNEA of the system sharing it keeps the velocity products for the J' q' pass)
    kinematics.keep_c = true;
  }
  std::unique_ptr<detail::KinematicsCache> own;  // (null when shared)
  detail::KinematicsCache& kinematics;           // *own or the shared one
  TreeData& data;                                // kinematics.data
  Jacobian Ja, Jb;                               // (6 × n) frame Jacobians of the points a and b
  std::uint64_t version = 0;                     // kinematics.version of Ja and Jb
  bool Ja_valid = false, Jb_valid = false;       // Ja, Jb are those of data's kinematics
  PoseSample desired;                            // a pose requirement's path at t_desired
  double t_desired = 0.0;
  bool desired_valid = false;  // desired holds the path at t_desired
  // a pose requirement's ω = J_ω q' (Ja's) at q' = qd_omega: the acceleration form's, read
  // again by the violation at the same state
  Vector3d omega = Vector3d::Zero();
  VectorXd qd_omega;         // (n)
  bool omega_valid = false;  // omega is that of the Ja kept and qd_omega
};

// forward kinematics at q once per state: both points of a closure, and the acceleration form
// and the violation of one evaluation, share it (the same q, bit for bit, gives the same
// kinematics); the Jacobians kept are dropped when the kinematics changed
inline void kinematics_at(const Tree& tree, const Eigen::Ref<const VectorXd>& q, FrameScratch& w) {
  w.kinematics.at(tree, q);
  if (w.version != w.kinematics.version) {
    w.Ja_valid = w.Jb_valid = w.omega_valid = false;
    w.version = w.kinematics.version;
  }
}

// the kinematics of one point at (q, q'): position, Jacobian and J' q' (zero for the world)
struct PointState {
  Vector3d p_W;
  Vector6d bias;  // [ω'; a] at q'' = 0
};
inline PointState point_state(const Tree& tree, const LinkPoint& pt,
                              const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, FrameScratch& w, Jacobian& J,
                              bool with_bias) {
  if (pt.link < 0) {
    J.setZero();
    return {pt.p, Vector6d::Zero()};
  }
  TreeData& d = w.data;
  kinematics_at(tree, q, w);
  if (qd.size() != tree.coordinate_count()) {
    throw std::invalid_argument("ukdyn::tree: a constraint between tree frames got " +
                                std::to_string(qd.size()) + " velocities, expected " +
                                std::to_string(tree.coordinate_count()));
  }
  PointState s;
  if (with_bias) {
    // the link velocities and velocity products of the RNEA at this state, when it ran on
    // these kinematics (the controller's model or the plant evaluated with the scratch this one
    // shares); v known without c (an RNEA before this scratch set keep_c): v is written again,
    // the same bits, and stays marked
    const bool v_known = w.kinematics.velocities_at(qd);
    s.bias = detail::frame_bias_from_kinematics(
        tree, qd, d, pt.link, pt.p, v_known && w.kinematics.c_valid ? &w.kinematics.c : nullptr);
    if (!v_known) w.kinematics.clear_velocities();  // (written on links 0 … pt.link only)
  } else {
    s.bias.setZero();
  }
  // (the acceleration form and the violation at one state need the Jacobian once)
  bool& J_valid = &J == &w.Ja ? w.Ja_valid : w.Jb_valid;
  if (!J_valid) {
    frame_jacobian(tree, d, pt.link, pt.p, J);
    if (&J == &w.Ja) w.omega_valid = false;
  }
  J_valid = true;
  s.p_W = world_point(d, pt.link, pt.p);
  return s;
}

// the world orientation of a link's frame (the world's own for link −1), after
// forward_kinematics
inline Matrix3d world_rotation(const TreeData& d, Index link, const Matrix3d& R_L) {
  return link < 0 ? R_L : Matrix3d(d.R_WL[std::size_t(link)] * R_L);
}

/// Refuses, naming `who` and `name` (std::invalid_argument), a contact whose point `at` or
/// plane's point has a link out of range or is not finite, both on the world, or a plane whose
/// orientation is not a rotation (frame_constraints.cpp). Cost O(1).
void check_contact(const Tree& tree, const std::string& who, const std::string& name,
                   const LinkPoint& at, const LinkFrame& plane);

}  // namespace ukdyn::tree::detail

// SPDX-License-Identifier: BSD-3-Clause
/// @file multibody/tree_closures.hpp
/// Weld and revolute loop closures between the frames of a kinematic tree (multibody/tree.hpp),
/// beside its point and distance closures, and unilateral contacts of link points, spheres or
/// thin disks with a plane: constraints to add to tree::system_builder, built on frame_jacobian and
/// frame_bias_acceleration (src/multibody/tree/frame_constraints.cpp).
#pragma once

#include <string>

#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/nonideal.hpp"
#include "ukdyn/multibody/tree.hpp"

namespace ukdyn::tree {

/// A frame fixed on a link, or on the world (link = -1): origin p and orientation R (columns: the
/// frame's axes) in the link's frame (the world's for -1).
struct LinkFrame {
  Index link = -1;                    ///< the link (Tree::link_index), -1 for the world
  Vector3d p = Vector3d::Zero();      ///< origin in the link's frame
  Matrix3d R = Matrix3d::Identity();  ///< orientation in the link's frame (a rotation)
};

/// A weld loop closure: frame a held at frame b, 6 holonomic rows
///   e_p = p_W(a) − p_W(b),   e_R = ½ Σ_k r_b,k × r_a,k   (r_a,k, r_b,k the columns of R_Wa, R_Wb;
/// e_R = sin θ · axis of the relative rotation, zero at R_Wa = R_Wb). A q'' = b is e'' = 0 exactly:
/// rows 0–2 J_v(a) − J_v(b); rows 3–5 L J_ω(a) − Lᵀ J_ω(b), L = −½ Σ [r_b,k]× [r_a,k]× (the
/// identity at the closure). @throws std::invalid_argument naming `name` as point_constraint, and
/// on an R that is not a rotation (to 1e-9). Cost per evaluation O(n · depth).
Constraint weld_constraint(const Tree& tree, std::string name, const LinkFrame& a,
                           const LinkFrame& b);

/// A revolute loop closure (a hinge closing the chain): points a and b held together and the
/// unit axis u_a (in a's link frame) kept parallel to u_b (in b's link frame), 5 holonomic rows:
/// the 3 of point_constraint, then u_a · x_b = 0 and u_a · y_b = 0 with x_b, y_b ⊥ u_b fixed in
/// b's link. Each axis row φ = u_a · x has φ' = (u_a × x) · (ω_a − ω_b); A q'' = b is φ'' = 0
/// exactly. In a planar mechanism 3 of the 5 rows are identically zero (A rank deficient, which
/// the fundamental equation allows). @throws std::invalid_argument as point_constraint, and on a
/// zero or non-finite axis. Cost per evaluation O(n · depth).
Constraint revolute_constraint(const Tree& tree, std::string name, LinkPoint a,
                               const Vector3d& axis_a, LinkPoint b, const Vector3d& axis_b);

/// A unilateral contact of a sphere (radius r, centre `at`) or a point (r = 0) of a link with a
/// plane fixed on the world (plane.link = -1) or on another link: one holonomic gap row
///   g = n_W · (p_W(at) − o_W) − r >= 0,
/// o_W the plane's origin plane.p, n_W its z axis (plane.R's third column, the side the contact
/// stays on) in the world. With d = p_W(at) − o_W and the plane's link angular velocity ω_o:
///   A = n_Wᵀ (J_v(at) − J_v(o)) + (n_W × d)ᵀ J_ω(o)    (n_W' = ω_o × n_W),
///   b = −n_W · (β_v(at) − β_v(o)) − (n_W × d) · β_ω(o) − 2 (ω_o × n_W) · d'
///       − (ω_o × (ω_o × n_W)) · d,
/// β = J' q' (frame_bias_acceleration), d' = (J_v(at) − J_v(o)) q'. The constraint is made
/// unilateral with Newton's coefficient `restitution` (Constraint::unilateral; docs/contact.md:
/// events, impacts, releases; Poisson's law: with_restitution_law). Add it to
/// system_builder(tree). @throws std::invalid_argument naming `name` on a link out of range, both
/// on the world, a point not finite, a radius negative or not finite, plane.R not a rotation, or
/// a restitution outside [0, 1]. Cost per evaluation O(n · depth), as distance_constraint's row.
Constraint contact_constraint(const Tree& tree, std::string name, LinkPoint at, double radius,
                              const LinkFrame& plane, double restitution = 0.0);

/// The contact-point kinematics of that contact (sphere of radius r centred at `at`, or a point),
/// for Coulomb friction there (CoulombFriction::kinematics; docs/contact.md, "Contacts on
/// robots"): rows n_Wᵀ J_rel, t_1ᵀ J_rel, t_2ᵀ J_rel (n_W, t_1, t_2 = plane.R's z, x and y axes
/// in the world, turning with the plane's link) of the Jacobian of the relative velocity of the
/// two links' material points at the contact point x = c − r n_W (c = p_W(at), o the plane's
/// point, d = c − o, ρ = −r n_W, ω_C, ω_P the links' angular velocities; zero for the world):
///   v_rel = v(c) + ω_C × ρ − v(o) − ω_P × (d + ρ),
///   J_rel = J_v(c) − J_v(o) − [ρ]× J_ω(C) + [d + ρ]× J_ω(P),
///   bias_i = (ω_P × r_i) · v_rel + r_i · (β_v(c) − β_v(o) + β_ω(C) × ρ + ω_C × ρ'
///            − β_ω(P) × (d + ρ) − ω_P × (d' + ρ')),   ρ' = −r ω_P × n_W,
/// on all n coordinates (β = J' q'; on a plane of the world J_P = J_v(at) − [ρ]× J_ω, bias
/// r_i · (β_v(at) + β_ω × ρ)). Row 0 is the contact row's A. @throws std::invalid_argument
/// naming `name` on a link out of range, both on the world, a point not finite or plane.R not a
/// rotation. Cost per evaluation O(n · depth).
ContactKinematics contact_kinematics(const Tree& tree, const std::string& name, LinkPoint at,
                                     double radius, const LinkFrame& plane);

/// A thin disk fixed on a link (or on the world, link = -1): its centre and the normal of its
/// face (the axis, any length > 0) in the link's frame, and its radius.
struct LinkDisk {
  Index link = -1;                     ///< the link (Tree::link_index), -1 for the world
  Vector3d centre = Vector3d::Zero();  ///< the disk's centre c in the link's frame
  Vector3d axis = Vector3d::UnitZ();   ///< its axis a in the link's frame (normalized here)
  double radius = 0.0;                 ///< r > 0
};

/// A unilateral contact of a thin disk's rim with a plane fixed on the world or on another link
/// (docs/contact.md: the disk row of bodies models, on a tree): one holonomic gap row
///   g = n_W · d − r h,   h = √(1 − s²),   s = n_W · a_W,   d = p_W(c) − o_W,
/// h the distance along the plane's normal from the centre down to the rim's lowest point over
/// r (a_W the disk's axis in the world, n_W and o_W as in contact_constraint). With the disk
/// link's and the plane link's angular velocities ω_l, ω_o (s' = (n_W × a_W) · (ω_o − ω_l)):
///   g'' = [n_W · d]'' + (r s / h) s'' + r s'² / h³, so
///   A = A_nd + (r s / h) (n_W × a_W)ᵀ (J_ω(o) − J_ω(c)),
///   b = b_nd − (r s / h) ((n_W × a_W) · (β_ω(o) − β_ω(c)) + (n_W' × a_W + n_W × a_W') ·
///       (ω_o − ω_l)) − r s'² / h³,
/// A_nd, b_nd contact_constraint's row of the centre (with r = 0). A disk lying flat (h = 0) has
/// no single lowest point: refused at q0 (|s| > 1 − 1e-6), and met during a run it makes the
/// row infinite, which stops the run naming the contact (docs/contact.md). Made unilateral with
/// Newton's `restitution`. @throws std::invalid_argument naming `name` as contact_constraint,
/// and on a radius not > 0, an axis zero or not finite, q0 of the wrong size or not finite, or
/// the disk flat on its plane at q0. Cost per evaluation O(n · depth).
Constraint disk_contact_constraint(const Tree& tree, std::string name, const LinkDisk& disk,
                                   const LinkFrame& plane, const Eigen::Ref<const VectorXd>& q0,
                                   double restitution = 0.0);

/// The contact-point kinematics of that disk contact, for Coulomb friction there (as
/// contact_kinematics): the contact point is the rim's point most opposed to n_W,
/// x = c + ρ, ρ = −r m/|m|, m = n_W − s a_W, s = n_W · a_W, which moves on the disk as it rolls,
/// so the material velocity there is v(c) + ω_C × ρ and the bias has ω_C × ρ' with
/// ρ' = −r (m' − (e·m') e)/|m|, e = m/|m|, m' = n_W' − s' a_W − s a_W', a_W' = ω_C × a_W,
/// n_W' = ω_P × n_W (not ω_C × (ω_C × ρ): ρ is not a material vector). Row 0 is the disk
/// row's A. A disk flat on its plane (m = 0) has no contact point: disk_contact_constraint
/// refuses it at q0 and the run stops on it. @throws std::invalid_argument naming `name` as
/// contact_kinematics, and on a radius not > 0 or an axis zero or not finite. Cost per
/// evaluation O(n · depth).
ContactKinematics disk_contact_kinematics(const Tree& tree, const std::string& name,
                                          const LinkDisk& disk, const LinkFrame& plane);

}  // namespace ukdyn::tree

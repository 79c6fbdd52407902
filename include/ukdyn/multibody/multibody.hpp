// SPDX-License-Identifier: BSD-3-Clause
/// @file multibody/multibody.hpp
/// Bodies, joints and force elements: a modelling layer that produces an ordinary System.
///
/// Every body keeps its own absolute coordinates (no coordinate elimination):
///  - particle      (x, y, z)                                   3 coordinates, M = m I
///  - planar body   (x, y, theta) of its centre of mass          3 coordinates, M = diag(m, m, I)
///  - rigid body    centre of mass r and quaternion u = (u0, u1, u2, u3)   7 coordinates,
///                  M = diag(m I3, 4 E_v(u)ᵀ J E_v(u)) with J = diag(J1, J2, J3)
/// (docs/multibody.md: the quaternion equations of motion of Udwadia & Schutte 2010). The 4 × 4
/// quaternion block is singular along u; the unit norm of u, a constraint "<body>.unit" of the
/// system, determines that direction (a singular M with [M; A] of full column rank).
///
/// Every joint is one or more named constraints whose rows touch the coordinates of its bodies
/// only (ConstraintModel::columns()), with A and b in closed form (rolling contacts, spatial
/// revolute drives and spatial gears: automatic
/// differentiation on the bodies' own coordinates). Joint friction is a
/// NonIdealForce that reads the joint's own ideal reaction. The result of Multibody::build() is a
/// System with one mass block per body part (mass_block), which both the dense and the sparse
/// engine run, plus the metadata that the reports (joint reactions, energies, momenta, poses)
/// need. Its callables' per-workspace scratch (System::make_scratch) holds each body's rotation
/// (planar cos/sin theta, R_WB) for the state last seen, keyed on the exact orientation
/// coordinates: the joints, forces and violation checks of one evaluation compute it once, and
/// the results are bitwise those of computing it everywhere.
///
/// Frames: the world frame W has z up for spatial models; planar models move in the (x, y) plane.
/// A body frame B has its origin at the centre of mass. A joint connects a frame F_P on its
/// parent body and a frame F_C on its child body (Frame: origin p_BF and orientation R_BF in body
/// coordinates); the ground is the body kGround, whose frame is W.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ukdyn/core/system.hpp"
#include "ukdyn/core/types.hpp"
#include "ukdyn/dynamics/contact_restitution.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/io/trajectory_files.hpp"
#include "ukdyn/simulation/simulate.hpp"

/// Multibody models in absolute coordinates: particles, planar and rigid bodies, joints and
/// force elements, built into a System (this file).
namespace ukdyn::mb {

using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;

/// A body: an index returned by Multibody::add_*; kGround is the fixed world.
using BodyId = Index;
/// The ground (world frame W).
inline constexpr BodyId kGround = -1;

/// The coordinates a body carries.
enum class BodyKind {
  kParticle,  ///< (x, y, z)
  kPlanar,    ///< (x, y, theta) in the (x, y) plane
  kRigid,     ///< (x, y, z, u0, u1, u2, u3), u a unit quaternion (u0 the scalar part)
};

/// A frame fixed on a body: origin p (body coordinates, metres) and orientation R (columns: the
/// frame's x, y, z axes in body coordinates). On a planar body only p.x, p.y and a rotation about
/// z make sense; on a particle only p (an offset that does not rotate).
struct Frame {
  Vector3d p = Vector3d::Zero();      ///< origin p_BF
  Matrix3d R = Matrix3d::Identity();  ///< orientation R_BF
  /// The frame at p with the body's orientation.
  static Frame at(const Vector3d& p) { return {p, Matrix3d::Identity()}; }
  /// A planar frame at (x, y) whose x axis makes `angle` with the body's x axis.
  static Frame planar(double x, double y, double angle = 0.0);
  /// The frame at p whose z axis is `axis` (normalized); x and y complete a right-handed frame.
  /// @throws std::invalid_argument when axis is zero.
  static Frame with_z(const Vector3d& p, const Vector3d& axis);
};

/// A prescribed (driving) motion of a joint's relative coordinate: returns (f(t), f'(t), f''(t)).
using MotionFn = std::function<Vector3d(double t)>;

/// Friction in a joint, applied as a non-ideal force (reported apart from the ideal reaction).
/// Revolute joints: a torque about the axis; prismatic joints: a force along the axis.
/// Coulomb: magnitude mu · radius · N (revolute; N the norm of the joint's ideal reaction force,
/// radius the pin radius) or mu · N (prismatic, N the norm of the reaction force), opposing the
/// relative rate w as w / sqrt(w² + eps²). Viscous: −c w.
struct JointFriction {
  double mu = 0.0;               ///< Coulomb coefficient, >= 0
  double radius = 0.0;           ///< pin radius of a revolute joint (m), >= 0
  double viscous = 0.0;          ///< viscous coefficient c >= 0 (N m s or N s/m)
  double regularization = 1e-6;  ///< eps > 0, in units of the relative rate
  /// True when either law is present.
  bool enabled() const { return mu > 0.0 || viscous > 0.0; }
};

/// The kinds of joint. Planar kinds apply between planar bodies (and the ground); spatial kinds
/// between rigid bodies, particles and the ground. Rows per kind: docs/multibody.md.
enum class JointType {
  kRevolute,        ///< planar: common point (2 rows); spatial: + z axes aligned (5 rows)
  kPrismatic,       ///< planar: slide along the parent frame's x, no rotation (2);
                    ///< spatial: slide along the parent frame's z, no rotation (5)
  kWeld,            ///< no relative motion (planar 3, spatial 6)
  kDistance,        ///< |p_C − p_P| = length (1)
  kPointOnLine,     ///< child origin on the parent frame's x line (planar 1) or z line (spatial 2)
  kSpherical,       ///< common point (3)
  kCylindrical,     ///< slide along and turn about the parent z axis (4)
  kUniversal,       ///< common point, parent z ⊥ child z (4)
  kPlanar,          ///< child frame's xy plane slides in the parent's xy plane (3)
  kPointOnPlane,    ///< child origin in the parent frame's xy plane (1)
  kGear,            ///< planar: angle(a) − ratio · angle(b) = its initial value (1, holonomic);
                    ///< spatial: rate(a) − ratio · rate(b) = 0 (1, nonholonomic)
  kRollingDisk,     ///< thin disk (child, axis = child frame z, radius) rolls on z = 0 (1 + 2)
  kRollingSphere,   ///< sphere (child, radius) rolls on z = 0 (1 + 2)
  kContact,         ///< unilateral: a point or sphere (child) above a plane or line of the
                    ///< parent, g = n·d − radius >= 0 (1 row; see contact())
  kContactDisk,     ///< unilateral: a thin disk (child) above a plane of the parent,
                    ///< g = n·d − radius sqrt(1 − (n·a)²) >= 0 (1 row; see contact_disk())
  kContactSpheres,  ///< unilateral: a sphere or point (child) outside a sphere of the parent,
                    ///< g = |c_C − c_P| − (radius + other_radius) >= 0, or inside it
                    ///< (SphereSide::kInside), g = (other_radius − radius) − |c_C − c_P| >= 0
                    ///< (1 row; see contact_spheres())
  kContactDiskSphere,  ///< unilateral: a thin disk (child) outside a sphere of the parent,
                       ///< g = sqrt(s² + m²) − other_radius >= 0, s and m the sphere's centre's
                       ///< offsets from the disk along its axis and beyond its rim
                       ///< (1 row; see contact_disk_sphere())
  kContactSphereBox,   ///< unilateral: a sphere or point (child) outside a box of the parent,
                       ///< g = |u − clamp(u, −h, h)| − radius >= 0, u the sphere's centre in
                       ///< the box's frame, h its half-extents (1 row; see contact_sphere_box())
};

/// True for the unilateral contacts (kContact, kContactDisk, kContactSpheres,
/// kContactDiskSphere, kContactSphereBox). Cost O(1).
inline bool is_contact(JointType type) {
  return type == JointType::kContact || type == JointType::kContactDisk ||
         type == JointType::kContactSpheres || type == JointType::kContactDiskSphere ||
         type == JointType::kContactSphereBox;
}

/// Which side of the other sphere a kContactSpheres contact keeps its sphere on: outside it (two
/// balls) or inside it (a ball in a spherical bowl or shell, a bead inside a ring).
enum class SphereSide {
  kOutside,  ///< outside it: g = |c_C − c_P| − (radius + other_radius) (two balls)
  kInside,   ///< inside it: g = (other_radius − radius) − |c_C − c_P| (a ball in a bowl)
};

/// Short name of a joint type ("revolute", …). Cost O(1).
const char* to_string(JointType type);

/// A joint between a parent and a child body. Use the factory functions below.
struct Joint {
  std::string name;                       ///< unique; names its constraints
  JointType type = JointType::kRevolute;  ///< what it constrains (its rows: JointType)
  BodyId parent = kGround;                ///< the parent body P (kGround: the world)
  BodyId child = kGround;                 ///< the child body C (kGround: the world)
  Frame frame_parent;                     ///< F_P on the parent (body coordinates)
  Frame frame_child;                      ///< F_C on the child (body coordinates)
  double length = 0.0;                    ///< kDistance: the distance (m), > 0
  double radius = 0.0;                    ///< rolling: the radius (m), > 0
  double other_radius = 0.0;  ///< kContactSpheres, kContactDiskSphere: the parent's sphere's radius
  SphereSide side = SphereSide::kOutside;  ///< kContactSpheres: outside or inside that sphere
  /// kContactSphereBox: the box's half-extents along frame_parent's axes (planar: z unused), > 0
  Vector3d box_half = Vector3d::Zero();
  std::string gear_a;  ///< kGear: name of the first revolute joint (a)
  std::string gear_b;  ///< kGear: name of the second revolute joint (b)
  double ratio = 1.0;  ///< kGear: angle_a − ratio · angle_b = const
  /// Prescribed motion of the joint's relative coordinate: revolute: the angle of F_C's x axis
  /// from F_P's x axis about the axis (planar: a linear row; spatial: the angle error by
  /// automatic differentiation); prismatic, cylindrical: the slide of F_C's origin along the
  /// axis. Added as a rheonomic constraint "<name>.drive", whose multiplier is the driving
  /// torque or force (drive_effort).
  MotionFn drive;
  JointFriction friction;  ///< adds a non-ideal force "<name>.friction"
  /// The contacts (is_contact()): Newton's (or Poisson's) coefficient of restitution e in
  /// [0, 1].
  double restitution = 0.0;
  /// The contacts (is_contact()): the law of the impacts (contact_restitution.hpp).
  RestitutionLaw restitution_law = RestitutionLaw::kNewton;
};

/// @name Joint factories (frames in body coordinates)
/// @{

/// A revolute joint: F_P and F_C share their origin (planar: 2 rows); spatial: also their z axes
/// aligned, the axis of rotation (5 rows).
Joint revolute(std::string name, BodyId parent, const Frame& fp, BodyId child, const Frame& fc);
/// A prismatic joint: F_C slides along F_P's x axis (planar, 2 rows) or z axis (spatial, 5 rows)
/// without relative rotation.
Joint prismatic(std::string name, BodyId parent, const Frame& fp, BodyId child, const Frame& fc);
/// A weld: F_C held on F_P, no relative motion (planar 3 rows, spatial 6).
Joint weld(std::string name, BodyId parent, const Frame& fp, BodyId child, const Frame& fc);
/// A distance constraint (massless rod): |p_C − p_P| = length (m, > 0) between the parent's
/// point p_parent and the child's point p_child (body coordinates); 1 row.
Joint distance(std::string name, BodyId parent, const Vector3d& p_parent, BodyId child,
               const Vector3d& p_child, double length);
/// The child's point p_child (body coordinates) on the line through F_P's origin along its x axis
/// (planar, 1 row) or z axis (spatial, 2 rows).
Joint point_on_line(std::string name, BodyId parent, const Frame& fp, BodyId child,
                    const Vector3d& p_child);
/// A ball joint: the parent's point p_parent and the child's point p_child (body coordinates)
/// coincide; 3 rows.
Joint spherical(std::string name, BodyId parent, const Vector3d& p_parent, BodyId child,
                const Vector3d& p_child);
/// A cylindrical joint: F_C slides along and turns about F_P's z axis; 4 rows.
Joint cylindrical(std::string name, BodyId parent, const Frame& fp, BodyId child, const Frame& fc);
/// A universal (Cardan) joint: F_P and F_C share their origin, and F_P's z axis stays
/// perpendicular to F_C's z axis; 4 rows.
Joint universal(std::string name, BodyId parent, const Frame& fp, BodyId child, const Frame& fc);
/// A planar joint (JointType::kPlanar, spatial): F_C's xy plane slides in F_P's xy plane; 3 rows.
Joint planar_joint(std::string name, BodyId parent, const Frame& fp, BodyId child, const Frame& fc);
/// The child's point p_child (body coordinates) in F_P's xy plane; 1 row.
Joint point_on_plane(std::string name, BodyId parent, const Frame& fp, BodyId child,
                     const Vector3d& p_child);
/// A gear between revolute joints a and b: planar, angle(a) − ratio · angle(b) = its initial
/// value; spatial, (ω_Ca − ω_Pa)·z_Pa = ratio (ω_Cb − ω_Pb)·z_Pb (velocity level: the initial
/// rates must satisfy it).
Joint gear(std::string name, std::string joint_a, std::string joint_b, double ratio);
/// A thin disk of `radius` rolling without slipping on the plane z = 0; its axis is the z axis
/// of `axis_frame` (child coordinates; the disk's centre is the body's centre of mass).
Joint rolling_disk(std::string name, BodyId disk, double radius, const Frame& axis_frame = {});
/// A sphere of `radius` (centre = centre of mass) rolling without slipping on z = 0.
Joint rolling_sphere(std::string name, BodyId sphere, double radius);
/// A unilateral contact (JointType::kContact, docs/contact.md, "Contacts on bodies"): the point
/// p_body of `body` (body coordinates), or a sphere of `radius` centred there, stays on the
/// positive side of a plane fixed on `plane_body` (kGround: the world). The plane is the frame
/// `plane`'s xy plane with normal n = its z axis (spatial models), or its x line with normal
/// n = its y axis (planar models). One holonomic row, made Constraint::unilateral(restitution):
///   g = n_W · (c_W − o_W) − radius >= 0,
/// c_W the world position of p_body, o_W of the plane frame's origin — the row of
/// point_on_plane (point_on_line in a planar model) with the offset c0 = radius, so it costs
/// what that bilateral joint costs: O(columns) for A and b in closed form. A particle takes it
/// (its point does not rotate). Checked by build(): radius >= 0, restitution in [0, 1], and the
/// usual body checks.
Joint contact(std::string name, BodyId plane_body, const Frame& plane, BodyId body,
              const Vector3d& p_body, double radius = 0.0, double restitution = 0.0);
/// A unilateral contact of a thin disk with a plane (JointType::kContactDisk; spatial models):
/// the disk of `radius` centred at disk.p on `body` with axis a = disk's z axis (body
/// coordinates) stays above the xy plane of `plane` on `plane_body`, normal n its z axis. Its
/// lowest point towards the plane is at distance radius · sqrt(1 − s²), s = n_W · a_W, from the
/// centre c_W along −n, so the gap row is
///   g = n_W · (c_W − o_W) − radius sqrt(1 − s²) >= 0,
/// in closed form: with h = sqrt(1 − s²), A = A_{n·d} + (radius s / h) A_s and
/// b = b_{n·d} + (radius s / h) b_s − radius s'² / h³ (A_s, b_s the dot row of s = n·a).
/// O(columns) for A and b, about twice the point contact's. A disk lying flat on the plane
/// (|s| = 1: no single lowest point, h = 0) is refused by build() at the initial pose; in a
/// run the row's entries become infinite there, which stops the run with a non-finite status
/// (never a wrong number). Needs rigid bodies (a planar model's disk is a circle: use contact()
/// with the radius).
Joint contact_disk(std::string name, BodyId plane_body, const Frame& plane, BodyId body,
                   const Frame& disk, double radius, double restitution = 0.0);
/// A unilateral contact of two spheres (JointType::kContactSpheres; docs/contact.md, "Contacts
/// on bodies"): the sphere of `radius` centred at p_body on `body` stays outside the sphere of
/// `other_radius` centred at p_other on `other_body` (kGround: a fixed sphere). Either radius
/// may be 0 (a point). One holonomic row, made Constraint::unilateral(restitution):
///   g = |c_W − o_W| − (radius + other_radius) >= 0,
/// c_W, o_W the world positions of the centres, with u = (c_W − o_W)/|c_W − o_W|:
///   A = uᵀ (J_c − J_o),  b = −(u·(J'q')_(c−o) + (|v|² − (u·v)²) / |c_W − o_W|),
/// v = c_W' − o_W' (the normal is the line of centres; the second term is its turning).
/// With side = SphereSide::kInside the sphere stays inside the other (a ball in a spherical
/// bowl or shell, a bead inside a ring; other_radius > radius):
///   g = (other_radius − radius) − |c_W − o_W| >= 0,   A and b the above with their sign flipped
/// (the same row with the sign −1 and the length other_radius − radius: the same cost).
/// O(columns) for A and b, about the point contact's. Planar models: circles in the plane.
/// Coincident centres (no normal) are refused by build() at the initial pose, and so are, for
/// kInside, radius >= other_radius and a centre outside the other sphere at the start; in a run
/// the row's entries become non-finite at coincident centres, which stops the run (never a
/// wrong number).
Joint contact_spheres(std::string name, BodyId other_body, const Vector3d& p_other,
                      double other_radius, BodyId body, const Vector3d& p_body, double radius,
                      double restitution = 0.0, SphereSide side = SphereSide::kOutside);
/// A unilateral contact of a thin disk with a sphere (JointType::kContactDiskSphere; spatial
/// models; docs/contact.md, "Contacts on bodies"): the disk of `radius` centred at disk.p on
/// `body`, axis k = disk's z axis (body coordinates), stays outside the sphere of
/// `other_radius` (>= 0: 0 is a point) centred at p_other on `other_body` (kGround: a fixed
/// sphere). With e = c_W − o_W (the disk's centre from the sphere's), its offset along the axis
/// s = k_W·e, the in-plane part w = e − s k_W, ρ = |w| and m = max(ρ − radius, 0), the
/// distance from the sphere's centre to the disk (its face where m = 0, its rim beyond) is
/// sqrt(s² + m²), so the gap row is
///   g = sqrt(s² + m²) − other_radius >= 0,
/// the normal n = (s k_W + m w/ρ)/sqrt(s² + m²) (from the sphere to the disk), the contact
/// point the disk's point nearest the sphere's centre. In closed form:
///   A = (s A_s + m A_ρ)/E,  b = (s b_s + m b_ρ)/E − (m s' − s m')²/E³,  E = sqrt(s² + m²),
/// with A_s, b_s the dot row of s = k·e and A_ρ = ŵᵀ (J_e − s J_k),
/// b_ρ = −(ŵ·(g_e − 2 s' k' − s g_k) + (|w'|² − ρ'²)/ρ) (ŵ = w/ρ; zero on the face; the terms
/// in ŵ·k, zero for a unit axis, are kept in the code). The row is
/// C¹ across the rim (m = 0 there on both sides). O(columns) for A and b, about twice the two
/// spheres' row. Needs a rigid disk body; build() refuses a sphere's centre on the rim
/// (E = 0: no normal) at the initial pose, and in a run the row's entries become non-finite
/// there, which stops the run (never a wrong number). A planar model's disk is a circle: use
/// contact_spheres() with its radius.
Joint contact_disk_sphere(std::string name, BodyId other_body, const Vector3d& p_other,
                          double other_radius, BodyId body, const Frame& disk, double radius,
                          double restitution = 0.0);
/// A unilateral contact of a sphere (or point: radius 0) with a box (JointType::kContactSphereBox;
/// docs/contact.md, "A sphere against a box"): the sphere of `radius` centred at p_body on `body`
/// stays outside the box of half-extents `half` whose centre and axes are the frame `box` on
/// `other_body` (kGround: a fixed box; planar models: a rectangle, half.z() unused). With
/// u_i = k_i·e the components of e = c_W − o_W (the sphere's centre from the box's) along the
/// box's unit axes k_i, σ_i = sign(u_i) and the excesses m_i = max(σ_i u_i − h_i, 0), the
/// distance from the centre to the box (a face where one m_i > 0, an edge where two, a corner
/// where three) is E = sqrt(Σ m_i²), so the gap row is
///   g = E − radius >= 0,  n = Σ σ_i m_i k_i / E (from the box to the sphere),
///   A = Σ (σ_i m_i / E) A_ui,  b = Σ (σ_i m_i / E) b_ui − (Σ_{m_i>0} u_i'² − E'²)/E,
/// with u_i'' = A_ui q'' − b_ui the dot rows of k_i·e (the last term, the normal's turning, is
/// zero on a face). The row is C¹ where the face, edge and corner regions meet (m_i = 0 there on
/// both sides). With the centre inside the box (every m_i = 0; a penetration deeper than the
/// radius) g = max_i(σ_i u_i − h_i) − radius, the nearest face's row. O(columns) for A and b,
/// about three dot rows. build() refuses a centre inside or on the box at the initial pose (no
/// normal: E = 0), half-extents that are not > 0 and a box and sphere on one body.
Joint contact_sphere_box(std::string name, BodyId other_body, const Frame& box,
                         const Vector3d& half, BodyId body, const Vector3d& p_body, double radius,
                         double restitution = 0.0);
/// @}

/// Applied force at a body point and torque (world frame W), from (q, q', t).
struct Wrench {
  Vector3d force = Vector3d::Zero();   ///< F (N), applied at the point
  Vector3d torque = Vector3d::Zero();  ///< tau (N m) about the body's centre of mass (planar: z)
};
/// Callable of an applied wrench. Must not allocate.
using WrenchFn = std::function<Wrench(const Eigen::Ref<const VectorXd>& q,
                                      const Eigen::Ref<const VectorXd>& qd, double t)>;

/// The kinds of force element.
enum class ForceType {
  kSpringDamper,   ///< between two body points: F = (k (l − l0) + c l') along the line
  kTorsionSpring,  ///< torque −k (dtheta − theta0) − c dtheta' between two bodies (see
                   ///< torsion_spring)
  kApplied,        ///< an applied wrench (WrenchFn) on one body at one point
};

/// A force element (gravity is Multibody::set_gravity).
struct Force {
  std::string name;                      ///< unique; names the force in reports
  ForceType type = ForceType::kApplied;  ///< the kind of element
  BodyId body_a = kGround;               ///< the first body (kApplied: the body acted on)
  BodyId body_b = kGround;               ///< the second body (unused by kApplied)
  Vector3d point_a = Vector3d::Zero();   ///< the point on body_a (body coordinates, m)
  Vector3d point_b = Vector3d::Zero();   ///< the point on body_b (body coordinates, m)
  double stiffness = 0.0;                ///< k (N/m, or N m/rad for a torsion spring)
  double damping = 0.0;                  ///< c (N s/m, or N m s/rad for a torsion spring)
  double rest = 0.0;                     ///< l0 (m), or theta0 (rad) for a torsion spring
  WrenchFn wrench;                       ///< kApplied
};

/// Spring-damper between body points (l0 = rest length). Potential ½ k (l − l0)².
Force spring_damper(std::string name, BodyId a, const Vector3d& pa, BodyId b, const Vector3d& pb,
                    double k, double c, double rest_length);
/// Torsional spring-damper between two planar bodies: torque −k (theta_b − theta_a − theta0) −
/// c (theta_b' − theta_a') on b (and its opposite on a). Between two rigid bodies (or one and the
/// ground): an isotropic rotational spring, torque −k theta n − c (omega_b − omega_a) on b with
/// theta n the rotation vector of b relative to a (|theta| < pi; V = ½ k theta²); theta0 must be
/// 0 (the rest orientation is the bodies' frames aligned). About a revolute joint's axis it is
/// that joint's torsion spring. Checked by build().
Force torsion_spring(std::string name, BodyId a, BodyId b, double k, double c, double theta0);
/// An applied wrench on `body`, the force acting at body point p.
Force applied(std::string name, BodyId body, const Vector3d& p, WrenchFn fn);

/// Metadata of a body in a built model.
struct BodyInfo {
  std::string name;                     ///< as given to Multibody::add_*
  BodyKind kind = BodyKind::kParticle;  ///< which coordinates it carries
  Index offset = 0;                     ///< first coordinate
  Index size = 0;                       ///< 3 or 7
  double mass = 0.0;                    ///< m (kg)
  Vector3d inertia = Vector3d::Zero();  ///< principal moments about the centre of mass (planar: z)
};

/// Metadata of a joint in a built model.
struct JointInfo {
  std::string name;                        ///< as given to the factory
  JointType type = JointType::kRevolute;   ///< the joint's kind
  BodyId parent = kGround;                 ///< the parent body P (kGround: the world)
  BodyId child = kGround;                  ///< the child body C (kGround: the world)
  Frame frame_parent;                      ///< F_P on the parent (body coordinates)
  Frame frame_child;                       ///< F_C on the child (body coordinates)
  bool planar = false;                     ///< between planar bodies
  SphereSide side = SphereSide::kOutside;  ///< kContactSpheres: outside or inside the other
  Vector3d box_half = Vector3d::Zero();    ///< kContactSphereBox: the box's half-extents
  std::vector<Index> constraints;          ///< indices in System of its constraints (joint, drive)
  Index drive = -1;                        ///< index of the "<name>.drive" constraint, or −1
  Index friction = -1;                     ///< index of its non-ideal force, or −1
  JointFriction friction_law;              ///< its friction parameters (for the reports)
};

/// The result of Multibody::build(): the System, a consistent initial state and metadata.
struct MultibodyModel {
  System system;                  ///< ready for Workspace, forward_dynamics, simulate
  VectorXd q0;                    ///< initial coordinates (n), from the bodies' initial poses
  VectorXd qd0;                   ///< initial velocities (n), from the bodies' initial velocities
  std::vector<BodyInfo> bodies;   ///< by BodyId
  std::vector<JointInfo> joints;  ///< in the order added
  Vector3d gravity = Vector3d::Zero();  ///< g (m/s², world), as set by Multibody::set_gravity
  /// Index of a body by name. @throws std::invalid_argument listing the names.
  BodyId body(std::string_view name) const;
  /// The flags SimulationOptions::angle_coordinates takes (n): true for a planar body's theta,
  /// false for the positions (x, y, z) and a rigid body's quaternion u0 … u3 (docs/simulation.md,
  /// "Scales and tolerances", says why), so that the run's
  /// violation scales weigh a joint's columns of angles by 1 and not by the model's length
  /// (docs/simulation.md, "Scales and tolerances"; a model file's bodies get them from their
  /// units). Cost O(n).
  std::vector<bool> angle_coordinates() const;
  /// Index of a joint by name. @throws std::invalid_argument listing the names.
  Index joint(std::string_view name) const;
};

/// Collects bodies, joints and forces; build() turns them into a MultibodyModel.
class Multibody {
 public:
  Multibody();
  ~Multibody();
  /// A deep copy: the copy's bodies, joints and forces are independent of the original's.
  Multibody(const Multibody&);
  /// A deep copy, as the copy constructor.
  Multibody& operator=(const Multibody&);

  /// A particle of mass m > 0 at p0 with velocity v0 (world).
  BodyId add_particle(std::string name, double mass, const Vector3d& p0,
                      const Vector3d& v0 = Vector3d::Zero());
  /// A planar body of mass m > 0 and inertia I > 0 about its centre of mass; pose0 = (x, y,
  /// theta), vel0 = (x', y', theta').
  BodyId add_planar_body(std::string name, double mass, double inertia, const Vector3d& pose0,
                         const Vector3d& vel0 = Vector3d::Zero());
  /// A rigid body of mass m > 0 with principal inertia (J1, J2, J3) > 0 about its centre of mass
  /// (body axes = principal axes); pose: centre of mass r0 and orientation R_WB = u0;
  /// velocity v0 (world) and angular velocity w0 (world).
  BodyId add_rigid_body(std::string name, double mass, const Vector3d& inertia, const Vector3d& r0,
                        const Quaterniond& u0, const Vector3d& v0 = Vector3d::Zero(),
                        const Vector3d& w0 = Vector3d::Zero());
  /// Adds a joint (checked in build()).
  Multibody& add_joint(Joint joint);
  /// Adds a force element (checked in build()).
  Multibody& add_force(Force force);
  /// Coulomb friction at contact `contact` (a point, sphere or disk contact() / contact_disk()
  /// on a plane of the ground or of a moving body, or contact_spheres(); docs/contact.md,
  /// "Friction at a body's contact"): a CoulombFriction named "coulomb.<contact>" whose sliding
  /// velocity is the contact point's (ContactKinematics, made by build()): v_rel = T q' with T the
  /// tangent rows of the Jacobian of the body's material point at the contact, v_P = v(centre) + ω
  /// × a (a = −r n, or a disk's rim point most opposed to n), less that of the plane body's
  /// material point there, p' + ω_P × (x − p), with n and t_i turning with the plane body;
  /// friction C = Tᵀ f, |f| = mu N with N the physical normal force; sticking T q' = 0 while
  /// |holding force| <= mu_static N. build() @throws std::invalid_argument on an unknown
  /// contact, mu < 0, mu_static < mu or regularization_velocity <= 0.
  Multibody& add_contact_friction(std::string contact, double mu,
                                  std::optional<double> mu_static = {},
                                  double regularization_velocity = 1e-9);
  /// Uniform gravity g (world; e.g. (0, −9.81, 0) for planar, (0, 0, −9.81) for spatial).
  Multibody& set_gravity(const Vector3d& g);
  /// The switching functions g(q, q', t) of non-smooth terms in the applied forces and the
  /// drives, one name each (SystemBuilder::switching_functions): simulate() locates their sign
  /// changes as events (SimulationOptions::switch_events). `fn` gets the bodies' scratch (a
  /// PoseCache), which it must not use. Default: none.
  Multibody& set_switching_functions(std::vector<std::string> names, SwitchScratchFn fn);

  /// Builds the System: coordinates named "<body>.x" … "<body>.u3"; one constant mass block per
  /// particle, planar body and rigid translation, one state-dependent 4 × 4 block per quaternion;
  /// the constraints "<body>.unit", then per joint "<joint>" (and "<joint>.drive",
  /// "<joint>.contact" for rolling height; unilateral for a contact); forces Q = gravity +
  /// springs + applied + the quaternion's velocity terms; potential energy of gravity and springs.
  /// @throws std::invalid_argument naming the problem (unknown body, joint between bodies of
  /// different kinds, bad parameter, a gear on a non-planar-revolute joint, duplicate names).
  MultibodyModel build() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Pose of a body at q: position of its centre of mass and orientation (planar: rotation about z
/// by theta; particle: identity).
struct Pose {
  Vector3d p_WB = Vector3d::Zero();            ///< centre of mass in world coordinates (m)
  Quaterniond R_WB = Quaterniond::Identity();  ///< orientation: rotates body B to world W
};
/// The pose of body b at q (the quaternion normalized). Cost O(1).
Pose body_pose(const MultibodyModel& mb, const Eigen::Ref<const VectorXd>& q, BodyId b);
/// Velocity of the centre of mass and angular velocity (world) of body b. Cost O(1).
std::pair<Vector3d, Vector3d> body_velocity(const MultibodyModel& mb,
                                            const Eigen::Ref<const VectorXd>& q,
                                            const Eigen::Ref<const VectorXd>& qd, BodyId b);
/// Kinetic energy of body b: ½ m v² + ½ ω_Bᵀ J ω_B. Cost O(1).
double kinetic_energy(const MultibodyModel& mb, const Eigen::Ref<const VectorXd>& q,
                      const Eigen::Ref<const VectorXd>& qd, BodyId b);
/// Total mechanical energy: kinetic energies + potential of gravity and springs. Cost O(bodies).
double total_energy(const MultibodyModel& mb, const Eigen::Ref<const VectorXd>& q,
                    const Eigen::Ref<const VectorXd>& qd, double t);
/// Linear momentum Σ m v and angular momentum about the world origin Σ (r × m v + R J ω_B).
std::pair<Vector3d, Vector3d> momentum(const MultibodyModel& mb,
                                       const Eigen::Ref<const VectorXd>& q,
                                       const Eigen::Ref<const VectorXd>& qd);
/// The world position of body point p (body coordinates) at q.
Vector3d world_point(const MultibodyModel& mb, const Eigen::Ref<const VectorXd>& q, BodyId b,
                     const Vector3d& p);

/// Reaction of a joint on its child body (on its parent when the child is the ground), reduced
/// to the joint point (the origin of F_C, at its world position):
///   force_W, torque_W      ideal part, world frame;
///   force_B, torque_B      the same in the body's frame;
///   nonideal_force_W, nonideal_torque_W   the joint friction (its C), world frame.
/// For a planar joint the torque is along z. From the joint's share A_kᵀ lambda_k of the ideal
/// generalized force (the drive's share is reported separately, see drive_effort).
struct JointReaction {
  BodyId body = kGround;                          ///< the body the reaction acts on
  Vector3d force_W = Vector3d::Zero();            ///< ideal reaction force (N), world frame
  Vector3d torque_W = Vector3d::Zero();           ///< ideal reaction torque (N m), world frame
  Vector3d force_B = Vector3d::Zero();            ///< force_W in the body's frame
  Vector3d torque_B = Vector3d::Zero();           ///< torque_W in the body's frame
  Vector3d nonideal_force_W = Vector3d::Zero();   ///< joint friction force (N), world frame
  Vector3d nonideal_torque_W = Vector3d::Zero();  ///< joint friction torque (N m), world frame
};

/// The reaction of joint j at (q, q', t) given the multipliers lambda (m) of an evaluation
/// (ws.lambda, or a Trajectory sample's lambda). The non-ideal part is zero in this overload.
/// Allocates (a report, not for the hot path). Cost O(rows · columns of the joint).
JointReaction joint_reaction(const MultibodyModel& mb, const Eigen::Ref<const VectorXd>& q,
                             const Eigen::Ref<const VectorXd>& qd, double t,
                             const Eigen::Ref<const VectorXd>& lambda, Index j);
/// As above, after forward_dynamics(mb.system, ws, q, qd, t): also the joint friction's force.
JointReaction joint_reaction(const MultibodyModel& mb, Workspace& ws,
                             const Eigen::Ref<const VectorXd>& q,
                             const Eigen::Ref<const VectorXd>& qd, double t, Index j);
/// The driving torque (revolute) or force (prismatic) of joint j's prescribed motion: the
/// generalized force of "<joint>.drive" along the driven coordinate. @throws std::invalid_argument
/// when the joint has no drive.
double drive_effort(const MultibodyModel& mb, const Eigen::Ref<const VectorXd>& q,
                    const Eigen::Ref<const VectorXd>& qd, double t,
                    const Eigen::Ref<const VectorXd>& lambda, Index j);

/// Writes every body's pose at every sample of tr as CSV for animation: a header
/// `t,<b>.x,<b>.y,<b>.z,<b>.qw,<b>.qx,<b>.qy,<b>.qz,…` then one line per sample.
/// @throws std::runtime_error when the file cannot be written, std::invalid_argument when tr
/// does not belong to mb (size).
void write_poses_csv(const MultibodyModel& mb, const Trajectory& tr, const std::string& path);

/// The multibody columns of a model run's CSV (modelfile/run.hpp), one value per sample of tr, in
/// order:
///  - `<b>.x, <b>.y, <b>.z, <b>.qw, <b>.qx, <b>.qy, <b>.qz` for every body (its pose, as
///    write_poses_csv), except the components that are coordinates of the system (the centre
///    of mass `<b>.x, <b>.y` of a planar body, `<b>.x, <b>.y, <b>.z` of a rigid body or a
///    particle: the standard coordinate columns hold them), so that no name repeats one of
///    csv_columns();
///  - `<b>.kinetic_energy` for every body (kinetic_energy);
///  - per joint, its ideal reaction on its child (joint_reaction from the sample's lambda,
///    world frame, reduced to the joint point): `reaction.<j>.fx, .fy, .tz` for a planar joint,
///    `reaction.<j>.fx, .fy, .fz, .tx, .ty, .tz` for a spatial one (rolling contacts: at the
///    centre); with friction the same components of the friction force as
///    `reaction.<j>.friction_fx, …` (an evaluation per sample; NaN where it fails); with a
///    drive its effort `drive.<j>` (drive_effort); a gear: its multiplier
///    `reaction.<j>.torque` (the torque along joint a's angle or rate).
/// @throws std::invalid_argument when tr does not belong to mb (sizes).
/// Cost O(N × (bodies + joints × joint rows × joint columns)), plus one forward_dynamics per
/// sample when a joint has friction.
std::vector<CsvColumn> report_csv_columns(const MultibodyModel& mb, const Trajectory& tr);

}  // namespace ukdyn::mb

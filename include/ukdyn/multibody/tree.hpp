// SPDX-License-Identifier: BSD-3-Clause
/// @file multibody/tree.hpp
/// A kinematic tree in joint coordinates as ukdyn's unconstrained system M(q) q'' = Q(q, q', t)
/// (Featherstone, *Rigid Body Dynamics Algorithms*, 2008; Pinocchio's Model/Data, MuJoCo's
/// mjModel/mjData). The description (Tree) is built once; every pass writes into a TreeData
/// sized from it, so no pass allocates.
///
/// Glossary (Featherstone's symbols; frames in the names, Drake's monogram style):
///   link i        a rigid body; its frame L_i is the child frame of its joint (URDF's
///                 convention: L_i = parent frame · origin(xyz, rpy) · joint motion)
///   λ(i)          the parent link of link i (-1: the world)
///   S_i (6 × n_i) motion subspace of joint i in L_i coordinates, spatial motion [ω; v]
///   X_i           the motion transform from λ(i) coordinates to L_i coordinates
///   I_i (6 × 6)   spatial inertia of link i about the origin of L_i, in L_i coordinates
///   Ic_i          composite inertia of the subtree rooted at i (CRBA)
///   v_i, a_i, f_i spatial velocity, acceleration and force of link i (RNEA)
///   h(q, q')      bias forces C(q, q') q' + g(q) (MuJoCo's qfrc_bias): M q'' + h = τ
///
/// Coordinates: per joint, in link order — revolute, continuous: the angle (rad); prismatic: the
/// displacement (m); fixed: none; floating: (x, y, z, u0, u1, u2, u3), the position of L in the
/// world and the unit quaternion u of R_WL (u0 the scalar part), exactly as a rigid body of
/// multibody.hpp: its velocities are the coordinates' time derivatives, ω_L = 2 E(u) u', the
/// unit norm kept by the constraint "<link>.unit" (u·u'' = −u'·u') that completes the then
/// singular M (docs/singular-mass.md).
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/core/types.hpp"
#include "ukdyn/core/units.hpp"

/// Kinematic trees in joint coordinates (URDF robots): Featherstone's recursions (this file).
namespace ukdyn::tree {

using Eigen::Matrix3d;
using Eigen::Vector3d;
/// A spatial vector (Featherstone): motion (angular; linear) or force (moment; force), 6 × 1.
using Vector6d = Eigen::Matrix<double, 6, 1>;
/// A spatial matrix (an inertia or a transform), 6 × 6.
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// The joints a tree knows (URDF's, planar excepted).
enum class JointKind {
  kFixed,       ///< no coordinate
  kRevolute,    ///< rotation about `axis` by q (limited)
  kContinuous,  ///< rotation about `axis` by q (unlimited)
  kPrismatic,   ///< translation along `axis` by q
  kFloating,    ///< 7 coordinates: position and unit quaternion (root links only)
};

/// Name of a joint kind as URDF spells it ("revolute", …, "floating").
const char* joint_kind_name(JointKind k);
/// Number of coordinates of a joint kind (0, 1 or 7).
int joint_coordinates(JointKind k);

/// The joint that attaches a link to its parent: its fixed origin in the parent's frame, its
/// kind and axis (unit, in the joint frame) and what URDF says of it. Damping (viscous,
/// −damping · q') and friction (Coulomb, make_system) act; limits and effort are checked
/// (check_joint_limits, check_effort_limits), velocity is kept. URDF's `<mimic>` is a holonomic
/// constraint "<joint>.mimic" of make_system: q_j = mimic_multiplier · q_ref + mimic_offset.
struct Joint {
  std::string name;                                          ///< unique in the tree
  JointKind kind = JointKind::kFixed;                        ///< what moves
  Vector3d p_PJ = Vector3d::Zero();                          ///< origin xyz in the parent frame
  Eigen::Quaterniond R_PJ = Eigen::Quaterniond::Identity();  ///< origin rpy as a rotation
  Vector3d axis = Vector3d::UnitX();                         ///< unit axis in the joint frame
  double damping = 0.0;   ///< viscous damping (N·m·s/rad or N·s/m), >= 0
  double friction = 0.0;  ///< URDF's friction: Coulomb torque (N·m) or force (N), >= 0
  double lower = -std::numeric_limits<double>::infinity();    ///< position limit
  double upper = std::numeric_limits<double>::infinity();     ///< position limit
  double effort = std::numeric_limits<double>::infinity();    ///< effort limit (kept)
  double velocity = std::numeric_limits<double>::infinity();  ///< velocity limit (kept)
  /// URDF's `<mimic joint=…>`: the joint whose coordinate this one follows (empty: none); both
  /// must have one coordinate (revolute, continuous, prismatic)
  std::string mimic;
  double mimic_multiplier = 1.0;  ///< q_j = mimic_multiplier · q_ref + mimic_offset (finite)
  double mimic_offset = 0.0;      ///< (rad or m, the unit of q_j; finite)
};

/// A mimic relation of the tree (Joint::mimic) by coordinates: q[coordinate] = multiplier ·
/// q[reference] + offset.
struct Mimic {
  Index link = -1;          ///< the following joint's link
  Index coordinate = -1;    ///< its coordinate
  Index reference = -1;     ///< the coordinate it follows
  double multiplier = 1.0;  ///< the factor
  double offset = 0.0;      ///< the offset
};

/// Mass properties of a link: mass, centre of mass and the 3 × 3 inertia about the centre of
/// mass, both in the link frame (URDF's `<inertial>`, its rpy already applied).
struct Inertial {
  double mass = 0.0;                  ///< kg, >= 0
  Vector3d com = Vector3d::Zero();    ///< centre of mass in the link frame
  Matrix3d I_com = Matrix3d::Zero();  ///< inertia about the com, link axes (symmetric PSD)
};

/// One link of the tree and the joint to its parent.
struct Link {
  std::string name;    ///< unique in the tree
  std::string parent;  ///< the parent link's name; empty for a root (attached to the world)
  Joint joint;         ///< the joint to the parent (to the world for a root)
  Inertial inertial;   ///< mass properties
};

/// The description of a kinematic tree: links sorted so that every parent precedes its
/// children, coordinate offsets, spatial inertias. Immutable once built.
class Tree {
 public:
  /// Builds and checks the tree. `gravity` is the world's gravitational acceleration (m/s²).
  /// @throws std::invalid_argument naming the link or joint: duplicate or empty names, an
  /// unknown parent, a cycle, a floating joint that is not a root's, a zero or non-finite
  /// axis, negative mass or damping, an inertia that is not symmetric positive semi-definite
  /// or not finite, a moving subtree without mass (M would be singular); a mimic of an unknown
  /// joint, of itself, of or by a joint without exactly one coordinate, with a non-finite
  /// multiplier or offset, or on a cycle of mimics. Cost O(links) (hashing the names).
  Tree(std::string name, std::vector<Link> links, Vector3d gravity = Vector3d(0, 0, -9.81));

  const std::string& name() const { return name_; }                      ///< the robot's name
  Index coordinate_count() const { return n_; }                          ///< n
  Index link_count() const { return Index(links_.size()); }              ///< links, parents first
  const Link& link(Index i) const { return links_.at(std::size_t(i)); }  ///< link i
  Index parent(Index i) const { return parent_[std::size_t(i)]; }        ///< λ(i), -1 for a root
  Index offset(Index i) const { return offset_[std::size_t(i)]; }        ///< first coordinate of i
  int dofs(Index i) const { return dofs_[std::size_t(i)]; }              ///< n_i
  /// I_i, the spatial inertia of link i about its frame's origin ([ω; v] order).
  const Matrix6d& spatial_inertia(Index i) const { return inertia_[std::size_t(i)]; }
  const Vector3d& gravity() const { return gravity_; }  ///< g in the world (m/s²)
  /// R_PJ of link i's joint origin as a matrix (precomputed for forward_kinematics).
  const Matrix3d& joint_rotation(Index i) const { return R_PJ_[std::size_t(i)]; }
  /// Index of the link called `name`. @throws std::invalid_argument naming it. Cost O(links).
  Index link_index(std::string_view name) const;
  /// Coordinate names: "<joint>" for one coordinate, "<link>.x" … "<link>.u3" for a floating
  /// base (the names multibody.hpp gives a rigid body).
  const std::vector<std::string>& coordinate_names() const { return names_; }
  /// The zero configuration: zero angles and displacements, identity quaternions (n) — except
  /// that a mimic joint sits at multiplier · q_ref + offset (so the pose meets the mimics).
  VectorXd neutral() const;
  /// The flags SimulationOptions::angle_coordinates takes (n): true for a revolute or
  /// continuous joint's angle, false for a prismatic joint's displacement and a floating base's
  /// position and quaternion u0 … u3 (docs/simulation.md, "Scales and tolerances", says why), so
  /// that the run's violation scales
  /// weigh a loop closure's columns of angles by 1 and not by the robot's length
  /// (docs/simulation.md, "Scales and tolerances"; a model file's robot gets them from its
  /// joints' units). Cost O(links).
  std::vector<bool> angle_coordinates() const;
  /// The links whose joint is floating (each gets a unit-norm constraint in make_system).
  const std::vector<Index>& floating_links() const { return floating_; }
  /// The mass of link i and of every link below it (kg), accumulated once at construction.
  double subtree_mass(Index i) const { return subtree_mass_[std::size_t(i)]; }
  /// The mimic relations (Joint::mimic), in link order of the following joints; make_system
  /// adds one constraint "<joint>.mimic" for each.
  const std::vector<Mimic>& mimics() const { return mimics_; }

 private:
  std::string name_;
  std::vector<Link> links_;
  std::vector<Index> parent_, offset_, floating_;
  std::vector<int> dofs_;
  std::vector<Matrix6d, Eigen::aligned_allocator<Matrix6d>> inertia_;
  std::vector<Matrix3d, Eigen::aligned_allocator<Matrix3d>> R_PJ_;
  std::vector<std::string> names_;
  std::vector<double> subtree_mass_;
  std::vector<Mimic> mimics_;
  Vector3d gravity_;
  Index n_ = 0;
};

/// Everything a pass over a Tree writes (Pinocchio's Data), sized once from the tree: no pass
/// allocates. One TreeData per thread.
struct TreeData {
  /// Sizes every buffer for `tree`. Allocates (once).
  explicit TreeData(const Tree& tree);

  /// A motion subspace S_i: 6 × n_i with n_i <= 7, stored in place (no heap).
  using S6 = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 7>;
  /// A vector of fixed-size Eigen objects (aligned storage).
  template <class T>
  using Aligned = std::vector<T, Eigen::aligned_allocator<T>>;
  Aligned<Eigen::Matrix3d> R_WL;  ///< (links) orientation of L_i in the world, forward_kinematics
  Aligned<Vector3d> p_WL;         ///< (links) origin of L_i in the world, forward_kinematics
  Aligned<Eigen::Matrix3d> E;  ///< (links) R_λL ᵀ: λ(i) → L_i coordinates, forward_kinematics
  Aligned<Vector3d> r;         ///< (links) origin of L_i in λ(i) coordinates, forward_kinematics
  Aligned<S6> S;               ///< (links) S_i (6 × n_i), forward_kinematics
  Aligned<Vector6d> v;         ///< (links) spatial velocity of L_i (L_i coordinates), rnea
  Aligned<Vector6d> a;         ///< (links) spatial acceleration of L_i, gravity as −g, rnea
  Aligned<Vector6d> f;         ///< (links) spatial force across joint i (L_i coordinates), rnea
  Aligned<Matrix6d> Ic;        ///< (links) composite inertias: mass_matrix
  Index tree_size = 0;         ///< the tree's link count, to refuse another tree's data
  std::vector<int> dofs;       ///< (links) n_i of the tree it was made for, likewise
};

/// Forward kinematics: every link's pose (R_WL, p_WL), the transforms X_i and the subspaces S_i
/// at q (n). The quaternion of a floating joint is normalized for the pose. Cost O(links).
/// @throws std::invalid_argument on a q or data of the wrong size.
void forward_kinematics(const Tree& tree, const Eigen::Ref<const VectorXd>& q, TreeData& data);

/// M(q) (n × n) by the composite-rigid-body algorithm (Featherstone, algorithm 6.2), exploiting
/// branch sparsity (entries of links on different branches are zero). Runs forward_kinematics.
/// Cost O(n · depth). @throws std::invalid_argument on wrong sizes.
void mass_matrix(const Tree& tree, const Eigen::Ref<const VectorXd>& q, TreeData& data,
                 Eigen::Ref<MatrixXd> M);

/// Inverse dynamics τ = M(q) q'' + h(q, q') by recursive Newton–Euler (Featherstone, algorithm
/// 5.1), gravity included, no damping. Runs forward_kinematics. Cost O(links).
/// @throws std::invalid_argument on wrong sizes.
void inverse_dynamics(const Tree& tree, const Eigen::Ref<const VectorXd>& q,
                      const Eigen::Ref<const VectorXd>& qd, const Eigen::Ref<const VectorXd>& qdd,
                      TreeData& data, Eigen::Ref<VectorXd> tau);

/// The bias forces h(q, q') = C(q, q') q' + g(q) (MuJoCo's qfrc_bias): inverse_dynamics with
/// q'' = 0. Cost O(links).
void bias_forces(const Tree& tree, const Eigen::Ref<const VectorXd>& q,
                 const Eigen::Ref<const VectorXd>& qd, TreeData& data, Eigen::Ref<VectorXd> h);

/// The frame Jacobian of a point of link `link` (p_L in link coordinates), in world axes, after
/// forward_kinematics: J (6 × n) with [ω_W; v_W(point)] = J q'. Columns of joints that are not
/// ancestors of the link are zero. Cost O(n · depth).
/// @throws std::invalid_argument on a link out of range or J of the wrong size.
void frame_jacobian(const Tree& tree, const TreeData& data, Index link, const Vector3d& p_L,
                    Eigen::Ref<Eigen::Matrix<double, 6, Eigen::Dynamic>> J);

/// J'(q, q') q' of frame_jacobian, the acceleration of a point p_L of link `link` when q'' = 0
/// (what A q'' = b of a constraint on the tree needs in b): [ω'_W; a_W(point)] in world axes,
/// a_W the classical (not spatial) acceleration, no gravity. Runs forward_kinematics and an
/// outward velocity pass over the link's ancestors (writes data.v and data.a). Cost O(depth).
/// @throws std::invalid_argument on wrong sizes or a link out of range.
Vector6d frame_bias_acceleration(const Tree& tree, const Eigen::Ref<const VectorXd>& q,
                                 const Eigen::Ref<const VectorXd>& qd, TreeData& data, Index link,
                                 const Vector3d& p_L);

/// The world position of a point p_L of link `link` after forward_kinematics. Cost O(1).
Vector3d world_point(const TreeData& data, Index link, const Vector3d& p_L);

/// Joint torques τ(q, q', t) (n): the tree's named input "tau" (a floating joint's 7 entries are
/// generalized forces on its coordinates). Must not allocate.
using JointTorqueFn =
    std::function<void(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, Eigen::Ref<VectorXd> tau)>;

/// The regularization eps (rad/s or m/s) of URDF's joint friction in make_system, as the bodies'
/// joint friction's default (mb::JointFriction::regularization), in SI units; a model in other
/// units takes it in its own (FrictionRegularization, docs/robots.md).
inline constexpr double kJointFrictionRegularization = 1e-6;

/// The regularization eps of URDF's joint friction, in the model's units: `angular` for a
/// revolute or continuous joint (rad per time unit), `linear` for a prismatic one (length per
/// time unit). The default is kJointFrictionRegularization in SI units; a model in ms takes
/// angular = 1e-9 rad/ms, the same 1e-6 rad/s, so that its motion is the SI model's.
struct FrictionRegularization {
  double angular = kJointFrictionRegularization;  ///< eps > 0 of a rotating joint (rad/time)
  double linear = kJointFrictionRegularization;   ///< eps > 0 of a prismatic joint (length/time)
};

/// The unconstrained system of a tree: M(q) from mass_matrix, Q = τ(q, q', t) − D q' − h(q, q')
/// (D the joints' viscous damping), the potential energy of gravity, the power of τ and of the
/// dampers (so a run's energy balance is checked), one non-ideal force "<joint>.friction" per
/// one-coordinate joint with URDF friction F > 0, C_j = −F q'_j / sqrt(q'_j² + eps²) (Coulomb
/// friction of magnitude F, eps = `friction`'s angular or linear; its work is accounted as the
/// non-ideal forces'), one unit-norm constraint "<link>.unit" per floating joint and one
/// holonomic row "<joint>.mimic" per mimic, q_j − multiplier · q_ref − offset = 0 (its
/// multiplier λ is the coupling torque or force on joint j; −multiplier · λ acts on ref).
/// Constraints, friction, control and simulate() then apply as to any System. The tree is copied
/// into the system's callables. @param tree the tree; @param tau the input "tau", or empty for
/// none;
/// @param friction the joint friction's regularization (both > 0).
/// @throws std::invalid_argument when an eps of `friction` is not a finite number > 0.
/// Cost O(links) to build.
System make_system(const Tree& tree, JointTorqueFn tau = {}, FrictionRegularization friction = {});

/// The SystemBuilder behind make_system, with all of the above already given: add constraints
/// on the tree (built with frame_jacobian and frame_bias_acceleration), non-ideal forces or
/// switching functions, then build(). make_system(tree, tau, friction) is
/// system_builder(tree, tau, friction).build().
SystemBuilder system_builder(const Tree& tree, JointTorqueFn tau = {},
                             FrictionRegularization friction = {});

// ---- centre of mass and momentum (src/multibody/tree/momentum.cpp) -------------------------

/// The tree's total mass Σ m_i (kg). Cost O(links).
double total_mass(const Tree& tree);

/// The centre of mass p_WG = Σ m_i p_W(com_i) / Σ m_i in the world, after forward_kinematics.
/// Cost O(links). @throws std::invalid_argument on a TreeData of another tree.
Vector3d center_of_mass(const Tree& tree, const TreeData& data);

/// The centre-of-mass Jacobian J_G (3 × n), v_G = J_G q' = Σ m_i J_v(com_i) q' / Σ m_i, after
/// forward_kinematics. Cost O(n · links). @throws std::invalid_argument on wrong sizes.
void com_jacobian(const Tree& tree, const TreeData& data,
                  Eigen::Ref<Eigen::Matrix<double, 3, Eigen::Dynamic>> J);

/// The tree's momentum in world axes: [k_O; l], k_O = Σ (R_WL I_i,com R_WLᵀ ω_i + p_W(com_i) ×
/// m_i v_W(com_i)) the angular momentum about the world origin, l = Σ m_i v_W(com_i) = M_tot v_G
/// the linear momentum (the angular momentum about the centre of mass is k_O − p_WG × l).
/// Runs forward_kinematics and an outward velocity pass (writes data.v). Cost O(links).
/// @throws std::invalid_argument on wrong sizes.
Vector6d momentum(const Tree& tree, const Eigen::Ref<const VectorXd>& q,
                  const Eigen::Ref<const VectorXd>& qd, TreeData& data);

// ---- constraints and requirements between tree frames (src/multibody/tree/frame_constraints.cpp)

/// A point of a link, or of the world (link = -1: p is then a world point).
struct LinkPoint {
  Index link = -1;                ///< the link (Tree::link_index), -1 for the world
  Vector3d p = Vector3d::Zero();  ///< the point in the link's frame (world frame for -1)
};

/// A loop closure holding two link points together: p_W(a) − p_W(b) = 0, 3 holonomic rows
/// (a ball joint between the links). A = J_v(a) − J_v(b), b = −(J'q')_v(a) + (J'q')_v(b)
/// (frame_jacobian, frame_bias_acceleration). Add it to system_builder(tree).
/// @throws std::invalid_argument naming `name` on a link out of range or both points on the
/// world. Cost per evaluation O(n · depth).
Constraint point_constraint(const Tree& tree, std::string name, LinkPoint a, LinkPoint b);

/// A loop closure keeping two link points at a distance: |p_W(a) − p_W(b)|² = length², one
/// holonomic row (a massless rod with ball ends). @throws std::invalid_argument as
/// point_constraint, and on a length that is not positive. Cost O(n · depth).
Constraint distance_constraint(const Tree& tree, std::string name, LinkPoint a, LinkPoint b,
                               double length);

/// A Cartesian path in position and orientation: at time t, the point's desired position
/// p, velocity v and acceleration a (world), the desired orientation R_WD, its angular
/// velocity w and angular acceleration w_dot (world axes). Must not allocate.
struct PoseSample {
  Vector3d p = Vector3d::Zero();      ///< desired position of the point (world, m)
  Vector3d v = Vector3d::Zero();      ///< its velocity p' (world, m/s)
  Vector3d a = Vector3d::Zero();      ///< its acceleration p'' (world, m/s²)
  Matrix3d R = Matrix3d::Identity();  ///< desired orientation R_WD (rotates D to W)
  Vector3d w = Vector3d::Zero();      ///< its angular velocity (world axes, rad/s)
  Vector3d w_dot = Vector3d::Zero();  ///< its angular acceleration (world axes, rad/s²)
};
/// The desired pose of a task-space requirement as a function of time.
using PosePathFn = std::function<void(double t, PoseSample& desired)>;

/// A task-space requirement (control/control.hpp) that link point `at` follow `path` in
/// position and orientation: 6 holonomic rows
///   e_p = p_W(at) − p_d(t),   e_R = ½ Σ_k r_d,k × r_k   (r_k, r_d,k the columns of R_WL, R_WD),
/// e_R = 0 iff R_WL = R_WD near it (e_R = sin θ · axis of R_WD R_WLᵀ). Acceleration form
/// A q'' = b is e'' = 0 exactly: rows 0–2 J_v, rows 3–5 L J_ω with L = −½ Σ [r_d,k]× [r_k]×
/// (→ I at e_R = 0).
/// Give it to ControllerBuilder::require with ErrorDynamics. `orientation` false: the 3 position
/// rows only. @throws std::invalid_argument naming `name` on a link out of range or an empty
/// path. Cost per evaluation O(n · depth).
Constraint pose_requirement(const Tree& tree, std::string name, LinkPoint at, PosePathFn path,
                            bool orientation = true);

// ---- joint and effort limits (src/multibody/tree/limits.cpp) --------------------------------

/// A limit that a run left: which joint, when it first did, and the largest excess (how far
/// beyond the limit, > 0) and when.
struct LimitExcess {
  std::string joint;        ///< the joint's name
  std::string limit;        ///< "lower", "upper" (position limits), "velocity" or "effort"
  double bound = 0.0;       ///< the limit's value
  double first_time = 0.0;  ///< the first sample beyond it
  double worst_time = 0.0;  ///< the sample of the largest excess
  double excess = 0.0;      ///< the largest excess (rad, m, N·m or N), > 0
  bool prismatic = false;   ///< a prismatic joint's (a length, a force), else a rotating one's
};

/// The samples at which joint positions leave URDF's [lower, upper] (revolute and prismatic
/// joints): one LimitExcess per joint and side. `q` holds N samples of n coordinates one after
/// the other (Trajectory::q), `t` the N times. Cost O(N · n).
/// @throws std::invalid_argument when q does not hold t.size() · n values.
std::vector<LimitExcess> check_joint_limits(const Tree& tree, const std::vector<double>& t,
                                            const std::vector<double>& q);

/// The samples at which generalized forces on one-coordinate joints exceed URDF's `effort`
/// (|τ_j| > effort_j): `tau` holds N samples of n values (ControlledTrajectory::Qc_control).
/// Cost O(N · n). @throws std::invalid_argument as check_joint_limits.
std::vector<LimitExcess> check_effort_limits(const Tree& tree, const std::vector<double>& t,
                                             const std::vector<double>& tau);

/// The two checks above over samples that come in pieces (a streamed run): observe() each
/// piece in time order, then excesses() lists what check_joint_limits and check_effort_limits
/// would for all samples at once (position limits first, then velocities — |q'_j| above URDF's
/// `velocity`, 0 or absent meaning none — then efforts; per joint in link order). Cost O(n)
/// per sample.
class LimitWatch {
 public:
  /// Watches the limits of `tree` (copied: the watch may outlive it).
  explicit LimitWatch(const Tree& tree);
  /// N samples: times t, positions q (N × n), generalized forces tau (N × n, or empty:
  /// efforts are not checked for these samples) and velocities qd (N × n, or empty: not
  /// checked). @throws std::invalid_argument on sizes.
  void observe(const std::vector<double>& t, const std::vector<double>& q,
               const std::vector<double>& tau, const std::vector<double>& qd = {});
  /// The limits left so far.
  std::vector<LimitExcess> excesses() const;

 private:
  std::vector<Index> offset_;  // coordinate of each one-coordinate joint
  std::vector<LimitExcess> lower_, upper_, velocity_, effort_;  // per such joint
  Index n_ = 0;
};

/// One line of text per excess: "joint 'j' exceeds its upper limit 2.9 by 0.03 rad (first at
/// t = 0.41 s, worst at t = 0.52 s)", in `units` (the model's: a prismatic joint's excess in its
/// length or force unit, a rotating one's in rad or its torque unit, the times in its time
/// unit; SI by default). Cost O(excesses).
std::string describe(const LimitExcess& e, const UnitSystem& units = {});

/// The units a URDF's SI numbers (metres, kilograms, seconds: URDF's own) are converted into:
/// how many of the model's length, mass and time units make a metre, a kilogram and a second
/// (1000, 1000, 1000 for mm, g, ms). A quantity of dimension kg^a m^b s^c is multiplied by
/// mass^a length^b time^c. The default converts nothing.
struct UnitScale {
  double length = 1.0;  ///< length units per metre
  double mass = 1.0;    ///< mass units per kilogram
  double time = 1.0;    ///< time units per second
};

/// Reads a URDF file (through urdfdom) into a Tree: links in depth-first order from the root;
/// URDF's world link, if any, is the world. Joint limits, damping, friction, effort and velocity
/// are kept, and `<mimic>` (Joint::mimic). Every number is converted by `scale` from SI into the
/// model's units: origins, centres of mass and a prismatic joint's limits and mimic offset by
/// length; masses by mass; inertias by mass·length²; a revolute joint's effort and friction by
/// mass·length²/time², damping by mass·length²/time, velocity limit by 1/time (a prismatic
/// joint's by mass·length/time², mass/time and length/time); a mimic's multiplier by the ratio of
/// the two joints' units. `gravity` is in the model's units already. @throws
/// std::invalid_argument naming the file and the line:column of the element at fault
/// ("<path>:12:5: …", docs/robots.md): malformed XML, urdfdom's message, a joint type ukdyn does
/// not know (planar), a moving link without `<inertial>`, an inertia that is not positive
/// definite, a graph that is not a tree, a mimic of no joint, of itself or on a cycle. Cost
/// O(links) plus two XML parses (TinyXML's check, then urdfdom's).
Tree load_urdf(const std::string& path, Vector3d gravity = Vector3d(0, 0, -9.81),
               const UnitScale& scale = {});

}  // namespace ukdyn::tree

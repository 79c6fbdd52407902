// SPDX-License-Identifier: BSD-3-Clause
// Private to the multibody layer: body kinematics in closed form, the joint constraint model
// built from rows of vector expressions, and the builder's storage.
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/autodiff.hpp"
#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/multibody/multibody.hpp"

namespace ukdyn::mb::detail {

/// Largest number of local columns of a joint (two rigid bodies).
inline constexpr int kMaxCols = 14;
using JacobianRow = Eigen::Matrix<double, 3, kMaxCols>;
using Matrix34 = Eigen::Matrix<double, 3, 4>;
using Vector4d = Eigen::Vector4d;

/// A body as a joint sees it: kind, its first coordinate in q, its first local column and its
/// index among the model's bodies (the entry of the PoseCache).
struct BodyRef {
  BodyKind kind = BodyKind::kParticle;
  Index offset = -1;  // −1: the ground
  Index local = 0;
  Index id = -1;  // the BodyId (−1: the ground)
  bool ground() const { return offset < 0; }
  Index size() const { return ground() ? 0 : (kind == BodyKind::kRigid ? 7 : 3); }
};

// ---- the bodies' rotations, once per evaluation ---------------------------------------------

/// cos theta and sin theta of a planar body.
struct CosSin {
  double c, s;
};
/// {std::cos(theta), std::sin(theta)}, bitwise, from one call of glibc's sincos (out of line:
/// one call whichever branch asks for it).
CosSin cos_sin_of(double theta);

/// The multibody System's per-workspace scratch (its CallableScratch, made by
/// System::make_scratch, which its joints' ConstraintScratch share): a memo of each body's
/// rotation, so that the joints, forces and violation checks of one evaluation compute it once
/// — planar: cos and sin of theta; any body: R_WB (rotation_WB). An entry is keyed on the exact
/// bits of the body's orientation coordinates (planar theta; rigid u0..u3) and recomputed when
/// they differ: a callable may be called at any q (projection, violation checks, Jacobian
/// checks), and a hit returns bitwise what the computation would. Lookup O(1) (a compare), no
/// allocation after construction. It lives in the Workspace, never in the System, so one
/// System serves any number of threads (docs/algorithm.md, "Thread safety").
class PoseCache final : public CallableScratch {
 public:
  /// Entries for `bodies` bodies (BodyRef::id in [0, bodies)). Allocates.
  explicit PoseCache(Index bodies);
  /// The number of entries.
  Index body_count() const { return Index(trig_.size()); }
  /// How many rotations were computed (cos/sin pairs and matrices: the misses), for the tests
  /// that check each is computed once per evaluation.
  std::int64_t computed() const { return computed_; }
  /// cos theta, sin theta of planar body b at theta: std::cos and std::sin of theta, computed
  /// when theta differs (bitwise) from the previous call's for b. Cost O(1).
  CosSin cos_sin(const BodyRef& b, double theta) {
    Trig& e = trig_[std::size_t(b.id)];
    const std::uint64_t key = std::bit_cast<std::uint64_t>(theta);
    if (key != e.key) {
      const CosSin cs = cos_sin_of(theta);
      e = {key, cs.c, cs.s};
      ++computed_;
    }
    return {e.c, e.s};
  }
  /// R_WB of body b (not the ground, not a particle) at q, as rotation_WB computes it, recomputed
  /// when the body's orientation coordinates differ from the previous call's. Cost O(1).
  const Matrix3d& rotation(const BodyRef& b, const Eigen::Ref<const VectorXd>& q);

 private:
  struct Trig {  // planar: cos and sin of the theta whose bits are key
    std::uint64_t key;
    double c, s;
  };
  struct Rotation {  // R_WB at the orientation coordinates whose bits are key (valid once set)
    std::array<std::uint64_t, 4> key{};
    bool valid = false;
    Matrix3d R;
  };
  std::vector<Trig> trig_;
  std::vector<Rotation> rotation_;
  std::int64_t computed_ = 0;
};

/// cos theta, sin theta of planar body b: from the cache, or computed when it is null. O(1).
inline CosSin planar_cos_sin(PoseCache* cache, const BodyRef& b, double theta) {
  if (cache != nullptr) return cache->cos_sin(b, theta);
  return cos_sin_of(theta);
}

/// The PoseCache in a description callable's scratch (null when none was given: the callables
/// then compute every rotation). The scratch of the multibody System's callables is always one
/// (System::make_scratch); cost O(1).
inline PoseCache* pose_cache(CallableScratch* s) { return static_cast<PoseCache*>(s); }

// ---- quaternion algebra (u = (u0, u1, u2, u3), u0 scalar) ----------------------------------

/// R(u) s = (u0² − e·e) s + 2 (e·s) e + 2 u0 (e × s): |u|² R_unit(u) s, homogeneous quadratic.
inline Vector3d rotate(const Vector4d& u, const Vector3d& s) {
  const Vector3d e = u.tail<3>();
  return (u[0] * u[0] - e.squaredNorm()) * s + 2.0 * e.dot(s) * e + 2.0 * u[0] * e.cross(s);
}
/// D(u, s) = ∂(R(u) s)/∂u (3 × 4), linear in u; D(u, s) u = 2 R(u) s.
inline Matrix34 rotate_jacobian(const Vector4d& u, const Vector3d& s) {
  const Vector3d e = u.tail<3>();
  Matrix34 D;
  D.col(0) = 2.0 * (u[0] * s + e.cross(s));
  Matrix3d S;  // [s]×
  S << 0, -s.z(), s.y(), s.z(), 0, -s.x(), -s.y(), s.x(), 0;
  D.rightCols<3>() =
      2.0 * (-s * e.transpose() + e.dot(s) * Matrix3d::Identity() + e * s.transpose() - u[0] * S);
  return D;
}
/// E_v(u): the last three rows of Udwadia–Schutte's E(u), ω_B = 2 E_v(u) u' (unit u).
inline Matrix34 E_v(const Vector4d& u) {
  Matrix34 E;
  E << -u[1], u[0], u[3], -u[2],  //
      -u[2], -u[3], u[0], u[1],   //
      -u[3], u[2], -u[1], u[0];
  return E;
}
/// G_v(u): ω_W = 2 G_v(u) u' (unit u), ω_W = 2 (u0 e' − u0' e + e × e').
inline Matrix34 G_v(const Vector4d& u) {
  Matrix34 G;
  G << -u[1], u[0], -u[3], u[2],  //
      -u[2], u[3], u[0], -u[1],   //
      -u[3], -u[2], u[1], u[0];
  return G;
}

/// Kinematics of a vector expression along the motion: value x, velocity v = dx/dt, bias
/// g = d²x/dt² at q'' = 0 (so that x'' = J q''_local + g), Jacobian J on the local columns.
struct VecKin {
  Vector3d x = Vector3d::Zero(), v = Vector3d::Zero(), g = Vector3d::Zero();
  JacobianRow J = JacobianRow::Zero();
  /// Tag of the constructor that leaves every entry unset (for one that clear() sets next).
  struct Unset {};
  VecKin() = default;
  explicit VecKin(Unset) : x(), v(), g(), J() {}
  /// Zeros x and v, and g and J unless !second_order.
  void clear(bool second_order = true) {
    x.setZero();
    v.setZero();
    if (!second_order) return;
    g.setZero();
    J.setZero();
  }
};

/// Adds sign · (point p_B + R s, or R s when !translate) of body b to k; a planar body's cos and
/// sin from `cache` when given; x and v only when !second_order (g and J untouched). Cost O(1).
void add_body_vector(const BodyRef& b, const Eigen::Ref<const VectorXd>& q,
                     const Eigen::Ref<const VectorXd>& qd, const Vector3d& s, bool translate,
                     double sign, VecKin& k, PoseCache* cache = nullptr, bool second_order = true);

/// A vector expression of a joint row.
struct VecExpr {
  enum Kind { kWorld, kBodyVector, kPointDiff } kind = kWorld;
  int slot_a = -1, slot_b = -1;  // kBodyVector: slot_a; kPointDiff: x_b − x_a
  Vector3d s_a = Vector3d::Zero(), s_b = Vector3d::Zero(), world = Vector3d::Zero();
  static VecExpr constant(const Vector3d& w) { return {kWorld, -1, -1, {}, {}, w}; }
  static VecExpr body_vector(int slot, const Vector3d& s) {
    return {kBodyVector, slot, -1, s, {}, {}};
  }
  static VecExpr diff(int a, const Vector3d& sa, int b, const Vector3d& sb) {
    return {kPointDiff, a, b, sa, sb, {}};
  }
};

/// A time-dependent offset c(t): constant c0 plus an optional motion f(t) (f, f', f'').
struct Offset {
  double c0 = 0.0;
  std::shared_ptr<const MotionFn> motion;
  Vector3d at(double t) const {
    Vector3d c(c0, 0.0, 0.0);
    if (motion) c += (*motion)(t);
    return c;
  }
};

/// One scalar row of a joint.
///  kDot       phi = a · b − c(t)
///  kDistance  phi = (a · a − L²) / (2 L), a a point difference
///  kLinear    phi = Σ coef_i q[column_i] − c(t)   (global coordinates, local columns)
///  kDisk      phi = a · b − L sqrt(1 − (b · axis)²): a thin disk's gap (a = centre − plane
///             point, b = the plane's normal, axis = the disk's axis, L = its radius)
///  kNorm      phi = sign (|a| − L): the gap of two spheres (a = the difference of their
///             centres; sign = +1, L = the sum of their radii: one outside the other; sign = −1,
///             L = R − r: a sphere of radius r inside one of radius R), a true distance (unlike
///             kDistance's), so that the gap and its rate are in length and speed units wherever
///             the spheres are
///  kDiskSphere  phi = sqrt(s² + m²) − sphere: a thin disk's gap to a sphere (a = the disk's
///             centre − the sphere's, axis = the disk's axis, L = its radius, s = axis·a,
///             m = max(|a − s axis| − L, 0); disk_sphere_gap())
///  kSphereBox phi = sqrt(Σ m_i²) − L: a sphere's gap to a box (a = the sphere's centre − the
///             box's, box[i] = the box's unit axes, half = its half-extents, L = the sphere's
///             radius, m_i = max(|box[i]·a| − half_i, 0); sphere_box_gap())
struct Row {
  enum Kind { kDot, kDistance, kLinear, kDisk, kNorm, kDiskSphere, kSphereBox } kind = kDot;
  VecExpr a, b;
  VecExpr axis;                      // kDisk, kDiskSphere: the disk's axis (a body vector)
  VecExpr box[3];                    // kSphereBox: the box's axes (body vectors; planar: two)
  Vector3d half = Vector3d::Zero();  // kSphereBox: the box's half-extents
  int box_axes = 3;                  // kSphereBox: 3 (spatial) or 2 (planar: a rectangle)
  double length = 0.0;
  double sign = 1.0;                            // kNorm: +1 (outside) or −1 (inside)
  double sphere = 0.0;                          // kDiskSphere: the sphere's radius
  std::vector<std::pair<Index, double>> terms;  // kLinear: (global coordinate, coefficient)
  std::vector<Index> local;                     // kLinear: local column of each term
  Offset c;
};

/// The gap of a thin disk and a sphere (Row::kDiskSphere, mb::contact_disk_sphere()) from
/// e = c − o (the disk's centre from the sphere's) and the disk's unit axis k (values, rates,
/// and, when second_order, Jacobians on the local columns and biases e'' = J q'' + g):
/// s = k·e, w = e − s k, ρ = |w|, m = max(ρ − radius, 0), E = sqrt(s² + m²);
///   g = E − sphere,  g' = (s s' + m m')/E,
///   g'' = (s s'' + m m'')/E + (m s' − s m')²/E³ = A q'' − b,
/// with m' = ŵ·w', m'' = ŵ·w'' + (|w'|² − m'²)/ρ on the rim (ŵ = w/ρ), 0 on the face. Also the
/// contact point's offset from the disk's centre, a = −radius ŵ (rim) or −w (face), the normal
/// n = (e + a)/E (from the sphere to the disk) and their rates. Non-finite where E = 0 (the
/// sphere's centre on the rim). Cost O(columns).
struct DiskSphereGap {
  double g = 0.0, rate = 0.0;  ///< g, g'
  Eigen::Matrix<double, 1, kMaxCols> A =
      Eigen::Matrix<double, 1, kMaxCols>::Zero();            ///< (second_order only)
  double b = 0.0;                                            ///< (second_order only)
  Vector3d a = Vector3d::Zero(), a_rate = Vector3d::Zero();  ///< the contact point's offset
  Vector3d n = Vector3d::Zero(), n_rate = Vector3d::Zero();  ///< the unit normal
};
DiskSphereGap disk_sphere_gap(const VecKin& e, const VecKin& k, double radius, double sphere,
                              bool second_order);

/// The gap of a sphere and a box (Row::kSphereBox, mb::contact_sphere_box()) from e = c − o (the
/// sphere's centre from the box's) and the box's unit axes k[0..axes) (values, rates and, when
/// second_order, Jacobians on the local columns and biases e'' = J q'' + g):
/// u_i = k_i·e, σ_i = sign(u_i), m_i = max(σ_i u_i − half_i, 0), E = sqrt(Σ m_i²);
///   g = E − radius,  g' = Σ σ_i m_i u_i' / E,
///   g'' = Σ σ_i m_i u_i'' / E + (Σ_{m_i>0} u_i'² − g'²)/E = A q'' − b;
/// inside the box (every m_i = 0) the nearest face's: g = σ_j u_j − half_j − radius. Also the
/// unit normal n = Σ σ_i m_i k_i / E (from the box to the sphere; inside: σ_j k_j) and its rate.
/// Non-finite where E = 0 outside (the centre on the box's surface). Cost O(columns).
struct SphereBoxGap {
  double g = 0.0, rate = 0.0;  ///< g, g'
  Eigen::Matrix<double, 1, kMaxCols> A =
      Eigen::Matrix<double, 1, kMaxCols>::Zero();            ///< (second_order only)
  double b = 0.0;                                            ///< (second_order only)
  Vector3d n = Vector3d::Zero(), n_rate = Vector3d::Zero();  ///< the unit normal
  bool inside = false;                                       ///< the centre is in the box
};
SphereBoxGap sphere_box_gap(const VecKin& e, const VecKin* k, int axes, const Vector3d& half,
                            double radius, bool second_order);

/// Largest number of rows of a joint model (a spatial weld: 6).
inline constexpr int kMaxRows = 6;

/// The closed-form joint model: rows over the coordinates of up to four bodies (slots).
/// Its scratch points to the System's PoseCache (make_scratch_sharing), so that the joints and
/// forces of one evaluation compute each body's rotation once.
class JointModel final : public ConstraintModel {
 public:
  /// The scratch: the PoseCache it reads the bodies' rotations from (the workspace's shared one,
  /// or its own).
  struct Scratch final : ConstraintScratch {
    PoseCache* cache = nullptr;
    std::unique_ptr<PoseCache> own;
  };
  /// @throws std::logic_error with more than kMaxRows rows or kMaxCols local columns.
  JointModel(std::vector<BodyRef> slots, std::vector<Row> rows);
  /// A Scratch with a PoseCache of its own (for evaluations outside a workspace). Allocates.
  std::unique_ptr<ConstraintScratch> make_scratch(Index n) const override;
  /// A Scratch on the workspace's PoseCache (the multibody System's CallableScratch), or
  /// make_scratch(n) when `shared` is none or too small for this joint's bodies.
  std::unique_ptr<ConstraintScratch> make_scratch_sharing(Index n,
                                                          CallableScratch* shared) const override;
  const std::vector<Index>& columns() const override { return cols_; }
  /// The dense rows (rows × n): the local form into a fixed-size buffer, then placed at
  /// columns() with zeros elsewhere — the values of the default scatter, in O(rows · n) stores
  /// without moving columns. Does not allocate.
  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override;
  void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double t,
                               ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A_local,
                               Eigen::Ref<VectorXd> b) const override;
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                 double t, ConstraintScratch* scratch, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override;
  const std::vector<BodyRef>& slots() const { return slots_; }
  const std::vector<Row>& rows() const { return rows_; }
  Index local_count() const { return Index(cols_.size()); }

 private:
  // the rows other than a planar revolute's, out of line (the planar revolute path stays short)
  [[gnu::noinline]] void general_form(const Eigen::Ref<const VectorXd>& q,
                                      const Eigen::Ref<const VectorXd>& qd, double t,
                                      PoseCache* cache, Eigen::Ref<MatrixXd> A,
                                      Eigen::Ref<VectorXd> b) const;
  [[gnu::noinline]] void general_violation(const Eigen::Ref<const VectorXd>& q,
                                           const Eigen::Ref<const VectorXd>& qd, double t,
                                           PoseCache* cache, Eigen::Ref<VectorXd> position,
                                           Eigen::Ref<VectorXd> velocity) const;
  // a kDisk row's A row i and b[i] (kd, kn: scratch for the centre difference and the normal)
  void disk_form(const Row& row, Index i, const Eigen::Ref<const VectorXd>& q,
                 const Eigen::Ref<const VectorXd>& qd, PoseCache* cache, VecKin& kd, VecKin& kn,
                 Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> b) const;
  // the kinematics of e into k (x and v only when !second_order: the violations)
  void eval(const VecExpr& e, const Eigen::Ref<const VectorXd>& q,
            const Eigen::Ref<const VectorXd>& qd, PoseCache* cache, VecKin& k,
            bool second_order = true) const;
  std::vector<BodyRef> slots_;
  std::vector<Row> rows_;
  std::vector<Index> cols_;
  // per row: its first vector is the previous row's, whose kinematics are reused (the rows of
  // one joint often share one: d·e_x, d·e_y of a revolute)
  std::vector<char> reuses_a_;
  Index max_id_ = -1;  // the largest BodyRef::id of the slots (the PoseCache entries it reads)
  // the rows are a planar revolute's d·e_x, d·e_y between planar bodies (or the ground), which
  // acceleration_form_local and violation evaluate by a shorter path (same A, b, phi, phi')
  bool planar_revolute_ = false;
};

/// The unit norm of a quaternion: phi = (u·u − 1)/2, A = uᵀ, b = −u'·u' (closed form).
class UnitQuaternionModel final : public ConstraintModel {
 public:
  explicit UnitQuaternionModel(Index offset) : cols_{offset, offset + 1, offset + 2, offset + 3} {}
  const std::vector<Index>& columns() const override { return cols_; }
  void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double, ConstraintScratch*,
                               Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> b) const override {
    const auto u = q.segment<4>(cols_[0]);
    const auto ud = qd.segment<4>(cols_[0]);
    A.row(0) = u.transpose();
    b[0] = -ud.squaredNorm();
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 ConstraintScratch*, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    const auto u = q.segment<4>(cols_[0]);
    position[0] = 0.5 * (u.squaredNorm() - 1.0);
    velocity[0] = u.dot(qd.segment<4>(cols_[0]));
  }

 private:
  std::vector<Index> cols_;
};

/// A constraint on a few columns whose A and b come from automatic differentiation of a
/// callable on the local coordinates (the inner model sees a system of columns().size()
/// coordinates). Used for rolling contacts and as the independent reference in the tests.
class LocalAutodiffModel final : public ConstraintModel {
 public:
  LocalAutodiffModel(std::vector<Index> cols, std::shared_ptr<const ConstraintModel> inner)
      : cols_(std::move(cols)), inner_(std::move(inner)) {}
  struct Scratch final : ConstraintScratch {
    std::unique_ptr<ConstraintScratch> inner;
    VectorXd q, qd;
  };
  std::unique_ptr<ConstraintScratch> make_scratch(Index) const override {
    auto s = std::make_unique<Scratch>();
    s->inner = inner_->make_scratch(Index(cols_.size()));
    s->q.resize(Index(cols_.size()));
    s->qd.resize(Index(cols_.size()));
    return s;
  }
  const std::vector<Index>& columns() const override { return cols_; }
  void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double t,
                               ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A,
                               Eigen::Ref<VectorXd> b) const override {
    auto& s = gather(q, qd, scratch);
    inner_->acceleration_form(s.q, s.qd, t, s.inner.get(), A, b);
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                 double t, ConstraintScratch* scratch, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& s = gather(q, qd, scratch);
    inner_->violation(s.q, s.qd, t, s.inner.get(), position, velocity);
  }

 private:
  Scratch& gather(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                  ConstraintScratch* scratch) const {
    auto& s = static_cast<Scratch&>(*scratch);
    for (std::size_t i = 0; i < cols_.size(); ++i) {
      s.q[Index(i)] = q[cols_[i]];
      s.qd[Index(i)] = qd[cols_[i]];
    }
    return s;
  }
  std::vector<Index> cols_;
  std::shared_ptr<const ConstraintModel> inner_;
};

// ---- generic (scalar-templated) position level, for the automatic-differentiation checks ----

/// The value of a scalar (double, or the value part of a dual number).
inline double value_of(double x) { return x; }
template <class D>
double value_of(const Eigen::AutoDiffScalar<D>& x) {
  return value_of(x.value());
}

template <class S>
using Vec3 = Eigen::Matrix<S, 3, 1>;

/// Point (translate) or vector of body b at generic q.
template <class S, class V>
Vec3<S> body_vector_generic(const BodyRef& b, const V& q, const Vector3d& s, bool translate) {
  using std::cos;
  using std::sin;
  Vec3<S> x;
  if (b.ground()) {
    for (int i = 0; i < 3; ++i) x[i] = S(s[i]);
    return x;
  }
  const Index o = b.offset;
  if (b.kind == BodyKind::kParticle) {
    for (int i = 0; i < 3; ++i) x[i] = S(s[i]);
  } else if (b.kind == BodyKind::kPlanar) {
    const S c = cos(q[o + 2]), sn = sin(q[o + 2]);
    x[0] = c * s.x() - sn * s.y();
    x[1] = sn * s.x() + c * s.y();
    x[2] = S(s.z());
  } else {
    const S& w = q[o + 3];
    Vec3<S> e;
    e << q[o + 4], q[o + 5], q[o + 6];
    const Vec3<S> sv = s.cast<S>();
    const S es = e.dot(sv);
    const S ee = e.dot(e);
    x = (w * w - ee) * sv + (2.0 * es) * e + (2.0 * w) * e.cross(sv);
  }
  if (translate) {
    if (b.kind == BodyKind::kPlanar) {
      x[0] += q[o];
      x[1] += q[o + 1];
    } else {
      for (int i = 0; i < 3; ++i) x[i] += q[o + i];
    }
  }
  return x;
}

template <class S, class V>
Vec3<S> vec_expr_generic(const std::vector<BodyRef>& slots, const VecExpr& e, const V& q) {
  switch (e.kind) {
    case VecExpr::kWorld:
      return e.world.cast<S>();
    case VecExpr::kBodyVector:
      return body_vector_generic<S>(slots[std::size_t(e.slot_a)], q, e.s_a, false);
    case VecExpr::kPointDiff:
      break;
  }
  const Vec3<S> xb = body_vector_generic<S>(slots[std::size_t(e.slot_b)], q, e.s_b, true);
  const Vec3<S> xa = body_vector_generic<S>(slots[std::size_t(e.slot_a)], q, e.s_a, true);
  return xb - xa;
}

/// The rows' phi(q, t) at generic q (global coordinates) and t, with c(t) expanded to second
/// order about t0 (exact for what a second-order forward pass sees).
template <class S, class V, class Out>
void joint_phi_generic(const JointModel& jm, const V& q, const S& t, double t0, Out& phi) {
  for (std::size_t r = 0; r < jm.rows().size(); ++r) {
    const Row& row = jm.rows()[r];
    const Vector3d c = row.c.at(t0);
    const S dt = t - t0;
    const S c_t = c[0] + c[1] * dt + 0.5 * c[2] * dt * dt;
    S out;
    switch (row.kind) {
      case Row::kDot: {
        const Vec3<S> a = vec_expr_generic<S>(jm.slots(), row.a, q);
        const Vec3<S> b = vec_expr_generic<S>(jm.slots(), row.b, q);
        out = a.dot(b) - c_t;
        break;
      }
      case Row::kDistance: {
        const Vec3<S> a = vec_expr_generic<S>(jm.slots(), row.a, q);
        out = (a.dot(a) - row.length * row.length) * (0.5 / row.length);
        break;
      }
      case Row::kLinear: {
        out = -c_t;
        for (const auto& [i, coef] : row.terms) out += coef * q[i];
        break;
      }
      case Row::kNorm: {
        using std::sqrt;
        const Vec3<S> a = vec_expr_generic<S>(jm.slots(), row.a, q);
        out = row.sign * (sqrt(a.dot(a)) - row.length);
        break;
      }
      case Row::kDisk: {
        using std::sqrt;
        const Vec3<S> a = vec_expr_generic<S>(jm.slots(), row.a, q);
        const Vec3<S> n = vec_expr_generic<S>(jm.slots(), row.b, q);
        const Vec3<S> ax = vec_expr_generic<S>(jm.slots(), row.axis, q);
        const S s = n.dot(ax);
        out = a.dot(n) - row.length * sqrt(1.0 - s * s);
        break;
      }
      case Row::kSphereBox: {
        // sqrt(Σ m_i²) − L, m_i = max(|k_i·a| − half_i, 0); inside: max_i(|k_i·a| − half_i) − L
        using std::sqrt;
        const Vec3<S> a = vec_expr_generic<S>(jm.slots(), row.a, q);
        S sum(0.0), deepest(0.0);
        bool outside = false, first = true;
        for (int i = 0; i < row.box_axes; ++i) {
          const S u = a.dot(vec_expr_generic<S>(jm.slots(), row.box[i], q));
          const S excess = (value_of(u) < 0.0 ? S(-u) : u) - row.half[i];
          if (value_of(excess) > 0.0) {
            sum += excess * excess;
            outside = true;
          }
          if (first || value_of(excess) > value_of(deepest)) deepest = excess;
          first = false;
        }
        out = (outside ? S(sqrt(sum)) : deepest) - row.length;
        break;
      }
      case Row::kDiskSphere: {
        // sqrt(s² + m²) − sphere, m = max(|a − s axis| − L, 0)
        using std::sqrt;
        const Vec3<S> a = vec_expr_generic<S>(jm.slots(), row.a, q);
        const Vec3<S> ax = vec_expr_generic<S>(jm.slots(), row.axis, q);
        const S s = a.dot(ax);
        const Vec3<S> w = a - s * ax;
        const S rho = sqrt(w.dot(w));
        const S m = value_of(rho) > row.length ? S(rho - row.length) : S(0.0);
        out = sqrt(s * s + m * m) - row.sphere;
        break;
      }
    }
    phi[Index(r)] = out;
  }
}

}  // namespace ukdyn::mb::detail

namespace ukdyn::mb::detail {

/// The joint's view of body id (ground: offset −1).
BodyRef body_ref(const std::vector<BodyInfo>& bodies, BodyId id);

/// Adds the generalized force of a world force F_W acting at body point s (body coordinates) to
/// Q: translation += F; planar theta += ((R s) × F)_z; quaternion += D(u, s)ᵀ F. Cost O(1).
void add_point_force(const BodyRef& b, const Eigen::Ref<const VectorXd>& q, const Vector3d& s,
                     const Vector3d& F_W, Eigen::Ref<VectorXd> Q, PoseCache* cache = nullptr);
/// Adds the generalized force of a world torque: planar theta += tau_z; quaternion += 2 G_vᵀ tau.
void add_torque(const BodyRef& b, const Eigen::Ref<const VectorXd>& q, const Vector3d& tau_W,
                Eigen::Ref<VectorXd> Q);
/// Angular velocity (world) of a body: planar (0, 0, theta'); rigid 2 G_v(u) u' / |u|².
Vector3d angular_velocity_W(const BodyRef& b, const Eigen::Ref<const VectorXd>& q,
                            const Eigen::Ref<const VectorXd>& qd);
/// Orientation matrix R_WB (rigid: of the normalized quaternion; planar: about z); from `cache`
/// when given (the same bits).
Matrix3d rotation_WB(const BodyRef& b, const Eigen::Ref<const VectorXd>& q,
                     PoseCache* cache = nullptr);

/// Rows of a planar joint (parent slot 0, child slot 1); the drive row, if any, separately.
std::vector<Row> planar_joint_rows(const Joint& j, const BodyRef& P, const BodyRef& C);
Row planar_drive_row(const Joint& j, const BodyRef& P, const BodyRef& C);
/// Rows of a spatial joint (parent slot 0, child slot 1); the drive row, if any, separately.
std::vector<Row> spatial_joint_rows(const Joint& j, const BodyRef& P, const BodyRef& C);
Row spatial_drive_row(const Joint& j, const BodyRef& P, const BodyRef& C);
/// "<name>.drive" of a spatial revolute joint: its angle = f(t) (holonomic, AD on the bodies).
Constraint spatial_revolute_drive(const Joint& j, const BodyRef& P, const BodyRef& C);
/// "<name>" of a contact (kContact, kContactDisk): its gap row (parent slot 0 = the plane's
/// body, child slot 1 = the contact's body), planar or spatial.
Row contact_row(const Joint& j, bool planar);
/// The unilateral constraint "<name>" of a contact, after the checks of its parameters (radius,
/// restitution, body kinds, no drive or friction, a disk not flat at q0).
/// @throws std::invalid_argument naming the contact.
Constraint contact_constraint(const Joint& j, const BodyRef& P, const BodyRef& C, bool planar,
                              const VectorXd& q0);
/// A gear between two spatial revolute joints at velocity level (nonholonomic, AD).
Constraint spatial_gear(const Joint& gear, const Joint& a, const BodyRef& Pa, const BodyRef& Ca,
                        const Joint& b, const BodyRef& Pb, const BodyRef& Cb);
/// The constraints of a rolling contact of rigid body C on z = 0: "<name>.contact" (holonomic
/// height, 1 row) and "<name>" (nonholonomic, 2 rows: the contact point's horizontal velocity).
std::vector<Constraint> rolling_constraints(const Joint& j, const BodyRef& C);
/// The contact-point kinematics of contact j (JointType::kContact, a point or sphere of body C
/// on a plane fixed on the ground; contacts.cpp) for Coulomb friction there (ContactKinematics):
/// rows n, t_1 (, t_2) of the Jacobian of the body's material point at the contact, v_P =
/// v(centre) + ω × (−r n), and their bias J_P' q'. Cost O(1) per evaluation, no allocation.
ContactKinematics contact_kinematics(const Joint& j, const BodyRef& C, bool planar);
/// The same for a point or sphere of body C on a plane of a moving body P, a disk of C on a
/// plane of the ground or of a moving body, or a sphere of C on a sphere of P (contacts.cpp):
/// the sliding velocity is the relative velocity of the two bodies' material points at the
/// contact point x = c + a,
///   v_rel = c' + ω_C × a − p' − ω_P × (d + a),   d = c − p,
/// (c the centre on C, p the plane's point or the other sphere's centre on P, ω = J_ω q' with
/// J_ω = 2 G_v(u) or e_z on θ; a = −r n, or for a disk of axis k a = −r m/|m|, m = n − (n·k) k,
/// the rim point most opposed to n, which moves on the disk as it rolls), rows t_iᵀ J_rel. On a
/// plane n = R_P n_P, t_i = R_P t_i,P; on a sphere n = d/|d|, t_1 = e × n/|e × n|, t_2 = n × t_1
/// with e the world axis least aligned with n at q0 (planar: t_1 = n × e_z), continuous in time
/// while |e·n| <= 0.9; beyond, e is the world axis least aligned with n at that instant (the
/// tangents turn by a step; the friction force and the stick rows' span do not). Row 0 is the gap's
/// gradient ∂g/∂q, g = n·d − r, n·d − r sqrt(1 − (n·k)²) or |d| − (r + r_P) (equal to nᵀ J_rel on
/// the motion: N is then exact). Bias: t_i'·v_rel + t_i·(v_rel)' at q'' = 0, (v_rel)' = c'' − p'' +
/// ω_C × a' − ω_P × (d' + a') (ω' = 0 at q'' = 0), and g'' for row 0. Columns: both bodies'. Cost
/// O(1), no allocation.
ContactKinematics relative_contact_kinematics(const Joint& j, const BodyRef& P, const BodyRef& C,
                                              bool planar, const VectorXd& q0);
/// The joint friction of a revolute or prismatic joint whose constraint is `constraint`.
NonIdealForce joint_friction_force(const Joint& j, const BodyRef& P, const BodyRef& C,
                                   const std::string& constraint, bool planar);
/// The friction's C at the current evaluation (as the NonIdealForce computes it); used by the
/// reports. k = the joint's constraint index.
void joint_friction_C(const Joint& j, const BodyRef& P, const BodyRef& C, bool planar, Index k,
                      const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                      const IdealForceInfo& ideal, Eigen::Ref<VectorXd> out);

/// Q(q, q', t) and V(q, t) of gravity, force elements and the quaternions' velocity terms.
/// Each takes the workspace's PoseCache as its scratch (System::make_scratch; null: none).
ForceScratchFn make_forces(const std::vector<BodyInfo>& bodies, const std::vector<Force>& forces,
                           const Vector3d& g);
PotentialScratchFn make_potential(const std::vector<BodyInfo>& bodies,
                                  const std::vector<Force>& forces, const Vector3d& g);
/// The power of the force elements that V does not account for — the dampers of spring-dampers
/// and torsion springs and the applied wrenches — or an empty callable when there are none
/// (gravity and springs derive from V, the quaternions' velocity terms do no work).
PowerScratchFn make_external_power(const std::vector<BodyInfo>& bodies,
                                   const std::vector<Force>& forces);

/// M_kk of a quaternion: 4 E_v(u)ᵀ J E_v(u) (4 × 4, positive semi-definite of rank 3: singular
/// along u, which the unit-norm constraint determines; docs/multibody.md 1.1).
void quaternion_mass(const Vector4d& u, const Vector3d& J, Eigen::Ref<MatrixXd> Mk);
/// The quaternion's velocity-dependent force −8 E_v(u')ᵀ J E_v(u) u' (4).
Vector4d quaternion_velocity_force(const Vector4d& u, const Vector4d& ud, const Vector3d& J);

}  // namespace ukdyn::mb::detail

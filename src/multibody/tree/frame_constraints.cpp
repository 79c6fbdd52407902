// SPDX-License-Identifier: BSD-3-Clause
// Constraints and requirements between tree frames, built on frame_jacobian and
// frame_bias_acceleration: a point loop closure (3 rows), a distance loop closure (1 row), a weld
// (6 rows) and a revolute closure (5 rows), a unilateral contact of a point, sphere or disk with
// a plane (1 row), and a task-space pose requirement (6 rows) for exact tracking control. (The
// contact point's kinematics for friction there: contact_kinematics.cpp.)
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "multibody/tree/frame_scratch.hpp"
#include "multibody/tree/kinematics_cache.hpp"
#include "multibody/tree/spatial.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/multibody/tree_closures.hpp"

namespace ukdyn::tree {

namespace {

// (frame_scratch.hpp: the buffers and point kinematics shared with contact_kinematics.cpp)
using detail::FrameScratch;
using detail::Jacobian;
using detail::kinematics_at;
using detail::point_state;
using detail::PointState;
using detail::world_rotation;

// L −= ½ [x]× [y]× = ½ (y xᵀ − (x · y) I), entry by entry: the products and sums of the 3 × 3
// product of the two cross-product matrices without its terms that are zero (at most two terms
// per entry, so the same bits as the product in any order). The orientation rows' L.
void subtract_half_skew_product(const Vector3d& x, const Vector3d& y, Matrix3d& L) {
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      const int a = (i + 1) % 3, c = (i + 2) % 3;
      const double p = i == j ? -(x[a] * y[a]) - x[c] * y[c] : y[i] * x[j];
      L(i, j) -= 0.5 * p;
    }
  }
}

// a pose requirement's path at t, once per time: the acceleration form and the violation of
// one evaluation ask for the same t (the path is a function of t: the same t, bit for bit,
// gives the same sample)
const PoseSample& desired_at(const PosePathFn& path, double t, FrameScratch& w) {
  if (!w.desired_valid || std::memcmp(&t, &w.t_desired, sizeof t) != 0) {
    w.desired_valid = false;   // (a path that throws leaves no sample)
    w.desired = PoseSample{};  // (the fields a path leaves unset keep their defaults)
    path(t, w.desired);
    w.t_desired = t;
    w.desired_valid = true;
  }
  return w.desired;
}

void check_point(const Tree& tree, const std::string& who, const std::string& name,
                 const LinkPoint& pt, const char* which);

// ω = J_ω q' of the point a (point_state ran: Ja valid), once per state (the same q', bit for
// bit, gives the same product)
const Vector3d& angular_velocity(FrameScratch& w, const Eigen::Ref<const VectorXd>& qd) {
  if (!w.omega_valid ||
      std::memcmp(qd.data(), w.qd_omega.data(), sizeof(double) * std::size_t(qd.size())) != 0) {
    w.omega = w.Ja.topRows<3>() * qd;
    w.qd_omega = qd;
    w.omega_valid = true;
  }
  return w.omega;
}

// both points of a loop closure: in range, finite, not both on the world
void check_points(const Tree& tree, const std::string& who, const std::string& name,
                  const LinkPoint& a, const LinkPoint& b) {
  check_point(tree, who, name, a, "a");
  check_point(tree, who, name, b, "b");
  if (a.link < 0 && b.link < 0) {
    throw std::invalid_argument(who + ": constraint '" + name +
                                "': both points are on the world (give a link for one)");
  }
}

void check_point(const Tree& tree, const std::string& who, const std::string& name,
                 const LinkPoint& pt, const char* which) {
  if (pt.link < -1 || pt.link >= tree.link_count()) {
    throw std::invalid_argument(
        who + ": constraint '" + name + "': link " + std::to_string(pt.link) + " of point " +
        which + " out of range [-1, " + std::to_string(tree.link_count()) + ") (-1: the world)");
  }
  if (!pt.p.allFinite()) {
    throw std::invalid_argument(who + ": constraint '" + name + "': point " + which +
                                " is not finite");
  }
}

// the models' common part: the tree, shared by copies, and a FrameScratch per workspace
class FrameModel : public ConstraintModel {
 public:
  explicit FrameModel(std::shared_ptr<const Tree> tree) : tree_(std::move(tree)) {}
  std::unique_ptr<ConstraintScratch> make_scratch(Index) const override {
    return std::make_unique<FrameScratch>(*tree_, nullptr);
  }
  // evaluated with a workspace of a system on the same tree (the tree's own closures, or a
  // controller's requirements with its model's workspace): that workspace's kinematics
  std::unique_ptr<ConstraintScratch> make_scratch_sharing(Index n,
                                                          CallableScratch* shared) const override {
    detail::KinematicsCache* k = detail::shared_kinematics(shared, *tree_);
    if (k == nullptr) return make_scratch(n);
    return std::make_unique<FrameScratch>(*tree_, k);
  }

 protected:
  std::shared_ptr<const Tree> tree_;
};

// p_W(a) − p_W(b) = 0: A = J_v(a) − J_v(b), b = −(J' q')_v(a) + (J' q')_v(b)
class PointModel final : public FrameModel {
 public:
  PointModel(std::shared_ptr<const Tree> tree, LinkPoint a, LinkPoint b)
      : FrameModel(std::move(tree)), a_(a), b_(b) {}
  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double, ConstraintScratch* s, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pa = point_state(*tree_, a_, q, qd, w, w.Ja, true);
    const PointState pb = point_state(*tree_, b_, q, qd, w, w.Jb, true);
    A = w.Ja.bottomRows<3>() - w.Jb.bottomRows<3>();
    b = pb.bias.tail<3>() - pa.bias.tail<3>();
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 ConstraintScratch* s, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pa = point_state(*tree_, a_, q, qd, w, w.Ja, false);
    const PointState pb = point_state(*tree_, b_, q, qd, w, w.Jb, false);
    position = pa.p_W - pb.p_W;
    velocity.noalias() = (w.Ja.bottomRows<3>() - w.Jb.bottomRows<3>()) * qd;
  }

 private:
  LinkPoint a_, b_;
};

// (|d|² − ℓ²) / (2ℓ) = 0 with d = p_W(a) − p_W(b) (metres near the closure):
// phi' = dᵀ d' / ℓ, phi'' = (d'ᵀ d' + dᵀ d'') / ℓ, d'' = (J_a − J_b) q'' + β_a − β_b
class DistanceModel final : public FrameModel {
 public:
  DistanceModel(std::shared_ptr<const Tree> tree, LinkPoint a, LinkPoint b, double length)
      : FrameModel(std::move(tree)), a_(a), b_(b), length_(length) {}
  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double, ConstraintScratch* s, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pa = point_state(*tree_, a_, q, qd, w, w.Ja, true);
    const PointState pb = point_state(*tree_, b_, q, qd, w, w.Jb, true);
    const Vector3d dist = pa.p_W - pb.p_W;
    // (J_a − J_b)_v into Ja's linear rows, then d' = (J_a − J_b)_v q'
    w.Ja.bottomRows<3>() -= w.Jb.bottomRows<3>();
    w.Ja_valid = false;  // (Ja now holds J_a − J_b)
    const Vector3d rate = w.Ja.bottomRows<3>() * qd;
    A.row(0).noalias() = (dist / length_).transpose() * w.Ja.bottomRows<3>();
    b[0] = -(rate.squaredNorm() + dist.dot(pa.bias.tail<3>() - pb.bias.tail<3>())) / length_;
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 ConstraintScratch* s, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pa = point_state(*tree_, a_, q, qd, w, w.Ja, false);
    const PointState pb = point_state(*tree_, b_, q, qd, w, w.Jb, false);
    const Vector3d dist = pa.p_W - pb.p_W;
    position[0] = (dist.squaredNorm() - length_ * length_) / (2.0 * length_);
    velocity[0] = dist.dot((w.Ja.bottomRows<3>() - w.Jb.bottomRows<3>()) * qd) / length_;
  }

 private:
  LinkPoint a_, b_;
  double length_;
};

// e = [p_W(a) − p_W(b); ½ Σ r_b,k × r_a,k]; e'' = 0 is A q'' = b (see weld_constraint)
class WeldModel final : public FrameModel {
 public:
  WeldModel(std::shared_ptr<const Tree> tree, const LinkFrame& a, const LinkFrame& b)
      : FrameModel(std::move(tree)), a_(a), b_(b) {}
  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double, ConstraintScratch* s, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pa = point_state(*tree_, {a_.link, a_.p}, q, qd, w, w.Ja, true);
    const PointState pb = point_state(*tree_, {b_.link, b_.p}, q, qd, w, w.Jb, true);
    // position: (J_v(a) − J_v(b)) q'' = β_v(b) − β_v(a)
    A.topRows<3>() = w.Ja.bottomRows<3>() - w.Jb.bottomRows<3>();
    b.head<3>() = pb.bias.tail<3>() - pa.bias.tail<3>();
    // orientation: r' = ω × r; e_R'' = L ω_a' − Lᵀ ω_b' + ½ Σ ((ω_b × r_b') × r_a + 2 r_b' × r_a'
    // + r_b × (ω_a × r_a')) with ω' = J_ω q'' + β_ω
    const Matrix3d Ra = world_rotation(w.data, a_.link, a_.R);
    const Matrix3d Rb = world_rotation(w.data, b_.link, b_.R);
    const Vector3d wa = w.Ja.topRows<3>() * qd, wb = w.Jb.topRows<3>() * qd;
    Matrix3d L = Matrix3d::Zero();
    Vector3d rest = Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const Vector3d ra = Ra.col(k), rb = Rb.col(k);
      const Vector3d ra1 = wa.cross(ra), rb1 = wb.cross(rb);
      subtract_half_skew_product(rb, ra, L);
      rest += 0.5 * (wb.cross(rb1).cross(ra) + 2.0 * rb1.cross(ra1) + rb.cross(wa.cross(ra1)));
    }
    A.bottomRows<3>().noalias() = L * w.Ja.topRows<3>();
    A.bottomRows<3>().noalias() -= L.transpose() * w.Jb.topRows<3>();
    b.tail<3>() = -rest - L * pa.bias.head<3>() + L.transpose() * pb.bias.head<3>();
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 ConstraintScratch* s, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pa = point_state(*tree_, {a_.link, a_.p}, q, qd, w, w.Ja, false);
    const PointState pb = point_state(*tree_, {b_.link, b_.p}, q, qd, w, w.Jb, false);
    position.head<3>() = pa.p_W - pb.p_W;
    velocity.head<3>() = (w.Ja.bottomRows<3>() - w.Jb.bottomRows<3>()) * qd;
    // e_R = ½ Σ r_b,k × r_a,k, e_R' = ½ Σ ((ω_b × r_b) × r_a + r_b × (ω_a × r_a))
    const Matrix3d Ra = world_rotation(w.data, a_.link, a_.R);
    const Matrix3d Rb = world_rotation(w.data, b_.link, b_.R);
    const Vector3d wa = w.Ja.topRows<3>() * qd, wb = w.Jb.topRows<3>() * qd;
    Vector3d e = Vector3d::Zero(), e_rate = Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const Vector3d ra = Ra.col(k), rb = Rb.col(k);
      e += 0.5 * rb.cross(ra);
      e_rate += 0.5 * (wb.cross(rb).cross(ra) + rb.cross(wa.cross(ra)));
    }
    position.tail<3>() = e;
    velocity.tail<3>() = e_rate;
  }

 private:
  LinkFrame a_, b_;
};

// [p_W(a) − p_W(b); u_a · x_b; u_a · y_b] = 0 (see revolute_constraint)
class RevoluteModel final : public FrameModel {
 public:
  RevoluteModel(std::shared_ptr<const Tree> tree, LinkPoint a, const Vector3d& axis_a, LinkPoint b,
                const Vector3d& axis_b)
      : FrameModel(std::move(tree)), a_(a), b_(b), u_a_(axis_a.normalized()) {
    // x_b, y_b: an orthonormal pair ⊥ u_b in b's link frame
    const Vector3d u = axis_b.normalized();
    const Vector3d seed = std::abs(u.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
    x_b_ = (seed - u * u.dot(seed)).normalized();
    y_b_ = u.cross(x_b_);
  }
  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double, ConstraintScratch* s, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pa = point_state(*tree_, a_, q, qd, w, w.Ja, true);
    const PointState pb = point_state(*tree_, b_, q, qd, w, w.Jb, true);
    A.topRows<3>() = w.Ja.bottomRows<3>() - w.Jb.bottomRows<3>();
    b.head<3>() = pb.bias.tail<3>() - pa.bias.tail<3>();
    // φ = u_a · x: φ'' = (u_a × x) · (ω_a' − ω_b') + ((ω_a × u_a) × x + u_a × (ω_b × x)) · (ω_a −
    // ω_b)
    const Vector3d u = world_rotation(w.data, a_.link, Matrix3d::Identity()) * u_a_;
    const Matrix3d Rb = world_rotation(w.data, b_.link, Matrix3d::Identity());
    const Vector3d wa = w.Ja.topRows<3>() * qd, wb = w.Jb.topRows<3>() * qd;
    const Vector3d dw = wa - wb, dbias = pa.bias.head<3>() - pb.bias.head<3>();
    for (int k = 0; k < 2; ++k) {
      const Vector3d x = Rb * (k == 0 ? x_b_ : y_b_);
      const Vector3d g = u.cross(x);
      A.row(3 + k).noalias() = g.transpose() * (w.Ja.topRows<3>() - w.Jb.topRows<3>());
      b[3 + k] = -g.dot(dbias) - (wa.cross(u).cross(x) + u.cross(wb.cross(x))).dot(dw);
    }
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 ConstraintScratch* s, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pa = point_state(*tree_, a_, q, qd, w, w.Ja, false);
    const PointState pb = point_state(*tree_, b_, q, qd, w, w.Jb, false);
    position.head<3>() = pa.p_W - pb.p_W;
    velocity.head<3>() = (w.Ja.bottomRows<3>() - w.Jb.bottomRows<3>()) * qd;
    // φ = u_a · x, φ' = (u_a × x) · (ω_a − ω_b)
    const Vector3d u = world_rotation(w.data, a_.link, Matrix3d::Identity()) * u_a_;
    const Matrix3d Rb = world_rotation(w.data, b_.link, Matrix3d::Identity());
    const Vector3d dw = (w.Ja.topRows<3>() - w.Jb.topRows<3>()) * qd;
    for (int k = 0; k < 2; ++k) {
      const Vector3d x = Rb * (k == 0 ? x_b_ : y_b_);
      position[3 + k] = u.dot(x);
      velocity[3 + k] = u.cross(x).dot(dw);
    }
  }

 private:
  LinkPoint a_, b_;
  Vector3d u_a_, x_b_, y_b_;  // unit axis in a's link frame; the pair ⊥ u_b in b's
};

// g = n_W · (p_W(at) − o_W) − r with n_W = R_Wo n_o: g'' = 0 is A q'' = b (see
// contact_constraint); n_W' = ω_o × n_W, n_W'' = ω_o' × n_W + ω_o × (ω_o × n_W). A disk (axis a
// in at's link): g = n_W · d − r h, h = √(1 − s²), s = n_W · a_W (see disk_contact_constraint)
class ContactModel final : public FrameModel {
 public:
  ContactModel(std::shared_ptr<const Tree> tree, LinkPoint at, double radius, LinkPoint origin,
               const Vector3d& normal, const Vector3d* axis = nullptr)
      : FrameModel(std::move(tree)),
        at_(at),
        origin_(origin),
        n_o_(normal),
        a_l_(axis != nullptr ? axis->normalized() : Vector3d::Zero()),
        radius_(radius),
        disk_(axis != nullptr) {}
  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double, ConstraintScratch* s, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pa = point_state(*tree_, at_, q, qd, w, w.Ja, true);
    const PointState po = point_state(*tree_, origin_, q, qd, w, w.Jb, true);
    const Vector3d n = world_rotation(w.data, origin_.link, Matrix3d::Identity()) * n_o_;
    const Vector3d dist = pa.p_W - po.p_W, n_x_d = n.cross(dist);
    // (J_v(at) − J_v(o)) into Ja's linear rows, then d' = (J_v(at) − J_v(o)) q'
    w.Ja.bottomRows<3>() -= w.Jb.bottomRows<3>();
    w.Ja_valid = false;  // (Ja now holds J_v(at) − J_v(o))
    const Vector3d rate = w.Ja.bottomRows<3>() * qd;
    A.row(0).noalias() = n.transpose() * w.Ja.bottomRows<3>();
    b[0] = -n.dot(pa.bias.tail<3>() - po.bias.tail<3>());
    // a plane on a link: n_W turns with ω_o (a world plane's n_W is fixed, ω_o = 0)
    const bool moving = origin_.link >= 0;
    const Vector3d wo = moving ? Vector3d(w.Jb.topRows<3>() * qd) : Vector3d::Zero();
    const Vector3d n1 = wo.cross(n);  // n_W'
    if (moving) {
      A.row(0).noalias() += n_x_d.transpose() * w.Jb.topRows<3>();
      b[0] -= n_x_d.dot(po.bias.head<3>()) + 2.0 * n1.dot(rate) + wo.cross(n1).dot(dist);
    }
    if (!disk_) return;
    // the disk: s'' = A_s q'' − b_s with m = n_W × a_W, A_s = mᵀ (J_ω(o) − J_ω(at)),
    // b_s = −m · (β_ω(o) − β_ω(at)) − (n_W' × a_W + n_W × a_W') · (ω_o − ω_l);
    // A += f A_s, b += f b_s − r s'² / h³ with f = r s / h (h = 0, a disk lying flat: infinite
    // entries, which stop the run naming the contact)
    const Vector3d a = world_rotation(w.data, at_.link, Matrix3d::Identity()) * a_l_;
    const Vector3d wl = w.Ja.topRows<3>() * qd, dw = wo - wl, m = n.cross(a);
    const double sn = n.dot(a), sd = m.dot(dw);
    const double h = std::sqrt(std::max(1.0 - sn * sn, 0.0));
    const double f = radius_ * sn / h;
    A.row(0).noalias() -= (f * m).transpose() * w.Ja.topRows<3>();
    if (moving) A.row(0).noalias() += (f * m).transpose() * w.Jb.topRows<3>();
    b[0] -= f * (m.dot(po.bias.head<3>() - pa.bias.head<3>()) +
                 (n1.cross(a) + n.cross(wl.cross(a))).dot(dw)) +
            radius_ * sd * sd / (h * h * h);
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 ConstraintScratch* s, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pa = point_state(*tree_, at_, q, qd, w, w.Ja, false);
    const PointState po = point_state(*tree_, origin_, q, qd, w, w.Jb, false);
    const Vector3d n = world_rotation(w.data, origin_.link, Matrix3d::Identity()) * n_o_;
    const Vector3d dist = pa.p_W - po.p_W;
    // g' = n_W · d' + (n_W × d) · ω_o
    position[0] = n.dot(dist) - radius_;
    velocity[0] = n.dot((w.Ja.bottomRows<3>() - w.Jb.bottomRows<3>()) * qd);
    const Vector3d wo = origin_.link >= 0 ? Vector3d(w.Jb.topRows<3>() * qd) : Vector3d::Zero();
    if (origin_.link >= 0) velocity[0] += n.cross(dist).dot(wo);
    if (!disk_) return;
    // the disk: g = n_W · d − r h, g' = [n_W · d]' + r s s' / h, s' = (n_W × a_W) · (ω_o − ω_l)
    const Vector3d a = world_rotation(w.data, at_.link, Matrix3d::Identity()) * a_l_;
    const double sn = n.dot(a), h = std::sqrt(std::max(1.0 - sn * sn, 0.0));
    position[0] = n.dot(dist) - radius_ * h;
    velocity[0] += radius_ * sn * n.cross(a).dot(wo - w.Ja.topRows<3>() * qd) / h;
  }

 private:
  LinkPoint at_, origin_;  // the sphere's or disk's centre; the plane's origin
  Vector3d n_o_;           // the plane's unit normal in its link's frame (the world's for -1)
  Vector3d a_l_;           // a disk's unit axis in at's link frame (zero: a sphere or point)
  double radius_;
  bool disk_;
};

// e = [p_W − p_d; ½ Σ r_d,k × r_k]; e'' = 0 is A q'' = b (see pose_requirement)
class PoseModel final : public FrameModel {
 public:
  PoseModel(std::shared_ptr<const Tree> tree, LinkPoint at, PosePathFn path, bool orientation)
      : FrameModel(std::move(tree)), at_(at), path_(std::move(path)), orientation_(orientation) {}
  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double t, ConstraintScratch* s, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pt = point_state(*tree_, at_, q, qd, w, w.Ja, true);
    const PoseSample& d = desired_at(path_, t, w);
    // position: J_v q'' = a_d − (J' q')_v
    A.topRows<3>() = w.Ja.bottomRows<3>();
    b.head<3>() = d.a - pt.bias.tail<3>();
    if (!orientation_) return;
    // orientation: r_k' = ω × r_k, r_d,k' = w_d × r_d,k, r_d,k'' = w_d' × r_d,k + w_d × r_d,k';
    // e_R'' = L ω' + ½ Σ (r_d,k'' × r_k + 2 r_d,k' × r_k' + r_d,k × (ω × r_k')) with
    // ω' = J_ω q'' + β_ω, L = −½ Σ [r_d,k]× [r_k]×
    const Matrix3d& R = w.data.R_WL[std::size_t(at_.link)];
    const Vector3d& omega = angular_velocity(w, qd);
    Matrix3d L = Matrix3d::Zero();
    Vector3d rest = Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const Vector3d r = R.col(k), rd = d.R.col(k);
      const Vector3d r1 = omega.cross(r), rd1 = d.w.cross(rd);
      const Vector3d rd2 = d.w_dot.cross(rd) + d.w.cross(rd1);
      subtract_half_skew_product(rd, r, L);
      rest += 0.5 * (rd2.cross(r) + 2.0 * rd1.cross(r1) + rd.cross(omega.cross(r1)));
    }
    A.bottomRows<3>().noalias() = L * w.Ja.topRows<3>();
    b.tail<3>() = -rest - L * pt.bias.head<3>();
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                 double t, ConstraintScratch* s, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pt = point_state(*tree_, at_, q, qd, w, w.Ja, false);
    const PoseSample& d = desired_at(path_, t, w);
    position.head<3>() = pt.p_W - d.p;
    velocity.head<3>() = w.Ja.bottomRows<3>() * qd - d.v;
    if (!orientation_) return;
    // e_R = ½ Σ r_d,k × r_k, e_R' = ½ Σ (r_d,k' × r_k + r_d,k × r_k')
    const Matrix3d& R = w.data.R_WL[std::size_t(at_.link)];
    const Vector3d& omega = angular_velocity(w, qd);
    Vector3d e = Vector3d::Zero(), e_rate = Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const Vector3d r = R.col(k), rd = d.R.col(k);
      e += 0.5 * rd.cross(r);
      e_rate += 0.5 * (d.w.cross(rd).cross(r) + rd.cross(omega.cross(r)));
    }
    position.tail<3>() = e;
    velocity.tail<3>() = e_rate;
  }

 private:
  LinkPoint at_;
  PosePathFn path_;
  bool orientation_;
};

}  // namespace

Constraint point_constraint(const Tree& tree, std::string name, LinkPoint a, LinkPoint b) {
  const std::string who = "ukdyn::tree::point_constraint";
  check_points(tree, who, name, a, b);
  auto model = std::make_shared<PointModel>(std::make_shared<const Tree>(tree), a, b);
  return Constraint(std::move(name), ConstraintKind::kHolonomic, 3, std::move(model));
}

Constraint distance_constraint(const Tree& tree, std::string name, LinkPoint a, LinkPoint b,
                               double length) {
  const std::string who = "ukdyn::tree::distance_constraint";
  check_points(tree, who, name, a, b);
  if (!(length > 0.0) || !std::isfinite(length)) {
    throw std::invalid_argument(who + ": constraint '" + name + "': the length must be a " +
                                "positive number, got " + std::to_string(length) +
                                " (two points held together: point_constraint)");
  }
  auto model = std::make_shared<DistanceModel>(std::make_shared<const Tree>(tree), a, b, length);
  return Constraint(std::move(name), ConstraintKind::kHolonomic, 1, std::move(model));
}

Constraint weld_constraint(const Tree& tree, std::string name, const LinkFrame& a,
                           const LinkFrame& b) {
  const std::string who = "ukdyn::tree::weld_constraint";
  check_points(tree, who, name, {a.link, a.p}, {b.link, b.p});
  for (const auto* f : {&a, &b}) {
    const Matrix3d& R = f->R;
    if (!R.allFinite() || !(R.transpose() * R).isApprox(Matrix3d::Identity(), 1e-9) ||
        !(R.determinant() > 0.0)) {
      throw std::invalid_argument(who + ": constraint '" + name + "': the orientation of frame " +
                                  (f == &a ? "a" : "b") +
                                  " is not a rotation (R must be orthonormal with det R = 1)");
    }
  }
  auto model = std::make_shared<WeldModel>(std::make_shared<const Tree>(tree), a, b);
  return Constraint(std::move(name), ConstraintKind::kHolonomic, 6, std::move(model));
}

Constraint revolute_constraint(const Tree& tree, std::string name, LinkPoint a,
                               const Vector3d& axis_a, LinkPoint b, const Vector3d& axis_b) {
  const std::string who = "ukdyn::tree::revolute_constraint";
  check_points(tree, who, name, a, b);
  for (const auto* u : {&axis_a, &axis_b}) {
    if (!u->allFinite() || !(u->norm() > 1e-12)) {
      throw std::invalid_argument(who + ": constraint '" + name + "': axis " +
                                  (u == &axis_a ? "a" : "b") +
                                  " must be a finite, nonzero vector (the hinge's axis in the "
                                  "link's frame)");
    }
  }
  auto model =
      std::make_shared<RevoluteModel>(std::make_shared<const Tree>(tree), a, axis_a, b, axis_b);
  return Constraint(std::move(name), ConstraintKind::kHolonomic, 5, std::move(model));
}

namespace {

// a contact's plane: a rotation (its z axis the normal)
void check_plane(const std::string& who, const std::string& name, const LinkFrame& plane) {
  const Matrix3d& R = plane.R;
  if (!R.allFinite() || !(R.transpose() * R).isApprox(Matrix3d::Identity(), 1e-9) ||
      !(R.determinant() > 0.0)) {
    throw std::invalid_argument(who + ": constraint '" + name +
                                "': the plane's orientation is not a rotation (R must be "
                                "orthonormal with det R = 1; its z axis is the normal)");
  }
}

}  // namespace

void detail::check_contact(const Tree& tree, const std::string& who, const std::string& name,
                           const LinkPoint& at, const LinkFrame& plane) {
  check_points(tree, who, name, at, {plane.link, plane.p});
  check_plane(who, name, plane);
}

Constraint contact_constraint(const Tree& tree, std::string name, LinkPoint at, double radius,
                              const LinkFrame& plane, double restitution) {
  const std::string who = "ukdyn::tree::contact_constraint";
  check_points(tree, who, name, at, {plane.link, plane.p});
  if (!(radius >= 0.0) || !std::isfinite(radius)) {
    throw std::invalid_argument(who + ": constraint '" + name + "': the radius must be a " +
                                "finite number >= 0, got " + std::to_string(radius) +
                                " (0: a point)");
  }
  check_plane(who, name, plane);
  auto model = std::make_shared<ContactModel>(std::make_shared<const Tree>(tree), at, radius,
                                              LinkPoint{plane.link, plane.p}, plane.R.col(2));
  Constraint c(std::move(name), ConstraintKind::kHolonomic, 1, std::move(model));
  c.unilateral(restitution);
  return c;
}

Constraint disk_contact_constraint(const Tree& tree, std::string name, const LinkDisk& disk,
                                   const LinkFrame& plane, const Eigen::Ref<const VectorXd>& q0,
                                   double restitution) {
  const std::string who = "ukdyn::tree::disk_contact_constraint";
  const LinkPoint at{disk.link, disk.centre};
  check_points(tree, who, name, at, {plane.link, plane.p});
  if (!(disk.radius > 0.0) || !std::isfinite(disk.radius)) {
    throw std::invalid_argument(who + ": constraint '" + name +
                                "': the disk's radius must be a finite number > 0, got " +
                                std::to_string(disk.radius));
  }
  if (!disk.axis.allFinite() || !(disk.axis.norm() > 1e-12)) {
    throw std::invalid_argument(who + ": constraint '" + name +
                                "': the disk's axis must be a finite, nonzero vector (the normal "
                                "of its face in the link's frame)");
  }
  check_plane(who, name, plane);
  if (q0.size() != tree.coordinate_count() || !q0.allFinite()) {
    throw std::invalid_argument(who + ": constraint '" + name + "': q0 must hold " +
                                std::to_string(tree.coordinate_count()) +
                                " finite coordinates (the start), got " +
                                std::to_string(q0.size()));
  }
  // a disk lying flat on its plane at the start has no single lowest point (h = 0): refused
  TreeData d(tree);
  forward_kinematics(tree, q0, d);
  const Vector3d n = world_rotation(d, plane.link, plane.R).col(2);
  const Vector3d a = world_rotation(d, disk.link, Matrix3d::Identity()) * disk.axis.normalized();
  if (const double s = std::abs(n.dot(a)); s > 1.0 - 1e-6) {
    throw std::invalid_argument(
        who + ": constraint '" + name +
        "': the disk lies flat on its plane at the start (|n·a| = " + format_number(s, 9) +
        "): it has no single lowest point there; tilt it (initial: q) or model it as a point "
        "contact at each of a few rim points");
  }
  auto model =
      std::make_shared<ContactModel>(std::make_shared<const Tree>(tree), at, disk.radius,
                                     LinkPoint{plane.link, plane.p}, plane.R.col(2), &disk.axis);
  Constraint c(std::move(name), ConstraintKind::kHolonomic, 1, std::move(model));
  c.unilateral(restitution);
  return c;
}

Constraint pose_requirement(const Tree& tree, std::string name, LinkPoint at, PosePathFn path,
                            bool orientation) {
  const std::string who = "ukdyn::tree::pose_requirement";
  if (at.link < 0 || at.link >= tree.link_count()) {
    throw std::invalid_argument(who + ": requirement '" + name + "': link " +
                                std::to_string(at.link) + " out of range [0, " +
                                std::to_string(tree.link_count()) + ")");
  }
  if (!path) {
    throw std::invalid_argument(who + ": requirement '" + name + "': the path is empty");
  }
  auto model = std::make_shared<PoseModel>(std::make_shared<const Tree>(tree), at, std::move(path),
                                           orientation);
  return Constraint(std::move(name), ConstraintKind::kHolonomic, orientation ? 6 : 3,
                    std::move(model));
}

}  // namespace ukdyn::tree

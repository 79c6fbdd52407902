// SPDX-License-Identifier: BSD-3-Clause
// The contact point's kinematics of a robot's contact, for Coulomb friction there
// (ContactKinematics; docs/contact.md, "Contacts on robots", and docs/robots.md, "Contacts"): a
// link's point, sphere or disk on a plane of the world or of another link. The sliding velocity
// is the relative velocity of the two links' material points at the contact point x (the
// contact link's minus the plane link's), in the plane's tangents, which turn with the plane's
// link. On the tree's joint coordinates, from frame_jacobian and frame_bias_acceleration.
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "multibody/disk_point.hpp"
#include "multibody/tree/frame_scratch.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/multibody/tree_closures.hpp"

namespace ukdyn::tree {

namespace {

using detail::FrameScratch;
using detail::point_state;
using detail::PointState;
using detail::world_rotation;

// The rows [n; t_1; t_2] of the relative velocity of the material points at the contact point
// and their rates, for the four cases (a point or sphere, or a disk; a plane of the world or of
// a link). c the centre on link C (at), o the plane's point on link P, d = c − o, ω_C, ω_P the
// links' angular velocities, ρ the vector from c to the contact point x:
//   ρ = −r n (a point, a sphere),   ρ = −r m/|m|, m = n − s a, s = n·a (a disk of axis a: its
//   rim point most opposed to n, which moves on the disk),
//   v_rel = v(c) + ω_C × ρ − v(o) − ω_P × (d + ρ),
//   J_rel = J_v(c) − J_v(o) − [ρ]× J_ω(C) + [d + ρ]× J_ω(P),
//   J_rel' q' = β_v(c) − β_v(o) + β_ω(C) × ρ + ω_C × ρ' − β_ω(P) × (d + ρ) − ω_P × (d' + ρ'),
// β = J' q' (frame_bias_acceleration). The rows r ∈ {n, t_1, t_2} (the plane's z, x, y turned
// with P: r' = ω_P × r) give J = rᵀ J_rel and bias = r'·v_rel + r·J_rel' q', the rate of
// r·v_rel at q'' = 0 (the stick constraint's acceleration form needs the turning of r). Row 0,
// nᵀ J_rel, is the gap's gradient (the contact row's A: the normal velocities of the two
// material points at a point where the surfaces touch differ by the gap's rate).
class Evaluator {
 public:
  Evaluator(std::shared_ptr<const Tree> tree, LinkPoint at, double radius, const LinkFrame& plane,
            const Vector3d* axis)
      : tree_(std::move(tree)),
        at_(at),
        origin_{plane.link, plane.p},
        R_P_(plane.R),
        a_L_(axis != nullptr ? axis->normalized() : Vector3d::Zero()),
        radius_(radius),
        disk_(axis != nullptr) {}

  void operator()(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                  ConstraintScratch* s, Eigen::Ref<MatrixXd> J, Eigen::Ref<VectorXd> bias) const {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pc = point_state(*tree_, at_, q, qd, w, w.Ja, true);
    const PointState po = point_state(*tree_, origin_, q, qd, w, w.Jb, true);
    const Matrix3d R = world_rotation(w.data, origin_.link, R_P_);
    const Vector3d n = R.col(2);
    // the links' angular velocities, d and d'
    const Vector3d wC = w.Ja.topRows<3>() * qd;
    const Vector3d wP = origin_.link >= 0 ? Vector3d(w.Jb.topRows<3>() * qd) : Vector3d::Zero();
    const Vector3d d = pc.p_W - po.p_W;
    const Vector3d dd = w.Ja.bottomRows<3>() * qd - w.Jb.bottomRows<3>() * qd;
    // ρ and its rate ρ' along q' (n' = ω_P × n; a disk's a' = ω_C × a)
    const Vector3d n1 = wP.cross(n);
    Vector3d rho = -radius_ * n, rho1 = -radius_ * n1;
    if (disk_) {
      const Vector3d a = world_rotation(w.data, at_.link, Matrix3d::Identity()) * a_L_;
      mb::detail::disk_lowest_point(n, n1, a, wC.cross(a), radius_, rho, rho1);
    }
    // v_rel and J_rel' q'
    const Vector3d arm = d + rho;
    const Vector3d v_rel = dd + wC.cross(rho) - wP.cross(arm);
    const Vector3d a_rel = pc.bias.tail<3>() - po.bias.tail<3>() + pc.bias.head<3>().cross(rho) +
                           wC.cross(rho1) - po.bias.head<3>().cross(arm) - wP.cross(dd + rho1);
    for (int i = 0; i < 3; ++i) {
      const Vector3d r = R.col((i + 2) % 3);  // n, t_1, t_2
      // rᵀ J_rel = rᵀ (J_v(c) − J_v(o)) + (ρ × r)ᵀ J_ω(C) − ((d + ρ) × r)ᵀ J_ω(P)
      J.row(i).noalias() = r.transpose() * w.Ja.bottomRows<3>();
      J.row(i).noalias() -= r.transpose() * w.Jb.bottomRows<3>();
      J.row(i).noalias() += rho.cross(r).transpose() * w.Ja.topRows<3>();
      J.row(i).noalias() -= arm.cross(r).transpose() * w.Jb.topRows<3>();
      bias[i] = wP.cross(r).dot(v_rel) + r.dot(a_rel);
    }
  }

 private:
  std::shared_ptr<const Tree> tree_;
  LinkPoint at_;      // the centre c (a point's own position) on link C
  LinkPoint origin_;  // the plane's point o on link P (-1: the world)
  Matrix3d R_P_;      // the plane's axes in P's frame: t_1, t_2, n
  Vector3d a_L_;      // a disk's unit axis in C's frame (zero otherwise)
  double radius_;     // r (0: a point)
  bool disk_;
};

ContactKinematics make_kinematics(const Tree& tree, LinkPoint at, double radius,
                                  const LinkFrame& plane, const Vector3d* axis) {
  auto shared = std::make_shared<const Tree>(tree);
  ContactKinematics kin;
  kin.tangents = 2;
  for (Index i = 0; i < tree.coordinate_count(); ++i) kin.columns.push_back(i);
  kin.make_scratch = [shared](Index) -> std::unique_ptr<ConstraintScratch> {
    return std::make_unique<FrameScratch>(*shared, nullptr);
  };
  if (plane.link >= 0 || axis != nullptr) {
    kin.evaluate = Evaluator(shared, at, radius, plane, axis);
    return kin;
  }
  // a point or sphere on a plane of the world: n, t_i fixed and ρ = −r n fixed, so
  // v_P = v(c) + ω × ρ: J_P = J_v − [ρ]× J_ω, J_P' q' = β_v + β_ω × ρ (Evaluator's terms that
  // are zero here left out)
  const Vector3d n = plane.R.col(2), t1 = plane.R.col(0), t2 = plane.R.col(1);
  const Vector3d a = -radius * n;  // ρ
  kin.evaluate = [shared, at, n, t1, t2, a](const Eigen::Ref<const VectorXd>& q,
                                            const Eigen::Ref<const VectorXd>& qd, double,
                                            ConstraintScratch* s, Eigen::Ref<MatrixXd> J,
                                            Eigen::Ref<VectorXd> bias) {
    auto& w = *static_cast<FrameScratch*>(s);
    const PointState pc = point_state(*shared, at, q, qd, w, w.Ja, true);
    const Vector3d g = pc.bias.tail<3>() + pc.bias.head<3>().cross(a);
    const Vector3d rows[3] = {n, t1, t2};
    for (int i = 0; i < 3; ++i) {
      // rᵀ (J_v − [a]× J_ω) = rᵀ J_v + (a × r)ᵀ J_ω   (−rᵀ [a]× = (a × r)ᵀ)
      J.row(i).noalias() = rows[i].transpose() * w.Ja.bottomRows<3>();
      J.row(i).noalias() += a.cross(rows[i]).transpose() * w.Ja.topRows<3>();
      bias[i] = rows[i].dot(g);
    }
  };
  return kin;
}

}  // namespace

ContactKinematics contact_kinematics(const Tree& tree, const std::string& name, LinkPoint at,
                                     double radius, const LinkFrame& plane) {
  detail::check_contact(tree, "ukdyn::tree::contact_kinematics", name, at, plane);
  return make_kinematics(tree, at, radius, plane, nullptr);
}

ContactKinematics disk_contact_kinematics(const Tree& tree, const std::string& name,
                                          const LinkDisk& disk, const LinkFrame& plane) {
  const std::string who = "ukdyn::tree::disk_contact_kinematics";
  detail::check_contact(tree, who, name, {disk.link, disk.centre}, plane);
  if (!(disk.radius > 0.0) || !std::isfinite(disk.radius) || !disk.axis.allFinite() ||
      !(disk.axis.norm() > 1e-12)) {
    throw std::invalid_argument(who + ": contact '" + name +
                                "': the disk needs a finite radius > 0 and a finite, nonzero "
                                "axis (the normal of its face in the link's frame)");
  }
  return make_kinematics(tree, {disk.link, disk.centre}, disk.radius, plane, &disk.axis);
}

}  // namespace ukdyn::tree

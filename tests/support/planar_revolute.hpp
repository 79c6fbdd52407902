// SPDX-License-Identifier: BSD-3-Clause
// Test and benchmark support: a planar revolute joint with local columns (the input of the
// sparse engine), written out by hand so that the engine's tests do not depend on
// multibody/multibody.hpp.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <ukdyn/core/constraint.hpp>

namespace ukdyn::testing {

// a planar revolute joint between bodies (x, y, theta) (coordinates 3i … 3i+2, reference point
// the centre of mass): point s_i of body i on point s_j of body j, or on the ground point g
// (j < 0). phi = p_i + R_i s_i − p_j − R_j s_j;  A_i = [I | R_i J s_i], A_j = −[I | R_j J s_j];
// b = R_i s_i theta_i'² − R_j s_j theta_j'²  (J: rotation by +90°)
class PlanarRevolute final : public ConstraintModel {
 public:
  PlanarRevolute(Index i, Eigen::Vector2d si, Index j, Eigen::Vector2d sj)
      : i_(i), j_(j), si_(si), sj_(sj) {
    const Index lo = j >= 0 ? std::min(i, j) : i, hi = j >= 0 ? std::max(i, j) : i;
    for (Index c = 0; c < 3; ++c) cols_.push_back(3 * lo + c);
    if (hi != lo) {
      for (Index c = 0; c < 3; ++c) cols_.push_back(3 * hi + c);
    }
  }
  const std::vector<Index>& columns() const override { return cols_; }
  void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double, ConstraintScratch*,
                               Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> b) const override {
    const Index oi = (j_ >= 0 && j_ < i_) ? 3 : 0, oj = 3 - oi;
    const Eigen::Vector2d ri = rot(q[3 * i_ + 2]) * si_;
    A.block(0, oi, 2, 2).setIdentity();
    A(0, oi + 2) = -ri.y();
    A(1, oi + 2) = ri.x();
    const double wi = qd[3 * i_ + 2];
    b = ri * wi * wi;
    if (j_ >= 0) {
      const Eigen::Vector2d rj = rot(q[3 * j_ + 2]) * sj_;
      A.block(0, oj, 2, 2) = -Eigen::Matrix2d::Identity();
      A(0, oj + 2) = rj.y();
      A(1, oj + 2) = -rj.x();
      const double wj = qd[3 * j_ + 2];
      b -= rj * wj * wj;
    }
  }
  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 ConstraintScratch*, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    const Eigen::Vector2d ri = rot(q[3 * i_ + 2]) * si_;
    position = q.segment<2>(3 * i_) + ri;
    velocity = qd.segment<2>(3 * i_) + Eigen::Vector2d(-ri.y(), ri.x()) * qd[3 * i_ + 2];
    if (j_ >= 0) {
      const Eigen::Vector2d rj = rot(q[3 * j_ + 2]) * sj_;
      position -= q.segment<2>(3 * j_) + rj;
      velocity -= qd.segment<2>(3 * j_) + Eigen::Vector2d(-rj.y(), rj.x()) * qd[3 * j_ + 2];
    } else {
      position -= sj_;
    }
  }

 private:
  static Eigen::Matrix2d rot(double th) {
    Eigen::Matrix2d R;
    R << std::cos(th), -std::sin(th), std::sin(th), std::cos(th);
    return R;
  }
  Index i_, j_;
  Eigen::Vector2d si_, sj_;
  std::vector<Index> cols_;
};

/// A named two-row holonomic Constraint of a PlanarRevolute.
inline Constraint planar_revolute(const std::string& name, Index i, Eigen::Vector2d si, Index j,
                                  Eigen::Vector2d sj) {
  return Constraint(name, ConstraintKind::kHolonomic, 2,
                    std::make_shared<PlanarRevolute>(i, si, j, sj));
}

}  // namespace ukdyn::testing

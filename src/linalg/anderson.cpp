// SPDX-License-Identifier: BSD-3-Clause
// AndersonAcceleration: type II Anderson acceleration, least squares by modified Gram–Schmidt on
// the stored differences (notation as in linalg/anderson.hpp).
#include "ukdyn/linalg/anderson.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "ukdyn/core/format.hpp"

namespace ukdyn {

void AndersonAcceleration::resize(Index dimension, int depth) {
  if (dimension < 0 || depth < 1) {
    throw std::invalid_argument(
        "ukdyn::AndersonAcceleration::resize: expected dimension >= 0 and depth >= 1, got " +
        format_number(dimension) + " and " + format_number(depth));
  }
  depth_ = depth;
  dF_.setZero(dimension, depth);
  dG_.setZero(dimension, depth);
  Q_.setZero(dimension, depth);
  R_.setZero(depth, depth);
  f_.setZero(dimension);
  g_.setZero(dimension);
  h_.setZero(depth);
  slot_.assign(std::size_t(depth), 0);
  head_ = 0;
  used_ = 0;
  reset();
}

AndersonAcceleration& AndersonAcceleration::set_drop_tolerance(double tolerance) {
  if (!(tolerance >= 0.0 && tolerance < 1.0)) {
    throw std::invalid_argument(
        "ukdyn::AndersonAcceleration::set_drop_tolerance: expected a tolerance in [0, 1), got " +
        format_number(tolerance));
  }
  drop_ = tolerance;
  return *this;
}

void AndersonAcceleration::update(const Eigen::Ref<const VectorXd>& x,
                                  const Eigen::Ref<const VectorXd>& g) {
  if (has_last_) {
    // ΔF, ΔG ← f_k − f_k−1, g_k − g_k−1 (over the oldest column once depth are stored)
    dF_.col(head_) = (g - x) - f_;
    dG_.col(head_) = g - g_;
    head_ = (head_ + 1) % depth_;
    stored_ = std::min(stored_ + 1, depth_);
  }
  // f_k = g_k − x_k
  f_ = g - x;
  g_ = g;
  has_last_ = true;
}

void AndersonAcceleration::extrapolate(Eigen::Ref<VectorXd> next) {
  // ΔF's kept columns = Q R, newest first (modified Gram–Schmidt; a column left with at most
  // drop_ of its norm, or not finite, is left out)
  int kept = 0;
  for (int j = 0; j < stored_; ++j) {
    const int slot = (head_ - 1 - j + 2 * depth_) % depth_;
    auto v = Q_.col(kept);
    v = dF_.col(slot);
    const double norm0 = v.norm();
    if (!(norm0 > 0.0) || !std::isfinite(norm0)) continue;
    for (int i = 0; i < kept; ++i) {
      const double r = Q_.col(i).dot(v);
      R_(i, kept) = r;
      v -= r * Q_.col(i);
    }
    const double norm = v.norm();
    if (!(norm > drop_ * norm0)) continue;
    R_(kept, kept) = norm;
    v /= norm;
    slot_[std::size_t(kept)] = slot;
    ++kept;
  }
  used_ = kept;
  // γ = R⁻¹ Qᵀ f_k (back substitution)
  for (int i = 0; i < kept; ++i) h_[i] = Q_.col(i).dot(f_);
  for (int i = kept - 1; i >= 0; --i) {
    double s = h_[i];
    for (int j = i + 1; j < kept; ++j) s -= R_(i, j) * h_[j];
    h_[i] = s / R_(i, i);
  }
  // x_k+1 = g_k − ΔG γ
  next = g_;
  for (int i = 0; i < kept; ++i) next -= h_[i] * dG_.col(slot_[std::size_t(i)]);
}

}  // namespace ukdyn

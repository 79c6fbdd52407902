// SPDX-License-Identifier: BSD-3-Clause
/// @file linalg/anderson.hpp
/// Anderson acceleration of a fixed-point iteration x ← g(x) in R^d, in the shape of Eigen's
/// decompositions: sized once, then update() and extrapolate() without allocating.
///
/// Type II (Walker & Ni, SIAM J. Numer. Anal. 49, 2011): with the residuals f_j = g(x_j) − x_j
/// and the last p differences ΔF = [f_j+1 − f_j], ΔG = [g_j+1 − g_j] (p <= depth),
///
///     γ = argmin ‖f_k − ΔF γ‖₂,     x_k+1 = g_k − ΔG γ,
///
/// the least squares solved by modified Gram–Schmidt on the columns of ΔF, newest first. A
/// column whose part outside the newer ones is at most drop_tolerance() of its norm is left out
/// (filtered Anderson acceleration: nearly parallel differences would only amplify roundoff).
/// With no difference kept, x_k+1 = g_k (a plain step). On an affine map g(x) = J x + c whose
/// J − I is regular on the span of the residuals, of dimension r <= depth, x_k+1 is the fixed
/// point once r differences are stored (in exact arithmetic) — for any contraction rate of the
/// plain iteration, and for some expanding maps too: a settled iterate must still be checked
/// against the map itself.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "ukdyn/core/types.hpp"

namespace ukdyn {

/// Anderson acceleration (type II) of x ← g(x) (see the file comment).
class AndersonAcceleration {
 public:
  /// The default number of differences kept.
  static constexpr int kDefaultDepth = 5;
  /// The default relative drop tolerance of a difference (see the file comment).
  static constexpr double kDefaultDropTolerance = 1e-8;

  /// An empty accelerator (dimension 0); call resize() before use.
  AndersonAcceleration() = default;
  /// Reserves memory for vectors of `dimension` entries and `depth` differences.
  AndersonAcceleration(Index dimension, int depth) { resize(dimension, depth); }
  /// Reserves memory for vectors of `dimension` entries and `depth` differences (allocates) and
  /// forgets the history. @throws std::invalid_argument when dimension < 0 or depth < 1.
  void resize(Index dimension, int depth);

  /// Forgets the stored iterates: the next update() starts a new history. Cost O(1).
  void reset() {
    stored_ = 0;
    has_last_ = false;
  }
  /// Records the iterate x and its image g = g(x) (both of dimension()): the differences of
  /// its residual f = g − x and of g from the previous update's. Cost O(d).
  void update(const Eigen::Ref<const VectorXd>& x, const Eigen::Ref<const VectorXd>& g);
  /// Writes the next iterate g_k − ΔG γ into `next` (dimension()), from the last update's g_k
  /// and f_k and the stored differences; g_k when there are none. Cost O(d p²), p the
  /// differences stored. Requires one update() since the last reset().
  void extrapolate(Eigen::Ref<VectorXd> next);

  /// Sets the relative drop tolerance (in [0, 1)); takes effect at the next extrapolate().
  AndersonAcceleration& set_drop_tolerance(double tolerance);
  /// The relative drop tolerance.
  double drop_tolerance() const { return drop_; }
  /// The dimension d of the iterates.
  Index dimension() const { return f_.size(); }
  /// The largest number of differences kept.
  int depth() const { return depth_; }
  /// The differences stored now (at most depth()).
  int stored() const { return stored_; }
  /// The differences the last extrapolate() used (stored() less those left out).
  int used() const { return used_; }

 private:
  MatrixXd dF_;  // (d × depth) ΔF, a ring: column (head_ − 1 − j) mod depth is the j-th newest
  MatrixXd dG_;            // (d × depth) ΔG, the same columns
  MatrixXd Q_;             // (d × depth) orthonormal columns of the kept differences of ΔF
  MatrixXd R_;             // (depth × depth) upper triangular: kept ΔF = Q R
  VectorXd f_;             // (d) residual f_k of the last update
  VectorXd g_;             // (d) image g_k of the last update
  VectorXd h_;             // (depth) Qᵀ f_k, then γ
  std::vector<int> slot_;  // (depth) the ring column of each kept difference
  int depth_ = 0, head_ = 0, stored_ = 0, used_ = 0;
  bool has_last_ = false;
  double drop_ = kDefaultDropTolerance;
};

}  // namespace ukdyn

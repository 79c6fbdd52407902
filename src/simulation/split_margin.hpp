// SPDX-License-Identifier: BSD-3-Clause
// The largest margin by which a split of the holding forces of several sticking contacts lies
// inside every friction cone (docs/friction.md, "Several contacts"): the exact test of whether
// a body on several contacts can still be held, whose sign the breakaway's bisection reads.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "ukdyn/core/types.hpp"

namespace ukdyn::detail {

/// One sticking contact's forces as affine functions of the split's free coordinates y (nz, in
/// force units): its holding force f = f0 + F y (d components in an orthonormal basis of the
/// tangent plane, `basis` (rows × d) mapping them to the holding force of stick_margin), its
/// normal force N = N0 + g·y, and its static coefficient mu.
struct SplitCone {
  Eigen::MatrixXd F;      // (d × nz)
  Eigen::VectorXd g;      // (nz)
  Eigen::VectorXd f0;     // (d)
  Eigen::MatrixXd basis;  // (n × d on the coordinate path; d × d at a contact point: I)
  double N0 = 0.0, mu = 0.0;
};

/// The margin, relative to the forces' scale, above which a split holds (max_split_margin).
inline constexpr double kSplitTolerance = 1e-12;

/// s* = max over y (|y| <= 1e3 scale) and s <= scale of s subject to, for every cone,
/// |f0 + F y| <= mu (N0 + g·y) − s and N0 + g·y >= s: the largest margin by which some split lies
/// inside every cone (s* >= 0: one holds them all; s* < 0: none does), relative to `scale` (> 0,
/// the forces' size), and its maximizer y into *y (nz). Solved by a barrier method (the cones'
/// log-determinant barriers, Newton steps, the barrier's weight raised tenfold to 1e15) to
/// about 1e-14 of the scale, in any units (the data are divided by the scale first) — or until
/// the sign of s* + kSplitTolerance is certain (a lower bound > −kSplitTolerance is returned
/// then, or an s whose gap bound puts s* below it). Returns s / scale; NaN when Newton fails. Cost:
/// about 200 Newton steps of O(nz³ + Σ d nz²); allocates.
double max_split_margin(const std::vector<SplitCone>& cones, Index nz, double scale,
                        Eigen::VectorXd* y);

}  // namespace ukdyn::detail

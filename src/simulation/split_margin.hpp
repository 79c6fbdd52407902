// SPDX-License-Identifier: BSD-3-Clause
// The largest margin by which a split of the holding forces of several sticking contacts lies
// inside every friction cone (docs/friction.md, "Several contacts"): the exact test of whether
// a body on several contacts can still be held, whose sign the breakaway's bisection reads.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <vector>

#include "ukdyn/core/system.hpp"
#include "ukdyn/core/types.hpp"
#include "ukdyn/dynamics/workspace.hpp"

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

/// The barrier method's scratch for max_split_margin (p = nz + 1, d the largest tangent count),
/// sized at its first call on a split space of that size and reused: no allocation after.
struct SplitBarrier {
  Eigen::VectorXd f0s, N0s;                 // (Σ d, cones) the cones' data over the scale
  Eigen::VectorXd z, G, step, alpha, grad;  // (p) the point (y, s), gradient, Newton step
  Eigen::VectorXd Fy, b, b_sum;             // (d) a cone's F y, and f0 + F y twice (barrier)
  Eigen::MatrixXd H, FtF;                   // (p × p, nz × nz) the Hessian, 2 Fᵀ F
  Eigen::LDLT<Eigen::MatrixXd> ldlt;        // (p) the Hessian's factorization
};

/// The split space of several sticking contacts of a system at an evaluation: their cones on
/// the coordinates ỹ (nz) of the change of their forces (orthonormal: |ỹ| is the change of
/// the forces (f_i, N_i) in force units), the map from ỹ to the change of the active rows'
/// multipliers, and the forces' scale.
struct SplitSpace {
  std::vector<SplitCone> cones;  // (sticking contacts, in their order)
  Eigen::MatrixXd null;          // (m_a × nz) the change of Λ on the active rows per ỹ
  std::vector<Index> row_of;     // (m_a) the active rows' indices in Λ
  Eigen::MatrixXd rows;          // (scratch: the active rows of A, then the forces' map)
  Index nz = 0;
  double scale = 0.0;    // the largest mu_s N_i and |f_i| at Λ
  SplitBarrier barrier;  // (max_split_margin's scratch)
};

/// The split space of the sticking contacts `stuck` (indices into sys.friction_contacts()) at
/// the evaluation ws made at (q, qd, t), with multipliers Λ (m, λ + λ_nonideal): Λ + Z y leaves
/// the motion unchanged (Z the left null space of the active rows of A), each f_i and N_i is
/// linear in y (N_i from the normal constraint's reaction, f_i the stick multipliers × κ at a
/// contact point, the rest of the reaction on the coordinate path), the y that change the
/// normal force of a contact of `fixed` (closed, sliding: its friction is μ N of it) are left
/// out, and y is taken in the forces' orthonormal coordinates. False when no y exists, or an
/// N_i is not linear in Λ (a coordinate-path normal constraint of several rows). N_i is signed
/// along Λ at the evaluation, or with `push` along a unilateral contact's push (the run's stick
/// decisions: a unilateral contact only pushes; the minimum-norm Λ's sign depends on the units).
/// Cost: an SVD of the active rows (m_a × n) and one of the forces' map; allocates.
bool split_space(const System& sys, Workspace& ws, const Eigen::VectorXd& Lambda,
                 const std::vector<std::size_t>& stuck, const std::vector<std::size_t>& fixed,
                 const Eigen::Ref<const Eigen::VectorXd>& q,
                 const Eigen::Ref<const Eigen::VectorXd>& qd, double t, SplitSpace& out,
                 bool push = false);

/// The margin, relative to the forces' scale, above which a split holds (max_split_margin).
inline constexpr double kSplitTolerance = 1e-12;

/// s* = max over y (|y| <= 1e3 scale) and s <= scale of s subject to, for every cone,
/// |f0 + F y| <= mu (N0 + g·y) − s and N0 + g·y >= s: the largest margin by which some split lies
/// inside every cone (s* >= 0: one holds them all; s* < 0: none does), relative to
/// `space.scale` (> 0, the forces' size), on the cones of `space` (nz coordinates), and its
/// maximizer y into *y (nz). Solved by a barrier method (the cones' log-determinant barriers,
/// Newton steps, the barrier's weight raised tenfold to 1e15) to about 1e-14 of the scale, in
/// any units (the data are divided by the scale first) — or until the sign of s* +
/// kSplitTolerance is certain (a lower bound > −kSplitTolerance is returned then, or an s whose
/// gap bound puts s* below it). With `sign_only` the sign is all that is sought (y is then any
/// point that decided it): every Newton iterate is a feasible point, so the first one with
/// s > −kSplitTolerance decides that a split holds; each weight is centred only to a Newton
/// decrement λ <= 1/9, where the gap bound 2 θ / τ still holds (s* − s <= (θ + (β + √θ) β /
/// (1 − β)) / τ for λ <= β < 1: the path-following bound, Nesterov's Introductory Lectures on
/// Convex Optimization, §4.2),
/// and the weight is raised a hundredfold (the same last weight, 1e16). The same decisions (to
/// the roundoff of s* at −kSplitTolerance), in about 2.5 times fewer Newton steps. Returns
/// s / scale; NaN when Newton fails. Cost: about 140 Newton steps (sign_only: 50 to 65) of
/// O(nz³ + Σ d nz²); no allocation once space.barrier is sized. With `optimum` (not with
/// sign_only) the sign does not end the search: s* and its maximizer to the gap's bound, 1e-14
/// of the scale (the numbers of the split of largest margin, for a note; about 140 Newton steps).
double max_split_margin(SplitSpace& space, Eigen::VectorXd* y, bool sign_only = false,
                        bool optimum = false);

}  // namespace ukdyn::detail

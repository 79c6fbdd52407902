// SPDX-License-Identifier: BSD-3-Clause
// Step-size collapse: when an adaptive method gives up, the likely cause — a singular
// configuration (the constraints lose rank), stiffness, or neither — and what to try.
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "simulation/integrator.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn::detail {

std::string format_short(double v) { return format_number(v, 3); }

namespace {
// the fall of the gap sigma_r / sigma_1 since the segment's start that says the constraints
// are about to lose rank (with the gap below kSingularMargin)
constexpr double kGapFall = 1e2;

// rank of A and the gap sigma_r / sigma_1 of W = L⁻¹ Aᵀ (r = r_ref, the rank to compare with;
// NaN with the sparse engine or without constraints) at state x (2n + 1) and t. Cost O(n m²).
struct ConstraintRank {
  bool valid = false;  // M and the state were fine, so rank and gap mean something
  Index rank = 0, rows = 0;
  double gap = std::numeric_limits<double>::quiet_NaN();
};
ConstraintRank constraint_rank(const System& sys, Workspace& ws, const std::vector<double>& x,
                               double t, Index r_ref) {
  const Index n = sys.coordinate_count();
  const Eigen::Map<const VectorXd> q(x.data(), n), qd(x.data() + n, n);  // views of x
  ConstraintRank c;
  const Status s = forward_dynamics(sys, ws, q, qd, t);
  if (s == Status::kNonFiniteInput || s == Status::kMassNotSymmetric ||
      s == Status::kMassNotPositiveDefinite) {
    return c;
  }
  c.valid = true;
  c.rank = ws.rank;
  c.rows = ws.active_rows;
  if (ws.is_sparse() || ws.active_rows == 0 || r_ref <= 0) return c;
  // Wᵀ = F⁻¹ Aᵀ (M = F Fᵀ): its singular values are those of B = A M^{-1/2}
  MatrixXd W = ws.A.transpose();
  ws.decomposition.solve_factor(W);
  const VectorXd sv = Eigen::JacobiSVD<MatrixXd>(W).singularValues();
  if (sv.size() > 0 && sv[0] > 0) c.gap = sv[std::min(r_ref, Index(sv.size())) - 1] / sv[0];
  return c;
}

}  // namespace

// the adaptive method gave up (explicit methods say so; CVODE by its flags)
bool step_collapsed(const SegmentResult& r) {
  if (r.collapsed) return true;
  for (const char* flag : {"CV_TOO_MUCH_WORK", "CV_ERR_FAILURE", "CV_CONV_FAILURE"}) {
    if (r.message.find(flag) != std::string::npos) return true;
  }
  return false;
}

// The likely cause of a collapsed step size — a singular configuration (the constraints lose
// rank), stiffness (the step held at dopri5's stability bound, many rejections), or neither
// (a jump in the forces, tolerances below the noise) — and what to try. x is the state where
// the method gave up (r.t_reached), x0 the one where it started (t0).
std::string diagnose_collapse(const System& sys, Workspace& ws, const SimulationOptions& o,
                              Integrator method, const SegmentResult& r,
                              const std::vector<double>& x, const std::vector<double>& x0,
                              double t0, const RunStatistics& stats, bool step_limit) {
  const long steps = stats.steps, rejected = stats.rejected_steps;
  const double rejected_share =
      steps + rejected > 0 ? double(rejected) / double(steps + rejected) : 0.0;
  // (times in the run's unit: s in SI units)
  const std::string tu = " " + o.units.time;
  const std::string where = "at t = " + format_short(r.t_reached) + tu;
  // a singular configuration: the rank drops, or the gap of the rank-th singular value closes
  if (sys.constraint_count() > 0) {
    const ConstraintRank start = constraint_rank(sys, ws, x0, t0, -1);
    const ConstraintRank from = constraint_rank(sys, ws, x0, t0, start.rank);
    const ConstraintRank now = constraint_rank(sys, ws, x, r.t_reached, start.rank);
    const bool lost = start.valid && now.valid && now.rank < start.rank;
    // (closing: within the neighbourhood where the integrators treat the pose as singular,
    // kSingularMargin, after a fall by two orders since t0; the bound was 1e-6, and a collapse
    // at a dead centre, 1e-4 from the pose, was blamed on nothing)
    const bool closing = now.gap < kSingularMargin && !(from.gap < kGapFall * now.gap);
    if (lost || closing) {
      return "Likely cause: a singular configuration " + where + ": the constraints " +
             (lost ? "lost rank (rank of A " + format_number(now.rank) + " of " +
                         format_number(now.rows) + " active rows, " + format_number(start.rank) +
                         " at t = " + format_short(t0) + tu + ")"
                   : "are about to lose rank (sigma_" + format_number(start.rank) +
                         " / sigma_1 = " + format_short(now.gap) + ", " + format_short(from.gap) +
                         " at t = " + format_short(t0) + tu + ")") +
             ", so the constraint forces grow without bound (a dead centre, a stretched or "
             "folded linkage, a branch point). Try: check the geometry and the initial state "
             "(ukdyn check), start away from that position, or pass through it with a fixed step "
             "(integrator: rk4, step: 1e-4)";
    }
  }
  // stiffness: the step held near dopri5's stability bound, or many rejections
  const bool explicit_method = method != Integrator::kBDF;
  if (explicit_method &&
      (r.stiffness > 0.8 * StiffnessTest::kStiffBound || rejected_share > 0.25)) {
    std::string text = "Likely cause: stiffness " + where + " (";
    if (r.stiffness > 0)
      text += "h·rho up to " + format_short(r.stiffness) + " in the last steps, ";
    text += format_short(100.0 * rejected_share) + "% of the steps rejected, last step " +
            format_short(r.last_step) + tu +
            "): the step size is held by stability, not accuracy (fast "
            "modes: stiff springs, regularized friction near rest, large damping). Try: "
            "integrator: bdf (--integrator bdf)";
    if (method == Integrator::kDopri5 && !o.stiff_switch) {
      text += ", or leave stiff_switch on (dopri5 then switches to BDF by itself)";
    }
    return text;
  }
  if (step_limit) return "";
  return "The step size collapsed " + where + " (" + format_number(rejected) + " of " +
         format_number(steps + rejected) +
         " steps rejected) with no sign of stiffness or of a singular configuration. Likely "
         "causes: the forces jump (give the time of the jump as a breakpoint), or the "
         "tolerances are below the roundoff of the accelerations. Try: breakpoints, or looser "
         "tolerances (--rtol 1e-7 --atol 1e-9)" +
         std::string(explicit_method ? ", or integrator: bdf" : "");
}

}  // namespace ukdyn::detail

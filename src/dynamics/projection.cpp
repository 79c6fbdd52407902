// SPDX-License-Identifier: BSD-3-Clause
// Constraint violations and projection onto the constraints (drift control): the correction of
// least M-norm, dq = −L⁻ᵀ W⁺ phi, through the same decomposition as the dynamics.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <cstdio>
#include <cstdlib>
#include "dynamics/engine.hpp"
#include "dynamics/internal.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/projection.hpp"

namespace ukdyn {

namespace {
// constraint k takes part in a projection
bool selected(const ProjectionOptions& o, Index k) {
  return o.mask.empty() || o.mask[std::size_t(k)] != 0;
}

void require_tolerance(const ProjectionOptions& o, const char* who) {
  if (!(o.tolerance > 0.0) || o.max_iterations < 0) {
    throw std::invalid_argument(std::string(who) +
                                ": ProjectionOptions need tolerance > 0 and max_iterations >= 0");
  }
}

// Tier 1: the sizes; then the inputs, as forward_dynamics checks them: a non-finite t, q (or
// q') is recorded in the workspace as kNonFiniteInput naming the coordinate (describe_status,
// throw_if_failed) and returned, so that a NaN state is never reported converged.
Status check_inputs(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                    const Eigen::Ref<const VectorXd>* qd, double t, const char* who) {
  detail::require_state_size(sys, q, qd, who);
  if (!std::isfinite(t)) return detail::fail(ws, Status::kNonFiniteInput, "t", -1, t);
  if (const Index i = detail::first_non_finite(q); i >= 0) {
    return detail::fail(ws, Status::kNonFiniteInput, "q", i, t);
  }
  if (qd) {
    if (const Index i = detail::first_non_finite(*qd); i >= 0) {
      return detail::fail(ws, Status::kNonFiniteInput, "q_dot", i, t);
    }
  }
  return Status::kOk;
}

// a projection that stopped on a failed evaluation: not converged, violation NaN (unknown)
ProjectionResult failed(ProjectionResult res, Status s = Status::kOk) {
  if (s != Status::kOk) res.status = s;
  res.converged = false;
  res.violation = std::numeric_limits<double>::quiet_NaN();
  return res;
}

// which rows a projection works on
enum class Level { kPosition, kVelocity };

// constraint k takes part in a projection of this level at t
bool takes_part(const System& sys, const Workspace& ws, const ProjectionOptions& o, Index k,
                double t, Level level) {
  const ConstraintKind kind = sys.constraint(k).kind();
  return selected(o, k) && detail::is_active(sys, ws, k, t) &&
         (kind == ConstraintKind::kHolonomic ||
          (level == Level::kVelocity && kind == ConstraintKind::kNonholonomic));
}

// e = −violation on the rows of the constraints that take part (zero elsewhere); returns the
// largest |violation|, or −1 when no row takes part
double measure_violation(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                         const Eigen::Ref<const VectorXd>& qd, double t, const ProjectionOptions& o,
                         Level level) {
  double worst = -1.0;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const Index r0 = sys.row_offset(k), rows = sys.constraint(k).rows();
    auto ek = ws.e.segment(r0, rows);
    if (!takes_part(sys, ws, o, k, t, level)) {
      ek.setZero();
      continue;
    }
    auto pk = ws.phi.segment(r0, rows);
    auto vk = ws.phi_dot.segment(r0, rows);
    sys.constraint(k).model().violation(q, qd, t, ws.scratch[std::size_t(k)].get(), pk, vk);
    if (level == Level::kPosition) {
      ek = -pk;
    } else {
      ek = -vk;
    }
    // (a NaN row must not vanish in the max: it is reported, see check_violation)
    const double row = ek.cwiseAbs().maxCoeff();
    if (!std::isfinite(row)) {
      detail::fail(ws, Status::kNonFiniteInput, level == Level::kPosition ? "phi" : "phi_dot", k,
                   t);
      return std::numeric_limits<double>::quiet_NaN();
    }
    worst = std::max(worst, row);
  }
  return worst;
}

// A on the rows of the constraints that take part: dphi/dq (holonomic) or dpsi/dq'
// (nonholonomic), zero elsewhere; only needed when a correction is
void assemble_jacobian(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                       const Eigen::Ref<const VectorXd>& qd, double t, const ProjectionOptions& o,
                       Level level) {
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (!takes_part(sys, ws, o, k, t, level)) {
      detail::zero_constraint_rows(sys, ws, k);
      continue;
    }
    // (a non-finite A shows up as a non-finite correction, as with the dense engine)
    detail::write_constraint_rows(sys, ws, k, q, qd, t, /*check=*/false);
  }
}

// Whether a projection is done at violation `worst`: within the tolerance, or stalled at the
// roundoff floor of its rows — within kFloor · tolerance, where kStalled corrections in a row
// did not halve the smallest violation seen (near a singular configuration or with redundant
// rows the floor can sit just above a tolerance of 1e-12: "1.02e-12 after 20 iterations")
struct Settling {
  static constexpr double kFloor = 100.0;
  static constexpr int kStalled = 3;
  double best = std::numeric_limits<double>::infinity();
  int stalled = 0;
  bool done(double worst, double tolerance) {
    if (worst <= tolerance) return true;
    if (worst <= kFloor * tolerance && worst > 0.5 * best) {
      if (++stalled >= kStalled) return true;
    } else {
      stalled = 0;
    }
    best = std::min(best, worst);
    return false;
  }
};

// x += L⁻ᵀ W⁺ e with the decomposition of the assembled A
template <class Vector>
void correct(Workspace& ws, Vector&& x) {
  ws.engine->decompose_constraints(ws);
  ws.engine->solve_ideal(ws, ws.e, ws.dqdd, ws.tmp_n, ws.lambda_tmp);
  x += ws.dqdd;
}

// M(q) = L Lᵀ (completed when M is singular) for a projection at (q, t)
Status factorize_mass(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                      double t) {
  Status s = detail::evaluate_mass(sys, ws, q, t);
  if (s == Status::kOk && ws.mass_singular) {
    s = detail::complete_singular_mass(ws, t, /*forces=*/false, /*regularize=*/true);
  }
  return s;
}

// dx −= L⁻ᵀ W⁺ A dx over the rows of the assembled A (its other rows are zero)
void remove_normal(Workspace& ws, Eigen::Ref<VectorXd> dx) {
  ws.engine->multiply_A(ws, dx, ws.e);
  ws.e = -ws.e;
  correct(ws, dx);
}
}  // namespace

void evaluate_violations(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                         const Eigen::Ref<const VectorXd>& qd, double t) {
  detail::require_same_system(sys, ws, "ukdyn::evaluate_violations");
  detail::require_state_size(sys, q, &qd, "ukdyn::evaluate_violations");
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const Constraint& c = sys.constraint(k);
    auto pk = ws.phi.segment(sys.row_offset(k), c.rows());
    auto vk = ws.phi_dot.segment(sys.row_offset(k), c.rows());
    if (!detail::is_active(sys, ws, k, t)) {
      pk.setZero();
      vk.setZero();
      continue;
    }
    c.model().violation(q, qd, t, ws.scratch[std::size_t(k)].get(), pk, vk);
  }
}

double position_violation(const System& sys, const Workspace& ws, Index k) {
  detail::require_same_system(sys, ws, "ukdyn::position_violation");
  return ws.phi.segment(sys.row_offset(k), sys.constraint(k).rows()).cwiseAbs().maxCoeff();
}

double velocity_violation(const System& sys, const Workspace& ws, Index k) {
  detail::require_same_system(sys, ws, "ukdyn::velocity_violation");
  return ws.phi_dot.segment(sys.row_offset(k), sys.constraint(k).rows()).cwiseAbs().maxCoeff();
}

Violations measure_violations(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t,
                              const ProjectionOptions& options) {
  detail::require_same_system(sys, ws, "ukdyn::measure_violations");
  require_tolerance(options, "ukdyn::measure_violations");
  detail::require_state_size(sys, q, &qd, "ukdyn::measure_violations");
  Violations v;
  v.finite =
      std::isfinite(t) && detail::first_non_finite(q) < 0 && detail::first_non_finite(qd) < 0;
  if (!v.finite) return v;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const bool position = takes_part(sys, ws, options, k, t, Level::kPosition);
    if (!position && !takes_part(sys, ws, options, k, t, Level::kVelocity)) continue;
    const Index r0 = sys.row_offset(k), rows = sys.constraint(k).rows();
    auto pk = ws.phi.segment(r0, rows);
    auto vk = ws.phi_dot.segment(r0, rows);
    sys.constraint(k).model().violation(q, qd, t, ws.scratch[std::size_t(k)].get(), pk, vk);
    // (a NaN must not vanish in the max)
    const double p = position ? pk.cwiseAbs().maxCoeff() : -1.0, d = vk.cwiseAbs().maxCoeff();
    if (!std::isfinite(p) || !std::isfinite(d)) {
      v.finite = false;
      return v;
    }
    v.position = std::max(v.position, p);
    v.velocity = std::max(v.velocity, d);
  }
  return v;
}

ProjectionResult project_positions(const System& sys, Workspace& ws, VectorXd& q, double t,
                                   const ProjectionOptions& options) {
  detail::require_same_system(sys, ws, "ukdyn::project_positions");
  require_tolerance(options, "ukdyn::project_positions");
  ProjectionResult res;
  res.status = check_inputs(sys, ws, q, nullptr, t, "ukdyn::project_positions");
  if (res.status != Status::kOk) return failed(res);
  Settling settling;
  for (;;) {
    // phi(q)
    const double worst = measure_violation(sys, ws, q, ws.zero_n, t, options, Level::kPosition);
    if (std::isnan(worst)) return failed(res, ws.status);
    res.violation = std::max(worst, 0.0);
    if (settling.done(worst, options.tolerance)) {
      res.converged = true;
      return res;
    }
    if (res.iterations == options.max_iterations) return res;
    // A = dphi/dq, M(q) = L Lᵀ;  q += −L⁻ᵀ W⁺ phi
    assemble_jacobian(sys, ws, q, ws.zero_n, t, options, Level::kPosition);
    res.status = factorize_mass(sys, ws, q, t);
    if (res.status != Status::kOk) return res;
    correct(ws, q);
    ++res.iterations;
    if (const Index i = detail::first_non_finite(q); i >= 0) {
      detail::fail(ws, Status::kNonFiniteResult, "q", i, t);
      return failed(res, Status::kNonFiniteResult);
    }
  }
}

ProjectionResult project_velocities(const System& sys, Workspace& ws,
                                    const Eigen::Ref<const VectorXd>& q, VectorXd& qd, double t,
                                    const ProjectionOptions& options) {
  detail::require_same_system(sys, ws, "ukdyn::project_velocities");
  require_tolerance(options, "ukdyn::project_velocities");
  ProjectionResult res;
  const Eigen::Ref<const VectorXd> qd_in = qd;  // a view, for the checks
  res.status = check_inputs(sys, ws, q, &qd_in, t, "ukdyn::project_velocities");
  if (res.status != Status::kOk) return failed(res);
  Settling settling;
  bool factorized = false;
  for (;;) {
    // phi'(q, q')
    const double worst = measure_violation(sys, ws, q, qd, t, options, Level::kVelocity);
    if (std::isnan(worst)) return failed(res, ws.status);
    res.violation = std::max(worst, 0.0);
    if (settling.done(worst, options.tolerance)) {
      res.converged = true;
      return res;
    }
    if (res.iterations == options.max_iterations) return res;
    // A, and M(q) = L Lᵀ once (q is fixed);  q' += −L⁻ᵀ W⁺ phi'
    assemble_jacobian(sys, ws, q, qd, t, options, Level::kVelocity);
    if (!factorized) {
      res.status = factorize_mass(sys, ws, q, t);
      if (res.status != Status::kOk) return res;
      factorized = true;
    }
    correct(ws, qd);
    ++res.iterations;
    if (const Index i = detail::first_non_finite(qd); i >= 0) {
      detail::fail(ws, Status::kNonFiniteResult, "q_dot", i, t);
      return failed(res, Status::kNonFiniteResult);
    }
  }
}

Status remove_normal_components(const System& sys, Workspace& ws,
                                const Eigen::Ref<const VectorXd>& q,
                                const Eigen::Ref<const VectorXd>& qd, double t,
                                const ProjectionOptions& options, Eigen::Ref<VectorXd> dq,
                                Eigen::Ref<VectorXd> dqd) {
  detail::require_same_system(sys, ws, "ukdyn::remove_normal_components");
  const Index n = sys.coordinate_count();
  if (q.size() != n || qd.size() != n || dq.size() != n || dqd.size() != n) {
    throw std::invalid_argument("ukdyn::remove_normal_components: q, q', dq and dq' need " +
                                format_number(n) + " entries");
  }
  bool holonomic = false, nonholonomic = false;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (!takes_part(sys, ws, options, k, t, Level::kVelocity)) continue;
    (sys.constraint(k).kind() == ConstraintKind::kHolonomic ? holonomic : nonholonomic) = true;
  }
  if (!holonomic && !nonholonomic) return Status::kOk;
  if (const Status s = factorize_mass(sys, ws, q, t); s != Status::kOk) return s;
  // velocity level (the rows of both kinds), then the position level (holonomic rows only)
  assemble_jacobian(sys, ws, q, qd, t, options, Level::kVelocity);
  remove_normal(ws, dqd);
  if (!holonomic) return Status::kOk;
  if (nonholonomic) assemble_jacobian(sys, ws, q, ws.zero_n, t, options, Level::kPosition);
  remove_normal(ws, dq);
  return Status::kOk;
}

}  // namespace ukdyn

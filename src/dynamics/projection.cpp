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
#include "dynamics/run_scales.hpp"
#include "linalg/safe_norm.hpp"
#include "linalg/scale_class.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/forward.hpp"
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

// a row of a constraint whose ‖a_i‖ is below this share of the constraint's largest takes the
// largest as its scale (set_run_scales)
constexpr double kRowFloor = 1e-3;

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

// max(1, class(‖x‖∞) / reference) (1 without a reference; reference the class of the run's
// length ℓ, detail::scale_class: both 10 · 1000^k): the state's share of a violation's scale, so
// that the tolerance follows the roundoff floor of a state that has grown out of the class of its
// length since the scales were set (a body falling far from where it started); a comparison
// only while the state stays in that class
double state_factor(const Eigen::Ref<const VectorXd>& x, double reference) {
  if (!(reference > 0.0) || x.size() == 0) return 1.0;
  const double big = x.cwiseAbs().maxCoeff();
  if (!(big >= detail::kScaleClassHalfStep * reference)) return 1.0;
  return std::max(1.0, detail::scale_class(big) / reference);
}

// the violation of a projection: the largest |row| in the constraints' own units (reported) and
// the largest |row| / its scale over the tolerance's factor of the state (compared with the
// tolerance: ws.phi_scale, see Workspace)
struct Worst {
  double raw = -1.0;       // −1 when no row takes part; NaN when a row is not finite
  double relative = -1.0;  // max_i |row_i| / (scale_i · state factor)
};

// e = −violation on the rows of the constraints that take part (zero elsewhere)
Worst measure_violation(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                        const Eigen::Ref<const VectorXd>& qd, double t, const ProjectionOptions& o,
                        Level level) {
  Worst worst;
  const bool position = level == Level::kPosition;
  const VectorXd& scale = position ? ws.phi_scale : ws.phi_dot_scale;
  // (velocities take no factor of the state: their scale v comes from the run's energy, and
  // speeds that grow without bound as a driven mechanism locks up must leave the velocity
  // projection failing, for find_constraint_conflict to name the lock-up; cli.run_lockup)
  const double factor = position ? state_factor(q, ws.length_scale) : 1.0;
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
    if (position) {
      ek = -pk;
    } else {
      ek = -vk;
    }
    // (a NaN row must not vanish in the max: it is reported, see check_violation)
    const double row = ek.cwiseAbs().maxCoeff();
    if (!std::isfinite(row)) {
      detail::fail(ws, Status::kNonFiniteInput, position ? "phi" : "phi_dot", k, t);
      worst.raw = worst.relative = std::numeric_limits<double>::quiet_NaN();
      return worst;
    }
    worst.raw = std::max(worst.raw, row);
    const auto sk = scale.segment(r0, rows);
    for (Index i = 0; i < rows; ++i) {
      worst.relative = std::max(worst.relative, std::abs(ek[i]) / (sk[i] * factor));
    }
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
  // the tolerances of each row (see Workspace::phi_scale)
  const double tol_q = options.tolerance * state_factor(q, ws.length_scale);
  const double tol_v = options.tolerance;  // (no factor of the state: see measure_violation)
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
    for (Index i = 0; i < rows && v.within_tolerance; ++i) {
      v.within_tolerance = (!position || std::abs(pk[i]) <= tol_q * ws.phi_scale[r0 + i]) &&
                           std::abs(vk[i]) <= tol_v * ws.phi_dot_scale[r0 + i];
    }
  }
  return v;
}

detail::RunLengthSpeed detail::run_length_speed(const System& sys, Workspace& ws,
                                                const Eigen::Ref<const VectorXd>& q,
                                                const Eigen::Ref<const VectorXd>& qd, double t,
                                                double duration, const std::vector<bool>* angles) {
  const Index n = sys.coordinate_count();
  RunLengthSpeed s;
  // (with angles: the largest |x_j| over the length coordinates, 0 when there is none)
  auto largest = [&](const auto& x) {
    if (angles == nullptr) return x.size() > 0 ? x.cwiseAbs().maxCoeff() : 0.0;
    double m = 0.0;
    for (Index j = 0; j < x.size(); ++j) {
      if (!(*angles)[std::size_t(j)]) m = std::max(m, std::abs(x[j]));
    }
    return m;
  };
  // ℓ = ‖q‖∞ (1 when every coordinate is 0: the model gives no length)
  double length = largest(q);
  s.has_length = length > 0.0 && std::isfinite(length);
  if (!s.has_length) length = 1.0;
  s.length = length;
  // E = max(T + |V|, ‖Q‖∞ ℓ) at the state: the energy the run's forces exchange over its
  // lengths (a pendulum released at rest at V = 0 has T + |V| = 0 but m g ℓ). The mass scale m =
  // 1ᵀ M 1 / n, a Rayleigh quotient of M (between its least and largest eigenvalue)
  double energy = 0.0, mass = 0.0;
  if (evaluate_unconstrained(sys, ws, q, qd, t) == Status::kOk) {
    const double T = ws.mass_singular ? 0.0 : detail::kinetic_energy(ws, qd);
    const double V = sys.potential_energy(q, t, ws.callables.get());
    const double Q = largest(ws.Q);
    energy = std::max(std::abs(T) + std::abs(V), Q * length);
    if (n > 0 && !ws.mass_singular) {
      ws.tmp_n.setOnes();
      double counted = double(n);
      if (angles != nullptr) {
        // (1_L: the length coordinates only)
        counted = 0.0;
        for (Index j = 0; j < n; ++j) {
          if ((*angles)[std::size_t(j)]) ws.tmp_n[j] = 0.0;
          counted += ws.tmp_n[j];
        }
      }
      if (counted > 0.0) mass = 2.0 * detail::kinetic_energy(ws, ws.tmp_n) / counted;
    }
  }
  ws.status = Status::kOk;
  if (!std::isfinite(energy)) energy = 0.0;
  s.energy = energy;
  // v = the largest of ‖q'‖∞, the speed √(2E/m) the run's energy gives its mass scale, and
  // ℓ / duration (a run from rest covers its lengths in its duration); ℓ per unit time when
  // none of them is > 0
  double speed = largest(qd);
  if (!std::isfinite(speed)) speed = 0.0;
  if (const double v = std::sqrt(2.0 * energy / mass); mass > 0.0 && std::isfinite(v)) {
    speed = std::max(speed, v);
  }
  if (duration > 0.0 && std::isfinite(duration)) speed = std::max(speed, length / duration);
  if (!(speed > 0.0)) speed = length;
  s.speed = speed;
  return s;
}

void set_run_scales(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                    const Eigen::Ref<const VectorXd>& qd, double t, double duration,
                    const std::vector<bool>& angle_coordinates) {
  detail::require_same_system(sys, ws, "ukdyn::set_run_scales");
  detail::require_state_size(sys, q, &qd, "ukdyn::set_run_scales");
  const Index n = sys.coordinate_count();
  if (!angle_coordinates.empty() && Index(angle_coordinates.size()) != n) {
    throw std::invalid_argument("ukdyn::set_run_scales: angle_coordinates has " +
                                std::to_string(angle_coordinates.size()) + " entries, expected " +
                                std::to_string(n) +
                                " (one per coordinate) or none (every coordinate a length); see "
                                "SimulationOptions::angle_coordinates");
  }
  ws.phi_scale.setConstant(10.0);  // (rows of acceleration constraints: never compared)
  ws.phi_dot_scale.setConstant(10.0);
  // ℓ, E and v (detail::run_length_speed)
  const detail::RunLengthSpeed run = detail::run_length_speed(sys, ws, q, qd, t, duration);
  const bool has_length = run.has_length;
  const double length = run.length, speed = run.speed;
  // the unit of the work channels is E's unit, the power of 1000 nearest to E / 10
  // (detail::energy_class_unit; 1 when there is none, and for a model in SI units), itself
  // rather than the power of two nearest to it: 1024 for a model in mm, g and ms weighed its
  // work channels 2.4 % apart from the same model's in SI units in the step-size control, which
  // then took other steps (268 against 267 for a robot arm with joint friction; u18 03)
  ws.energy_unit = detail::energy_class_unit(run.energy);
  // (every scale kept is a class, detail::scale_class: 10 for a model in SI units, which so
  // keeps the tolerances in its own units, and a change of units by powers of 1000 moves each
  // by exactly its factor)
  ws.length_scale = detail::scale_class(length);
  ws.speed_scale = detail::scale_class(speed);
  // the decade of v / ℓ, at most 1 (the user's atol is never loosened: a run faster than 10
  // per unit time keeps it), and 1 when the state gives no length (ℓ = 1 is then a unit's, and
  // v / ℓ would move with the lengths' unit)
  ws.rate_unit = has_length ? std::min(1.0, detail::rate_decade(speed / length)) : 1.0;
  // each column's own scale s_j (angle_coordinates): ℓ_q for a length, 1 for an angle, with ℓ_q
  // and v_q the lengths' own ℓ and v (run_length_speed over the
  // length coordinates: in the unit of length alone); without flags, or when no length
  // coordinate is nonzero, every column is a length's and the rows' scales are class(‖a_i‖ ℓ)
  // and class(‖a_i‖ v), bit for bit as before
  bool weighed = false;
  double lq = length, vq = speed;
  VectorXd s;  // (once per run)
  if (std::find(angle_coordinates.begin(), angle_coordinates.end(), true) !=
      angle_coordinates.end()) {
    const detail::RunLengthSpeed own =
        detail::run_length_speed(sys, ws, q, qd, t, duration, &angle_coordinates);
    weighed = own.has_length;
    lq = own.length;
    vq = own.speed;
  }
  if (weighed) {
    s.resize(n);
    for (Index j = 0; j < n; ++j) s[j] = angle_coordinates[std::size_t(j)] ? 1.0 : lq;
  }
  // ‖a_i ∘ s‖ (with flags) or ‖a_i‖
  auto row_norm = [&](const MatrixXd& Ak, Index i) {
    return weighed ? detail::safe_norm(Ak.row(i).cwiseProduct(s.transpose()).eval().data(), n)
                   : detail::safe_norm(Ak.row(i).eval().data(), n);
  };
  MatrixXd Ak;  // (once per run)
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const Constraint& c = sys.constraint(k);
    if (c.kind() == ConstraintKind::kAcceleration) continue;
    // ‖a_i‖ at (q, q', t), whether or not the constraint acts yet
    detail::write_constraint_rows(sys, ws, k, q, qd, t, /*check=*/false);
    Ak.resize(c.rows(), n);
    detail::copy_constraint_rows(sys, ws, k, Ak);
    double largest = 0.0;
    for (Index i = 0; i < c.rows(); ++i) {
      const double a = row_norm(Ak, i);
      if (std::isfinite(a)) largest = std::max(largest, a);
    }
    if (!(largest > 0.0)) largest = 1.0;
    for (Index i = 0; i < c.rows(); ++i) {
      double a = row_norm(Ak, i);
      // a row that vanishes here, or nearly — below kRowFloor of its constraint's largest (a
      // weld's rotation row about an axis its loop does not turn: ‖a_i‖ of roundoff, 1e-17) —
      // takes that largest (the unit when all vanish): its violation is the roundoff of terms of
      // its constraint's size, which a scale of its own ‖a_i‖ would ask a projection to go below
      if (!(a >= kRowFloor * largest) || !std::isfinite(a)) a = largest;
      if (weighed) {
        // class(‖a_i ∘ s‖) and class(‖a_i ∘ s‖ v_q / ℓ_q): a length's column times ℓ_q and
        // v_q, an angle's times 1 and v_q / ℓ_q
        ws.phi_scale[sys.row_offset(k) + i] = detail::scale_class(a);
        ws.phi_dot_scale[sys.row_offset(k) + i] = detail::scale_class(a * (vq / lq));
      } else {
        ws.phi_scale[sys.row_offset(k) + i] = detail::scale_class(a * length);
        ws.phi_dot_scale[sys.row_offset(k) + i] = detail::scale_class(a * speed);
      }
    }
  }
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
    const Worst worst = measure_violation(sys, ws, q, ws.zero_n, t, options, Level::kPosition);
    if (std::isnan(worst.raw)) return failed(res, ws.status);
    res.violation = std::max(worst.raw, 0.0);
    if (settling.done(worst.relative, options.tolerance)) {
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
    const Worst worst = measure_violation(sys, ws, q, qd, t, options, Level::kVelocity);
    if (std::isnan(worst.raw)) return failed(res, ws.status);
    res.violation = std::max(worst.raw, 0.0);
    if (settling.done(worst.relative, options.tolerance)) {
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

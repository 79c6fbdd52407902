// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/reduced_dynamics.cpp
/// Stage 2 of linearize(): the chart x = (q_Ip, q'_Iv) → (q, q') of the constraint manifold
/// (Newton on the dependent coordinates) and the reduced dynamics f(x) = (q'_Ip, q''_Iv) from
/// the fundamental equation (docs/linearize.md, "The reduction").
#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <sstream>
#include <string>

#include <Eigen/QR>

#include "analysis/internal.hpp"
#include "dynamics/run_scales.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"

namespace ukdyn::analysis {
namespace {
constexpr int kMaxNewton = 40;
// |Φ| (or |ψ|) left at convergence, relative to max(1, |z_D|): Newton on consistent rows ends
// at roundoff, some 1e-16
constexpr double kResidualTolerance = 1e-10;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// a coordinate below this fraction of its natural scale is at 0, or at its roundoff: it gives
// the model no length (it is stepped by its natural scale, not by its own size)
constexpr double kRoundoff = 1e-3;
}  // namespace

ReducedDynamics::ReducedDynamics(const System& sys, const Partition& p, const OperatingPoint& base,
                                 const LinearizeOptions& options)
    : sys_(sys),
      p_(p),
      base_(base),
      ws_(sys, dense_options(options.solver)),
      q_(base.q),
      qd_(base.qd) {
  hold_contact_mode(sys, ws_, base);  // (the base point's contact mode in every evaluation)
}

VectorXd ReducedDynamics::base_state() const {
  VectorXd x(state_size());
  Index k = 0;
  for (Index j : p_.ip) x(k++) = base_.q(j);
  for (Index j : p_.iv) x(k++) = base_.qd(j);
  return x;
}

double ReducedDynamics::model_change(Index j, double p) {
  // the base point's M (its lower triangle) and rows a_i of A, and D = diag(M)^(-1/2)
  const Index n = sys_.coordinate_count();
  if (base_M_.size() == 0) {
    evaluate_unconstrained(sys_, ws_, base_.q, base_.qd, base_.t);
    base_M_ = ws_.M;
    assemble_constraints(sys_, ws_, base_.q, base_.qd, base_.t);
    base_A_ = ws_.A;
    ws_.status = Status::kOk;
    D_.setZero(n);
    for (Index k = 0; k < n; ++k)
      if (base_M_(k, k) > 0 && std::isfinite(base_M_(k, k))) D_(k) = 1 / std::sqrt(base_M_(k, k));
    // each row's change is measured against its constraint's largest row ‖a_i D‖, or against
    // the largest of all where the constraint's rows (nearly) vanish here — a four-bar's row at
    // its fold, which would otherwise change by 100 % over any step
    row_size_.setZero(base_A_.rows());
    for (Index i = 0; i < base_A_.rows(); ++i)
      row_size_(i) = (base_A_.row(i).transpose().cwiseProduct(D_)).norm();
    const double largest = row_size_.size() > 0 ? row_size_.maxCoeff() : 0.0;
    for (Index c = 0; c < sys_.constraint_count(); ++c) {
      auto rows = row_size_.segment(sys_.row_offset(c), sys_.constraint(c).rows());
      const double own = rows.size() > 0 ? rows.maxCoeff() : 0.0;
      rows.setConstant(own >= 1e-3 * largest ? own : largest);
    }
  }
  q_ = base_.q;
  q_(j) += p;
  bool ok = false;
  try {  // (a callable that refuses a point far away: as a change too large)
    ok = evaluate_unconstrained(sys_, ws_, q_, base_.qd, base_.t) == Status::kOk &&
         assemble_constraints(sys_, ws_, q_, base_.qd, base_.t) == Status::kOk;
  } catch (const std::exception&) {
    ok = false;
  }
  ws_.status = Status::kOk;
  if (!ok || !ws_.M.allFinite() || !ws_.A.allFinite()) return kInfinity;
  // |ΔM_ab| D_a D_b (<= 1 at the base by Cauchy–Schwarz), ‖Δa_i D‖ / row_size_(i)
  double change = 0.0;
  for (Index b = 0; b < n; ++b)
    for (Index a = b; a < n; ++a)
      change = std::max(change, std::abs(ws_.M(a, b) - base_M_(a, b)) * D_(a) * D_(b));
  for (Index i = 0; i < base_A_.rows(); ++i) {
    const double size = row_size_(i);
    if (!(size > 0) || !std::isfinite(size)) continue;
    change = std::max(change,
                      ((ws_.A.row(i) - base_A_.row(i)).transpose().cwiseProduct(D_)).norm() / size);
  }
  return change;
}

double ReducedDynamics::natural_scale(Index j, double start) {
  // p* = the least step (by factors of 4) that changes the model by kChange, with the next two
  // shorter ones below it (a step near a multiple of 2π changes a periodic model little); the
  // natural scale is 10 p*: kChange / 10 of change per σ where the change is linear (a
  // Cartesian pendulum's x: σ = 0.1 L; an angle in a loop: 0.1 rad)
  constexpr double kChange = 1e-2, kFactor = 4.0;
  constexpr int kProbes = 40;
  double p = start;
  int k = 0;
  // (by 1024 while the change is below 1e-4 of the target: a cyclic coordinate, whose model
  // never changes, is known in a few probes; the downward search then finds the least step)
  // (M and A that do not change over 1e24 times the start: no scale of its own)
  const double top = 1e24 * start;
  double change = model_change(j, p);
  for (; k < kProbes && change < kChange; ++k) {
    p *= change < 1e-4 * kChange ? 1024.0 : kFactor;
    if (!(p <= top)) return kInfinity;
    change = model_change(j, p);
  }
  if (change < kChange) return kInfinity;
  // (each probe once: the next shorter two, moved along as p shrinks)
  double next = model_change(j, p / kFactor), after = model_change(j, p / (kFactor * kFactor));
  for (k = 0; k < kProbes && !(next < kChange && after < kChange); ++k) {
    p /= kFactor;
    next = after;
    after = model_change(j, p / (kFactor * kFactor));
  }
  return 10 * p;
}

VectorXd ReducedDynamics::state_scales() {
  const Index n = sys_.coordinate_count();
  const detail::RunLengthSpeed run =
      detail::run_length_speed(sys_, ws_, base_.q, base_.qd, base_.t, 0.0);
  // λ_j, the scale of the model's own change along each independent position (natural_scale)
  VectorXd lambda(n);
  for (Index j = 0; j < n; ++j) lambda(j) = natural_scale(j, run.length);
  // ℓ̃ = ‖q‖∞ without the coordinates at 0 or its roundoff (below 1e-3 λ_j: what an
  // equilibrium search leaves, 1e-14 rad, or a damped run 2.6e-9 rad), 1 (the unit, as at q =
  // 0) when every one is: a length made of roundoff gave steps of 1e-15 rad, below the chart's
  // own roundoff (and steps of 2.6e-10 rad an error of 3e-6)
  double length = 0.0;
  for (Index j = 0; j < n; ++j)
    if (lambda(j) == kInfinity || std::abs(base_.q(j)) >= kRoundoff * lambda(j))
      length = std::max(length, std::abs(base_.q(j)));
  if (!(length > 0) || !std::isfinite(length)) length = 1.0;
  // a position: its own magnitude, or the model's where it is below 1e-3 of that (a coordinate
  // at 0: a step of 1e-4 ℓ there left the projection's roundoff above the estimate) — ℓ̃, at
  // most λ_j (an angle at 0 beside lengths of 500 mm is not stepped by 50 rad); never above λ_j
  constexpr double kZero = 1e-3;
  VectorXd s(state_size());
  VectorXd sigma_q = VectorXd::Constant(n, length);
  model_scales_ = lambda.cwiseMin(length);
  Index k = 0;
  for (Index j : p_.ip) {
    const double model = model_scales_(j);
    sigma_q(j) =
        std::min(std::abs(base_.q(j)) >= kZero * model ? std::abs(base_.q(j)) : model, lambda(j));
    s(k++) = sigma_q(j);
  }
  // a velocity: its own magnitude, or the coordinate's scale at the run's rate v / ℓ̃
  rate_ = run.speed / length;
  for (Index j : p_.iv) {
    const double model = rate_ * sigma_q(j);
    s(k++) = std::abs(base_.qd(j)) >= kZero * model ? std::abs(base_.qd(j)) : model;
  }
  q_ = base_.q;
  return s;
}

VectorXd ReducedDynamics::model_state_scales() const {
  VectorXd s(state_size());
  Index k = 0;
  for (Index j : p_.ip) s(k++) = model_scales_(j);
  for (Index j : p_.iv) s(k++) = rate_ * model_scales_(j);
  return s;
}

bool ReducedDynamics::newton(bool velocity) {
  const auto& rows = velocity ? p_.velocity_rows : p_.holonomic_rows;
  const auto& dep = velocity ? p_.dv : p_.dp;
  VectorXd& z = velocity ? qd_ : q_;
  if (rows.empty() || dep.empty()) return true;
  const Index nr = Index(rows.size()), nd = Index(dep.size());
  MatrixXd J(nr, nd);
  VectorXd r(nr);
  for (int it = 0; it < kMaxNewton; ++it) {
    // r = Φ(q) (positions) or Φ' / ψ(q, q') (velocities); J = their columns D of A
    evaluate_violations(sys_, ws_, q_, qd_, base_.t);
    for (Index i = 0; i < nr; ++i)
      r(i) = velocity ? ws_.phi_dot(rows[std::size_t(i)]) : ws_.phi(rows[std::size_t(i)]);
    if (!r.allFinite()) break;
    assemble_constraints(sys_, ws_, q_, qd_, base_.t);
    for (Index i = 0; i < nr; ++i)
      for (Index j = 0; j < nd; ++j) J(i, j) = ws_.A(rows[std::size_t(i)], dep[std::size_t(j)]);
    // z_D ← z_D − J⁺ r (least squares: redundant rows are consistent on the manifold)
    const VectorXd dz = J.colPivHouseholderQr().solve(-r);
    if (!dz.allFinite()) break;
    double zmax = 1.0;
    for (Index j : dep) zmax = std::max(zmax, std::abs(z(j)));
    for (Index j = 0; j < nd; ++j) z(dep[std::size_t(j)]) += dz(j);
    if (dz.lpNorm<Eigen::Infinity>() > 1e-14 * zmax) continue;
    // converged; the residual must vanish too — it does not where the rank of the rows
    // changes near the base point (a singular configuration: more independent rows than
    // dependent coordinates)
    if (r.lpNorm<Eigen::Infinity>() <= kResidualTolerance * zmax) return true;
    std::ostringstream msg;
    msg << "the " << (velocity ? "velocity" : "holonomic") << " constraints cannot be met "
        << "with the chosen dependent coordinates near the point (residual " << r.norm()
        << "): their rank changes there — a singular configuration (docs/linearize.md)";
    why_ = msg.str();
    return false;
  }
  std::ostringstream msg;
  msg << "Newton on the " << (velocity ? "velocity constraints" : "holonomic constraints")
      << " did not converge in " << kMaxNewton << " steps (residual " << r.norm() << ")";
  why_ = msg.str();
  return false;
}

bool ReducedDynamics::complete(const Eigen::Ref<const VectorXd>& x) {
  // start from the base point with the independent entries of x
  q_ = base_.q;
  qd_ = base_.qd;
  Index k = 0;
  for (Index j : p_.ip) q_(j) = x(k++);
  for (Index j : p_.iv) qd_(j) = x(k++);
  // q_Dp from Φ(q, t) = 0, then q'_Dv from the velocity constraints at that q
  return newton(false) && newton(true);
}

bool ReducedDynamics::evaluate(const Eigen::Ref<const VectorXd>& x,
                               const std::vector<LinearOutput>& outputs, Eigen::Ref<VectorXd> F) {
  if (!complete(x)) return false;
  forward_dynamics(sys_, ws_, q_, qd_, base_.t);
  if (ws_.status != Status::kOk) {
    why_ = describe_status(sys_, ws_);
    return false;
  }
  // F = (q'_Ip, q''_Iv, outputs)
  Index k = 0;
  for (Index j : p_.ip) F(k++) = qd_(j);
  for (Index j : p_.iv) F(k++) = ws_.qdd(j);
  for (const auto& y : outputs)
    F(k++) = y.expression ? y.expression(q_, qd_, base_.t)
                          : (y.rate ? qd_(y.coordinate) : q_(y.coordinate));
  return true;
}

}  // namespace ukdyn::analysis

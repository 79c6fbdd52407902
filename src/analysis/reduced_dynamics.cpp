// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/reduced_dynamics.cpp
/// Stage 2 of linearize(): the chart x = (q_Ip, q'_Iv) → (q, q') of the constraint manifold
/// (Newton on the dependent coordinates) and the reduced dynamics f(x) = (q'_Ip, q''_Iv) from
/// the fundamental equation (docs/linearize.md, "The reduction").
#include <algorithm>
#include <cmath>
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

VectorXd ReducedDynamics::state_scales() {
  const detail::RunLengthSpeed run =
      detail::run_length_speed(sys_, ws_, base_.q, base_.qd, base_.t, 0.0);
  // its own magnitude; the model's scale for an entry below 1e-3 of that (a coordinate at 0, or
  // at the roundoff of 0: a step of 1e-4 ℓ there left the projection's roundoff above the
  // estimate)
  constexpr double kZero = 1e-3;
  const auto own = [](double x, double model) {
    return std::abs(x) >= kZero * model ? std::abs(x) : model;
  };
  VectorXd s(state_size());
  Index k = 0;
  for (Index j : p_.ip) s(k++) = own(base_.q(j), run.length);
  for (Index j : p_.iv)
    s(k++) = own(base_.qd(j), run.speed * own(base_.q(j), run.length) / run.length);
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

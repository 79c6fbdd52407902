// SPDX-License-Identifier: BSD-3-Clause
// The largest margin of a split of the holding forces inside every friction cone (a small
// second-order cone programme), by a barrier method. See split_margin.hpp.
#include "simulation/split_margin.hpp"

#include <Eigen/Cholesky>

#include <cmath>
#include <limits>

namespace ukdyn::detail {

namespace {

// (|y| <= kRadius scale: the barrier is bounded where the forces can grow without limit, a body
// squeezed between two walls; the cap s <= scale likewise)
constexpr double kRadius = 1e3;

// the barrier of the margin problem at z = (y, s) (scale units): its value's finiteness (false
// outside the domain), gradient and Hessian into G, H
bool barrier(const std::vector<SplitCone>& cones, const Eigen::VectorXd& f0s,
             const Eigen::VectorXd& N0s, const Eigen::VectorXd& z, Eigen::VectorXd& G,
             Eigen::MatrixXd& H, Eigen::VectorXd& alpha, Eigen::VectorXd& grad) {
  const Index p = z.size(), nz = p - 1;
  const auto y = z.head(nz);
  const double s = z[nz];
  G.setZero(p);
  H.setZero(p, p);
  // −log l for l = λ·z + l0 > 0 (λ in alpha)
  auto linear = [&](double l) {
    if (!(l > 0.0)) return false;
    G -= alpha / l;
    H.noalias() += alpha * alpha.transpose() / (l * l);
    return true;
  };
  Index at = 0;
  for (std::size_t i = 0; i < cones.size(); ++i) {
    const SplitCone& cone = cones[i];
    const Index d = cone.F.rows();
    const double N = N0s[Index(i)] + cone.g.dot(y);
    // N >= s
    alpha.head(nz) = cone.g;
    alpha[nz] = -1.0;
    if (!linear(N - s)) return false;
    // |b| <= a, a = mu N − s, b = f0 + F y: −log(a² − |b|²)
    alpha.head(nz) = cone.mu * cone.g;
    const double a = cone.mu * N - s;
    if (d == 0) {
      if (!linear(a)) return false;
      continue;
    }
    const auto b = f0s.segment(at, d) + cone.F * y;
    at += d;
    const double D = a * a - b.squaredNorm();
    if (!(a > 0.0) || !(D > 0.0)) return false;
    // ∇D = 2 a α − 2 Bᵀ b, ∇²D = 2 α αᵀ − 2 Bᵀ B (B = [F 0])
    grad = 2.0 * a * alpha;
    grad.head(nz).noalias() -= 2.0 * cone.F.transpose() * b;
    G -= grad / D;
    H.noalias() += grad * grad.transpose() / (D * D) - 2.0 * alpha * alpha.transpose() / D;
    H.topLeftCorner(nz, nz).noalias() += 2.0 * cone.F.transpose() * cone.F / D;
  }
  // s <= 1, |y| <= kRadius
  alpha.setZero();
  alpha[nz] = 1.0;
  if (!linear(1.0 - s)) return false;
  const double room = kRadius * kRadius - y.squaredNorm();
  if (!(room > 0.0)) return false;
  grad.setZero();
  grad.head(nz) = -2.0 * y;
  G -= grad / room;
  H.noalias() += grad * grad.transpose() / (room * room);
  H.topLeftCorner(nz, nz).diagonal().array() += 2.0 / room;
  return true;
}

}  // namespace

double max_split_margin(const std::vector<SplitCone>& cones, Index nz, double scale,
                        Eigen::VectorXd* y_out) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!(scale > 0.0) || cones.empty()) return nan;
  // the data in units of the scale; the start y = 0, s below every margin there
  Index rows = 0;
  for (const SplitCone& cone : cones) rows += cone.f0.size();
  Eigen::VectorXd f0s(rows), N0s(Index(cones.size()));
  double s0 = 0.0;
  for (Index i = 0, at = 0; const SplitCone& cone : cones) {
    const Index d = cone.f0.size();
    f0s.segment(at, d) = cone.f0 / scale;
    at += d;
    N0s[i] = cone.N0 / scale;
    s0 = std::min({s0, N0s[i], cone.mu * N0s[i] - f0s.segment(at - d, d).norm()});
    ++i;
  }
  const Index p = nz + 1;
  Eigen::VectorXd z = Eigen::VectorXd::Zero(p), G(p), step(p), alpha(p), grad(p);
  Eigen::MatrixXd H(p, p);
  z[nz] = s0 - 1.0;
  // the barrier's parameter (2 per cone, 1 per linear term): the gap s* − s on the central path
  // is at most it over the weight τ
  const double theta = 3.0 * double(cones.size()) + 2.0;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(p);
  for (double tau = 1.0; tau <= 1e16; tau *= 10.0) {
    double decrement = std::numeric_limits<double>::infinity();
    for (int newton = 0; newton < 60 && decrement > 1e-12; ++newton) {
      if (!barrier(cones, f0s, N0s, z, G, H, alpha, grad)) return nan;
      G[nz] -= tau;  // (the objective −τ s)
      ldlt.compute(H);
      if (ldlt.info() != Eigen::Success) return nan;
      step = -ldlt.solve(G);
      decrement = -G.dot(step);  // λ², in the Hessian's norm
      if (!(decrement >= 0.0)) return nan;
      // (damped Newton: a step of 1/(1 + λ) stays inside a self-concordant barrier's domain)
      const double lambda = std::sqrt(decrement);
      z += (lambda > 0.25 ? 1.0 / (1.0 + lambda) : 1.0) * step;
    }
    if (!barrier(cones, f0s, N0s, z, G, H, alpha, grad)) return nan;
    // decided: a split with a margin above −kSplitTolerance (s <= s*), or none within the gap's
    // bound
    const double s = z[nz], gap = 2.0 * theta / tau;
    if (s > -kSplitTolerance || s + gap < -kSplitTolerance || gap < 1e-14) break;
  }
  if (y_out) *y_out = z.head(nz) * scale;
  return z[nz];
}

}  // namespace ukdyn::detail

// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/equilibrium.cpp
/// Equilibria and steady motions: Gauss–Newton with a backtracking line search on the reduced
/// accelerations q''_Iv(x) of the chart of linearize() (docs/linearize.md, "Equilibria").
#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/QR>

#include "analysis/internal.hpp"
#include "ukdyn/analysis/linearize.hpp"

namespace ukdyn {
namespace {
constexpr const char* kEquilibriumWho = "find_equilibrium";
}  // namespace

Equilibrium find_equilibrium(const System& sys, const OperatingPoint& guess,
                             const EquilibriumOptions& o) {
  if (!(o.tolerance > 0) || o.max_iterations < 1)
    throw std::invalid_argument(std::string(kEquilibriumWho) +
                                ": EquilibriumOptions out of range (tolerance > 0, "
                                "max_iterations >= 1)");
  Workspace ws(sys, analysis::dense_options(o.linearize.solver));
  // the chart at the current point: a static search (unknowns not named) takes a new one after
  // every step, so that it can walk past the edge of the first chart (a pendulum released
  // horizontally, whose first chart has the height as its coordinate, hangs where that chart
  // is singular); named unknowns keep the chart of the guess
  OperatingPoint current = guess;
  std::unique_ptr<analysis::Partition> part;
  std::unique_ptr<analysis::ReducedDynamics> rd;
  std::vector<Index> unknown;  // entries of x
  Index sp = 0, sv = 0;
  auto chart_at = [&](const OperatingPoint& point) {
    rd.reset();
    part = std::make_unique<analysis::Partition>(
        analysis::choose_coordinates(sys, ws, point, o.linearize, kEquilibriumWho, false));
    rd = std::make_unique<analysis::ReducedDynamics>(sys, *part, point, o.linearize);
    sp = Index(part->ip.size());
    sv = Index(part->iv.size());
    unknown.clear();
    if (o.unknowns.empty()) {
      for (Index k = 0; k < sp; ++k) unknown.push_back(k);
      return;
    }
    // the unknowns: positions among I_p, rates among I_v
    for (const auto& name : o.unknowns) {
      bool rate = false;
      const Index j = analysis::coordinate_of(sys, name, rate, kEquilibriumWho);
      const auto& set = rate ? part->iv : part->ip;
      const auto it = std::find(set.begin(), set.end(), j);
      if (it == set.end())
        throw std::invalid_argument(std::string(kEquilibriumWho) + ": the unknown '" + name +
                                    "' is a dependent " + (rate ? "velocity" : "position") +
                                    " (the constraints fix it); name an independent one");
      unknown.push_back((rate ? sp : 0) + Index(it - set.begin()));
    }
  };
  chart_at(current);
  const Index nz = Index(unknown.size());

  // r(z) = q''_Iv at x = x₀ (the chart's base) with the unknowns replaced by z, each entry in
  // its coordinate's acceleration unit (accel, from the guess: the search and its stopping test
  // are then the same in any units; u20 09: absolute in the model's units, an equilibrium in
  // mm, g and ms stopped 1e-9 rad from where SI's did)
  VectorXd x, F;
  VectorXd accel = VectorXd::Ones(sys.coordinate_count());
  auto residual = [&](const Eigen::Ref<const VectorXd>& z, Eigen::Ref<VectorXd> r) {
    VectorXd xz = x;
    for (Index k = 0; k < nz; ++k) xz(unknown[std::size_t(k)]) = z(k);
    if (!rd->evaluate(xz, {}, F)) return false;
    r = F.tail(sv);
    for (Index k = 0; k < sv; ++k) r(k) /= accel(part->iv[std::size_t(k)]);
    return true;
  };
  VectorXd z(nz), r(sv), r_new(sv), z_new(nz), h(nz);
  VectorXd scale;  // the chart base's state scales (ReducedDynamics::state_scales)
  auto start_chart = [&] {
    x = rd->base_state();
    scale = rd->state_scales();
    F.resize(x.size());
    for (Index k = 0; k < nz; ++k) z(k) = x(unknown[std::size_t(k)]);
  };
  start_chart();
  if (!residual(z, r))
    throw EquilibriumError(std::string(kEquilibriumWho) +
                           ": the guess cannot be completed to a state on "
                           "the constraint manifold: " +
                           rd->why());
  // the guess, completed onto the manifold, is the first base point
  current = {rd->q(), rd->qd(), guess.t};
  if (o.unknowns.empty()) {
    chart_at(current);
    start_chart();
  }
  // the acceleration unit of each coordinate: its model scale (ReducedDynamics::model_scales)
  // at the guess's rate², (v / ℓ̃)²
  accel = rd->model_scales() * (rd->rate() * rd->rate());
  for (Index j = 0; j < accel.size(); ++j)
    if (!(accel(j) > 0) || !std::isfinite(accel(j))) accel(j) = 1.0;
  residual(z, r);
  const analysis::RiddersOptions ro{o.linearize.table_size, o.linearize.step_ratio, 2.0};
  int it = 0;
  std::string stuck;
  MatrixXd J, E;
  while (r.norm() > o.tolerance && stuck.empty()) {
    if (it == o.max_iterations) {
      stuck = "the iteration limit was reached";
      break;
    }
    ++it;
    // the Jacobian ∂r/∂z, then the Gauss–Newton step Δ = −J⁺ r
    for (Index k = 0; k < nz; ++k)
      h(k) = o.linearize.initial_step * std::max(scale(unknown[std::size_t(k)]), std::abs(z(k)));
    std::string why;
    if (!analysis::ridders_jacobian(residual, z, h, sv, ro, J, E, why)) {
      stuck = why + ": " + rd->why();
      break;
    }
    const VectorXd dz = -J.completeOrthogonalDecomposition().solve(r);
    // backtracking: halve the step until ‖r‖ decreases enough (Armijo, c = 1e-4)
    double alpha = 1.0;
    bool accepted = false;
    for (; alpha >= 1.0 / 1024 && !accepted; alpha /= 2) {
      z_new = z + alpha * dz;
      accepted = residual(z_new, r_new) && r_new.norm() <= (1 - 1e-4 * alpha) * r.norm();
    }
    if (!accepted) {
      stuck =
          "the line search found no decrease along the Newton direction (a minimum of "
          "‖q''‖ that is not zero, or a singular Jacobian)";
      break;
    }
    z = z_new;
    r = r_new;
    if (o.unknowns.empty() && r.norm() > o.tolerance) {
      // a new chart at the accepted point
      residual(z, r_new);
      current = {rd->q(), rd->qd(), guess.t};
      chart_at(current);
      start_chart();
      if (!residual(z, r)) {
        stuck = rd->why();
        break;
      }
    }
  }
  // the state at z, on the manifold
  VectorXd r_final(sv);
  residual(z, r_final);
  VectorXd r_model = r_final;  // (in the model's units)
  for (Index k = 0; k < sv; ++k) r_model(k) *= accel(part->iv[std::size_t(k)]);
  if (!stuck.empty()) {
    Index worst = 0;
    r_final.cwiseAbs().maxCoeff(&worst);
    std::ostringstream msg;
    msg << kEquilibriumWho << ": no equilibrium found from the guess after " << it
        << " Newton steps: " << stuck << "; the reduced accelerations have norm " << r_model.norm()
        << " (" << r_final.norm() << " of their scale; tolerance " << o.tolerance
        << "), the largest " << sys.coordinate_names()[std::size_t(part->iv[std::size_t(worst)])]
        << "'' = " << r_model(worst) << ", at q = (";
    for (Index j = 0; j < sys.coordinate_count(); ++j)
      msg << (j ? ", " : "") << sys.coordinate_names()[std::size_t(j)] << " = " << rd->q()(j);
    msg << ")";
    throw EquilibriumError(msg.str());
  }
  Equilibrium eq;
  eq.point.q = rd->q();
  eq.point.qd = rd->qd();
  eq.point.t = guess.t;
  eq.residual = r_model.norm();
  eq.iterations = it;
  return eq;
}

}  // namespace ukdyn

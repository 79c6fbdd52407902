// SPDX-License-Identifier: BSD-3-Clause
// The energy balance of a run: E(t) − E(0) = W_nonideal + W_ideal + W_drive + W_external +
// W_control + W_impact (docs/contact.md), the works integrated in the ODE state
// (simulation/constrained_ode.cpp) or, for the control, beside it
// (control/simulate_controlled.cpp). Its residual, relative to the energy the run exchanged, is the
// run's certificate (docs/simulation.md, "Energy balance").
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "simulation/energy_balance.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {

namespace {

// the relative energy resolution of a run, below which a residual never fails the balance: a
// state held to a relative 1e-11 (the projections' tolerance, section "Scales and tolerances"
// of docs/simulation.md) carries energies to about that share of their level; ten times that
// (the chain below left 1.0e-11 of its 5 J)
constexpr double kFloor = 1e-10;

std::string format3(double v) { return format_number(v, 3); }

// the warning of a run whose balance fails: the worst sample and what may cause it
// (in the run's units: J and s in SI units)
std::string warning(double worst_r, double worst_t, double balance, double tolerance,
                    const UnitSystem& units) {
  return "energy balance: E(t) - E(0) - (sum of the works) = " + format3(worst_r) + " " +
         units.energy() + " at t = " + format3(worst_t) + " " + units.time + ", " +
         format3(balance) + " of the energy exchanged, above the tolerance " + format3(tolerance) +
         " (energy_balance_tolerance): energy was gained or lost that no work channel accounts "
         "for (integration error, a jump of the state, or forces in Q that neither the potential "
         "nor an external power describes)";
}

}  // namespace

namespace detail {

double EnergyBalance::add(double t, double T, double V, double E, const double (&works)[6]) {
  // r_i = E_i − E_0 − ΣW_i;  exchanged = Σ_channels Σ_i |W_i − W_{i−1}|
  if (count_ == 0) E0_ = E;
  double sum = 0.0;
  for (int c = 0; c < 6; ++c) {
    sum += works[c];
    if (count_ > 0) exchanged_ += std::abs(works[c] - previous_[c]);
    previous_[c] = works[c];
  }
  const double r = E - E0_ - sum;
  finite_ = finite_ && std::isfinite(r);
  largest_ = std::max(largest_, std::abs(r));
  T_max_ = std::max(T_max_, std::abs(T));
  level_ = std::max(level_, std::abs(T) + std::abs(V));
  if (count_ == 0 || !(std::abs(r) <= std::abs(worst_r_))) {
    worst_r_ = r;
    worst_t_ = t;
  }
  ++count_;
  return r;
}

void EnergyBalance::finish(RunStatistics& s, double tolerance, const UnitSystem& units) const {
  s.energy_balance = s.energy_exchanged = s.energy_drift = 0.0;
  s.energy_balance_checked = std::isfinite(tolerance);
  if (count_ == 0) return;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // relative to the energy exchanged, the kinetic energy, or the roundoff of E = T + V; and
  // never failing below kFloor of the run's energy level: with a finite tolerance the last term
  // makes a residual of kFloor · level exactly the tolerance (a closed chain of 100 links, one
  // RK4 step of 1 ms: 5e-11 J of 5 J, with 7e-11 J exchanged, failed without it)
  const double floor = std::isfinite(tolerance) && tolerance > 0.0 ? kFloor / tolerance : 0.0;
  const double scale = std::max(
      {exchanged_, T_max_, 1e-9 * level_, floor * level_, std::numeric_limits<double>::min()});
  s.energy_exchanged = exchanged_;
  s.energy_balance = finite_ ? largest_ / scale : nan;
  // the older figure: relative to the run's energy, or absolute (J) when that is below one unit
  // of energy (a run in which nothing moves has E(0) = T = 0: never divide by them)
  constexpr double kDriftFloor = 1.0;
  const double old_scale = std::max({std::abs(E0_), T_max_, exchanged_, kDriftFloor});
  s.energy_drift = !finite_ ? nan : largest_ / old_scale;
  // a run that ended well but whose balance fails: the warning status
  if (s.status == Status::kOk && std::isfinite(tolerance) && !(s.energy_balance <= tolerance)) {
    s.status = Status::kEnergyBalance;
    s.message = warning(worst_r_, worst_t_, s.energy_balance, tolerance, units);
  }
}

}  // namespace detail

void compute_energy_balance(Trajectory& traj, double tolerance, const UnitSystem& units) {
  const std::size_t N = traj.t.size();
  traj.energy_balance_residual.resize(N);
  traj.check_consistent("ukdyn::compute_energy_balance");
  detail::EnergyBalance balance;
  for (std::size_t i = 0; i < N; ++i) {
    const double works[6] = {
        traj.work_nonideal[i], traj.work_ideal[i],
        traj.work_drive[i],    traj.work_external[i],
        traj.work_control[i],  traj.work_impact.empty() ? 0.0 : traj.work_impact[i]};
    traj.energy_balance_residual[i] = balance.add(traj.t[i], traj.kinetic_energy[i],
                                                  traj.potential_energy[i], traj.energy[i], works);
  }
  balance.finish(traj.stats, tolerance, units);
}

}  // namespace ukdyn

// The energy balance of a run: E(t) − E(0) = W_nonideal + W_ideal + W_drive + W_external +
// W_control, the works integrated in the ODE state (constrained_ode.cpp) or, for the control,
// beside it (control_simulate.cpp). Its residual, relative to the energy the run exchanged, is the
// run's certificate (docs/simulation.md, "Energy balance").
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "ukdyn/simulate.hpp"

namespace ukdyn {

namespace {

std::string format(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v;
  return s.str();
}

// the warning of a run whose balance fails: the worst sample and what may cause it
std::string warning(const Trajectory& traj, double tolerance) {
  const auto& r = traj.energy_balance_residual;
  std::size_t worst = 0;
  for (std::size_t i = 0; i < r.size(); ++i) {
    if (!(std::abs(r[i]) <= std::abs(r[worst]))) worst = i;
  }
  return "energy balance: E(t) - E(0) - (sum of the works) = " + format(r[worst]) + " J at t = " +
         format(traj.t[worst]) + " s, " + format(traj.stats.energy_balance) +
         " of the energy exchanged, above the tolerance " + format(tolerance) +
         " (energy_balance_tolerance): energy was gained or lost that no work channel accounts "
         "for (integration error, a jump of the state, or forces in Q that neither the potential "
         "nor an external power describes)";
}

}  // namespace

void compute_energy_balance(Trajectory& traj, double tolerance) {
  const std::size_t N = traj.t.size();
  traj.energy_balance_residual.resize(N);
  traj.check_consistent("ukdyn::compute_energy_balance");
  RunStatistics& s = traj.stats;
  s.energy_balance = s.energy_exchanged = s.energy_drift = 0.0;
  s.energy_balance_checked = std::isfinite(tolerance);
  if (N == 0) return;
  const std::vector<double>* works[] = {&traj.work_nonideal, &traj.work_ideal, &traj.work_drive,
                                        &traj.work_external, &traj.work_control};
  const double E0 = traj.energy.front();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // r_i = E_i − E_0 − ΣW_i;  exchanged = Σ_channels Σ_i |W_i − W_{i−1}|
  double largest = 0.0, T_max = 0.0, level = 0.0, exchanged = 0.0;
  bool finite = true;
  for (std::size_t i = 0; i < N; ++i) {
    double sum = 0.0;
    for (const auto* w : works) {
      sum += (*w)[i];
      if (i > 0) exchanged += std::abs((*w)[i] - (*w)[i - 1]);
    }
    const double r = traj.energy[i] - E0 - sum;
    traj.energy_balance_residual[i] = r;
    finite = finite && std::isfinite(r);
    largest = std::max(largest, std::abs(r));
    T_max = std::max(T_max, std::abs(traj.kinetic_energy[i]));
    level = std::max(level, std::abs(traj.kinetic_energy[i]) + std::abs(traj.potential_energy[i]));
  }
  // relative to the energy exchanged, the kinetic energy, or the roundoff of E = T + V
  const double scale =
      std::max({exchanged, T_max, 1e-9 * level, std::numeric_limits<double>::min()});
  s.energy_exchanged = exchanged;
  s.energy_balance = finite ? largest / scale : nan;
  // the older figure: relative to the run's energy, or absolute (J) when that is below one unit
  // of energy (a run in which nothing moves has E(0) = T = 0: never divide by them)
  constexpr double kDriftFloor = 1.0;
  const double old_scale = std::max({std::abs(E0), T_max, exchanged, kDriftFloor});
  s.energy_drift = !finite ? nan : largest / old_scale;
  // a run that ended well but whose balance fails: the warning status
  if (s.status == Status::kOk && std::isfinite(tolerance) && !(s.energy_balance <= tolerance)) {
    s.status = Status::kEnergyBalance;
    s.message = warning(traj, tolerance);
  }
}

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// Internal: the energy balance of a run accumulated sample by sample
// (simulation/energy_balance.cpp), so that a streamed run (SimulationOptions::sample_sink)
// certifies its balance without keeping its samples. compute_energy_balance() runs the same
// accumulator over a stored trajectory: both give the same numbers bit for bit. Not installed.
#pragma once

#include <cstddef>

#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::detail {

class EnergyBalance {
 public:
  // the next sample: its time, energies and the six work channels (nonideal, ideal, drive,
  // external, control, impact); returns its residual E − E(0) − ΣW
  double add(double t, double T, double V, double E, const double (&works)[6]);
  // the balance's figures into s (energy_balance, energy_exchanged, energy_drift,
  // energy_balance_checked = tolerance finite) and, when s.status is kOk and the balance
  // exceeds the tolerance (or is NaN), Status::kEnergyBalance with its warning
  void finish(RunStatistics& s, double tolerance, const UnitSystem& units = {}) const;

 private:
  std::size_t count_ = 0;
  double E0_ = 0.0, largest_ = 0.0, T_max_ = 0.0, level_ = 0.0, exchanged_ = 0.0;
  bool finite_ = true;
  double previous_[6] = {};               // (the six work channels)
  double worst_r_ = 0.0, worst_t_ = 0.0;  // the sample of largest |residual|
};

}  // namespace ukdyn::detail

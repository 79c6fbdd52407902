// SPDX-License-Identifier: BSD-3-Clause
// Trajectory: the consistency of its names and fields (tier 1 for writers and hand-made ones).
#include <stdexcept>
#include <string>

#include "ukdyn/core/format.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {

void Trajectory::check_consistent(const char* who) const {
  const Trajectory& traj = *this;
  const std::size_t N = traj.t.size();
  const std::size_t nq = std::size_t(traj.n), mr = std::size_t(traj.m);  // (not n, m: members)
  const std::size_t K = traj.constraint_names.size();
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument(std::string(who) + ": inconsistent trajectory: " + what +
                                " (a Trajectory from ukdyn::simulate() is always consistent)");
  };
  if (traj.n < 0 || traj.m < 0) fail("negative n or m");
  if (traj.coordinate_names.size() != nq) {
    fail(format_number(traj.coordinate_names.size()) +
         " coordinate names, expected n = " + format_number(nq));
  }
  if (traj.constraint_rows.size() != K || traj.constraint_kinds.size() != K) {
    fail(format_number(K) + " constraint names but " + format_number(traj.constraint_rows.size()) +
         " row counts and " + format_number(traj.constraint_kinds.size()) + " kinds");
  }
  Index rows = 0;
  for (Index r : traj.constraint_rows) rows += r;
  if (rows != traj.m) {
    fail("the constraints have " + format_number(rows) +
         " rows in all, expected m = " + format_number(mr));
  }
  auto field = [&](const char* name, const std::vector<double>& f, std::size_t width,
                   const char* width_name) {
    if (f.size() != N * width) {
      fail("field '" + std::string(name) + "' has " + format_number(f.size()) +
           " values, expected N × " + width_name + " = " + format_number(N) + " × " +
           format_number(width));
    }
  };
  field("q", traj.q, nq, "n");
  field("qd", traj.qd, nq, "n");
  field("qdd", traj.qdd, nq, "n");
  field("Qc_ideal", traj.Qc_ideal, nq, "n");
  field("Qc_nonideal", traj.Qc_nonideal, nq, "n");
  field("lambda", traj.lambda, mr, "m");
  for (Index k : traj.unilateral) {
    if (k < 0 || std::size_t(k) >= K || traj.constraint_rows[std::size_t(k)] != 1)
      fail("unilateral constraint index " + format_number(k) + " is not a one-row constraint");
  }
  if (!traj.lambda_total.empty() || !traj.unilateral.empty())
    field("lambda_total", traj.lambda_total, traj.unilateral.size(), "u");
  field("position_violation", traj.position_violation, K, "K");
  field("velocity_violation", traj.velocity_violation, K, "K");
  field("kinetic_energy", traj.kinetic_energy, 1, "1");
  field("potential_energy", traj.potential_energy, 1, "1");
  field("energy", traj.energy, 1, "1");
  field("work_nonideal", traj.work_nonideal, 1, "1");
  field("work_ideal", traj.work_ideal, 1, "1");
  field("work_drive", traj.work_drive, 1, "1");
  field("work_external", traj.work_external, 1, "1");
  field("work_control", traj.work_control, 1, "1");
  if (!traj.work_impact.empty()) field("work_impact", traj.work_impact, 1, "1");
  field("energy_balance_residual", traj.energy_balance_residual, 1, "1");
}

}  // namespace ukdyn

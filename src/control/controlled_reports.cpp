// SPDX-License-Identifier: BSD-3-Clause
// A controlled run's reports: the fields of its samples (sample_fields), its columns beside the
// plant's (control_csv_columns, write_csv), and the diagnosis of a run whose step size collapsed
// where the requirement rows lost rank (diagnose_requirements) (ukdyn/control/control.hpp,
// control/controlled_plant.hpp).
#include "control/controlled_plant.hpp"

#include <Eigen/SVD>

#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "ukdyn/io/trajectory_files.hpp"

namespace ukdyn {

namespace control_detail {

namespace {

// sigma_min / sigma_max of the active requirement rows A_r at (q, q', t), NaN without rows
double requirement_gap(const Controller& ctrl, ControlWorkspace& cws,
                       const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t) {
  compute_control(ctrl, cws, q, qd, t);
  MatrixXd rows(cws.req.active_rows, cws.req.A.cols());
  Index k = 0;
  for (Index i = 0; i < cws.req.A.rows() && k < rows.rows(); ++i) {
    if (cws.req.A.row(i).squaredNorm() > 0.0) rows.row(k++) = cws.req.A.row(i);
  }
  if (k == 0) return std::numeric_limits<double>::quiet_NaN();
  const VectorXd sv = Eigen::JacobiSVD<MatrixXd>(rows.topRows(k)).singularValues();
  return sv[0] > 0.0 ? sv[sv.size() - 1] / sv[0] : 0.0;
}

}  // namespace

void diagnose_requirements(const ControlledPlant& st, const ControlledScratch& w,
                           const Eigen::Ref<const VectorXd>& q0,
                           const Eigen::Ref<const VectorXd>& qd0, double t0,
                           const std::string& time_unit, RunStatistics& stats) {
  if (stats.status != Status::kIntegratorFailure || w.stats.evaluations == 0) return;
  ControlWorkspace cws(st.ctrl);
  const double start = requirement_gap(st.ctrl, cws, q0, qd0, t0);
  const double now = requirement_gap(st.ctrl, cws, w.q_last, w.qd_last, w.t_last);
  if (!(now < 1e-4) || start < 100.0 * now) return;
  std::string& m = stats.message;
  for (const char* cause : {". Likely cause", ". The step size collapsed"}) {
    if (const auto at = m.find(cause); at != std::string::npos) m.erase(at);
  }
  char gaps[160];
  std::snprintf(gaps, sizeof gaps,
                "sigma_min / sigma_max of the requirement rows %.3g at t = %g %s, %.3g at the "
                "start",
                now, w.t_last, time_unit.c_str(), start);
  m += std::string(". Likely cause: the requirements lost rank (") + gaps +
       "): they cannot all be met there — a path that leaves the reachable set, or passes a "
       "singular configuration of the mechanism (an arm stretched out). Try: a requirement that "
       "stays inside the workspace, fewer requirement rows, or actuated coordinates and a "
       "weighted law that tolerate the loss (docs/control.md)";
}

}  // namespace control_detail

std::vector<std::vector<double>*> sample_fields(ControlledTrajectory& run) {
  return {&run.plant.t,
          &run.plant.q,
          &run.plant.qd,
          &run.plant.qdd,
          &run.plant.Qc_ideal,
          &run.plant.Qc_nonideal,
          &run.plant.lambda,
          &run.plant.lambda_total,
          &run.plant.position_violation,
          &run.plant.velocity_violation,
          &run.plant.kinetic_energy,
          &run.plant.potential_energy,
          &run.plant.energy,
          &run.plant.work_nonideal,
          &run.plant.work_ideal,
          &run.plant.work_drive,
          &run.plant.work_external,
          &run.plant.work_control,
          &run.plant.work_impact,
          &run.plant.energy_balance_residual,
          &run.error,
          &run.error_rate,
          &run.error_bound,
          &run.Qc_control,
          &run.Qc_robust,
          &run.control_power,
          &run.control_effort,
          &run.control_work_abs,
          &run.control_work};
}

std::vector<CsvColumn> control_csv_columns(const ControlledTrajectory& run) {
  const Index N = run.samples(), n = run.plant.n, m_r = Index(run.row_names.size());
  if (Index(run.error.size()) != N * m_r || Index(run.Qc_control.size()) != N * n ||
      Index(run.control_power.size()) != N || Index(run.control_effort.size()) != N ||
      Index(run.control_work_abs.size()) != N || Index(run.control_work.size()) != N ||
      (run.robust && Index(run.error_bound.size()) != N * m_r)) {
    throw std::invalid_argument(
        "ukdyn::control_csv_columns: inconsistent controlled trajectory "
        "(one from simulate_controlled() always is consistent)");
  }
  std::vector<CsvColumn> cols;
  auto matrix = [&](const std::string& prefix, const std::vector<double>& f,
                    const std::vector<std::string>& names) {
    const Index width = Index(names.size());
    for (Index i = 0; i < width; ++i) {
      CsvColumn c{prefix + names[std::size_t(i)], {}};
      c.values.reserve(std::size_t(N));
      for (Index j = 0; j < N; ++j) c.values.push_back(f[std::size_t(j * width + i)]);
      cols.push_back(std::move(c));
    }
  };
  matrix("error.", run.error, run.row_names);
  if (run.robust) matrix("error_bound.", run.error_bound, run.row_names);
  matrix("Qc_control.", run.Qc_control, run.plant.coordinate_names);
  if (run.robust) matrix("Qc_robust.", run.Qc_robust, run.plant.coordinate_names);
  cols.push_back({"control_power", run.control_power});
  cols.push_back({"control_effort", run.control_effort});
  cols.push_back({"control_work_abs", run.control_work_abs});
  cols.push_back({"control_work", run.control_work});
  return cols;
}

void write_csv(const ControlledTrajectory& run, const std::string& path) {
  write_csv(run.plant, path, control_csv_columns(run));
}

}  // namespace ukdyn

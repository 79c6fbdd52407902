// SPDX-License-Identifier: BSD-3-Clause
// Why requirements cannot be met, and the warnings of a controlled run's statistics: the text
// that `ukdyn check`, `ukdyn run` and Python print (docs/control.md, "Requirements that cannot
// be met"). Reports only: allocates, never called in a run's evaluations.
//
// For a row i not met, with A_r,i its requirement row, A_p the physical rows active at the
// evaluation and X S the rows the law solves (X = A_r P):
//   fixed by a physical constraint   A_r,i = c A_p  (its least-squares residual ~ 0): the
//                                    constraints with c ≠ 0 decide the row, no force can move it
//   not actuated                     (X S)_i = 0 while X_i ≠ 0: the actuators cannot move it
//   in conflict with other rows      u ᵀ (X S) = 0 for a left singular vector u of a zero
//                                    singular value with u_i ≠ 0: the rows j with u_j ≠ 0 are
//                                    dependent, and their targets e_j disagree
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "control/internal.hpp"
#include "simulation/initial_check.hpp"

namespace ukdyn {
namespace {

// a row counts as zero below this fraction of its scale (the law's rank threshold is 1e-10 of
// the largest pivot; rows computed through M⁻¹ and a projection carry ~1e-12 relative roundoff)
constexpr double kZero = 1e-8;

std::string quoted(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t j = 0; j < names.size(); ++j) {
    out += (j == 0 ? "'" : j + 1 == names.size() ? "' and '" : "', '") + names[j];
  }
  return out + "'";
}

// the rows of a group that depends linearly in `rows` (m_r × ·) and holds an open row not
// yet explained (a left null vector u, uᵀ rows = 0, with u_i ≠ 0 there); marks them explained
std::vector<std::string> dependent_rows(const Controller& ctrl,
                                        const std::vector<unsigned char>& open_rows,
                                        const MatrixXd& rows,
                                        std::vector<unsigned char>& explained) {
  const Index m_r = rows.rows();
  std::vector<std::string> group;
  if (m_r == 0 || rows.cols() == 0) return group;
  const Eigen::JacobiSVD<MatrixXd> svd(rows, Eigen::ComputeFullU);
  const VectorXd& sigma = svd.singularValues();
  const double top = sigma.size() > 0 ? sigma[0] : 0.0;
  std::vector<unsigned char> in(std::size_t(m_r), 0);
  for (Index k = 0; k < m_r; ++k) {
    if (k < sigma.size() && sigma[k] > kZero * top) continue;
    const auto u = svd.matrixU().col(k);
    bool open = false;
    for (Index i = 0; i < m_r; ++i) {
      open = open ||
             (std::abs(u[i]) > kZero && open_rows[std::size_t(i)] && !explained[std::size_t(i)]);
    }
    if (!open) continue;
    for (Index i = 0; i < m_r; ++i) {
      if (std::abs(u[i]) > kZero && !explained[std::size_t(i)] && rows.row(i).norm() > 0.0) {
        in[std::size_t(i)] = 1;
      }
    }
  }
  for (Index i = 0; i < m_r; ++i) {
    if (!in[std::size_t(i)]) continue;
    explained[std::size_t(i)] = 1;
    group.push_back(ctrl.row_names()[std::size_t(i)]);
  }
  return group;
}

// the causes for the `open` rows (to be explained); with actuators_only, only those of the
// actuators (the others are found, to be set apart, but not said)
std::string explain(const Controller& ctrl, const ControlWorkspace& ws,
                    const std::vector<unsigned char>& open, bool actuators_only) {
  const Index m_r = ctrl.requirement_rows();
  const auto& names = ctrl.row_names();
  const System& model = ctrl.model();
  const MatrixXd& A = ws.req.A;
  std::vector<std::string> causes;
  std::vector<unsigned char> explained(std::size_t(m_r), 0);

  // rows that the physical constraints fix: A_r,iᵀ = A_pᵀ c
  const MatrixXd& Ap = ws.model.A;
  if (ws.model.active_rows > 0 && Ap.rows() > 0) {
    const Eigen::CompleteOrthogonalDecomposition<MatrixXd> cod(Ap.transpose());
    for (Index i = 0; i < m_r; ++i) {
      const double a = A.row(i).norm();
      if (!open[std::size_t(i)] || !(a > 0.0)) continue;
      const VectorXd c = cod.solve(A.row(i).transpose());
      if ((Ap.transpose() * c - A.row(i).transpose()).norm() > kZero * a) continue;
      std::vector<std::string> by;
      const double largest = c.cwiseAbs().maxCoeff();
      for (Index k = 0; k < model.constraint_count(); ++k) {
        const Index r0 = model.row_offset(k), rk = model.constraint(k).rows();
        if (c.segment(r0, rk).cwiseAbs().maxCoeff() > kZero * largest) {
          by.push_back(model.constraint(k).name());
        }
      }
      explained[std::size_t(i)] = 1;
      if (actuators_only) continue;
      causes.push_back("requirement row '" + names[std::size_t(i)] + "' asks for a motion that " +
                       (by.size() == 1 ? "the physical constraint " : "the physical constraints ") +
                       quoted(by) + (by.size() == 1 ? " fixes" : " fix") +
                       " (its row is a combination of theirs): no force can change it, and it "
                       "contradicts what they hold");
    }
  }

  // rows that the actuators cannot move: (X S)_i = 0, X_i ≠ 0
  if (!ctrl.fully_actuated()) {
    std::vector<std::string> unmoved;
    for (Index i = 0; i < m_r; ++i) {
      if (!open[std::size_t(i)] || explained[std::size_t(i)]) continue;
      const double x = ws.X.row(i).norm();
      if (x > 0.0 && ws.XS.row(i).norm() <= kZero * x * std::max(1.0, ctrl.actuation().norm())) {
        explained[std::size_t(i)] = 1;
        unmoved.push_back(names[std::size_t(i)]);
      }
    }
    if (!unmoved.empty()) {
      std::string actuators;
      for (Index j : ctrl.actuated_coordinates()) {
        actuators += (actuators.empty() ? "" : ", ") + model.coordinate_names()[std::size_t(j)];
      }
      if (actuators.empty()) actuators = format_number(ctrl.actuators()) + " actuators of S";
      causes.push_back(std::string("requirement ") + (unmoved.size() == 1 ? "row " : "rows ") +
                       quoted(unmoved) + (unmoved.size() == 1 ? " is" : " are") +
                       " not moved by the actuated coordinates (" + actuators +
                       "): actuate a coordinate that moves it");
    }
  }

  // rows in conflict with each other whatever the actuators (left null vectors of X = A_r P),
  // then rows that the actuators cannot meet together (of X S)
  const std::vector<std::string> conflict = dependent_rows(ctrl, open, ws.X, explained);
  if (conflict.size() > 1 && !actuators_only) {
    causes.push_back("requirement rows " + quoted(conflict) +
                     " contradict each other: their rows are dependent (what one asks, the "
                     "others fix) and their targets differ — remove one, or make them agree");
  }
  if (!ctrl.fully_actuated()) {
    const std::vector<std::string> too_few = dependent_rows(ctrl, open, ws.XS, explained);
    if (too_few.size() > 1) {
      causes.push_back("requirement rows " + quoted(too_few) + " need more than the " +
                       format_number(ctrl.actuators()) + " actuated " +
                       (ctrl.actuators() == 1 ? "coordinate" : "coordinates") +
                       " can give together: actuate more coordinates, or require less");
    }
  }
  std::string out;
  for (const std::string& c : causes) out += (out.empty() ? "" : "; ") + c;
  return out;
}

}  // namespace

std::string explain_requirements_not_met(const Controller& ctrl, const ControlWorkspace& ws) {
  control_detail::require_same_controller(ctrl, ws, "ukdyn::explain_requirements_not_met");
  if (ws.status != ControlStatus::kRequirementsNotMet) return "";
  std::vector<unsigned char> open(ws.met.size());
  for (std::size_t i = 0; i < open.size(); ++i) open[i] = !ws.met[i];
  return explain(ctrl, ws, open, false);
}

std::string explain_unactuated_requirements(const Controller& ctrl, const ControlWorkspace& ws) {
  control_detail::require_same_controller(ctrl, ws, "ukdyn::explain_unactuated_requirements");
  if (ctrl.fully_actuated() ||
      (ws.status != ControlStatus::kOk && ws.status != ControlStatus::kRequirementsNotMet)) {
    return "";
  }
  std::vector<unsigned char> open(std::size_t(ctrl.requirement_rows()));
  for (Index i = 0; i < ctrl.requirement_rows(); ++i) {
    open[std::size_t(i)] = ws.req.A.row(i).norm() > 0.0;
  }
  return explain(ctrl, ws, open, true);
}

std::vector<std::string> control_warnings(const ControlStatistics& c,
                                          const std::string& time_unit) {
  std::vector<std::string> out;
  char line[256];
  if (c.not_met > 0) {
    std::snprintf(line, sizeof line,
                  "the control could not meet every requirement in %ld of %ld evaluations "
                  "(first at t = %g %s: ",
                  c.not_met, c.evaluations, c.first_not_met, time_unit.c_str());
    std::string w = line + c.not_met_message;
    std::snprintf(line, sizeof line,
                  "); largest residual %.3g. It applied %s: see the error.* columns for what was "
                  "not met",
                  c.max_residual,
                  c.held_control ? "the control that meets them with the contact held, the "
                                   "contact sliding under it"
                                 : "the least-squares force");
    out.push_back(w + line);
  }
  if (std::isfinite(c.bound_exceeded_at)) {
    std::snprintf(line, sizeof line,
                  "the error left its guaranteed bound at t = %g %s, by up to %.3g times the bound "
                  "(row '",
                  c.bound_exceeded_at, time_unit.c_str(), c.bound_worst_ratio);
    std::string w = line + c.bound_worst_row;
    std::snprintf(line, sizeof line,
                  "' at t = %g %s): the uncertainty model (robust: bound, relative_bound, "
                  "gain_uncertainty) does not hold for this plant, and error_bound.* guarantees "
                  "nothing (the run's notes say more)",
                  c.bound_worst_time, time_unit.c_str());
    out.push_back(w + line);
  }
  return out;
}

std::string explain_uncorrected_requirements(const Controller& ctrl,
                                             const Eigen::Ref<const VectorXd>& q,
                                             const Eigen::Ref<const VectorXd>& qd, double t,
                                             double tolerance, double duration) {
  const System& req = ctrl.requirements();
  // "constraint 'a' (holonomic): position violation 1, velocity violation 0", one per violated
  // requirement with its name, in the scales of the run (the initial check's)
  std::vector<std::string> names;
  const std::vector<std::string> lines =
      detail::check_initial_conditions(req, q, qd, t, tolerance, duration, &names);
  std::string out;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const Constraint& c = req.constraint(req.constraint_index(names[i]));
    if (c.stabilization().enabled() || !c.is_active(t)) continue;
    const std::size_t colon = lines[i].find("): ");
    const std::string violation = colon == std::string::npos ? "" : lines[i].substr(colon + 3);
    out += (out.empty() ? "" : "; ") + std::string("requirement '") + names[i] +
           "' starts unmet (" + violation + ") and has no dynamics";
  }
  if (out.empty()) return out;
  return out + ": the control keeps the error's " +
         "acceleration (its rate, nonholonomic) at zero, so it is never corrected — it stays, or "
         "grows at its rate. Give the requirement dynamics: {omega: 10, zeta: 1} "
         "(docs/control.md), "
         "or start on it";
}

}  // namespace ukdyn

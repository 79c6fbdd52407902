// SPDX-License-Identifier: BSD-3-Clause
// ControlWorkspace: every buffer of the control pipeline, sized once; the description of a
// control status.
#include <cmath>
#include <string>

#include "control/internal.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn {

using control_detail::format;

namespace {
// the nominal model's solver: no Gauss/virtual-work residuals (not reported by the controller;
// the consistency test still runs)
SolverOptions model_options(SolverOptions o) {
  o.compute_residuals = false;
  // the laws read the model's dense M, A and decomposition (control/laws.cpp)
  o.engine = Engine::kDense;
  return o;
}
}  // namespace

const char* to_string(ControlStatus s) {
  switch (s) {
    case ControlStatus::kOk:
      return "ok";
    case ControlStatus::kRequirementsNotMet:
      return "requirements not met";
    case ControlStatus::kModelFailed:
      return "nominal model failed";
    case ControlStatus::kNonFiniteInput:
      return "non-finite requirement or weight";
    case ControlStatus::kWeightNotPositiveDefinite:
      return "weight not positive definite";
    case ControlStatus::kNonFiniteResult:
      return "non-finite control force";
  }
  return "unknown";
}

ControlWorkspace::ControlWorkspace(const Controller& ctrl)
    : model(ctrl.model(), model_options(ctrl.options().solver)),
      req(ctrl.requirements(), model_options(ctrl.options().solver)),
      controller_id_(ctrl.id()) {
  const Index n = ctrl.coordinate_count(), m_r = ctrl.requirement_rows(), k = ctrl.actuators();
  // the requirements are evaluated at the model's state right after the model: their scratch
  // shares the model's callables' (a pose requirement on the model's tree then reads the
  // forward kinematics of the model's evaluation instead of running its own)
  const System& reqs = ctrl.requirements();
  for (Index c = 0; c < reqs.constraint_count(); ++c) {
    req.scratch[std::size_t(c)] =
        reqs.constraint(c).model().make_scratch_sharing(n, model.callables.get());
  }
  const Index m_p = ctrl.model().constraint_rows();
  const bool direct = control_detail::gauss_direct(ctrl);
  e.setZero(m_r);
  X.setZero(m_r, n);
  XS.setZero(direct ? 0 : m_r, direct ? 0 : k);
  N.setZero(ctrl.law() == ControlLaw::kWeighted ? n : 0,
            ctrl.law() == ControlLaw::kWeighted ? n : 0);
  Nu.setZero(direct ? 0 : k, direct ? 0 : k);
  const bool actuated = !ctrl.fully_actuated();
  MinvS.setZero(actuated ? n : 0, actuated ? k : 0);
  decomposition.resize(k, m_r);
  decomposition.set_threshold(ctrl.options().solver.rank_threshold);
  u.setZero(k);
  Qc_nominal.setZero(n);
  residual.setZero(m_r);
  met.assign(std::size_t(m_r), 1);
  s.setZero(m_r);
  kappa.setZero(m_r);
  v.setZero(m_r);
  u_robust.setZero(k);
  Qc_robust.setZero(n);
  Qc_control.setZero(n);
  qdd.setZero(n);
  Qc_physical.setZero(n);
  tmp_n.setZero(n);
  tmp_n2.setZero(n);
  tmp_n3.setZero(n);
  tmp_k.setZero(k);
  lambda_r.setZero(m_r);
  lambda_p.setZero(m_p);
}

std::string describe_control_status(const Controller& ctrl, const ControlWorkspace& ws) {
  return control_detail::describe_control_status(ctrl, ws, false);
}

std::string control_detail::describe_control_status(const Controller& ctrl,
                                                    const ControlWorkspace& ws, bool held) {
  const std::string when = "ukdyn control at t = " + format(ws.failed_time) + ": ";
  switch (ws.status) {
    case ControlStatus::kOk:
      return "ok";
    case ControlStatus::kRequirementsNotMet: {
      std::string actuators;
      if (ctrl.fully_actuated()) {
        actuators = "with every coordinate actuated";
      } else if (!ctrl.actuated_coordinates().empty()) {
        for (Index j : ctrl.actuated_coordinates()) {
          actuators +=
              (actuators.empty() ? "" : ", ") + ctrl.model().coordinate_names()[std::size_t(j)];
        }
        actuators = "with the actuators (" + actuators + ")";
      } else {
        actuators = "with the " + format_number(ctrl.actuators()) + " actuators of S";
      }
      std::string missed, kept;
      for (Index i = 0; i < ctrl.requirement_rows(); ++i) {
        if (ws.met[std::size_t(i)]) {
          kept += (kept.empty() ? "'" : ", '") + ctrl.row_names()[std::size_t(i)] + "'";
        } else {
          missed += (missed.empty() ? "'" : ", '") + ctrl.row_names()[std::size_t(i)] +
                    "' (residual " + format(ws.residual[i]) + ")";
        }
      }
      // (why, when a cause is found: a physical constraint, the actuators, a conflict)
      const std::string why = explain_requirements_not_met(ctrl, ws);
      return when + "the requirements cannot all be met " + actuators +
             (why.empty() ? "" : ": " + why) + " (rank of the requirement rows " +
             format_number(ws.rank) + "); " +
             (held ? "the control that meets them with the sliding contact held applied (the "
                     "contact slides under it)"
                   : "least squares applied") +
             ". Not met: " + missed + (kept.empty() ? "; none met" : "; met: " + kept);
    }
    case ControlStatus::kModelFailed:
      // (the model's evaluation succeeded, singular M and all, when the law's own factorization
      // of M failed: say that, not "failed: ok")
      if (ws.model.status == Status::kOk) {
        return when +
               "the mass matrix M of the nominal model is not positive definite (the control "
               "law's Cholesky factorization M = L Lᵀ failed), and control needs a positive "
               "definite M (docs/singular-mass.md, \"Limits\")";
      }
      return when + "the nominal model failed: " + describe_status(ctrl.model(), ws.model);
    case ControlStatus::kNonFiniteInput: {
      const std::string q = ws.failed_quantity;
      if (q == "N") return when + "the weight N holds NaN or Inf";
      std::string name;
      if (ws.failed_index >= 0 && ws.failed_index < ctrl.requirement_count()) {
        name = " of requirement '" + ctrl.requirement(ws.failed_index).name() + "'";
      }
      return when + q + name + " holds NaN or Inf";
    }
    case ControlStatus::kWeightNotPositiveDefinite:
      return when +
             (ctrl.law() == ControlLaw::kWeighted
                  ? std::string("the weight N") + (ctrl.fully_actuated() ? "" : " (Sᵀ N S)")
                  : std::string("Sᵀ M⁻¹ S")) +
             " is not positive definite (its Cholesky factorization failed)";
    case ControlStatus::kNonFiniteResult:
      return when + "the control force overflowed (NaN or Inf)";
  }
  return when + "unknown status";
}

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// check_model: what `ukdyn check` reports about a model at its initial state — sizes, rank and
// redundancy of the constraints, consistency of the initial state, M, and the control there.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/QR>

#include "control/contact_modes.hpp"
#include "control/control_at_start.hpp"
#include "dynamics/contact_dynamics.hpp"
#include "dynamics/internal.hpp"
#include "modelfile/angle_flags.hpp"
#include "modelfile/contact_start.hpp"
#include "simulation/contact_events.hpp"
#include "simulation/initial_check.hpp"
#include "ukdyn/control/control.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/modelfile/model.hpp"

namespace ukdyn {
namespace {

// numerical rank of the rows S (k × n) with Eigen's column-pivoting QR and the solver's relative
// threshold: pivot j counts when |R_jj| > threshold · |R_00| (as in FundamentalDecomposition)
Index rank_of_rows(const MatrixXd& S, double threshold) {
  if (S.rows() == 0 || S.cols() == 0) return 0;
  if (!S.allFinite()) return 0;
  Eigen::ColPivHouseholderQR<MatrixXd> qr(S.transpose());
  qr.setThreshold(threshold);
  return qr.rank();
}

// a number for messages, 3 significant digits
std::string format(double x) { return format_number(x, 3); }

// The unilateral contacts a run refuses to start with (u22 07): penetrated at the initial state
// beyond the run's own test (ContactEvents::start: a gap below −max(initial_tolerance,
// kTouchGap) times the contact's gap unit 0.1 phi_scale after set_run_scales), each a problem
// with the run's message and its hint (locate_run_error). The run tests them before any
// projection: `project: true` does not act on a unilateral gap. Returns their names.
// O(contacts) gap evaluations.
std::vector<std::string> penetrated_contacts(const Model& model,
                                             std::vector<std::string>& problems) {
  const System& sys = model.system;
  const SimulationOptions& o = model.options;
  std::vector<std::string> names;
  const detail::ContactDynamics contacts(sys);
  if (contacts.contacts().empty()) return names;
  try {
    Workspace ws(sys, o.solver);
    set_run_scales(sys, ws, model.q0, model.qd0, o.t_start, o.t_end - o.t_start,
                   detail::model_angle_coordinates(model));
    const double tolerance = std::max(o.initial_tolerance, detail::ContactEvents::kTouchGap);
    for (const Index k : contacts.contacts()) {
      double g = 0.0, gd = 0.0;
      contacts.gap(sys, ws, k, model.q0, model.qd0, o.t_start, g, gd);
      if (!(g < -tolerance * 0.1 * ws.phi_scale(sys.row_offset(k)))) continue;
      names.push_back(sys.constraint(k).name());
      problems.push_back("the unilateral constraint '" + names.back() +
                         "' is penetrated at the initial state: its gap is " + format_number(g, 6) +
                         " (a unilateral constraint needs a gap >= 0; a run refuses to start): "
                         "start with the contact open or touching: change the initial q so that "
                         "its gap is >= 0 (`project: true` does not act on a unilateral gap)");
    }
  } catch (const std::exception&) {
    // (a gap that cannot be evaluated: the run's start says so, and so do the checks below)
  }
  return names;
}

// The contacts at the initial state as the run's start solves them (ContactEvents::start: the
// touching contacts' impact, then the LCP of the accelerations with the sliding friction in it):
// a start the run refuses (Painlevé's paradox past the critical mu) is a problem with the run's
// located message (locate_contact_start). The run of model.options, streamed as `ukdyn run`'s,
// stopped once its first sample is recorded; a start that fails otherwise (a penetrated contact,
// a violated initial state, a setting) is left to the checks that say it. A controlled model's
// start is its control's (check_control). Cost: the run's start and one evaluation.
void check_contacts_at_start(const Model& model, CheckReport& report) {
  if (model.controller || detail::ContactDynamics(model.system).contacts().empty()) return;
  SimulationOptions o = model.options;
  o.units = model.unit_system;
  o.project_initial = model.project_initial || o.project_initial;
  o.should_stop = [] { return true; };
  o.sample_sink = [](const Trajectory&) {};
  o.progress = nullptr;
  try {
    (void)simulate(model.system, model.q0, model.qd0, o);
  } catch (const detail::ContactStartError& e) {
    report.problems.push_back(detail::locate_contact_start(model, e).what());
  } catch (const std::exception&) {
    // (reported by the checks above, or by the run itself)
  }
}

// the control at the initial state, as the run's first evaluation: requirements that cannot all
// be met (contradicting each other or a physical constraint, or not actuated) or a controller
// that fails there are problems (the run would warn, or stop). A singular M (a rigid body's
// quaternion) is controlled on the model's completion M_A, as in the run (compute_control). A
// model with contacts (unilateral, or Coulomb) is evaluated by the run's own start, stopped at
// its first sample (control_at_start): the contacts it closes there (the touching ones at rest
// that the LCP of the accelerations loads) and the Coulomb contacts it sticks are held, and
// those a requirement lifts are let go of, as in every evaluation of the run.
void check_control(const Model& model, CheckReport& report) {
  if (!model.controller || !report.mass_positive_definite) return;
  const Controller& ctrl = *model.controller;
  // requirements without dynamics that start unmet: never corrected (u21 05)
  try {
    if (const std::string why = explain_uncorrected_requirements(
            ctrl, model.q0, model.qd0, model.options.t_start, model.options.initial_tolerance,
            model.options.t_end - model.options.t_start);
        !why.empty())
      report.problems.push_back(why);
  } catch (const std::exception&) {
    // (an evaluation that fails is reported by the control's check below)
  }
  auto report_status = [&](ControlStatus s, const std::string& description,
                           const std::string& unactuated, bool held = false) {
    if (s == ControlStatus::kRequirementsNotMet) {
      report.problems.push_back(
          std::string("the control cannot meet its requirements at the initial state (a run "
                      "warns and applies ") +
          (held ? "the control that meets them with the sliding contact held, the contact "
                  "sliding under it"
                : "the least-squares force") +
          "): " + description);
    } else if (s == ControlStatus::kOk && !unactuated.empty()) {
      report.problems.push_back(
          "the control meets its requirements at the initial state only because they ask for "
          "no force there: " +
          unactuated);
    } else if (s != ControlStatus::kOk) {
      report.problems.push_back("the control fails at the initial state: " + description);
    }
  };
  try {
    if (!control_detail::ContactModes(ctrl).any()) {
      ControlWorkspace cws(ctrl);
      const ControlStatus s =
          compute_control(ctrl, cws, model.q0, model.qd0, model.options.t_start);
      report_status(s, s == ControlStatus::kOk ? "" : describe_control_status(ctrl, cws),
                    explain_unactuated_requirements(ctrl, cws));
      return;
    }
    // the run's start, in the model's units (its messages'), from the state the run starts at
    SimulationOptions o = model.options;
    o.units = model.unit_system;
    o.project_initial = model.project_initial || o.project_initial;
    const control_detail::ControlAtStart c =
        control_detail::control_at_start(ctrl, model.system, model.q0, model.qd0, o);
    if (!c.evaluated) return;  // (the run stops before its first sample: said above)
    if (!c.pull_failure.empty()) {
      // (the run stops there: "the controller failed: " and the same text)
      report.problems.push_back("the control fails at the initial state: " + c.pull_failure);
      return;
    }
    report_status(c.status,
                  c.stick_note.empty() ? c.description : c.description + "; " + c.stick_note,
                  c.unactuated, c.held);
  } catch (const InconsistentInitialState&) {
    // (the initial state's violations, reported above: the run does not start)
  } catch (const detail::ContactStartError& e) {
    // (the run refuses its contacts at the start: at the friction's or the contact's entry)
    report.problems.push_back(detail::locate_contact_start(model, e).what());
  } catch (const std::exception& e) {
    report.problems.push_back(std::string("the control cannot be evaluated at the initial "
                                          "state: ") +
                              e.what());
  }
}

}  // namespace

CheckReport check_model(const Model& model) {
  const System& sys = model.system;
  const SimulationOptions& o = model.options;
  const double t = o.t_start;
  const Index n = sys.coordinate_count();
  CheckReport report;
  report.coordinates = n;

  // the initial state must have n finite entries before anything is evaluated
  if (model.q0.size() != n || model.qd0.size() != n) {
    report.problems.push_back("the initial state has " + format_number(model.q0.size()) +
                              " positions and " + format_number(model.qd0.size()) +
                              " velocities, expected n = " + format_number(n));
    return report;
  }
  if (!model.q0.allFinite() || !model.qd0.allFinite()) {
    report.problems.push_back("the initial state holds NaN or Inf");
    return report;
  }

  Workspace ws(sys, o.solver);
  const double threshold = o.solver.rank_threshold;
  // unilateral contacts open at the start are not constraints there (docs/contact.md)
  detail::release_open_contacts(sys, ws, model.q0, model.qd0, t);

  // M(q0, t), Q(q0, q'0, t): M is positive definite when stage 1 got past its factorization
  const Status s_mass = evaluate_unconstrained(sys, ws, model.q0, model.qd0, t);
  const bool mass_failed =
      s_mass == Status::kMassNotPositiveDefinite || s_mass == Status::kMassNotSymmetric ||
      (s_mass == Status::kNonFiniteInput && std::string_view(ws.failed_quantity) == "M");
  report.mass_positive_definite = !mass_failed;
  report.mass_singular = !mass_failed && ws.mass_singular;
  if (s_mass != Status::kOk) report.problems.push_back(describe_status(sys, ws));

  // A, b of the constraints active at t_start, and the whole fundamental equation when M allows
  Status s_all = Status::kOk;
  if (report.mass_positive_definite && s_mass == Status::kOk) {
    s_all = forward_dynamics(sys, ws, model.q0, model.qd0, t);
    if (s_all != Status::kOk) report.problems.push_back(describe_status(sys, ws));
  } else {
    ws.status = Status::kOk;
    const Status s_a = assemble_constraints(sys, ws, model.q0, model.qd0, t);
    if (s_a != Status::kOk) report.problems.push_back(describe_status(sys, ws));
  }
  report.constraint_rows = ws.active_rows;

  // the rows of the active constraints, in declaration order
  std::vector<Index> active;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (ws.active[std::size_t(k)]) active.push_back(k);
  }
  MatrixXd stacked(ws.active_rows, n);
  {
    Index r = 0;
    for (Index k : active) {
      const Index rows = sys.constraint(k).rows();
      detail::copy_constraint_rows(sys, ws, k, stacked.middleRows(r, rows));
      r += rows;
    }
  }

  // rank A: the decomposition's when stage 3 ran, else the QR rank of the stacked rows
  const bool solved = report.mass_positive_definite && s_mass == Status::kOk &&
                      (s_all == Status::kOk || s_all == Status::kInconsistentConstraints ||
                       s_all == Status::kNonFiniteResult);
  report.rank = solved ? ws.rank : rank_of_rows(stacked, threshold);
  report.degrees_of_freedom = n - report.rank;

  // redundancy: constraint k is redundant when its rows do not raise the rank of those before it;
  // none is when all the rows are independent (one decomposition instead of one per constraint)
  // (the sparse engine's rank when it found them all independent: its threshold, 1e-6, is the
  // stricter; a dense QR of a chain of 10⁴ coordinates would take minutes)
  const bool independent =
      stacked.allFinite() && ((solved && ws.is_sparse() && ws.rank == stacked.rows()) ||
                              rank_of_rows(stacked, threshold) == stacked.rows());
  if (stacked.allFinite() && !independent) {
    MatrixXd kept(0, n);
    Index kept_rank = 0;
    for (Index k : active) {
      const Index rows = sys.constraint(k).rows();
      MatrixXd grown(kept.rows() + rows, n);
      grown.topRows(kept.rows()) = kept;
      detail::copy_constraint_rows(sys, ws, k, grown.bottomRows(rows));
      const Index grown_rank = rank_of_rows(grown, threshold);
      if (grown_rank <= kept_rank) {
        report.redundant.push_back(sys.constraint(k).name());
      } else {
        kept = std::move(grown);
        kept_rank = grown_rank;
      }
    }
  }

  // initial consistency, and whether projection finds a consistent state near
  // (in the scales of the run from q0 that `ukdyn run` makes: set_run_scales, docs/simulation.md
  // "Scales and tolerances")
  const double duration = o.t_end - t;
  std::vector<std::string> violated;
  report.initial_violations =
      detail::check_initial_conditions(sys, model.q0, model.qd0, t, o.initial_tolerance, duration,
                                       &violated, detail::model_angle_coordinates(model));
  report.penetrated = penetrated_contacts(model, report.problems);
  // (violations other than the penetrated contacts: what projection could mend)
  const bool only_penetrated =
      !report.penetrated.empty() &&
      std::all_of(violated.begin(), violated.end(), [&](const std::string& name) {
        return std::find(report.penetrated.begin(), report.penetrated.end(), name) !=
               report.penetrated.end();
      });
  // constraints that contradict each other (x = 0 and x = 1, 1 = 0): where the position
  // projection from q0 stalls, the violation no correction removes (find_constraint_conflict);
  // such constraints are not "redundant", and projecting cannot help
  if (!report.initial_violations.empty() && report.mass_positive_definite) {
    try {
      VectorXd q = model.q0, qd = model.qd0;
      Workspace wc(sys, o.solver);
      set_run_scales(sys, wc, q, qd, t, duration, detail::model_angle_coordinates(model));
      detail::release_open_contacts(sys, wc, q, qd, t);  // (an open gap is no violation)
      const ProjectionResult rp = project_positions(sys, wc, q, t, o.projection);
      ProjectionResult rv;
      if (rp.status == Status::kOk && rp.converged)
        rv = project_velocities(sys, wc, q, qd, t, o.projection);
      if (rp.status == Status::kOk && (!rp.converged || !rv.converged)) {
        const ConstraintConflict c = find_constraint_conflict(
            sys, wc, q, rp.converged ? qd : model.qd0, t, o.projection.tolerance);
        if (c.found) report.contradictory = c.names;
      }
    } catch (const std::exception&) {
      // reported below, by the projection of the initial state
    }
  }
  if (!report.contradictory.empty()) {
    std::string names;
    for (const auto& c : report.contradictory) names += (names.empty() ? "'" : ", '") + c + "'";
    report.problems.push_back(
        report.contradictory.size() == 1
            ? "the constraint " + names +
                  " cannot be satisfied: no state satisfies it (correct or remove it; "
                  "projecting the initial state cannot help)"
            : "the constraints " + names +
                  " contradict each other: no state satisfies them together (correct or remove "
                  "one of them; projecting the initial state cannot help)");
    std::erase_if(report.redundant, [&](const std::string& name) {
      return std::find(report.contradictory.begin(), report.contradictory.end(), name) !=
             report.contradictory.end();
    });
  } else if (!report.initial_violations.empty() && !only_penetrated) {
    const bool project = model.project_initial || o.project_initial;
    if (!project) {
      report.problems.push_back(
          "the initial state violates the constraints and `initial: project:` is not true");
    } else if (report.mass_positive_definite) {
      VectorXd q = model.q0, qd = model.qd0;
      Workspace wp(sys, o.solver);
      try {
        set_run_scales(sys, wp, q, qd, t, duration, detail::model_angle_coordinates(model));
        detail::release_open_contacts(sys, wp, q, qd, t);  // (an open gap is no violation)
        const ProjectionResult rp = project_positions(sys, wp, q, t, o.projection);
        const ProjectionResult rv = project_velocities(sys, wp, q, qd, t, o.projection);
        const auto left =
            detail::check_initial_conditions(sys, q, qd, t, o.initial_tolerance, duration, nullptr,
                                             detail::model_angle_coordinates(model));
        if (!rp.converged || !rv.converged || !left.empty()) {
          report.problems.push_back(
              "no consistent initial state near the given one: projection left a violation of " +
              format(std::max(rp.violation, rv.violation)));
        }
      } catch (const std::exception& e) {
        report.problems.push_back(std::string("projecting the initial state failed: ") + e.what());
      }
    }
  }

  // the energy must be finite where the run starts
  if (sys.has_potential() && !std::isfinite(sys.potential_energy(model.q0, t))) {
    report.problems.push_back("the potential energy is not finite at the initial state");
  }
  check_contacts_at_start(model, report);
  check_control(model, report);
  return report;
}

}  // namespace ukdyn

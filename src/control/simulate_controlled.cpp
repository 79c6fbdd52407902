// SPDX-License-Identifier: BSD-3-Clause
// Controlled simulation: the plant (a System that may differ from the controller's nominal
// model) under the control force, run by simulate(); the controlled plant, its quadratures and
// its reports are control/controlled_plant.hpp's stages (controlled_plant.cpp,
// controlled_quadratures.cpp, controlled_reports.cpp). Here the run: the controlled System
// simulated with the quadratures beside it, each sample's control evaluated afresh with the
// run's contact modes, the statistics read from the run's scratch, the plant's energy balance
// with the control's work.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "control/contact_modes.hpp"
#include "control/control_at_start.hpp"
#include "control/controlled_plant.hpp"
#include "control/internal.hpp"
#include "simulation/energy_balance.hpp"
#include "simulation/observed_run.hpp"
#include "simulation/sample_grid.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"

namespace ukdyn {

namespace {

// Whether the last assembly of the requirements in c evaluated every violation the samples
// report (phi, psi of each holonomic or nonholonomic requirement: active and stabilized, so that
// assemble_constraints called its violation(); an inactive one's would be stale). O(K).
bool violations_assembled(const Controller& ctrl, const ControlWorkspace& c) {
  const System& req = ctrl.requirements();
  for (Index k = 0; k < req.constraint_count(); ++k) {
    if (req.constraint(k).kind() == ConstraintKind::kAcceleration) continue;
    if (!c.req.active[std::size_t(k)] || !c.req.stabilization[std::size_t(k)].enabled()) {
      return false;
    }
  }
  return true;
}

}  // namespace

System controlled_system(const Controller& ctrl, const System& plant) {
  control_detail::require_same_plant(ctrl, plant, "ukdyn::controlled_system");
  // the controller's model follows the run's contact modes, which only simulate_controlled
  // hands it
  for (const Constraint& c : plant.constraints()) {
    if (c.is_unilateral()) {
      throw std::invalid_argument(
          "ukdyn::controlled_system: the constraint '" + c.name() +
          "' is unilateral; a controlled plant with contacts runs in simulate_controlled, whose "
          "controller holds the contacts the run holds (docs/contact.md, \"Contacts under "
          "control\")");
    }
  }
  return control_detail::build_controlled(
      std::make_shared<control_detail::ControlledPlant>(ctrl, plant, 0), false);
}

ControlledTrajectory simulate_controlled(
    const Controller& ctrl, const System& plant, const Eigen::Ref<const VectorXd>& q0,
    const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& options,
    const std::function<void(const ControlledTrajectory& sample)>& sample_sink) {
  return control_detail::run_controlled(ctrl, plant, q0, qd0, options, sample_sink, nullptr);
}

control_detail::ControlAtStart control_detail::control_at_start(
    const Controller& ctrl, const System& plant, const Eigen::Ref<const VectorXd>& q0,
    const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& options) {
  ControlAtStart start;
  // stopped once the first sample is recorded; nothing kept, nothing reported on the way
  SimulationOptions o = options;
  o.should_stop = [] { return true; };
  o.sample_sink = nullptr;
  o.progress = nullptr;
  run_controlled(
      ctrl, plant, q0, qd0, o, [](const ControlledTrajectory&) {}, &start);
  return start;
}

ControlledTrajectory control_detail::run_controlled(
    const Controller& ctrl, const System& plant, const Eigen::Ref<const VectorXd>& q0,
    const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& options,
    const std::function<void(const ControlledTrajectory& sample)>& sample_sink,
    ControlAtStart* start) {
  const char* who = "ukdyn::simulate_controlled";
  require_same_plant(ctrl, plant, who);
  const Index n = plant.coordinate_count(), m_r = ctrl.requirement_rows();
  if (q0.size() != n || qd0.size() != n) {
    throw std::invalid_argument(std::string(who) + ": q0 and qd0 need n = " + format_number(n) +
                                " entries, got " + format_number(q0.size()) + " and " +
                                format_number(qd0.size()));
  }
  const bool robust = ctrl.robust().has_value();
  const Index aux = kBounds + (robust ? m_r : 0);
  const auto st = [&] {
    auto p = std::make_shared<ControlledPlant>(ctrl, plant, aux);
    p->units = options.units;
    return std::shared_ptr<const ControlledPlant>(std::move(p));
  }();
  const System sys = build_controlled(st, true);

  // the quadratures z (work, effort, absolute work, bounds), from (0, 0, 0, V_i(0)), their
  // rates from the control of the run's evaluation at each stage; then their integrals y from
  // 0 (as when they were coordinates: a run's steps then stay what they were where its scales
  // did not count them); each weighed by the error control in its unit (quadrature_units,
  // below)
  detail::Quadratures quad = control_quadratures(ctrl, *st, q0, qd0, options.t_start);
  // the requirements' switching times are breakpoints of the dynamics
  SimulationOptions o = options;
  for (const Constraint& c : ctrl.requirements().constraints()) {
    for (double t : {c.active_interval().begin, c.active_interval().end}) {
      if (std::isfinite(t)) o.breakpoints.push_back(t);
    }
  }
  // (the run's own balance misses the control's work: the plant's is checked below)
  o.energy_balance_tolerance = std::numeric_limits<double>::infinity();
  const double tolerance = plant.accounts_for_energy() ? checked_energy_balance_tolerance(options)
                                                       : std::numeric_limits<double>::infinity();

  // the names; the samples go into `run` (kept) or into `one` (each passed to the sink)
  ControlledTrajectory run;
  Trajectory& tr = run.plant;
  tr.coordinate_names = plant.coordinate_names();
  run.row_names = ctrl.row_names();
  run.robust = robust;
  const bool streamed = bool(sample_sink);
  ControlledTrajectory one;
  if (!streamed) {
    // kept in memory: the plant's values and the control's per sample, bounded as simulate()
    // bounds its own (the controlled run itself streams into `run`, one sample at a time)
    const double per_sample =
        double(1 + 5 * n + plant.constraint_rows() + 2 * plant.constraint_count() + 9 + 2 * n +
               (robust ? 3 : 2) * m_r + 4);
    const std::string bound =
        "of a controlled run kept in memory (kMaxStoredValues = 2^28 "
        "values, " +
        format_number(long(per_sample)) + " per sample)";
    (void)detail::SampleGrid(
        options, std::min(kMaxStreamedSamples, std::floor(kMaxStoredValues / per_sample)),
        bound.c_str());
  }
  ControlledTrajectory& out = streamed ? one : run;
  detail::EnergyBalance balance;  // the plant's, with the control's work
  ControlWorkspace cws(ctrl);
  control_detail::ContactModes sample_contacts(ctrl);
  const Workspace* run_ws = nullptr;               // the run's (its modes), once it starts
  const ControlledScratch* run_scratch = nullptr;  // the run's control, once it starts
  std::string pull;
  control_detail::BoundWatch bounds(ctrl, options.t_start);  // |error| against error_bound
  VectorXd q(n), qd(n), qdd(n);
  o.sample_sink = [&](const Trajectory& s) {
    // the plant's sample, and the quadratures z at it
    if (streamed) {
      if (one.plant.coordinate_names.empty()) {
        one.plant.coordinate_names = tr.coordinate_names;
        one.plant.constraint_names = s.constraint_names;
        one.plant.constraint_rows = s.constraint_rows;
        one.plant.constraint_kinds = s.constraint_kinds;
        one.plant.unilateral = s.unilateral;
        one.plant.n = n;
        one.plant.m = s.m;
        one.row_names = run.row_names;
        one.robust = robust;
      }
      for (auto* f : sample_fields(one)) f->clear();
    }
    Trajectory& p = out.plant;
    const double t = s.t[0];
    p.t.push_back(t);
    for (auto [to, from] : {std::pair{&p.q, &s.q},
                            {&p.qd, &s.qd},
                            {&p.qdd, &s.qdd},
                            {&p.Qc_ideal, &s.Qc_ideal},
                            {&p.Qc_nonideal, &s.Qc_nonideal}}) {
      to->insert(to->end(), from->begin(), from->begin() + n);
    }
    for (auto [to, from] : {std::pair{&p.lambda, &s.lambda},
                            {&p.lambda_total, &s.lambda_total},
                            {&p.position_violation, &s.position_violation},
                            {&p.velocity_violation, &s.velocity_violation},
                            {&p.potential_energy, &s.potential_energy},
                            {&p.work_nonideal, &s.work_nonideal},
                            {&p.work_ideal, &s.work_ideal},
                            {&p.work_drive, &s.work_drive},
                            {&p.work_external, &s.work_external}}) {
      to->insert(to->end(), from->begin(), from->end());
    }
    const double* z = quad.sample.data();
    q = Eigen::Map<const VectorXd>(s.q.data(), n);
    qd = Eigen::Map<const VectorXd>(s.qd.data(), n);
    qdd = Eigen::Map<const VectorXd>(s.qdd.data(), n);
    // (the control at the run's first sample with the run's modes, settled as the run's own
    // evaluations settle them: control_at_start's)
    if (start != nullptr && !start->evaluated && run_ws != nullptr) {
      start->evaluated = true;
      ControlWorkspace c0(ctrl);
      control_detail::ContactModes modes(ctrl);
      modes.set_units(options.units);
      modes.mirror(run_ws, c0);
      ControlStatus s0 = compute_control(ctrl, c0, q, qd, t);
      start->status = s0;
      // (a requirement that needs a contact to pull: the run stops, saying pull_failure)
      if (modes.settle(ctrl, c0, q, qd, t, s0, start->pull_failure)) {
        start->status = s0;
        start->held = modes.held_sliding();
        if (s0 != ControlStatus::kOk)
          start->description = control_detail::describe_control_status(ctrl, c0, start->held);
        start->unactuated = explain_unactuated_requirements(ctrl, c0);
        if (modes.slipped() < 0) start->stick_note = modes.stick_note(ctrl);
        if (modes.held_sliding()) start->stick_note = modes.held_note(ctrl);
      }
    }
    // the control at the sample (evaluated afresh at the sample's state)
    // (with the run's contact modes, as in the run's evaluations). The run evaluated the
    // control at the sample's state just before (the sample's q''): without contacts, whose
    // modes the sample settles on its own, its results are this evaluation's, bit for bit
    const ControlWorkspace* at_sample = nullptr;
    if (run_scratch != nullptr && !sample_contacts.any() && run_scratch->t_last == t &&
        std::memcmp(q.data(), run_scratch->q_last.data(), sizeof(double) * std::size_t(n)) == 0 &&
        std::memcmp(qd.data(), run_scratch->qd_last.data(), sizeof(double) * std::size_t(n)) == 0 &&
        (run_scratch->cws.status == ControlStatus::kOk ||
         run_scratch->cws.status == ControlStatus::kRequirementsNotMet)) {
      at_sample = &run_scratch->cws;
    } else {
      sample_contacts.mirror(run_ws, cws);
      ControlStatus cs = compute_control(ctrl, cws, q, qd, t);
      sample_contacts.settle(ctrl, cws, q, qd, t, cs, pull);
      at_sample = &cws;
    }
    // T = q'ᵀ M q' / 2 of the plant: the run's (its M is the plant's, z not being coordinates)
    const double T = s.kinetic_energy[0];
    const double V = s.potential_energy[0];
    p.kinetic_energy.push_back(T);
    p.energy.push_back(T + V);
    p.work_control.push_back(z[kWork]);
    // the impacts' work Σ (T⁺ − T⁻), kept when the plant has contacts (their jumps leave z')
    const double impact = s.work_impact.empty() ? 0.0 : s.work_impact[0];
    if (!s.work_impact.empty()) p.work_impact.push_back(impact);
    const double works[6] = {s.work_nonideal[0], s.work_ideal[0], s.work_drive[0],
                             s.work_external[0], z[kWork],        impact};
    p.energy_balance_residual.push_back(balance.add(t, T, V, T + V, works));

    const ControlWorkspace& c = *at_sample;
    // errors: phi (holonomic), psi (nonholonomic), A_r q'' − b_r (acceleration form); phi and
    // psi are those the run's assembly of the requirements just evaluated at this state (the
    // same violation() call) when every such requirement was active and stabilized there
    const VectorXd accel_residual = c.req.A * qdd - c.req.b;
    const bool assembled = &c != &cws && violations_assembled(ctrl, c);
    if (!assembled) evaluate_violations(ctrl.requirements(), cws.req, q, qd, t);
    const Workspace& v = assembled ? c.req : cws.req;
    for (Index i = 0; i < m_r; ++i) {
      switch (ctrl.requirement(ctrl.row_requirement(i)).kind()) {
        case ConstraintKind::kHolonomic:
          out.error.push_back(v.phi[i]);
          out.error_rate.push_back(v.phi_dot[i]);
          break;
        case ConstraintKind::kNonholonomic:
          out.error.push_back(v.phi_dot[i]);
          out.error_rate.push_back(0.0);
          break;
        case ConstraintKind::kAcceleration:
          out.error.push_back(accel_residual[i]);
          out.error_rate.push_back(0.0);
          break;
      }
    }
    out.Qc_control.insert(out.Qc_control.end(), c.Qc_control.data(), c.Qc_control.data() + n);
    out.Qc_robust.insert(out.Qc_robust.end(), c.Qc_robust.data(), c.Qc_robust.data() + n);
    out.control_power.push_back(c.Qc_control.dot(qd));
    out.control_work.push_back(z[kWork]);
    out.control_effort.push_back(z[kEffort]);
    out.control_work_abs.push_back(z[kWorkAbs]);
    for (Index i = 0; robust && i < m_r; ++i) {
      out.error_bound.push_back(std::sqrt(std::max(z[kBounds + i], 0.0) / ctrl.robust_scale(i)));
      bounds.add(t, i, out.error[out.error.size() - std::size_t(m_r - i)], out.error_bound.back());
    }
    if (streamed) sample_sink(one);
  };
  // the control statistics, read from the run's workspace (its ControlledScratch) at the end
  std::optional<ControlledScratch> after;
  // the run's rate decade (the integrators' atol on q' and on z, Workspace::rate_unit): the
  // plant's own, from its state, as when z were auxiliary coordinates of an augmented system
  // (whose unit masses and integrands, which move with the model's units, it must not count)
  double plant_rate = 1.0;
  {
    Workspace scales(plant);
    set_run_scales(plant, scales, q0, qd0, o.t_start, o.t_end - o.t_start, o.angle_coordinates);
    plant_rate = scales.rate_unit;
    quad.unit = quadrature_units(scales, o.t_end - o.t_start, aux);
  }
  const Trajectory full = detail::simulate_observed(
      sys, q0, qd0, o,
      [&](const Workspace& ws) {
        after.emplace(*st);
        auto& w = static_cast<ControlledScratch&>(*ws.callables);
        w.run_ws = nullptr;
        after->stats = w.stats;
        after->failure = w.failure;
        after->failure_t = w.failure_t;
        after->slip_note = w.slip_note;
        after->slip_t = w.slip_t;
        after->held_note = w.held_note;
        after->q_last = w.q_last;
        after->qd_last = w.qd_last;
        after->t_last = w.t_last;
      },
      [&](Workspace& ws) {
        // the contacts' modes of each workspace of the run (the plant's constraint indices: the
        // controlled system keeps them), for the control's model in its evaluations: the run's
        // own (the first; also the samples'), then the branch check's, whose modes are a copy
        // of the run's (it used to evaluate the control with every contact held)
        auto& scratch = static_cast<ControlledScratch&>(*ws.callables);
        scratch.run_modes = &ws.activity_override;
        scratch.run_ws = &ws;  // (its own evaluation, whose factor of M the control may adopt)
        if (run_scratch == nullptr) {
          run_ws = &ws;
          run_scratch = &scratch;
        }
      },
      plant_rate, &quad);
  const ControlledScratch& w = *after;

  // the names, the statistics and the plant's energy balance
  tr.constraint_names = full.constraint_names;
  tr.constraint_rows = full.constraint_rows;
  tr.constraint_kinds = full.constraint_kinds;
  tr.unilateral = full.unilateral;
  tr.n = n;
  tr.m = full.m;
  tr.stats = full.stats;
  if (!w.slip_note.empty()) {
    // a stick the control breaks at the start never held: the contact slides from the start,
    // its initial mode, and the run locates no slip (as for any contact that cannot stick at
    // the start); the note says so, where the event list shows none (u24)
    std::string note = w.slip_note;
    const bool listed =
        std::any_of(tr.stats.contact_events.begin(), tr.stats.contact_events.end(),
                    [](const ContactEvent& e) { return e.kind == ContactEvent::Kind::kSlip; });
    if (w.slip_t <= o.t_start && !listed) {
      note.insert(std::min(note.rfind(" (docs/contact.md"), note.size()),
                  " from the start: it never stuck, so contact_events lists no slip (its "
                  "initial mode is sliding)");
    }
    tr.stats.notes.push_back(note);
  }
  if (!w.held_note.empty()) tr.stats.notes.push_back(w.held_note);
  // requirements without dynamics that start unmet stay unmet (u21 05)
  if (const std::string why = explain_uncorrected_requirements(ctrl, q0, qd0, options.t_start,
                                                               options.initial_tolerance,
                                                               options.t_end - options.t_start);
      !why.empty())
    tr.stats.notes.push_back(why);
  diagnose_requirements(*st, w, q0, qd0, options.t_start, options.units.time, tr.stats);
  run.control = w.stats;
  bounds.finish(run.control, tr.stats, options.units.time);
  balance.finish(tr.stats, tolerance, options.units);
  // the controller's failure, where it failed in the run's last step (evaluations there lie at
  // or after the last sample; one before it was avoided by a smaller step, and the run failed
  // for its own reason, said by its own message): the run's status is then the controller's
  // (its NaN force made the run's evaluation report a non-finite Q, which the user never gave)
  if (!w.failure.empty() && tr.stats.status != Status::kOk &&
      tr.stats.status != Status::kEnergyBalance && tr.stats.status != Status::kInterrupted &&
      w.failure_t >= tr.stats.t_reached) {
    tr.stats.status = Status::kControlFailed;
    tr.stats.message = "the controller failed: " + w.failure;
  }
  return run;
}

ControlledTrajectory simulate_controlled(const Controller& ctrl, const System& plant,
                                         const Eigen::Ref<const VectorXd>& q0,
                                         const Eigen::Ref<const VectorXd>& qd0,
                                         const SimulationOptions& options) {
  if (!options.sample_sink) return simulate_controlled(ctrl, plant, q0, qd0, options, nullptr);
  // the plant's part of each sample to the options' sink
  SimulationOptions o = options;
  o.sample_sink = nullptr;
  return simulate_controlled(ctrl, plant, q0, qd0, o,
                             [&](const ControlledTrajectory& s) { options.sample_sink(s.plant); });
}

}  // namespace ukdyn

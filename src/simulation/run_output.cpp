// SPDX-License-Identifier: BSD-3-Clause
// The run's output: each sample (q, q', q'', the forces, energies, works, violations) recorded
// into the trajectory or handed to the sample sink, and the progress report (docs/simulation.md,
// "Interrupts and outputs", "Sample grid and streaming"). The class: simulation/run.hpp.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <string>

#include "simulation/run.hpp"

namespace ukdyn::detail {

// records a sample at t from the state x (projected first, when projecting); returns
// kInterrupted after recording it when a stop was requested, unless it is the `last` one
Status Run::record(double t, const double* x, bool last) {
  std::copy(x, x + sample_.size(), sample_.begin());
  if (projecting_) {
    bool changed = false;
    ProjectionOptions quiet = projection_;
    if (const Status s = project(t, sample_.data(), quiet, changed); s != Status::kOk) return s;
  }
  q_ = Eigen::Map<const VectorXd>(sample_.data(), n_);
  qd_ = Eigen::Map<const VectorXd>(sample_.data() + n_, n_);
  const Status s = forward_dynamics(sys_, ws_, q_, qd_, t);
  // several contacts sticking: the split of their holding forces that every cone admits, closest
  // to the minimum-norm one (run_stick_slip.cpp, holding_split)
  if (s == Status::kOk && sticking_contacts() > 1 && holding_split(t) == 0) ws_.lambda += split_;
  // into the trajectory kept, or into one_ for the sink
  const bool streamed = bool(o_.sample_sink);
  Trajectory& out = streamed ? one_ : traj_;
  if (streamed) {
    for (auto* f : {&one_.t,
                    &one_.q,
                    &one_.qd,
                    &one_.qdd,
                    &one_.Qc_ideal,
                    &one_.Qc_nonideal,
                    &one_.lambda,
                    &one_.lambda_total,
                    &one_.position_violation,
                    &one_.velocity_violation,
                    &one_.kinetic_energy,
                    &one_.potential_energy,
                    &one_.energy,
                    &one_.work_nonideal,
                    &one_.work_ideal,
                    &one_.work_drive,
                    &one_.work_external,
                    &one_.work_control,
                    &one_.work_impact,
                    &one_.energy_balance_residual}) {
      f->clear();
    }
  }
  auto push = [](std::vector<double>& f, const Eigen::Ref<const VectorXd>& v) {
    f.insert(f.end(), v.data(), v.data() + v.size());
  };
  out.t.push_back(t);
  push(out.q, q_);
  push(out.qd, qd_);
  push(out.qdd, ws_.qdd);
  push(out.Qc_ideal, ws_.Qc_ideal);
  push(out.Qc_nonideal, ws_.Qc_nonideal);
  push(out.lambda, ws_.lambda);
  const bool nonideal = ws_.lambda_nonideal.size() == ws_.lambda.size();
  // the stick rows of each sticking contact: the whole multiplier lambda + lambda_nonideal, the
  // holding force its slip is decided by (stick_margin_here, holding_split: Λ), not the ideal
  // share alone, which misses the part of another contact's sliding friction this one carries
  // (a rod turning about its held end A while B slides: −4.54 N for A's −6.73 N)
  if (nonideal) {
    const auto& contacts = sys_.friction_contacts();
    double* first = out.lambda.data() + (out.lambda.size() - std::size_t(ws_.lambda.size()));
    for (std::size_t c = 0; c < mode_.size(); ++c) {
      const Index k = contacts[c].stick_constraint;
      if (mode_[c] != ContactMode::kSticking || k < 0 || !ws_.active[std::size_t(k)]) continue;
      const Index r = sys_.row_offset(k), rows = sys_.constraint(k).rows();
      // (where it carries none, the ideal share as it was, bit for bit: −0 stays −0)
      for (Index j = r; j < r + rows; ++j)
        if (ws_.lambda_nonideal[j] != 0.0) first[j] += ws_.lambda_nonideal[j];
    }
  }
  // the unilateral constraints' whole multipliers (their contact forces)
  for (Index k : traj_.unilateral) {
    const Index r = sys_.row_offset(k);
    out.lambda_total.push_back(ws_.lambda[r] + (nonideal ? ws_.lambda_nonideal[r] : 0.0));
  }
  const double T = detail::kinetic_energy(ws_, qd_),
               V = sys_.potential_energy(q_, t, ws_.callables.get());
  out.kinetic_energy.push_back(T);
  out.potential_energy.push_back(V);
  out.energy.push_back(T + V);
  peak_kinetic_ = std::max(peak_kinetic_, T);
  // (T + |V| at the start, as the divergence message says; the run's energy unit, the power of
  // two nearest to max(T + |V|, |Q| l), where that is 0: a body released at rest at V = 0 has
  // no energy yet)
  if (!(energy_scale_ > 0.0)) {
    energy_scale_ = T + std::abs(V) > 0.0 ? T + std::abs(V) : ws_.energy_unit;
  }
  // the work channels (absent ones are zero), and the balance so far
  const auto work = [&](Index channel) {
    return channel < 0
               ? 0.0
               : sample_[std::size_t(2 * n_ + channel)] / works_.scale(channel, ws_.energy_unit);
  };
  const double works[6] = {work(works_.nonideal),
                           work(works_.ideal),
                           work(works_.drive),
                           work(works_.external),
                           0.0,
                           contacts_ ? contacts_->impact_work() : 0.0};
  out.work_nonideal.push_back(works[0]);
  out.work_ideal.push_back(works[1]);
  out.work_drive.push_back(works[2]);
  out.work_external.push_back(works[3]);
  out.work_control.push_back(works[4]);
  if (contacts_) out.work_impact.push_back(works[5]);
  out.energy_balance_residual.push_back(balance_.add(t, T, V, T + V, works));
  // a caller's quadratures at this sample, for its sink
  if (works_.quadrature >= 0) {
    const auto z = sample_.begin() + 2 * n_ + works_.quadrature;
    std::copy(z, z + quad_->count, quad_->sample.begin());
  }
  // violations of each constraint
  evaluate_violations(sys_, ws_, q_, qd_, t);
  for (Index k = 0; k < sys_.constraint_count(); ++k) {
    // (a constraint given in acceleration form only, A q'' = b, has no position or velocity
    // function: its violations are unknown, NaN, never 0; unmeasured_violations notes it)
    if (sys_.constraint(k).kind() == ConstraintKind::kAcceleration && ws_.active[std::size_t(k)]) {
      out.position_violation.push_back(std::numeric_limits<double>::quiet_NaN());
      out.velocity_violation.push_back(std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    const double p = position_violation(sys_, ws_, k), v = velocity_violation(sys_, ws_, k);
    out.position_violation.push_back(p);
    out.velocity_violation.push_back(v);
    note_violation(p, v);
  }
  ++traj_.stats.samples;
  last_time_ = t;
  // the sample to the sink; what it throws stops the run (the driver rethrows it)
  if (streamed) {
    try {
      o_.sample_sink(one_);
    } catch (...) {
      sink_error_ = std::current_exception();
      failure_ = "the sample sink failed at t = " + format(t);
      return Status::kInterrupted;
    }
  }
  // the samples recorded (or passed) by now
  while (samples_ && next_sample_ < samples_->size() && (*samples_)[next_sample_] <= t) {
    ++next_sample_;
  }
  if (s != Status::kOk) {
    failure_ = describe_status(sys_, ws_);
    return s;
  }
  return !last && stop_requested() ? Status::kInterrupted : Status::kOk;
}

// step size from the times the steps reach (BDF reports converged attempts, so a rejected
// attempt can make t go back: then the step is unknown and the last one is kept)
void Run::report_progress(double t) {
  if (progress_.steps > 0 && t > progress_.t) progress_.step = t - progress_.t;
  progress_.t = t;
  ++progress_.steps;
  o_.progress(progress_);
}

void unmeasured_violations(const System& sys, RunStatistics& stats) {
  std::string names;
  for (const Constraint& c : sys.constraints()) {
    if (c.kind() == ConstraintKind::kAcceleration)
      names += (names.empty() ? "'" : ", '") + c.name() + "'";
  }
  if (names.empty()) return;
  stats.max_position_violation = std::numeric_limits<double>::quiet_NaN();
  stats.max_velocity_violation = std::numeric_limits<double>::quiet_NaN();
  if (stats.notes.size() < kMaxNotes) {
    const bool one = names.find(',') == std::string::npos;
    stats.notes.push_back(
        std::string(one ? "the constraint " : "the constraints ") + names +
        " given in acceleration form only (A q'' = b) " + (one ? "has" : "have") +
        " no position or velocity function: " +
        (one ? "its violation is" : "their violations are") +
        " unknown (NaN in the violation.* column" + (one ? "" : "s") +
        " and in max_position_violation, max_velocity_violation), and drift control cannot "
        "correct " +
        (one ? "it" : "them") +
        ". Give the position-level function (a holonomic: constraint, or ukdyn.from_sympy) "
        "to measure and correct the drift");
  }
}

void unsettled_reactions(const System& sys, const Workspace& ws, const UnitSystem& units,
                         RunStatistics& stats) {
  const std::int64_t count = ws.counters.nonideal_unsettled;
  if (count == 0 || stats.notes.size() >= kMaxNotes) return;
  const UnsettledReactions& u = ws.unsettled;
  // t = first [to last] unit
  std::string when = "t = " + format(u.first_t);
  if (u.last_t != u.first_t) when += " to " + format(u.last_t);
  when += " " + units.time;
  const Index k = u.worst_constraint;
  const std::string name =
      k >= 0 && k < sys.constraint_count() ? "'" + sys.constraint(k).name() + "'" : "a constraint";
  stats.notes.push_back(
      when + ": the non-ideal forces did not settle on the reactions they cause in " +
      format_number(count) + (count == 1 ? " evaluation" : " evaluations") +
      " (their fixed point, docs/friction.md §1): the worst, at t = " + format(u.worst_t) + " " +
      units.time + ", still moved the reaction of " + name + " by " + format(u.worst_residual) +
      " of the largest reaction in its last round, and the motion there used that round's "
      "forces (a Coulomb contact sliding at or past Painlevé's critical mu, or a force whose "
      "feedback through the reactions has no consistent value)");
}

}  // namespace ukdyn::detail

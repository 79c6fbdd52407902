// SPDX-License-Identifier: BSD-3-Clause
// JSON summary of a run: statistics, final state and the options given.
#include "ukdyn/io/trajectory_files.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "ukdyn/control/control.hpp"
#include "ukdyn/simulation/options.hpp"

#include "io/atomic_file.hpp"

namespace ukdyn {
namespace {

constexpr const char* kSummaryWho = "ukdyn::write_summary_json";

void write_summary_json_text(const std::string& text, const std::string& path);

}  // namespace

std::string summary_json(const Trajectory& traj, const SimulationOptions& options,
                         const RunProvenance* provenance, const ControlStatistics* control) {
  using nlohmann::json;
  traj.check_consistent("ukdyn::summary_json");
  const RunStatistics& s = traj.stats;
  const std::size_t N = traj.t.size(), n = std::size_t(traj.n);

  // statistics of the run (NaN and Inf, which JSON lacks, are written as null)
  json j = json::object();
  j["status"] = to_string(s.status);
  j["message"] = s.message;
  j["steps"] = s.steps;
  j["rejected_steps"] = s.rejected_steps;
  j["evaluations"] = s.evaluations;
  j["least_squares"] = s.least_squares;
  j["tangential_steps"] = s.tangential_steps;
  j["projected_stage_steps"] = s.projected_stage_steps;
  j["projections"] = s.projections;
  j["events"] = s.events;
  j["switch_events"] = s.switch_events;
  j["stick_refusals"] = s.stick_refusals;
  j["notes"] = s.notes;
  // the contacts' events (docs/contact.md, "In a run"), by constraint name: the plots and the
  // viewer mark the impacts (present when the system has unilateral contacts: work_impact is
  // then kept, or when the run listed a stick or slip of Coulomb friction); the keys of a
  // release, a stick and a slip besides (NaN, which JSON lacks, as null)
  if (!traj.work_impact.empty() || !s.contact_events.empty()) {
    auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
    json contacts = json::array();
    for (const ContactEvent& e : s.contact_events) {
      const auto k = std::size_t(e.constraint);
      json entry = {{"t", e.t},
                    {"contact", k < traj.constraint_names.size() ? json(traj.constraint_names[k])
                                                                 : json(nullptr)},
                    {"kind", to_string(e.kind)},
                    {"speed_before", e.speed_before},
                    {"speed_after", e.speed_after},
                    {"impulse", e.impulse},
                    {"energy_change", e.energy_change}};
      if (e.kind == ContactEvent::Kind::kRelease) entry["force_before"] = number(e.force_before);
      if (e.kind == ContactEvent::Kind::kStick || e.kind == ContactEvent::Kind::kSlip) {
        entry["friction"] = e.friction;
        entry["holding_force"] = number(e.holding_force);
        entry["friction_limit"] = number(e.friction_limit);
      }
      contacts.push_back(std::move(entry));
    }
    j["contact_events"] = std::move(contacts);
  }
  j["stiff_switches"] = s.stiff_switches;
  j["stiff_switch_time"] =
      std::isfinite(s.stiff_switch_time) ? json(s.stiff_switch_time) : json(nullptr);
  j["stiff_steps"] = s.stiff_steps;
  j["wall_time"] = s.wall_time;
  j["max_position_violation"] = s.max_position_violation;
  j["max_velocity_violation"] = s.max_velocity_violation;
  j["energy_balance"] = s.energy_balance;
  j["energy_exchanged"] = s.energy_exchanged;
  j["energy_balance_tolerance"] = options.energy_balance_tolerance;
  j["energy_balance_checked"] = s.energy_balance_checked;
  j["energy_drift"] = s.energy_drift;

  // time span and the last sample by coordinate name (null when there is no sample)
  // (a streamed run's trajectory holds its last sample only: stats.samples counts them all)
  const bool streamed = s.samples > long(N);
  j["t_start"] = streamed ? json(options.t_start) : N > 0 ? json(traj.t.front()) : json(nullptr);
  j["t_reached"] = s.t_reached;
  j["samples"] = streamed ? std::size_t(s.samples) : N;
  if (N > 0) {
    json q = json::object(), qd = json::object();
    for (std::size_t c = 0; c < n; ++c) {
      q[traj.coordinate_names[c]] = traj.q[(N - 1) * n + c];
      qd[traj.coordinate_names[c]] = traj.qd[(N - 1) * n + c];
    }
    j["final_state"] = {{"q", std::move(q)}, {"q_dot", std::move(qd)}};
  } else {
    j["final_state"] = nullptr;
  }
  j["constraints"] = traj.constraint_names;

  // the options given: every option of the table (simulation/options.hpp), and the per-constraint
  // drift
  json given = json::object();
  for (const OptionInfo& info : option_table()) {
    const OptionValue v = info.get(options);
    if (const bool* b = std::get_if<bool>(&v))
      given[info.name] = *b;
    else if (const long* l = std::get_if<long>(&v))
      given[info.name] = *l;
    else if (const double* d = std::get_if<double>(&v))
      given[info.name] = *d;
    else if (const std::string* text = std::get_if<std::string>(&v))
      given[info.name] = *text;
    else
      given[info.name] = std::get<std::vector<double>>(v);
  }
  json drift_per_constraint = json::object();
  for (const auto& [name, d] : options.drift_per_constraint) {
    drift_per_constraint[name] = {
        {"method", to_string(d.method)}, {"alpha", d.alpha}, {"beta", d.beta}};
  }
  given["drift_per_constraint"] = std::move(drift_per_constraint);
  j["options"] = std::move(given);

  if (control) {
    j["control"] = {
        {"evaluations", control->evaluations},
        {"not_met", control->not_met},
        {"max_residual", control->max_residual},
        {"first_not_met",
         std::isfinite(control->first_not_met) ? json(control->first_not_met) : json(nullptr)},
        {"not_met_message", control->not_met_message},
        {"max_kappa", control->max_kappa},
        {"bound_exceeded_at", std::isfinite(control->bound_exceeded_at)
                                  ? json(control->bound_exceeded_at)
                                  : json(nullptr)},
        {"bound_worst_ratio", control->bound_worst_ratio},
        {"bound_worst_row", control->bound_worst_row},
        {"bound_worst_time", std::isfinite(control->bound_worst_time)
                                 ? json(control->bound_worst_time)
                                 : json(nullptr)}};
  }
  // what the run was made from (io/provenance.hpp)
  json made = {{"ukdyn_version", version()}, {"ukdyn_commit", commit()}};
  if (provenance) {
    const RunProvenance& p = *provenance;
    made["model_name"] = p.model_name;
    made["model_file"] = p.model_file.empty() ? json(nullptr) : json(p.model_file);
    made["example"] = p.example.empty() ? json(nullptr) : json(p.example);
    made["model_sha256"] = p.model_sha256;
    json parameters = json::object(), overridden = json::array();
    for (const ProvenanceParameter& q : p.parameters) {
      parameters[q.name] = q.value;
      if (q.overridden) overridden.push_back(q.name);
    }
    made["parameters"] = std::move(parameters);
    made["overridden"] = std::move(overridden);
    made["arguments"] = p.arguments;
  }
  j["provenance"] = std::move(made);
  // each coordinate's unit ("" not known), for the plots' labels (ukdyn/plotting.py)
  if (provenance && !provenance->units.empty()) {
    json units = json::object();
    for (const auto& [name, unit] : provenance->units) {
      if (!units.contains(name)) units[name] = unit;  // (a name twice: the first)
    }
    j["units"] = std::move(units);
  }
  // the base units and the derived labels (UnitSystem: J, N, W only in SI units)
  if (provenance && !provenance->unit_system.empty()) {
    json system = json::object();
    for (const auto& [name, unit] : provenance->unit_system) system[name] = unit;
    j["unit_system"] = std::move(system);
  }

  // names are user text: invalid UTF-8 is replaced (U+FFFD) rather than refused
  std::string text = j.dump(2, ' ', false, json::error_handler_t::replace);
  text += '\n';
  return text;
}

void write_summary_json(const Trajectory& traj, const SimulationOptions& options,
                        const std::string& path) {
  write_summary_json_text(summary_json(traj, options), path);
}

void write_summary_json(const Trajectory& traj, const SimulationOptions& options,
                        const std::string& path, const RunProvenance& provenance,
                        const ControlStatistics* control) {
  write_summary_json_text(summary_json(traj, options, &provenance, control), path);
}

namespace {
void write_summary_json_text(const std::string& text, const std::string& path) {
  // a temporary beside `path`, renamed over it when complete (io/atomic_file.hpp)
  detail::write_whole_file(path, kSummaryWho, text.data(), text.size());
}
}  // namespace

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// The settings of a run, checked before it starts (docs/simulation.md, "Settings"): the names of
// the integrators and drift controls, check_settings (every SimulationOptions value a run cannot
// use, as a SettingError naming it), the sizes of the initial state (validate), and the times the
// run is cut at: its samples (sample_grid) and its segments' ends (segment_ends).
#include "ukdyn/simulation/simulate.hpp"

#include "ukdyn/simulation/options.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "simulation/run.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn {

const char* to_string(Integrator integrator) {
  switch (integrator) {
    case Integrator::kRK4:
      return "rk4";
    case Integrator::kRK5:
      return "rk5";
    case Integrator::kDopri5:
      return "dopri5";
    case Integrator::kRKF78:
      return "rkf78";
    case Integrator::kBDF:
      return "bdf";
  }
  return "unknown";
}

Integrator integrator_from_string(const std::string& name) {
  for (Integrator i : {Integrator::kRK4, Integrator::kRK5, Integrator::kDopri5, Integrator::kRKF78,
                       Integrator::kBDF}) {
    if (name == to_string(i)) return i;
  }
  throw std::invalid_argument("ukdyn: unknown integrator '" + name +
                              "'; the integrators are rk4, rk5, dopri5, rkf78, bdf");
}

double checked_energy_balance_tolerance(const SimulationOptions& o) {
  constexpr double kBalancePerRtol = 1e3;
  const bool adaptive = o.integrator == Integrator::kDopri5 || o.integrator == Integrator::kRKF78 ||
                        o.integrator == Integrator::kBDF;
  return adaptive ? std::max(o.energy_balance_tolerance, kBalancePerRtol * o.rtol)
                  : o.energy_balance_tolerance;
}

const char* to_string(DriftControl drift) {
  switch (drift) {
    case DriftControl::kNone:
      return "none";
    case DriftControl::kBaumgarte:
      return "baumgarte";
    case DriftControl::kProjection:
      return "projection";
  }
  return "unknown";
}

DriftControl drift_from_string(const std::string& name) {
  for (DriftControl d :
       {DriftControl::kNone, DriftControl::kBaumgarte, DriftControl::kProjection}) {
    if (name == to_string(d)) return d;
  }
  throw std::invalid_argument("ukdyn: unknown drift control '" + name +
                              "'; the choices are none, baumgarte, projection");
}

namespace detail {

// the sizes of q0, qd0 and the per-constraint drift settings (the run's other settings:
// check_settings)
void validate(const System& sys, const Eigen::Ref<const VectorXd>& q0,
              const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& o) {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("ukdyn::simulate: " + what);
  };
  if (q0.size() != sys.coordinate_count() || qd0.size() != sys.coordinate_count()) {
    fail("q0 and qd0 need n = " + format_number(sys.coordinate_count()) + " entries, got " +
         format_number(q0.size()) + " and " + format_number(qd0.size()));
  }
  // a non-finite initial state is misuse, named like forward_dynamics names it
  for (Index i = 0; i < sys.coordinate_count(); ++i) {
    if (std::isfinite(q0[i]) && std::isfinite(qd0[i])) continue;
    const bool in_q = !std::isfinite(q0[i]);
    fail(std::string(in_q ? "q0" : "qd0") + " is not finite at coordinate '" +
         sys.coordinate_names()[std::size_t(i)] + "' (" + format(in_q ? q0[i] : qd0[i]) + ")");
  }
  if (!o.angle_coordinates.empty() && Index(o.angle_coordinates.size()) != sys.coordinate_count()) {
    fail("angle_coordinates needs n = " + format_number(sys.coordinate_count()) +
         " entries (one per coordinate) or none (every coordinate a length), got " +
         format_number(Index(o.angle_coordinates.size())));
  }
  for (const auto& [name, d] : o.drift_per_constraint) {
    sys.constraint_index(name);  // throws naming the unknown constraint
    if (!(d.alpha >= 0.0 && d.beta >= 0.0 && std::isfinite(d.alpha) && std::isfinite(d.beta))) {
      throw SettingError("drift_per_constraint", "ukdyn::simulate: Baumgarte gains of '" + name +
                                                     "' must be finite and >= 0");
    }
  }
}

namespace {

// the resolution of the run's times: sorted_times merges samples and segment ends closer than this
double time_resolution(double a, double b) {
  return 1e-12 * std::max({1.0, std::abs(a), std::abs(b)});
}

// sorted, de-duplicated times in [a, b]
std::vector<double> sorted_times(std::vector<double> v, double a, double b) {
  v.erase(std::remove_if(v.begin(), v.end(),
                         [&](double t) { return !(t >= a && t <= b) || !std::isfinite(t); }),
          v.end());
  std::sort(v.begin(), v.end());
  const double eps = 1e-12 * std::max({1.0, std::abs(a), std::abs(b)});
  std::vector<double> out;
  for (double t : v) {
    if (out.empty() || t - out.back() > eps) out.push_back(t);
  }
  return out;
}

}  // namespace

// the run's sample times (t_start, every output_every, output_at, t_end), refused above the
// bound of a streamed run, or of one kept in memory (values per sample: t, q, q', q'', Qc_ideal,
// Qc_nonideal, lambda, two violations per constraint, three energies, six works)
detail::SampleGrid sample_grid(const System& sys, const SimulationOptions& o) {
  if (o.sample_sink) {
    return detail::SampleGrid(o, kMaxStreamedSamples, "of a streamed run (kMaxStreamedSamples)");
  }
  const double per_sample = double(1 + 5 * sys.coordinate_count() + sys.constraint_rows() +
                                   2 * sys.constraint_count() + 9);
  const std::string bound = "of a run kept in memory (kMaxStoredValues = 2^28 values, " +
                            format_number(long(per_sample)) +
                            " per sample; a SimulationOptions::sample_sink streams up to 1e9)";
  return detail::SampleGrid(
      o, std::min(kMaxStreamedSamples, std::floor(kMaxStoredValues / per_sample)), bound.c_str());
}

// the segments' ends: t_start, breakpoints inside, t_end
std::vector<double> segment_ends(const System& sys, const SimulationOptions& o) {
  std::vector<double> v = o.breakpoints;
  for (const auto& c : sys.constraints()) {
    v.push_back(c.active_interval().begin);
    v.push_back(c.active_interval().end);
  }
  v.push_back(o.t_start);
  v.push_back(o.t_end);
  return sorted_times(std::move(v), o.t_start, o.t_end);
}

}  // namespace detail

void check_settings(const System& sys, const SimulationOptions& o) {
  using detail::format, detail::kRaiseMaxSteps, detail::sample_grid, detail::segment_ends,
      detail::time_resolution;
  auto fail = [](const char* setting, const std::string& what) {
    throw SettingError(setting, "ukdyn::simulate: " + std::string(setting) + " " + what);
  };
  auto finite = [](double v) { return std::isfinite(v); };
  // the run's interval: finite, and longer than the resolution of its times
  if (!finite(o.t_start)) fail("t_start", "(" + format(o.t_start) + ") must be a finite number");
  if (!finite(o.t_end)) fail("t_end", "(" + format(o.t_end) + ") must be a finite number");
  if (!(o.t_end - o.t_start > time_resolution(o.t_start, o.t_end))) {
    fail("t_end", "(" + format(o.t_end) + ") must exceed t_start (" + format(o.t_start) +
                      ") by more than 1e-12 max(1, |t_start|, |t_end|) = " +
                      format(time_resolution(o.t_start, o.t_end)) +
                      ", the resolution of the run's times");
  }
  if (!(o.step > 0.0) || !finite(o.step))
    fail("step", "must be a finite number > 0, got " + format(o.step));
  if (!(o.rtol > 0.0) || !finite(o.rtol))
    fail("rtol", "must be a finite number > 0, got " + format(o.rtol));
  if (!(o.atol > 0.0) || !finite(o.atol))
    fail("atol", "must be a finite number > 0, got " + format(o.atol));
  if (!(o.output_every >= 0.0) || !finite(o.output_every)) {
    fail("output_every",
         "must be a finite number >= 0 (0: only t_start and t_end), got " + format(o.output_every));
  }
  for (std::size_t i = 0; i < o.output_at.size(); ++i) {
    const double t = o.output_at[i];
    if (!(t >= o.t_start && t <= o.t_end)) {
      fail("output_at", "time " + format(t) + " (entry " + format_number(i) +
                            ") is outside the run [" + format(o.t_start) + ", " + format(o.t_end) +
                            "]");
    }
  }
  if (!(o.max_step >= 0.0))
    fail("max_step", "must be >= 0 (0: unlimited), got " + format(o.max_step));
  if (!(o.energy_balance_tolerance > 0.0)) {
    fail("energy_balance_tolerance",
         "must be > 0 (infinity: no check), got " + format(o.energy_balance_tolerance));
  }
  if (o.max_steps <= 0) fail("max_steps", "must be positive, got " + format_number(o.max_steps));
  if (!(o.baumgarte_alpha >= 0.0) || !finite(o.baumgarte_alpha)) {
    fail("baumgarte_alpha", "must be a finite number >= 0, got " + format(o.baumgarte_alpha));
  }
  if (!(o.baumgarte_beta >= 0.0) || !finite(o.baumgarte_beta)) {
    fail("baumgarte_beta", "must be a finite number >= 0, got " + format(o.baumgarte_beta));
  }
  if (!(o.initial_tolerance >= 0.0) || !finite(o.initial_tolerance)) {
    fail("initial_tolerance", "must be a finite number >= 0, got " + format(o.initial_tolerance));
  }
  if (!(o.projection.tolerance > 0.0) || !finite(o.projection.tolerance)) {
    fail("projection_tolerance", "(projection.tolerance) must be a finite number > 0, got " +
                                     format(o.projection.tolerance));
  }
  // every option within the range of the options table (simulation/options.hpp): the ones not
  // checked above
  try {
    check_options(o);
  } catch (const OptionError& e) {
    throw SettingError(e.setting(), "ukdyn::simulate: " + e.problem());
  }
  const double resolution = 16.0 * std::numeric_limits<double>::epsilon() *
                            std::max(std::abs(o.t_start), std::abs(o.t_end));
  // the adaptive methods held to max_step: a step that t resolves, and a run that max_steps
  // allows — at least (t_end − t_start) / max_step steps (else the run would crawl towards
  // max_steps for hours, e.g. max_step = 1e-300)
  if (o.max_step > 0.0 && o.integrator != Integrator::kRK4 && o.integrator != Integrator::kRK5) {
    if (!(o.max_step >= resolution)) {
      fail("max_step", "(" + format(o.max_step) + ") is below the resolution of t on [" +
                           format(o.t_start) + ", " + format(o.t_end) +
                           "], 16 eps max(|t_start|, |t_end|) = " + format(resolution) +
                           " (0: unlimited)");
    }
    const double least = (o.t_end - o.t_start) / o.max_step;
    if (least > double(o.max_steps)) {
      fail("max_step", "(" + format(o.max_step) + ") needs at least " + format(least) +
                           " steps over [" + format(o.t_start) + ", " + format(o.t_end) +
                           "], more than max_steps = " + format_number(o.max_steps) +
                           " (a larger max_step, or raise max_steps: " + kRaiseMaxSteps + ")");
    }
  }
  // the fixed-step methods: a step that t resolves, and at most max_steps of them
  if (o.integrator == Integrator::kRK4 || o.integrator == Integrator::kRK5) {
    if (!(o.step >= resolution)) {
      fail("step", "(" + format(o.step) + ") of " + to_string(o.integrator) +
                       " is below the resolution of t on [" + format(o.t_start) + ", " +
                       format(o.t_end) +
                       "], 16 eps max(|t_start|, |t_end|) = " + format(resolution));
    }
    // samples no closer than the steps (between steps they would be interpolated, not
    // integrated)
    if (o.output_every > 0.0 && o.output_every < o.step) {
      fail("output_every", "(" + format(o.output_every) + ") is below the step (" + format(o.step) +
                               ") of " + to_string(o.integrator) +
                               ": take a step <= output_every, or output_every >= step");
    }
    // the steps of each segment, as integrate_explicit takes them (counted in double: the
    // count may exceed any integer)
    const std::vector<double> ends = segment_ends(sys, o);
    double steps = 0.0;
    for (std::size_t k = 0; k + 1 < ends.size(); ++k) {
      steps += std::max(1.0, std::ceil((ends[k + 1] - ends[k]) / o.step * (1.0 - 1e-12)));
    }
    if (steps > double(o.max_steps)) {
      fail("step", "(" + format(o.step) + ") of " + to_string(o.integrator) + " takes " +
                       format(steps) + " steps over [" + format(o.t_start) + ", " +
                       format(o.t_end) + "], more than max_steps = " + format_number(o.max_steps) +
                       " (take a larger step, or raise max_steps: " + kRaiseMaxSteps + ")");
    }
  }
  // the sample grid: within the bound of a streamed run (o.sample_sink) or of one kept in memory,
  // its spacing above the resolution of t (SettingError naming output_every or output_at)
  (void)sample_grid(sys, o);
}

}  // namespace ukdyn

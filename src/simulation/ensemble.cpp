// SPDX-License-Identifier: BSD-3-Clause
// Ensembles (simulation/ensemble.hpp): many runs of one model file on a pool of std::threads.
//
// Why std::thread and not oneTBB: a sample is a whole run (milliseconds to minutes), so the pool
// needs nothing but a shared counter from which each free thread takes the next sample — dynamic
// scheduling without work stealing. The standard library does that in a few lines, adds no
// dependency to libukdyn.a's consumers (find_package(ukdyn) would have to find TBB), and keeps the
// threads the ensemble's own, so that ThreadSanitizer sees every one and cancellation is a flag.
// parse_model serializes the readings of the samples that change parameters (GiNaC).
#include "ukdyn/simulation/ensemble.hpp"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>
#include <utility>

#include <nlohmann/json.hpp>

#include "io/atomic_file.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/modelfile/run.hpp"

namespace ukdyn {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// "a, b, c"
std::string comma_list(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// The coordinate a sample's initial value sets: its index and whether the value is its velocity,
// by the coordinate's name or its spelling in expressions (a body's cart.x is cart_x there): x,
// x_dot, cart.x, cart_x, cart.x_dot, cart_x_dot. {-1, false} for none. Cost O(n).
std::pair<Index, bool> coordinate_of(const std::vector<std::string>& coords,
                                     const std::string& name) {
  for (std::size_t k = 0; k < coords.size(); ++k) {
    std::string spelled = coords[k];
    std::replace(spelled.begin(), spelled.end(), '.', '_');
    if (name == coords[k] || name == spelled) return {Index(k), false};
    if (name == coords[k] + "_dot" || name == spelled + "_dot") return {Index(k), true};
  }
  return {-1, false};
}

// What a sample's name sets, checked against the model once before any run.
void check_sample_names(const Model& base, const std::vector<EnsembleSample>& samples) {
  const auto& coords = base.system.coordinate_names();
  auto is_coordinate = [&](const std::string& name) {
    return coordinate_of(coords, name).first >= 0;
  };
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const EnsembleSample& s = samples[i];
    const std::string who = "ukdyn::run_ensemble: sample " + std::to_string(i) + ": ";
    for (const auto& kv : s.parameters) {
      if (!base.parameters.count(kv.first)) {
        std::vector<std::string> known;
        for (const auto& p : base.parameters) known.push_back(p.first);
        throw std::invalid_argument(who + "the model has no parameter '" + kv.first +
                                    "' (its parameters are " + comma_list(known) + ")");
      }
    }
    for (const auto& kv : s.initial) {
      if (!is_coordinate(kv.first)) {
        throw std::invalid_argument(who + "'" + kv.first +
                                    "' is not a coordinate or velocity of the model (its "
                                    "coordinates are " +
                                    comma_list(coords) + ")");
      }
      if (s.parameters.count(kv.first)) {
        throw std::invalid_argument(who + "'" + kv.first + "' is set twice");
      }
      // (the same coordinate by its two spellings, cart.x and cart_x)
      for (const auto& other : s.initial) {
        if (other.first < kv.first &&
            coordinate_of(coords, other.first) == coordinate_of(coords, kv.first)) {
          throw std::invalid_argument(who + "'" + other.first + "' and '" + kv.first +
                                      "' set the same coordinate");
        }
      }
    }
    for (const auto& kv : s.settings) {
      const OptionInfo* info = find_option(kv.first);
      if (!info || (info->type != OptionType::kNumber && info->type != OptionType::kInteger)) {
        throw std::invalid_argument(who + "'" + kv.first +
                                    "' is not a numeric option of the table (the options are " +
                                    option_names() + ")");
      }
      if (s.parameters.count(kv.first) || s.initial.count(kv.first)) {
        throw std::invalid_argument(who + "'" + kv.first + "' is set twice");
      }
    }
  }
}

// The shared state of one ensemble: the description, read-only, and the counters of its pool.
struct Pool {
  const EnsembleModel& model;
  const std::vector<EnsembleSample>& samples;
  const EnsembleOptions& options;
  const Model& base;                         // the model read with model.overrides only
  const SimulationOptions& base_options;     // its settings with model.settings
  const std::vector<std::string>& recorded;  // the recorded columns
  std::vector<SampleResult>& results;        // one per sample, each written by one thread

  std::atomic<std::size_t> next{0};   // the next sample to take
  std::atomic<bool> stopping{false};  // should_stop said so, or a misuse was found
  std::mutex progress_mutex;          // progress counters and callback, misuse text
  EnsembleProgress progress;
  std::string misuse;         // a recorded output that is not a column (found by the first run)
  std::exception_ptr thrown;  // the first exception that left a worker (options.progress's)

  // keeps the first exception that would have left a worker thread, and stops the others
  void keep_exception(std::exception_ptr e) {
    {
      const std::lock_guard<std::mutex> lock(progress_mutex);
      if (!thrown) thrown = std::move(e);
    }
    stopping = true;
  }

  bool stop_requested() {
    if (stopping.load(std::memory_order_relaxed)) return true;
    if (options.should_stop && options.should_stop()) {
      stopping = true;
      return true;
    }
    return false;
  }
};

// Runs sample i into pool.results[i].
void run_sample(Pool& pool, std::size_t i) {
  const EnsembleSample& sample = pool.samples[i];
  SampleResult& out = pool.results[i];
  const std::size_t n_at = std::max<std::size_t>(pool.options.at.size(), 1);
  const std::size_t n_rec = pool.recorded.size();
  out.values.assign(n_at * n_rec, kNaN);
  out.trajectory.clear();

  // the sample's model: the shared one, or read again with its parameters
  std::optional<Model> own;
  const Model* model = &pool.base;
  SimulationOptions o;
  try {
    if (!sample.parameters.empty()) {
      std::map<std::string, double> overrides = pool.model.overrides;
      for (const auto& kv : sample.parameters) overrides[kv.first] = kv.second;
      // (parse_model serializes the readings: GiNaC is not thread-safe)
      own.emplace(parse_model(pool.model.text, pool.model.file, overrides));
    }
    if (!sample.initial.empty()) {
      if (!own) own.emplace(pool.base);
      const auto& coords = own->system.coordinate_names();
      for (const auto& [name, value] : sample.initial) {
        const auto [k, velocity] = coordinate_of(coords, name);  // (checked: k >= 0)
        (velocity ? own->qd0 : own->q0)[k] = value;
      }
    }
    if (own) model = &*own;
    // settings: the file's (of this reading), the ensemble's, the sample's, the recording times
    if (sample.parameters.empty()) {
      o = pool.base_options;
    } else {
      o = own->options;
      for (const auto& kv : pool.model.settings) set_option(o, kv.first, kv.second);
    }
    o.project_initial = model->project_initial;
    for (const auto& kv : sample.settings) set_option(o, kv.first, kv.second);
    o.output_at.insert(o.output_at.end(), pool.options.at.begin(), pool.options.at.end());
  } catch (const ModelError& e) {
    out.outcome = SampleOutcome::kRefused;
    out.message = e.what();
    return;
  } catch (const std::invalid_argument& e) {
    out.outcome = SampleOutcome::kRefused;
    out.message = user_message(e);
    return;
  }
  o.should_stop = [&pool] { return pool.stop_requested(); };
  o.progress = nullptr;

  // the run, streamed: the recorded columns at the times `at`, and the whole trajectory if kept
  std::vector<std::size_t> index;  // of each recorded column among the run's columns
  std::vector<char> filled(pool.options.at.size(), 0);  // each time recorded
  bool resolved = false;
  auto take = [&](const ModelRun& chunk) {
    const std::vector<CsvColumn> cols = chunk.columns();
    if (!resolved) {
      resolved = true;
      for (const std::string& name : pool.recorded) {
        std::size_t k = 0;
        while (k < cols.size() && cols[k].name != name) ++k;
        if (k == cols.size()) {
          const std::lock_guard<std::mutex> lock(pool.progress_mutex);
          if (pool.misuse.empty()) {
            std::vector<std::string> names;
            for (const auto& c : cols) names.push_back(c.name);
            pool.misuse = "ukdyn::run_ensemble: the output '" + name +
                          "' is not a column of the model's trajectory.csv (its columns are " +
                          comma_list(names) + ")";
          }
          pool.stopping = true;
        }
        index.push_back(k);
      }
    }
    if (pool.options.keep_trajectories) {
      if (out.trajectory.empty()) {
        out.trajectory = cols;
      } else {
        for (std::size_t c = 0; c < cols.size() && c < out.trajectory.size(); ++c) {
          auto& to = out.trajectory[c].values;
          to.insert(to.end(), cols[c].values.begin(), cols[c].values.end());
        }
      }
    }
    const auto& at = pool.options.at;
    if (at.empty()) return;
    const std::vector<double>& t = chunk.trajectory.t;
    for (std::size_t r = 0; r < t.size(); ++r) {
      for (std::size_t k = 0; k < at.size(); ++k) {
        // the first sample at that time (a time met twice, at an event, keeps the first)
        if (t[r] != at[k] || filled[k]) continue;
        filled[k] = true;
        for (std::size_t j = 0; j < n_rec; ++j) {
          if (index[j] < cols.size()) out.values[k * n_rec + j] = cols[index[j]].values[r];
        }
      }
    }
  };
  try {
    ModelRun run = run_model(*model, o, take);
    out.outcome = SampleOutcome::kRun;
    out.stats = std::move(run.trajectory.stats);
    out.controlled = run.controlled;
    out.control = std::move(run.control);
    out.message = out.stats.message;
    if (pool.options.at.empty() && run.trajectory.samples() > 0) {
      // the last sample (run_model's streamed form returns it alone)
      const std::vector<CsvColumn> last = run.columns();
      for (std::size_t j = 0; j < n_rec; ++j) {
        for (const CsvColumn& c : last) {
          if (c.name == pool.recorded[j] && !c.values.empty()) {
            out.values[j] = c.values.back();
            break;
          }
        }
      }
    }
  } catch (const std::invalid_argument& e) {
    // an inconsistent initial state, a setting this sample's run cannot use
    out = SampleResult{};
    out.values.assign(n_at * n_rec, kNaN);
    out.outcome = SampleOutcome::kRefused;
    out.message = user_message(e);
  } catch (const std::exception& e) {
    out = SampleResult{};
    out.values.assign(n_at * n_rec, kNaN);
    out.outcome = SampleOutcome::kRefused;
    out.message = e.what();
  }
}

// the counts of a sample's contact events by kind (impacts with the rests), and the time of its
// last rest or plastic impact (an impact that left its contact closed, g'⁺ ≈ 0: e = 0 ends the
// bouncing at once, the limit of the accumulation's t₀ (1 + 2e/(1 − e)) as e → 0; NaN when
// none), as columns through `column` (ensemble_table's)
template <class Column>
void add_event_columns(const EnsembleResult& result, Column&& column) {
  using Kind = ContactEvent::Kind;
  auto count = [](const SampleResult& r, Kind a, Kind b) {
    // (a rest that held a contact leaving the impact, g'⁻ >= 0, is no impact: group rest)
    return double(std::count_if(
        r.stats.contact_events.begin(), r.stats.contact_events.end(), [&](const ContactEvent& e) {
          return e.kind == a || (e.kind == b && (b != Kind::kRest || e.speed_before < 0.0));
        }));
  };
  const std::pair<const char*, std::pair<Kind, Kind>> counts[] = {
      {"impacts", {Kind::kImpact, Kind::kRest}},
      {"releases", {Kind::kRelease, Kind::kRelease}},
      {"sticks", {Kind::kStick, Kind::kStick}},
      {"slips", {Kind::kSlip, Kind::kSlip}}};
  for (const auto& kinds : counts) {
    auto& c = column(kinds.first);
    for (const SampleResult& r : result.samples) {
      c.push_back(count(r, kinds.second.first, kinds.second.second));
    }
  }
  auto& rest = column("rest_time");
  for (const SampleResult& r : result.samples) {
    double t = kNaN;
    for (const ContactEvent& e : r.stats.contact_events) {
      const bool plastic =
          e.kind == Kind::kImpact && std::abs(e.speed_after) <= 1e-9 * std::abs(e.speed_before);
      if (e.kind == Kind::kRest || plastic) t = e.t;
    }
    rest.push_back(t);
  }
}

// "x@5", "theta@end"
std::string at_name(const std::string& column, const std::vector<double>& at, std::size_t k) {
  return column + "@" + (at.empty() ? std::string("end") : format_number(at[k]));
}

void append_csv_number(std::string& out, double x) {
  if (std::isnan(x)) {
    out += "nan";
    return;
  }
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, x);
  UKDYN_CHECK(ec == std::errc(), "std::to_chars needs at most 24 characters for a double");
  out.append(buf, end);
}

// a CSV field, quoted when it holds a comma, a quote or a line break
void append_text(std::string& out, const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) {
    out += s;
    return;
  }
  out += '"';
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
}

}  // namespace

namespace {
bool sample_interrupted(const SampleResult& s) {
  return s.outcome == SampleOutcome::kRun && s.stats.status == Status::kInterrupted;
}
}  // namespace

std::size_t EnsembleResult::failed() const {
  return std::size_t(std::count_if(samples.begin(), samples.end(), [](const SampleResult& s) {
    return !s.ok() && !sample_interrupted(s) && s.outcome != SampleOutcome::kNotRun;
  }));
}

std::size_t EnsembleResult::interrupted_samples() const {
  return std::size_t(std::count_if(samples.begin(), samples.end(), sample_interrupted));
}

std::size_t EnsembleResult::not_run() const {
  return std::size_t(std::count_if(samples.begin(), samples.end(), [](const SampleResult& s) {
    return s.outcome == SampleOutcome::kNotRun;
  }));
}

std::size_t EnsembleResult::ok() const {
  return std::size_t(
      std::count_if(samples.begin(), samples.end(), [](const SampleResult& s) { return s.ok(); }));
}

EnsembleResult run_ensemble(const EnsembleModel& model, const std::vector<EnsembleSample>& samples,
                            const EnsembleOptions& options) {
  // the model with the ensemble's overrides, read once: its errors are the caller's
  std::optional<Model> base;
  base.emplace(parse_model(model.text, model.file, model.overrides));
  SimulationOptions base_options = base->options;
  for (const auto& kv : model.settings) set_option(base_options, kv.first, kv.second);
  check_sample_names(*base, samples);
  for (double t : options.at) {
    if (!std::isfinite(t)) {
      throw std::invalid_argument("ukdyn::run_ensemble: a recording time is not finite: " +
                                  format_number(t));
    }
  }

  EnsembleResult result;
  result.at = options.at;
  // (the columns of the contacts' events: decided by the model, so that every chunk of a
  // distributed sweep has them)
  const auto& cs = base->system.constraints();
  result.contacts =
      !base->system.friction_contacts().empty() ||
      std::any_of(cs.begin(), cs.end(), [](const Constraint& c) { return c.is_unilateral(); });
  for (const auto& c : base->system.coordinate_names()) result.recorded.push_back(c);
  for (const auto& c : base->system.coordinate_names()) result.recorded.push_back(c + "_dot");
  const std::vector<std::string>& outputs =
      options.outputs.empty() ? base->output_names : options.outputs;
  for (const auto& name : outputs) {
    if (std::find(result.recorded.begin(), result.recorded.end(), name) == result.recorded.end())
      result.recorded.push_back(name);
  }
  result.samples.resize(samples.size());

  Pool pool{model, samples, options, *base, base_options, result.recorded, result.samples};
  pool.progress.total = samples.size();
  // each thread takes the next sample until none is left; after a stop request the rest are
  // marked not run
  auto work = [&pool] {
    while (true) {
      const std::size_t i = pool.next.fetch_add(1);
      if (i >= pool.samples.size()) return;
      SampleResult& r = pool.results[i];
      if (pool.stop_requested()) {
        r.outcome = SampleOutcome::kNotRun;
        r.message = "not run: the ensemble was stopped before this sample";
        r.values.assign(std::max<std::size_t>(pool.options.at.size(), 1) * pool.recorded.size(),
                        kNaN);
        continue;
      }
      // (an exception must not leave the thread: std::terminate; it is rethrown after the join)
      try {
        run_sample(pool, i);
        const std::lock_guard<std::mutex> lock(pool.progress_mutex);
        ++pool.progress.done;
        if (!r.ok()) ++pool.progress.failed;
        if (pool.options.progress) pool.options.progress(pool.progress);
      } catch (...) {
        pool.keep_exception(std::current_exception());
      }
    }
  };
  unsigned threads =
      options.threads != 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  threads = unsigned(std::min<std::size_t>(threads, std::max<std::size_t>(samples.size(), 1)));
  if (threads <= 1) {
    work();
  } else {
    std::vector<std::thread> pool_threads;
    pool_threads.reserve(threads);
    for (unsigned k = 0; k < threads; ++k) pool_threads.emplace_back(work);
    for (auto& t : pool_threads) t.join();
  }
  if (pool.thrown) std::rethrow_exception(pool.thrown);
  if (!pool.misuse.empty()) throw std::invalid_argument(pool.misuse);
  result.interrupted = pool.stopping.load();
  return result;
}

std::vector<EnsembleSample> samples_of_design(const Model& model, const DesignTable& design) {
  enum class Kind { kParameter, kInitial, kSetting };
  std::vector<Kind> kinds;
  const auto& coords = model.system.coordinate_names();
  for (const std::string& name : design.names) {
    if (model.parameters.count(name)) {
      kinds.push_back(Kind::kParameter);
      continue;
    }
    if (coordinate_of(coords, name).first >= 0) {
      kinds.push_back(Kind::kInitial);
      continue;
    }
    const OptionInfo* info = find_option(name);
    if (info && (info->type == OptionType::kNumber || info->type == OptionType::kInteger)) {
      kinds.push_back(Kind::kSetting);
      continue;
    }
    std::vector<std::string> known;
    for (const auto& p : model.parameters) known.push_back(p.first);
    throw std::invalid_argument(
        "ukdyn::samples_of_design: '" + name +
        "' is not a parameter, coordinate, velocity (<coordinate>_dot) or numeric option of "
        "the model (its parameters are " +
        (known.empty() ? std::string("none") : comma_list(known)) + "; its coordinates " +
        comma_list(coords) + ")");
  }
  std::vector<EnsembleSample> out(design.rows.size());
  for (std::size_t i = 0; i < design.rows.size(); ++i) {
    for (std::size_t k = 0; k < design.names.size(); ++k) {
      const double v = design.rows[i][k];
      switch (kinds[k]) {
        case Kind::kParameter:
          out[i].parameters[design.names[k]] = v;
          break;
        case Kind::kInitial:
          out[i].initial[design.names[k]] = v;
          break;
        case Kind::kSetting:
          out[i].settings[design.names[k]] = v;
          break;
      }
    }
  }
  return out;
}

std::vector<EnsembleSample> samples_of_design(const EnsembleModel& model,
                                              const DesignTable& design) {
  return samples_of_design(parse_model(model.text, model.file, model.overrides), design);
}

EnsembleTable ensemble_table(const EnsembleResult& result,
                             const std::vector<EnsembleSample>& samples,
                             std::vector<std::string> names) {
  if (samples.size() != result.samples.size()) {
    throw std::invalid_argument("ukdyn::ensemble_table: " + std::to_string(samples.size()) +
                                " samples but " + std::to_string(result.samples.size()) +
                                " results");
  }
  if (names.empty()) {
    std::set<std::string> seen;
    for (const EnsembleSample& s : samples) {
      for (const auto* m : {&s.parameters, &s.initial, &s.settings}) {
        for (const auto& kv : *m) {
          if (seen.insert(kv.first).second) names.push_back(kv.first);
        }
      }
    }
  }
  const std::size_t N = samples.size();
  EnsembleTable table;
  auto column = [&](const std::string& name) -> std::vector<double>& {
    table.numbers.push_back(CsvColumn{name, {}});
    table.numbers.back().values.reserve(N);
    return table.numbers.back().values;
  };
  {
    auto& c = column("sample");
    for (std::size_t i = 0; i < N; ++i) c.push_back(double(i));
  }
  for (const std::string& name : names) {
    auto& c = column(name);
    for (const EnsembleSample& s : samples) {
      double v = kNaN;
      for (const auto* m : {&s.parameters, &s.initial, &s.settings}) {
        if (auto it = m->find(name); it != m->end()) v = it->second;
      }
      c.push_back(v);
    }
  }
  // the summary figures
  using Get = double (*)(const SampleResult&);
  const std::pair<const char*, Get> figures[] = {
      {"status_code",
       [](const SampleResult& r) {
         return r.outcome == SampleOutcome::kRun       ? double(int(r.stats.status))
                : r.outcome == SampleOutcome::kRefused ? -1.0
                                                       : -2.0;
       }},
      {"ok", [](const SampleResult& r) { return r.ok() ? 1.0 : 0.0; }},
      {"steps", [](const SampleResult& r) { return double(r.stats.steps); }},
      {"rejected_steps", [](const SampleResult& r) { return double(r.stats.rejected_steps); }},
      {"evaluations", [](const SampleResult& r) { return double(r.stats.evaluations); }},
      {"t_reached",
       [](const SampleResult& r) {
         return r.outcome == SampleOutcome::kRun ? r.stats.t_reached : kNaN;
       }},
      {"max_position_violation",
       [](const SampleResult& r) { return r.stats.max_position_violation; }},
      {"max_velocity_violation",
       [](const SampleResult& r) { return r.stats.max_velocity_violation; }},
      {"energy_balance", [](const SampleResult& r) { return r.stats.energy_balance; }},
      {"energy_exchanged", [](const SampleResult& r) { return r.stats.energy_exchanged; }},
      {"control_evaluations", [](const SampleResult& r) { return double(r.control.evaluations); }},
      {"control_not_met", [](const SampleResult& r) { return double(r.control.not_met); }},
      {"control_max_residual", [](const SampleResult& r) { return r.control.max_residual; }},
      {"control_max_kappa", [](const SampleResult& r) { return r.control.max_kappa; }},
  };
  for (const auto& [name, get] : figures) {
    auto& c = column(name);
    for (const SampleResult& r : result.samples) c.push_back(get(r));
  }
  if (result.contacts) add_event_columns(result, column);
  // the recorded values, time-major
  const std::size_t n_at = std::max<std::size_t>(result.at.size(), 1);
  const std::size_t n_rec = result.recorded.size();
  for (std::size_t k = 0; k < n_at; ++k) {
    for (std::size_t j = 0; j < n_rec; ++j) {
      auto& c = column(at_name(result.recorded[j], result.at, k));
      for (const SampleResult& r : result.samples) {
        const std::size_t at = k * n_rec + j;
        c.push_back(at < r.values.size() ? r.values[at] : kNaN);
      }
    }
  }
  for (const SampleResult& r : result.samples) {
    table.status.push_back(r.outcome == SampleOutcome::kRun       ? to_string(r.stats.status)
                           : r.outcome == SampleOutcome::kRefused ? "refused"
                                                                  : "not run");
    table.message.push_back(r.message);
  }
  return table;
}

void write_ensemble_csv(const EnsembleTable& table, const std::string& path) {
  constexpr const char* who = "ukdyn::write_ensemble_csv";
  detail::AtomicFile file(path, who);
  std::FILE* f = file.open_stdio();
  std::string line;
  for (const CsvColumn& c : table.numbers) {
    append_text(line, c.name);
    line += ',';
  }
  line += "status,message\n";
  const std::size_t N = table.status.size();
  for (std::size_t i = 0; i < N; ++i) {
    for (const CsvColumn& c : table.numbers) {
      append_csv_number(line, i < c.values.size() ? c.values[i] : kNaN);
      line += ',';
    }
    append_text(line, table.status[i]);
    line += ',';
    append_text(line, table.message[i]);
    line += '\n';
    if (line.size() > (std::size_t(1) << 16) || i + 1 == N) {
      if (std::fwrite(line.data(), 1, line.size(), f) != line.size()) {
        const int err = errno;
        std::fclose(f);
        file.fail("write", err);
      }
      line.clear();
    }
  }
  if (N == 0 && std::fwrite(line.data(), 1, line.size(), f) != line.size()) {
    const int err = errno;
    std::fclose(f);
    file.fail("write", err);
  }
  if (std::fclose(f) != 0) file.fail("write", errno);
  file.commit();
}

void write_ensemble_hdf5(const EnsembleTable& table, const std::string& path,
                         const std::string& summary) {
  nlohmann::json j = summary.empty() ? nlohmann::json::object() : nlohmann::json::parse(summary);
  if (!j.is_object()) {
    throw std::invalid_argument("ukdyn::write_ensemble_hdf5: the summary is not a JSON object");
  }
  j["status"] = table.status;
  j["message"] = table.message;
  write_table_hdf5(path, table.numbers, j.dump(2) + "\n");
}

}  // namespace ukdyn

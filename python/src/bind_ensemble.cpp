// SPDX-License-Identifier: BSD-3-Clause
// Ensembles for ukdyn.sweep (python/ukdyn/ensemble.py): the design (simulation/sampling.hpp) and
// run_ensemble (simulation/ensemble.hpp) of a model's text, on threads here or, called once per
// chunk of samples, on Dask's workers.
#include <atomic>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

#include "common.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/simulation/ensemble.hpp"

namespace ukdyn::python {
namespace {

// the options of a settings dict, checked by the table's setter, as (name, value) pairs
std::map<std::string, OptionValue> settings_of(const py::dict& given) {
  SimulationOptions o;
  apply_simulation_options(o, given, "sweep");
  std::map<std::string, OptionValue> out;
  for (auto [k, v] : given) {
    if (v.is_none()) continue;
    const std::string key = py::str(k);
    out[find_option(key)->name] = get_option(o, key);
  }
  return out;
}

// runs f; a std::invalid_argument whose text begins with "ukdyn::<function>: " is thrown again
// with "sweep: " (the Python call) in place of that C++ name: a ValueError in Python
template <class F>
auto without_function_name(const char* function, F&& f) {
  try {
    return f();
  } catch (const std::invalid_argument& e) {
    const std::string prefix = std::string("ukdyn::") + function + ": ";
    const std::string text = e.what();
    if (text.rfind(prefix, 0) != 0) throw;
    throw std::invalid_argument("sweep: " + text.substr(prefix.size()));
  }
}

// the design's table from ukdyn.sweep's arguments: grid [(name, values)], random [(name, law,
// a, b)] with law "uniform", "normal" or "loguniform"
py::tuple design(const std::vector<std::pair<std::string, std::vector<double>>>& grid,
                 const std::vector<std::tuple<std::string, std::string, double, double>>& random,
                 std::size_t draws, std::uint64_t seed, bool lhs) {
  Design d;
  for (const auto& [name, values] : grid) d.grid.push_back({name, values});
  for (const auto& [name, law, a, b] : random) {
    // the law is checked on a stand-in text; its messages show the numbers given
    const std::string probe = name + "~" + law + "(0,1)";
    RandomVariable v;
    try {
      v = parse_random_variable(probe);
    } catch (const std::invalid_argument& e) {
      std::string text = e.what();
      const std::string quoted = "'" + probe + "'";
      if (text.rfind(quoted, 0) == 0) {
        text.replace(
            0, quoted.size(),
            "'" + name + "~" + law + "(" + format_number(a) + ", " + format_number(b) + ")'");
      }
      throw std::invalid_argument("sweep: " + text);
    }
    v.a = a;
    v.b = b;
    d.random.push_back(v);
  }
  d.draws = draws;
  d.seed = seed;
  d.latin_hypercube = lhs;
  DesignTable t;
  {
    ReleasedGil release;
    t = without_function_name("make_design", [&] { return make_design(d); });
  }
  py::array_t<double> rows({py::ssize_t(t.rows.size()), py::ssize_t(t.names.size())});
  auto r = rows.mutable_unchecked<2>();
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    for (std::size_t k = 0; k < t.names.size(); ++k)
      r(py::ssize_t(i), py::ssize_t(k)) = t.rows[i][k];
  }
  return py::make_tuple(t.names, rows);
}

// Runs work() on a thread of its own while this thread (with the GIL released) asks
// should_stop() every InterruptCheck::kInterval and sets `stop` once it says yes; work's
// exception is thrown again here. So Python's signal handlers run: CPython runs them on the main
// thread only, which is the caller's, never one of run_ensemble's threads.
void run_watched(const std::function<bool()>& should_stop, std::atomic<bool>& stop,
                 const std::function<void()>& work) {
  // (a stop asked already: before any sample starts)
  if (should_stop()) stop = true;
  std::mutex mutex;
  std::condition_variable finished;
  bool done = false;
  std::exception_ptr error;
  std::thread worker([&] {
    try {
      work();
    } catch (...) {
      error = std::current_exception();
    }
    const std::lock_guard<std::mutex> lock(mutex);
    done = true;
    finished.notify_all();
  });
  const auto interval = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(InterruptCheck::kInterval));
  std::unique_lock<std::mutex> lock(mutex);
  while (!finished.wait_for(lock, interval, [&] { return done; })) {
    lock.unlock();
    if (!stop && should_stop()) stop = true;
    lock.lock();
  }
  lock.unlock();
  worker.join();
  if (error) std::rethrow_exception(error);
}

// run_samples: run_ensemble of the samples `rows` (one per row, a value per name) → a dict: names
// (the table's numeric columns), columns (arrays), status, message, trajectories (list of dicts, or
// None), interrupted, exception (what a signal handler raised, or None)
py::dict run_samples(const std::string& text, const std::string& file,
                     const std::map<std::string, double>& overrides, const py::dict& settings,
                     const std::vector<std::string>& names, const py::array_t<double>& rows,
                     const std::vector<double>& at, const std::vector<std::string>& outputs,
                     bool keep, unsigned threads, py::object stop) {
  EnsembleModel model;
  model.text = text;
  model.file = file;
  model.overrides = overrides;
  model.settings = settings_of(settings);
  if (rows.ndim() != 2 || std::size_t(rows.shape(1)) != names.size()) {
    throw std::invalid_argument("_run_ensemble: rows must be samples x names");
  }
  DesignTable table;
  table.names = names;
  const auto r = rows.unchecked<2>();
  for (py::ssize_t i = 0; i < r.shape(0); ++i) {
    std::vector<double> row;
    for (py::ssize_t k = 0; k < r.shape(1); ++k) row.push_back(r(i, k));
    table.rows.push_back(std::move(row));
  }
  EnsembleOptions o;
  o.threads = threads;
  o.at = at;
  o.outputs = outputs;
  o.keep_trajectories = keep;
  // Ctrl-C: the module's check (Python's signal handlers, then `stop`) on this thread, which
  // run_ensemble's threads see as a flag (run_watched)
  const InterruptCheck interrupt(stop);
  SimulationOptions holder;
  interrupt.attach(holder);
  std::atomic<bool> stopping{false};
  o.should_stop = [&stopping] { return stopping.load(std::memory_order_relaxed); };
  std::vector<EnsembleSample> samples;
  EnsembleResult result;
  EnsembleTable out;
  {
    ReleasedGil release;
    samples =
        without_function_name("samples_of_design", [&] { return samples_of_design(model, table); });
    run_watched(holder.should_stop, stopping, [&] { result = run_ensemble(model, samples, o); });
    out = ensemble_table(result, samples, names);
  }
  py::dict d;
  py::list cols, col_names;
  for (CsvColumn& c : out.numbers) {
    col_names.append(c.name);
    cols.append(take(std::move(c.values)));
  }
  d["names"] = col_names;
  d["columns"] = cols;
  d["status"] = out.status;
  d["message"] = out.message;
  if (keep) {
    py::list trajectories;
    for (SampleResult& s : result.samples) {
      py::dict t;
      for (CsvColumn& c : s.trajectory) t[py::str(c.name)] = take(std::move(c.values));
      trajectories.append(t);
    }
    d["trajectories"] = trajectories;
  } else {
    d["trajectories"] = py::none();
  }
  d["interrupted"] = result.interrupted;
  d["exception"] = interrupt.exception();
  return d;
}

}  // namespace

void bind_ensemble(py::module_& m) {
  m.def("_design", &design, py::arg("grid"), py::arg("random"), py::arg("draws"), py::arg("seed"),
        py::arg("lhs"),
        "make_design (simulation/sampling.hpp): (names, rows as a samples x names array).");
  m.def(
      "_parse_grid",
      [](const std::string& text) {
        const GridAxis a = parse_grid_axis(text);
        return py::make_tuple(a.name, a.values);
      },
      py::arg("text"), "parse_grid_axis: 'mu=0:0.5:11' or 'omega=1,2,4' -> (name, values).");
  m.def(
      "_parse_random",
      [](const std::string& text) {
        static const char* const laws[] = {"uniform", "normal", "loguniform"};
        const RandomVariable v = parse_random_variable(text);
        return py::make_tuple(v.name, laws[int(v.distribution)], v.a, v.b);
      },
      py::arg("text"), "parse_random_variable: 'k~normal(1,0.1)' -> (name, law, a, b).");
  m.def("_run_ensemble", &run_samples, py::arg("text"), py::arg("file"), py::arg("overrides"),
        py::arg("settings"), py::arg("names"), py::arg("rows"), py::arg("at"), py::arg("outputs"),
        py::arg("keep"), py::arg("threads"), py::arg("stop") = py::none(),
        "run_ensemble (simulation/ensemble.hpp) with the GIL released: a dict of the table "
        "(names, columns, status, message), trajectories, interrupted, exception. Use "
        "ukdyn.sweep().");
}

}  // namespace ukdyn::python

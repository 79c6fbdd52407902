// SPDX-License-Identifier: BSD-3-Clause
// Conversions between NumPy and Eigen, simulation settings from keyword arguments, and run
// reports as Python objects (common.hpp).
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <string>

#include <ukdyn/simulation/options.hpp>

#include "common.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn::python {
namespace {

std::string size_message(const char* who, const char* what, const std::string& expected,
                         const std::string& actual) {
  return std::string(who) + ": " + what + " must have " + expected + " (got " + actual + ")";
}

std::string shape_text(const py::array& a) {
  std::string s = "shape (";
  for (py::ssize_t k = 0; k < a.ndim(); ++k)
    s += (k ? ", " : "") + ukdyn::format_number(a.shape(k));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// obj as a float64 array (a view when it already is one; converted otherwise). Complex numbers
// are refused rather than cast with their imaginary part dropped.
py::array_t<double> as_array(py::handle obj, const char* who, const char* what) {
  // (NumPy would read None as a 0-d NaN: "must have 2 entries (got 1)"); a callable's value is
  // read with who "ukdyn callable" and what "Q(q, q_dot, t)", …
  if (obj.is_none()) {
    const bool returned = std::strcmp(who, "ukdyn callable") == 0;
    throw std::invalid_argument(std::string(who) + ": " + what +
                                (returned ? " returned None (it must return numbers: did it "
                                            "miss a return statement?)"
                                          : " is None"));
  }
  if (PyComplex_Check(obj.ptr()) ||
      (py::isinstance<py::array>(obj) &&
       py::reinterpret_borrow<py::array>(obj).dtype().kind() == 'c')) {
    throw std::invalid_argument(std::string(who) + ": " + what +
                                " must be real numbers (got complex)");
  }
  auto a = py::array_t<double>::ensure(obj);
  if (!a) throw std::invalid_argument(std::string(who) + ": " + what + " must be numbers");
  return a;
}

}  // namespace

void CallbackErrors::raise_if_any() {
  if (!error) return;
  py::error_already_set e = std::move(*error);
  error.reset();
  throw e;
}

py::array_t<double> take(std::vector<double>&& v) {
  auto* owned = new std::vector<double>(std::move(v));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<double>*>(p); });
  return py::array_t<double>({py::ssize_t(owned->size())}, {py::ssize_t(sizeof(double))},
                             owned->data(), owner);
}

py::array_t<double> copy_vector(const Eigen::Ref<const VectorXd>& v) {
  py::array_t<double> a(v.size());
  if (v.size() > 0) std::memcpy(a.mutable_data(), v.data(), sizeof(double) * std::size_t(v.size()));
  return a;
}

py::array_t<double> copy_matrix(const Eigen::Ref<const MatrixXd>& M) {
  py::array_t<double, py::array::f_style> a({py::ssize_t(M.rows()), py::ssize_t(M.cols())});
  Eigen::Map<MatrixXd>(a.mutable_data(), M.rows(), M.cols()) = M;
  return a;
}

py::array view_vector(const VectorXd& v, py::handle owner) {
  py::array a(py::dtype::of<double>(), {py::ssize_t(v.size())}, {py::ssize_t(sizeof(double))},
              v.data(), owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

py::array view_matrix(const MatrixXd& M, py::handle owner) {
  py::array a(py::dtype::of<double>(), {py::ssize_t(M.rows()), py::ssize_t(M.cols())},
              {py::ssize_t(sizeof(double)), py::ssize_t(sizeof(double) * M.rows())}, M.data(),
              owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

void read_into(py::handle obj, const char* who, const char* what, Eigen::Ref<VectorXd> out) {
  const Index n = out.size();
  // fast path: a contiguous float64 array of the right size, copied without any allocation
  if (py::isinstance<py::array_t<double, py::array::c_style>>(obj)) {
    auto a = py::reinterpret_borrow<py::array_t<double, py::array::c_style>>(obj);
    if (a.ndim() == 1 && a.shape(0) == n) {
      if (n > 0) std::memcpy(out.data(), a.data(), sizeof(double) * std::size_t(n));
      return;
    }
  }
  py::array_t<double> a = as_array(obj, who, what);
  if (a.ndim() > 1 || a.size() != n) {
    throw std::invalid_argument(
        size_message(who, what, ukdyn::format_number(n) + " entries",
                     a.ndim() > 1 ? shape_text(a) : ukdyn::format_number(a.size())));
  }
  auto r = a.unchecked();
  if (a.ndim() == 0) {
    out[0] = *a.data();
  } else {
    for (Index i = 0; i < n; ++i) out[i] = r(i);
  }
}

double read_number(py::handle obj, const char* who, const char* what, double t) {
  // (a str would be read by NumPy as text: say what it is, not "must be numbers")
  if (py::isinstance<py::str>(obj) || py::isinstance<py::bytes>(obj)) {
    throw std::invalid_argument(std::string(who) + ": " + what + " returned " +
                                std::string(py::str(py::repr(obj))).substr(0, 40) +
                                " (it must return a number)");
  }
  py::array_t<double> a = as_array(obj, who, what);
  if (a.size() != 1) {
    throw std::invalid_argument(
        std::string(who) + ": " + what + " must return one number (got " +
        (a.ndim() == 1 ? ukdyn::format_number(a.size()) + " entries" : shape_text(a)) + ")");
  }
  const double value = *a.data();
  if (!std::isfinite(value)) {
    throw std::invalid_argument(std::string(who) + ": " + what + " returned " +
                                ukdyn::format_number(value) + " at t = " + ukdyn::format_number(t) +
                                " (it must return a finite number)");
  }
  return value;
}

void read_vector(py::handle obj, Index n, const char* who, const char* what, VectorXd& out) {
  out.resize(n);
  read_into(obj, who, what, out);
}

void read_matrix_into(py::handle obj, const char* who, const char* what, Eigen::Ref<MatrixXd> out) {
  py::array_t<double> a = as_array(obj, who, what);
  const Index rows = out.rows(), cols = out.cols();
  // a single row or column may be given as a 1-D array
  const bool flat_ok = a.ndim() == 1 && (rows == 1 || cols == 1) && a.size() == rows * cols;
  if (!(a.ndim() == 2 && a.shape(0) == rows && a.shape(1) == cols) && !flat_ok) {
    throw std::invalid_argument(size_message(
        who, what, "shape (" + ukdyn::format_number(rows) + ", " + ukdyn::format_number(cols) + ")",
        shape_text(a)));
  }
  if (flat_ok) {
    auto r = a.unchecked<1>();
    // out may be a block with an outer stride (rows of a larger A): index, never data()[i]
    for (Index i = 0; i < rows * cols; ++i) {
      if (rows == 1)
        out(0, i) = r(i);
      else
        out(i, 0) = r(i);
    }
    return;
  }
  auto r = a.unchecked<2>();
  for (Index i = 0; i < rows; ++i)
    for (Index j = 0; j < cols; ++j) out(i, j) = r(i, j);
}

MatrixXd read_matrix(py::handle obj, const char* who, const char* what) {
  py::array_t<double> a = as_array(obj, who, what);
  if (a.ndim() != 2) {
    throw std::invalid_argument(size_message(who, what, "two dimensions", shape_text(a)));
  }
  MatrixXd M(a.shape(0), a.shape(1));
  read_matrix_into(a, who, what, M);
  return M;
}

// --- settings ----------------------------------------------------------------------------------

namespace {

std::string type_name(py::handle v) {
  return std::string(py::str(py::type::of(v).attr("__name__")));
}

double number(py::handle v, const std::string& who, const char* key) {
  // a complex (Python's or NumPy's) would be cast with its imaginary part dropped
  if (PyComplex_Check(v.ptr()) || type_name(v).find("complex") != std::string::npos) {
    throw std::invalid_argument(who + ": " + key + " must be a real number (got " + type_name(v) +
                                ")");
  }
  try {
    return v.cast<double>();
  } catch (const py::cast_error&) {
    throw std::invalid_argument(who + ": " + key + " must be a number (got " + type_name(v) + ")");
  }
}

// a whole number: a Python int or an integral float within the range of T
template <class T>
T integer(py::handle v, const std::string& who, const char* key) {
  if (py::isinstance<py::bool_>(v) ||
      !(py::isinstance<py::int_>(v) || py::isinstance<py::float_>(v) ||
        py::hasattr(v, "__index__"))) {
    throw std::invalid_argument(who + ": " + key + " must be a whole number (got " + type_name(v) +
                                ")");
  }
  const double x = number(v, who, key);
  if (!(std::isfinite(x) && x == std::floor(x) && x >= double(std::numeric_limits<T>::min()) &&
        x <= double(std::numeric_limits<T>::max()))) {
    throw std::invalid_argument(who + ": " + key + " must be a whole number between " +
                                ukdyn::format_number(std::numeric_limits<T>::min()) + " and " +
                                ukdyn::format_number(std::numeric_limits<T>::max()) + " (got " +
                                std::string(py::repr(v)) + ")");
  }
  return static_cast<T>(x);
}

// True or False (also NumPy's bool); 0 and 1 are accepted as the integers they are
bool boolean(py::handle v, const std::string& who, const char* key) {
  if (py::isinstance<py::bool_>(v) || type_name(v) == "bool_") return PyObject_IsTrue(v.ptr()) == 1;
  if (py::isinstance<py::int_>(v)) {
    const double x = number(v, who, key);
    if (x == 0 || x == 1) return x == 1;
  }
  throw std::invalid_argument(who + ": " + key + " must be True or False (got " +
                              std::string(py::repr(v)).substr(0, 60) + ")");
}

std::vector<double> numbers(py::handle v, const std::string& who, const char* key) {
  std::vector<double> out;
  if (py::isinstance<py::float_>(v) || py::isinstance<py::int_>(v)) return {number(v, who, key)};
  if (py::isinstance<py::str>(v) || !py::hasattr(v, "__iter__")) {
    throw std::invalid_argument(
        who + ": " + key + " must be a number or a sequence of numbers (got " + type_name(v) + ")");
  }
  for (py::handle x : py::iter(v)) out.push_back(number(x, who, key));
  return out;
}

std::string text(py::handle v, const std::string& who, const char* key) {
  if (!py::isinstance<py::str>(v))
    throw std::invalid_argument(who + ": " + key + " must be a string");
  return v.cast<std::string>();
}

// a Python value as the option's type (a type error names the key as given)
OptionValue option_value(const OptionInfo& info, py::handle v, const std::string& who,
                         const char* key) {
  switch (info.type) {
    case OptionType::kNumber:
      return number(v, who, key);
    case OptionType::kInteger:
      return integer<long>(v, who, key);
    case OptionType::kBool:
      return boolean(v, who, key);
    case OptionType::kChoice:
      return text(v, who, key);
    case OptionType::kNumbers:
      return numbers(v, who, key);
  }
  return number(v, who, key);
}

// sets the option `key` through the table's setter (simulation/options.hpp): a range error names it
void set_from_python(SimulationOptions& o, const OptionInfo& info, const std::string& key,
                     py::handle v, const std::string& who) {
  const OptionValue value = option_value(info, v, who, key.c_str());
  try {
    set_option(o, key, value);
  } catch (const OptionError& e) {
    throw std::invalid_argument(who + ": " + e.what());
  }
}

py::object to_python(const OptionValue& v) {
  if (const bool* b = std::get_if<bool>(&v)) return py::bool_(*b);
  if (const long* l = std::get_if<long>(&v)) return py::int_(*l);
  if (const double* d = std::get_if<double>(&v)) return py::float_(*d);
  if (const std::string* t = std::get_if<std::string>(&v)) return py::str(*t);
  return py::cast(std::get<std::vector<double>>(v));
}

}  // namespace

std::string solver_option_names() {
  std::string out;
  for (const OptionInfo& info : option_table()) {
    if (info.solver) out += (out.empty() ? "" : ", ") + info.name;
  }
  return out;
}

void apply_solver_options(SolverOptions& o, py::dict& settings) {
  const std::string who = "solver options";
  SimulationOptions with;
  with.solver = o;
  py::list used;
  for (auto [k, v] : settings) {
    const std::string key = py::str(k);
    const OptionInfo* info = find_option(key);
    if (!info || !info->solver) continue;
    if (!v.is_none()) set_from_python(with, *info, key, v, who);  // None: keep the default
    used.append(k);
  }
  o = with.solver;
  for (py::handle k : used) PyDict_DelItem(settings.ptr(), k.ptr());
}

void apply_simulation_options(SimulationOptions& o, const py::dict& given, const char* who_c) {
  const std::string who = who_c;
  for (auto [k, v] : given) {
    const std::string key = py::str(k);
    const OptionInfo* info = find_option(key);
    if (!info) {
      throw std::invalid_argument(who + ": unknown setting '" + key +
                                  "' (known: " + option_names() + ")");
    }
    if (v.is_none()) continue;  // None: keep the model's value
    set_from_python(o, *info, key, v, who);
  }
}

py::dict simulation_options_dict(const SimulationOptions& o) {
  py::dict d;
  for (const OptionInfo& info : option_table()) d[py::str(info.name)] = to_python(info.get(o));
  return d;
}

py::list options_list() {
  py::list out;
  const SimulationOptions defaults;
  for (const OptionInfo& info : option_table()) {
    static const char* const kTypes[] = {"number", "integer", "bool", "choice", "numbers"};
    py::dict d;
    d["name"] = info.name;
    d["type"] = kTypes[int(info.type)];
    d["default"] = to_python(info.get(defaults));
    d["range"] = option_rule(info);
    d["choices"] = info.choices;
    d["aliases"] = info.aliases;
    d["solver"] = info.solver;
    d["flag"] = option_flag(info);
    d["example"] = info.example;
    d["doc"] = info.doc;
    out.append(d);
  }
  return out;
}

py::dict statistics_dict(const RunStatistics& s) {
  py::dict d;
  d["steps"] = s.steps;
  d["rejected_steps"] = s.rejected_steps;
  d["evaluations"] = s.evaluations;
  d["least_squares"] = s.least_squares;
  d["tangential_steps"] = s.tangential_steps;
  d["projected_stage_steps"] = s.projected_stage_steps;
  d["projections"] = s.projections;
  d["events"] = s.events;
  d["switch_events"] = s.switch_events;
  d["stick_refusals"] = s.stick_refusals;
  // the impacts, releases and rests of unilateral contacts and the sticks and slips of Coulomb
  // friction (docs/contact.md), one dict each, with summary.json's keys (NaN stays NaN)
  py::list contacts;
  for (const ContactEvent& e : s.contact_events) {
    py::dict c;
    c["t"] = e.t;
    c["constraint"] = e.constraint;
    c["kind"] = to_string(e.kind);
    c["speed_before"] = e.speed_before;
    c["speed_after"] = e.speed_after;
    c["impulse"] = e.impulse;
    c["energy_change"] = e.energy_change;
    if (e.kind == ContactEvent::Kind::kRelease) c["force_before"] = e.force_before;
    if (e.kind == ContactEvent::Kind::kStick || e.kind == ContactEvent::Kind::kSlip) {
      c["friction"] = e.friction;
      c["holding_force"] = e.holding_force;
      c["friction_limit"] = e.friction_limit;
    }
    contacts.append(c);
  }
  d["contact_events"] = contacts;
  d["notes"] = s.notes;
  d["stiff_switches"] = s.stiff_switches;
  d["stiff_switch_time"] = s.stiff_switch_time;
  d["stiff_steps"] = s.stiff_steps;
  d["wall_time"] = s.wall_time;
  d["max_position_violation"] = s.max_position_violation;
  d["max_velocity_violation"] = s.max_velocity_violation;
  d["energy_balance"] = s.energy_balance;
  d["energy_exchanged"] = s.energy_exchanged;
  d["energy_balance_checked"] = s.energy_balance_checked;
  d["energy_drift"] = s.energy_drift;
  d["t_reached"] = s.t_reached;
  d["status"] = to_string(s.status);
  d["message"] = s.message;
  return d;
}

struct InterruptCheck::State {
  PyObject* stop = nullptr;  // borrowed (see the constructor); null or None: no callable
  std::chrono::steady_clock::time_point next{};  // the next look at the signals
  bool stopped = false;
  std::optional<py::error_already_set> error;  // what a handler raised (touched with the GIL)
};

InterruptCheck::InterruptCheck(py::handle stop) : state_(std::make_shared<State>()) {
  state_->stop = stop.is_none() ? nullptr : stop.ptr();
}

void InterruptCheck::attach(SimulationOptions& o) const {
  const auto interval = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(kInterval));
  o.should_stop = [st = state_, interval]() -> bool {
    if (st->stopped) return true;
    // (a clock read a step; the GIL only every interval)
    const auto now = std::chrono::steady_clock::now();
    if (now < st->next) return false;
    st->next = now + interval;
    const AcquiredGil gil;
    if (!gil.held()) {
      st->stopped = true;  // the interpreter is exiting
      return true;
    }
    // Python's handlers of the signals that arrived (KeyboardInterrupt from the default one)
    if (PyErr_CheckSignals() != 0) {
      st->error.emplace();
      st->stopped = true;
      return true;
    }
    if (st->stop) {
      PyObject* answer = PyObject_CallNoArgs(st->stop);
      const int yes = answer ? PyObject_IsTrue(answer) : -1;
      Py_XDECREF(answer);
      if (yes < 0) st->error.emplace();
      st->stopped = yes != 0;
    }
    return st->stopped;
  };
}

py::object InterruptCheck::exception() const {
  if (!state_->error) return py::none();
  return state_->error->value();
}

py::tuple run_tuple(ModelRun&& run, py::object interrupt, const SimulationOptions& options,
                    const RunProvenance* provenance) {
  // the summary first (its final state reads the trajectory, whose columns move out below)
  std::string summary =
      summary_json(run.trajectory, options, provenance, run.controlled ? &run.control : nullptr);
  std::vector<CsvColumn> columns = run.columns();
  py::list names, values;
  for (CsvColumn& c : columns) {
    names.append(c.name);
    values.append(take(std::move(c.values)));
  }
  py::object control = py::none();
  if (run.controlled) {
    py::dict c;
    c["evaluations"] = run.control.evaluations;
    c["not_met"] = run.control.not_met;
    c["max_residual"] = run.control.max_residual;
    c["first_not_met"] = run.control.first_not_met;
    c["not_met_message"] = run.control.not_met_message;
    c["max_kappa"] = run.control.max_kappa;
    c["bound_exceeded_at"] = run.control.bound_exceeded_at;
    c["bound_worst_ratio"] = run.control.bound_worst_ratio;
    c["bound_worst_row"] = run.control.bound_worst_row;
    c["bound_worst_time"] = run.control.bound_worst_time;
    control = c;
  }
  return py::make_tuple(names, values, statistics_dict(run.trajectory.stats), control,
                        std::move(interrupt), std::move(summary));
}

}  // namespace ukdyn::python

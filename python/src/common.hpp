// SPDX-License-Identifier: BSD-3-Clause
// Shared declarations of the Python module's binding files (python/src/*.cpp): conversions
// between NumPy and Eigen, simulation settings from keyword arguments, and the handles that the
// bound classes wrap. The module only translates; no physics lives here (docs/style.md).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/ukdyn.hpp>

namespace ukdyn::python {
namespace py = pybind11;

// --- errors ------------------------------------------------------------------------------------

/// A model whose run cannot start because its contacts at the initial state cannot be solved
/// (Painlevé's paradox), located at the friction's or contact's entry of the file
/// (detail::locate_contact_start, as `ukdyn run` prints it): raised as
/// ukdyn.ContactStartError, a ukdyn.ModelError that is also a ValueError (the run's misuse, as
/// before it was located).
class ContactStartModelError : public ModelError {
 public:
  /// The located error (ModelError's file, line, column, message, hint).
  explicit ContactStartModelError(const ModelError& located) : ModelError(located) {}
};

// --- NumPy <-> Eigen -----------------------------------------------------------------------------

/// A 1-D NumPy array that takes over `v` (no copy: the array owns the vector through a capsule).
py::array_t<double> take(std::vector<double>&& v);
/// A fresh 1-D NumPy array holding a copy of v.
py::array_t<double> copy_vector(const Eigen::Ref<const VectorXd>& v);
/// A fresh 2-D NumPy array (Fortran order, like Eigen) holding a copy of M.
py::array_t<double> copy_matrix(const Eigen::Ref<const MatrixXd>& M);
/// A read-only NumPy view of a workspace buffer (no copy), kept alive by `owner`. The buffer
/// must not be reallocated while the view lives (workspace buffers are sized once).
py::array view_vector(const VectorXd& v, py::handle owner);
/// The same for a matrix (Fortran order).
py::array view_matrix(const MatrixXd& M, py::handle owner);

/// Copies a 1-D sequence of n numbers into out (resized to n). @throws std::invalid_argument
/// naming `who` and `what` with the expected and the actual size.
void read_vector(py::handle obj, Index n, const char* who, const char* what, VectorXd& out);
/// Copies an n-entry vector into `out` (which has n entries) without allocating when obj is a
/// contiguous float64 array. @throws std::invalid_argument as read_vector.
void read_into(py::handle obj, const char* who, const char* what, Eigen::Ref<VectorXd> out);
/// Copies a rows × cols matrix into `out` (rows × cols). @throws std::invalid_argument.
void read_matrix_into(py::handle obj, const char* who, const char* what, Eigen::Ref<MatrixXd> out);
/// The one finite number a callable returned at time t (a float, a 0-d or 1-entry array).
/// @throws std::invalid_argument naming `who` and `what`: None, a str, complex, several
/// entries, or a value that is not finite (with t).
double read_number(py::handle obj, const char* who, const char* what, double t);
/// A matrix of any size from a 2-D sequence. @throws std::invalid_argument.
MatrixXd read_matrix(py::handle obj, const char* who, const char* what);

// --- settings and reports
// --------------------------------------------------------------------------

/// Applies keyword settings to `o`: every option of the table (simulation/options.hpp, by name or
/// alias), each through its validating setter; None keeps the value. @throws std::invalid_argument
/// naming an unknown key (with the known ones) or the option whose value is bad.
void apply_simulation_options(SimulationOptions& o, const py::dict& settings, const char* who);
/// Applies the solver options of the table (OptionInfo::solver: rank_threshold, engine, …) to
/// `o`, removing the keys it used from `settings`.
void apply_solver_options(SolverOptions& o, py::dict& settings);
/// The names of the table's solver options, comma-separated.
std::string solver_option_names();
/// The options as a dict: every option of the table by its name (apply_simulation_options
/// takes it back).
py::dict simulation_options_dict(const SimulationOptions& o);
/// The table as a list of dicts (name, type, default, range, choices, aliases, solver, flag,
/// example, doc).
py::list options_list();
/// The statistics of a run as a dict.
py::dict statistics_dict(const RunStatistics& s);

/// A model run as the tuple (names, columns, statistics, control statistics or None,
/// interrupt, summary) that the Python Result class wraps; the columns are NumPy arrays taking
/// over run.columns(); interrupt is InterruptCheck::exception() (None unless a signal handler
/// raised); summary is the run's summary.json text (summary_json of io/trajectory_files.hpp with
/// `options` and `provenance`, null for none), which Result.to_hdf5 writes as `ukdyn run` does.
py::tuple run_tuple(ModelRun&& run, py::object interrupt, const SimulationOptions& options,
                    const RunProvenance* provenance);

/// Ctrl-C during a run with the GIL released (docs/python.md, "Interrupts"). attach() sets
/// SimulationOptions::should_stop to a check that, at most every kInterval of the run, takes the
/// GIL, runs Python's signal handlers (PyErr_CheckSignals; only the main thread runs them) and
/// then calls `stop` (a Python callable, or None): a true result, or an exception raised by a
/// handler or by `stop`, stops the run at its next step (Status::kInterrupted). The Python side
/// (ukdyn/interrupt.py) gives `stop`: it reports that its SIGINT handler was called, and raises
/// ukdyn.Interrupted (a KeyboardInterrupt) with the partial result once the run has returned.
/// The check is for one thread at a time: a run's own, or, for an ensemble, the caller's thread,
/// which tells run_ensemble's threads through a flag (bind_ensemble.cpp, run_watched). At
/// interpreter exit it says stop without taking the GIL (AcquiredGil).
class InterruptCheck {
 public:
  /// How often the run looks at Python's signals (a GIL acquisition each time).
  static constexpr double kInterval = 0.02;  // s
  /// With the GIL. `stop` is borrowed: it must outlive the run (an argument of the call).
  explicit InterruptCheck(py::handle stop);
  /// Sets o.should_stop.
  void attach(SimulationOptions& o) const;
  /// The exception that a signal handler (or `stop`) raised during the run, or None. The GIL.
  py::object exception() const;

 private:
  struct State;
  std::shared_ptr<State> state_;
};

// --- the GIL, at interpreter exit too (gil.cpp) -------------------------------------------------
//
// A thread must not take the GIL once Python has begun to finalize: CPython 3.11 then ends it with
// pthread_exit, whose unwinding through C++ frames (a noexcept destructor, a std::thread) calls
// std::terminate ("terminate called without an active exception"). So every place where the
// module gives the GIL up for a long time or takes it from C++ goes through a gate, which the
// module's atexit hook (run before finalization begins) closes: after that, a thread that would
// take the GIL does not (AcquiredGil::held() is false: a run asked whether to stop is told yes, a
// Python callable is not called) or, when it is a call's thread returning to Python, stays parked
// for good, as CPython 3.14 parks daemon threads. The hook waits (at most 2 s) for the work under
// way to stop so. The thread that runs the hook is never stopped.

/// Replaces py::gil_scoped_release around C++ work: gives the GIL up and takes it back at the
/// end of the scope, or parks the thread for good when the interpreter is exiting meanwhile.
class ReleasedGil {
 public:
  ReleasedGil();  ///< with the GIL
  ~ReleasedGil();
  ReleasedGil(const ReleasedGil&) = delete;
  ReleasedGil& operator=(const ReleasedGil&) = delete;

 private:
  PyThreadState* state_;
};

/// Replaces py::gil_scoped_acquire on a thread that runs C++ code (a run's check for Ctrl-C, a
/// Python callable): takes the GIL unless the interpreter is exiting; held() says which.
class AcquiredGil {
 public:
  AcquiredGil();
  ~AcquiredGil();
  AcquiredGil(const AcquiredGil&) = delete;
  AcquiredGil& operator=(const AcquiredGil&) = delete;
  /// True when the GIL is held (Python may be called).
  bool held() const { return gil_.has_value(); }

 private:
  std::optional<py::gil_scoped_acquire> gil_;
};

/// Registers the atexit hook that closes the gate (module.cpp, once, at import).
void register_gil_gate(py::module_& m);

// --- handles
// -----------------------------------------------------------------------------------------

/// Where the Python callables of a System report a Python exception: the first one raised
/// during an evaluation is kept here (the callable writes NaN so that the evaluation stops with
/// kNonFiniteInput), and the front end raises it again once the C++ call has returned.
struct CallbackErrors {
  std::optional<py::error_already_set> error;  ///< the first exception, if any (GIL to touch)
  /// Raises the stored exception (and forgets it). Needs the GIL.
  void raise_if_any();
};

/// A System as Python sees it: the description, and the exception slot of its Python callables
/// (null for systems built in C++: model files).
struct SystemHandle {
  System system;                           ///< the description
  std::shared_ptr<CallbackErrors> errors;  ///< null unless built from Python callables
  /// Raises a pending exception of the callables, if any. Needs the GIL.
  void raise_pending() const {
    if (errors) errors->raise_if_any();
  }
};

/// A Controller as Python sees it (immutable, shared with the model it came from).
struct ControllerHandle {
  std::shared_ptr<const Controller> controller;  ///< not null
  std::shared_ptr<CallbackErrors> errors;        ///< null unless it calls Python callables
  /// Raises a pending exception of the callables, if any. Needs the GIL.
  void raise_pending() const {
    if (errors) errors->raise_if_any();
  }
};

// --- the binding files
// ----------------------------------------------------------------------------
void bind_model(py::module_& m);      // bind_model.cpp
void bind_solver(py::module_& m);     // bind_solver.cpp
void bind_control(py::module_& m);    // bind_control.cpp
void bind_callables(py::module_& m);  // bind_callables.cpp
void bind_ensemble(py::module_& m);   // bind_ensemble.cpp
void bind_linearize(py::module_& m);  // bind_linearize.cpp

}  // namespace ukdyn::python

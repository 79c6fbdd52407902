// SPDX-License-Identifier: BSD-3-Clause
// The Python module ukdyn._ukdyn: exception translation and the module's entry point. The
// classes and functions are bound in bind_*.cpp; the package ukdyn (python/ukdyn/) wraps them.
#include <string_view>

#include "common.hpp"

#include <ukdyn/core/format.hpp>

#include "viewer.hpp"  // app/: the viewer's embedded three.js (viewer_embedded.cpp)

namespace ukdyn::python {
namespace {

// the exception classes of ukdyn/errors.py (imported when first needed)
py::object error_class(const char* name) { return py::module_::import("ukdyn.errors").attr(name); }

// C++ exceptions -> Python: ModelError -> ukdyn.ModelError (file, line, column, message, hint;
// ContactStartModelError -> ukdyn.ContactStartError),
// SolveError -> ukdyn.SolveError (status), InconsistentInitialState ->
// ukdyn.InconsistentInitialState, SettingError and simulate's other misuse -> ValueError (their
// text without "ukdyn::simulate: "); the rest follow pybind11's defaults (std::invalid_argument ->
// ValueError, other std::exception -> RuntimeError), with any byte of a message that is not UTF-8
// shown as U+FFFD
void translate(std::exception_ptr p) {
  try {
    if (p) std::rethrow_exception(p);
  } catch (const ModelError& e) {
    // (a run refused at its contacts' start: ukdyn.ContactStartError, also a ValueError)
    py::object cls =
        error_class(dynamic_cast<const ContactStartModelError*>(&e) != nullptr ? "ContactStartError"
                                                                               : "ModelError");
    py::object err = cls(e.what(), e.file(), e.line(), e.column(), e.message(), e.hint());
    PyErr_SetObject(cls.ptr(), err.ptr());
  } catch (const InconsistentInitialState& e) {
    // a ValueError, as every std::invalid_argument, typed with its cause (in the order of
    // InconsistentInitialState::Cause)
    static const char* const causes[] = {"not_projected", "contradictory", "projection_failed",
                                         "penetrated"};
    py::object cls = error_class("InconsistentInitialState");
    py::object err = cls(valid_utf8(user_message(e)), causes[int(e.cause())]);
    PyErr_SetObject(cls.ptr(), err.ptr());
  } catch (const SettingError& e) {
    // a ValueError naming the setting, without the C++ function's name
    PyErr_SetString(PyExc_ValueError, valid_utf8(user_message(e)).c_str());
  } catch (const SolveError& e) {
    py::object cls = error_class("SolveError");
    py::object err = cls(e.what(), to_string(e.status()));
    PyErr_SetObject(cls.ptr(), err.ptr());
  } catch (const py::builtin_exception&) {
    throw;  // pybind11's own (py::value_error, …): its default translation
  } catch (const py::error_already_set&) {
    throw;
  } catch (const std::invalid_argument& e) {
    // misuse of a run (a non-finite q0, sizes that differ): a ValueError without the C++
    // function's name "ukdyn::simulate: ", as for SettingError (docs/python.md, "Errors")
    std::string text = valid_utf8(e.what());
    static constexpr std::string_view kSimulate = "ukdyn::simulate: ";
    if (text.rfind(kSimulate, 0) == 0) {
      text.erase(0, kSimulate.size());
    } else if (text == e.what()) {
      throw;
    }
    PyErr_SetString(PyExc_ValueError, text.c_str());
  } catch (const std::exception& e) {
    // a message that is not valid UTF-8 (pybind11's default would raise UnicodeDecodeError
    // in its place): the same Python class, with U+FFFD for each bad byte; otherwise the default
    const std::string text = valid_utf8(e.what());
    if (text == e.what()) throw;
    PyObject* cls = dynamic_cast<const std::invalid_argument*>(&e) != nullptr ||
                            dynamic_cast<const std::domain_error*>(&e) != nullptr
                        ? PyExc_ValueError
                        : PyExc_RuntimeError;
    PyErr_SetString(cls, text.c_str());
  }
}

// Debian's three.js file `name` embedded at build time (python/CMakeLists.txt), as bytes; None
// for another name or when the module was built without libjs-three
py::object viewer_script(const std::string& name) {
  static const std::pair<const char*, const char* const*> scripts[] = {
      {"three.min.js", &cli::kThreeJs},
      {"OrbitControls.js", &cli::kOrbitControlsJs},
      {"STLLoader.js", &cli::kStlLoaderJs},
      {"OBJLoader.js", &cli::kObjLoaderJs},
      {"ColladaLoader.js", &cli::kColladaLoaderJs}};
  for (const auto& [file, text] : scripts)
    if (name == file && **text != '\0') return py::bytes(*text);
  return py::none();
}

}  // namespace
}  // namespace ukdyn::python

PYBIND11_MODULE(_ukdyn, m) {
  namespace up = ukdyn::python;
  m.doc() =
      "ukdyn's compiled core (pybind11). Use the package `ukdyn`, which wraps it; docs/python.md.";
  pybind11::register_exception_translator(&up::translate);
  up::register_gil_gate(m);
  up::bind_model(m);
  up::bind_solver(m);
  up::bind_control(m);
  up::bind_callables(m);
  up::bind_ensemble(m);
  up::bind_linearize(m);
  // the options table (simulation/options.hpp): what every simulate() accepts
  m.def("_options", &up::options_list,
        "The simulation options table: a list of dicts (name, type, default, range, choices, "
        "aliases, solver, flag, example, doc).");
  m.def("_viewer_script", &up::viewer_script, pybind11::arg("name"),
        "Debian's three.js file `name` (three.min.js, OrbitControls.js, STLLoader.js, "
        "OBJLoader.js, ColladaLoader.js) as embedded at build time: bytes, or None when the "
        "module was built without libjs-three. viewer.py's fallback.");
  m.def(
      "_simulation_options",
      [](const pybind11::dict& settings) {
        ukdyn::SimulationOptions o;
        up::apply_simulation_options(o, settings, "simulation_options");
        return up::simulation_options_dict(o);
      },
      pybind11::arg("settings"),
      "The default options with `settings` applied through the table's setter, as a dict.");
}

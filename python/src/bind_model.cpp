// SPDX-License-Identifier: BSD-3-Clause
// ukdyn.Model: model files and the built-in examples (modelfile/model.hpp), run as `ukdyn run` runs
// them (modelfile/run.hpp), and check_model.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>

#include "common.hpp"
#include "embedded.hpp"  // app/embedded.hpp: the example models, embedded at build time
#include "modelfile/contact_start.hpp"  // src/: the run refused at its contacts' start
#include "suggest.hpp"                  // app/suggest.hpp: did-you-mean, as the command's
#include "ukdyn/core/format.hpp"
#include "ukdyn/io/provenance.hpp"
#include "ukdyn/io/trajectory_files.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/modelfile/visual.hpp"

namespace ukdyn::python {
namespace {

using Overrides = std::map<std::string, double>;

// "<what> called 'name' (did you mean 'X'?); the examples are A, B, ...": the nearest example
// suggested by the command's rule (app/suggest.cpp), so both suggest the same name
std::invalid_argument unknown_example(const std::string& what, const std::string& name) {
  std::vector<std::string> names;
  std::string list;
  for (const auto& f : cli::example_models()) {
    names.emplace_back(f.name);
    list += (list.empty() ? "" : ", ") + names.back();
  }
  return std::invalid_argument(what + " called '" + name + "'" + cli::did_you_mean(name, names) +
                               "; the examples are " + list);
}

const cli::EmbeddedFile* find_example(const std::string& name) {
  for (const auto& f : cli::example_models()) {
    if (name == f.name) return &f;
  }
  return nullptr;
}

// the model run with settings; q0 / qd0 replace the initial state when given; `stop` is asked
// every InterruptCheck::kInterval whether to stop (after Python's signal handlers ran)
py::tuple run(const Model& model, const py::dict& settings, py::object q0, py::object qd0,
              py::object stop, py::object source) {
  SimulationOptions o = model.options;
  apply_simulation_options(o, settings, "Model.simulate");
  const InterruptCheck interrupt(stop);
  interrupt.attach(o);
  const Model* m = &model;
  std::optional<Model> changed;
  if (!q0.is_none() || !qd0.is_none()) {
    changed.emplace(model);
    if (!q0.is_none())
      read_vector(q0, model.system.coordinate_count(), "Model.simulate", "q0", changed->q0);
    if (!qd0.is_none())
      read_vector(qd0, model.system.coordinate_count(), "Model.simulate", "qd0", changed->qd0);
    m = &*changed;
  }
  ModelRun r;
  {
    ReleasedGil release;  // the run is C++ only (model files hold no Python code)
    try {
      r = run_model(*m, o);
    } catch (const detail::ContactStartError& e) {
      // at the friction's or contact's entry, as `ukdyn run` says it (app/run.cpp)
      throw ContactStartModelError(detail::locate_contact_start(*m, e));
    }
  }
  // what the run was made from, as `ukdyn run` records it (model_provenance): the source that
  // ukdyn.load kept (file or example, SHA-256 of its text, the overridden parameters)
  RunProvenance provenance;
  if (!source.is_none()) {
    const py::dict d = source.cast<py::dict>();
    provenance =
        model_provenance(*m, d["file"].cast<std::string>(), d["example"].cast<std::string>(), "",
                         d["overridden"].cast<std::vector<std::string>>(), {});
    provenance.model_sha256 = d["sha256"].cast<std::string>();
  } else {
    provenance = model_provenance(*m, model.file, "", "", {}, {});
    provenance.model_sha256.clear();  // (not known: a model parsed from text, or from_sympy)
  }
  return run_tuple(std::move(r), interrupt.exception(), o, &provenance);
}

// the model with what it was loaded from, for its runs' provenance (Model._source)
py::object with_source(std::shared_ptr<Model> md, const std::string& file,
                       const std::string& example, std::string_view text,
                       const Overrides& overrides) {
  py::object obj = py::cast(std::move(md));
  py::dict d;
  std::error_code ec;
  const auto absolute =
      file.empty() ? std::filesystem::path() : std::filesystem::absolute(file, ec);
  d["file"] = file.empty() || ec ? file : absolute.lexically_normal().string();
  d["example"] = example;
  d["sha256"] = sha256_hex(text);
  std::vector<std::string> names;
  for (const auto& given : overrides) names.push_back(given.first);
  d["overridden"] = names;
  obj.attr("_source") = d;
  return obj;
}

py::dict check(const Model& model) {
  CheckReport r;
  {
    ReleasedGil release;
    r = check_model(model);
  }
  py::dict d;
  d["coordinates"] = r.coordinates;
  d["constraint_rows"] = r.constraint_rows;
  d["rank"] = r.rank;
  d["degrees_of_freedom"] = r.degrees_of_freedom;
  d["redundant"] = r.redundant;
  d["initial_violations"] = r.initial_violations;
  d["mass_positive_definite"] = r.mass_positive_definite;
  d["mass_singular"] = r.mass_singular;
  d["problems"] = r.problems;
  d["ok"] = r.ok();
  return d;
}

}  // namespace

void bind_model(py::module_& m) {
  py::class_<Model, std::shared_ptr<Model>>(m, "Model", py::dynamic_attr(), R"doc(
A model read from a model file, an example or SymPy expressions (the C++ ukdyn::Model): the
system, its parameters, initial state and simulation settings, output expressions and, when
the file has a `control:` section, its controller. Immutable; load one with ukdyn.load(),
ukdyn.parse() or ukdyn.from_sympy(). Model.simulate() runs it exactly as `ukdyn run` does.
)doc")
      .def_readonly("name", &Model::name, "The model's `name:` (the file name otherwise).")
      .def_readonly("file", &Model::file,
                    "Where it came from (a path, examples/models/NAME.yaml, "
                    "or the name given to parse()).")
      .def_property_readonly(
          "parameters", [](const Model& md) { return py::dict(py::cast(md.parameters)); },
          "The `parameters:` after overrides, as a new dict name -> value.")
      .def_property_readonly(
          "coordinates", [](const Model& md) { return md.system.coordinate_names(); },
          "The coordinate names (n).")
      .def_property_readonly(
          "units",
          [](const Model& md) {
            py::dict out;
            const auto& names = md.system.coordinate_names();
            for (std::size_t i = 0; i < names.size(); ++i) {
              out[py::str(names[i])] =
                  i < md.coordinate_units.size() ? md.coordinate_units[i] : std::string();
            }
            for (std::size_t i = 0; i < md.output_names.size(); ++i) {
              const py::str name(md.output_names[i]);
              if (!out.contains(name)) {
                out[name] = i < md.output_units.size() ? md.output_units[i] : std::string();
              }
            }
            for (const auto& [name, unit] : contact_gap_units(md)) out[py::str(name)] = unit;
            return out;
          },
          "Each coordinate's and output expression's unit, as a new dict name -> unit: the "
          "file's `units:`, else the length unit (m), rad and 1 (quaternion components) for the "
          "bodies' coordinates and a robot's joints (by the joint's kind), else \"\" (not "
          "known); the length unit of the gap column gap.<name> of each contacts: entry of a "
          "bodies or robot model (a distance), a generalized model's gap in the unit its "
          "coordinates share; the force unit of each contact's lambda.<name> and "
          "lambda_total.<name> (the torque's for a gap in rad), and of its friction's holding "
          "force lambda.stick.<friction>.i.")
      .def_property_readonly(
          "unit_system",
          [](const Model& md) {
            const UnitSystem& u = md.unit_system;
            py::dict out;
            out["length"] = u.length;
            out["mass"] = u.mass;
            out["time"] = u.time;
            out["velocity"] = u.velocity();
            out["force"] = u.force();
            out["energy"] = u.energy();
            out["power"] = u.power();
            return out;
          },
          "The model's units (`units: {length: mm, mass: g, time: ms}`, SI when not given) and "
          "the labels derived from them, as a new dict: length, mass, time, velocity, force, "
          "energy, power (N, J, W only in SI units; g·mm²/ms² in g, mm, ms). Labels only: no "
          "number is converted.")
      .def_property_readonly(
          "constraints",
          [](const Model& md) {
            py::list out;
            for (const Constraint& c : md.system.constraints()) out.append(c.name());
            return out;
          },
          "The constraint names, including the stick constraints of Coulomb friction.")
      .def_property_readonly(
          "q0", [](const Model& md) { return copy_vector(md.q0); },
          "The initial positions of `initial: q:` (n; a copy, not projected).")
      .def_property_readonly(
          "qd0", [](const Model& md) { return copy_vector(md.qd0); },
          "The initial velocities of `initial: q_dot:` (n; a copy).")
      .def_readonly("project_initial", &Model::project_initial, "`initial: project:`.")
      .def_property_readonly(
          "options", [](const Model& md) { return simulation_options_dict(md.options); },
          "The `simulate:` and `output:` settings as a dict (the keys simulate() accepts).")
      .def_readonly("output_names", &Model::output_names,
                    "The names of the `output: expressions:` (the last CSV columns).")
      .def_property_readonly(
          "system",
          [](const Model& md) {
            return SystemHandle{md.system, nullptr};
          },
          "The System (the plant, without its controller).")
      .def_property_readonly(
          "controller",
          [](const Model& md) -> py::object {
            if (!md.controller) return py::none();
            return py::cast(ControllerHandle{md.controller, nullptr});
          },
          "The Controller of the `control:` section, or None.")
      .def_property_readonly(
          "_scene_json", [](const Model& md) { return viewer_scene_json(md); },
          "The scene the browser viewer draws (modelfile/visual.hpp), as JSON text; "
          "Result.show() uses it.")
      .def_property_readonly(
          "is_multibody", [](const Model& md) { return bool(md.multibody); },
          "True for a model written with bodies:/joints:/forces:.")
      .def("_run", &run, py::arg("settings"), py::arg("q0") = py::none(),
           py::arg("qd0") = py::none(), py::arg("stop") = py::none(),
           py::arg("source") = py::none(),
           "Runs the model (run_model, modelfile/run.hpp) with the GIL released; returns (names, "
           "columns, "
           "statistics, control statistics or None, the exception a signal handler raised or "
           "None, the summary.json text). source: Model._source (ukdyn.load's), for the "
           "summary's provenance. stop() is called every 20 ms of the run, after Python's signal "
           "handlers; "
           "true stops the run. Use Model.simulate().")
      .def("check", &check,
           R"doc(What `ukdyn check` reports (check_model, modelfile/model.hpp), as a dict:
coordinates, constraint_rows, rank, degrees_of_freedom, redundant (constraint names),
initial_violations, mass_positive_definite, mass_singular, problems, ok.)doc")
      .def(
          "solver",
          [](const Model& md, py::kwargs kw) {
            return py::cast(SystemHandle{md.system, nullptr}).attr("solver")(**kw);
          },
          "A Solver of the model's system (see System.solver()).")
      .def("__repr__", [](const Model& md) {
        return "<ukdyn.Model '" + md.name +
               "' n=" + ukdyn::format_number(md.system.coordinate_count()) +
               " constraints=" + ukdyn::format_number(md.system.constraint_count()) +
               (md.controller ? " controlled" : "") + ">";
      });

  m.def(
      "_load_file",
      [](const std::string& path, const Overrides& overrides, const GivenTables& tables) {
        std::shared_ptr<Model> md;
        std::string text;
        {
          ReleasedGil release;
          md = std::make_shared<Model>(load_model(path, overrides, tables));
          std::ifstream in(path, std::ios::binary);
          text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        }
        return with_source(std::move(md), path, "", text, overrides);
      },
      py::arg("path"), py::arg("overrides"), py::arg("tables") = GivenTables{},
      "load_model(path, overrides, tables). Raises ModelError.");
  m.def(
      "_parse",
      [](const std::string& text, const std::string& file, const Overrides& overrides,
         const GivenTables& tables) {
        ReleasedGil release;
        return std::make_shared<Model>(parse_model(text, file, overrides, tables));
      },
      py::arg("text"), py::arg("file"), py::arg("overrides"), py::arg("tables") = GivenTables{},
      "parse_model(text, file, overrides, tables). Raises ModelError.");
  m.def(
      "_load_example",
      [](const std::string& name, const Overrides& overrides, const GivenTables& tables) {
        const cli::EmbeddedFile* f = find_example(name);
        if (!f) throw unknown_example("no model file or example", name);
        std::shared_ptr<Model> md;
        {
          ReleasedGil release;
          md = std::make_shared<Model>(
              parse_model(f->text, "examples/models/" + name + ".yaml", overrides, tables));
        }
        return with_source(std::move(md), "", name, f->text, overrides);
      },
      py::arg("name"), py::arg("overrides"), py::arg("tables") = GivenTables{},
      "The built-in example `name`. Raises ValueError listing the examples for another name.");
  m.def(
      "_write_table_hdf5",
      [](const std::string& path, const std::vector<std::string>& names,
         const std::vector<std::vector<double>>& values, const std::string& summary) {
        if (names.size() != values.size())
          throw std::invalid_argument("_write_table_hdf5: names and columns differ in number");
        std::vector<CsvColumn> columns;
        for (std::size_t c = 0; c < names.size(); ++c) columns.push_back({names[c], values[c]});
        ReleasedGil release;
        write_table_hdf5(path, columns, summary);
      },
      py::arg("path"), py::arg("names"), py::arg("columns"), py::arg("summary"),
      "write_table_hdf5(path, columns, summary) (io/trajectory_files.hpp).");
  m.def(
      "_read_table_hdf5",
      [](const std::string& path) {
        std::vector<CsvColumn> columns;
        std::string summary;
        {
          ReleasedGil release;
          columns = read_table_hdf5(path);
          try {
            summary = read_hdf5_string_attribute(path, "summary");
          } catch (const std::runtime_error&) {
            summary.clear();  // a table written without a summary
          }
        }
        py::list names, values;
        for (auto& c : columns) {
          names.append(c.name);
          values.append(py::array_t<double>(py::ssize_t(c.values.size()), c.values.data()));
        }
        return py::make_tuple(names, values, summary);
      },
      py::arg("path"), "(names, columns, summary text) of a write_table_hdf5 file.");
  m.def(
      "examples",
      []() {
        std::vector<std::string> names;
        for (const auto& f : cli::example_models()) names.emplace_back(f.name);
        return names;
      },
      "The names of the built-in example models (examples/models/*.yaml), sorted.");
  m.def(
      "example_text",
      [](const std::string& name) {
        const cli::EmbeddedFile* f = find_example(name);
        if (!f) throw unknown_example("no example", name);
        return std::string(f->text);
      },
      py::arg("name"),
      "The YAML text of a built-in example. Raises ValueError listing the examples.");
}

}  // namespace ukdyn::python

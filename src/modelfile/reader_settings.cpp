// SPDX-License-Identifier: BSD-3-Clause
// Model files, the run's part: the initial state (initial:, with keep), the run settings
// (simulate:, output:) and their check, the mass matrix at the initial state, the output
// expressions and the units. The reader's other stages are in reader.cpp (parameters,
// coordinates, dynamics, constraints, non-ideal forces), reader_multibody.cpp, reader_control.cpp
// and reader_visual.cpp.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <string_view>

#include <yaml-cpp/yaml.h>
#include <Eigen/Cholesky>

#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/multibody/tree.hpp"
#include "ukdyn/simulation/options.hpp"

#include "modelfile/initial_keep.hpp"
#include "modelfile/reader.hpp"

namespace ukdyn::model_reader {

void Reader::read_initial(const YAML::Node& root, Model& model) {
  const Index n = Index(coordinates_.size());
  // a multibody model's bodies give the initial state; initial: overrides it by name
  if (model.q0.size() != n) model.q0 = VectorXd::Zero(n);
  if (model.qd0.size() != n) model.qd0 = VectorXd::Zero(n);
  const YAML::Node init = root["initial"];
  if (!init) return;
  if (!init.IsMap()) fail(init, "initial must be a mapping with q, q_dot and project");
  positions_.initial = position(init);
  // a coordinate's value written straight under initial: (initial: {x: 1}) would otherwise be
  // ignored: every key is checked, and a coordinate's name gets a hint to its place
  for (const auto& kv : init) {
    const std::string key = kv.first.Scalar();
    if (key == "q" || key == "q_dot" || key == "project") continue;
    const std::string base = key.size() > 4 && key.compare(key.size() - 4, 4, "_dot") == 0
                                 ? key.substr(0, key.size() - 4)
                                 : key;
    const bool coordinate_name =
        std::find(coordinates_.begin(), coordinates_.end(), base) != coordinates_.end();
    fail(kv.first, "unknown key '" + key + "' in initial",
         coordinate_name ? "positions go under q and velocities under q_dot: initial: {q: {" +
                               base + ": 1}, q_dot: {" + base + ": 0}}"
                         : "initial has q, q_dot and project");
  }
  auto read_map = [&](const char* key, VectorXd& v) {
    const YAML::Node m = init[key];
    if (!m) return;
    if (!m.IsMap())
      fail(m, std::string("initial ") + key + " must map coordinate names to values",
           "q: {x: 0, y: 1}");
    for (const auto& kv : m)
      v[coordinate(kv.first)] = number(kv.second, std::string("initial ") + key);
  };
  read_map("q", model.q0);
  read_map("q_dot", model.qd0);
  const YAML::Node project = init["project"];
  if (project && project.IsMap()) {
    // project: {keep: [x, y_dot, …]}: x keeps its position and its velocity, y_dot the velocity
    for (const auto& kv : project) {
      if (kv.first.Scalar() != "keep")
        fail(kv.first, "unknown key '" + kv.first.Scalar() + "' in initial: project",
             "project: true, or project: {keep: [names]}");
    }
    const YAML::Node keep = project["keep"];
    if (!keep || !keep.IsSequence() || keep.size() == 0) {
      fail(keep ? keep : project, "keep must be a list of coordinates (x) or velocities (x_dot)",
           "project: {keep: [crank_theta]} keeps the crank's angle and rate");
    }
    keep_node_ = keep;
    keep_q_.assign(std::size_t(n), 0);
    keep_qd_.assign(std::size_t(n), 0);
    for (const auto& k : keep) {
      const std::string name = k.Scalar();
      bool velocity_only = false;
      Index j = -1;
      for (std::size_t i = 0; i < coordinates_.size() && j < 0; ++i) {
        if (names_coordinate(name, coordinates_[i])) j = Index(i);
      }
      for (std::size_t i = 0; i < velocities_.size() && j < 0; ++i) {
        if (names_coordinate(name, velocities_[i])) {
          j = Index(i);
          velocity_only = true;
        }
      }
      if (!k.IsScalar() || j < 0) {
        fail(k, "keep: '" + name + "' is not a coordinate or a velocity",
             "the coordinates are " + join(coordinates_) +
                 " (x keeps x and x_dot, x_dot only the velocity)");
      }
      if ((velocity_only ? keep_qd_ : keep_q_)[std::size_t(j)])
        fail(k, "keep: '" + name + "' is listed twice");
      if (!velocity_only) keep_q_[std::size_t(j)] = 1;
      keep_qd_[std::size_t(j)] = 1;
      kept_names_.push_back(name);
    }
    model.project_initial = true;
  } else if (project) {
    bool value = false;
    if (!project.IsScalar() || !YAML::convert<bool>::decode(project, value))
      fail(project, "initial project must be true or false, or {keep: [names]}", "project: true");
    model.project_initial = value;
  }
}

void Reader::apply_keep(Model& model) {
  if (keep_q_.empty()) return;
  const std::string why = project_keeping(model.system, model.q0, model.qd0, model.options.t_start,
                                          keep_q_, keep_qd_, kept_names_);
  if (!why.empty()) {
    fail(keep_node_, "initial: project: " + why,
         "keep fewer coordinates, or give values that the constraints allow");
  }
}

void Reader::read_simulate(const YAML::Node& root, Model& model) {
  SimulationOptions& o = model.options;
  // the defaults with a time dimension are SimulationOptions' in seconds, converted into the
  // model's time unit (units: {time: ms}: t_end 1000, output_every 10, step 1, Baumgarte's gains
  // 0.01 per ms), so that a model in ms runs on its defaults as the same model in s
  {
    UnitSystem units;
    if (const YAML::Node u = root["units"]; u && u.IsMap()) read_unit_system(u, units);
    const SimulationOptions d;
    const double per_s = units.per_second();
    o.t_end = 1.0 * per_s;
    o.output_every = d.output_every * per_s;
    o.step = d.step * per_s;
    o.baumgarte_alpha = d.baumgarte_alpha / per_s;
    o.baumgarte_beta = d.baumgarte_beta / per_s;
  }
  const YAML::Node s = root["simulate"];
  if (!s) return;
  if (!s.IsMap()) fail(s, "simulate must be a mapping", "{t_end: 2, integrator: dopri5}");
  positions_.simulate = position(s);
  // every key is an option of the table (simulation/options.hpp), set by its one validating setter
  for (const auto& kv : s) {
    const std::string key = kv.first.Scalar();
    const YAML::Node v = kv.second;
    const OptionInfo* info = find_option(key);
    if (!info) fail(kv.first, "unknown key '" + key + "' in simulate", option_names());
    positions_.settings[info->name] = position(v);
    try {
      switch (info->type) {
        case OptionType::kNumber:
        case OptionType::kInteger:
          // a number, or an expression of the parameters
          set_option(o, key, number(v, key));
          break;
        case OptionType::kNumbers: {
          if (!v.IsSequence()) fail(v, key + " must be a list of numbers", "[0.5, 1.5]");
          std::vector<double> list;
          for (const auto& x : v) list.push_back(number(x, key));
          set_option(o, key, list);
          break;
        }
        case OptionType::kBool:
        case OptionType::kChoice:
          if (!v.IsScalar()) fail(v, key + " must be " + option_rule(*info));
          set_option_text(o, key, v.Scalar());
          break;
      }
    } catch (const OptionError& e) {
      fail(v, e.problem(), e.hint());
    }
  }
  if (!(o.t_end > o.t_start)) fail(s, "t_end must be greater than t_start");
  // solver options that this system cannot use (engine: sparse with a dense M, …) are refused
  // here, at their key, as the workspace a run makes would refuse them
  std::vector<YAML::Node> solver_keys;
  for (const auto& kv : s) {
    if (find_option(kv.first.Scalar())->solver) solver_keys.push_back(kv.first);
  }
  if (!solver_keys.empty()) {
    try {
      Workspace ws(model.system, o.solver);
    } catch (const std::invalid_argument& e) {
      std::string message = e.what();
      if (const auto k = message.find(": "); k != std::string::npos) message.erase(0, k + 2);
      YAML::Node at = solver_keys.front();
      for (const YAML::Node& key : solver_keys) {
        if (message.find(key.Scalar()) != std::string::npos) at = key;
      }
      fail(at, message);
    }
  }
}

// M(q0, t_start) must be symmetric positive semi-definite, and where it is singular the
// constraints must determine the coordinates it gives no inertia ([M; A] of full column rank):
// a model that fails here cannot start, so the error points at the declaration of M (or T)
// rather than at the run.
void Reader::check_mass_matrix(const YAML::Node& root, const Model& model) {
  const Index n = model.system.coordinate_count();
  // M given by constant blocks is symmetric positive definite when they are (read_dynamics
  // gives blocks only then; a dense M of many coordinates would not fit)
  if (model.system.mass_is_block_diagonal() &&
      std::all_of(model.system.mass_blocks().begin(), model.system.mass_blocks().end(),
                  [](const MassBlock& b) {
                    return b.constant() && !b.singular && b.value.allFinite() &&
                           b.value == b.value.transpose() &&
                           Eigen::LLT<MatrixXd>(b.value).info() == Eigen::Success;
                  })) {
    return;
  }
  MatrixXd M(n, n);
  model.system.mass_matrix(model.q0, model.options.t_start, M);
  const YAML::Node at = root["mass_matrix"] ? root["mass_matrix"] : root["kinetic_energy"];
  const std::string where = " at the initial state (t = " + brief(model.options.t_start) + ")";
  const std::string source = root["mass_matrix"] ? "mass_matrix" : "kinetic_energy";
  if (!M.allFinite()) {
    fail(at, "the mass matrix is not finite" + where,
         "check " + source + " for divisions by zero or logarithms of non-positive values at q0");
  }
  const double scale = M.cwiseAbs().maxCoeff();
  if ((M - M.transpose()).cwiseAbs().maxCoeff() > 1e-12 * scale) {
    fail(at, "the mass matrix is not symmetric" + where, "M(i, j) must equal M(j, i)");
  }
  if (scale > 0.0 && Eigen::LLT<MatrixXd>(M).info() == Eigen::Success) return;
  // the names of the coordinates i with pred(i), comma-separated
  const auto coordinates_where = [&](auto pred) {
    std::string names;
    for (Index i = 0; i < n; ++i) {
      if (pred(i)) names += (names.empty() ? "" : ", ") + coordinates_[std::size_t(i)];
    }
    return names;
  };
  // a singular M is accepted when it is positive semi-definite (M + 1e-10 max|M| I positive
  // definite) and the constraints determine the coordinates it gives no inertia
  MatrixXd shifted = M;
  shifted.diagonal().array() += 1e-10 * (scale > 0.0 ? scale : 1.0);
  const bool from_T = source == "kinetic_energy";
  if (Eigen::LLT<MatrixXd>(shifted).info() != Eigen::Success) {
    const std::string negative = coordinates_where([&](Index i) { return M(i, i) < 0; });
    fail(at, "the mass matrix is not positive semi-definite" + where,
         !negative.empty()
             ? "negative inertia for " + negative +
                   (from_T ? ": the kinetic energy must not decrease with any velocity"
                           : ": every diagonal entry of M must be >= 0")
             : (from_T ? "the kinetic energy must be >= 0 for every velocity"
                       : "M must be positive semi-definite: check the off-diagonal entries"));
  }
  Workspace ws(model.system, model.options.solver);
  // (with every unilateral contact open as well: a coordinate that only a contact determines
  // has no acceleration once it opens — u16 04, a floor under a coordinate without inertia)
  Status status = forward_dynamics(model.system, ws, model.q0, model.qd0, model.options.t_start);
  bool contacts = false;
  for (Index k = 0; k < model.system.constraint_count(); ++k) {
    if (!model.system.constraint(k).is_unilateral()) continue;
    ws.activity_override[std::size_t(k)] = 0;
    contacts = true;
  }
  if (status != Status::kMotionUndetermined && contacts)
    status = forward_dynamics(model.system, ws, model.q0, model.qd0, model.options.t_start);
  if (status == Status::kMotionUndetermined) {
    const std::string lacking = coordinates_where([&](Index i) { return !(M(i, i) > 0); });
    // a control requirement on such a coordinate does not determine it either: it is met by a
    // force, and no force determines the acceleration of a coordinate without inertia (its row
    // of M q'' = Q + F reads 0 = Q_i + F_i whatever q''_i is: docs/singular-mass.md, "Limits").
    // (the controller is read after the plant: the requirements' expressions are scanned for
    // the names of those coordinates, x, x_dot or x_ddot, with '.' written '_')
    std::string required;
    const YAML::Node reqs = root["control"] ? root["control"]["requirements"] : YAML::Node();
    if (reqs && reqs.IsSequence()) {
      const auto names_lacking = [&](const std::string& expr) {
        for (std::size_t p = 0; p < expr.size();) {
          const auto c = static_cast<unsigned char>(expr[p]);
          if (!(std::isalpha(c) || c == '_')) {
            ++p;
            continue;
          }
          std::size_t e = p;
          while (e < expr.size() && (std::isalnum(static_cast<unsigned char>(expr[e])) ||
                                     expr[e] == '_' || expr[e] == '.')) {
            ++e;
          }
          std::string id = expr.substr(p, e - p);
          for (const char* suffix : {"_ddot", "_dot"}) {
            const std::string sfx = suffix;
            if (id.size() > sfx.size() &&
                id.compare(id.size() - sfx.size(), sfx.size(), sfx) == 0) {
              id.resize(id.size() - sfx.size());
              break;
            }
          }
          for (Index i = 0; i < n; ++i) {
            std::string name = coordinates_[std::size_t(i)];
            std::replace(name.begin(), name.end(), '.', '_');
            if (!(M(i, i) > 0) && (id == name || id == coordinates_[std::size_t(i)])) return true;
          }
          p = e;
        }
        return false;
      };
      for (const auto& r : reqs) {
        if (!r.IsMap() || !r["name"]) continue;
        bool touches = false;
        for (const char* kind : {"holonomic", "nonholonomic", "acceleration"}) {
          if (r[kind] && r[kind].IsScalar()) touches = touches || names_lacking(r[kind].Scalar());
        }
        if (touches) required += (required.empty() ? "'" : ", '") + r["name"].Scalar() + "'";
      }
    }
    const std::string control_hint =
        required.empty()
            ? std::string()
            : "; the control requirement " + required +
                  " does not fix them: a requirement is met by a force, and a force does not "
                  "determine the acceleration of a coordinate without inertia (0 = Q + F on its "
                  "row, whatever the acceleration) — if its motion is prescribed, write it under "
                  "constraints:, else give the coordinate inertia";
    fail(at,
         "the mass matrix is singular" + where +
             " and the constraints do not determine "
             "every coordinate: " +
             describe_status(model.system, ws),
         (lacking.empty() ? std::string("give the coordinates inertia")
                          : "no inertia for " + lacking) +
             (from_T ? ": the kinetic energy must involve every velocity that no constraint fixes"
                     : ": a zero row of M needs constraints that fix its coordinate") +
             (contacts ? " (a unilateral contact does not: it may open)" : "") + control_hint);
  }
}

void Reader::read_output(const YAML::Node& root, Model& model) {
  SimulationOptions& o = model.options;
  const YAML::Node out = root["output"];
  std::vector<Expr> exprs;
  if (out) {
    if (!out.IsMap())
      fail(out, "output must be a mapping", "{every: 0.01, at: [1], expressions: {s: x + y}}");
    for (const auto& kv : out) {
      const std::string key = kv.first.Scalar();
      if (key == "every") {
        o.output_every = number(kv.second, "every");
        if (o.output_every < 0) fail(kv.second, "every must be >= 0");
        positions_.settings["output_every"] = position(kv.second);
      } else if (key == "at") {
        if (!kv.second.IsSequence()) fail(kv.second, "at must be a list of times");
        positions_.settings["output_at"] = position(kv.second);
        for (const auto& tn : kv.second) {
          const double t = number(tn, "output time");
          if (t < o.t_start || t > o.t_end) {
            fail(tn, "output time " + tn.Scalar() + " is outside the run [" + brief(o.t_start) +
                         ", " + brief(o.t_end) + "]");
          }
          o.output_at.push_back(t);
        }
      } else if (key == "expressions") {
        if (!kv.second.IsMap()) fail(kv.second, "expressions must map names to expressions");
        for (const auto& e : kv.second) {
          model.output_names.push_back(e.first.Scalar());
          exprs.push_back(expression(e.second, "output expression '" + e.first.Scalar() + "'"));
        }
      } else {
        fail(kv.first, "unknown key '" + key + "' in output", "every, at, expressions");
      }
    }
  }
  note_desired(root);
  for (const auto& [name, e] : desired_outputs_) {
    if (std::find(model.output_names.begin(), model.output_names.end(), name) !=
        model.output_names.end())
      continue;
    model.output_names.push_back(name);
    exprs.push_back(e);
  }
  add_gap_outputs(root, model, exprs);
  read_visual(root, model, exprs);
  model.output_program = compile(exprs, out ? out : root, "the output expressions");
}

namespace {
bool is_base_unit_key(const std::string& key) {
  return key == "length" || key == "mass" || key == "time";
}
}  // namespace

// units: {length: mm, mass: g, time: ms}: the model's base units, each from its accepted list
// (UnitSystem::kLengths, kMasses, kTimes); with a coordinate named like one of the keys the key
// is refused, since it names the base unit
void Reader::read_unit_system(const YAML::Node& u, UnitSystem& units) {
  auto one = [&](const char* key, const auto& accepted, std::string& out) {
    const YAML::Node v = u[key];
    if (!v) return;
    const bool taken =
        std::any_of(coordinates_.begin(), coordinates_.end(),
                    [&](const std::string& c) { return c == key || names_coordinate(key, c); });
    if (taken) {
      fail(v,
           std::string("units: '") + key + "' is the unit of " + key +
               " of the model, but a coordinate is also named '" + key + "'",
           "rename the coordinate (its unit can then be given by its name)");
    }
    std::string list;
    for (std::string_view a : accepted) list += (list.empty() ? "" : ", ") + std::string(a);
    const std::string text = v.IsScalar() ? v.Scalar() : std::string();
    if (std::find(accepted.begin(), accepted.end(), text) == accepted.end()) {
      fail(
          v,
          std::string("units: unknown unit of ") + key + " '" + text + "' (accepted: " + list + ")",
          std::string("units: {") + key + ": " + std::string(accepted[1]) +
              "} (the unit labels the console, the summary and the plots; it changes no "
              "number: write the model's numbers in it)");
    }
    out = text;
  };
  one("length", UnitSystem::kLengths, units.length);
  one("mass", UnitSystem::kMasses, units.mass);
  one("time", UnitSystem::kTimes, units.time);
}

void Reader::read_units(const YAML::Node& root, Model& model) {
  const std::vector<std::string>& names = model.system.coordinate_names();
  model.coordinate_units.assign(names.size(), "");
  model.output_units.assign(model.output_names.size(), "");
  const YAML::Node u = root["units"];
  if (u && (!u.IsMap() || u.size() == 0)) {
    fail(u, "units must map coordinates (or output expressions) to their units",
         "units: {x: m, theta: rad}, or the base units: units: {length: mm, mass: g, time: ms}");
  }
  // the base units: length, mass, time (SI unless given), from the accepted lists
  if (u) read_unit_system(u, model.unit_system);
  // a body's coordinates: its centre of mass in the length unit, its angle in rad, its
  // quaternion's components without unit (the multibody layer's conventions, docs/multibody.md)
  if (model.multibody) {
    for (std::size_t i = 0; i < names.size(); ++i) {
      const std::string& c = names[i];
      const std::string suffix =
          c.substr(c.rfind('.') == std::string::npos ? c.size() : c.rfind('.'));
      if (suffix == ".x" || suffix == ".y" || suffix == ".z") {
        model.coordinate_units[i] = model.unit_system.length;
      } else if (suffix == ".theta") {
        model.coordinate_units[i] = "rad";
      } else if (suffix == ".u0" || suffix == ".u1" || suffix == ".u2" || suffix == ".u3") {
        model.coordinate_units[i] = "1";
      }
    }
  }
  // a robot's joints (docs/robots.md): a revolute or continuous joint's angle in rad, a
  // prismatic joint's displacement in the length unit, a floating base's position in the length
  // unit and its quaternion's components without unit
  if (model.robot) {
    // (the system's coordinates are the tree's, in its order: tree::system_builder)
    const tree::Tree& robot = *model.robot;
    for (Index i = 0; i < robot.link_count(); ++i) {
      const tree::JointKind kind = robot.link(i).joint.kind;
      for (int k = 0; k < robot.dofs(i); ++k) {
        const std::size_t j = std::size_t(robot.offset(i) + k);
        if (j >= names.size()) continue;
        std::string& unit = model.coordinate_units[j];
        if (kind == tree::JointKind::kRevolute || kind == tree::JointKind::kContinuous)
          unit = "rad";
        else if (kind == tree::JointKind::kPrismatic ||
                 (kind == tree::JointKind::kFloating && k < 3))
          unit = model.unit_system.length;
        else if (kind == tree::JointKind::kFloating)
          unit = "1";
      }
    }
  }
  // units: {x: m, theta: rad, s: m}: each named coordinate's or output expression's unit, a
  // short text
  if (!u) return;
  for (const auto& kv : u) {
    const std::string& name = kv.first.Scalar();
    if (is_base_unit_key(name)) continue;  // (read_unit_system)
    const auto output = std::find(model.output_names.begin(), model.output_names.end(), name);
    const bool is_coordinate =
        std::any_of(coordinates_.begin(), coordinates_.end(),
                    [&](const std::string& c) { return c == name || names_coordinate(name, c); });
    if (!is_coordinate && output == model.output_names.end()) {
      fail(kv.first, "units: '" + name + "' is neither a coordinate nor an output expression",
           "the coordinates are " + join(coordinates_) +
               (model.output_names.empty()
                    ? std::string()
                    : ", the output expressions " + join(model.output_names)));
    }
    const YAML::Node& value = kv.second;
    const std::string text = value.IsScalar() ? value.Scalar() : std::string();
    const bool printable = std::none_of(text.begin(), text.end(), [](char ch) {
      return static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f;
    });
    if (value.IsNull() || (value.IsScalar() && text.empty())) {
      fail(value, "the unit of '" + kv.first.Scalar() + "' is empty",
           "give its unit (units: {x: m, theta: rad}; 1 for a number without a unit), or leave '" +
               kv.first.Scalar() + "' out of units:");
    }
    if (value.IsScalar() && !printable) {
      fail(value,
           "the unit of '" + kv.first.Scalar() +
               "' contains a control character (a tab, a newline or an escape sequence)",
           "write the unit as plain text: units: {x: m, theta: rad, s: mm}");
    }
    if (!value.IsScalar() || text.size() > 32) {
      fail(value,
           "the unit of '" + kv.first.Scalar() + "' must be a short text (at most 32 characters)",
           "units: {x: m, theta: rad, s: mm} (the unit labels the plots' axes; it does not change "
           "any number)");
    }
    if (is_coordinate) {
      // a body's or a joint's coordinate has its unit by construction: its position in the
      // model's length unit, its angle in rad, a quaternion's component without one; a label
      // converts no number, so another would be wrong (u21 07: 'deg' on radians)
      const std::size_t k = std::size_t(coordinate(kv.first));
      const std::string& own = model.coordinate_units[k];
      const bool built = model.multibody || model.robot;
      if (built && own == model.unit_system.length && text != own) {
        fail(value,
             "units: '" + name + "' is a " + (model.robot ? "joint's" : "body's") +
                 " coordinate, in " + own + " (the model's length unit); it cannot be given '" +
                 text + "'",
             "its positions are all in the length unit: change units: {length: " + text +
                 "} (and the model's numbers) or leave '" + name +
                 "' out of units: (docs/model-format.md, \"Units\")");
      }
      if (built && (own == "rad" || own == "1") && text != own) {
        fail(value,
             "units: '" + name + "' is " +
                 (own == "rad" ? std::string("an angle, in rad")
                               : std::string("a quaternion's component, without unit")) +
                 "; it cannot be given '" + text + "' (a unit labels the values, it converts none)",
             own == "rad" ? "leave '" + name +
                                "' out of units: (its values and the plots are "
                                "radians; an angle in degrees is an expression: initial: {q: "
                                "{" +
                                name + ": 90*pi/180}})"
                          : "leave '" + name + "' out of units:");
      }
      model.coordinate_units[k] = text;
    } else {
      model.output_units[std::size_t(output - model.output_names.begin())] = text;
    }
  }
}

// the run's settings as `ukdyn run` checks them (check_run_settings, modelfile/run.hpp: the same
// check_settings a run makes), located at the key that gave the setting at fault
// (locate_run_error: simulate: KEY, output: every / at, or the simulate: mapping when the setting
// is a default that the others make unusable, e.g. rk4's step over a longer t_end)
void Reader::check_settings(const YAML::Node& root, Model& model) {
  positions_.start = position(root);
  model.positions = positions_;
  try {
    check_run_settings(model, model.options);
  } catch (const SettingError& e) {
    throw locate_run_error(model, e);
  }
}

}  // namespace ukdyn::model_reader

// SPDX-License-Identifier: BSD-3-Clause
// Model files: YAML with symbolic expressions → a System, an initial state and run settings.
// Derivatives are symbolic (modelfile/expression.hpp):
//   Lagrangian      M = ∂²T/∂q̇∂q̇,  Q = ∂L/∂q − D(∂T/∂q̇) − ∂V/∂q … (L = T − V) + forces
//   holonomic       A = ∂φ/∂q,  b = −D(D φ)          (D: total time derivative without q̈)
//   nonholonomic    A = ∂ψ/∂q̇,  b = −D ψ
// Every error names file:line:column and gives a hint.
#include "ukdyn/modelfile/model.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>
#include <Eigen/Cholesky>

#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/nonideal.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/simulation/options.hpp"

#include "modelfile/angle_flags.hpp"
#include "modelfile/initial_keep.hpp"
#include "modelfile/reader.hpp"

namespace ukdyn {

ModelError::ModelError(const std::string& file, int line, int column, const std::string& message,
                       const std::string& hint)
    : std::runtime_error(valid_utf8(
          file +
          (line > 0 ? ":" + format_number(line) + ":" + format_number(column) : std::string()) +
          ": error: " + message + (hint.empty() ? "" : " (hint: " + hint + ")"))),
      file_(valid_utf8(file)),
      line_(line),
      column_(column),
      message_(valid_utf8(message)),
      hint_(valid_utf8(hint)) {}

namespace model_reader {

// The first velocity (in declaration order) that e depends on, or null: the inputs are
// [q; q'; t; …], so the velocities are the inputs n … 2n − 1 (one traversal of e).
const std::string* velocity_in(const ExpressionSet& set, Expr e,
                               const std::vector<std::string>& velocities) {
  const Index n = Index(velocities.size());
  for (const Index k : set.inputs_of(e)) {
    if (k >= n && k < 2 * n) return &velocities[std::size_t(k - n)];
  }
  return nullptr;
}

namespace {
// YAML's spellings of a non-finite float (.nan, .NaN, .NAN, .inf, -.Inf, +.INF, …; YAML 1.2's
// core schema): a value the expression parser would only call an unexpected '.'
bool yaml_non_finite(const YAML::Node& node) {
  if (!node.IsScalar() || node.Tag() == "!") return false;  // (a quoted scalar is text)
  std::string s = node.Scalar();
  if (!s.empty() && (s[0] == '+' || s[0] == '-')) s.erase(0, 1);
  return s == ".nan" || s == ".NaN" || s == ".NAN" || s == ".inf" || s == ".Inf" || s == ".INF";
}
}  // namespace

// When YAML has split an expression of the flow list `list` (`key: [if(t - 0.5, F, 0), 0]`) at
// the commas inside its parentheses: the hint to quote it, with the list as it should be written
// (`forces: ["if(t - 0.5, F, 0)", 0]`); else "". An unquoted entry with more '(' than ')' is
// joined with the entries after it until they balance; a list with no such entry, or any
// unbalanced entry left, is said to be cut too.
std::string cut_flow_list_hint(const YAML::Node& list, const std::string& key) {
  if (!list.IsSequence() || list.Style() != YAML::EmitterStyle::Flow) return "";
  std::vector<std::string> groups;
  std::vector<bool> joined;
  std::ptrdiff_t depth = 0;
  bool unbalanced = false;
  for (const auto& entry : list) {
    if (!entry.IsScalar()) return "";
    const std::string& text = entry.Scalar();
    const bool quoted = entry.Tag() == "!";
    const std::ptrdiff_t opened = std::count(text.begin(), text.end(), '('),
                         closed = std::count(text.begin(), text.end(), ')');
    if (depth > 0 && !quoted) {
      groups.back() += ", " + text;
      joined.back() = true;
    } else {
      depth = 0;
      groups.push_back(quoted ? "\"" + text + "\"" : text);
      joined.push_back(false);
      if (opened != closed && !quoted) unbalanced = true;
    }
    if (!quoted) depth += opened - closed;
  }
  bool any_joined = false;
  std::string written = key + ": [";
  for (std::size_t i = 0; i < groups.size(); ++i) {
    any_joined = any_joined || joined[i];
    written += (i > 0 ? ", " : "") + (joined[i] ? "\"" + groups[i] + "\"" : groups[i]);
  }
  written += "]";
  if (!any_joined && !unbalanced) return "";
  return "inside YAML brackets [...] a comma ends an entry, so the commas inside an expression's "
         "parentheses split it: quote the expression (" +
         (any_joined ? written : std::string("\"atan2(y, x)\"")) +
         ") or write the list in block style, one entry per line";
}

double Reader::number(const YAML::Node& node, const std::string& what) {
  if (!node.IsScalar()) fail(node, what + " must be a number");
  // nan, inf written bare (YAML's .nan and .inf are refused where the expression is read): not
  // names of the model (u16 04: "unknown name 'nan'", listing the coordinates)
  {
    std::string word;
    for (char ch : node.Scalar())
      if (!std::isspace(static_cast<unsigned char>(ch)) && ch != '+' && ch != '-')
        word += char(std::tolower(static_cast<unsigned char>(ch)));
    if (word == "nan" || word == "inf" || word == "infinity")
      fail(node, what + " must be a finite number, but is '" + node.Scalar() + "'",
           "use a number or a formula of the parameters");
  }
  // a number, or an expression of the parameters only
  const Expr e = expression(node, what);
  if (const auto inputs = set_->inputs_of(e); !inputs.empty()) {
    fail(node,
         what + " must be a constant, but depends on '" +
             set_->input_names()[std::size_t(inputs.front())] + "'",
         "use numbers and parameters here");
  }
  const Program p = compile({e}, node, what);
  std::vector<double> in(std::size_t(p.inputs()), 0.0), scratch(std::size_t(p.scratch_size()));
  double out = 0.0;
  p.evaluate(in.data(), &out, scratch.data());
  if (!std::isfinite(out))
    fail(node, what + " must be a finite number, but is " + brief(out),
         "a double holds magnitudes up to about 1.8e308");
  return out;
}

Expr Reader::expression(const YAML::Node& node, const std::string& what, bool in_C) {
  if (!node.IsScalar()) {
    fail(node, what + " must be an expression (a number or a formula)",
         "write it as a single value, e.g. 0.5*m*x_dot^2");
  }
  if (yaml_non_finite(node)) {
    fail(node,
         what + " must be a finite number, got '" + node.Scalar() + "' (YAML's " +
             (node.Scalar().find_first_of("aA") != std::string::npos ? "not-a-number)"
                                                                     : "infinity)"),
         "write a finite number or an expression of the parameters");
  }
  if (!renamed_.empty()) refuse_renamed(node, what);
  Expr e = 0;
  try {
    e = set_->parse(node.Scalar());
  } catch (const expr::ParseError& error) {
    // the expression starts at the node; quoted scalars start one character later
    YAML::Mark m = node.Mark();
    const bool quoted = node.Tag() == "!";
    m.column += int(error.position()) + (quoted ? 1 : 0);
    const std::string message = error.what();
    // a flow mapping or list ({a: atan2(y, x)}) ends the value at the comma: '(' left open
    const std::string& text = node.Scalar();
    const bool cut =
        std::count(text.begin(), text.end(), '(') > std::count(text.begin(), text.end(), ')');
    fail_at(
        m, "in " + what + ": " + message,
        cut && !quoted
            ? "inside YAML brackets {…} or […] a comma ends the value, so '" + text +
                  "' may be cut short: quote the expression (\"atan2(y, x)\") or write it on "
                  "its own line (block style)"
        : message.find("the parameters' values") != std::string::npos
            ? "change the parameter's value, or write the expression for it"
        : message.find("exceeds the largest double") != std::string::npos
            ? "write a number a double holds (|x| < 1.8e308), or change the model's units"
            : "expressions use the coordinates, their velocities (x_dot), t and the parameters");
  }
  // defined with the parameters' values? (errors point here; compiled only when it may fail:
  // compiling a kinetic energy of 10⁵ terms just to check it was a tenth of loading it)
  if (!set_->compile_cannot_fail(e)) compile({e}, node, what);
  // the constraints' forces are inputs of C only (nothing else is evaluated with them)
  // (they are the last inputs, in the order of constraint_inputs_)
  const Index first_force = Index(set_->input_names().size() - constraint_inputs_.size());
  if (!in_C && !constraint_inputs_.empty()) {
    if (const auto inputs = set_->inputs_of(e); !inputs.empty() && inputs.back() >= first_force) {
      const Index k = *std::lower_bound(inputs.begin(), inputs.end(), first_force);
      fail(node,
           "in " + what + ": '" + set_->input_names()[std::size_t(k)] + "' is known only in a C",
           "a constraint's N_ and lambda_ are inputs of the non-ideal forces written as C");
    }
  }
  return e;
}

// The constants of an expression are evaluated when it is compiled, with the parameters' values:
// sqrt(L - 2) with L = 1 is complex only then (the parser refuses what divides by zero, like
// 1/(L - 1) with L = 1, where it is written).
Program Reader::compile(const std::vector<Expr>& exprs, const YAML::Node& where,
                        const std::string& what) const {
  try {
    return set_->compile(exprs);
  } catch (const std::exception& e) {
    std::string reason = e.what();
    const std::string prefix = "ukdyn::expr::ExpressionSet::compile: ";
    if (reason.rfind(prefix, 0) == 0) reason.erase(0, prefix.size());
    fail(where, "cannot evaluate " + what + " with the parameters' values: " + reason,
         "a parameter value makes it undefined: a division by zero, or sqrt or log of a "
         "negative number");
  }
}

std::vector<YAML::Node> Reader::rows_of(const YAML::Node& node, const std::string& what) {
  std::vector<YAML::Node> rows;
  if (node.IsSequence()) {
    for (const auto& r : node) rows.push_back(r);
  } else if (node.IsScalar()) {
    rows.push_back(node);
  } else {
    fail(node, what + " must be an expression or a list of expressions");
  }
  if (rows.empty()) fail(node, what + " has no rows");
  return rows;
}

namespace {

// the identifiers of an expression's text, in order (a number's exponent, 1e5, is none)
std::vector<std::string> identifiers_in(const std::string& text) {
  std::vector<std::string> out;
  const auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  for (std::size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (!word(c) && c != '.') {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < text.size() && (word(text[j]) || text[j] == '.')) ++j;
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_')
      out.push_back(text.substr(i, j - i));
    i = j;
  }
  return out;
}

}  // namespace

std::vector<std::string> Reader::overrides_read(const std::string& text) const {
  std::vector<std::string> names;
  for (const std::string& used : identifiers_in(text)) {
    if (const auto b = set_by_.find(used); b != set_by_.end())
      for (const std::string& given : b->second)
        if (std::find(names.begin(), names.end(), given) == names.end()) names.push_back(given);
  }
  return names;
}

std::string Reader::overridden_in(const YAML::Node& at) const {
  if (set_by_.empty() || !at.IsScalar()) return {};
  const std::vector<std::string> names = overrides_read(at.Scalar());
  std::string out;
  for (const std::string& name : names)
    out += (out.empty() ? "--set " : ", ") + name + "=" + format_number(overrides_.at(name));
  return out.empty() ? out : out + ": ";
}

// Parameters are numbers or expressions of the parameters before them (`I: m*L^2/12`), read
// in the order written, each evaluated once with the values before it: a name defined later
// (or the parameter itself) is an error, so there are no cycles. An override (--set) replaces
// the parameter's value where it is defined, whether the file gives a number or an expression
// (the override wins), and the parameters after it are evaluated with the new value.
void Reader::read_parameters(const YAML::Node& root) {
  // an override that is not finite is refused first: the parameters after it would otherwise
  // fail to evaluate and be blamed
  for (const auto& [name, value] : overrides_) {
    if (!std::isfinite(value))
      throw OverrideError(file_, 0, 0, "--set " + name + ": the value must be a finite number");
  }
  const YAML::Node p = root["parameters"];
  if (p) {
    if (!p.IsMap()) fail(p, "parameters must be a mapping name: value", "e.g. {m: 1, g: 9.81}");
    // the names in order (for "defined after it"), and pi, built in unless a parameter takes it
    std::vector<std::string> order;
    for (const auto& kv : p) order.push_back(kv.first.Scalar());
    ExpressionSet earlier(std::vector<std::string>{});
    if (std::find(order.begin(), order.end(), "pi") == order.end())
      earlier.set_constant("pi", 3.14159265358979323846);
    std::size_t index = 0;
    for (const auto& kv : p) {
      const std::string name = kv.first.Scalar();
      ++index;
      if (!is_identifier(name))
        fail(kv.first, "parameter name '" + name + "' is not an identifier");
      if (name == "t") fail(kv.first, "'t' is time and cannot be a parameter");
      if (!kv.second.IsScalar()) {
        fail(kv.second, "parameter '" + name + "' must be a number or an expression",
             "of the parameters written before it, e.g. I: m*L^2/12");
      }
      const std::string& text = kv.second.Scalar();
      if (yaml_non_finite(kv.second))
        fail(kv.second, "parameter '" + name + "' must be a finite number, got '" + text + "'");
      double v = 0.0;
      bool is_number = false;
      try {
        std::size_t used = 0;
        v = std::stod(text, &used);
        is_number = used == text.size();
      } catch (const std::out_of_range&) {
        is_number = true;  // 1e999: refused below as not finite
        v = std::numeric_limits<double>::infinity();
      } catch (const std::invalid_argument&) {
        is_number = false;  // a name or a formula
      }
      if (is_number && !std::isfinite(v)) {
        fail(kv.second, "parameter '" + name + "' must be a finite number, got '" + text + "'");
      }
      if (!is_number) v = derived_parameter(kv.second, name, earlier, order, index - 1);
      if (const auto o = overrides_.find(name); o != overrides_.end()) {
        v = o->second;
        set_by_[name] = {name};
      } else if (!is_number) {
        // (a parameter derived from overridden ones is set by their overrides)
        if (auto from = overrides_read(text); !from.empty()) set_by_[name] = std::move(from);
      }
      parameters_[name] = v;
      try {
        earlier.set_constant(name, v);
      } catch (const std::invalid_argument&) {
        // a function's name: refused with its position once the expressions are set up
        // (read_generalized / read_multibody); not usable in the parameters after it
      }
    }
  }
  for (const auto& [name, value] : overrides_) {
    if (!parameters_.count(name)) {
      std::vector<std::string> known;
      for (const auto& kv : parameters_) known.push_back(kv.first);
      throw OverrideError(
          file_, 0, 0, "--set " + name + ": the model has no parameter '" + name + "'",
          known.empty() ? "it declares no parameters" : "its parameters are " + join(known));
    }
    parameters_[name] = value;
  }
}

double Reader::derived_parameter(const YAML::Node& node, const std::string& name,
                                 ExpressionSet& earlier, const std::vector<std::string>& order,
                                 std::size_t index) {
  const std::string what = "parameter '" + name + "'";
  const std::string& text = node.Scalar();
  Expr e = 0;
  try {
    e = earlier.parse(text);
  } catch (const expr::ParseError& error) {
    YAML::Mark m = node.Mark();
    m.column += int(error.position()) + (node.Tag() == "!" ? 1 : 0);
    // the name at the error: a parameter written at or after this one?
    std::size_t end = error.position();
    while (end < text.size() &&
           (std::isalnum(static_cast<unsigned char>(text[end])) || text[end] == '_'))
      ++end;
    const std::string token = text.substr(error.position(), end - error.position());
    const auto later = std::find(order.begin() + std::ptrdiff_t(index), order.end(), token);
    if (!token.empty() && later != order.end()) {
      if (later == order.begin() + std::ptrdiff_t(index)) {
        fail_at(m, "in " + what + ": '" + name + "' refers to itself",
                "a parameter is a number or an expression of the parameters before it");
      }
      fail_at(m,
              "in " + what + ": '" + token + "' is defined after '" + name +
                  "' (parameters are evaluated in the order written)",
              "move " + token + " above " + name);
    }
    fail_at(m, "in " + what + ": " + error.what(),
            "a parameter is a number or an expression of the parameters before it (and pi)");
  }
  double out = 0.0;
  try {
    const Program p = earlier.compile({e});
    std::vector<double> scratch(std::size_t(p.scratch_size()));
    p.evaluate(nullptr, &out, scratch.data());
  } catch (const std::exception& error) {
    std::string reason = error.what();
    const std::string prefix = "ukdyn::expr::ExpressionSet::compile: ";
    if (reason.rfind(prefix, 0) == 0) reason.erase(0, prefix.size());
    fail(node, "cannot evaluate " + what + ": " + reason);
  }
  if (!std::isfinite(out)) {
    fail(node, what + " must be a finite number, but '" + text + "' is " + brief(out));
  }
  return out;
}

void Reader::read_coordinates(const YAML::Node& root) {
  const YAML::Node c = root["coordinates"];
  if (!c)
    throw ModelError(file_, 1, 1, "no 'coordinates:'",
                     "list the coordinates, e.g. coordinates: [x, y]");
  if (!c.IsSequence() || c.size() == 0) fail(c, "coordinates must be a non-empty list of names");
  std::set<std::string> seen;
  for (const auto& node : c) {
    const std::string name = node.Scalar();
    if (!node.IsScalar() || !is_identifier(name))
      fail(node, "coordinate '" + name + "' is not an identifier");
    if (name == "t" || parameters_.count(name))
      fail(node, "coordinate '" + name + "' clashes with time or a parameter");
    if (!seen.insert(name).second) fail(node, "coordinate '" + name + "' is listed twice");
    coordinates_.push_back(name);
    velocities_.push_back(name + "_dot");
    chain_.emplace_back(name, name + "_dot");
  }
}

Index Reader::coordinate(const YAML::Node& node) {
  const std::string& name = node.Scalar();
  for (std::size_t i = 0; i < coordinates_.size(); ++i) {
    if (coordinates_[i] == name) return Index(i);
  }
  // crank.x for crank_x (names_coordinate)
  for (std::size_t i = 0; i < coordinates_.size(); ++i) {
    if (names_coordinate(name, coordinates_[i])) return Index(i);
  }
  fail(node, "unknown coordinate '" + name + "'", "the coordinates are " + join(coordinates_));
}

Expr Reader::time_derivative(Expr e) {
  // the inputs: the coordinates (0 … n−1), their velocities, t (2n), the constraints' forces
  const Index n = Index(coordinates_.size());
  const std::vector<Index> in = set_->inputs_of(e);
  const bool moves =
      std::any_of(in.begin(), in.end(), [n](Index k) { return k < n || k == 2 * n; });
  return moves ? set_->total_derivative(e, "t", chain_) : set_->constant(0.0);
}

YAML::Node Reader::load_yaml(const std::string& text, const std::string& file) {
  // not YAML at all: an XML robot description (URDF, MJCF, SDF)
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && text[first] == '<') {
    throw ModelError(file, 1, 1,
                     "this looks like an XML file (URDF, MJCF, SDF …): ukdyn reads its own YAML "
                     "model format",
                     "a URDF is read from a .urdf file, or named by a model file's robot: {urdf: "
                     "arm.urdf} (docs/robots.md); else write bodies: and joints:");
  }
  // a NUL byte: a binary file, or text cut by a C string (YAML's own message names an escape)
  if (const std::size_t nul = text.find('\0'); nul != std::string::npos) {
    const std::size_t line_start =
        text.rfind('\n', nul) == std::string::npos ? 0 : text.rfind('\n', nul) + 1;
    const int line = 1 + int(std::count(text.begin(), text.begin() + long(nul), '\n'));
    throw ModelError(file, line, int(nul - line_start) + 1,
                     "the model text holds a NUL byte (is this a binary file?)",
                     "a model file is YAML text (docs/model-format.md)");
  }
  // the tree, refusing duplicate keys, a second document, self-referencing aliases, runaway
  // nesting and syntax errors (modelfile/yaml_structure.cpp)
  const YAML::Node root = load_checked_yaml(text, file);
  if (root.IsNull()) {
    // located where the model should begin, as every reader error is (file:line:column)
    throw ModelError(file, 1, 1, "the model file is empty (or holds only comments)",
                     "start with name:, coordinates:, … (docs/model-format.md)");
  }
  if (!root.IsMap()) {
    throw ModelError(file, 1, 1, "a model is a mapping of keys",
                     "start with name:, coordinates:, …");
  }
  return root;
}

Model Reader::read(const YAML::Node& root) {
  for (const auto& kv : root) {
    const std::string key = kv.first.Scalar();
    if (std::find(kTopLevelKeys.begin(), kTopLevelKeys.end(), key) == kTopLevelKeys.end()) {
      fail(kv.first, "unknown key '" + key + "'", "the keys are " + join(kTopLevelKeys));
    }
  }
  Model model = read_plant(root);
  read_control(root, model);
  return model;
}

Model Reader::read_plant(const YAML::Node& root) {
  read_parameters(root);
  if (root["contacts"] && !root["bodies"] && !root["robot"]) {
    YAML::Node at = root["contacts"];
    for (const auto& kv : root) {
      if (kv.first.Scalar() == "contacts") at = kv.first;
    }
    fail(at, "'contacts' goes with bodies: or robot:",
         "in generalized coordinates a contact is a constraint with unilateral: true (its gap as "
         "holonomic:, docs/contact.md)");
  }
  Model model = root["robot"]    ? read_robot(root)
                : root["bodies"] ? read_multibody(root)
                                 : read_generalized(root);
  model.file = file_;
  model.name = root["name"] ? root["name"].Scalar() : file_;
  model.parameters = parameters_;
  read_initial(root, model);
  read_simulate(root, model);
  check_mass_matrix(root, model);
  read_output(root, model);
  read_units(root, model);
  // the coordinates that are angles (rad, deg: a planar body's angle, a revolute joint's,
  // units: {theta: rad}; not a quaternion's components), whose columns the run's
  // violation scales weigh by 1 rather than by its length (SimulationOptions::angle_coordinates;
  // left empty, every coordinate a length, when there is none)
  model.options.angle_coordinates = detail::model_angle_coordinates(model);
  label_gaps(model);
  apply_time_unit(model);
  // initial: project: true, or simulate: project_initial: true
  model.project_initial = model.project_initial || model.options.project_initial;
  model.options.project_initial = model.project_initial;
  check_settings(root, model);
  apply_keep(model);
  return model;
}

// The run's units (SimulationOptions::units) from the model's, as run_model sets them, so that
// simulate(model.system, …, model.options) runs as run_model does: the rate unit of a state
// without length follows them (docs/simulation.md, "The integrators' atol"). (The defaults with a
// time dimension are in the time unit already: read_simulate.)
void Reader::apply_time_unit(Model& model) const { model.options.units = model.unit_system; }

void Reader::make_expression_set(const YAML::Node& root, const std::vector<std::string>& cnames) {
  std::vector<std::string> inputs = coordinates_;
  inputs.insert(inputs.end(), velocities_.begin(), velocities_.end());
  inputs.push_back("t");
  input_constraints_ = cnames;
  for (const auto& c : cnames) constraint_inputs_.push_back("N_" + c);
  for (const auto& c : cnames) constraint_inputs_.push_back("lambda_" + c);
  inputs.insert(inputs.end(), constraint_inputs_.begin(), constraint_inputs_.end());
  try {
    set_ = std::make_unique<ExpressionSet>(inputs);
  } catch (const std::invalid_argument& e) {
    std::string message = e.what();
    if (const auto k = message.find(": "); k != std::string::npos) message.erase(0, k + 2);
    const YAML::Node where = root["coordinates"] ? root["coordinates"] : root["bodies"];
    fail(where ? where : root, "a coordinate's name is taken: " + message,
         "x_dot is the velocity of x, and N_c and lambda_c are the forces of constraint c");
  }
  for (const auto& [name, value] : parameters_) {
    try {
      set_->set_constant(name, value);
    } catch (const std::invalid_argument& e) {
      // a function's name, or a velocity's or a constraint's input (x_dot, N_rod, lambda_rod)
      const YAML::Node p = root["parameters"];
      for (const auto& kv : p) {
        if (kv.first.Scalar() == name) {
          fail(kv.first, "parameter '" + name + "' clashes with a function or an input",
               "the names x_dot (each coordinate's velocity), N_c and lambda_c (each "
               "constraint's), and the functions sin, cos, … are taken");
        }
      }
      throw ModelError(file_, 1, 1, e.what());
    }
  }
  // pi: built in, unless a parameter or coordinate takes the name
  if (!parameters_.count("pi") && std::find(inputs.begin(), inputs.end(), "pi") == inputs.end()) {
    set_->set_constant("pi", 3.14159265358979323846);
  }
  layout_.n = Index(coordinates_.size());
  layout_.extra = Index(2 * cnames.size());
  read_tables(root);
}

bool Reader::switches(std::vector<std::string>& names, Program& program) {
  names.clear();
  if (switch_sources_.empty()) return false;
  // (one traversal of every expression of the dynamics; a switch of N_c or lambda_c, which the
  // state alone does not give, is left to the step-size control)
  // a switch of a constraint's expressions is named "g in the constraint 'NAME'" (simulate()
  // then reports a kink of that constraint, not a sliding mode, when it chatters)
  // (by their text, g and -g alike: each call of switching_functions makes new expressions)
  std::map<std::string, std::string> of_constraint;
  const Expr zero = set_->constant(0.0);
  for (const auto& [cname, exprs] : constraint_switch_sources_) {
    for (const Expr e : set_->switching_functions(exprs)) {
      of_constraint.emplace(set_->to_string(e), cname);
      of_constraint.emplace(set_->to_string(set_->subtract(zero, e)), cname);
    }
  }
  std::vector<Expr> g;
  for (const Expr e : set_->switching_functions(switch_sources_)) {
    const std::vector<Index> in = set_->inputs_of(e);
    if (in.empty() || in.back() > 2 * layout_.n) continue;
    g.push_back(e);
    const std::string text = set_->to_string(e);
    const auto c = of_constraint.find(text);
    names.push_back(text +
                    (c == of_constraint.end() ? "" : " in the constraint '" + c->second + "'"));
  }
  switch_sources_.clear();
  constraint_switch_sources_.clear();
  if (g.empty()) return false;
  program = set_->compile(g);
  return true;
}

void Reader::add_switches(SystemBuilder& builder) {
  std::vector<std::string> names;
  Program p;
  if (!switches(names, p)) return;
  sizes_->fit(layout_.size(), p);
  const InputLayout layout = layout_;
  builder.switching_functions(
      std::move(names),
      [p, layout](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                  double t, CallableScratch* s, Eigen::Ref<VectorXd> out) {
        ModelBuffers& b = model_buffers(s);
        layout.fill(b.in, q, qd, t);
        p.evaluate(b.in.data(), out.data(), b.scratch.data());
      });
}

std::vector<std::string> Reader::constraint_names(const YAML::Node& root) {
  std::vector<std::string> names;
  if (const YAML::Node cs = root["constraints"]; cs && cs.IsSequence()) {
    for (const auto& c : cs) {
      if (c.IsMap() && c["name"] && is_identifier(c["name"].Scalar()) &&
          std::find(names.begin(), names.end(), c["name"].Scalar()) == names.end())
        names.push_back(c["name"].Scalar());
    }
  }
  return names;
}

Model Reader::read_generalized(const YAML::Node& root) {
  read_coordinates(root);
  // the named constraints (a name given twice is refused by read_constraints)
  make_expression_set(root, constraint_names(root));
  SystemBuilder builder(coordinates_);
  read_dynamics(root, builder);
  read_constraints(root, builder);
  read_nonideal(root, builder);
  add_switches(builder);
  Model model = [&] {
    try {
      return Model{.system = builder.build()};
    } catch (const std::invalid_argument& e) {
      throw ModelError(file_, 1, 1, e.what());
    }
  }();
  check_friction_normals(root, model.system);
  return model;
}

}  // namespace model_reader

Model parse_model(const std::string& text, const std::string& file,
                  const std::map<std::string, double>& overrides) {
  return parse_model(text, file, overrides, GivenTables{});
}

Model parse_model(const std::string& text, const std::string& file,
                  const std::map<std::string, double>& overrides, const GivenTables& tables) {
  // the YAML is parsed first, by any number of threads at once (yaml-cpp shares nothing between
  // documents; it is a third of the pendulum's reading, bench/RESULTS.md "Ensembles")
  const YAML::Node root = model_reader::Reader::load_yaml(text, file);
  // then one model is read at a time, whichever thread asks (an ensemble's workers, Python
  // threads with the GIL released): GiNaC, which the reader differentiates with, shares
  // reference-counted objects whose counts are not atomic. The reader's GiNaC objects all die
  // before the lock is released; the Model holds none (its expressions are compiled programs)
  static std::mutex mutex;
  const std::lock_guard<std::mutex> lock(mutex);
  return model_reader::Reader(file, overrides, &tables).read(root);
}

Model load_model(const std::string& path, const std::map<std::string, double>& overrides) {
  return load_model(path, overrides, GivenTables{});
}

Model load_model(const std::string& path, const std::map<std::string, double>& overrides,
                 const GivenTables& tables) {
  // a directory, a device or a stream is not a model file; a regular file is read whole, up to
  // kMaxModelFileBytes (a bounded read: /dev/zero or a runaway file never fills the memory)
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!ec && std::filesystem::is_directory(status)) {
    throw ModelError(path, 0, 0, "is a directory, not a model file",
                     "give the path of a .yaml model file");
  }
  // a URDF alone: a robot model naming it (modelfile/reader_urdf.cpp)
  if (model_reader::is_urdf_path(path) && std::filesystem::is_regular_file(status))
    return parse_model(model_reader::urdf_model_text(path), path, overrides, tables);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ModelError(path, 0, 0, "cannot read the model file", "check the path");
  std::string text;
  std::vector<char> chunk(std::size_t(1) << 16);
  while (in) {
    in.read(chunk.data(), std::streamsize(chunk.size()));
    text.append(chunk.data(), std::size_t(in.gcount()));
    if (text.size() > kMaxModelFileBytes) {
      throw ModelError(
          path, 0, 0,
          "the model file is larger than " + format_number(kMaxModelFileBytes >> 20) + " MB" +
              (std::filesystem::is_regular_file(status) ? "" : " (it is not a regular file)"),
          "a model file is a few kB of YAML; is this the right file?");
    }
  }
  if (in.bad()) throw ModelError(path, 0, 0, "cannot read the model file", "check the path");
  return parse_model(text, path, overrides, tables);
}

std::vector<std::vector<double>> evaluate_output_expressions(const Model& model,
                                                             const Trajectory& traj) {
  const expr::Program& p = model.output_program;
  const Index n = traj.n, N = traj.samples();
  std::vector<std::vector<double>> out(std::size_t(p.outputs()),
                                       std::vector<double>(std::size_t(N)));
  std::vector<double> in(std::size_t(p.inputs()), 0.0), values(std::size_t(p.outputs())),
      scratch(std::size_t(p.scratch_size()));
  for (Index i = 0; i < N; ++i) {
    std::copy_n(traj.q.begin() + i * n, n, in.begin());
    std::copy_n(traj.qd.begin() + i * n, n, in.begin() + n);
    in[std::size_t(2 * n)] = traj.t[std::size_t(i)];
    p.evaluate(in.data(), values.data(), scratch.data());
    for (std::size_t k = 0; k < values.size(); ++k) out[k][std::size_t(i)] = values[k];
  }
  return out;
}

}  // namespace ukdyn

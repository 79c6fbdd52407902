// SPDX-License-Identifier: BSD-3-Clause
// The table of simulation options (simulation/options.hpp) and its one validating setter.
#include "ukdyn/simulation/options.hpp"
#include "ukdyn/core/format.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <system_error>

namespace ukdyn {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// 2^63: an integer option bounded by it takes every long (the bound itself excluded)
constexpr double kLongEnd = 9223372036854775808.0;

// shortest round-trip text of a number ("1e-09", "0.5", "inf")
std::string number_text(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// "a, b or c"
std::string join_or(const std::vector<std::string>& v) {
  std::string out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    out += (i == 0 ? "" : i + 1 == v.size() ? " or " : ", ") + v[i];
  }
  return out;
}

const char* const kEngines[] = {"auto", "dense", "sparse"};
const char* const kAlgorithms[] = {"default", "textbook"};

// the rows' accessors: get returns the field as the type's alternative, put assigns one
#define UKDYN_FIELD(field, T)                                           \
  [](const SimulationOptions& o) -> OptionValue { return T(o.field); }, \
      [](SimulationOptions& o, const OptionValue& v) {                  \
        o.field = static_cast<decltype(o.field)>(std::get<T>(v));       \
      }

OptionInfo number(std::string name, double min, bool min_open, double max, bool max_open,
                  std::string example, std::string doc) {
  OptionInfo i;
  i.name = std::move(name);
  i.type = OptionType::kNumber;
  i.min = min;
  i.min_open = min_open;
  i.max = max;
  i.max_open = max_open;
  i.example = std::move(example);
  i.doc = std::move(doc);
  return i;
}

OptionInfo integer(std::string name, double min, double max, std::string example, std::string doc) {
  OptionInfo i =
      number(std::move(name), min, false, max, max == kLongEnd, std::move(example), std::move(doc));
  i.type = OptionType::kInteger;
  return i;
}

OptionInfo boolean(std::string name, std::string doc) {
  OptionInfo i;
  i.name = std::move(name);
  i.type = OptionType::kBool;
  i.doc = std::move(doc);
  return i;
}

OptionInfo choice(std::string name, std::string noun, std::vector<std::string> choices,
                  std::string example, std::string doc) {
  OptionInfo i;
  i.name = std::move(name);
  i.type = OptionType::kChoice;
  i.noun = std::move(noun);
  i.choices = std::move(choices);
  i.example = std::move(example);
  i.doc = std::move(doc);
  return i;
}

OptionInfo numbers(std::string name, std::string example, std::string doc) {
  OptionInfo i;
  i.name = std::move(name);
  i.type = OptionType::kNumbers;
  i.example = std::move(example);
  i.doc = std::move(doc);
  return i;
}

// a row with its accessors
OptionInfo with(OptionInfo i, OptionValue (*get)(const SimulationOptions&),
                void (*put)(SimulationOptions&, const OptionValue&)) {
  i.get = get;
  i.put = put;
  if (i.type == OptionType::kBool && i.example.empty()) {
    i.example = std::get<bool>(get(SimulationOptions{})) ? "false" : "true";
  }
  return i;
}

std::vector<OptionInfo> make_table() {
  std::vector<OptionInfo> t;
  // the run's interval and integrator
  t.push_back(with(number("t_start", -kInf, false, kInf, false, "-0.5",
                          "initial time (in the model's time unit: s in SI units)"),
                   UKDYN_FIELD(t_start, double)));
  t.push_back(with(number("t_end", -kInf, false, kInf, false, "2.5",
                          "final time (in the model's time unit), after t_start"),
                   UKDYN_FIELD(t_end, double)));
  t.push_back(with(
      choice("integrator", "integrator", {"rk4", "rk5", "dopri5", "rkf78", "bdf"}, "rkf78",
             "integration method (docs/simulation.md, \"Integrators\")"),
      [](const SimulationOptions& o) -> OptionValue {
        return std::string(to_string(o.integrator));
      },
      [](SimulationOptions& o, const OptionValue& v) {
        o.integrator = integrator_from_string(std::get<std::string>(v));
      }));
  t.push_back(with(
      number("rtol", 0.0, true, kInf, true, "1e-07", "relative tolerance of dopri5, rkf78 and bdf"),
      UKDYN_FIELD(rtol, double)));
  t.push_back(with(
      number("atol", 0.0, true, kInf, true, "1e-09", "absolute tolerance of dopri5, rkf78 and bdf"),
      UKDYN_FIELD(atol, double)));
  t.push_back(with(number("step", 0.0, true, kInf, true, "0.002",
                          "the step of rk4 and rk5; the first step tried by dopri5 and rkf78"),
                   UKDYN_FIELD(step, double)));
  {
    OptionInfo i = number("max_step", 0.0, false, kInf, false, "0.25",
                          "largest step of the adaptive methods (0: unlimited)");
    i.allow_infinite = true;
    t.push_back(with(std::move(i), UKDYN_FIELD(max_step, double)));
  }
  t.push_back(with(integer("max_steps", 1.0, kLongEnd, "123456",
                           "accepted steps a run may take, with every method"),
                   UKDYN_FIELD(max_steps, long)));
  t.push_back(with(boolean("stiff_switch", "dopri5 goes on with bdf once the problem turns stiff"),
                   UKDYN_FIELD(stiff_switch, bool)));
  t.push_back(with(
      boolean("switch_events", "sign changes of sign, abs, heaviside, min, max and if are events"),
      UKDYN_FIELD(switch_events, bool)));
  // samples
  t.push_back(with(number("output_every", 0.0, false, kInf, true, "0.05",
                          "sample spacing (0: only t_start and t_end)"),
                   UKDYN_FIELD(output_every, double)));
  {
    // (each time inside [t_start, t_end]: check_settings says so, naming the run's interval)
    OptionInfo i =
        numbers("output_at", "0.25,0.75", "further sample times, inside [t_start, t_end]");
    i.allow_infinite = true;
    t.push_back(with(std::move(i), UKDYN_FIELD(output_at, std::vector<double>)));
  }
  t.push_back(with(
      numbers("breakpoints", "0.5", "times where the dynamics jumps (the integrators stop there)"),
      UKDYN_FIELD(breakpoints, std::vector<double>)));
  // drift control
  t.push_back(with(
      choice("drift", "drift control", {"none", "baumgarte", "projection"}, "baumgarte",
             "drift control of every constraint (a constraint's own drift: overrides it)"),
      [](const SimulationOptions& o) -> OptionValue { return std::string(to_string(o.drift)); },
      [](SimulationOptions& o, const OptionValue& v) {
        o.drift = drift_from_string(std::get<std::string>(v));
      }));
  t.push_back(with(number("baumgarte_alpha", 0.0, false, kInf, true, "5",
                          "Baumgarte gain alpha (per time unit) of drift: baumgarte"),
                   UKDYN_FIELD(baumgarte_alpha, double)));
  t.push_back(with(number("baumgarte_beta", 0.0, false, kInf, true, "5",
                          "Baumgarte gain beta (per time unit) of drift: baumgarte"),
                   UKDYN_FIELD(baumgarte_beta, double)));
  t.push_back(
      with(number("projection_tolerance", 0.0, true, kInf, true, "1e-11",
                  "violation the projection leaves, relative to each row's scale (Scales and "
                  "tolerances)"),
           UKDYN_FIELD(projection.tolerance, double)));
  {
    OptionInfo i = integer("projection_max_iterations", 1.0, 2147483647.0, "30",
                           "Gauss-Newton iterations of a projection at most");
    i.aliases = {"projection_iterations"};
    t.push_back(with(std::move(i), UKDYN_FIELD(projection.max_iterations, long)));
  }
  // the initial state and the energy balance
  t.push_back(with(boolean("project_initial",
                           "project an inconsistent initial state onto the constraints instead "
                           "of refusing it"),
                   UKDYN_FIELD(project_initial, bool)));
  t.push_back(
      with(number("initial_tolerance", 0.0, false, kInf, true, "1e-08",
                  "largest constraint violation of a consistent initial state, relative to each "
                  "row's scale"),
           UKDYN_FIELD(initial_tolerance, double)));
  {
    OptionInfo i = number("energy_balance_tolerance", 0.0, true, kInf, false, "0.001",
                          "energy balance residual a run may end with (inf: no check)");
    i.allow_infinite = true;
    t.push_back(with(std::move(i), UKDYN_FIELD(energy_balance_tolerance, double)));
  }
  // the fundamental-equation solver (SolverOptions)
  auto solver = [](OptionInfo i) {
    i.solver = true;
    return i;
  };
  t.push_back(with(
      solver(choice("engine", "engine", {"auto", "dense", "sparse"}, "dense",
                    "dense or sparse engine (auto: by size and structure; docs/sparse.md)")),
      [](const SimulationOptions& o) -> OptionValue {
        return std::string(kEngines[int(o.solver.engine)]);
      },
      [](SimulationOptions& o, const OptionValue& v) {
        const std::string& s = std::get<std::string>(v);
        o.solver.engine = s == "dense"    ? Engine::kDense
                          : s == "sparse" ? Engine::kSparse
                                          : Engine::kAuto;
      }));
  t.push_back(with(
      solver(choice("algorithm", "algorithm", {"default", "textbook"}, "textbook",
                    "default, or the textbook formula (eqs. 9-12, for reference)")),
      [](const SimulationOptions& o) -> OptionValue {
        return std::string(kAlgorithms[int(o.solver.algorithm)]);
      },
      [](SimulationOptions& o, const OptionValue& v) {
        o.solver.algorithm =
            std::get<std::string>(v) == "textbook" ? Algorithm::kTextbook : Algorithm::kDefault;
      }));
  t.push_back(with(solver(integer("sparse_threshold", 0.0, kLongEnd, "8",
                                  "engine auto: the sparse engine from this many coordinates on")),
                   UKDYN_FIELD(solver.sparse_threshold, long)));
  t.push_back(with(solver(number("rank_threshold", 0.0, true, 1.0, true, "1e-09",
                                 "relative pivot below which the dense engine counts a rank "
                                 "deficiency")),
                   UKDYN_FIELD(solver.rank_threshold, double)));
  t.push_back(with(solver(number("sparse_rank_threshold", 0.0, true, 1.0, true, "1e-05",
                                 "the sparse engine's rank threshold")),
                   UKDYN_FIELD(solver.sparse_rank_threshold, double)));
  t.push_back(with(solver(number("consistency_tolerance", 0.0, true, kInf, true, "1e-07",
                                 "relative residual above which the constraints are "
                                 "inconsistent")),
                   UKDYN_FIELD(solver.consistency_tolerance, double)));
  t.push_back(with(solver(number("symmetry_tolerance", 0.0, false, kInf, true, "1e-11",
                                 "relative asymmetry of M above which it is refused")),
                   UKDYN_FIELD(solver.symmetry_tolerance, double)));
  t.push_back(
      with(solver(boolean(
               "compute_residuals",
               "compute the Gauss, virtual-work and constraint residuals at every evaluation")),
           UKDYN_FIELD(solver.compute_residuals, bool)));
  return t;
}
#undef UKDYN_FIELD

const char* type_name(OptionType type) {
  switch (type) {
    case OptionType::kNumber:
      return "number";
    case OptionType::kInteger:
      return "integer";
    case OptionType::kBool:
      return "bool";
    case OptionType::kChoice:
      return "choice";
    case OptionType::kNumbers:
      return "numbers";
  }
  return "?";
}

bool in_range(const OptionInfo& i, double v) {
  if (std::isnan(v)) return false;
  if (std::isinf(v) && !(i.type == OptionType::kNumber && i.allow_infinite)) return false;
  const bool above = i.min_open ? v > i.min : v >= i.min;
  const bool below = i.max_open ? v < i.max : v <= i.max;
  return above && below;
}

const OptionInfo& row(std::string_view name) {
  if (const OptionInfo* i = find_option(name)) return *i;
  throw OptionError(std::string(name), "unknown setting '" + std::string(name) + "'",
                    "the settings are " + option_names());
}

std::string default_hint(const OptionInfo& i) {
  return "the default is " + option_text(i.get(SimulationOptions{}));
}

// "NAME must be RULE, got VALUE"
[[noreturn]] void refuse(const OptionInfo& i, std::string_view given, const std::string& got) {
  throw OptionError(i.name, std::string(given) + " must be " + option_rule(i) + ", got " + got,
                    default_hint(i));
}

// the value converted to the alternative `put` takes, or OptionError
OptionValue checked(const OptionInfo& i, std::string_view given, const OptionValue& value) {
  auto wrong_type = [&]() -> OptionValue {
    throw OptionError(
        i.name,
        std::string(given) + " must be " + option_rule(i) + " (got a value of another type)",
        default_hint(i));
  };
  switch (i.type) {
    case OptionType::kNumber: {
      double v = 0.0;
      if (const double* d = std::get_if<double>(&value))
        v = *d;
      else if (const long* l = std::get_if<long>(&value))
        v = double(*l);
      else
        return wrong_type();
      if (!in_range(i, v)) refuse(i, given, number_text(v));
      return v;
    }
    case OptionType::kInteger: {
      if (const long* l = std::get_if<long>(&value)) {
        // (every long is below 2^63, though double(LONG_MAX) rounds to it)
        const double x = double(*l);
        const bool above = i.min_open ? x > i.min : x >= i.min;
        const bool below = i.max >= kLongEnd || (i.max_open ? x < i.max : x <= i.max);
        if (!above || !below) refuse(i, given, format_number(*l));
        return *l;
      }
      const double* d = std::get_if<double>(&value);
      if (!d) return wrong_type();
      if (!in_range(i, *d) || std::floor(*d) != *d) refuse(i, given, number_text(*d));
      return long(*d);
    }
    case OptionType::kBool:
      if (!std::holds_alternative<bool>(value)) return wrong_type();
      return value;
    case OptionType::kChoice: {
      const std::string* s = std::get_if<std::string>(&value);
      if (!s) return wrong_type();
      for (const auto& c : i.choices) {
        if (c == *s) return value;
      }
      throw OptionError(i.name, "unknown " + i.noun + " '" + *s + "'", join_or(i.choices));
    }
    case OptionType::kNumbers: {
      const auto* list = std::get_if<std::vector<double>>(&value);
      if (!list) {
        if (const double* d = std::get_if<double>(&value))
          return checked(i, given, std::vector<double>{*d});
        return wrong_type();
      }
      for (double v : *list) {
        if (!i.allow_infinite && !std::isfinite(v)) refuse(i, given, number_text(v));
      }
      return value;
    }
  }
  return wrong_type();
}

std::string trimmed(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return std::string(s);
}

// a number from text (strtod: "1e-9", "inf", "nan"); false when the text is not one
bool parse_number(std::string_view text, double& v) {
  const std::string s = trimmed(text);
  if (s.empty()) return false;
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size();
}

}  // namespace

OptionError::OptionError(std::string setting, std::string problem, std::string hint)
    : SettingError(std::move(setting), problem + (hint.empty() ? "" : " (" + hint + ")")),
      problem_(std::move(problem)),
      hint_(std::move(hint)) {}

const std::vector<OptionInfo>& option_table() {
  static const std::vector<OptionInfo> table = make_table();
  return table;
}

const OptionInfo* find_option(std::string_view name) {
  for (const OptionInfo& i : option_table()) {
    if (i.name == name) return &i;
    for (const auto& a : i.aliases) {
      if (a == name) return &i;
    }
  }
  return nullptr;
}

std::string option_names() {
  std::string out;
  for (const OptionInfo& i : option_table()) out += (out.empty() ? "" : ", ") + i.name;
  return out;
}

void set_option(SimulationOptions& o, std::string_view name, const OptionValue& value) {
  const OptionInfo& i = row(name);
  i.put(o, checked(i, name, value));
}

void check_options(const SimulationOptions& o) {
  for (const OptionInfo& i : option_table()) checked(i, i.name, i.get(o));
}

void set_option_text(SimulationOptions& o, std::string_view name, std::string_view text) {
  const OptionInfo& i = row(name);
  const std::string quoted = "'" + std::string(text) + "'";
  switch (i.type) {
    case OptionType::kNumber:
    case OptionType::kInteger: {
      double v = 0.0;
      if (!parse_number(text, v)) refuse(i, name, quoted);
      set_option(o, name, v);
      return;
    }
    case OptionType::kBool: {
      const std::string s = trimmed(text);
      if (s != "true" && s != "false") refuse(i, name, quoted);
      set_option(o, name, s == "true");
      return;
    }
    case OptionType::kChoice:
      set_option(o, name, trimmed(text));
      return;
    case OptionType::kNumbers: {
      std::vector<double> list;
      std::string_view rest = text;
      if (!trimmed(rest).empty()) {
        while (true) {
          const std::size_t comma = rest.find(',');
          double v = 0.0;
          if (!parse_number(rest.substr(0, comma), v)) refuse(i, name, quoted);
          list.push_back(v);
          if (comma == std::string_view::npos) break;
          rest.remove_prefix(comma + 1);
        }
      }
      set_option(o, name, list);
      return;
    }
  }
}

OptionValue get_option(const SimulationOptions& o, std::string_view name) {
  return row(name).get(o);
}

std::string option_text(const OptionValue& value) {
  if (const bool* b = std::get_if<bool>(&value)) return *b ? "true" : "false";
  if (const long* l = std::get_if<long>(&value)) return format_number(*l);
  if (const double* d = std::get_if<double>(&value)) return number_text(*d);
  if (const std::string* s = std::get_if<std::string>(&value)) return *s;
  std::string out = "[";
  for (double v : std::get<std::vector<double>>(value)) {
    out += (out.size() > 1 ? ", " : "") + number_text(v);
  }
  return out + "]";
}

std::string option_rule(const OptionInfo& i) {
  switch (i.type) {
    case OptionType::kBool:
      return "true or false";
    case OptionType::kChoice:
      return join_or(i.choices);
    case OptionType::kNumbers:
      return i.allow_infinite ? "a list of numbers" : "a list of finite numbers";
    case OptionType::kInteger:
      return i.max >= kLongEnd
                 ? "a whole number >= " + number_text(i.min)
                 : "a whole number from " + number_text(i.min) + " to " + number_text(i.max);
    case OptionType::kNumber:
      break;
  }
  const bool low = std::isfinite(i.min), high = std::isfinite(i.max);
  std::string kind = i.allow_infinite ? "a number" : "a finite number";
  if (!low && !high) return kind;
  if (low && high) {
    return kind + " in " + (i.min_open ? "(" : "[") + number_text(i.min) + ", " +
           number_text(i.max) + (i.max_open ? ")" : "]");
  }
  if (low) {
    return kind + (i.min_open ? " > " : " >= ") + number_text(i.min) +
           (i.allow_infinite ? ", or inf" : "");
  }
  return kind + (i.max_open ? " < " : " <= ") + number_text(i.max);
}

std::string option_flag(const OptionInfo& i) {
  std::string flag = "--" + i.name;
  for (char& c : flag) {
    if (c == '_') c = '-';
  }
  return flag;
}

std::string options_markdown() {
  std::string out =
      "| option | type | default | range | `ukdyn run` flag | what it sets |\n"
      "|---|---|---|---|---|---|\n";
  const SimulationOptions defaults;
  for (const OptionInfo& i : option_table()) {
    std::string name = "`" + i.name + "`";
    for (const auto& a : i.aliases) name += " (also `" + a + "`)";
    // (appended piece by piece: GCC 12 warns, wrongly, of a memcpy bound on "`" + std::string&&)
    std::string flag = "`";
    flag += option_flag(i);
    flag += '`';
    if (i.type == OptionType::kBool) flag += ", `--no-" + option_flag(i).substr(2) + "`";
    out += "| " + name + " | " + type_name(i.type) + (i.solver ? " (solver)" : "") + " | " +
           option_text(i.get(defaults)) + " | " + option_rule(i) + " | " + flag + " | " + i.doc +
           " |\n";
  }
  return out;
}

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
/// @file simulation/options.hpp
/// The one table of simulation options: every setting of SimulationOptions that a user can give
/// by name (its name, type, default, range and doc line), from which the model file's
/// `simulate:` reader, `ukdyn run`'s flags, the JSON summary's `options`, Python's keyword
/// arguments and `Model.options`, and the table in docs/simulation.md ("Options") are all
/// derived, so every front end accepts the same options by construction. One validating setter
/// (set_option) serves them all: an out-of-range value reads the same everywhere and names the
/// option.
///
/// Not in the table (not plain values): SimulationOptions::drift_per_constraint (given per
/// constraint, `drift:` in a model file), and the callables progress, sample_sink and
/// should_stop.
#pragma once

#include <cmath>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn {

/// The type of an option's value.
enum class OptionType {
  kNumber,   ///< a double in [min, max] (bounds open or closed; infinite values only if allowed)
  kInteger,  ///< a whole number in [min, max] (given as an integer or a whole double)
  kBool,     ///< true or false
  kChoice,   ///< one of OptionInfo::choices
  kNumbers,  ///< a list of numbers (each finite unless OptionInfo::allow_infinite)
};

/// An option's value: bool (kBool), long (kInteger), double (kNumber), text (kChoice), or a list
/// of numbers (kNumbers). set_option also takes a long for kNumber and a whole double for
/// kInteger.
using OptionValue = std::variant<bool, long, double, std::string, std::vector<double>>;

/// One row of the table.
struct OptionInfo {
  std::string name;  ///< as SimulationOptions spells it ("rtol", "projection_tolerance")
  OptionType type = OptionType::kNumber;  ///< the value's type
  /// the numbers' range [min, max] (kNumber, kInteger, each entry of kNumbers); ±infinity: no
  /// bound
  double min = -HUGE_VAL;
  double max = HUGE_VAL;  ///< upper end of the range (see min)
  bool min_open = false;  ///< strict lower bound (> min)
  bool max_open = false;  ///< strict upper bound (< max)
  /// kNumber: ±inf accepted when inside the bounds; kNumbers: entries not checked here (output_at:
  /// check_settings refuses a time outside the run, naming the run's interval)
  bool allow_infinite = false;
  std::vector<std::string> choices;  ///< kChoice: the accepted names
  std::string noun;                  ///< kChoice: what a choice is ("integrator", "drift control")
  std::vector<std::string> aliases;  ///< older spellings, accepted on input everywhere
  bool solver = false;               ///< a SolverOptions field (also a setting of Python's solvers)
  std::string example;               ///< a valid value other than the default, as text (tests)
  std::string doc;                   ///< one line: what it sets
  OptionValue (*get)(const SimulationOptions&) = nullptr;  ///< the value now
  /// assigns a value already checked and converted to the type's alternative of OptionValue
  void (*put)(SimulationOptions&, const OptionValue&) = nullptr;
};

/// A bad value (or name) for an option: a SettingError (so std::invalid_argument) whose
/// setting() is the option's name in the table, and whose text is problem() followed by
/// " (hint())" when there is a hint. problem() names the option as it was given (an alias stays
/// an alias) and the rule: "rtol must be a finite number > 0, got -1", "unknown integrator
/// 'euler'", "max_steps must be a whole number from 1 to 1e+18, got 2.5". Front ends put it at
/// their place: the model file's line and column, the flag and its text, Python's ValueError.
class OptionError : public SettingError {
 public:
  /// @param setting the option's name; @param problem what is wrong; @param hint how to fix it.
  OptionError(std::string setting, std::string problem, std::string hint);
  const std::string& problem() const { return problem_; }  ///< what is wrong, naming the option
  const std::string& hint() const { return hint_; }        ///< the choices, or the default

 private:
  std::string problem_, hint_;
};

/// The table, in the order the docs and `ukdyn run --help` list it. Built once; cost O(1).
const std::vector<OptionInfo>& option_table();

/// The row of `name` or of one of its aliases; nullptr when there is none. Cost O(options).
const OptionInfo* find_option(std::string_view name);

/// The names of the table, comma-separated ("t_start, t_end, integrator, …"), for "unknown
/// setting" messages.
std::string option_names();

/// Sets option `name` (or an alias) of o to value after checking its type and range.
/// @throws OptionError naming the option as given: an unknown name (hint: the names), a value of
/// the wrong type, out of range, not whole (kInteger), not a choice (hint: the choices).
/// Relations between options (t_end after t_start, output_at inside the run, an rk4 step count
/// within max_steps) are check_settings()'s. Cost O(1) (O(entries) for lists).
void set_option(SimulationOptions& o, std::string_view name, const OptionValue& value);

/// Checks every option's value in o against the table's rules, as set_option would (check_settings
/// calls it, so a SimulationOptions filled field by field in C++ is held to the same ranges).
/// @throws OptionError for the first option out of its range. Cost O(options + list entries).
void check_options(const SimulationOptions& o);

/// set_option() from text as a person types it: a number ("1e-9", "inf"), a whole number, true
/// or false, a choice's name, or comma-separated numbers ("0.5,1.5"; "" the empty list).
/// @throws OptionError as set_option(), also for text that is not of the option's type.
void set_option_text(SimulationOptions& o, std::string_view name, std::string_view text);

/// The value of option `name` (or an alias) in o. @throws OptionError for an unknown name.
OptionValue get_option(const SimulationOptions& o, std::string_view name);

/// A value as text: shortest round-trip numbers ("1e-09", "10000000", "inf"), true/false, a
/// choice's name, lists as "[0.5, 1.5]".
std::string option_text(const OptionValue& value);

/// The range of an option in words: "a finite number > 0", "a whole number from 1 to 1e+18",
/// "true or false", "rk4, rk5, dopri5, rkf78 or bdf".
std::string option_rule(const OptionInfo& info);

/// The docs table (docs/simulation.md, "Options"): Markdown, one row per option with its name
/// (and aliases), type, default, range and doc line, and the command-line flag. A test checks
/// that the docs hold exactly this text.
std::string options_markdown();

/// `--name-with-dashes`: the command-line flag of an option.
std::string option_flag(const OptionInfo& info);

}  // namespace ukdyn

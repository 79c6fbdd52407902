// SPDX-License-Identifier: BSD-3-Clause
// The options table (simulation/options.hpp): every option of the table is accepted by the model
// file's simulate: section, echoed by the JSON summary, refused out of its range with an error that
// names it (by the setter, and located in a model file), and documented in docs/simulation.md
// exactly as options_markdown() prints it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "ukdyn/io/trajectory_files.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/options.hpp"

namespace UKDYN_TEST_FILE {

using namespace ukdyn;

const std::string kModel =
    "coordinates: [x]\n"
    "kinetic_energy: 0.5*x_dot^2\n"
    "potential_energy: 0.5*x^2\n"
    "initial: {q: {x: 1}}\n";

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// the option's example (a valid value other than the default) as YAML: lists in brackets
std::string yaml_value(const OptionInfo& info, const std::string& text) {
  return info.type == OptionType::kNumbers ? "[" + text + "]" : text;
}

// the defaults with option `name` set from `text` by the table's setter
SimulationOptions with_text(const std::string& name, const std::string& text) {
  SimulationOptions o;
  o.t_end = 1.0;
  set_option_text(o, name, text);
  return o;
}

// two values the same bit for bit (doubles compared by bits; NaN never appears here)
void expect_same(const OptionValue& a, const OptionValue& b, const std::string& what) {
  ASSERT_EQ(a.index(), b.index()) << what;
  if (const double* x = std::get_if<double>(&a)) {
    std::uint64_t ba = 0, bb = 0;
    std::memcpy(&ba, x, 8);
    std::memcpy(&bb, &std::get<double>(b), 8);
    EXPECT_EQ(ba, bb) << what << ": " << option_text(a) << " vs " << option_text(b);
  } else {
    EXPECT_TRUE(a == b) << what << ": " << option_text(a) << " vs " << option_text(b);
  }
}

// a text out of the option's range (or not of its type) that the setter must refuse
std::string bad_text(const OptionInfo& info) {
  switch (info.type) {
    case OptionType::kBool:
      return "maybe";
    case OptionType::kChoice:
      return "nonsense";
    case OptionType::kNumbers:
      return "nan";
    case OptionType::kNumber:
    case OptionType::kInteger:
      break;
  }
  char text[64];
  if (std::isfinite(info.min)) {
    std::snprintf(text, sizeof text, "%.17g", info.min_open ? info.min : info.min - 1.0);
  } else if (std::isfinite(info.max)) {
    std::snprintf(text, sizeof text, "%.17g", info.max_open ? info.max : info.max + 1.0);
  } else {
    return "nan";
  }
  return text;
}

TEST(OptionsTable, NamesAreUniqueEveryDefaultIsAcceptedAndEveryExampleDiffers) {
  std::set<std::string> names;
  const SimulationOptions defaults;
  for (const OptionInfo& info : option_table()) {
    SCOPED_TRACE(info.name);
    EXPECT_TRUE(names.insert(info.name).second) << "twice in the table";
    for (const auto& a : info.aliases) EXPECT_TRUE(names.insert(a).second) << a;
    EXPECT_FALSE(info.doc.empty());
    EXPECT_EQ(find_option(info.name), &info);
    // the default passes the setter unchanged
    SimulationOptions o;
    set_option(o, info.name, info.get(defaults));
    expect_same(info.get(o), info.get(defaults), "default");
    // the example is valid and differs from the default
    const SimulationOptions e = with_text(info.name, info.example);
    EXPECT_FALSE(info.get(e) == info.get(defaults)) << info.example;
  }
  EXPECT_EQ(find_option("projection_iterations"), find_option("projection_max_iterations"));
  EXPECT_EQ(find_option("nonsense"), nullptr);
}

TEST(OptionsTable, ModelFileAcceptsEveryOptionAndAlias) {
  for (const OptionInfo& info : option_table()) {
    std::vector<std::string> spellings = {info.name};
    spellings.insert(spellings.end(), info.aliases.begin(), info.aliases.end());
    for (const std::string& key : spellings) {
      SCOPED_TRACE(key);
      const Model m = parse_model(
          kModel + "simulate: {" + key + ": " + yaml_value(info, info.example) + "}\n", "m.yaml");
      expect_same(info.get(m.options), info.get(with_text(info.name, info.example)), key);
    }
  }
  // simulate: project_initial is initial: project:
  EXPECT_TRUE(parse_model(kModel + "simulate: {project_initial: true}\n").project_initial);
}

TEST(OptionsTable, ModelFileNamesTheOptionsOfAnUnknownKey) {
  try {
    parse_model(kModel + "simulate: {rtoll: 1e-6}\n", "m.yaml");
    FAIL() << "accepted";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 5);
    EXPECT_EQ(e.column(), 12);
    EXPECT_EQ(e.message(), "unknown key 'rtoll' in simulate");
    EXPECT_EQ(e.hint(), option_names());
    EXPECT_TRUE(contains(e.hint(), "t_start, t_end, integrator, rtol, atol")) << e.hint();
  }
}

TEST(OptionsTable, ModelFileRefusesSolverOptionsTheSystemCannotUse) {
  // the sparse engine needs a block-diagonal M: refused at the key, not when the run starts
  try {
    parse_model(
        "coordinates: [x, y]\nmass_matrix: [[2, 1], [1, 2]]\nforces: [0, 0]\n"
        "simulate: {t_end: 2, engine: sparse}\n",
        "m.yaml");
    FAIL() << "accepted";
  } catch (const ModelError& e) {
    EXPECT_EQ(e.line(), 4);
    EXPECT_EQ(e.column(), 22);
    EXPECT_TRUE(contains(e.message(), "Engine::kSparse needs a block-diagonal mass matrix"))
        << e.what();
  }
}

TEST(OptionsTable, JsonSummaryEchoesEveryOption) {
  // every option at its example value at once (t_end first: output_at must lie inside)
  SimulationOptions o;
  for (const OptionInfo& info : option_table()) set_option_text(o, info.name, info.example);
  Trajectory tr;
  tr.coordinate_names = {"x"};
  tr.n = 1;
  const std::string path =
      (std::filesystem::temp_directory_path() / "ukdyn_test_options_summary.json").string();
  write_summary_json(tr, o, path);
  std::ifstream in(path);
  const nlohmann::json j = nlohmann::json::parse(in);
  const auto& echoed = j.at("options");
  for (const OptionInfo& info : option_table()) {
    SCOPED_TRACE(info.name);
    ASSERT_TRUE(echoed.contains(info.name));
    const auto& v = echoed.at(info.name);
    OptionValue read;
    switch (info.type) {
      case OptionType::kNumber:
        read = v.get<double>();
        break;
      case OptionType::kInteger:
        read = v.get<long>();
        break;
      case OptionType::kBool:
        read = v.get<bool>();
        break;
      case OptionType::kChoice:
        read = v.get<std::string>();
        break;
      case OptionType::kNumbers:
        read = v.get<std::vector<double>>();
        break;
    }
    expect_same(read, info.get(o), "json");
    expect_same(read, info.get(with_text(info.name, info.example)), "example");
  }
  // the table's options and drift_per_constraint, nothing else
  EXPECT_EQ(echoed.size(), option_table().size() + 1);
  std::filesystem::remove(path);
}

TEST(OptionsTable, OutOfRangeIsRefusedNamingTheOption) {
  for (const OptionInfo& info : option_table()) {
    const std::string bad = bad_text(info);
    SCOPED_TRACE(info.name + " = " + bad);
    // the setter: an OptionError whose setting() is the option, and whose text names it
    SimulationOptions o;
    try {
      set_option_text(o, info.name, bad);
      // output_at's times are checked against the run's interval by check_settings
      ASSERT_TRUE(info.type == OptionType::kNumbers && info.allow_infinite) << "accepted";
      try {
        check_settings(parse_model(kModel).system, o);
        ADD_FAILURE() << "check_settings accepted it";
      } catch (const SettingError& e) {
        EXPECT_EQ(e.setting(), info.name);
        EXPECT_TRUE(contains(e.what(), info.name)) << e.what();
      }
    } catch (const OptionError& e) {
      EXPECT_EQ(e.setting(), info.name);
      const std::string named = info.type == OptionType::kChoice ? info.noun : info.name;
      EXPECT_TRUE(contains(e.problem(), named)) << e.what();
      EXPECT_TRUE(contains(e.what(), bad)) << e.what();
    }
    // the model file: located at the value, naming the option
    try {
      parse_model(kModel + "simulate: {" + info.name + ": " + yaml_value(info, bad) + "}\n",
                  "m.yaml");
      ADD_FAILURE() << "the model file accepted it";
    } catch (const ModelError& e) {
      EXPECT_EQ(e.line(), 5);
      EXPECT_EQ(e.column(), int(std::strlen("simulate: {") + info.name.size() + 2 + 1 +
                                (info.type == OptionType::kNumbers ? 1 : 0)))
          << e.what();
      const std::string named = info.type == OptionType::kChoice ? info.noun : info.name;
      EXPECT_TRUE(contains(e.message(), named)) << e.what();
    }
  }
}

TEST(OptionsTable, SetterRulesReadTheSameForEveryOption) {
  SimulationOptions o;
  try {
    set_option(o, "rtol", -1.0);
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_EQ(std::string(e.what()),
              "rtol must be a finite number > 0, got -1 (the default is 1e-09)");
  }
  try {
    set_option(o, "max_steps", 2.5);
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_EQ(e.problem(), "max_steps must be a whole number >= 1, got 2.5");
  }
  // every long is a whole number of steps; a double at 2^63 or beyond is not a long
  set_option(o, "max_steps", std::numeric_limits<long>::max());
  EXPECT_EQ(o.max_steps, std::numeric_limits<long>::max());
  EXPECT_THROW(set_option(o, "max_steps", 9223372036854775808.0), OptionError);
  set_option(o, "max_steps", 4503599627370496.0);  // 2^52
  EXPECT_EQ(o.max_steps, 4503599627370496L);
  o.max_steps = SimulationOptions{}.max_steps;
  try {
    set_option(o, "integrator", std::string("euler"));
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_EQ(std::string(e.what()), "unknown integrator 'euler' (rk4, rk5, dopri5, rkf78 or bdf)");
  }
  try {
    set_option(o, "projection_iterations", 0L);
    FAIL();
  } catch (const OptionError& e) {
    // named as given, setting() the table's name
    EXPECT_EQ(e.setting(), "projection_max_iterations");
    EXPECT_TRUE(contains(e.problem(), "projection_iterations must be a whole number")) << e.what();
  }
  try {
    set_option(o, "stiff_switch", 1.0);  // a number for a bool
    FAIL();
  } catch (const OptionError& e) {
    EXPECT_TRUE(contains(e.problem(), "stiff_switch must be true or false")) << e.what();
  }
  EXPECT_THROW(set_option(o, "nonsense", 1.0), OptionError);
  // the infinite energy balance tolerance turns the check off; an infinite rtol is refused
  set_option_text(o, "energy_balance_tolerance", "inf");
  EXPECT_TRUE(std::isinf(o.energy_balance_tolerance));
  EXPECT_THROW(set_option_text(o, "rtol", "inf"), OptionError);
  // nothing was changed by a refused value
  EXPECT_EQ(o.rtol, SimulationOptions{}.rtol);
  EXPECT_EQ(o.integrator, Integrator::kDopri5);
}

TEST(OptionsTable, DocsTableIsTheGeneratedOne) {
  // docs/simulation.md holds options_markdown() between these two lines
  const std::string begin =
      "<!-- options table: generated by ukdyn::options_markdown(); "
      "tests/simulation/test_options.cpp checks it -->\n";
  const std::string end = "<!-- end of the options table -->\n";
  std::ifstream in(std::string(UKDYN_DOCS_DIR) + "/simulation.md");
  std::stringstream text;
  text << in.rdbuf();
  const std::string doc = text.str();
  const std::size_t b = doc.find(begin), e = doc.find(end);
  ASSERT_NE(b, std::string::npos) << "docs/simulation.md lacks the begin marker";
  ASSERT_NE(e, std::string::npos) << "docs/simulation.md lacks the end marker";
  ASSERT_LT(b, e);
  const std::string table = doc.substr(b + begin.size(), e - b - begin.size());
  EXPECT_EQ(table, options_markdown())
      << "docs/simulation.md's options table differs from the table in src/simulation/options.cpp; "
         "replace it with:\n"
      << options_markdown();
}

}  // namespace UKDYN_TEST_FILE

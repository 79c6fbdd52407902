// Where `run` and `check` get their model: a file or an embedded example, with --set overrides.
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <string>
#include <string_view>
#include <system_error>

#include "commands.hpp"
#include "embedded.hpp"

namespace ukdyn::cli {
namespace {

// the example's description: its first comment line ("# …"), or its name
std::string describe(const char* text) {
  std::string_view s(text);
  while (!s.empty()) {
    const std::size_t end = s.find('\n');
    std::string_view line = s.substr(0, end);
    if (line.starts_with("#")) {
      line.remove_prefix(1);
      while (line.starts_with(" ")) line.remove_prefix(1);
      return std::string(line);
    }
    if (end == std::string_view::npos) break;
    s.remove_prefix(end + 1);
  }
  return "";
}

std::string example_names() {
  std::string names;
  for (const auto& f : example_models()) names += (names.empty() ? "" : ", ") + std::string(f.name);
  return names;
}

}  // namespace

std::map<std::string, double> parse_overrides(const std::vector<std::string>& set) {
  std::map<std::string, double> overrides;
  for (const std::string& item : set) {
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw UsageError("--set '" + item + "': expected name=value (e.g. --set mu=0.3)");
    }
    const std::string name = item.substr(0, eq), text = item.substr(eq + 1);
    double value = 0.0;
    const char* first = text.data();
    const char* last = text.data() + text.size();
    if (!text.empty() && *first == '+') ++first;
    const auto [end, ec] = std::from_chars(first, last, value);
    if (text.empty() || ec != std::errc() || end != last) {
      throw UsageError("--set " + name + "=" + text + ": '" + text + "' is not a number");
    }
    overrides[name] = value;
  }
  return overrides;
}

Model load_source(const ModelSource& source) {
  const auto overrides = parse_overrides(source.set);
  if (source.path.empty() == source.example.empty()) {
    throw UsageError("give either a model file or --example NAME (ukdyn examples lists them)");
  }
  try {
    if (!source.path.empty()) return load_model(source.path, overrides);
    for (const auto& f : example_models()) {
      if (source.example == f.name) {
        return parse_model(f.text, "examples/models/" + source.example + ".yaml", overrides);
      }
    }
  } catch (const OverrideError& e) {
    // --set of a parameter the model does not declare is a command-line mistake (exit 2)
    throw UsageError(e.message() + (e.hint().empty() ? "" : " (" + e.hint() + ")"));
  }
  throw UsageError("no example called '" + source.example + "'; the examples are " +
                   example_names());
}

int examples_command() {
  std::size_t width = 0;
  for (const auto& f : example_models()) width = std::max(width, std::string_view(f.name).size());
  for (const auto& f : example_models()) {
    std::printf("%-*s  %s\n", int(width), f.name, describe(f.text).c_str());
  }
  std::printf("\nrun one with: ukdyn run --example NAME [-o DIR]\n");
  return kExitOk;
}

}  // namespace ukdyn::cli

// SPDX-License-Identifier: BSD-3-Clause
// Where `run` and `check` get their model: a file or an embedded example, with --set overrides.
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>

#include <nlohmann/json.hpp>

#include <ukdyn/io/trajectory_files.hpp>

#include <ukdyn/core/format.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/simulation/options.hpp>

#include "commands.hpp"
#include "embedded.hpp"
#include "suggest.hpp"

namespace ukdyn::cli {
namespace {

// the example's description: its first comment line ("# …") that is not a licence tag
// ("# SPDX-License-Identifier: …"), or its name
std::string describe(const char* text) {
  std::string_view s(text);
  while (!s.empty()) {
    const std::size_t end = s.find('\n');
    std::string_view line = s.substr(0, end);
    if (line.starts_with("#")) {
      line.remove_prefix(1);
      while (line.starts_with(" ")) line.remove_prefix(1);
      if (!line.starts_with("SPDX-")) return std::string(line);
    }
    if (end == std::string_view::npos) break;
    s.remove_prefix(end + 1);
  }
  return "";
}

std::vector<std::string> example_list() {
  std::vector<std::string> names;
  for (const auto& f : example_models()) names.emplace_back(f.name);
  return names;
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
  throw UsageError("no example called '" + source.example + "'" +
                   did_you_mean(source.example, example_list()) + "; the examples are " +
                   example_names());
}

std::string source_text(const ModelSource& source) {
  if (!source.path.empty()) {
    std::ifstream in(source.path, std::ios::binary);
    if (!in) throw UsageError("cannot read the model file '" + source.path + "'");
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  for (const auto& f : example_models()) {
    if (source.example == f.name) return f.text;
  }
  throw UsageError("no example called '" + source.example + "'" +
                   did_you_mean(source.example, example_list()) + "; the examples are " +
                   example_names());
}

RunProvenance provenance_of(const ModelSource& source, const Model& model,
                            const std::vector<std::string>& arguments) {
  std::string file;
  if (!source.path.empty()) {
    std::error_code ec;
    const auto absolute = std::filesystem::absolute(source.path, ec);
    file = ec ? source.path : absolute.lexically_normal().string();
  }
  std::vector<std::string> overridden;
  for (const auto& given : parse_overrides(source.set)) overridden.push_back(given.first);
  return model_provenance(model, file, source.example, source_text(source), overridden, arguments);
}

namespace {
// the --format list of a command line (argv), if it gives one: "--format csv,hdf5" or
// "--format=hdf5"
std::optional<std::vector<std::string>> format_of(const std::vector<std::string>& argv) {
  std::optional<std::string> text;
  for (std::size_t i = 0; i < argv.size(); ++i) {
    if (argv[i] == "--format" && i + 1 < argv.size()) text = argv[i + 1];
    if (argv[i].rfind("--format=", 0) == 0) text = argv[i].substr(9);
  }
  if (!text) return std::nullopt;
  std::vector<std::string> out;
  std::stringstream in(*text);
  for (std::string item; std::getline(in, item, ',');) out.push_back(item);
  return out;
}

// the summary of an earlier run: summary.json, or the `summary` attribute of its trajectory.h5
// (`ukdyn run --format hdf5`, Python's Result.to_hdf5)
std::string summary_text(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw UsageError("--from-summary: cannot read '" + file + "'");
  char magic[8] = {};
  in.read(magic, sizeof magic);
  if (in.gcount() == 8 && std::string_view(magic, 8) == std::string_view("\x89HDF\r\n\x1a\n", 8)) {
    try {
      return read_hdf5_string_attribute(file, "summary");
    } catch (const std::exception& e) {
      throw UsageError("--from-summary " + file + ": an HDF5 file without a run's summary (" +
                       e.what() + ")");
    }
  }
  in.clear();
  in.seekg(0);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// the text of a setting's value as its flag would take it
std::string setting_text(const nlohmann::json& v) {
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_string()) return v.get<std::string>();
  if (v.is_number_integer()) return std::to_string(v.get<long long>());
  if (v.is_number()) return format_number(v.get<double>());
  std::string text;
  for (const auto& x : v) text += (text.empty() ? "" : ",") + format_number(x.get<double>());
  return text;
}
}  // namespace

void apply_summary(RunArguments& args) {
  const std::string& file = args.from_summary;
  if (!args.source.path.empty() || !args.source.example.empty()) {
    throw UsageError("--from-summary " + file +
                     " names the model itself: give no model file or --example with it");
  }
  const nlohmann::json j = nlohmann::json::parse(summary_text(file), nullptr, false);
  const auto bad = [&](const std::string& what) {
    return UsageError("--from-summary " + file + ": " + what);
  };
  if (j.is_discarded() || !j.is_object()) throw bad("not a JSON summary of a ukdyn run");
  const auto it = j.find("provenance");
  if (it == j.end() || !it->is_object() || !it->contains("model_sha256")) {
    throw bad("it records no model (written by a ukdyn before 0.1's provenance)");
  }
  const nlohmann::json& p = *it;
  try {
    // the model, unchanged since that run
    ModelSource source;
    if (p.contains("example") && p["example"].is_string()) {
      source.example = p["example"].get<std::string>();
    } else {
      source.path = p.at("model_file").get<std::string>();
    }
    const std::string hash = sha256_hex(source_text(source));
    if (hash != p.at("model_sha256").get<std::string>()) {
      throw bad("the model " + (source.path.empty() ? "example " + source.example : source.path) +
                " has changed since that run (SHA-256 " + hash + ", the run's " +
                p.at("model_sha256").get<std::string>() +
                "): run the model itself to simulate the new version");
    }
    // its overrides, then those given now
    std::vector<std::string> set;
    for (const auto& name : p.at("overridden")) {
      const std::string key = name.get<std::string>();
      set.push_back(key + "=" + format_number(p.at("parameters").at(key).get<double>()));
    }
    set.insert(set.end(), args.source.set.begin(), args.source.set.end());
    source.set = std::move(set);
    // every setting, then the flags given now
    std::vector<FlagSetting> settings;
    for (const auto& [key, value] : j.at("options").items()) {
      if (!find_option(key) || value.is_null() || value.is_object()) continue;
      settings.push_back({key, "--from-summary (" + key + ")", setting_text(value)});
    }
    settings.insert(settings.end(), args.settings.begin(), args.settings.end());
    args.settings = std::move(settings);
    // the table formats of that run (its --format), unless given now
    if (!format_of(args.arguments) && p.contains("arguments") && p["arguments"].is_array()) {
      if (auto earlier = format_of(p["arguments"].get<std::vector<std::string>>())) {
        args.formats = std::move(*earlier);
      }
    }
    args.source = std::move(source);
  } catch (const nlohmann::json::exception& e) {
    throw bad(std::string("malformed provenance or options (") + e.what() + ")");
  }
}

int examples_command(const std::string& name) {
  if (!name.empty()) {
    for (const auto& f : example_models()) {
      if (name == f.name) {
        std::fputs(f.text, stdout);
        return kExitOk;
      }
    }
    throw UsageError("no example called '" + name + "'" + did_you_mean(name, example_list()) +
                     "; the examples are " + example_names());
  }
  std::size_t width = 0;
  for (const auto& f : example_models()) width = std::max(width, std::string_view(f.name).size());
  for (const auto& f : example_models()) {
    std::printf("%-*s  %s\n", int(width), f.name, describe(f.text).c_str());
  }
  std::printf(
      "\nrun one with: ukdyn run --example NAME [-o DIR]; print its file with: ukdyn examples "
      "NAME\n");
  return kExitOk;
}

void check_plot_formats(const std::vector<std::string>& formats) {
  for (const std::string& f : formats) {
    if (f != "png" && f != "pdf" && f != "svg") {
      throw UsageError("--plot-format " + f + ": the plot formats are png, pdf and svg" +
                       did_you_mean(f, {"png", "pdf", "svg"}) + " (--plot-format png,pdf,svg)");
    }
  }
  if (formats.empty()) throw UsageError("--plot-format: give png, pdf, svg or a list");
}

void check_plot_style(const std::string& style) {
  if (style != "screen" && style != "paper") {
    throw UsageError("--plot-style " + style + ": the plot styles are screen and paper" +
                     did_you_mean(style, {"screen", "paper"}));
  }
}

TableFormats parse_formats(const std::vector<std::string>& formats) {
  TableFormats out;
  for (const std::string& f : formats) {
    if (f == "csv") {
      out.csv = true;
    } else if (f == "hdf5") {
      out.hdf5 = true;
    } else {
      throw UsageError("--format " + f + ": the formats are csv and hdf5 (--format csv,hdf5)");
    }
  }
  if (!out.csv && !out.hdf5) throw UsageError("--format: give csv, hdf5 or both");
  return out;
}

}  // namespace ukdyn::cli

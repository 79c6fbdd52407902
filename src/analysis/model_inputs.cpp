// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/model_inputs.cpp
/// Inputs of a linear model that are model-file parameters: a family of systems, each parsed
/// from the model text with one parameter overridden.
#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "ukdyn/analysis/linearize.hpp"
#include "ukdyn/modelfile/model.hpp"

namespace ukdyn {

LinearInput model_parameter_input(const std::string& text, const std::string& file,
                                  const std::map<std::string, double>& overrides,
                                  const std::string& name) {
  const Model nominal = parse_model(text, file, overrides);
  const auto it = nominal.parameters.find(name);
  if (it == nominal.parameters.end()) {
    std::string list;
    for (const auto& [p, v] : nominal.parameters) list += (list.empty() ? "" : ", ") + p;
    throw std::invalid_argument("model_parameter_input: the model " + file + " has no parameter '" +
                                name + "'; its parameters are " + (list.empty() ? "(none)" : list));
  }
  LinearInput in;
  in.name = name;
  in.kind = InputKind::kParameter;
  in.nominal = it->second;
  in.family = [text, file, overrides, name](double p) {
    auto changed = overrides;
    changed[name] = p;
    return parse_model(text, file, changed).system;
  };
  return in;
}

std::vector<LinearInput> model_inputs(const Model& model, const std::string& text,
                                      const std::vector<std::string>& names, const char* who) {
  const System& sys = model.system;
  const auto& coords = sys.coordinate_names();
  std::vector<LinearInput> inputs;
  for (const std::string& name : names) {
    if (model.parameters.count(name))
      inputs.push_back(model_parameter_input(text, model.file, model.parameters, name));
    else if (std::find(coords.begin(), coords.end(), name) != coords.end())
      inputs.push_back(force_input(sys, name));
    else
      throw std::invalid_argument(std::string(who) + " " + name +
                                  ": neither a coordinate (a generalized force along it) nor a "
                                  "parameter of the model");
  }
  return inputs;
}

}  // namespace ukdyn

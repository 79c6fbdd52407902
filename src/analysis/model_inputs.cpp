/// @file analysis/model_inputs.cpp
/// Inputs of a linear model that are model-file parameters: a family of systems, each parsed
/// from the model text with one parameter overridden.
#include <map>
#include <stdexcept>
#include <string>

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

}  // namespace ukdyn

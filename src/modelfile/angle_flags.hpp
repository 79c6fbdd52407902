// SPDX-License-Identifier: BSD-3-Clause
// The model's angles (not installed): SimulationOptions::angle_coordinates from its coordinates'
// units, as the reader sets model.options' and run_model and check_model use them, whatever
// options the caller copied in (another model's flags are not this one's).
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include "ukdyn/core/units.hpp"
#include "ukdyn/modelfile/model.hpp"

namespace ukdyn::detail {

/// One flag per coordinate, true for a unit that UnitSystem::is_angle accepts (rad, deg);
/// empty when there is none (every coordinate a length). Cost O(n).
inline std::vector<bool> model_angle_coordinates(const Model& model) {
  std::vector<bool> flags;
  for (const std::string& u : model.coordinate_units) flags.push_back(UnitSystem::is_angle(u));
  if (std::find(flags.begin(), flags.end(), true) == flags.end()) flags.clear();
  return flags;
}

}  // namespace ukdyn::detail

// SPDX-License-Identifier: BSD-3-Clause
// Test support: the output expression `name` of a model file (`output: expressions:`) at every
// sample of a run, evaluated by the library's own evaluate_output_expressions.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::testing {

inline std::vector<double> output(const Model& m, const Trajectory& tr, const std::string& name) {
  const auto values = evaluate_output_expressions(m, tr);
  for (std::size_t k = 0; k < m.output_names.size(); ++k) {
    if (m.output_names[k] == name) return values[k];
  }
  ADD_FAILURE() << m.file << " has no output expression " << name;
  return {};
}

}  // namespace ukdyn::testing

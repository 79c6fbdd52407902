// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/linearize_along.cpp
/// Time-varying linearization along a trajectory: linearize() at each point in one chart
/// (include/ukdyn/analysis/linearize.hpp; docs/linearize.md, "Along a trajectory").
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "ukdyn/analysis/linearize.hpp"
#include "ukdyn/core/status.hpp"

namespace ukdyn {

std::vector<LinearModel> linearize_along(const System& sys, const std::vector<OperatingPoint>& path,
                                         const std::vector<LinearInput>& inputs,
                                         const std::vector<LinearOutput>& outputs,
                                         const LinearizeOptions& options) {
  std::vector<LinearModel> out;
  out.reserve(path.size());
  LinearizeOptions o = options;
  for (std::size_t k = 0; k < path.size(); ++k) {
    const std::string where = "linearize_along: point " + std::to_string(k) +
                              " (t = " + std::to_string(path[k].t) + "): ";
    try {
      out.push_back(linearize(sys, path[k], inputs, outputs, o));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + e.what());
    } catch (const SolveError& e) {
      throw SolveError(e.status(), where + e.what());
    }
    // the first point's chart for all: its independent coordinates by name
    if (k == 0) {
      const auto& names = sys.coordinate_names();
      o.independent_positions.clear();
      o.independent_velocities.clear();
      for (Index j : out[0].independent_positions)
        o.independent_positions.push_back(names[std::size_t(j)]);
      for (Index j : out[0].independent_velocities)
        o.independent_velocities.push_back(names[std::size_t(j)]);
    }
  }
  return out;
}

}  // namespace ukdyn

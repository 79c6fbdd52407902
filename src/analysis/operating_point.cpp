// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/operating_point.cpp
/// An operating point moved onto the constraint manifold (analysis/linearize.hpp).
#include <sstream>
#include <string>

#include "analysis/internal.hpp"
#include "ukdyn/analysis/linearize.hpp"
#include "ukdyn/core/status.hpp"
#include "ukdyn/dynamics/projection.hpp"

namespace ukdyn {

OperatingPoint project_onto_manifold(const System& sys, const OperatingPoint& p) {
  Workspace ws(sys, analysis::dense_options({}));
  OperatingPoint out = p;
  // positions first (Φ = 0), then the velocities at those positions (Φ' = 0, ψ = 0)
  for (const bool velocity : {false, true}) {
    const ProjectionResult r = velocity ? project_velocities(sys, ws, out.q, out.qd, out.t)
                                        : project_positions(sys, ws, out.q, out.t);
    if (!r.converged || r.status != Status::kOk) {
      std::ostringstream msg;
      msg << "project_onto_manifold: the " << (velocity ? "velocities" : "positions")
          << " could not be projected onto the constraints (violation left " << r.violation
          << " after " << r.iterations << " corrections)";
      throw SolveError(Status::kProjectionFailed, msg.str());
    }
  }
  return out;
}

}  // namespace ukdyn

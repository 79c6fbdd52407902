// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/operating_point.cpp
/// An operating point moved onto the constraint manifold (analysis/linearize.hpp).
#include <sstream>
#include <string>
#include <vector>

#include "analysis/internal.hpp"
#include "dynamics/contact_dynamics.hpp"
#include "ukdyn/analysis/linearize.hpp"
#include "ukdyn/core/status.hpp"
#include "ukdyn/dynamics/projection.hpp"

namespace ukdyn {

namespace analysis {

std::vector<std::string> hold_contact_mode(const System& sys, Workspace& ws,
                                           const OperatingPoint& at) {
  std::vector<std::string> open;
  if (detail::release_open_contacts(sys, ws, at.q, at.qd, at.t) == 0) return open;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (sys.constraint(k).is_unilateral() && ws.activity_override[std::size_t(k)] == 0)
      open.push_back(sys.constraint(k).name());
  }
  return open;
}

}  // namespace analysis

OperatingPoint project_onto_manifold(const System& sys, const OperatingPoint& p) {
  Workspace ws(sys, analysis::dense_options({}));
  // (an open contact is no violation: the point keeps its gap)
  analysis::hold_contact_mode(sys, ws, p);
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

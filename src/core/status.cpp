// SPDX-License-Identifier: BSD-3-Clause
// Status names and the internal check of tier-2 errors.
#include "ukdyn/core/status.hpp"
#include "ukdyn/core/format.hpp"

#include <string>

namespace ukdyn {

const char* to_string(Status s) {
  switch (s) {
    case Status::kOk:
      return "ok";
    case Status::kNonFiniteInput:
      return "non-finite input (NaN or Inf)";
    case Status::kMassNotSymmetric:
      return "mass matrix not symmetric";
    case Status::kMassNotPositiveDefinite:
      return "mass matrix not positive definite";
    case Status::kInconsistentConstraints:
      return "inconsistent constraints";
    case Status::kNonFiniteResult:
      return "non-finite result";
    case Status::kProjectionFailed:
      return "projection onto the constraints failed";
    case Status::kIntegratorFailure:
      return "integrator failure";
    case Status::kEnergyBalance:
      return "energy_balance";
    case Status::kMotionUndetermined:
      return "motion not determined";
    case Status::kInterrupted:
      return "interrupted";
    case Status::kControlFailed:
      return "control failed";
  }
  return "unknown status";
}

namespace detail {
void check_failed(const char* expr, const char* file, int line, const char* msg) {
  throw std::logic_error(std::string("ukdyn internal error: ") + msg + " (" + expr + ") at " +
                         file + ":" + format_number(line));
}
}  // namespace detail

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// Constraint::unilateral: a holonomic row g(q, t) >= 0 whose force only pushes (docs/contact.md).
#include <cmath>
#include <stdexcept>

#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn {

Constraint& Constraint::unilateral(double restitution) {
  const std::string who = "ukdyn::Constraint::unilateral: constraint '" + name_ + "'";
  if (kind_ != ConstraintKind::kHolonomic) {
    throw std::invalid_argument(who + " is " + to_string(kind_) +
                                ": only a holonomic constraint (a gap g(q, t) >= 0) can be "
                                "unilateral");
  }
  if (rows_ != 1) {
    throw std::invalid_argument(who + " has " + format_number(rows_) +
                                " rows: a unilateral constraint is one gap g(q, t) >= 0 (declare "
                                "one constraint per contact)");
  }
  if (!(restitution >= 0.0 && restitution <= 1.0)) {
    throw std::invalid_argument(who + ": the restitution must lie in [0, 1], got " +
                                format_number(restitution, 3));
  }
  // (a contact exists for the whole run: an interval would be ignored by its events)
  if (active_.begin != TimeInterval{}.begin || active_.end != TimeInterval{}.end) {
    throw std::invalid_argument(who + " is active on [" + format_number(active_.begin) + ", " +
                                format_number(active_.end) +
                                "] only: a unilateral constraint with an interval of activity is "
                                "not supported (a contact acts for the whole run)");
  }
  unilateral_ = true;
  restitution_ = restitution;
  return *this;
}

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
/// @file dynamics/contact_restitution.hpp
/// The law of restitution of a unilateral contact's impacts (docs/contact.md, "Impacts" and
/// "Poisson's restitution"): Newton's (kinematic, the default of Constraint::unilateral) or
/// Poisson's (kinetic).
///
/// Glossary: e the contact's coefficient (Constraint::restitution), g'⁻ and g'⁺ its gap speed
/// before and after, P_c the normal impulse of the compression phase (the one that stops the
/// approach), P_r that of the restitution phase.
#pragma once

#include "ukdyn/core/constraint.hpp"

namespace ukdyn {

/// How a unilateral constraint's coefficient of restitution e ends an impact.
enum class RestitutionLaw : unsigned char {
  kNewton,   ///< kinematic: g'⁺ = −e g'⁻ (the default)
  kPoisson,  ///< kinetic: P_r = e P_c, the restitution phase's impulse e times the compression's
};

/// "newton" or "poisson". Cost O(1).
const char* to_string(RestitutionLaw law);

/// A copy of the unilateral constraint `contact` (its name, rows, gap, active interval,
/// stabilization, drive mark and coefficient e) whose impacts follow `law`. Under Poisson's law
/// an impact has two phases (docs/contact.md, "Poisson's restitution"): compression, the
/// impulse P_c that brings the approach to zero (an impact with e = 0, friction included), then
/// restitution, the impulse e P_c at once and whatever more keeps every gap from closing, with
/// friction on the whole normal impulse. Without friction both laws give g'⁺ = −e g'⁻; with
/// friction they differ when the slip stops or reverses during the impact. The gap is evaluated
/// through one more virtual call (the law wraps the constraint's model). Cost O(1).
/// @throws std::invalid_argument naming the constraint when it is not unilateral.
Constraint with_restitution_law(const Constraint& contact, RestitutionLaw law);

/// The law of constraint c's impacts: Poisson's when c was made by with_restitution_law(…,
/// RestitutionLaw::kPoisson), else Newton's. Cost O(1).
RestitutionLaw restitution_law(const Constraint& c);

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// `ukdyn check`: the report of check_model(), readable.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <ukdyn/control/control.hpp>
#include <ukdyn/modelfile/model.hpp>

#include "commands.hpp"
#include "terminal_text.hpp"
#include "ukdyn/core/format.hpp"

namespace ukdyn::cli {
namespace {

const char* kind_name(ConstraintKind kind) {
  switch (kind) {
    case ConstraintKind::kHolonomic:
      return "holonomic";
    case ConstraintKind::kNonholonomic:
      return "nonholonomic";
    default:
      return "acceleration form";
  }
}

}  // namespace

int check_command(const ModelSource& source) {
  const Model model = load_source(source);
  const CheckReport r = check_model(model);
  const System& sys = model.system;
  const double t = model.options.t_start;

  std::printf("model: %s (%s)\n", terminal_text(model.name, false).c_str(),
              terminal_text(model.file, false).c_str());
  std::printf("  coordinates         %lld  (%s)\n", static_cast<long long>(r.coordinates),
              terminal_text(join(sys.coordinate_names())).c_str());
  std::printf("  constraints         %lld\n", static_cast<long long>(sys.constraint_count()));
  bool contacts = false;
  for (const Constraint& c : sys.constraints()) {
    if (c.is_unilateral()) {
      // a contact (docs/contact.md): one-sided, its gap >= 0, with its restitution
      contacts = true;
      std::printf("    %-20s unilateral contact (gap >= 0, pushes only), restitution %s\n",
                  terminal_text(c.name(), false).c_str(), format_number(c.restitution()).c_str());
      continue;
    }
    std::printf("    %-20s %s, %lld row%s%s\n", terminal_text(c.name(), false).c_str(),
                kind_name(c.kind()), static_cast<long long>(c.rows()), c.rows() == 1 ? "" : "s",
                c.is_active(t) ? "" : ", inactive at t_start");
  }
  std::printf("  constraint rows     %lld  (active at t = %g%s)\n",
              static_cast<long long>(r.constraint_rows), t,
              contacts ? "; the contacts that touch, not the open ones" : "");
  std::printf("  rank of A           %lld\n", static_cast<long long>(r.rank));
  std::printf("  degrees of freedom  %lld\n", static_cast<long long>(r.degrees_of_freedom));
  if (r.redundant.empty()) {
    // no constraint is redundant as a whole, yet rows may depend on each other (a closed
    // spatial loop's, as the Bricard mechanism's): say so rather than a bare "none" beside a rank
    // below the row count
    const long long dependent = static_cast<long long>(r.constraint_rows - r.rank);
    if (dependent > 0 && r.contradictory.empty()) {
      std::printf(
          "  redundant constraints  none as a whole; %lld of the %lld rows %s on the others "
          "(rank %lld), as the rows of a closed loop can: ukdyn's solution needs no change\n",
          dependent, static_cast<long long>(r.constraint_rows),
          dependent == 1 ? "depends" : "depend", static_cast<long long>(r.rank));
    } else {
      std::printf("  redundant constraints  none\n");
    }
  } else {
    // a contact's row can be redundant where it touches (a box on four corners) and still not
    // be removable: a one-sided support matters as soon as the motion would lift another one
    std::vector<std::string> bilateral, unilateral;
    for (const std::string& name : r.redundant)
      (sys.constraint(sys.constraint_index(name)).is_unilateral() ? unilateral : bilateral)
          .push_back(name);
    if (!bilateral.empty())
      std::printf(
          "  redundant constraints  %s  (their rows add nothing to the rank of the ones "
          "before them; the motion is the same without them)\n",
          terminal_text(join(bilateral)).c_str());
    if (!unilateral.empty())
      std::printf(
          "  redundant contacts  %s  (touching, their rows add nothing to the rank of the ones "
          "before them here; a one-sided contact still matters once another would lift, and "
          "how the redundant contacts share the load is not determined: docs/contact.md)\n",
          terminal_text(join(unilateral)).c_str());
  }
  if (!r.contradictory.empty()) {
    std::printf(
        "  contradictory constraints  %s  (inconsistent: no state satisfies them "
        "together)\n",
        terminal_text(join(r.contradictory)).c_str());
  }
  if (r.initial_violations.empty()) {
    std::printf("  initial state       consistent with every constraint\n");
  } else {
    std::printf("  initial state       violates %zu constraint%s%s:\n", r.initial_violations.size(),
                r.initial_violations.size() == 1 ? "" : "s",
                !model.project_initial ? ""
                : r.penetrated.empty()
                    ? " (projected before a run: initial: project: true)"
                    : " (a penetrated contact is not projected: a run refuses to start)");
    for (const auto& v : r.initial_violations) std::printf("    %s\n", terminal_text(v).c_str());
  }
  std::printf("  mass matrix         %s\n",
              !r.mass_positive_definite ? "NOT symmetric positive (semi-)definite"
              : r.mass_singular ? "singular, symmetric positive semi-definite (the constraints "
                                  "determine the rest: docs/singular-mass.md)"
                                : "symmetric positive definite");
  if (model.controller) {
    const Controller& ctrl = *model.controller;
    std::printf("  control             %s law, %lld requirement%s, %s%s\n", to_string(ctrl.law()),
                static_cast<long long>(ctrl.requirement_count()),
                ctrl.requirement_count() == 1 ? "" : "s",
                ctrl.fully_actuated() ? "every coordinate actuated" : "actuated:",
                ctrl.robust() ? ", robust term" : "");
    if (!ctrl.fully_actuated() && !ctrl.actuated_coordinates().empty()) {
      for (Index j : ctrl.actuated_coordinates()) {
        std::printf("                        %s\n",
                    terminal_text(sys.coordinate_names()[std::size_t(j)], false).c_str());
      }
    } else if (!ctrl.fully_actuated()) {
      // an actuation matrix (joints' actuators, S given): each actuator's generalized force
      // direction, column j of S, as a combination of the coordinates
      const MatrixXd& S = ctrl.actuation();
      for (Index j = 0; j < S.cols(); ++j) {
        std::string terms;
        for (Index i = 0; i < S.rows(); ++i) {
          const double v = S(i, j);
          if (v == 0.0) continue;
          const std::string& name = sys.coordinate_names()[std::size_t(i)];
          const std::string size = std::abs(v) == 1.0 ? "" : format_number(std::abs(v)) + " ";
          terms += (terms.empty() ? (v < 0 ? "-" : "") : (v < 0 ? " - " : " + ")) + size + name;
        }
        std::printf("                        actuator %lld: %s\n", static_cast<long long>(j + 1),
                    terms.empty() ? "0" : terminal_text(terms, false).c_str());
      }
    }
    for (Index k = 0; k < ctrl.requirement_count(); ++k) {
      const Constraint& c = ctrl.requirement(k);
      std::printf("    %-20s %s, %lld row%s\n", terminal_text(c.name(), false).c_str(),
                  kind_name(c.kind()), static_cast<long long>(c.rows()), c.rows() == 1 ? "" : "s");
    }
  }
  if (r.ok()) {
    std::printf("ok\n");
    return kExitOk;
  }
  std::printf("problems:\n");
  for (const auto& p : r.problems) std::printf("  - %s\n", terminal_text(p).c_str());
  return kExitCheck;
}

}  // namespace ukdyn::cli

// SPDX-License-Identifier: BSD-3-Clause
// Model files, the constraints (modelfile/reader.hpp): constraints: → the rows of A and b,
//   holonomic       A = ∂φ/∂q,  b = −D(D φ)          (D: total time derivative without q̈)
//   nonholonomic    A = ∂ψ/∂q̇,  b = −D ψ
// Every error names file:line:column and gives a hint.
#include "ukdyn/modelfile/model.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>
#include <Eigen/Cholesky>

#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/nonideal.hpp"
#include "ukdyn/dynamics/contact_restitution.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/simulation/options.hpp"

#include "modelfile/initial_keep.hpp"
#include "modelfile/reader.hpp"

namespace ukdyn::model_reader {

namespace {

// The columns of a constraint's A: the union of the rows' inputs in [offset, offset + n), less
// offset, increasing; all n when no row holds any (A is zero: kept dense, as written). O(total
// inputs · log).
std::vector<Index> local_columns(const std::vector<std::vector<Index>>& inputs, Index offset,
                                 Index n) {
  std::set<Index> union_of;
  for (const auto& in : inputs) {
    for (const Index k : in) {
      if (k >= offset && k < offset + n) union_of.insert(k - offset);
    }
  }
  std::vector<Index> columns(union_of.begin(), union_of.end());
  if (columns.empty()) {
    columns.resize(std::size_t(n));
    for (Index j = 0; j < n; ++j) columns[std::size_t(j)] = j;
  }
  return columns;
}

}  // namespace

Constraint Reader::read_constraint(const YAML::Node& c, const std::string& name,
                                   const std::string& what) {
  const Index n = Index(coordinates_.size());
  const int kinds = int(bool(c["holonomic"])) + int(bool(c["nonholonomic"])) + int(bool(c["A"]));
  if (kinds != 1) {
    fail(c, what + " needs exactly one of holonomic, nonholonomic, or A with b");
  }
  std::vector<Expr> accel, levels;
  ConstraintKind kind;
  Index rows = 0;
  std::vector<Index> columns;  // of A: all n (dense rows) or fewer (a local model)
  const Expr zero = set_->constant(0.0);
  if (c["holonomic"]) {
    // A = ∂φ/∂q, b = −D(Dφ); levels [φ; Dφ]
    kind = ConstraintKind::kHolonomic;
    const auto phis = rows_of(c["holonomic"], what);
    rows = Index(phis.size());
    std::vector<Expr> phi, phid, b;
    for (const auto& node : phis) {
      const Expr e = expression(node, what);
      if (const std::string* v = velocity_in(*set_, e, velocities_)) {
        fail(node, what + " is holonomic but depends on the velocity '" + *v + "'",
             "write it as nonholonomic: instead");
      }
      phi.push_back(e);
      phid.push_back(time_derivative(e));
      b.push_back(set_->negate(time_derivative(phid.back())));
    }
    // ∂φ/∂q_j is 0 for the q_j that no row of φ holds: A's columns are those that some row holds
    std::vector<std::vector<Index>> in_phi;
    in_phi.reserve(phi.size());
    for (const Expr& e : phi) in_phi.push_back(set_->inputs_of(e));
    columns = local_columns(in_phi, 0, n);
    for (Index r = 0; r < rows; ++r) {
      const auto& in = in_phi[std::size_t(r)];
      for (const Index j : columns)
        accel.push_back(std::binary_search(in.begin(), in.end(), j)
                            ? set_->diff(phi[std::size_t(r)], coordinates_[std::size_t(j)])
                            : zero);
    }
    accel.insert(accel.end(), b.begin(), b.end());
    levels = phi;
    levels.insert(levels.end(), phid.begin(), phid.end());
  } else if (c["nonholonomic"]) {
    // A = ∂ψ/∂q̇, b = −Dψ; levels [ψ]
    kind = ConstraintKind::kNonholonomic;
    const auto psis = rows_of(c["nonholonomic"], what);
    rows = Index(psis.size());
    std::vector<Expr> psi, b;
    for (const auto& node : psis) {
      psi.push_back(expression(node, what));
      b.push_back(set_->negate(time_derivative(psi.back())));
    }
    // ∂ψ/∂q̇_j is 0 for the q̇_j that no row of ψ holds: A's columns are those that some row holds
    std::vector<std::vector<Index>> in_psi;
    in_psi.reserve(psi.size());
    for (const Expr& e : psi) in_psi.push_back(set_->inputs_of(e));
    columns = local_columns(in_psi, n, n);
    for (Index r = 0; r < rows; ++r) {
      const auto& in = in_psi[std::size_t(r)];
      for (const Index j : columns)
        accel.push_back(std::binary_search(in.begin(), in.end(), n + j)
                            ? set_->diff(psi[std::size_t(r)], velocities_[std::size_t(j)])
                            : zero);
    }
    accel.insert(accel.end(), b.begin(), b.end());
    levels = psi;
  } else {
    kind = ConstraintKind::kAcceleration;
    const YAML::Node A = c["A"], b = c["b"];
    if (!b) fail(c, what + " gives A but no b");
    if (!A.IsSequence() || A.size() == 0) fail(A, "A must be a list of rows");
    rows = Index(A.size());
    const auto bs = rows_of(b, what + ", b");
    if (Index(bs.size()) != rows)
      fail(b, "b must have one entry per row of A (" + format_number(rows) + ")");
    std::vector<Expr> entries;
    for (const auto& row : A) {
      if (!row.IsSequence() || Index(row.size()) != n)
        fail(row, "each row of A must have " + format_number(n) + " entries");
      for (const auto& e : row) entries.push_back(expression(e, what + ", A"));
    }
    // the columns with an entry that is not a literal 0
    std::vector<std::vector<Index>> nonzero(1);
    for (Index j = 0; j < n; ++j) {
      for (Index r = 0; r < rows; ++r) {
        if (set_->is_literal_zero(entries[std::size_t(r * n + j)])) continue;
        nonzero[0].push_back(j);
        break;
      }
    }
    columns = local_columns(nonzero, 0, n);
    for (Index r = 0; r < rows; ++r)
      for (const Index j : columns) accel.push_back(entries[std::size_t(r * n + j)]);
    for (const auto& e : bs) accel.push_back(expression(e, what + ", b"));
  }
  // the inputs the programs read (each evaluation fills those only)
  std::set<Index> read;
  for (const auto* list : {&accel, &levels}) {
    for (const Expr& e : *list) {
      for (const Index k : set_->inputs_of(e)) read.insert(k);
    }
  }
  note_switches(accel);
  note_switches(levels);
  constraint_switch_sources_.emplace_back(name, accel);
  constraint_switch_sources_.back().second.insert(constraint_switch_sources_.back().second.end(),
                                                  levels.begin(), levels.end());
  Constraint constraint(name, kind, rows,
                        std::make_shared<CompiledConstraint>(
                            kind, rows, n, layout_, compile(accel, c, "the derivatives of " + what),
                            compile(levels, c, what), std::vector<Index>(read.begin(), read.end()),
                            Index(columns.size()) < n ? columns : std::vector<Index>{}));
  if (const YAML::Node a = c["active"]) {
    if (!a.IsSequence() || a.size() != 2) fail(a, "active must be [t0, t1]");
    const double t0 = number(a[0], "active"), t1 = number(a[1], "active");
    if (!(t0 <= t1)) fail(a, "active needs t0 <= t1");
    constraint.active_between(t0, t1);
  }
  return constraint;
}

std::pair<double, RestitutionLaw> Reader::read_restitution(const YAML::Node& e,
                                                           const YAML::Node& law,
                                                           const std::string& what) {
  const double restitution = e ? number(e, "restitution") : 0.0;
  if (!(restitution >= 0.0 && restitution <= 1.0)) {
    fail(e,
         "the restitution of " + what + " must lie in [0, 1], got " + format_number(restitution, 3),
         "restitution: 0.5");
  }
  RestitutionLaw restitution_law = RestitutionLaw::kNewton;
  if (law) {
    const std::string text = law.IsScalar() ? law.Scalar() : std::string();
    if (text == "poisson") {
      restitution_law = RestitutionLaw::kPoisson;
    } else if (text != "newton") {
      fail(law,
           "the restitution_law of " + what + " must be newton or poisson, got " +
               (law.IsScalar() ? "'" + text + "'"
                               : std::string("a ") + (law.IsMap() ? "mapping" : "list")),
           "restitution_law: poisson   (Poisson's: the restitution impulse is e times the "
           "compression impulse; newton: g'⁺ = −e g'⁻)");
    }
  }
  return {restitution, restitution_law};
}

void Reader::read_unilateral(const YAML::Node& c, const std::string& name, Constraint& constraint) {
  // unilateral: true (a gap g >= 0 whose force only pushes), restitution: e in [0, 1]
  // (docs/contact.md)
  // restitution_law: newton (the default) or poisson
  const YAML::Node u = c["unilateral"], e = c["restitution"], law = c["restitution_law"];
  // (a YAML boolean only: true or false unquoted; not yes, on, 1, or a quoted "true")
  bool unilateral = false;
  if (u) {
    const std::string text = u.IsScalar() ? u.Scalar() : std::string();
    const bool plain = u.Tag() != "!";
    if (plain && (text == "true" || text == "True" || text == "TRUE")) {
      unilateral = true;
    } else if (!plain || !(text == "false" || text == "False" || text == "FALSE")) {
      fail(u,
           "unilateral in constraint '" + name + "' must be true or false, got " +
               (u.IsScalar() ? (plain ? "" : "the quoted text ") + std::string("'") + text + "'"
                             : std::string("a ") + (u.IsMap() ? "mapping" : "list")),
           "unilateral: true   (unquoted)");
    }
  }
  if (e && !unilateral) {
    fail(e, "constraint '" + name + "' gives a restitution but is not unilateral",
         "unilateral: true, restitution: 0.5");
  }
  if (law && !unilateral) {
    fail(law, "constraint '" + name + "' gives a restitution_law but is not unilateral",
         "unilateral: true, restitution: 0.5, restitution_law: poisson");
  }
  if (!unilateral) return;
  if (constraint.kind() != ConstraintKind::kHolonomic || constraint.rows() != 1) {
    fail(u,
         "constraint '" + name + "' cannot be unilateral: it is " +
             (constraint.kind() != ConstraintKind::kHolonomic
                  ? std::string(to_string(constraint.kind()))
                  : "holonomic with " + format_number(constraint.rows()) + " rows") +
             ", and a unilateral constraint is one holonomic gap g(q, t) >= 0",
         "holonomic: y - r   (one row: the gap)");
  }
  // (a contact acts for the whole run: its events would ignore an interval, docs/contact.md)
  if (const YAML::Node a = c["active"]) {
    fail(a,
         "active: is not supported on a unilateral constraint: the contact '" + name +
             "' would act for the whole run",
         "remove active:; for a surface that comes or goes, run the parts separately, each "
         "starting from the last one's final state");
  }
  const auto [restitution, restitution_law] = read_restitution(e, law, "constraint '" + name + "'");
  constraint.unilateral(restitution);
  if (restitution_law != RestitutionLaw::kNewton)
    constraint = with_restitution_law(constraint, restitution_law);
}

void Reader::read_constraints(const YAML::Node& root, SystemBuilder& builder) {
  const YAML::Node cs = root["constraints"];
  if (!cs) return;
  if (!cs.IsSequence())
    fail(cs, "constraints must be a list", "- {name: rod, holonomic: x^2 + y^2 - 1}");
  std::set<std::string> seen;
  for (const auto& c : cs) {
    if (!c.IsMap()) fail(c, "a constraint must be a mapping with a name and a kind");
    if (!c["name"]) fail(c, "a constraint needs a name", "{name: rod, holonomic: ...}");
    if (!c["name"].IsScalar() || c["name"].Scalar().empty())
      fail(c["name"], "a constraint's name must be a non-empty text", "{name: rod, ...}");
    const std::string name = c["name"].Scalar();
    if (!seen.insert(name).second) fail(c["name"], "constraint '" + name + "' is declared twice");
    for (const auto& kv : c) {
      static const std::set<std::string> keys = {
          "name",   "holonomic",     "nonholonomic", "A",           "b",
          "active", "stabilization", "unilateral",   "restitution", "restitution_law"};
      if (!keys.count(kv.first.Scalar())) {
        fail(kv.first, "unknown key '" + kv.first.Scalar() + "' in constraint '" + name + "'",
             "a constraint has name, holonomic | nonholonomic | A and b, active, stabilization, "
             "unilateral, restitution, restitution_law");
      }
    }
    Constraint constraint = read_constraint(c, name, "constraint '" + name + "'");
    if (const YAML::Node s = c["stabilization"]) {
      if (!s.IsMap()) fail(s, "stabilization must be {alpha: …, beta: …}");
      const double alpha = s["alpha"] ? number(s["alpha"], "alpha") : 0.0;
      const double beta = s["beta"] ? number(s["beta"], "beta") : 0.0;
      if (alpha < 0 || beta < 0) fail(s, "stabilization gains must be >= 0");
      constraint.stabilize(alpha, beta);
    }
    read_unilateral(c, name, constraint);
    builder.add(constraint);
    positions_.constraints[name] = position(c);
    constraint_names_.push_back(name);
    constraint_rows_.push_back(constraint.rows());
  }
}

}  // namespace ukdyn::model_reader

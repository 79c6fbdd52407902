// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/coordinate_partition.cpp
/// Stage 1 of linearize(): the independent coordinates, from column-pivoted QR decompositions of
/// the constraint Jacobians at the operating point (docs/linearize.md, "Choice of coordinates").
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/QR>
#include <Eigen/SVD>

#include "analysis/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"

namespace ukdyn::analysis {
namespace {

std::string join_names(const System& sys, const std::vector<Index>& idx) {
  std::string s;
  for (Index j : idx) s += (s.empty() ? "" : ", ") + sys.coordinate_names()[std::size_t(j)];
  return s.empty() ? "(none)" : s;
}

std::vector<Index> complement(Index n, const std::vector<Index>& set) {
  std::vector<Index> out;
  for (Index j = 0; j < n; ++j)
    if (std::find(set.begin(), set.end(), j) == set.end()) out.push_back(j);
  return out;
}

MatrixXd select(const MatrixXd& A, const std::vector<Index>& rows, const std::vector<Index>& cols) {
  MatrixXd out(Index(rows.size()), Index(cols.size()));
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < cols.size(); ++j) out(Index(i), Index(j)) = A(rows[i], cols[j]);
  return out;
}

// σ_min / σ_max of a tall block (1 for an empty one)
double condition_of(const MatrixXd& J) {
  if (J.cols() == 0) return 1.0;
  if (J.rows() < J.cols()) return 0.0;
  Eigen::JacobiSVD<MatrixXd> svd(J);
  const auto& s = svd.singularValues();
  return s(0) > 0 ? s(s.size() - 1) / s(0) : 0.0;
}

// the first `rank` pivots of a column-pivoted QR of J (columns numbered by `cols`), with the rank
// decided against `scale`; throws at a singular configuration (a kept pivot in the grey zone)
std::vector<Index> pivoted_columns(const MatrixXd& J, const std::vector<Index>& cols, double scale,
                                   const LinearizeOptions& o, const System& sys, const char* who,
                                   const char* what) {
  std::vector<Index> out;
  if (J.rows() == 0 || J.cols() == 0 || scale == 0.0) return out;
  Eigen::ColPivHouseholderQR<MatrixXd> qr(J);
  const Index k = std::min(J.rows(), J.cols());
  const auto R = qr.matrixQR().topLeftCorner(k, k).diagonal().cwiseAbs();
  const auto& perm = qr.colsPermutation().indices();
  for (Index i = 0; i < k; ++i) {
    const double ratio = R(i) / scale;
    if (ratio <= o.rank_threshold) break;
    if (ratio < o.singular_threshold) {
      std::ostringstream msg;
      msg << who << ": singular configuration: the " << what
          << " Jacobian is close to losing rank (pivot " << i + 1 << " is " << ratio
          << " of the largest, between the rank threshold " << o.rank_threshold
          << " and the singular threshold " << o.singular_threshold
          << "); no linear model in minimal coordinates is well defined here (docs/linearize.md, "
             "\"Singular configurations\"). Dependent candidates so far: "
          << join_names(sys, out);
      throw std::invalid_argument(msg.str());
    }
    out.push_back(cols[std::size_t(perm(i))]);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<Index> by_name(const System& sys, const std::vector<std::string>& names,
                           const char* who) {
  std::vector<Index> out;
  for (const auto& name : names) {
    bool rate = false;
    const Index j = coordinate_of(sys, name, rate, who);
    if (std::find(out.begin(), out.end(), j) != out.end())
      throw std::invalid_argument(std::string(who) + ": the independent coordinate '" + name +
                                  "' is given twice");
    out.push_back(j);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// checks a named dependent set: right count and a well-conditioned block of the Jacobian
void check_named(const System& sys, const MatrixXd& J, const std::vector<Index>& dependent,
                 std::size_t rank, const LinearizeOptions& o, const char* who, const char* what) {
  if (dependent.size() != rank) {
    std::ostringstream msg;
    msg << who << ": the constraints fix " << rank << ' ' << what << " here, so " << rank
        << " coordinates must be dependent, but the names given leave " << dependent.size() << " ("
        << join_names(sys, dependent) << ") dependent";
    throw std::invalid_argument(msg.str());
  }
  const std::vector<Index> all_rows = [&] {
    std::vector<Index> r(std::size_t(J.rows()));
    for (Index i = 0; i < J.rows(); ++i) r[std::size_t(i)] = i;
    return r;
  }();
  const double c = condition_of(select(J, all_rows, dependent));
  if (c < o.singular_threshold) {
    std::ostringstream msg;
    msg << who << ": the " << what << " " << join_names(sys, dependent)
        << " cannot be the dependent ones here: their columns of the constraint Jacobian are "
           "singular (σ_min/σ_max = "
        << c << " < " << o.singular_threshold << "); name other independent coordinates";
    throw std::invalid_argument(msg.str());
  }
}

}  // namespace

SolverOptions dense_options(const SolverOptions& solver) {
  SolverOptions o = solver;
  o.engine = Engine::kDense;
  o.algorithm = Algorithm::kDefault;
  return o;
}

Index coordinate_of(const System& sys, const std::string& name, bool& rate, const char* who) {
  rate = false;
  try {
    return sys.coordinate_index(name);
  } catch (const std::invalid_argument&) {
  }
  const std::string suffix = "_dot";
  if (name.size() > suffix.size() && name.ends_with(suffix)) {
    try {
      const Index j = sys.coordinate_index(name.substr(0, name.size() - suffix.size()));
      rate = true;
      return j;
    } catch (const std::invalid_argument&) {
    }
  }
  std::string list;
  for (const auto& c : sys.coordinate_names()) list += (list.empty() ? "" : ", ") + c;
  throw std::invalid_argument(std::string(who) + ": no coordinate '" + name +
                              "' (nor its rate NAME_dot); the coordinates are " + list);
}

Partition choose_coordinates(const System& sys, Workspace& ws, const OperatingPoint& at,
                             const LinearizeOptions& o, const char* who, bool check_manifold) {
  const Index n = sys.coordinate_count();
  if (at.q.size() != n || at.qd.size() != n)
    throw std::invalid_argument(std::string(who) + ": the operating point has " +
                                std::to_string(at.q.size()) + " positions and " +
                                std::to_string(at.qd.size()) + " velocities; the system has " +
                                std::to_string(n) + " coordinates");
  if (!(o.rank_threshold > 0 && o.rank_threshold < 1) ||
      !(o.singular_threshold >= o.rank_threshold && o.singular_threshold < 1) ||
      !(o.initial_step > 0) || o.table_size < 2 || !(o.step_ratio > 1) ||
      !(o.manifold_tolerance > 0))
    throw std::invalid_argument(std::string(who) +
                                ": LinearizeOptions out of range (rank_threshold in (0, 1), "
                                "singular_threshold in [rank_threshold, 1), initial_step > 0, "
                                "table_size >= 2, step_ratio > 1, manifold_tolerance > 0)");

  // the contact mode of the point: an open unilateral contact takes no rows
  hold_contact_mode(sys, ws, at);
  // A at the point, and the rows of each kind
  assemble_constraints(sys, ws, at.q, at.qd, at.t);
  if (ws.status != Status::kOk) throw_if_failed(sys, ws);
  Partition p;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (!ws.active[std::size_t(k)]) continue;
    const Constraint& c = sys.constraint(k);
    if (c.kind() == ConstraintKind::kAcceleration)
      throw std::invalid_argument(
          std::string(who) + ": the constraint '" + c.name() +
          "' is given in acceleration form; its manifold (positions and velocities it "
          "allows) is not known, so minimal coordinates cannot be chosen. Declare it holonomic "
          "or nonholonomic");
    for (Index i = 0; i < c.rows(); ++i) {
      const Index row = sys.row_offset(k) + i;
      if (c.kind() == ConstraintKind::kHolonomic) p.holonomic_rows.push_back(row);
      p.velocity_rows.push_back(row);
    }
  }

  // the point must lie on the manifold: |Φ|, |Φ'|, |ψ| small
  evaluate_violations(sys, ws, at.q, at.qd, at.t);
  const double scale = std::max({1.0, at.q.norm(), at.qd.norm()});
  for (Index row : p.velocity_rows) {
    if (!check_manifold) break;
    const double v = std::max(std::abs(ws.phi(row)), std::abs(ws.phi_dot(row)));
    if (!(v <= o.manifold_tolerance * scale)) {
      Index k = 0;
      while (k + 1 < sys.constraint_count() && sys.row_offset(k + 1) <= row) ++k;
      std::ostringstream msg;
      msg << who << ": the operating point is not on the constraint manifold: row "
          << row - sys.row_offset(k) << " of the constraint '" << sys.constraint(k).name()
          << "' is violated by " << v << " (tolerance " << o.manifold_tolerance * scale
          << "); project the state first (ukdyn::project_positions / project_velocities)";
      throw std::invalid_argument(msg.str());
    }
  }

  const MatrixXd Jh = select(ws.A, p.holonomic_rows, complement(n, {}));
  const MatrixXd Jv = select(ws.A, p.velocity_rows, complement(n, {}));
  const double scale_h = Jh.size() ? Jh.colwise().norm().maxCoeff() : 0.0;
  const double scale_v = Jv.size() ? Jv.colwise().norm().maxCoeff() : 0.0;

  // dependent positions: the best-conditioned columns of Φ_q, or the complement of the names
  if (o.independent_positions.empty()) {
    p.dp = pivoted_columns(Jh, complement(n, {}), scale_h, o, sys, who, "position");
  } else {
    p.dp = complement(n, by_name(sys, o.independent_positions, who));
    const auto rank = pivoted_columns(Jh, complement(n, {}), scale_h, o, sys, who, "position");
    check_named(sys, Jh, p.dp, rank.size(), o, who, "positions");
  }
  p.ip = complement(n, p.dp);

  // dependent velocities: D_p, then the best columns of J_v with range(J_v[:, D_p]) removed
  std::vector<Index> rest = p.ip;
  MatrixXd Jr = select(Jv, complement(Jv.rows(), {}), rest);
  if (!p.dp.empty() && Jv.rows() > 0) {
    const MatrixXd Y = select(Jv, complement(Jv.rows(), {}), p.dp);
    Eigen::HouseholderQR<MatrixXd> qr(Y);
    const MatrixXd Q1 = qr.householderQ() * MatrixXd::Identity(Y.rows(), Y.cols());
    Jr -= Q1 * (Q1.transpose() * Jr);
  }
  const auto dn = pivoted_columns(Jr, rest, scale_v, o, sys, who, "velocity");
  if (o.independent_velocities.empty()) {
    p.dv = p.dp;
    p.dv.insert(p.dv.end(), dn.begin(), dn.end());
    std::sort(p.dv.begin(), p.dv.end());
  } else {
    p.iv = by_name(sys, o.independent_velocities, who);
    for (Index j : p.iv)
      if (std::find(p.dp.begin(), p.dp.end(), j) != p.dp.end())
        throw std::invalid_argument(std::string(who) + ": '" +
                                    sys.coordinate_names()[std::size_t(j)] +
                                    "' is named an independent velocity, but its position is "
                                    "dependent (a holonomic constraint fixes it)");
    p.dv = complement(n, p.iv);
    check_named(sys, Jv, p.dv, p.dp.size() + dn.size(), o, who, "velocities");
  }
  p.iv = complement(n, p.dv);
  p.condition = condition_of(select(Jv, complement(Jv.rows(), {}), p.dv));
  if (!p.dv.empty() && p.condition < o.singular_threshold)
    throw std::invalid_argument(
        std::string(who) + ": singular configuration: the dependent velocities " +
        join_names(sys, p.dv) + " are fixed by an ill-conditioned block " +
        "of the constraint Jacobian (σ_min/σ_max = " + std::to_string(p.condition) + ")");
  return p;
}

}  // namespace ukdyn::analysis

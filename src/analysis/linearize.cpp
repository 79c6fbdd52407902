// SPDX-License-Identifier: BSD-3-Clause
/// @file analysis/linearize.cpp
/// Stage 4 of linearize(): A, B, C, D about an operating point, and the modes
/// (include/ukdyn/analysis/linearize.hpp; docs/linearize.md).
#include "ukdyn/analysis/linearize.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "analysis/internal.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/status.hpp"

namespace ukdyn {
namespace {
constexpr const char* kWho = "linearize";

// ∂q''/∂Q = N (Nᵀ M N)⁻¹ Nᵀ with N a basis of null(A): the fundamental equation's response to
// a generalized force (Gauss's principle restricted to A δq'' = 0), exact. (n × n)
MatrixXd force_response(const Workspace& ws, double rank_threshold) {
  const Index n = ws.M.rows();
  MatrixXd N = MatrixXd::Identity(n, n);
  if (ws.A.rows() > 0) {
    Eigen::JacobiSVD<MatrixXd> svd(ws.A, Eigen::ComputeFullV);
    const auto& s = svd.singularValues();
    Index r = 0;
    while (r < s.size() && s(r) > rank_threshold * s(0)) ++r;
    N = svd.matrixV().rightCols(n - r);
  }
  const MatrixXd G = N.transpose() * ws.M.selfadjointView<Eigen::Lower>() * N;
  Eigen::LLT<MatrixXd> llt(G);
  if (llt.info() != Eigen::Success)
    throw SolveError(Status::kMassNotPositiveDefinite,
                     std::string(kWho) +
                         ": the mass matrix is not positive definite on the constraints' null "
                         "space at the operating point; the force inputs' B is not defined");
  return N * llt.solve(N.transpose());
}

// Ridders' table settled in every entry of J (rows: the entries of F, `rows`; a column per
// input z_c of scale σ_c, `columns`, the larger of its steps' scale and the model's, so that a
// step scale of roundoff cannot make every error look small: 6.1 ± 46 for −24.85, u20 05): err <=
// |J| / 10, or err is small beside the size r_e = |F₀(e)| + s_e of its row, s_e = max over the
// states k of |A(e, k)| σ_k (`row_scale`: how much entry e changes over the states' scales): err <=
// 1e-3 r_e / σ_c, or err <= 1e-6 max_e r_e / σ_c (a row that is 0 but for roundoff, a wheel's rate
// along the lean: 2.5e-13 ± 2.2e-13). Otherwise the steps straddle a kink or a pole (an input that
// is not differentiable there, or a first step that leaves the function's smooth part): an error,
// never a table that did not settle returned as the derivative (a parameter of 1 mm stepped by 0.1
// gave B = −858 for 2.9e6, B_error 568). Cost O(rows · columns).
void require_settled(const MatrixXd& J, const MatrixXd& err, const VectorXd& F0,
                     const VectorXd& row_scale, const VectorXd& sigma, const VectorXd& steps,
                     const std::vector<std::string>& columns, const std::vector<std::string>& rows,
                     const std::vector<std::string>& notes = {}) {
  const VectorXd r = F0.cwiseAbs() + row_scale;
  const double largest = r.size() > 0 ? r.maxCoeff() : 0.0;
  for (Index c = 0; c < J.cols(); ++c)
    for (Index e = 0; e < J.rows(); ++e) {
      const double e_ = err(e, c);
      if (e_ <= 0.1 * std::abs(J(e, c)) || e_ <= 1e-3 * r(e) / sigma(c) ||
          e_ <= 1e-6 * largest / sigma(c))
        continue;
      throw SolveError(Status::kNonFiniteResult,
                       std::string(kWho) + ": the derivative of " + rows[std::size_t(e)] +
                           " along " + columns[std::size_t(c)] + " did not settle (" +
                           format_number(J(e, c), 4) + " ± " + format_number(e_, 2) +
                           "): it is not differentiable there, or not smooth over steps of " +
                           format_number(steps(c), 3) +
                           " (LinearizeOptions::initial_step scales them; docs/linearize.md)" +
                           (std::size_t(c) < notes.size() ? notes[std::size_t(c)] : ""));
    }
}

// Force inputs enter B exactly (force_response) unless a non-ideal force can see them: with
// constraint rows acting, a friction that reads the reactions (a contact's, a joint's under
// load) changes with the force input, and ∂q''/∂u is not N (Nᵀ M N)⁻¹ Nᵀ. Where no row acts,
// every reaction is 0 whatever u is — a robot tree with URDF joint friction (u20 06: its joint
// torques were refused though the friction reads nothing): the non-ideal forces depend on the
// state only, and the column is exact. @throws std::invalid_argument naming the input.
void require_exact_force_inputs(const System& sys, const analysis::Partition& part,
                                const std::vector<LinearInput>& inputs) {
  if (sys.nonideal_count() == 0 || part.velocity_rows.empty()) return;
  for (const auto& in : inputs)
    if (in.kind == InputKind::kForce)
      throw std::invalid_argument(
          std::string(kWho) + ": force input '" + in.name +
          "': the system has non-ideal forces ('" + sys.nonideal_name(0) + "'" +
          (sys.nonideal_count() > 1 ? ", …" : "") +
          ") and constraints acting at the point: the forces may read the reactions an input "
          "changes, so its column of B is not exact; force inputs are supported where no "
          "constraint acts or with ideal constraints (a parameter input works: docs/linearize.md)");
}

// What a column at rest along a non-ideal force says: Coulomb friction (a URDF joint's
// <dynamics friction>, a contact's mu) has a kink at a rate of 0 (regularized over 1e-6), so the
// table along that rate does not settle and no linear model exists there. One note per state
// (empty for positions and for rates that are not at rest). O(s · forces).
std::vector<std::string> friction_notes(const System& sys, const analysis::Partition& part,
                                        const OperatingPoint& at, const VectorXd& sigma) {
  std::vector<std::string> notes(part.ip.size() + part.iv.size());
  if (sys.nonideal_count() == 0) return notes;
  std::string names;
  for (Index i = 0; i < sys.nonideal_count(); ++i)
    names += (i ? ", '" : "'") + sys.nonideal_name(i) + "'";
  for (std::size_t k = 0; k < part.iv.size(); ++k) {
    const Index j = part.iv[k];
    const std::size_t c = part.ip.size() + k;
    if (std::abs(at.qd(j)) >= 1e-3 * sigma(Index(c))) continue;
    const std::string rate = sys.coordinate_names()[std::size_t(j)] + "_dot";
    notes[c] = "; at " + rate + " = 0 the system's non-ideal forces (" + names +
               ") are not differentiable when they are Coulomb friction (a URDF joint's "
               "<dynamics friction>, a contact's mu: a kink at rest), and no linear model "
               "exists there: linearize at a state where " +
               rate + " is not 0, or a model without that friction";
  }
  return notes;
}

// A kink at the point: f continuous, its one-sided derivatives different — a contact whose gap
// switches from one region of its shape to another there (a sphere over a box's edge: the face's
// row on one side, the edge's on the other; g is C¹, not C²). Ridders' central differences then
// return the mean of the two slopes at every step, and the table settles on a number that
// belongs to neither side (u22 03: g/(2r) for 0 and g/r, A_error 1e-12). The second difference
// s(h) = (F(x + h) − 2 F(x) + F(x − h)) / h is the jump of the one-sided slopes at every h across
// a kink, and shrinks with h where F is smooth (F'' h): entry e is kinked along state k when
// |s(h₁)| exceeds the settling tolerance of require_settled (1e-3 r_e / σ_k, 1e-6 of the largest
// row's size / σ_k) and half of |s(4 h₁)|, h₁ the table's smallest step (a kink within about
// h₁ / 2 of the point). The contact to blame is a unilateral one held at the point whose row of
// A has such a kink along k. @throws SolveError naming the contact (or the entry), both
// one-sided derivatives and what to do. Cost: 4 evaluations per state, 1 at the point.
void refuse_kinks(const System& sys, analysis::ReducedDynamics& rd, const LinearModel& lm,
                  const std::vector<LinearOutput>& outputs, const VectorXd& h,
                  const VectorXd& sigma, const VectorXd& row_scale,
                  const std::vector<std::string>& rows, const LinearizeOptions& options) {
  const Index s = lm.x0.size(), p = row_scale.size();
  VectorXd F0(p), Fp(p), Fm(p), Fp4(p), Fm4(p), x(s);
  if (!rd.evaluate(lm.x0, outputs, F0)) return;
  const MatrixXd A0 = rd.workspace().A;
  MatrixXd Ap, Am, Ap4, Am4;
  const VectorXd r = F0.cwiseAbs() + row_scale;
  const double largest = r.size() > 0 ? r.maxCoeff() : 0.0;
  const double smallest = std::pow(options.step_ratio, options.table_size - 1);
  for (Index k = 0; k < s; ++k) {
    const double h1 = h(k) / smallest, h4 = 4 * h1;
    const auto at = [&](double step, VectorXd& F, MatrixXd& A) {
      x = lm.x0;
      x(k) += step;
      if (!rd.evaluate(x, outputs, F)) return false;
      A = rd.workspace().A;
      return true;
    };
    // (a step the chart cannot take: the table's own steps were taken, so leave it be)
    if (!at(h1, Fp, Ap) || !at(-h1, Fm, Am) || !at(h4, Fp4, Ap4) || !at(-h4, Fm4, Am4)) continue;
    for (Index e = 0; e < p; ++e) {
      const double s1 = (Fp(e) - 2 * F0(e) + Fm(e)) / h1;
      const double s4 = (Fp4(e) - 2 * F0(e) + Fm4(e)) / h4;
      const double tol = std::max(1e-3 * r(e), 1e-6 * largest) / sigma(k);
      if (!(std::abs(s1) > tol && std::abs(s1) > 0.5 * std::abs(s4))) continue;
      // the one-sided derivatives, extrapolated to h → 0 (D(h) = D + c h: (4 D(h₁) − D(4h₁)) / 3)
      const double below = (4 * (F0(e) - Fm(e)) / h1 - (F0(e) - Fm4(e)) / h4) / 3;
      const double above = (4 * (Fp(e) - F0(e)) / h1 - (Fp4(e) - F0(e)) / h4) / 3;
      // the contact whose row kinks along k
      std::string contact;
      for (Index c = 0; c < sys.constraint_count() && contact.empty(); ++c) {
        if (!sys.constraint(c).is_unilateral() || !rd.workspace().active[std::size_t(c)]) continue;
        const Index r0 = sys.row_offset(c);
        for (Index i = r0; i < r0 + sys.constraint(c).rows() && contact.empty(); ++i)
          for (Index j = 0; j < A0.cols(); ++j) {
            const double size =
                std::max({std::abs(A0(i, j)), std::abs(Ap(i, j)), std::abs(Am(i, j)),
                          std::abs(Ap4(i, j)), std::abs(Am4(i, j))});
            const double a1 = (Ap(i, j) - 2 * A0(i, j) + Am(i, j)) / h1;
            const double a4 = (Ap4(i, j) - 2 * A0(i, j) + Am4(i, j)) / h4;
            if (std::abs(a1) > 1e-6 * size / sigma(k) && std::abs(a1) > 0.5 * std::abs(a4)) {
              contact = sys.constraint(c).name();
              break;
            }
          }
      }
      const std::string& state = lm.state_names[std::size_t(k)];
      const std::string x0 = format_number(lm.x0(k), 6);
      const std::string slopes = "the derivative of " + rows[std::size_t(e)] + " along " + state +
                                 " is " + format_number(below, 4) + " on the side " + state +
                                 " < " + x0 + " and " + format_number(above, 4) + " on " + state +
                                 " > " + x0 + " (a central difference returns their mean, " +
                                 format_number(0.5 * (below + above), 4) + ")";
      throw SolveError(
          Status::kNonFiniteResult,
          std::string(kWho) + ": " +
              (contact.empty()
                   ? "the model is not differentiable at the operating point: " + slopes +
                         ": a switch there (abs, sign, min, max in an expression, a contact "
                         "changing the region of its gap); no linear model exists at a switch: "
                         "move the operating point off it (docs/linearize.md, \"Non-smooth "
                         "forces\")"
                   : "the contact '" + contact +
                         "' switches there between two regions of its gap (its gap is not "
                         "twice differentiable: a sphere's centre over a box's edge or corner, "
                         "between a face's region and an edge's; a disk–sphere contact between "
                         "the disk's rim and its face): " +
                         slopes +
                         "; no linear model exists at a switch: move the operating point off "
                         "it, to one side of the switch (docs/linearize.md, \"Non-smooth "
                         "forces\")"));
    }
  }
}

}  // namespace

LinearInput force_input(const System& sys, const std::string& coordinate) {
  LinearInput in;
  in.name = coordinate;
  in.kind = InputKind::kForce;
  in.coordinate = sys.coordinate_index(coordinate);
  return in;
}

LinearOutput coordinate_output(const System& sys, const std::string& name) {
  LinearOutput out;
  out.name = name;
  out.coordinate = analysis::coordinate_of(sys, name, out.rate, "coordinate_output");
  return out;
}

std::vector<std::pair<std::string, std::complex<double>>> LinearModel::mode(Index k) const {
  if (k < 0 || k >= eigenvectors.cols())
    throw std::invalid_argument("LinearModel::mode: no mode " + std::to_string(k) + " (there are " +
                                std::to_string(eigenvectors.cols()) + ")");
  std::vector<std::pair<std::string, std::complex<double>>> out;
  for (Index i = 0; i < eigenvectors.rows(); ++i)
    out.emplace_back(state_names[std::size_t(i)], eigenvectors(i, k));
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return std::abs(a.second) > std::abs(b.second);
  });
  return out;
}

LinearModel linearize(const System& sys, const OperatingPoint& at,
                      const std::vector<LinearInput>& inputs,
                      const std::vector<LinearOutput>& outputs, const LinearizeOptions& options) {
  const Index n = sys.coordinate_count();
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const auto& in = inputs[i];
    if (in.kind == InputKind::kForce && (in.coordinate < 0 || in.coordinate >= n))
      throw std::invalid_argument(std::string(kWho) + ": input " + std::to_string(i) + " ('" +
                                  in.name + "') is a force along coordinate " +
                                  std::to_string(in.coordinate) + ", not in [0, " +
                                  std::to_string(n) + ")");
    if (in.kind == InputKind::kParameter && !in.family)
      throw std::invalid_argument(std::string(kWho) + ": parameter input '" + in.name +
                                  "' has no family of systems");
  }
  for (std::size_t i = 0; i < outputs.size(); ++i)
    if (!outputs[i].expression && (outputs[i].coordinate < 0 || outputs[i].coordinate >= n))
      throw std::invalid_argument(std::string(kWho) + ": output '" + outputs[i].name +
                                  "' names coordinate " + std::to_string(outputs[i].coordinate) +
                                  ", not in [0, " + std::to_string(n) + ")");

  // stage 1: the coordinates
  Workspace ws(sys, analysis::dense_options(options.solver));
  const analysis::Partition part = analysis::choose_coordinates(sys, ws, at, options, kWho);
  require_exact_force_inputs(sys, part, inputs);
  analysis::ReducedDynamics rd(sys, part, at, options);
  const Index s = rd.state_size(), ny = Index(outputs.size()), nu = Index(inputs.size());

  LinearModel lm;
  lm.open_contacts = analysis::hold_contact_mode(sys, ws, at);
  lm.independent_positions = part.ip;
  lm.independent_velocities = part.iv;
  lm.chart_condition = part.condition;
  for (Index j : part.ip) lm.state_names.push_back(sys.coordinate_names()[std::size_t(j)]);
  for (Index j : part.iv) lm.state_names.push_back(sys.coordinate_names()[std::size_t(j)] + "_dot");
  for (const auto& in : inputs) lm.input_names.push_back(in.name);
  for (const auto& y : outputs) lm.output_names.push_back(y.name);

  // the point itself: f₀ (zero at an equilibrium), M and A for the force inputs
  lm.x0 = rd.base_state();
  VectorXd F0(s + ny);
  if (!rd.evaluate(lm.x0, outputs, F0))
    throw SolveError(Status::kProjectionFailed,
                     std::string(kWho) + ": at the operating point: " + rd.why());
  lm.f0 = F0.head(s);

  // A, C: Ridders on x ↦ (f, g)
  const analysis::RiddersOptions ro{options.table_size, options.step_ratio, 2.0};
  std::string why;
  VectorXd h(s);
  // (relative to each state's own scale, never to a unit: ReducedDynamics::state_scales)
  h = options.initial_step * rd.state_scales();
  MatrixXd J, E;
  const analysis::VectorFunction F = [&](const Eigen::Ref<const VectorXd>& x,
                                         Eigen::Ref<VectorXd> out) {
    return rd.evaluate(x, outputs, out);
  };
  if (!analysis::ridders_jacobian(F, lm.x0, h, s + ny, ro, J, E, why))
    throw SolveError(Status::kProjectionFailed, std::string(kWho) + ": " + why + ": " + rd.why());
  std::vector<std::string> rows;  // (F's entries: f of the states, then the outputs)
  for (const auto& x : lm.state_names) rows.push_back(x + "'");
  for (const auto& y : lm.output_names) rows.push_back("output '" + y + "'");
  const VectorXd sigma = (h / options.initial_step).cwiseMax(rd.model_state_scales());
  VectorXd row_scale = VectorXd::Zero(s + ny);
  for (Index k = 0; k < s; ++k) row_scale = row_scale.cwiseMax(J.col(k).cwiseAbs() * sigma(k));
  require_settled(J, E, F0, row_scale, sigma, h, lm.state_names, rows,
                  friction_notes(sys, part, at, sigma));
  refuse_kinks(sys, rd, lm, outputs, h, sigma, row_scale, rows, options);
  lm.A = J.topRows(s);
  lm.A_error = E.topRows(s);
  lm.C = J.bottomRows(ny);
  lm.C_error = E.bottomRows(ny);

  // B, D: exact for forces, Ridders over the family for parameters
  lm.B.setZero(s, nu);
  lm.B_error.setZero(s, nu);
  lm.D.setZero(ny, nu);
  lm.D_error.setZero(ny, nu);
  MatrixXd response;
  for (Index c = 0; c < nu; ++c) {
    const auto& in = inputs[std::size_t(c)];
    if (in.kind == InputKind::kForce) {
      // δq'' = N (Nᵀ M N)⁻¹ Nᵀ e_j u: only the velocity rows of B
      rd.evaluate(lm.x0, outputs, F0);
      if (response.size() == 0) response = force_response(rd.workspace(), options.rank_threshold);
      Index k = Index(part.ip.size());
      for (Index j : part.iv) lm.B(k++, c) = response(j, in.coordinate);
      continue;
    }
    const analysis::VectorFunction Fp = [&](const Eigen::Ref<const VectorXd>& u,
                                            Eigen::Ref<VectorXd> out) {
      // (a family that refuses the value — a model file whose expressions cannot be evaluated
      // there — is a point the function cannot be evaluated at, as a failed chart is)
      std::optional<System> family;
      try {
        family.emplace(in.family(in.nominal + u(0)));
      } catch (const std::exception& e) {
        why =
            "the system at " + in.name + " = " + format_number(in.nominal + u(0)) + ": " + e.what();
        return false;
      }
      const System& sp = *family;
      if (sp.coordinate_count() != n || sp.constraint_rows() != sys.constraint_rows()) {
        why = "the system at " + in.name + " = " + std::to_string(in.nominal + u(0)) +
              " has other coordinates or constraints";
        return false;
      }
      analysis::ReducedDynamics rp(sp, part, at, options);
      const bool ok = rp.evaluate(lm.x0, outputs, out);
      if (!ok) why = rp.why();
      return ok;
    };
    // (relative to p₀: a parameter of 1 mm in SI units stepped by 0.1 crossed 0; a parameter
    // at 0, a force's magnitude, has no scale but its unit's)
    const double p_scale = in.nominal != 0.0 ? std::abs(in.nominal) : 1.0;
    const VectorXd u0 = VectorXd::Zero(1);
    const VectorXd hu = VectorXd::Constant(1, options.initial_step * p_scale);
    std::string why_p;
    if (!analysis::ridders_jacobian(Fp, u0, hu, s + ny, ro, J, E, why_p))
      throw SolveError(Status::kProjectionFailed,
                       std::string(kWho) + ": parameter '" + in.name + "': " + why_p + ": " + why);
    require_settled(J, E, F0, row_scale, VectorXd::Constant(1, p_scale), hu,
                    {"parameter '" + in.name + "'"}, rows);
    lm.B.col(c) = J.col(0).head(s);
    lm.B_error.col(c) = E.col(0).head(s);
    lm.D.col(c) = J.col(0).tail(ny);
    lm.D_error.col(c) = E.col(0).tail(ny);
  }

  // the subsystem asked for, then its modes
  if (!options.states.empty()) analysis::keep_states(lm, options.states, kWho);
  if (lm.A.rows() > 0) {
    Eigen::EigenSolver<MatrixXd> es(lm.A);
    if (es.info() != Eigen::Success)
      throw SolveError(Status::kNonFiniteResult,
                       std::string(kWho) + ": the eigenvalues of A did not converge");
    lm.eigenvalues = es.eigenvalues();
    lm.eigenvectors = es.eigenvectors();
  }
  return lm;
}

}  // namespace ukdyn

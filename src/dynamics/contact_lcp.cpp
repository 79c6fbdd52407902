// SPDX-License-Identifier: BSD-3-Clause
// ContactLcp: the linear complementarity problem w = W z + r, w, z >= 0, wᵀz = 0 of the contacts
// that push, solved by Siconos Numerics' lexicographic Lemke method and, where Lemke finds no
// solution (a W that is not positive semi-definite: the controlled W̃ of a weighted or actuated
// law), by its enumeration of the 2^k complementary bases (docs/contact.md, "The LCP solver").
#include "ukdyn/dynamics/contact.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <siconos/numerics/LCP_Solvers.h>
#include <siconos/numerics/LinearComplementarityProblem.h>
#include <siconos/numerics/NumericsMatrix.h>
#include <siconos/numerics/NumericsVerbose.h>
#include <siconos/numerics/SolverOptions.h>
#include <siconos/numerics/lcp_cst.h>
#include <siconos/numerics/lcp_enum.h>

#include "ukdyn/core/format.hpp"
#include "ukdyn/core/status.hpp"

namespace ukdyn {

namespace {
// one Siconos solve of `problem` into z, w (k each) by Lemke or (SICONOS_LCP_ENUM) the
// enumeration with its sign tolerance and our workspace; returns Siconos's info
int run_siconos(LinearComplementarityProblem& problem, int solver_id, double enum_tolerance,
                double* z, double* w, std::vector<double>& dwork, std::vector<int>& iwork) {
  // solver_options_delete frees the members but not the structure itself (Siconos 4.4, Debian
  // 12): the structure is freed here, or every solve leaks 120 bytes (LeakSanitizer, CI)
  const std::unique_ptr<::SolverOptions, void (*)(::SolverOptions*)> options(
      solver_options_create(solver_id), [](::SolverOptions* o) {
        // (lcp_enum's workspace is ours: not Siconos's to free)
        o->dWork = nullptr;
        o->iWork = nullptr;
        solver_options_delete(o);
        std::free(o);  // NOLINT(cppcoreguidelines-no-malloc): Siconos allocated it with malloc
      });
  std::fill(z, z + problem.size, 0.0);
  std::fill(w, w + problem.size, 0.0);
  int info = 0;
  if (solver_id == SICONOS_LCP_ENUM) {
    // the workspace reserved at construction (its size checked against Siconos's own count)
    UKDYN_CHECK(std::size_t(lcp_enum_getNbDWork(&problem, options.get())) <= dwork.size() &&
                    std::size_t(lcp_enum_getNbIWork(&problem, options.get())) <= iwork.size(),
                "ContactLcp: lcp_enum needs more workspace than reserved");
    options->dWork = dwork.data();
    options->iWork = iwork.data();
    options->dparam[SICONOS_DPARAM_TOL] = enum_tolerance;
    lcp_enum(&problem, z, w, &info, options.get());
  } else {
    lcp_lexicolemke(&problem, z, w, &info, options.get());
  }
  return info;
}

}  // namespace

const char* to_string(ContactEvent::Kind kind) {
  switch (kind) {
    case ContactEvent::Kind::kImpact:
      return "impact";
    case ContactEvent::Kind::kRelease:
      return "release";
    case ContactEvent::Kind::kRest:
      return "rest";
    case ContactEvent::Kind::kStick:
      return "stick";
    case ContactEvent::Kind::kSlip:
      return "slip";
  }
  return "unknown";
}

ContactLcp::ContactLcp(Index max_size) : max_size_(max_size) {
  if (max_size < 0) {
    throw std::invalid_argument("ukdyn::ContactLcp: max_size must be >= 0, got " +
                                format_number(max_size));
  }
  r_.resize(max_size);
  d_.setOnes(max_size);
  z_.setZero(max_size);
  w_.setZero(max_size);
  // lcp_enum's workspace: the k × k system, its right-hand side and two k-vectors; k pivots and
  // k basis flags (lcp_enum_getNbDWork / getNbIWork, Siconos 4.4)
  const Index m = std::min(max_size, kMaxEnumerated);
  enum_dwork_.assign(std::size_t(3 * m + m * m), 0.0);
  enum_iwork_.assign(std::size_t(2 * m), 0);
}

ContactLcp::~ContactLcp() = default;
ContactLcp::ContactLcp(ContactLcp&&) noexcept = default;
ContactLcp& ContactLcp::operator=(ContactLcp&&) noexcept = default;

bool ContactLcp::solve(const Eigen::Ref<const MatrixXd>& W, const Eigen::Ref<const VectorXd>& r,
                       double tolerance) {
  const Index k = r.size();
  if (W.rows() != k || W.cols() != k || k > max_size_) {
    throw std::invalid_argument("ukdyn::ContactLcp::solve: W must be k × k and r k with k <= " +
                                format_number(max_size_) + ", got W " + format_number(W.rows()) +
                                " × " + format_number(W.cols()) + " and r " + format_number(k));
  }
  size_ = k;
  info_ = 0;
  auto z = z_.head(k);
  auto w = w_.head(k);
  // r >= 0: z = 0, w = r (every contact separates or stays without force)
  if (k == 0 || r.minCoeff() >= 0.0) {
    z.setZero();
    w = r;
    return true;
  }
  // the scaled problem W̃ = D W D, r̃ = D r (w̃ = D w, z = D z̃): d_i a power of two near
  // |W_ii|^(−1/2), so that Lemke's pivots and the enumeration's signs meet diagonals of order one
  // whatever the rows' factor (a gap 1e-90 y gave W ~ 1e-180, where Lemke found no solution);
  // exact in binary, and d_i = 1 for |W_ii| in [2^-10, 2^10] (every model in SI units: then
  // nothing is scaled, bit for bit), and for a zero diagonal (the friction cone's rows)
  auto d = d_.head(k);
  for (Index i = 0; i < k; ++i) d[i] = row_scale(W(i, i));
  const bool scaled = (d.array() != 1.0).any();
  // lexicographic Lemke on a column-major copy (Siconos reads W as a Fortran array), quiet
  MatrixXd scaled_W = W;  // (the copies: allocated at events only, never in a step)
  if (scaled) scaled_W = d.asDiagonal() * W * d.asDiagonal();
  MatrixXd dense = scaled_W;  // (Siconos's)
  if (scaled) {
    r_.head(k) = d.cwiseProduct(r);
  } else {
    r_.head(k) = r;
  }
  const auto rs = r_.head(k);
  numerics_set_verbose(0);
  NumericsMatrix* M = NM_create_from_data(NM_DENSE, int(k), int(k), dense.data());
  LinearComplementarityProblem problem{};
  problem.size = int(k);
  problem.M = M;
  problem.q = r_.data();
  solver_ = Solver::kLemke;
  info_ =
      run_siconos(problem, SICONOS_LCP_LEMKE, 0.0, z_.data(), w_.data(), enum_dwork_, enum_iwork_);
  bool ok = info_ == 0 && check(scaled_W, rs, tolerance);
  const double W_norm = scaled_W.norm();
  if (!ok && k <= kMaxEnumerated && W_norm > 0.0) {
    // Lemke may end on a ray where a solution exists unless W is copositive-plus (a symmetric
    // PSD W is): enumerate the complementary bases, exact for the few contacts of an event.
    // Its sign test on the basic variables (w_i or z_i) is absolute: tolerance times the larger
    // of their scales ‖r‖ and ‖r‖ / ‖W‖ (the solution is checked as Lemke's after)
    dense = scaled_W;
    solver_ = Solver::kEnumeration;
    info_ =
        run_siconos(problem, SICONOS_LCP_ENUM, tolerance * rs.norm() * std::max(1.0, 1.0 / W_norm),
                    z_.data(), w_.data(), enum_dwork_, enum_iwork_);
    ok = info_ == 0 && check(scaled_W, rs, tolerance);
  }
  NM_free_not_dense(M);  // (the data is dense's)
  if (!ok) {
    if (info_ == 0) info_ = -1;
    return false;
  }
  // (roundoff below the tolerance: exact signs); z = D z̃, w = D⁻¹ w̃
  z = z.cwiseMax(0.0);
  w = w.cwiseMax(0.0);
  if (scaled) {
    z = z.cwiseProduct(d);
    w = w.cwiseQuotient(d);
  }
  return true;
}

double ContactLcp::row_scale(double W_ii) {
  // 2^(−10 j) with j the nearest whole number to log2 |W_ii| / 20: |W_ii| d² in [2^-10, 2^10]
  const double a = std::abs(W_ii);
  if (!(a > 0.0) || !std::isfinite(a)) return 1.0;
  const double j = std::round(std::log2(a) / 20.0);
  return j == 0.0 ? 1.0 : std::ldexp(1.0, -10 * int(j));
}

bool ContactLcp::check(const Eigen::Ref<const MatrixXd>& W, const Eigen::Ref<const VectorXd>& r,
                       double tolerance) {
  // w = W z + r, z >= 0, w >= 0, wᵀz = 0, to tolerance · (‖W‖ ‖z‖ + ‖r‖)
  const Index k = r.size();
  auto z = z_.head(k);
  auto w = w_.head(k);
  w = W * z + r;
  const double scale = W.norm() * z.norm() + r.norm();
  const double tol = tolerance * std::max(scale, 1e-300);
  return z.minCoeff() >= -tol && w.minCoeff() >= -tol &&
         std::abs(w.dot(z)) <= tol * (z.norm() + 1.0);
}

}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// ContactLcp: the linear complementarity problem w = W z + r, w, z >= 0, wᵀz = 0 of the contacts
// that push, solved by Siconos Numerics' lexicographic Lemke method (docs/contact.md).
#include "ukdyn/dynamics/contact.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>

#include <siconos/numerics/LCP_Solvers.h>
#include <siconos/numerics/LinearComplementarityProblem.h>
#include <siconos/numerics/NumericsMatrix.h>
#include <siconos/numerics/NumericsVerbose.h>
#include <siconos/numerics/SolverOptions.h>
#include <siconos/numerics/lcp_cst.h>

#include "ukdyn/core/format.hpp"

namespace ukdyn {

const char* to_string(ContactEvent::Kind kind) {
  switch (kind) {
    case ContactEvent::Kind::kImpact:
      return "impact";
    case ContactEvent::Kind::kRelease:
      return "release";
    case ContactEvent::Kind::kRest:
      return "rest";
  }
  return "unknown";
}

ContactLcp::ContactLcp(Index max_size) : max_size_(max_size) {
  if (max_size < 0) {
    throw std::invalid_argument("ukdyn::ContactLcp: max_size must be >= 0, got " +
                                format_number(max_size));
  }
  r_.resize(max_size);
  z_.setZero(max_size);
  w_.setZero(max_size);
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
  // lexicographic Lemke on a column-major copy (Siconos reads W as a Fortran array), quiet
  MatrixXd dense = W;  // (Siconos's copy: allocated at events only, never in a step)
  r_.head(k) = r;
  numerics_set_verbose(0);
  NumericsMatrix* M = NM_create_from_data(NM_DENSE, int(k), int(k), dense.data());
  LinearComplementarityProblem problem{};
  problem.size = int(k);
  problem.M = M;
  problem.q = r_.data();
  // solver_options_delete frees the members but not the structure itself (Siconos 4.4, Debian
  // 12): the structure is freed here, or every solve leaks 120 bytes (LeakSanitizer, CI)
  const std::unique_ptr<::SolverOptions, void (*)(::SolverOptions*)> options(
      solver_options_create(SICONOS_LCP_LEMKE), [](::SolverOptions* o) {
        solver_options_delete(o);
        std::free(o);  // NOLINT(cppcoreguidelines-no-malloc): Siconos allocated it with malloc
      });
  z.setZero();
  w.setZero();
  lcp_lexicolemke(&problem, z_.data(), w_.data(), &info_, options.get());
  NM_free_not_dense(M);  // (the data is dense's)
  if (info_ != 0) return false;
  // the solution checked: w = W z + r, z >= 0, w >= 0, wᵀz = 0, to tolerance
  w = W * z + r;
  const double scale = W.norm() * z.norm() + r.norm();
  const double tol = tolerance * std::max(scale, 1e-300);
  if (z.minCoeff() < -tol || w.minCoeff() < -tol || std::abs(w.dot(z)) > tol * (z.norm() + 1.0)) {
    info_ = -1;
    return false;
  }
  // (roundoff below the tolerance: exact signs)
  z = z.cwiseMax(0.0);
  w = w.cwiseMax(0.0);
  return true;
}

}  // namespace ukdyn

// Workspace: sizing every buffer once; describing a failed evaluation.
#include "ukdyn/workspace.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "ukdyn/reference.hpp"
#include "ukdyn/system.hpp"

namespace ukdyn {

Workspace::Workspace(const System& sys, const SolverOptions& options)
    : options_(options), system_id_(sys.id()), n_(sys.dofs()), m_(sys.constraint_rows()) {
  if (!(options.rank_threshold > 0.0 && options.rank_threshold < 1.0)) {
    throw std::invalid_argument("ukdyn::Workspace: SolverOptions::rank_threshold must lie in "
                                "(0, 1), got " + std::to_string(options.rank_threshold));
  }
  if (!(options.consistency_tolerance > 0.0)) {
    throw std::invalid_argument("ukdyn::Workspace: SolverOptions::consistency_tolerance must be "
                                "> 0, got " + std::to_string(options.consistency_tolerance));
  }
  if (!(options.symmetry_tolerance >= 0.0)) {
    throw std::invalid_argument("ukdyn::Workspace: SolverOptions::symmetry_tolerance must be "
                                ">= 0, got " + std::to_string(options.symmetry_tolerance));
  }
  const Index n = n_, m = m_, K = sys.constraint_count();
  M.setZero(n, n);
  Q.setZero(n);
  a.setZero(n);
  A.setZero(m, n);
  b.setZero(m);
  active.assign(std::size_t(K), 0);
  activity_override.assign(std::size_t(K), -1);
  nonideal_enabled.assign(std::size_t(sys.nonideal_count()), 1);
  slip_hint.setZero(n, sys.nonideal_count());
  for (const auto& c : sys.constraints()) stabilization.push_back(c.stabilization());
  phi.setZero(m);
  phi_dot.setZero(m);
  zero_n.setZero(n);
  lambda_tmp.setZero(m);
  decomposition.resize(n, m);
  decomposition.set_threshold(options.rank_threshold);
  e.setZero(m);
  lambda.setZero(m);
  Qc_ideal.setZero(n);
  shares.setZero(n, K);
  C.setZero(n);
  Qc_nonideal.setZero(n);
  lambda_nonideal.setZero(m);
  Qc.setZero(n);
  qdd.setZero(n);
  dqdd.setZero(n);
  C_term.setZero(n);
  tmp_n.setZero(n);
  tmp_m.setZero(m);
  for (const auto& c : sys.constraints()) scratch.push_back(c.model().make_scratch(n));
  if (options.algorithm == Algorithm::kTextbook) {
    textbook = std::make_unique<TextbookDecomposition>(n, m);
    textbook->set_threshold(options.rank_threshold);
  }
}

Workspace::~Workspace() = default;
Workspace::Workspace(Workspace&&) noexcept = default;
Workspace& Workspace::operator=(Workspace&&) noexcept = default;

Eigen::Ref<const VectorXd> Workspace::lambda_of(const System& sys, Index k) const {
  return lambda.segment(sys.row_offset(k), sys.constraint(k).rows());
}

std::string describe_status(const System& sys, const Workspace& ws) {
  std::ostringstream s;
  s.precision(6);
  s << to_string(ws.status);
  if (ws.status == Status::kOk) return s.str();
  s << " at t = " << ws.failed_time;
  const std::string what = ws.failed_quantity;
  if (!what.empty()) s << " in " << what;
  const Index k = ws.failed_index;
  if ((what == "A" || what == "b") && k >= 0 && k < sys.constraint_count()) {
    s << " of constraint '" << sys.constraint(k).name() << "'";
  } else if (what == "C" && k >= 0 && k < sys.nonideal_count()) {
    s << " of non-ideal force '" << sys.nonideal_name(k) << "'";
  } else if ((what == "q" || what == "q_dot") && k >= 0 && k < sys.dofs()) {
    s << " (coordinate '" << sys.coordinate_names()[std::size_t(k)] << "')";
  }
  switch (ws.status) {
    case Status::kInconsistentConstraints:
      s << ": A q'' = b has no solution; residual |A q'' - b| = " << ws.residuals.constraint
        << " with rank(A) = " << ws.rank << " of " << ws.active_rows << " active rows";
      break;
    case Status::kMassNotPositiveDefinite:
      s << ": the Cholesky factorization of M failed (is every coordinate given inertia?)";
      break;
    case Status::kMassNotSymmetric:
      s << ": M differs from its transpose by more than the symmetry tolerance "
        << ws.options().symmetry_tolerance << " (relative)";
      break;
    default: break;
  }
  return s.str();
}

void throw_if_failed(const System& sys, const Workspace& ws) {
  if (ws.status != Status::kOk) throw SolveError(ws.status, "ukdyn: " + describe_status(sys, ws));
}

}  // namespace ukdyn

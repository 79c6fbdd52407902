// SPDX-License-Identifier: BSD-3-Clause
// Workspace: sizing every buffer once; describing a failed evaluation.
#include "ukdyn/dynamics/workspace.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "dynamics/engine.hpp"
#include "dynamics/internal.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/linalg/sparse.hpp"

namespace ukdyn {

namespace {

// Engine::kAuto's choice, by the measured cost of one evaluation (callgrind; docs/sparse.md,
// "Choice of engine"): the sparse engine for a block-diagonal M under Algorithm::kDefault with
// at most kAutoMaxDenseRows rows from constraints without columns() (each couples every body),
// when either n >= sparse_threshold (cheaper on every structure tried) or M has two or more
// blocks and m <= n (several bodies without more rows than coordinates: 0.6–0.8× the dense
// engine's instructions from two bodies on; with m > n the null-space basis of the redundant
// rows dominates and the dense engine stays). Cost O(constraints).
bool auto_picks_sparse(const System& sys, const SolverOptions& options) {
  if (options.algorithm != Algorithm::kDefault || !sys.mass_is_block_diagonal()) return false;
  // rows of constraints without columns() are dense rows of the sparse A: each couples every
  // body, so many of them make G dense and the sparse engine slower than the dense one
  Index dense_rows = 0;
  for (const auto& c : sys.constraints()) {
    if (c.model().columns().empty()) dense_rows += c.rows();
  }
  if (dense_rows > kAutoMaxDenseRows) return false;
  if (sys.coordinate_count() >= options.sparse_threshold) return true;
  return sys.mass_blocks().size() >= 2 && sys.constraint_rows() <= sys.coordinate_count();
}

}  // namespace

Workspace::Workspace(const System& sys, const SolverOptions& options)
    : options_(options),
      system_id_(sys.id()),
      n_(sys.coordinate_count()),
      m_(sys.constraint_rows()) {
  if (!(options.rank_threshold > 0.0 && options.rank_threshold < 1.0)) {
    throw std::invalid_argument(
        "ukdyn::Workspace: SolverOptions::rank_threshold must lie in "
        "(0, 1), got " +
        format_number(options.rank_threshold));
  }
  if (!(options.consistency_tolerance > 0.0)) {
    throw std::invalid_argument(
        "ukdyn::Workspace: SolverOptions::consistency_tolerance must be "
        "> 0, got " +
        format_number(options.consistency_tolerance));
  }
  if (!(options.symmetry_tolerance >= 0.0)) {
    throw std::invalid_argument(
        "ukdyn::Workspace: SolverOptions::symmetry_tolerance must be "
        ">= 0, got " +
        format_number(options.symmetry_tolerance));
  }
  if (!(options.sparse_rank_threshold > 0.0 && options.sparse_rank_threshold < 1.0)) {
    throw std::invalid_argument(
        "ukdyn::Workspace: SolverOptions::sparse_rank_threshold must lie "
        "in (0, 1), got " +
        format_number(options.sparse_rank_threshold));
  }
  if (options.sparse_threshold < 0) {
    throw std::invalid_argument(
        "ukdyn::Workspace: SolverOptions::sparse_threshold must be >= 0, "
        "got " +
        format_number(options.sparse_threshold));
  }
  // the engine (kAuto: auto_picks_sparse)
  bool use_sparse = false;
  switch (options.engine) {
    case Engine::kDense:
      break;
    case Engine::kSparse:
      if (!sys.mass_is_block_diagonal()) {
        throw std::invalid_argument(
            "ukdyn::Workspace: Engine::kSparse needs a block-diagonal mass matrix (give M with "
            "SystemBuilder::mass_block), got a system whose M is one dense matrix");
      }
      if (options.algorithm != Algorithm::kDefault) {
        throw std::invalid_argument(
            "ukdyn::Workspace: Engine::kSparse runs Algorithm::kDefault only, got the textbook "
            "algorithm (use Engine::kDense or kAuto with it)");
      }
      use_sparse = true;
      break;
    case Engine::kAuto:
      use_sparse = auto_picks_sparse(sys, options);
      break;
  }
  const Index n = n_, m = m_, K = sys.constraint_count();
  if (use_sparse) {
    sparse = std::make_unique<SparseDecomposition>(sys);
    sparse->set_threshold(options.sparse_rank_threshold);
    Index rows = 0, width = 0;
    for (const auto& c : sys.constraints()) {
      rows = std::max(rows, c.rows());
      const Index cols = Index(c.model().columns().size());
      width = std::max(width, cols == 0 ? n : cols);
    }
    A_rows.setZero(rows, width);
  } else {
    M.setZero(n, n);
    M_aux.setZero(n, n);
    A.setZero(m, n);
    // rows local to a block singular by construction (constraints with sorted columns()), when
    // the other blocks are constant
    const auto& blocks = sys.mass_blocks();
    const bool local = std::all_of(blocks.begin(), blocks.end(), [](const MassBlock& blk) {
      return blk.singular || blk.constant();
    });
    for (const MassBlock& blk : blocks) {
      if (!local) break;
      if (!blk.singular) continue;
      for (Index k = 0; k < K; ++k) {
        const auto& cols = sys.constraint(k).model().columns();
        if (cols.empty() || cols.front() < blk.offset || cols.back() >= blk.offset + blk.size) {
          continue;
        }
        for (Index r = 0; r < sys.constraint(k).rows(); ++r) {
          singular_local_rows.insert(singular_local_rows.end(),
                                     {sys.row_offset(k) + r, blk.offset, blk.size});
        }
      }
    }
  }
  Q.setZero(n);
  a.setZero(n);
  nonzero_cols.assign(std::size_t(n), 0);
  b.setZero(m);
  active.assign(std::size_t(K), 0);
  activity_override.assign(std::size_t(K), -1);
  nonideal_enabled.assign(std::size_t(sys.nonideal_count()), 1);
  slip_hint_held.assign(std::size_t(sys.nonideal_count()), 0);
  // Coulomb contacts: relative sliding velocities and their scratch (the contact-point path's
  // Jacobian rows, bias and kinematics buffers)
  Index contact_rows_max = 0, contact_width = 0, tangents_max = 0;
  contact_jacobian.clear();
  contact_scratch.clear();
  for (const auto& contact : sys.friction_contacts()) {
    contact_rows_max = std::max(contact_rows_max, sys.constraint(contact.normal_constraint).rows());
    contact_width = std::max(contact_width, contact.size());
    const ContactKinematics& kin = contact.kinematics;
    tangents_max = std::max(tangents_max, kin ? kin.tangents : Index(0));
    contact_jacobian.push_back(kin ? MatrixXd::Zero(1 + kin.tangents, Index(kin.columns.size()))
                                   : MatrixXd());
    contact_scratch.push_back(kin && kin.make_scratch ? kin.make_scratch(n) : nullptr);
  }
  contact_bias.setZero(tangents_max > 0 ? 1 + tangents_max : 0,
                       Index(sys.friction_contacts().size()));
  // (a slip hint on the contact-point path holds the d tangential components)
  slip_hint.setZero(std::max(n, tangents_max), sys.nonideal_count());
  sliding.setZero(contact_width, Index(sys.friction_contacts().size()));
  contact_rows.setZero(contact_rows_max, n);
  contact_b.setZero(contact_rows_max);
  contact_basis.setZero(contact_rows_max, contact_width);
  surface_u.setZero(contact_width);
  surface_u_dot.setZero(contact_width);
  for (const auto& c : sys.constraints()) stabilization.push_back(c.stabilization());
  phi.setZero(m);
  phi_dot.setZero(m);
  phi_scale.setConstant(m, 10.0);  // (the class of a model in SI units: set_run_scales)
  phi_dot_scale.setConstant(m, 10.0);
  zero_n.setZero(n);
  lambda_tmp.setZero(m);
  decomposition.resize(use_sparse ? 0 : n, use_sparse ? 0 : m);
  decomposition.set_threshold(options.rank_threshold);
  // a tree's M factorized along its branches (SystemBuilder::mass_tree; dense engine)
  if (!use_sparse) decomposition.set_mass_tree(sys.mass_tree());
  e.setZero(m);
  lambda.setZero(m);
  Qc_ideal.setZero(n);
  // (the sparse engine sizes them on first use when no non-ideal force needs them)
  if (!use_sparse || sys.nonideal_count() > 0) shares.setZero(n, K);
  if (sys.nonideal_count() > 0) {
    reactions.setZero(n, K);
    reactions_next.setZero(n, K);
    lambda_read.setZero(m);
    reaction_acceleration.resize(m, AndersonAcceleration::kDefaultDepth);
  }
  C.setZero(n);
  Qc_nonideal.setZero(n);
  lambda_nonideal.setZero(m);
  Qc.setZero(n);
  qdd.setZero(n);
  dqdd.setZero(n);
  C_term.setZero(n);
  tmp_n.setZero(n);
  tmp_m.setZero(m);
  callables = sys.make_scratch();
  for (const auto& c : sys.constraints())
    scratch.push_back(c.model().make_scratch_sharing(n, callables.get()));
  const detail::TextbookProvider* reference = nullptr;
  if (options.algorithm == Algorithm::kTextbook) {
    reference = detail::textbook_provider();
    if (reference == nullptr) {
      throw std::invalid_argument(
          "ukdyn::Workspace: Algorithm::kTextbook is in the reference library, which this "
          "program does not link: add ukdyn::reference to its target_link_libraries (the "
          "ukdyn command and the Python module include it)");
    }
    textbook.reset(reference->make(n, m, options.rank_threshold));
  }
  // the engine, once: each stage calls it (dynamics/engine.hpp)
  engine = use_sparse  ? &detail::sparse_engine()
           : reference ? reference->engine
                       : &detail::dense_engine();
}

void TextbookDeleter::operator()(TextbookDecomposition* p) const {
  if (p != nullptr) detail::textbook_provider()->destroy(p);
}

namespace detail {
namespace {
// set once, before main, by the reference library's static initializer; read afterwards
std::atomic<const TextbookProvider*> g_textbook_provider{nullptr};
}  // namespace
const TextbookProvider* textbook_provider() { return g_textbook_provider.load(); }
void register_textbook_provider(const TextbookProvider* provider) {
  g_textbook_provider.store(provider);
}

void throw_other_system(const Workspace& ws, const char* who) {
  if (ws.system_id() == 0) {
    throw std::invalid_argument(std::string(who) +
                                ": the workspace is empty (moved from: its buffers went to "
                                "another Workspace); make one with Workspace(sys), or move-assign "
                                "one to it");
  }
  throw std::invalid_argument(std::string(who) +
                              ": the workspace was made for another system (make one with "
                              "Workspace(sys))");
}

void throw_state_size(Index n, Index q_size, Index qd_size, const char* who) {
  const bool bad_q = q_size != n;
  throw std::invalid_argument(std::string(who) + ": " + (bad_q ? "q" : "q_dot") + " has " +
                              format_number(bad_q ? q_size : qd_size) +
                              " entries, expected n = " + format_number(n));
}
}  // namespace detail

Workspace::~Workspace() = default;
Workspace::Workspace(Workspace&&) noexcept = default;
Workspace& Workspace::operator=(Workspace&&) noexcept = default;

Eigen::Ref<const VectorXd> Workspace::lambda_of(const System& sys, Index k) const {
  return lambda.segment(sys.row_offset(k), sys.constraint(k).rows());
}

namespace {
// "; the constraints that cannot all hold: 'a', 'b'" — those with a row carrying the
// least-squares residual r = A q'' − b (|r_i| >= 1e-3 max |r|), or "" when r is unavailable
std::string inconsistent_constraints(const System& sys, const Workspace& ws) {
  const Index m = sys.constraint_rows();
  if (ws.qdd.size() != sys.coordinate_count() || ws.b.size() != m || m == 0) return "";
  VectorXd r(m);
  ws.engine->constraint_residual(ws, ws.qdd, r);
  const double r_max = r.cwiseAbs().maxCoeff();
  if (!(r_max > 0.0)) return "";
  std::string names;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    const auto rows = r.segment(sys.row_offset(k), sys.constraint(k).rows());
    if (rows.size() == 0 || rows.cwiseAbs().maxCoeff() < 1e-3 * r_max) continue;
    names += (names.empty() ? "'" : ", '") + sys.constraint(k).name() + "'";
  }
  return names.empty() ? "" : "; the constraints that cannot all hold: " + names;
}
}  // namespace

namespace {
// The coordinates that [M; A] leaves undetermined: the null space of M / s + Aᵀ diag(1/‖a_i‖²) A
// (s the largest diagonal of M), from the M and A of the failed evaluation; with the sparse
// engine only the failed block and the rows local to it (which are all it uses). Error path:
// allocates. Returns a list of quoted coordinate names.
std::string undetermined_coordinates(const System& sys, const Workspace& ws) {
  const Index n = sys.coordinate_count();
  MatrixXd M, A;
  Index o = 0, size = n;
  if (ws.sparse) {
    const SparseDecomposition& sp = *ws.sparse;
    const Index b = ws.failed_index;
    if (b < 0 || b >= sp.block_count()) return "";
    o = sp.block_offset(b);
    size = sp.block_size(b);
    M = sp.mass_block(b);
    const auto As = sp.matrix_A();
    std::vector<Index> local;
    for (Index i = 0; i < As.rows(); ++i) {
      bool inside = true, any = false;
      for (decltype(As)::InnerIterator it(As, i); it; ++it) {
        if (it.value() == 0.0) continue;
        any = true;
        inside = inside && it.col() >= o && it.col() < o + size;
      }
      if (any && inside) local.push_back(i);
    }
    A.setZero(Index(local.size()), size);
    for (std::size_t r = 0; r < local.size(); ++r) {
      for (decltype(As)::InnerIterator it(As, local[r]); it; ++it) {
        if (it.value() != 0.0) A(Index(r), it.col() - o) = it.value();
      }
    }
  } else {
    M = ws.M.selfadjointView<Eigen::Lower>();
    A = ws.A;
  }
  double s = M.diagonal().maxCoeff();
  if (!(s > 0.0)) s = 1.0;
  MatrixXd N = M / s;
  for (Index i = 0; i < A.rows(); ++i) {
    const double norm2 = A.row(i).squaredNorm();
    if (norm2 > 0.0) N += A.row(i).transpose() * A.row(i) / norm2;
  }
  Eigen::SelfAdjointEigenSolver<MatrixXd> eig(N);
  const VectorXd& ev = eig.eigenvalues();
  const double top = std::max(ev.cwiseAbs().maxCoeff(), 1.0);
  std::vector<bool> named(std::size_t(size), false);
  for (Index k = 0; k < size; ++k) {
    if (ev[k] > 1e-9 * top) continue;
    const VectorXd v = eig.eigenvectors().col(k);
    const double vmax = v.cwiseAbs().maxCoeff();
    for (Index i = 0; i < size; ++i) {
      if (std::abs(v[i]) > 0.1 * vmax) named[std::size_t(i)] = true;
    }
  }
  std::string names;
  for (Index i = 0; i < size; ++i) {
    if (!named[std::size_t(i)]) continue;
    names += (names.empty() ? "'" : ", '") + sys.coordinate_names()[std::size_t(o + i)] + "'";
  }
  return names;
}
}  // namespace

std::string describe_status(const System& sys, const Workspace& ws) {
  std::ostringstream s;
  s.precision(6);
  s << to_string(ws.status);
  if (ws.status == Status::kOk) return s.str();
  s << " at t = " << ws.failed_time;
  const std::string what = ws.failed_quantity;
  if (!what.empty()) s << " in " << what;
  const Index k = ws.failed_index;
  if (ws.status == Status::kMotionUndetermined) {
    // (failed_index is the sparse engine's block, reported below)
  } else if ((what == "A" || what == "b" || what == "phi" || what == "phi_dot") && k >= 0 &&
             k < sys.constraint_count()) {
    s << " of constraint '" << sys.constraint(k).name() << "'";
  } else if (what == "C" && k >= 0 && k < sys.nonideal_count()) {
    s << " of non-ideal force '" << sys.nonideal_name(k) << "'";
  } else if ((what == "q" || what == "q_dot") && k >= 0 && k < sys.coordinate_count()) {
    s << " (coordinate '" << sys.coordinate_names()[std::size_t(k)] << "')";
  }
  switch (ws.status) {
    case Status::kInconsistentConstraints:
      s << ": A q'' = b has no solution; residual |A q'' - b| = " << ws.residuals.constraint
        << " with rank(A) = " << ws.rank << " of " << ws.active_rows << " active rows";
      s << inconsistent_constraints(sys, ws);
      break;
    case Status::kMassNotPositiveDefinite:
      s << ": M is not positive semi-definite (it has a negative eigenvalue; a singular M is "
           "accepted when the constraints determine the coordinates it gives no inertia)";
      break;
    case Status::kMotionUndetermined: {
      const std::string names = undetermined_coordinates(sys, ws);
      s << ": M is singular and [M; A] does not have full column rank, so the accelerations of "
        << (names.empty() ? std::string("some coordinates") : "the coordinates " + names)
        << " are not determined (give them inertia, or constraints that fix them)";
      if (ws.sparse) {
        s << "; the sparse engine completes a singular block of M only with constraints on that "
             "block alone (use Engine::kDense for constraints that tie it to other bodies)";
      }
      break;
    }
    case Status::kMassNotSymmetric:
      s << ": M differs from its transpose by more than the symmetry tolerance "
        << ws.options().symmetry_tolerance << " (relative)";
      break;
    default:
      break;
  }
  return s.str();
}

void throw_if_failed(const System& sys, const Workspace& ws) {
  if (ws.status != Status::kOk) throw SolveError(ws.status, "ukdyn: " + describe_status(sys, ws));
}

}  // namespace ukdyn

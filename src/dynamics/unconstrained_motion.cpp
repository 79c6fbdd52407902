// Stage 1: the unconstrained system. M(q,t), Q(q,q',t), M = L Lᵀ, a = M⁻¹ Q (eqs. 1, 2).
// A singular (positive semi-definite) M is factorized after stage 2 as the auxiliary
// M_A = M + Aᵀ G A, with Q_A = Q + Aᵀ G b (complete_singular_mass; docs/singular-mass.md).
#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

#include "dynamics/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/linalg/sparse.hpp"

namespace ukdyn {

namespace {
// max |M_ij − M_ji| over i < j
double asymmetry(const MatrixXd& M) {
  double worst = 0.0;
  for (Index j = 0; j < M.cols(); ++j) {
    for (Index i = 0; i < j; ++i) worst = std::max(worst, std::abs(M(i, j) - M(j, i)));
  }
  return worst;
}
}  // namespace

namespace detail {
namespace {
// the sparse engine: the blocks M_bb(q,t) that are not constant, the same checks as below on
// the blocks, and M_bb = L_b L_bᵀ block by block (singular blocks: checked, factorized later)
Status evaluate_mass_blocks(const System& sys, Workspace& ws, const VectorXd& q, double t) {
  SparseDecomposition& sp = *ws.sparse;
  const auto& blocks = sys.mass_blocks();
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    if (!blocks[b].constant()) blocks[b].fn(q, t, sp.mass_block(Index(b)));
  }
  if (!sp.mass_finite()) return detail::fail(ws, Status::kNonFiniteInput, "M", -1, t);
  if (sp.mass_asymmetry() > ws.options().symmetry_tolerance * sp.mass_max_abs()) {
    return detail::fail(ws, Status::kMassNotSymmetric, "M", -1, t);
  }
  if (sp.compute_mass().info() != Eigen::Success) {
    return detail::fail(ws, Status::kMassNotPositiveDefinite, "M", -1, t);
  }
  return Status::kOk;
}

// Whether the factor just computed is that of a regular M: Cholesky succeeded and its pivots
// L_kk² lie within kSingularPivotRatio of each other (else M is treated as singular).
bool regular_factor(const Workspace& ws, Eigen::ComputationInfo info) {
  if (info != Eigen::Success) return false;
  if (ws.textbook) return true;
  const auto d = ws.decomposition.matrix_llt().diagonal();
  const double lo = d.cwiseAbs().minCoeff(), hi = d.cwiseAbs().maxCoeff();
  return lo * lo >= SparseDecomposition::kSingularPivotRatio * hi * hi;
}
// Whether M + shift I is positive definite (M positive semi-definite to within shift), block by
// block when the system gives M as diagonal blocks (O(Σ size³) instead of O(n³)); uses the lower
// triangle of ws.M_aux as scratch. Once M was found singular, the constant blocks and those
// singular by construction were checked then and are skipped.
bool positive_semidefinite(const System& sys, Workspace& ws, double shift) {
  using Llt = Eigen::internal::llt_inplace<double, Eigen::Lower>;
  if (sys.mass_is_block_diagonal()) {
    for (const MassBlock& b : sys.mass_blocks()) {
      if (ws.mass_singular && (b.constant() || b.singular)) continue;
      auto S = ws.M_aux.topLeftCorner(b.size, b.size);
      S.triangularView<Eigen::Lower>() = ws.M.block(b.offset, b.offset, b.size, b.size);
      S.diagonal().array() += shift;
      if (Llt::unblocked(S) != -1) return false;
    }
    return true;
  }
  ws.M_aux.triangularView<Eigen::Lower>() = ws.M;
  ws.M_aux.diagonal().array() += shift;
  return Llt::blocked(ws.M_aux) == -1;
}

// M_A += g a aᵀ on one diagonal block (lower triangle; Mo its first entry, column-major with
// leading dimension ld), g = s / ‖a‖², a = the block's part of a row of A (entries a[k inc]);
// Qo (when not null) += g b_i a. S > 0 fixes the block size at compile time (a quaternion's 4).
template <Index S>
void add_local_row(double* Mo, Index ld, const double* a, Index inc, Index size, double s,
                   double b_i, double* Qo) {
  const Index n = S > 0 ? S : size;
  double norm2 = 0.0;
  for (Index k = 0; k < n; ++k) norm2 += a[k * inc] * a[k * inc];
  if (!(norm2 > 0.0)) return;  // an inactive row
  const double g = s / norm2;
  for (Index j = 0; j < n; ++j) {
    const double f = g * a[j * inc];
    for (Index k = j; k < n; ++k) Mo[j * ld + k] += f * a[k * inc];
    if (Qo) Qo[j] += f * b_i;
  }
}
}  // namespace

double kinetic_energy(const Workspace& ws, const VectorXd& qd) {
  if (ws.sparse) return 0.5 * ws.sparse->mass_norm_squared(qd);
  return 0.5 * qd.dot(ws.M * qd);
}

Status evaluate_mass(const System& sys, Workspace& ws, const VectorXd& q, double t) {
  if (ws.sparse) {
    // M(q,t) block by block; constant blocks evaluated and factorized once
    if (!(sys.mass_is_constant() && ws.mass_factorized)) {
      ws.mass_factorized = false;
      if (const Status s = evaluate_mass_blocks(sys, ws, q, t); s != Status::kOk) return s;
      ws.mass_factorized = true;
    }
    ws.mass_singular = ws.sparse->mass_singular();
    return Status::kOk;
  }
  // M(q,t) and M = L Lᵀ; a constant M is evaluated and factorized once
  if (!(sys.mass_is_constant() && ws.mass_factorized)) {
    ws.mass_factorized = false;
    sys.mass_matrix(q, t, ws.callables.get(), ws.M);
    if (!ws.M.allFinite()) return detail::fail(ws, Status::kNonFiniteInput, "M", -1, t);
    const double scale = ws.M.cwiseAbs().maxCoeff();
    if (asymmetry(ws.M) > ws.options().symmetry_tolerance * scale) {
      return detail::fail(ws, Status::kMassNotSymmetric, "M", -1, t);
    }
    if (!ws.mass_singular) {
      const auto info =
          detail::with_decomposition(ws, [&](auto& d) { return d.compute_mass(ws.M).info(); });
      if (regular_factor(ws, info)) {
        ws.mass_factorized = true;
        return Status::kOk;
      }
    }
    // singular: accepted when positive semi-definite, M + 1e-10 max|M| I positive definite;
    // factorized with the constraints (complete_singular_mass). From now on this workspace
    // takes the singular path.
    if (scale > 0.0 && !positive_semidefinite(sys, ws, 1e-10 * scale)) {
      return detail::fail(ws, Status::kMassNotPositiveDefinite, "M", -1, t);
    }
    ws.mass_singular = true;
    ws.mass_factorized = true;
  }
  return Status::kOk;
}

Status complete_singular_mass(Workspace& ws, double t, bool forces, bool regularize) {
  if (ws.sparse) {
    SparseDecomposition& sp = *ws.sparse;
    // a projection's metric only needs to be positive definite: M_A + 1e-8 s I where the
    // projection's rows leave M_A singular
    if (sp.compute_augmented_mass().info() != Eigen::Success &&
        !(regularize && sp.compute_augmented_mass(1e-8).info() == Eigen::Success)) {
      return detail::fail(ws, Status::kMotionUndetermined, "M", sp.undetermined_block(), t);
    }
    // a = M_A⁻¹ (Q + Aᵀ G b)
    if (forces) {
      ws.a = ws.Q;
      sp.augment_forces(ws.b, ws.a);
      sp.solve_mass_in_place(ws.a);
    }
    return Status::kOk;
  }
  // M completed block by block with the rows local to its blocks singular by construction (a
  // quaternion's unit norm; the other blocks are constant), while they suffice:
  // M_A,bb = M_bb + Σ_local g_i a_i a_iᵀ, g_i = s_b / ‖a_i‖², s_b = max diag M_bb (as the sparse
  // engine), O(Σ size²) instead of O(Σ nnz(a_i)²)
  if (!ws.singular_local_rows.empty() && ws.singular_completion != 2 && !ws.textbook) {
    const Index n = ws.coordinate_count(), m = ws.rows();
    std::copy(ws.M.data(), ws.M.data() + n * n, ws.M_aux.data());  // (one memcpy)
    if (forces) ws.tmp_n = ws.Q;
    const auto& rows = ws.singular_local_rows;
    for (std::size_t r = 0; r < rows.size(); r += 3) {
      const Index i = rows[r], o = rows[r + 1], size = rows[r + 2];
      double* Mo = ws.M_aux.data() + o * n + o;
      const double* a = ws.A.data() + o * m + i;  // row i of A from column o
      double* Qo = forces ? ws.tmp_n.data() + o : nullptr;
      const double* Mb = ws.M.data() + o * n + o;
      double sb = Mb[0];
      for (Index k = 1; k < size; ++k) sb = std::max(sb, Mb[k * n + k]);
      if (!(sb > 0.0)) {  // a zero block: the largest diagonal of M (1 if M = 0)
        sb = ws.M.diagonal().maxCoeff();
        if (!(sb > 0.0)) sb = 1.0;
      }
      if (size == 4) {
        add_local_row<4>(Mo, n, a, m, size, sb, ws.b[i], Qo);
      } else {
        add_local_row<0>(Mo, n, a, m, size, sb, ws.b[i], Qo);
      }
    }
    // factorized, with pivots L_kk² within kSingularPivotRatio of each other: on all of M_A the
    // first time, then on each completed block
    if (ws.decomposition.compute_mass(ws.M_aux).info() == Eigen::Success) {
      const auto& L = ws.decomposition.matrix_llt();
      const auto regular = [&](Index o, Index size) {
        double lo = L(o, o), hi = lo;  // L_kk > 0
        for (Index k = o + 1; k < o + size; ++k) {
          lo = std::min(lo, L(k, k));
          hi = std::max(hi, L(k, k));
        }
        return lo * lo >= SparseDecomposition::kSingularPivotRatio * hi * hi;
      };
      bool ok = ws.singular_completion == 1 || regular(0, n);
      for (std::size_t r = 0; ok && ws.singular_completion == 1 && r < rows.size(); r += 3) {
        ok = regular(rows[r + 1], rows[r + 2]);
      }
      if (ok) {
        if (!regularize) ws.singular_completion = 1;
        if (forces) ws.decomposition.solve_mass(ws.tmp_n, ws.a);
        return Status::kOk;
      }
    }
    // other blocks are singular too (or a projection left out the local rows): every row, from
    // now on unless this is a projection
    if (!regularize) ws.singular_completion = 2;
  }
  double s = ws.M.diagonal().maxCoeff();
  if (!(s > 0.0)) s = 1.0;
  // M_A = M + Σ_i g_i a_i a_iᵀ (lower triangle), g_i = s / ‖a_i‖², s = max diag M; only the
  // non-zero entries of each row of A take part
  const Index n = ws.coordinate_count();
  ws.M_aux.triangularView<Eigen::Lower>() = ws.M;
  if (forces) ws.tmp_n = ws.Q;
  for (Index i = 0; i < ws.A.rows(); ++i) {
    Index nz = 0;
    double norm2 = 0.0;
    for (Index j = 0; j < n; ++j) {
      const double v = ws.A(i, j);
      if (v != 0.0) {
        ws.nonzero_cols[std::size_t(nz++)] = j;
        norm2 += v * v;
      }
    }
    if (nz == 0) continue;  // an inactive row
    const double g = s / norm2;
    for (Index p = 0; p < nz; ++p) {
      const Index j = ws.nonzero_cols[std::size_t(p)];
      const double f = g * ws.A(i, j);
      for (Index r = p; r < nz; ++r) {
        const Index k = ws.nonzero_cols[std::size_t(r)];
        ws.M_aux(std::max(j, k), std::min(j, k)) += f * ws.A(i, k);
      }
      if (forces) ws.tmp_n[j] += f * ws.b[i];
    }
  }
  auto info =
      detail::with_decomposition(ws, [&](auto& d) { return d.compute_mass(ws.M_aux).info(); });
  if (info != Eigen::Success && regularize) {
    // a projection's metric only needs to be positive definite
    ws.M_aux.diagonal().array() += 1e-8 * s;
    info = detail::with_decomposition(ws, [&](auto& d) { return d.compute_mass(ws.M_aux).info(); });
  }
  if (info != Eigen::Success) return detail::fail(ws, Status::kMotionUndetermined, "M", -1, t);
  if (forces) detail::with_decomposition(ws, [&](auto& d) { d.solve_mass(ws.tmp_n, ws.a); });
  return Status::kOk;
}
}  // namespace detail

Status evaluate_unconstrained(const System& sys, Workspace& ws, const VectorXd& q,
                              const VectorXd& qd, double t) {
  detail::require_same_system(sys, ws, "ukdyn::evaluate_unconstrained");
  detail::require_state_size(sys, q, &qd, "ukdyn::evaluate_unconstrained");
  if (const Status s = detail::evaluate_mass(sys, ws, q, t); s != Status::kOk) return s;
  // Q(q,q',t)
  sys.forces(q, qd, t, ws.callables.get(), ws.Q);
  if (!ws.Q.allFinite()) return detail::fail(ws, Status::kNonFiniteInput, "Q", -1, t);
  // a = M⁻¹ Q; for a singular M, a = M_A⁻¹ Q_A once A is known (assemble_constraints)
  if (ws.mass_singular) return Status::kOk;
  if (ws.sparse) {
    ws.sparse->solve_mass(ws.Q, ws.a);
  } else {
    detail::with_decomposition(ws, [&](auto& d) { d.solve_mass(ws.Q, ws.a); });
  }
  return Status::kOk;
}

}  // namespace ukdyn

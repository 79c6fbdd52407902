// SPDX-License-Identifier: BSD-3-Clause
// The dense engine (not installed): dense M (n × n) and A (m × n) in the workspace, on a
// decomposition D with FundamentalDecomposition's interface (compute_mass, compute_constraints,
// solve_mass, solve_ideal, project_nonideal, rank). Instantiated with FundamentalDecomposition
// (dynamics/dense_engine.cpp, the default) and TextbookDecomposition
// (reference/textbook_engine.cpp). Costs: M = L Lᵀ O(n³/3), W = A L⁻ᵀ and its complete
// orthogonal decomposition O(m n² + m² n), solves O(n² + m n); products O(m n).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include <Eigen/Cholesky>

#include "dynamics/engine.hpp"
#include "dynamics/internal.hpp"
#include "linalg/safe_norm.hpp"
#include "ukdyn/linalg/sparse.hpp"

namespace ukdyn::detail {

/// The decomposition a dense engine on D keeps in the workspace (specialized where the engine
/// is instantiated).
template <class D>
D& decomposition_of(Workspace& ws);

/// max |M_ij − M_ji| over i < j.
double asymmetry(const MatrixXd& M);

/// The checks of an evaluated M in one pass over its pairs (M_ij, M_ji): false unless every
/// entry is finite; else scale = max |M_ij| and asym = max over i < j of |M_ij − M_ji|, the
/// values of M.cwiseAbs().maxCoeff() and asymmetry(M). O(n²), one read of each entry.
bool check_mass_entries(const MatrixXd& M, double& scale, double& asym);

/// check_mass_entries for an M declared sparse along the tree `parent` (SystemBuilder::mass_tree:
/// M_ij = 0 unless one of i, j is an ancestor of the other) over the diagonal and the pairs (k,
/// ancestor a) only, the entries the tree's factorization reads (scale: max |M_kk|, |M_ka|; an
/// asymmetry of order 1e308 overflows and reads as non-finite). Cost O(n + Σ_k d_k), d_k the
/// number of ancestors of k, instead of O(n²).
bool check_mass_entries_tree(const MatrixXd& M, const std::vector<Index>& parent, double& scale,
                             double& asym);

/// Whether M + shift I is positive definite (M positive semi-definite to within shift), block
/// by block when the system gives M as diagonal blocks (O(Σ size³) instead of O(n³)); uses the
/// lower triangle of ws.M_aux as scratch. Once M was found singular, the constant blocks and
/// those singular by construction were checked then and are skipped.
bool positive_semidefinite(const System& sys, Workspace& ws, double shift);

/// M completed block by block with the rows local to its blocks singular by construction (a
/// quaternion's unit norm, the other blocks constant): true when that made M_A regular (then
/// factorized in ws.decomposition, and with `forces` ws.a solved). Dense engine on
/// FundamentalDecomposition only (dynamics/dense_engine.cpp).
bool complete_singular_mass_locally(Workspace& ws, bool forces, bool regularize);

/// M_A = M + Σ_i g_i a_i a_iᵀ (lower triangle of ws.M_aux), g_i = s / ‖a_i‖², s = max diag M
/// (1 when M = 0), over the non-zero entries of each row of A; with `forces`
/// ws.tmp_n = Q + Aᵀ G b. Returns s. O(Σ_i nnz(a_i)²).
double assemble_auxiliary_mass(Workspace& ws, bool forces);

template <class D>
class DenseEngine final : public EngineOps {
 public:
  Status evaluate_mass(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                       double t) const override {
    // M(q,t) and M = L Lᵀ; a constant M is evaluated and factorized once
    if (sys.mass_is_constant() && ws.mass_factorized) return Status::kOk;
    ws.mass_factorized = false;
    sys.mass_matrix(q, t, ws.callables.get(), ws.M);
    double scale = 0.0, asym = 0.0;
    bool finite = false;
    if constexpr (std::is_same_v<D, FundamentalDecomposition>) {
      const auto& tree = ws.decomposition.mass_tree();
      finite = tree.empty() ? check_mass_entries(ws.M, scale, asym)
                            : check_mass_entries_tree(ws.M, tree, scale, asym);
    } else {
      finite = check_mass_entries(ws.M, scale, asym);
    }
    if (!finite) {
      return fail(ws, Status::kNonFiniteInput, "M", -1, t);
    }
    if (asym > ws.options().symmetry_tolerance * scale) {
      return fail(ws, Status::kMassNotSymmetric, "M", -1, t);
    }
    if (!ws.mass_singular &&
        regular_factor(ws, decomposition_of<D>(ws).compute_mass(ws.M).info())) {
      ws.mass_factorized = true;
      return Status::kOk;
    }
    // singular: accepted when positive semi-definite, M + 1e-10 max|M| I positive definite;
    // factorized with the constraints (complete_singular_mass). From now on this workspace
    // takes the singular path.
    if (scale > 0.0 && !positive_semidefinite(sys, ws, 1e-10 * scale)) {
      return fail(ws, Status::kMassNotPositiveDefinite, "M", -1, t);
    }
    // (the completions M + Aᵀ G A leave a tree's pattern: dense Cholesky from now on)
    if constexpr (std::is_same_v<D, FundamentalDecomposition>) {
      ws.decomposition.set_mass_tree({});
    }
    ws.mass_singular = true;
    ws.mass_factorized = true;
    return Status::kOk;
  }

  void solve_mass(Workspace& ws) const override { decomposition_of<D>(ws).solve_mass(ws.Q, ws.a); }

  Status complete_singular_mass(Workspace& ws, double t, bool forces,
                                bool regularize) const override {
    if constexpr (std::is_same_v<D, FundamentalDecomposition>) {
      if (complete_singular_mass_locally(ws, forces, regularize)) return Status::kOk;
    }
    const double s = assemble_auxiliary_mass(ws, forces);
    D& d = decomposition_of<D>(ws);
    auto info = d.compute_mass(ws.M_aux).info();
    if (info != Eigen::Success && regularize) {
      // a projection's metric only needs to be positive definite
      ws.M_aux.diagonal().array() += 1e-8 * s;
      info = d.compute_mass(ws.M_aux).info();
    }
    if (info != Eigen::Success) return fail(ws, Status::kMotionUndetermined, "M", -1, t);
    if (forces) d.solve_mass(ws.tmp_n, ws.a);
    return Status::kOk;
  }

  double kinetic_energy(const Workspace& ws, const VectorXd& qd) const override {
    return 0.5 * qd.dot(ws.M * qd);
  }

  Status write_constraint_rows(const System& sys, Workspace& ws, Index k,
                               const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double t,
                               bool check) const override {
    const Constraint& c = sys.constraint(k);
    auto Ak = ws.A.middleRows(sys.row_offset(k), c.rows());
    auto bk = ws.b.segment(sys.row_offset(k), c.rows());
    c.model().acceleration_form(q, qd, t, ws.scratch[std::size_t(k)].get(), Ak, bk);
    if (check && !all_finite(Ak)) return fail(ws, Status::kNonFiniteInput, "A", k, t);
    return Status::kOk;
  }
  void zero_constraint_rows(const System& sys, Workspace& ws, Index k) const override {
    ws.A.middleRows(sys.row_offset(k), sys.constraint(k).rows()).setZero();
  }
  void copy_constraint_rows(const System& sys, const Workspace& ws, Index k,
                            Eigen::Ref<MatrixXd> out) const override {
    out = ws.A.middleRows(sys.row_offset(k), sys.constraint(k).rows());
  }

  void multiply_A(const Workspace& ws, const Eigen::Ref<const VectorXd>& x,
                  Eigen::Ref<VectorXd> out) const override {
    out.noalias() = ws.A * x;
  }
  void error_signal(Workspace& ws) const override {
    ws.e = ws.b;
    ws.e.noalias() -= ws.A * ws.a;
  }
  void constraint_residual(const Workspace& ws, const VectorXd& x, VectorXd& out) const override {
    out = -ws.b;
    out.noalias() += ws.A * x;
  }
  void multiply_At(const Workspace& ws, const VectorXd& y, VectorXd& out) const override {
    out.noalias() = ws.A.transpose() * y;
  }
  void multiply_mass(const Workspace& ws, const VectorXd& x, VectorXd& out) const override {
    out.noalias() = ws.M * x;
  }
  double norm_A(const Workspace& ws) const override { return safe_norm(ws.A.data(), ws.A.size()); }
  void constraint_share(const System& sys, const Workspace& ws, Index k, const VectorXd& lambda,
                        Eigen::Ref<VectorXd> out) const override {
    const Index r0 = sys.row_offset(k), rows = sys.constraint(k).rows();
    out.noalias() = ws.A.middleRows(r0, rows).transpose() * lambda.segment(r0, rows);
  }
  double constraint_power(const System& sys, const Workspace& ws, Index k,
                          const Eigen::Ref<const VectorXd>& qd, VectorXd&) const override {
    // q'ᵀ A_kᵀ lambda_k = Σ_rows lambda_r (A_r q')
    const Index r0 = sys.row_offset(k), rows = sys.constraint(k).rows();
    double p = 0.0;
    for (Index r = r0; r < r0 + rows; ++r) p += ws.lambda[r] * ws.A.row(r).dot(qd);
    return p;
  }

  void decompose_constraints(Workspace& ws) const override {
    decomposition_of<D>(ws).compute_constraints(ws.A);
  }
  Index rank(const Workspace& ws) const override {
    return decomposition_of<D>(const_cast<Workspace&>(ws)).rank();
  }
  double rank_margin(const Workspace& ws) const override {
    if constexpr (std::is_same_v<D, FundamentalDecomposition>) {
      const FundamentalDecomposition& d = ws.decomposition;
      return d.rank() == 0 ? 1.0 : d.min_pivot() / d.max_pivot();
    } else {
      return std::numeric_limits<double>::quiet_NaN();
    }
  }
  void solve_ideal(Workspace& ws, const VectorXd& e, VectorXd& dq, VectorXd& Qc,
                   VectorXd& lambda) const override {
    decomposition_of<D>(ws).solve_ideal(e, dq, Qc, lambda);
  }
  void project_nonideal(Workspace& ws) const override {
    decomposition_of<D>(ws).project_nonideal(ws.C, ws.dqdd, ws.Qc_nonideal, ws.lambda_nonideal);
  }

 private:
  // Whether the factor just computed is that of a regular M: Cholesky succeeded and every pivot
  // is regular (SparseDecomposition::pivot_is_regular; else M is treated as singular).
  static bool regular_factor(const Workspace& ws, Eigen::ComputationInfo info) {
    if (info != Eigen::Success) return false;
    if constexpr (std::is_same_v<D, FundamentalDecomposition>) {
      const auto d = ws.decomposition.matrix_llt().diagonal();
      for (Index k = 0; k < d.size(); ++k) {
        if (!SparseDecomposition::pivot_is_regular(d[k] * d[k], ws.M(k, k))) return false;
      }
      return true;
    } else {
      return true;
    }
  }
};

}  // namespace ukdyn::detail

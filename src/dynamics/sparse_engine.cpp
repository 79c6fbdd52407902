// SPDX-License-Identifier: BSD-3-Clause
// The sparse engine: block-diagonal M, sparse A in a fixed pattern, rank-revealing sparse LDLᵀ of
// G = W Wᵀ (SparseDecomposition, linalg/sparse.hpp; docs/sparse.md). M and A of the workspace
// stay empty; their values live in ws.sparse. Costs O(bodies) per evaluation for chains and trees
// with loop closures.
#include "dynamics/engine.hpp"
#include "dynamics/internal.hpp"
#include "ukdyn/linalg/sparse.hpp"

namespace ukdyn::detail {

namespace {

class SparseEngine final : public EngineOps {
 public:
  Status evaluate_mass(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                       double t) const override {
    SparseDecomposition& sp = *ws.sparse;
    // M(q,t) block by block; constant blocks evaluated and factorized once
    if (!(sys.mass_is_constant() && ws.mass_factorized)) {
      ws.mass_factorized = false;
      const auto& blocks = sys.mass_blocks();
      for (std::size_t b = 0; b < blocks.size(); ++b) {
        if (!blocks[b].constant()) blocks[b].fn(q, t, sp.mass_block(Index(b)));
      }
      // the same checks as the dense engine's, on the blocks; M_bb = L_b L_bᵀ block by block
      // (singular blocks: checked, factorized later)
      if (!sp.mass_finite()) return fail(ws, Status::kNonFiniteInput, "M", -1, t);
      if (sp.mass_asymmetry() > ws.options().symmetry_tolerance * sp.mass_max_abs()) {
        return fail(ws, Status::kMassNotSymmetric, "M", -1, t);
      }
      if (sp.compute_mass().info() != Eigen::Success) {
        return fail(ws, Status::kMassNotPositiveDefinite, "M", -1, t);
      }
      ws.mass_factorized = true;
    }
    ws.mass_singular = sp.mass_singular();
    return Status::kOk;
  }
  void solve_mass(Workspace& ws) const override { ws.sparse->solve_mass(ws.Q, ws.a); }
  Status complete_singular_mass(Workspace& ws, double t, bool forces,
                                bool regularize) const override {
    SparseDecomposition& sp = *ws.sparse;
    // a projection's metric only needs to be positive definite: M_A + 1e-8 s I where the
    // projection's rows leave M_A singular
    if (sp.compute_augmented_mass().info() != Eigen::Success &&
        !(regularize && sp.compute_augmented_mass(1e-8).info() == Eigen::Success)) {
      return fail(ws, Status::kMotionUndetermined, "M", sp.undetermined_block(), t);
    }
    // a = M_A⁻¹ (Q + Aᵀ G b)
    if (forces) {
      ws.a = ws.Q;
      sp.augment_forces(ws.b, ws.a);
      sp.solve_mass_in_place(ws.a);
    }
    return Status::kOk;
  }
  double kinetic_energy(const Workspace& ws, const VectorXd& qd) const override {
    return 0.5 * ws.sparse->mass_norm_squared(qd);
  }

  Status write_constraint_rows(const System& sys, Workspace& ws, Index k,
                               const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double t,
                               bool check) const override {
    // the local form (rows × columns) or the dense rows (rows × n), then the pattern
    const Constraint& c = sys.constraint(k);
    auto bk = ws.b.segment(sys.row_offset(k), c.rows());
    const bool local = ws.sparse->constraint_is_local(k);
    const Index width = local ? Index(c.model().columns().size()) : sys.coordinate_count();
    auto Ak = ws.A_rows.topLeftCorner(c.rows(), width);
    if (local) {
      c.model().acceleration_form_local(q, qd, t, ws.scratch[std::size_t(k)].get(), Ak, bk);
    } else {
      c.model().acceleration_form(q, qd, t, ws.scratch[std::size_t(k)].get(), Ak, bk);
    }
    ws.sparse->set_constraint_rows(k, Ak);
    if (check && !all_finite(Ak)) return fail(ws, Status::kNonFiniteInput, "A", k, t);
    return Status::kOk;
  }
  void zero_constraint_rows(const System&, Workspace& ws, Index k) const override {
    ws.sparse->zero_constraint_rows(k);
  }
  void copy_constraint_rows(const System&, const Workspace& ws, Index k,
                            Eigen::Ref<MatrixXd> out) const override {
    ws.sparse->constraint_rows_dense(k, out);
  }

  void multiply_A(const Workspace& ws, const Eigen::Ref<const VectorXd>& x,
                  Eigen::Ref<VectorXd> out) const override {
    ws.sparse->multiply_A(x, out);
  }
  void error_signal(Workspace& ws) const override {
    ws.sparse->multiply_A(ws.a, ws.e);
    ws.e = ws.b - ws.e;
  }
  void constraint_residual(const Workspace& ws, const VectorXd& x, VectorXd& out) const override {
    ws.sparse->multiply_A(x, out);
    out -= ws.b;
  }
  void multiply_At(const Workspace& ws, const VectorXd& y, VectorXd& out) const override {
    ws.sparse->multiply_At(y, out);
  }
  void multiply_mass(const Workspace& ws, const VectorXd& x, VectorXd& out) const override {
    ws.sparse->multiply_mass(x, out);
  }
  double norm_A(const Workspace& ws) const override { return ws.sparse->norm_A(); }
  void constraint_share(const System&, const Workspace& ws, Index k, const VectorXd& lambda,
                        Eigen::Ref<VectorXd> out) const override {
    // (the sparse engine writes constraint k's columns only)
    out.setZero();
    ws.sparse->share(k, lambda, out);
  }
  double constraint_power(const System& sys, const Workspace& ws, Index k,
                          const Eigen::Ref<const VectorXd>& qd, VectorXd& scratch) const override {
    constraint_share(sys, ws, k, ws.lambda, scratch);  // share_k = A_kᵀ lambda_k
    return qd.dot(scratch);
  }

  void decompose_constraints(Workspace& ws) const override { ws.sparse->compute_constraints(); }
  Index rank(const Workspace& ws) const override { return ws.sparse->rank(); }
  double rank_margin(const Workspace& ws) const override { return ws.sparse->rank_margin(); }
  void solve_ideal(Workspace& ws, const VectorXd& e, VectorXd& dq, VectorXd& Qc,
                   VectorXd& lambda) const override {
    ws.sparse->solve_ideal(e, dq, Qc, lambda);
  }
  void project_nonideal(Workspace& ws) const override {
    ws.sparse->project_nonideal(ws.C, ws.dqdd, ws.Qc_nonideal, ws.lambda_nonideal);
  }
};

}  // namespace

const EngineOps& sparse_engine() {
  static const SparseEngine engine;
  return engine;
}

}  // namespace ukdyn::detail

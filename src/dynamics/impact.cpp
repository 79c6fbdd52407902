// SPDX-License-Identifier: BSD-3-Clause
// ContactDynamics: the unilateral contacts at an event (docs/contact.md, "Equations").
//   P = M⁻¹ − M⁻¹A_bᵀ (A_b M⁻¹ A_bᵀ)⁺ A_b M⁻¹     the inverse mass with the bilateral rows removed
//   W = A_c P A_cᵀ                                 the Delassus matrix of the contacts
//   accelerations:  w = W lambda + (A_c q''_free − b_c),  0 <= lambda ⊥ w >= 0
//   impact:         w = W Λ + (1 + e) v⁻,             0 <= Λ ⊥ w >= 0,  q'⁺ = q'⁻ + P A_cᵀ Λ
#include <algorithm>
#include <vector>

#include "dynamics/contact_dynamics.hpp"
#include "dynamics/internal.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn::detail {

namespace {
Index count_unilateral(const System& sys) {
  Index k = 0;
  for (const auto& c : sys.constraints()) k += c.is_unilateral() ? 1 : 0;
  return k;
}
}  // namespace

Index release_open_contacts(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                            const Eigen::Ref<const VectorXd>& qd, double t) {
  Index released = 0;
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (!sys.constraint(k).is_unilateral()) continue;
    Eigen::Matrix<double, 1, 1> p, v;
    sys.constraint(k).model().violation(q, qd, t, ws.scratch[std::size_t(k)].get(), p, v);
    // (ContactEvents::kTouchGap, relative to the unit of the row's scale's class: 1 for a model
    // in SI units, Workspace::phi_scale / 10)
    if (p[0] > 1e-9 * (0.1 * ws.phi_scale[sys.row_offset(k)])) {
      ws.activity_override[std::size_t(k)] = 0;
      ++released;
    }
  }
  return released;
}

ContactDynamics::ContactDynamics(const System& sys)
    : n_(sys.coordinate_count()), lcp_(count_unilateral(sys)) {
  for (Index k = 0; k < sys.constraint_count(); ++k) {
    if (sys.constraint(k).is_unilateral()) contacts_.push_back(k);
  }
  M_.resize(n_, n_);
  A_.resize(sys.constraint_rows(), n_);
  b_.resize(sys.constraint_rows());
}

void ContactDynamics::gap(const System& sys, Workspace& ws, Index k,
                          const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                          double t, double& g, double& gd) const {
  // (a unilateral constraint has one holonomic row: Constraint::unilateral)
  Eigen::Matrix<double, 1, 1> p, v;
  sys.constraint(k).model().violation(q, qd, t, ws.scratch[std::size_t(k)].get(), p, v);
  g = p[0];
  gd = v[0];
}

bool ContactDynamics::prepare(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t,
                              const std::vector<Index>& set) {
  set_ = set;
  const Index k = Index(set.size());
  // M and its Cholesky factor
  sys.mass_matrix(q, t, ws.callables.get(), M_);
  llt_.compute(M_);
  if (llt_.info() != Eigen::Success) return false;
  // the rows of the active bilateral constraints (A_b) and of the contacts in the set (A_c)
  rows_b_ = 0;
  for (Index c = 0; c < sys.constraint_count(); ++c) {
    const Constraint& con = sys.constraint(c);
    if (con.is_unilateral() || !is_active(sys, ws, c, t)) continue;
    con.model().acceleration_form(q, qd, t, ws.scratch[std::size_t(c)].get(),
                                  A_.middleRows(rows_b_, con.rows()),
                                  b_.segment(rows_b_, con.rows()));
    rows_b_ += con.rows();
  }
  A_b_ = A_.topRows(rows_b_);
  A_c_.resize(k, n_);
  b_c_.resize(k);
  MatrixXd row(1, n_);
  for (Index i = 0; i < k; ++i) {
    const Index c = set[std::size_t(i)];
    sys.constraint(c).model().acceleration_form(q, qd, t, ws.scratch[std::size_t(c)].get(), row,
                                                b_c_.segment(i, 1));
    A_c_.row(i) = row;
  }
  // X = P A_cᵀ = M⁻¹A_cᵀ − Y G_b⁺ A_b M⁻¹A_cᵀ,  Y = M⁻¹A_bᵀ, G_b = A_b Y (least squares: redundant
  // bilateral rows are allowed)
  X_ = llt_.solve(A_c_.transpose());
  if (rows_b_ > 0) {
    const MatrixXd Y = llt_.solve(A_b_.transpose());
    const MatrixXd G = A_b_ * Y;
    Eigen::CompleteOrthogonalDecomposition<MatrixXd> cod(G);
    X_ -= Y * cod.solve(A_b_ * X_);
  }
  // W = A_c P A_cᵀ, symmetrized against roundoff
  W_ = A_c_ * X_;
  W_ = 0.5 * (W_ + W_.transpose()).eval();
  lambda_.setZero(k);
  w_.setZero(k);
  v_after_.setZero(k);
  return true;
}

bool ContactDynamics::accelerations(const System& sys, Workspace& ws,
                                    const Eigen::Ref<const VectorXd>& q,
                                    const Eigen::Ref<const VectorXd>& qd, double t) {
  // q''_free: the run's own evaluation with EVERY contact released — those of the set get their
  // forces from the LCP below, the others are open (at the start no contact's mode is set yet,
  // and after an impact a contact that separates may still be marked closed: left as they are,
  // they would act as two-sided rows in q''_free)
  std::vector<signed char> saved(contacts_.size());
  for (std::size_t i = 0; i < contacts_.size(); ++i) {
    saved[i] = ws.activity_override[std::size_t(contacts_[i])];
    ws.activity_override[std::size_t(contacts_[i])] = 0;
  }
  const Status s = forward_dynamics(sys, ws, q, qd, t);
  for (std::size_t i = 0; i < contacts_.size(); ++i) {
    ws.activity_override[std::size_t(contacts_[i])] = saved[i];
  }
  if (s != Status::kOk) return false;
  // w = W lambda + (A_c q''_free − b_c)
  const VectorXd r = A_c_ * ws.qdd - b_c_;
  if (!lcp_.solve(W_, r)) return false;
  lambda_ = lcp_.z();
  w_ = lcp_.w();
  return true;
}

bool ContactDynamics::impact(Eigen::Ref<VectorXd> qd, const Eigen::Ref<const VectorXd>& v_minus,
                             const Eigen::Ref<const VectorXd>& e) {
  // w = W Λ + (1 + e) v⁻ = v⁺ + e v⁻
  const VectorXd r = (VectorXd::Ones(e.size()) + e).cwiseProduct(v_minus);
  if (!lcp_.solve(W_, r)) return false;
  lambda_ = lcp_.z();
  w_ = lcp_.w();
  // q'⁺ = q'⁻ + P A_cᵀ Λ;  g'⁺ = g'⁻ + W Λ
  qd += X_ * lambda_;
  v_after_ = v_minus + W_ * lambda_;
  return true;
}

}  // namespace ukdyn::detail

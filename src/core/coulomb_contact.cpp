// SPDX-License-Identifier: BSD-3-Clause
// Coulomb contacts: the sliding velocity relative to the constraint (docs/friction.md),
//   v_rel = P (v − u),  P = I − N_k⁺ N_k,
// and the stick constraint P (v − u) = 0 that the simulation switches on while a contact sticks.
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <utility>

#include "dynamics/internal.hpp"
#include "linalg/safe_norm.hpp"
#include "linalg/scale_class.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/workspace.hpp"

namespace ukdyn {
namespace detail {

double normal_row_unit(const Eigen::Ref<const MatrixXd>& rows_n, Index rows, VectorXd& row) {
  double largest = 0.0;
  for (Index i = 0; i < rows; ++i) {
    row = rows_n.row(i).transpose();
    const double a = detail::safe_norm(row.data(), row.size());
    if (std::isfinite(a)) largest = std::max(largest, a);
  }
  return detail::scale_class(largest) / 10.0;
}

void normal_part(const Eigen::Ref<const MatrixXd>& normals, const Eigen::Ref<const VectorXd>& R,
                 VectorXd& out) {
  if (normals.rows() == 1) {
    const double aa = normals.row(0).squaredNorm();
    out = normals.row(0).transpose() * (aa > 0.0 ? normals.row(0).dot(R) / aa : 0.0);
    return;
  }
  const MatrixXd Nt = normals.transpose();
  out = Nt * Nt.completeOrthogonalDecomposition().solve(R);
}

namespace {

// u and u' on the sliding coordinates; the normal constraint's scratch and buffers for the
// tangential projector P at (q, t) and at the shifted points of its rate
class StickScratch final : public ConstraintScratch {
 public:
  StickScratch(Index n, Index size, Index rows, std::unique_ptr<ConstraintScratch> normal_scratch)
      : u(VectorXd::Zero(size)),
        u_dot(VectorXd::Zero(size)),
        w(VectorXd::Zero(size)),
        g(VectorXd::Zero(size)),
        rate(VectorXd::Zero(size)),
        rate2(VectorXd::Zero(size)),
        shifted(VectorXd::Zero(n)),
        row(VectorXd::Zero(n)),
        rows_n(MatrixXd::Zero(std::max<Index>(rows, 1), n)),
        b_n(VectorXd::Zero(std::max<Index>(rows, 1))),
        basis(MatrixXd::Zero(std::max<Index>(rows, 1), size)),
        normal(std::move(normal_scratch)) {}
  VectorXd u, u_dot;  // (size) surface velocity and its rate
  VectorXd w;         // (size) v − u
  VectorXd g;         // (size) scratch: P(s) w
  VectorXd rate;      // (size) dP/dt w, central difference at h
  VectorXd rate2;     // (size) the same at 2h
  VectorXd shifted;   // (n) q + s q'
  VectorXd row;       // (n) a row of the normal constraint, for its norm (row_unit)
  MatrixXd rows_n;    // (rows × n) the normal constraint's rows of A
  VectorXd b_n;       // (rows) its b (unused)
  MatrixXd basis;     // (rows × size) orthonormal basis of its rows on the sliding coordinates
  Index basis_size = 0;
  std::unique_ptr<ConstraintScratch> normal;
};

// The stick constraint of a Coulomb contact: the contact moves with the surface,
//   psi = P (v − u) = 0,   P = I − N_k⁺ N_k  (the tangential projector of sliding_velocity),
// on the sliding coordinates. The normal part of v is the normal constraint's business: for a
// rheonomic constraint (a rotating wire) the stuck contact moves with the surface's normal
// motion, which the constraint itself imposes. Rows: P (size rows, rank size − rank N_k: the
// rows are dependent, which the pseudo-inverse of the Udwadia–Kalaba equation takes). Along the
// motion d psi/dt = P (v' − u') + P' (v − u); its tangential part is the acceleration form
//   P q''_c = P u' − P P' (v − u),
// with P' (v − u) the derivative of s ↦ P(q + s q', t + s)(v − u) at 0 (Richardson-extrapolated
// central differences: P depends on the rows of A only, which models do not differentiate).
// Without a normal constraint (none found) P = I: psi = v − u.
//
// Scale: the rows are stated in the unit of the normal constraint's rows beside which they
// stand in one rank decision and one projection, kappa P (v − u) = 0 with kappa =
// class(max_i ‖n_i‖) / 10 (detail::scale_class; n_i the normal constraint's rows of A at (q, t),
// whole), so that a normal constraint written × 1e8 brings stick rows × 1e9, not rows of 1 that
// its rank decision (relative to the largest pivot) would take for roundoff. kappa is 1 for
// rows of norm in [0.0316, 31.6] (every example in SI units: the same bits as unscaled), and a
// change of units by 1000^j moves it by exactly that factor (docs/simulation.md, "Scales and
// tolerances"). kappa is constant within a class: the rows' zero set is P (v − u) = 0 whatever
// it is, and on it d(kappa psi)/dt = kappa dpsi/dt.
class StickModel final : public ConstraintModel {
 public:
  StickModel(std::vector<Index> coordinates, SurfaceVelocityFn surface,
             std::optional<Constraint> normal)
      : coordinates_(std::move(coordinates)),
        surface_(std::move(surface)),
        normal_constraint_(std::move(normal)),
        normal_(normal_constraint_ ? &normal_constraint_->model() : nullptr),
        normal_rows_(normal_constraint_ ? normal_constraint_->rows() : 0) {
    columns_ = coordinates_;
    std::sort(columns_.begin(), columns_.end());
    position_.resize(coordinates_.size());
    for (std::size_t r = 0; r < coordinates_.size(); ++r) {
      position_[r] = Index(std::lower_bound(columns_.begin(), columns_.end(), coordinates_[r]) -
                           columns_.begin());
    }
  }

  std::unique_ptr<ConstraintScratch> make_scratch(Index n) const override {
    // the normal constraint's own scratch (not the workspace's shared one: it is evaluated here
    // at shifted points, which must not disturb a shared cache)
    return std::make_unique<StickScratch>(n, Index(coordinates_.size()), normal_rows_,
                                          normal_ ? normal_->make_scratch(n) : nullptr);
  }
  const std::vector<Index>& columns() const override { return columns_; }

  void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double t,
                               ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A_local,
                               Eigen::Ref<VectorXd> b) const override {
    auto& s = static_cast<StickScratch&>(*scratch);
    const Index nc = Index(coordinates_.size());
    // w = v − u, and u'
    for (Index r = 0; r < nc; ++r) s.w[r] = qd[coordinates_[std::size_t(r)]];
    if (surface_) {
      surface_(q, qd, t, s.u, s.u_dot);
      s.w -= s.u;
    } else {
      s.u_dot.setZero();
    }
    // the rate P' w, then P at (q, t) itself (its basis stays in the scratch)
    s.rate.setZero();
    if (normal_) {
      double h = 1e-3;
      for (int pass = 0; pass < 2; ++pass) {
        difference(q, qd, t, h, s, s.rate);
        difference(q, qd, t, 2.0 * h, s, s.rate2);
        s.rate = (4.0 * s.rate - s.rate2) / 3.0;
        // the basis turns at about |P' w| / |w|: keep h well below its time scale
        const double w_norm = s.w.norm(), turn = s.rate.norm();
        if (!(turn * h > 5e-3 * w_norm)) break;
        h = 5e-3 * w_norm / turn;
      }
      basis_at(q, qd, t, 0.0, s);
    }
    // A_local = P in the rows' coordinate order
    A_local.setZero();
    for (Index r = 0; r < nc; ++r) {
      A_local(r, position_[std::size_t(r)]) = 1.0;
      for (Index j = 0; j < s.basis_size; ++j) {
        for (Index c = 0; c < nc; ++c) {
          A_local(r, position_[std::size_t(c)]) -= s.basis(j, r) * s.basis(j, c);
        }
      }
    }
    // b = P (u' − P' w)
    b = s.u_dot - s.rate;
    project(s, b);
    // both × kappa, the normal rows' unit
    if (const double kappa = row_unit(s); kappa != 1.0) {
      A_local *= kappa;
      b *= kappa;
    }
  }

  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                 double t, ConstraintScratch* scratch, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& s = static_cast<StickScratch&>(*scratch);
    position.setZero();
    for (std::size_t r = 0; r < coordinates_.size(); ++r) velocity[Index(r)] = qd[coordinates_[r]];
    if (surface_) {
      surface_(q, qd, t, s.u, s.u_dot);
      velocity -= s.u;
    }
    if (normal_) {
      basis_at(q, qd, t, 0.0, s);
      project(s, velocity);
      velocity *= row_unit(s);
    }
  }

 private:
  // the orthonormal basis of the normal rows on the sliding coordinates at (q + step q', t + step)
  // into s.basis (Gram–Schmidt twice, as sliding_velocity)
  void basis_at(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double t,
                double step, StickScratch& s) const {
    if (step == 0.0) {
      normal_->acceleration_form(q, qd, t, s.normal.get(), s.rows_n, s.b_n.head(normal_rows_));
    } else {
      s.shifted = q + step * qd;
      normal_->acceleration_form(s.shifted, qd, t + step, s.normal.get(), s.rows_n,
                                 s.b_n.head(normal_rows_));
    }
    const Index nc = Index(coordinates_.size());
    Index basis = 0;
    for (Index i = 0; i < normal_rows_; ++i) {
      auto e = s.basis.row(basis);
      for (Index r = 0; r < nc; ++r) e[r] = s.rows_n(i, coordinates_[std::size_t(r)]);
      const double norm0 = e.norm();
      if (!(norm0 > 0.0)) continue;
      for (int pass = 0; pass < 2; ++pass) {
        for (Index j = 0; j < basis; ++j) e -= e.dot(s.basis.row(j)) * s.basis.row(j);
      }
      const double norm = e.norm();
      if (norm <= 1e-10 * norm0) continue;
      e /= norm;
      ++basis;
    }
    s.basis_size = basis;
  }

  // kappa = class(max_i ‖n_i‖) / 10, the unit of the normal constraint's rows n_i in s.rows_n
  // (as basis_at at step 0 left them; 1 without a normal constraint or when every row vanishes
  // or is not finite)
  double row_unit(StickScratch& s) const {
    if (normal_ == nullptr) return 1.0;
    return normal_row_unit(s.rows_n, normal_rows_, s.row);
  }

  // v ← P v with the basis in s
  static void project(const StickScratch& s, Eigen::Ref<VectorXd> v) {
    for (Index j = 0; j < s.basis_size; ++j) {
      const auto e = s.basis.row(j);
      v -= v.dot(e) * e.transpose();
    }
  }

  // out = (P(h) w − P(−h) w) / (2h), P(s) at (q + s q', t + s)
  void difference(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                  double t, double h, StickScratch& s, VectorXd& out) const {
    basis_at(q, qd, t, h, s);
    s.g = s.w;
    project(s, s.g);
    out = s.g;
    basis_at(q, qd, t, -h, s);
    s.g = s.w;
    project(s, s.g);
    out -= s.g;
    out /= 2.0 * h;
  }

  std::vector<Index> coordinates_;  // in the friction's order (the rows)
  std::vector<Index> columns_;      // sorted
  std::vector<Index> position_;     // row r's coordinate within columns_
  SurfaceVelocityFn surface_;
  std::optional<Constraint> normal_constraint_;  // the contact's normal constraint, if known
  const ConstraintModel* normal_;                // its model, or null
  Index normal_rows_;
};

// The stick constraint of a Coulomb contact on the contact-point path (ContactKinematics):
// the contact point's material velocity has no tangential part,
//   psi = T q' = 0,   T = (t_iᵀ J_P)_i  (d rows on the kinematics' columns),
// with the acceleration form T q'' = −T' q' (the bias rows of the kinematics). The normal part is
// the contact constraint's. Scale: × kappa, the unit of the normal constraint's rows as
// StickModel's (normal_row_unit; 1 for a contact in SI units, and a change of units of the rows
// moves the stick rows with them).
class PointStickModel final : public ConstraintModel {
 public:
  struct Scratch final : public ConstraintScratch {
    Scratch(Index n, Index rows, Index cols, Index normal_rows,
            std::unique_ptr<ConstraintScratch> own, std::unique_ptr<ConstraintScratch> normal)
        : J(MatrixXd::Zero(rows, cols)),
          bias(VectorXd::Zero(rows)),
          rows_n(MatrixXd::Zero(std::max<Index>(normal_rows, 1), n)),
          b_n(VectorXd::Zero(std::max<Index>(normal_rows, 1))),
          row(VectorXd::Zero(n)),
          kinematics(std::move(own)),
          normal_scratch(std::move(normal)) {}
    MatrixXd J;       // (1 + d) × |columns|
    VectorXd bias;    // (1 + d)
    MatrixXd rows_n;  // (normal rows × n) the normal constraint's rows of A
    VectorXd b_n;     // (normal rows) its b (unused)
    VectorXd row;     // (n) one of them, for its norm
    std::unique_ptr<ConstraintScratch> kinematics;
    std::unique_ptr<ConstraintScratch> normal_scratch;
  };
  PointStickModel(ContactKinematics kinematics, std::optional<Constraint> normal)
      : kin_(std::move(kinematics)),
        normal_constraint_(std::move(normal)),
        normal_(normal_constraint_ ? &normal_constraint_->model() : nullptr),
        normal_rows_(normal_constraint_ ? normal_constraint_->rows() : 0) {}

  std::unique_ptr<ConstraintScratch> make_scratch(Index n) const override {
    return std::make_unique<Scratch>(n, 1 + kin_.tangents, Index(kin_.columns.size()), normal_rows_,
                                     kin_.make_scratch ? kin_.make_scratch(n) : nullptr,
                                     normal_ ? normal_->make_scratch(n) : nullptr);
  }
  const std::vector<Index>& columns() const override { return kin_.columns; }

  void acceleration_form_local(const Eigen::Ref<const VectorXd>& q,
                               const Eigen::Ref<const VectorXd>& qd, double t,
                               ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A_local,
                               Eigen::Ref<VectorXd> b) const override {
    auto& s = static_cast<Scratch&>(*scratch);
    kin_.evaluate(q, qd, t, s.kinematics.get(), s.J, s.bias);
    const double kappa = unit(q, qd, t, s);
    A_local = kappa * s.J.bottomRows(kin_.tangents);
    b = -kappa * s.bias.tail(kin_.tangents);
  }

  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                 double t, ConstraintScratch* scratch, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    auto& s = static_cast<Scratch&>(*scratch);
    kin_.evaluate(q, qd, t, s.kinematics.get(), s.J, s.bias);
    position.setZero();
    velocity.setZero();
    for (std::size_t j = 0; j < kin_.columns.size(); ++j)
      velocity += s.J.col(Index(j)).tail(kin_.tangents) * qd[kin_.columns[j]];
    velocity *= unit(q, qd, t, s);
  }

 private:
  // kappa of the normal constraint's rows at (q, t) (1 without one)
  double unit(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double t,
              Scratch& s) const {
    if (normal_ == nullptr) return 1.0;
    normal_->acceleration_form(q, qd, t, s.normal_scratch.get(), s.rows_n,
                               s.b_n.head(normal_rows_));
    return normal_row_unit(s.rows_n, normal_rows_, s.row);
  }
  ContactKinematics kin_;
  std::optional<Constraint> normal_constraint_;  // the contact's normal constraint, if known
  const ConstraintModel* normal_;                // its model, or null
  Index normal_rows_;
};

}  // namespace

Constraint point_stick_constraint(const std::string& name, const ContactKinematics& kinematics,
                                  const Constraint* normal) {
  std::optional<Constraint> copy;
  if (normal != nullptr) copy = *normal;
  return Constraint(name, ConstraintKind::kNonholonomic, kinematics.tangents,
                    std::make_shared<const PointStickModel>(kinematics, std::move(copy)));
}

double contact_normal_force(const System& sys, const Workspace& ws, Index c,
                            const Eigen::Ref<const VectorXd>& reaction) {
  const auto& cols = sys.friction_contacts()[std::size_t(c)].kinematics.columns;
  const auto& J = ws.contact_jacobian[std::size_t(c)];
  double wr = 0.0;
  for (std::size_t j = 0; j < cols.size(); ++j) wr += J(0, Index(j)) * reaction[cols[j]];
  const double ww = J.row(0).squaredNorm();
  return ww > 0.0 ? std::abs(wr) / ww : 0.0;
}

void add_contact_force(const System& sys, const Workspace& ws, Index c, double scale,
                       const Eigen::Ref<const VectorXd>& f, Eigen::Ref<VectorXd> C) {
  const auto& kin = sys.friction_contacts()[std::size_t(c)].kinematics;
  const auto& J = ws.contact_jacobian[std::size_t(c)];
  for (std::size_t j = 0; j < kin.columns.size(); ++j)
    C[kin.columns[j]] += scale * J.col(Index(j)).tail(kin.tangents).dot(f);
}

Constraint stick_constraint(const std::string& name, const std::vector<Index>& coordinates,
                            const SurfaceVelocityFn& surface, const Constraint* normal) {
  std::optional<Constraint> copy;
  if (normal != nullptr) copy = *normal;
  return Constraint(name, ConstraintKind::kNonholonomic, Index(coordinates.size()),
                    std::make_shared<const StickModel>(coordinates, surface, std::move(copy)));
}

Index sliding_velocity(const System& sys, Workspace& ws, Index c,
                       const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, bool rows_assembled) {
  const FrictionContact& contact = sys.friction_contacts()[std::size_t(c)];
  if (const ContactKinematics& kin = contact.kinematics) {
    // the contact-point path: v_rel = T q' (no normal to remove: T is tangential already)
    auto& J = ws.contact_jacobian[std::size_t(c)];
    auto bias = ws.contact_bias.col(c).head(1 + kin.tangents);
    kin.evaluate(q, qd, t, ws.contact_scratch[std::size_t(c)].get(), J, bias);
    auto v = ws.sliding.col(c).head(kin.tangents);
    v.setZero();
    for (std::size_t j = 0; j < kin.columns.size(); ++j)
      v += J.col(Index(j)).tail(kin.tangents) * qd[kin.columns[j]];
    return 0;
  }
  const std::vector<Index>& coords = contact.coordinates;
  const Index nc = Index(coords.size()), k = contact.normal_constraint;
  auto v = ws.sliding.col(c).head(nc);
  // v − u
  for (Index r = 0; r < nc; ++r) v[r] = qd[coords[std::size_t(r)]];
  if (contact.surface_velocity) {
    contact.surface_velocity(q, qd, t, ws.surface_u.head(nc), ws.surface_u_dot.head(nc));
    v -= ws.surface_u.head(nc);
  }
  // N_k: constraint k's rows of A at (q, t), as assembled or evaluated here
  if (!is_active(sys, ws, k, t)) return 0;
  const Index rows = sys.constraint(k).rows();
  auto Ak = ws.contact_rows.topRows(rows);
  if (rows_assembled) {
    copy_constraint_rows(sys, ws, k, Ak);
  } else {
    sys.constraint(k).model().acceleration_form(q, qd, t, ws.scratch[std::size_t(k)].get(), Ak,
                                                ws.contact_b.head(rows));
  }
  // an orthonormal basis e_j of the rows of N_k (Gram–Schmidt, twice: rows may be dependent)
  Index basis = 0;
  for (Index i = 0; i < rows; ++i) {
    auto e = ws.contact_basis.row(basis).head(nc);
    for (Index r = 0; r < nc; ++r) e[r] = Ak(i, coords[std::size_t(r)]);
    const double norm0 = e.norm();
    if (!(norm0 > 0.0)) continue;
    for (int pass = 0; pass < 2; ++pass) {
      for (Index j = 0; j < basis; ++j) {
        e -= e.dot(ws.contact_basis.row(j).head(nc)) * ws.contact_basis.row(j).head(nc);
      }
    }
    const double norm = e.norm();
    if (norm <= 1e-10 * norm0) continue;
    e /= norm;
    ++basis;
  }
  // v_rel = (I − Σ e_j e_jᵀ)(v − u)
  remove_normals(ws, basis, v);
  return basis;
}

void remove_normals(const Workspace& ws, Index basis, Eigen::Ref<VectorXd> v) {
  for (Index j = 0; j < basis; ++j) {
    const auto e = ws.contact_basis.row(j).head(v.size());
    v -= v.dot(e) * e.transpose();
  }
}

}  // namespace detail
}  // namespace ukdyn

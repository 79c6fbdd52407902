// Coulomb contacts: the sliding velocity relative to the constraint (docs/friction.md),
//   v_rel = P (v − u),  P = I − N_k⁺ N_k,
// and the stick constraint v − u = 0 that the simulation switches on while a contact sticks.
#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <utility>

#include "dynamics/internal.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/workspace.hpp"

namespace ukdyn {
namespace detail {

namespace {

// u and u' on the sliding coordinates
class StickScratch final : public ConstraintScratch {
 public:
  explicit StickScratch(Index size) : u(VectorXd::Zero(size)), u_dot(VectorXd::Zero(size)) {}
  VectorXd u, u_dot;
};

// psi = v − u(q, t) on the sliding coordinates: A = the unit rows of those coordinates,
// b = u' (so that A q'' = b is d psi/dt = 0)
class StickModel final : public ConstraintModel {
 public:
  StickModel(std::vector<Index> coordinates, SurfaceVelocityFn surface)
      : coordinates_(std::move(coordinates)), surface_(std::move(surface)) {
    columns_ = coordinates_;
    std::sort(columns_.begin(), columns_.end());
    position_.resize(coordinates_.size());
    for (std::size_t r = 0; r < coordinates_.size(); ++r) {
      position_[r] = Index(std::lower_bound(columns_.begin(), columns_.end(), coordinates_[r]) -
                           columns_.begin());
    }
  }

  std::unique_ptr<ConstraintScratch> make_scratch(Index) const override {
    return std::make_unique<StickScratch>(Index(coordinates_.size()));
  }
  const std::vector<Index>& columns() const override { return columns_; }

  void acceleration_form_local(const VectorXd& q, const VectorXd& qd, double t,
                               ConstraintScratch* scratch, Eigen::Ref<MatrixXd> A_local,
                               Eigen::Ref<VectorXd> b) const override {
    A_local.setZero();
    for (std::size_t r = 0; r < coordinates_.size(); ++r) A_local(Index(r), position_[r]) = 1.0;
    if (!surface_) {
      b.setZero();
      return;
    }
    auto& s = static_cast<StickScratch&>(*scratch);
    surface_(q, qd, t, s.u, s.u_dot);
    b = s.u_dot;
  }

  void violation(const VectorXd& q, const VectorXd& qd, double t, ConstraintScratch* scratch,
                 Eigen::Ref<VectorXd> position, Eigen::Ref<VectorXd> velocity) const override {
    position.setZero();
    for (std::size_t r = 0; r < coordinates_.size(); ++r) velocity[Index(r)] = qd[coordinates_[r]];
    if (!surface_) return;
    auto& s = static_cast<StickScratch&>(*scratch);
    surface_(q, qd, t, s.u, s.u_dot);
    velocity -= s.u;
  }

 private:
  std::vector<Index> coordinates_;  // in the friction's order (the rows)
  std::vector<Index> columns_;      // sorted
  std::vector<Index> position_;     // row r's coordinate within columns_
  SurfaceVelocityFn surface_;
};

}  // namespace

Constraint stick_constraint(const std::string& name, const std::vector<Index>& coordinates,
                            const SurfaceVelocityFn& surface) {
  return Constraint(name, ConstraintKind::kNonholonomic, Index(coordinates.size()),
                    std::make_shared<const StickModel>(coordinates, surface));
}

Index sliding_velocity(const System& sys, Workspace& ws, Index c, const VectorXd& q,
                       const VectorXd& qd, double t, bool rows_assembled) {
  const FrictionContact& contact = sys.friction_contacts()[std::size_t(c)];
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

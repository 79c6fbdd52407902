// SPDX-License-Identifier: BSD-3-Clause
// Non-ideal forces: the view of the ideal force they read, and the ready-made friction laws.
#include "ukdyn/core/nonideal.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "dynamics/internal.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/workspace.hpp"

namespace ukdyn {

const VectorXd& IdealForceInfo::Qc_ideal() const { return ws_.Qc_ideal; }
CallableScratch* IdealForceInfo::scratch() const {
  return replaced_ ? scratch_ : ws_.callables.get();
}
const VectorXd& IdealForceInfo::lambda() const { return ws_.lambda; }
Eigen::Ref<const VectorXd> IdealForceInfo::lambda(Index k) const { return ws_.lambda_of(sys_, k); }
Eigen::Ref<const VectorXd> IdealForceInfo::share(Index k) const { return ws_.shares.col(k); }
Eigen::Ref<const VectorXd> IdealForceInfo::reaction(Index k) const {
  read_reactions_ = true;
  if (outer_ != nullptr) outer_->read_reactions_ = true;
  return ws_.reactions.col(k);
}
Eigen::Ref<const VectorXd> IdealForceInfo::slip_hint(Index i) const { return ws_.slip_hint.col(i); }
bool IdealForceInfo::slip_hint_held(Index i) const {
  return ws_.slip_hint_held[std::size_t(i)] != 0;
}
Eigen::Ref<const VectorXd> IdealForceInfo::sliding_velocity(Index c) const {
  const auto& contacts = sys_.friction_contacts();
  return ws_.sliding.col(c).head(contacts[std::size_t(c)].size());
}
Eigen::Ref<const MatrixXd> IdealForceInfo::contact_jacobian(Index c) const {
  return ws_.contact_jacobian[std::size_t(c)];
}
double IdealForceInfo::normal_force(Index k, const std::vector<Index>& on) const {
  const auto R = reaction(k);
  if (on.empty()) return R.norm();
  double s = 0.0;
  for (const Index i : on) s += R[i] * R[i];
  return std::sqrt(s);
}
double IdealForceInfo::contact_normal_force(Index c, Index k) const {
  return detail::contact_normal_force(sys_, ws_, c, reaction(k));
}
void IdealForceInfo::add_contact_force(Index c, double scale, const Eigen::Ref<const VectorXd>& f,
                                       Eigen::Ref<VectorXd> C) const {
  detail::add_contact_force(sys_, ws_, c, scale, f, C);
}
Index IdealForceInfo::constraint_index(std::string_view name) const {
  return sys_.constraint_index(name);
}

NonIdealForce::NonIdealForce(std::string name, NonIdealFn fn) : name_(std::move(name)) {
  if (!fn) throw std::invalid_argument("ukdyn::NonIdealForce '" + name_ + "': empty callable");
  bind_ = [fn = std::move(fn)](const System&) { return fn; };
}

NonIdealForce::NonIdealForce(std::string name, Binder bind)
    : name_(std::move(name)), bind_(std::move(bind)) {
  if (!bind_) throw std::invalid_argument("ukdyn::NonIdealForce '" + name_ + "': empty binder");
}

namespace {
// the listed coordinates, all of them when the list is empty; checks the range
std::vector<Index> resolve_coordinates(const std::vector<Index>& listed, Index n,
                                       const std::string& who) {
  if (listed.empty()) {
    std::vector<Index> all(static_cast<std::size_t>(n));
    for (Index i = 0; i < n; ++i) all[std::size_t(i)] = i;
    return all;
  }
  for (std::size_t j = 0; j < listed.size(); ++j) {
    const Index i = listed[j];
    if (i < 0 || i >= n) {
      throw std::invalid_argument(who + ": coordinate index " + format_number(i) +
                                  " is out of range [0, " + format_number(n) + ")");
    }
    if (std::find(listed.begin(), listed.begin() + std::ptrdiff_t(j), i) !=
        listed.begin() + std::ptrdiff_t(j)) {
      throw std::invalid_argument(who + ": coordinate index " + format_number(i) +
                                  " is listed twice");
    }
  }
  return listed;
}
}  // namespace

namespace {
// The law on the contact-point path (ContactKinematics): v_rel = T q' (sliding_velocity),
//   C = Tᵀ f,  f = −mu N v_rel / sqrt(|v_rel|² + eps²),  N = |w·R_k| / |w|² (physical),
// with the slip hint (d tangential components) as the coordinate path's.
NonIdealFn contact_point_law(const CoulombFriction& spec, const System& sys, Index k,
                             const std::string& who) {
  const ContactKinematics& kin = spec.kinematics;
  if (!spec.coordinates.empty())
    throw std::invalid_argument(who +
                                ": a friction at a contact point slides the point, not "
                                "listed coordinates: leave coordinates empty");
  if (!spec.normal_coordinates.empty())
    throw std::invalid_argument(who +
                                ": a friction at a contact point reads its normal force at the "
                                "point (physical already): leave normal_coordinates empty");
  if (spec.surface_velocity)
    throw std::invalid_argument(who +
                                ": a surface velocity under a contact point is not "
                                "supported yet");
  if (kin.tangents != 1 && kin.tangents != 2)
    throw std::invalid_argument(who + ": the contact kinematics' tangents must be 1 or 2, got " +
                                format_number(kin.tangents));
  for (std::size_t j = 0; j < kin.columns.size(); ++j) {
    const Index i = kin.columns[j];
    if (i < 0 || i >= sys.coordinate_count() || (j > 0 && !(kin.columns[j - 1] < i)))
      throw std::invalid_argument(who +
                                  ": the contact kinematics' columns must be strictly "
                                  "increasing coordinate indices in [0, " +
                                  format_number(sys.coordinate_count()) + ")");
  }
  const double mu = spec.mu, eps2 = spec.regularization_velocity * spec.regularization_velocity;
  const Index self = sys.nonideal_count(), contact = Index(sys.friction_contacts().size());
  return [k, mu, eps2, self, contact](const Eigen::Ref<const VectorXd>&,
                                      const Eigen::Ref<const VectorXd>&, double,
                                      const IdealForceInfo& ideal, Eigen::Ref<VectorXd> C) {
    const auto v = ideal.sliding_velocity(contact);
    const double v2 = v.squaredNorm();
    const double N = ideal.contact_normal_force(contact, k);
    // (the column, named: a Block of the temporary Ref would outlive it — ASan, stack use
    // after scope)
    const Eigen::Ref<const VectorXd> hint_column = ideal.slip_hint(self);
    const auto hint = hint_column.head(v.size());
    if (hint.squaredNorm() > 0.0) {
      // slipping from rest: mu N along the hint (see the coordinate path)
      if (v2 <= 1e4 * eps2 || ideal.slip_hint_held(self)) {
        ideal.add_contact_force(contact, mu * N, hint, C);
      } else {
        ideal.add_contact_force(contact, -mu * N / std::sqrt(v2), v, C);
      }
      return;
    }
    // f = −mu N v_rel / sqrt(|v_rel|² + eps²)
    ideal.add_contact_force(contact, -mu * N / std::sqrt(v2 + eps2), v, C);
  };
}
}  // namespace

NonIdealForce coulomb_friction(CoulombFriction spec) {
  std::string name = spec.name.empty() ? "coulomb." + spec.constraint : spec.name;
  spec.name = name;
  NonIdealForce force(
      name, NonIdealForce::Binder([spec, name](const System& sys) -> NonIdealFn {
        const std::string who = "ukdyn::coulomb_friction '" + name + "'";
        if (!(spec.mu >= 0.0)) {
          throw std::invalid_argument(who + ": mu must be >= 0, got " + format_number(spec.mu));
        }
        if (!(spec.regularization_velocity > 0.0)) {
          throw std::invalid_argument(who + ": regularization_velocity must be > 0, got " +
                                      format_number(spec.regularization_velocity));
        }
        if (spec.mu_static && !(*spec.mu_static >= spec.mu)) {
          throw std::invalid_argument(who +
                                      ": mu_static must be >= mu = " + format_number(spec.mu) +
                                      ", got " + format_number(*spec.mu_static));
        }
        const Index k = sys.constraint_index(spec.constraint);
        if (spec.kinematics) return contact_point_law(spec, sys, k, who);
        const std::vector<Index> coords =
            resolve_coordinates(spec.coordinates, sys.coordinate_count(), who);
        // p, the coordinates N is read on (empty: all n); checked like the sliding ones
        std::vector<Index> on;
        if (!spec.normal_coordinates.empty())
          on = resolve_coordinates(spec.normal_coordinates, sys.coordinate_count(),
                                   who + " (normal_coordinates)");
        const double mu = spec.mu,
                     eps2 = spec.regularization_velocity * spec.regularization_velocity;
        const Index self = sys.nonideal_count();  // this force's index once bound
        const Index contact = Index(sys.friction_contacts().size());  // and its contact's
        return [k, coords, on, mu, eps2, self, contact](
                   const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                   const IdealForceInfo& ideal, Eigen::Ref<VectorXd> C) {
          // v_rel, the sliding velocity relative to the constraint (see CoulombFriction)
          const auto v = ideal.sliding_velocity(contact);
          const double v2 = v.squaredNorm();
          const double N = ideal.normal_force(k, on);  // |R_p| (docs/friction.md §1)
          const auto hint = ideal.slip_hint(self);
          if (hint.squaredNorm() > 0.0) {
            // slipping from rest: mu N along the hint while |v_rel| <= 100 eps (the speed at which
            // the simulation locates stops: a restart from v_rel ≈ 0 never sees the friction flip
            // inside its first step), then exactly −mu N v_rel/|v_rel| (held: at every speed, see
            // Workspace::slip_hint_held)
            if (v2 <= 1e4 * eps2 || ideal.slip_hint_held(self)) {
              for (Index i : coords) C[i] = mu * N * hint[i];
            } else {
              const double scale = -mu * N / std::sqrt(v2);
              for (std::size_t r = 0; r < coords.size(); ++r) C[coords[r]] = scale * v[Index(r)];
            }
            return;
          }
          // C_i = −mu N v_rel,i / sqrt(|v_rel|² + eps²)
          const double scale = -mu * N / std::sqrt(v2 + eps2);
          for (std::size_t r = 0; r < coords.size(); ++r) C[coords[r]] = scale * v[Index(r)];
        };
      }));
  force.coulomb_ = std::make_shared<const CoulombFriction>(spec);
  return force;
}

NonIdealForce viscous_friction(ViscousFriction spec) {
  std::string name = spec.name;  // copied first: spec moves into the binder
  return NonIdealForce(
      std::move(name),
      NonIdealForce::Binder([spec = std::move(spec)](const System& sys) -> NonIdealFn {
        const std::string who = "ukdyn::viscous_friction '" + spec.name + "'";
        if (!(spec.coefficient >= 0.0)) {
          throw std::invalid_argument(who + ": coefficient must be >= 0, got " +
                                      format_number(spec.coefficient));
        }
        const std::vector<Index> coords =
            resolve_coordinates(spec.coordinates, sys.coordinate_count(), who);
        const double c = spec.coefficient;
        // C_i = −c q'_i
        return [coords, c](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>& qd,
                           double, const IdealForceInfo&, Eigen::Ref<VectorXd> C) {
          for (Index i : coords) C[i] = -c * qd[i];
        };
      }));
}

}  // namespace ukdyn

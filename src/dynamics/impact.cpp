// SPDX-License-Identifier: BSD-3-Clause
// ContactDynamics: the unilateral contacts at an event (docs/contact.md, "Equations").
//   P = M⁻¹ − M⁻¹A_bᵀ (A_b M⁻¹ A_bᵀ)⁺ A_b M⁻¹     the inverse mass with the bilateral rows removed
//   W = A_c P A_cᵀ                                 the Delassus matrix of the contacts
//   accelerations:  w = W lambda + (A_c q''_free − b_c),  0 <= lambda ⊥ w >= 0
//   impact:         w = W Λ + (1 + e) v⁻,             0 <= Λ ⊥ w >= 0,  q'⁺ = q'⁻ + P A_cᵀ Λ
//                   (Newton's law; Poisson's: a compression phase with e = 0, then a restitution
//                   phase whose impulse is at least e times the compression's)
// and with Coulomb friction on the contacts (docs/contact.md, "Friction at contacts"): the
// sliding friction's columns F in the accelerations' LCP (W + F not a P-matrix: Painlevé's
// paradox, an error), the friction impulse D β in the impact's (Anitescu–Potra).
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/LU>

#include "dynamics/contact_dynamics.hpp"
#include "dynamics/internal.hpp"
#include "linalg/scale_class.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/dynamics/contact_restitution.hpp"
#include "ukdyn/dynamics/forward.hpp"

namespace ukdyn::detail {

namespace {
Index count_unilateral(const System& sys) {
  Index k = 0;
  for (const auto& c : sys.constraints()) k += c.is_unilateral() ? 1 : 0;
  return k;
}
// the friction variables of the impacts' LCP at most: ±each sliding coordinate and one cone per
// Coulomb contact on a unilateral constraint
Index friction_variables(const System& sys) {
  Index count = 0;
  for (const FrictionContact& fc : sys.friction_contacts()) {
    if (sys.constraint(fc.normal_constraint).is_unilateral()) count += 2 * fc.size() + 1;
  }
  return count;
}
// the contacts' rows are redundant where W restricted to them has a pivot below this fraction
// of its largest (its complete orthogonal decomposition): four coplanar corners of a box
constexpr double kRedundantPivot = 1e-10;
// a contact's slack w_i within this fraction of the largest |r_i| is zero (ContactEvents'
// kUnloaded): it touches without separating
constexpr double kZeroSlack = 1e-9;

// The least-norm solution of the LCP w = M z + r, 0 <= z ⊥ w >= 0 (size s) with the rows `on`
// at w = 0 and every other z zero: z_on = −M_on,on⁺ r_on, the least-norm multipliers of those
// rows — for M = W the fundamental equation's with those contacts active (the reaction P A_cᵀ z
// is unique, its split among redundant rows is not, and the least-norm split is the symmetric
// one where Lemke's pivots give a vertex). `adjust`, when given, may change that z before it
// is checked into another answer with the same rows `on` (friction_split: opposite friction
// directions folded into one impulse, a leaving contact's sliding speed). Into z and w (s each;
// z within roundoff of 0 made 0, w_on = 0) when it solves the LCP to tol = tolerance (‖M‖ ‖z‖ +
// ‖r‖), else z and w left alone and false. O(|on|³ + s²); allocates (events only).
bool least_norm_lcp(const MatrixXd& M, const VectorXd& r, const std::vector<Index>& on, VectorXd& z,
                    VectorXd& w, const std::function<void(VectorXd&)>& adjust = {},
                    double tolerance = 1e-9) {
  const Index s = r.size(), a = Index(on.size());
  if (a == 0) return false;
  MatrixXd Ma(a, a);
  VectorXd ra(a);
  for (Index i = 0; i < a; ++i) {
    ra[i] = r[on[std::size_t(i)]];
    for (Index j = 0; j < a; ++j) Ma(i, j) = M(on[std::size_t(i)], on[std::size_t(j)]);
  }
  Eigen::CompleteOrthogonalDecomposition<MatrixXd> cod;
  cod.setThreshold(kRedundantPivot);
  cod.compute(Ma);
  const VectorXd za = -cod.solve(ra);
  VectorXd zc = VectorXd::Zero(s);
  for (Index i = 0; i < a; ++i) zc[on[std::size_t(i)]] = za[i];
  if (adjust) adjust(zc);
  const VectorXd wc = M * zc + r;
  const double tol = tolerance * std::max(M.norm() * zc.norm() + r.norm(), 1e-300);
  if (!zc.allFinite() || zc.minCoeff() < -tol || wc.minCoeff() < -tol) return false;
  for (Index i : on) {
    if (std::abs(wc[i]) > tol) return false;
  }
  z = zc.unaryExpr([tol](double v) { return v > tol ? v : 0.0; });
  w = wc.cwiseMax(0.0);
  for (Index i : on) w[i] = 0.0;
  return true;
}

// a row of an LCP answer within this fraction of its own terms Σ_j |M_ij z_j| + |r_i|, plus
// kRowFloor of the largest |r_i| (a row whose terms all vanish: a contact that leaves), is zero
constexpr double kRowResidual = 1e-6;
constexpr double kRowFloor = 1e-9;

// True when z solves the LCP w = M z + r, 0 <= z ⊥ w >= 0 row by row: w_i >= −tol_i and
// min(s_i z_i, w_i) <= tol_i, tol_i = kRowResidual (Σ_j |M_ij| |z_j| + |r_i|) + kRowFloor
// max_j |r_j|, s_i the row's largest |M_ij| (z_i in w's unit). ContactLcp::check's tolerance,
// relative to ‖M‖ ‖z‖, takes any z when ‖z‖ is huge (a degenerate pivot's 1e17); a row's own
// terms do not. O(s²); allocates w (events only).
bool complementary_rows(const MatrixXd& M, const VectorXd& r, const VectorXd& z) {
  const VectorXd w = M * z + r;
  const double floor = kRowFloor * r.cwiseAbs().maxCoeff();
  for (Index i = 0; i < r.size(); ++i) {
    const double terms = M.row(i).cwiseAbs().dot(z.cwiseAbs()) + std::abs(r[i]);
    const double tol = kRowResidual * terms + floor, s = M.row(i).cwiseAbs().maxCoeff();
    if (!std::isfinite(w[i]) || !(z[i] >= -tol) || w[i] < -tol) return false;
    if (std::min(s * z[i], w[i]) > tol) return false;
  }
  return true;
}

// The contacts of the LCP answer z, w (k) of W, r that push or touch (z_i > 0, or w_i within
// kZeroSlack of the largest |r_i|) into `on`; true when W on them is singular (redundant rows:
// their split is not unique) and, with `unloaded`, one of them touches without pushing (a vertex
// of the solutions, not their least-norm split). O(k³).
bool redundant_contacts(const Eigen::Ref<const MatrixXd>& W, const Eigen::Ref<const VectorXd>& r,
                        const Eigen::Ref<const VectorXd>& z, const Eigen::Ref<const VectorXd>& w,
                        std::vector<Index>& on, bool unloaded) {
  const Index k = r.size();
  const double roundoff = kZeroSlack * r.cwiseAbs().maxCoeff();
  on.clear();
  bool touches_only = false;
  for (Index i = 0; i < k; ++i) {
    const bool pushes = z[i] > 0.0, touches = w[i] <= roundoff;
    if (pushes || touches) on.push_back(i);
    touches_only = touches_only || (!pushes && touches);
  }
  if (on.size() < 2 || (unloaded && !touches_only)) return false;
  MatrixXd Wa(Index(on.size()), Index(on.size()));
  for (std::size_t i = 0; i < on.size(); ++i)
    for (std::size_t j = 0; j < on.size(); ++j) Wa(Index(i), Index(j)) = W(on[i], on[j]);
  Eigen::CompleteOrthogonalDecomposition<MatrixXd> cod;
  cod.setThreshold(kRedundantPivot);
  cod.compute(Wa);
  return cod.rank() < Wa.rows();
}

// the contacts 0 … k − 1
std::vector<Index> every_contact(Index k) {
  std::vector<Index> on;
  for (Index i = 0; i < k; ++i) on.push_back(i);
  return on;
}

// the contacts whose r_i = (1 + e_i) g'⁻_i is below −kRowResidual of the largest |r_j|: those
// that approach (the others touch at rest, at the roundoff of the impact before — 5e-9 of its
// speeds — or leave)
std::vector<Index> approaching(const Eigen::Ref<const VectorXd>& r) {
  const double roundoff = kRowResidual * r.cwiseAbs().maxCoeff();
  std::vector<Index> on;
  for (Index i = 0; i < r.size(); ++i)
    if (r[i] < -roundoff) on.push_back(i);
  return on;
}
}  // namespace

bool ContactDynamics::solve_contacts(ContactLcp& lcp, const MatrixXd& Mlcp, const VectorXd& r,
                                     Index k, VectorXd& z, VectorXd& w) {
  std::vector<Index> on;
  if (!lcp.solve(Mlcp, r)) {
    // (Lemke and the enumeration found none: the least-norm split of all the contacts pushing,
    // where it solves the LCP)
    for (Index i = 0; i < k; ++i) on.push_back(i);
    return least_norm_lcp(Mlcp, r, on, z, w);
  }
  z = lcp.z();
  w = lcp.w();
  // a contact left unloaded at zero slack at a vertex of redundant contacts: the least-norm split
  // on those and the contacts that push (where the rows are not redundant the solution on them
  // is unique, Lemke's, and stays bit for bit)
  if (!redundant_contacts(Mlcp.topLeftCorner(k, k), r.head(k), z.head(k), w.head(k), on, true))
    return true;
  VectorXd z_split, w_split;
  if (least_norm_lcp(Mlcp, r, on, z_split, w_split)) {
    z = z_split;
    w = w_split;
  }
  return true;
}

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
    : n_(sys.coordinate_count()),
      lcp_(count_unilateral(sys)),
      friction_lcp_(count_unilateral(sys) + friction_variables(sys)) {
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
                              const std::vector<Index>& set, bool for_impact) {
  set_ = set;
  failure_.clear();
  failure_contacts_.clear();
  const Index k = Index(set.size());
  sys.mass_matrix(q, t, ws.callables.get(), M_);
  // the rows of the active bilateral constraints (A_b) and of the contacts in the set (A_c)
  rows_b_ = 0;
  for (Index c = 0; c < sys.constraint_count(); ++c) {
    const Constraint& con = sys.constraint(c);
    if (con.is_unilateral() || !is_active(sys, ws, c, t)) continue;
    if (for_impact && stick_of_set(sys, c)) continue;  // (the impact's friction replaces it)
    con.model().acceleration_form(q, qd, t, ws.scratch[std::size_t(c)].get(),
                                  A_.middleRows(rows_b_, con.rows()),
                                  b_.segment(rows_b_, con.rows()));
    rows_b_ += con.rows();
  }
  A_b_ = A_.topRows(rows_b_);
  // the Cholesky factor of M, or, when M has singular blocks (a quaternion's: singular along u,
  // which its unit-norm row of A_b determines), of M + s NᵀN, N the rows of A_b normalized (s:
  // M's mean diagonal, for the scale). P, the inverse mass with the bilateral rows removed, is the
  // same with either: it maps f to the x of [M A_bᵀ; A_b 0] [x; mu] = [f; 0], where A_b x = 0 makes
  // A_bᵀ A_b x vanish.
  const bool singular = std::any_of(sys.mass_blocks().begin(), sys.mass_blocks().end(),
                                    [](const MassBlock& b) { return b.singular; });
  if (!singular) llt_.compute(M_);
  if (singular || llt_.info() != Eigen::Success) {
    if (rows_b_ == 0) return false;
    // (the rows normalized: a row's scale, the rescaled models' 1e±8, must not swamp M)
    const VectorXd norms = A_b_.rowwise().norm();
    MatrixXd N = A_b_;
    for (Index r = 0; r < rows_b_; ++r) {
      if (norms[r] > 0.0) N.row(r) /= norms[r];
    }
    M_augmented_ = M_;
    M_augmented_.noalias() += M_.diagonal().mean() * (N.transpose() * N);
    llt_.compute(M_augmented_);
    if (llt_.info() != Eigen::Success) return false;
  }
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
  if (rows_b_ > 0) {
    Y_ = llt_.solve(A_b_.transpose());
    cod_.compute(A_b_ * Y_);
  }
  X_ = A_c_.transpose();
  for (Index i = 0; i < k; ++i) X_.col(i) = apply_p(X_.col(i));
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
  // w = (W + F) lambda + (A_c q''_free − b_c)
  r_ = A_c_ * ws.qdd - b_c_;
  failure_ = non_finite(sys, r_);
  if (!failure_.empty()) return false;
  if (sliding_friction(sys, ws, q, qd, t)) {
    const MatrixXd Mlcp = W_ + F_;
    failure_ = painleve(sys, Mlcp, failure_contacts_);
    return failure_.empty() && solve_contacts(lcp_, Mlcp, r_, W_.rows(), lambda_, w_);
  }
  return solve_contacts(lcp_, W_, r_, W_.rows(), lambda_, w_);
}

VectorXd ContactDynamics::apply_p(const VectorXd& f) const {
  // P f = M⁻¹f − Y G_b⁺ A_b M⁻¹f,  Y = M⁻¹A_bᵀ, G_b = A_b Y (least squares: redundant bilateral
  // rows are allowed)
  VectorXd x = llt_.solve(f);
  if (rows_b_ > 0) x -= Y_ * cod_.solve(A_b_ * x);
  return x;
}

bool ContactDynamics::sliding_friction(const System& sys, Workspace& ws,
                                       const Eigen::Ref<const VectorXd>& q,
                                       const Eigen::Ref<const VectorXd>& qd, double t) {
  const Index k = Index(set_.size());
  const auto& fcs = sys.friction_contacts();
  bool any = false;
  for (std::size_t c = 0; c < fcs.size(); ++c) {
    const FrictionContact& fc = fcs[c];
    const auto at = std::find(set_.begin(), set_.end(), fc.normal_constraint);
    // (a sticking contact's friction is its stick constraint's rows, among the bilateral ones)
    if (at == set_.end() || fc.mu <= 0.0 || !ws.nonideal_enabled[std::size_t(fc.force)]) continue;
    const Index i = Index(at - set_.begin());
    // v_rel with the contact's rows (it counts as closed here)
    signed char& override_k = ws.activity_override[std::size_t(fc.normal_constraint)];
    const signed char saved = override_k;
    override_k = 1;
    sliding_velocity(sys, ws, Index(c), q, qd, t, false);
    override_k = saved;
    const Index nc = fc.size();
    const auto v = ws.sliding.col(Index(c)).head(nc);
    const auto hint = ws.slip_hint.col(fc.force);
    const double v2 = v.squaredNorm(), eps2 = fc.eps * fc.eps;
    // the friction per unit N, as the law (CoulombFriction) applies it; none at rest, where the
    // stick/slip events decide
    VectorXd f = VectorXd::Zero(n_);
    const bool hinted =
        hint.squaredNorm() > 0.0 && (v2 <= 1e4 * eps2 || ws.slip_hint_held[std::size_t(fc.force)]);
    if (!hinted && !(v2 > 1e4 * eps2)) continue;
    // N per unit lambda_i: |A_iᵀ lambda_i| = |A_i| lambda_i (Cartesian sliding coordinates), or
    // |A_i·w| / |w|² lambda_i at a contact point (f = Tᵀ f_t there)
    double per_unit = 0.0;
    if (fc.kinematics) {
      if (hinted) {
        add_contact_force(sys, ws, Index(c), fc.mu, hint.head(nc), f);
      } else {
        add_contact_force(sys, ws, Index(c), -fc.mu / std::sqrt(v2 + eps2), v, f);
      }
      per_unit = contact_normal_force(sys, ws, Index(c), A_c_.row(i).transpose());
    } else {
      if (hinted) {
        for (Index j : fc.coordinates) f[j] = fc.mu * hint[j];
      } else {
        const double scale = -fc.mu / std::sqrt(v2 + eps2);
        for (Index r = 0; r < nc; ++r) f[fc.coordinates[std::size_t(r)]] = scale * v[r];
      }
      per_unit = coordinate_normal_force(fc, A_c_.row(i));  // |a_p|
    }
    if (!any) {
      F_.setZero(k, k);
      mu_.setZero(k);
    }
    any = true;
    F_.col(i) += A_c_ * apply_p(per_unit * f);
    mu_[i] = std::max(mu_[i], fc.mu);
  }
  return any;
}

std::string ContactDynamics::non_finite(const System& sys, const VectorXd& r) const {
  if (W_.allFinite() && r.allFinite()) return "";
  std::string names;
  for (Index c : set_) names += (names.empty() ? "'" : ", '") + sys.constraint(c).name() + "'";
  return "the contact rows of " + names +
         " are not finite (NaN or Inf) at this state, so no contact force can be found; a disk "
         "contact whose disk lies flat on its plane (|n·a| = 1) has no single lowest point there "
         "(docs/contact.md, \"Contacts on bodies\"): model a disk that may land flat with point "
         "contacts on its rim";
}

std::string ContactDynamics::painleve(const System& sys, const MatrixXd& Mlcp,
                                      std::vector<Index>& at) const {
  const Index k = Mlcp.rows();
  const double scale = std::max(W_.cwiseAbs().maxCoeff(), 1e-300);
  // the smallest set of contacts whose principal minor is negative (beyond roundoff)
  const Index subsets = k <= kMinorsUpTo ? (Index(1) << k) : 0;
  std::vector<Index> worst;
  double worst_minor = 0.0;
  auto consider = [&](const std::vector<Index>& J) {
    MatrixXd S(Index(J.size()), Index(J.size()));
    for (std::size_t a = 0; a < J.size(); ++a)
      for (std::size_t b = 0; b < J.size(); ++b) S(Index(a), Index(b)) = Mlcp(J[a], J[b]);
    const double minor = S.determinant() / std::pow(scale, double(J.size()));
    if (minor < -1e-10 && (worst.empty() || J.size() < worst.size())) {
      worst = J;
      worst_minor = minor;
    }
  };
  for (Index i = 0; i < k; ++i) consider({i});
  for (Index mask = 1; worst.empty() && mask < subsets; ++mask) {
    std::vector<Index> J;
    for (Index i = 0; i < k; ++i)
      if (mask & (Index(1) << i)) J.push_back(i);
    if (J.size() > 1) consider(J);
  }
  at.clear();
  if (worst.empty()) return {};
  std::string names;
  for (Index i : worst) {
    at.push_back(set_[std::size_t(i)]);
    names += (names.empty() ? "'" : ", '") + sys.constraint(set_[std::size_t(i)]).name() +
             "' (mu = " + format_number(mu_[i], 4) + ")";
  }
  std::string critical;
  if (worst.size() == 1) {
    // W_ii + mu F_ii/mu: the coefficient at which its effective compliance vanishes
    const Index i = worst[0];
    if (mu_[i] > 0.0 && F_(i, i) < 0.0)
      critical = "; for this contact's angle the critical mu is " +
                 format_number(-W_(i, i) * mu_[i] / F_(i, i), 4);
  }
  return "Painlevé's paradox at the contact" + std::string(worst.size() > 1 ? "s " : " ") + names +
         ": with its sliding friction the contact problem (the LCP of the normal forces) has no "
         "solution or several — the friction turns the contact's effective normal compliance "
         "negative (principal minor " +
         format_number(worst_minor, 3) + " of the normalized W + F)" + critical +
         ". Rigid-body contact with Coulomb friction is inconsistent or indeterminate here: lower "
         "mu, or model the contact as compliant (docs/contact.md, \"Painlevé\")";
}

bool ContactDynamics::stick_of_set(const System& sys, Index c) const {
  for (const FrictionContact& fc : sys.friction_contacts()) {
    if (fc.stick_constraint == c &&
        std::find(set_.begin(), set_.end(), fc.normal_constraint) != set_.end())
      return true;
  }
  return false;
}

bool ContactDynamics::impact(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                             Eigen::Ref<VectorXd> qd, double t,
                             const Eigen::Ref<const VectorXd>& v_minus,
                             const Eigen::Ref<const VectorXd>& e) {
  const Index k = Index(set_.size());
  friction_impulse_.setZero(k);
  const bool friction = impact_friction(sys, ws, q, qd, t, v_minus);
  const Index nb = friction ? D_.cols() : 0;
  PD_.resize(n_, nb);
  for (Index b = 0; b < nb; ++b) PD_.col(b) = apply_p(D_.col(b));
  beta_.setZero(nb);
  // the laws: a Newton contact keeps w = g'⁺ + e g'⁻ >= 0 throughout, a Poisson contact takes
  // e = 0 in the compression phase and e times its compression impulse in the restitution phase
  VectorXd e_newton = e, e_poisson = VectorXd::Zero(k);
  for (Index i = 0; i < k; ++i) {
    if (e[i] > 0.0 &&
        restitution_law(sys.constraint(set_[std::size_t(i)])) == RestitutionLaw::kPoisson) {
      e_poisson[i] = e[i];
      e_newton[i] = 0.0;
    }
  }
  const VectorXd qd_minus = qd;
  // compression (the whole impact when no contact follows Poisson):
  //   w = W Λ + (1 + e_N) v⁻  (= g'⁺ + e_N g'⁻),  with friction from v_rel⁻
  VectorXd r = (VectorXd::Ones(k) + e_newton).cwiseProduct(v_minus);
  failure_ = non_finite(sys, r);
  if (!failure_.empty()) return false;
  if (!impulse(sys, qd, r, friction ? VectorXd(vt_minus_) : VectorXd(), VectorXd::Zero(k)))
    return false;
  if (!e_poisson.isZero()) {
    // restitution (Poisson): each Poisson contact's impulse e Λ_c (Λ_c its compression impulse),
    // and more where a gap would still close or a Newton contact's law asks for it:
    //   Λ = e_P Λ_c + Λ',  w = W Λ' + (g'₀ + e_N g'⁻) >= 0,
    //   the cone Σ β <= mu |A_i| (e_P Λ_c + Λ')
    // with g'₀, v_rel₀ the velocities after the impulse e_P Λ_c
    const VectorXd lambda_c = lambda_, extra = e_poisson.cwiseProduct(lambda_c);
    qd += X_ * extra;
    r = v_minus + A_c_ * (qd - qd_minus) + e_newton.cwiseProduct(v_minus);
    VectorXd vt;
    if (friction) vt = vt_minus_ + D_.transpose() * (qd - qd_minus);
    if (!impulse(sys, qd, r, vt, extra)) return false;
    lambda_ += lambda_c + extra;
  }
  // g'⁺ = g'⁻ + A_c (q'⁺ − q'⁻) (one phase: g'⁻ + W Λ + A_c P D β, as ever)
  if (e_poisson.isZero()) {
    v_after_ = v_minus + W_ * lambda_;
    if (nb > 0) v_after_ += A_c_ * (PD_ * beta_);
  } else {
    v_after_ = v_minus + A_c_ * (qd - qd_minus);
  }
  // each contact's friction impulse |D β| (on its sliding coordinates)
  for (Index f = 0; f < Index(cone_mu_.size()); ++f) {
    VectorXd sum = VectorXd::Zero(n_);
    for (Index b = 0; b < nb; ++b)
      if (direction_cone_[std::size_t(b)] == f) sum += beta_[b] * D_.col(b);
    friction_impulse_[cone_contact_[std::size_t(f)]] += sum.norm();
  }
  return true;
}

void ContactDynamics::hold(Eigen::Ref<VectorXd> qd, const Eigen::Ref<const VectorXd>& qd_minus,
                           const std::vector<Index>& rows, const VectorXd& still) {
  if (rows.empty()) return;
  // the held contacts' normal rows, then the friction directions of their cones that stick
  // (every direction's |v_t⁺| <= the contact's still speed): a held group at rest, not sliding
  // off at the speed its normal impulse gives (a rocking block's centre, h ω)
  std::vector<Index> directions;
  VectorXd vt;
  const bool friction = beta_.size() > 0 && beta_.size() == D_.cols();
  if (friction) {
    vt = vt_minus_ + D_.transpose() * (qd - qd_minus);
    for (Index f = 0; f < Index(cone_contact_.size()); ++f) {
      const auto at = std::find(rows.begin(), rows.end(), cone_contact_[std::size_t(f)]);
      if (at == rows.end()) continue;
      std::vector<Index> own;
      bool sticks = true;
      for (Index b = 0; b < D_.cols(); ++b) {
        if (direction_cone_[std::size_t(b)] != f) continue;
        own.push_back(b);
        sticks = sticks && std::abs(vt[b]) <= still[*at];
      }
      if (sticks) directions.insert(directions.end(), own.begin(), own.end());
    }
  }
  const Index r = Index(rows.size()), d = Index(directions.size());
  MatrixXd J(r + d, n_), PJ(n_, r + d);
  VectorXd v(r + d);
  for (Index a = 0; a < r; ++a) {
    J.row(a) = A_c_.row(rows[std::size_t(a)]);
    v[a] = v_after_[rows[std::size_t(a)]];
  }
  for (Index a = 0; a < d; ++a) {
    J.row(r + a) = D_.col(directions[std::size_t(a)]).transpose();
    v[r + a] = vt[directions[std::size_t(a)]];
  }
  for (Index c = 0; c < r + d; ++c) PJ.col(c) = apply_p(J.row(c).transpose());
  MatrixXd W = J * PJ;
  W = 0.5 * (W + W.transpose()).eval();
  const VectorXd impulse = Eigen::CompleteOrthogonalDecomposition<MatrixXd>(W).solve(-v);
  const VectorXd dqd = PJ * impulse;
  qd += dqd;
  v_after_ += A_c_ * dqd;
  for (Index a = 0; a < r; ++a) lambda_[rows[std::size_t(a)]] += impulse[a];
  // (the friction's share: each cone's |Σ β_b D_b| on its contact)
  for (Index f = 0; f < Index(cone_contact_.size()) && d > 0; ++f) {
    VectorXd sum = VectorXd::Zero(n_);
    for (Index a = 0; a < d; ++a)
      if (direction_cone_[std::size_t(directions[std::size_t(a)])] == f)
        sum += impulse[r + a] * D_.col(directions[std::size_t(a)]);
    friction_impulse_[cone_contact_[std::size_t(f)]] += sum.norm();
  }
}

bool ContactDynamics::impulse(const System& sys, Eigen::Ref<VectorXd> qd, const VectorXd& r,
                              const VectorXd& vt, const VectorXd& offset) {
  const Index k = Index(set_.size());
  if (vt.size() == 0) {
    // frictionless: w = W Λ + r, 0 <= Λ ⊥ w >= 0;  q' += P A_cᵀ Λ, each contact's impulse in the
    // unit of its row, Λ_i = d_i Λ'_i, d_i = 10 / class(‖A_c,i‖) (S W S, S r, w = S⁻¹ w': a gap
    // row × 1e8 gave W of 1e16); d = 1 in SI units, and then nothing is scaled
    VectorXd d = VectorXd::Ones(k);
    for (Index i = 0; i < k; ++i) d[i] = 10.0 / scale_class(A_c_.row(i).norm());
    if ((d.array() != 1.0).any()) {
      if (!solve_contacts(lcp_, d.asDiagonal() * W_ * d.asDiagonal(), d.cwiseProduct(r), k, lambda_,
                          w_))
        return false;
      lambda_ = d.cwiseProduct(lambda_);
      w_ = w_.cwiseQuotient(d);
    } else if (!solve_contacts(lcp_, W_, r, k, lambda_, w_)) {
      return false;
    }
    qd += X_ * lambda_;
    return true;
  }
  // with friction (Anitescu–Potra): z = (Λ, β, γ), the friction impulse D β along the ±tangents
  //   w_Λ = W Λ + A_c P D β + r                          (r = (1 + e) v⁻ for Newton's law)
  //   w_β = Dᵀ P A_cᵀ Λ + Dᵀ P D β + E γ + v_rel         (γ: the sliding speed after)
  //   w_γ = μ̃ (Λ + offset) − Eᵀ β                        (the cone: Σ β <= mu |A_i| Λ_i)
  const Index nb = D_.cols(), nf = Index(cone_mu_.size()), size = k + nb + nf;
  MatrixXd Mlcp = MatrixXd::Zero(size, size);
  VectorXd rr = VectorXd::Zero(size);
  Mlcp.topLeftCorner(k, k) = W_;
  Mlcp.block(0, k, k, nb) = A_c_ * PD_;
  Mlcp.block(k, 0, nb, k) = D_.transpose() * X_;
  Mlcp.block(k, k, nb, nb) = D_.transpose() * PD_;
  for (Index b = 0; b < nb; ++b) {
    const Index f = direction_cone_[std::size_t(b)];
    Mlcp(k + b, k + nb + f) = 1.0;
    Mlcp(k + nb + f, k + b) = -1.0;
  }
  for (Index f = 0; f < nf; ++f) {
    const Index i = cone_contact_[std::size_t(f)];
    const double mu_i = cone_mu_[std::size_t(f)] * cone_normal_[std::size_t(f)];
    Mlcp(k + nb + f, i) = mu_i;
    rr[k + nb + f] = mu_i * offset[i];
  }
  rr.head(k) = r;
  rr.segment(k, nb) = vt;
  // the LCP in z = S z', w' = S w, M' = S M S (a congruence: the same LCP, its blocks of order one
  // in any units and under any factor of the rows):
  //   Λ_i = d_i Λ'_i, row i × d_i,   d_i = √(10 / class(W_ii))
  //   β_b = f_c β'_b, row b × f_c,   f_c = √(10 / class(max (Dᵀ P D)_bb of b's cone c))
  //   γ_c = γ'_c / f_c, cone row c × 1 / f_c   (E and −Eᵀ stay ±1, μ̃ becomes μ̃ d_i / f_c)
  // every w' and z' then a √(mass) × speed. A row's factor ρ (a row written in other units, the
  // metamorphic suite's rows × 1e±8) is a congruence of the same kind (W_ii × ρ², its coupling
  // to β, its μ̃ and r × ρ, Λ / ρ), which d_i undoes to within a class; Λ scaled alone (its row
  // not: Λ_i = c_i Λ'_i, c_i = 10 / class(W_ii)) left each normal row of w' ρ times the rest
  // and Λ' ρ times β'. d = f = 1 where the blocks are of order 1, as in SI units: then nothing is
  // scaled
  VectorXd S = VectorXd::Ones(size);
  for (Index i = 0; i < k; ++i) S[i] = std::sqrt(10.0 / scale_class(W_(i, i)));
  VectorXd cone_top = VectorXd::Zero(nf);
  for (Index b = 0; b < nb; ++b) {
    double& top = cone_top[direction_cone_[std::size_t(b)]];
    top = std::max(top, Mlcp(k + b, k + b));
  }
  for (Index f = 0; f < nf; ++f) S[k + nb + f] = 1.0 / std::sqrt(10.0 / scale_class(cone_top[f]));
  for (Index b = 0; b < nb; ++b) S[k + b] = 1.0 / S[k + nb + direction_cone_[std::size_t(b)]];
  const bool equilibrated = (S.array() != 1.0).any();
  if (equilibrated) {
    Mlcp = S.asDiagonal() * Mlcp * S.asDiagonal();
    rr = S.cwiseProduct(rr);
  }
  VectorXd z, w;
  std::vector<Index> on;
  if (!solve_contacts(friction_lcp_, Mlcp, rr, k, z, w)) {
    // (Siconos found none: each contact sticking or sliding, the approaching ones pushing — a
    // rocking box's landing edge, its other edge leaving —, else all of them)
    if (!friction_split(Mlcp, rr, approaching(rr.head(k)), z, w) &&
        !friction_split(Mlcp, rr, every_contact(k), z, w)) {
      failure_ = unsolved_impact(sys, Mlcp.topLeftCorner(k, k));
      return false;
    }
  } else if (redundant_contacts(Mlcp.topLeftCorner(k, k), rr.head(k), z.head(k), w.head(k), on,
                                false)) {
    // (redundant contacts, Lemke's answer one of many: its friction impulses, on some corners
    // only, may turn the body — a box landing flat while it slides took up a yaw; the least-norm
    // split where each contact sticks or slides, when one solves the LCP)
    VectorXd z_split, w_split;
    if (friction_split(Mlcp, rr, on, z_split, w_split)) {
      z = z_split;
      w = w_split;
    }
  }
  if (!complementary_rows(Mlcp, rr, z)) {
    // (an answer that fails the LCP row by row, though the whole-vector test relative to ‖z‖
    // took it: Lemke ended on a degenerate pivot — the perpendicular tangent's v_rel⁻ roundoff
    // of 0 — with γ ~ 1e17 and a normal row both pushing and separating, the landing of rows
    // × 1e8 with the pyramid along the slip; then each contact sticking or sliding, all pushing)
    if (!friction_split(Mlcp, rr, approaching(rr.head(k)), z, w) &&
        !friction_split(Mlcp, rr, every_contact(k), z, w)) {
      failure_ = unsolved_impact(sys, Mlcp.topLeftCorner(k, k));
      return false;
    }
  }
  if (equilibrated) {
    z = S.cwiseProduct(z);
    w = w.cwiseQuotient(S);
  }
  lambda_ = z.head(k);
  w_ = w.head(k);
  const VectorXd beta = z.segment(k, nb);
  beta_ += beta;
  qd += X_ * lambda_ + PD_ * beta;
  return true;
}

bool ContactDynamics::friction_split(const MatrixXd& Mlcp, const VectorXd& rr,
                                     const std::vector<Index>& pushing, VectorXd& z,
                                     VectorXd& w) const {
  const Index k = Index(set_.size()), nb = Index(direction_cone_.size());
  const Index nf = Index(cone_mu_.size());
  // each cone's directions against the sliding velocity before (v_rel⁻ · d_b < 0), the most
  // against first: one for a single tangent, up to two for a pyramid
  std::vector<std::vector<Index>> against(static_cast<std::size_t>(nf));
  for (Index b = 0; b < nb; ++b) {
    if (!(rr[k + b] < 0.0)) continue;
    auto& a = against[std::size_t(direction_cone_[std::size_t(b)])];
    a.insert(std::find_if(a.begin(), a.end(), [&](Index o) { return rr[k + o] > rr[k + b]; }), b);
  }
  // each cone's choices (a cone whose contact does not push, or that was at rest, has none: no
  // friction impulse): slide along its most-against direction (that direction's slack and the
  // cone's zero), slide along the edge of its two (both slacks zero), or stick (the slacks of
  // its directions against zero and γ = 0: v_t⁺ = 0)
  // — and a cone that was at rest before (no direction against: a rocking box's landing corner,
  // whose velocity is along its normal) may still need an impulse to stay at rest: it sticks
  // with all its directions (`every`), each pair of opposite ones folded into one impulse
  // (least_norm_lcp's `opposite`), as may a cone with a direction against, last
  struct Choice {
    std::size_t directions;
    bool slides;
    bool every = false;
  };
  std::vector<std::vector<Index>> all(static_cast<std::size_t>(nf));
  for (Index b = 0; b < nb; ++b) all[std::size_t(direction_cone_[std::size_t(b)])].push_back(b);
  std::vector<std::vector<Choice>> choices(static_cast<std::size_t>(nf));
  for (Index f = 0; f < nf; ++f) {
    const std::size_t n = against[std::size_t(f)].size();
    if (std::find(pushing.begin(), pushing.end(), cone_contact_[std::size_t(f)]) == pushing.end())
      continue;
    auto& c = choices[std::size_t(f)];
    if (n > 0) {
      c.push_back({1, true});
      if (n == 2) c.push_back({2, true});
      c.push_back({n, false});
    }
    c.push_back({all[std::size_t(f)].size(), false, true});
  }
  // the answer's adjustments: a pair of opposite directions both on (a cone that sticks with
  // every direction; they come in pairs, +u then −u: impact_friction) folded into one
  // nonnegative impulse, the same impulse and the same w but the cone's Σ β (z_b − z_b' kept);
  // the sliding speed γ of a cone whose contact leaves (Λ = 0, no friction impulse, its cone
  // row w_γ = 0) the largest −w_b of its directions, so that w_b = D_bᵀ v⁺ + γ >= 0 — the
  // tangential speed it leaves with
  const auto adjust = [&](VectorXd& zc) {
    for (Index b = 0; b < nb; ++b) {
      if (zc[k + b] >= 0.0) continue;
      zc[k + (b ^ 1)] -= zc[k + b];
      zc[k + b] = 0.0;
    }
    VectorXd wc;
    for (Index f = 0; f < nf; ++f) {
      if (zc[cone_contact_[std::size_t(f)]] != 0.0 || zc[k + nb + f] != 0.0) continue;
      if (wc.size() == 0) wc = Mlcp * zc + rr;
      double speed = 0.0;
      for (const Index b : all[std::size_t(f)]) speed = std::max(speed, -wc[k + b]);
      zc[k + nb + f] = speed;
    }
  };
  // the least-norm solution with those slacks zero, when it solves the LCP
  std::vector<Index> on;
  auto attempt = [&](const std::vector<std::size_t>& pick) {
    on = pushing;
    for (Index f = 0; f < nf; ++f) {
      if (choices[std::size_t(f)].empty()) continue;
      const Choice& c = choices[std::size_t(f)][pick[std::size_t(f)]];
      const auto& list = c.every ? all[std::size_t(f)] : against[std::size_t(f)];
      for (std::size_t j = 0; j < c.directions; ++j) on.push_back(k + list[j]);
      if (c.slides) on.push_back(k + nb + f);
    }
    return least_norm_lcp(Mlcp, rr, on, z, w, adjust);
  };
  // the same choice for every cone first (a body landing flat on redundant contacts: the
  // symmetric split; the edge where a cone has one direction against is its one direction),
  // then every mixture (up to kMixedCones cones)
  std::vector<std::size_t> pick(static_cast<std::size_t>(nf), 0);
  for (const int uniform : {0, 1, 2}) {
    for (std::size_t f = 0; f < pick.size(); ++f) {
      const std::size_t n = choices[f].size();
      if (n == 0)
        pick[f] = 0;
      else if (uniform == 2)
        pick[f] = n == 1 ? 0 : n - 2;  // (sticks; a cone at rest before: with every direction)
      else
        pick[f] = uniform == 1 && n == 4 ? 1 : 0;  // (the edge, or the one direction)
    }
    if (attempt(pick)) return true;
  }
  if (nf > kMixedCones) return false;
  std::fill(pick.begin(), pick.end(), 0);
  for (;;) {
    // (the next mixture, as the digits of a counter)
    std::size_t f = 0;
    while (f < pick.size() && ++pick[f] >= std::max<std::size_t>(choices[f].size(), 1))
      pick[f++] = 0;
    if (f == pick.size()) return false;
    if (attempt(pick)) return true;
  }
}

std::string ContactDynamics::unsolved_impact(const System& sys, const MatrixXd& W) const {
  std::string names;
  for (Index c : set_) names += (names.empty() ? "'" : ", '") + sys.constraint(c).name() + "'";
  Eigen::CompleteOrthogonalDecomposition<MatrixXd> cod;
  cod.setThreshold(kRedundantPivot);
  cod.compute(W);
  const Index k = W.rows(), size = k + D_.cols() + Index(cone_mu_.size());
  return "the impact's LCP with friction at the contacts " + names + " has no solution (" +
         std::to_string(size) + " variables: Siconos lcp_lexicolemke" +
         (size <= ContactLcp::kMaxEnumerated ? std::string(" and the enumeration") : "") + ")" +
         (cod.rank() < k ? ", their rows redundant (rank " + std::to_string(cod.rank()) + " of " +
                               std::to_string(k) + ")"
                         : std::string()) +
         ", nor does the least-norm split with each contact sticking or sliding along its "
         "pyramid's directions against its tangential velocity (docs/contact.md, \"Not done "
         "yet\")";
}

bool ContactDynamics::impact_friction(const System& sys, Workspace& ws,
                                      const Eigen::Ref<const VectorXd>& q,
                                      const Eigen::Ref<const VectorXd>& qd, double t,
                                      const Eigen::Ref<const VectorXd>& v_minus) {
  const auto& fcs = sys.friction_contacts();
  std::vector<VectorXd> directions;
  std::vector<double> vt;
  direction_cone_.clear();
  cone_contact_.clear();
  cone_mu_.clear();
  cone_normal_.clear();
  for (std::size_t c = 0; c < fcs.size(); ++c) {
    const FrictionContact& fc = fcs[c];
    const auto at = std::find(set_.begin(), set_.end(), fc.normal_constraint);
    if (at == set_.end() || !(fc.mu > 0.0)) continue;
    const Index i = Index(at - set_.begin());
    // v_rel and the contact's normals on its sliding coordinates (it counts as closed here)
    signed char& override_k = ws.activity_override[std::size_t(fc.normal_constraint)];
    const signed char saved = override_k;
    override_k = 1;
    const Index normals = sliding_velocity(sys, ws, Index(c), q, qd, t, false);
    override_k = saved;
    const Index nc = fc.size();
    const VectorXd v = ws.sliding.col(Index(c)).head(nc);
    // the cone's N per unit impulse: |A_i·w| / |w|² at the contact point (w = J_Pᵀ n_W), |A_i|
    // on the coordinate path — g'⁻_i / N_i is then the approach speed in the unit of v_rel
    const double per_unit = fc.kinematics
                                ? contact_normal_force(sys, ws, Index(c), A_c_.row(i).transpose())
                                : coordinate_normal_force(fc, A_c_.row(i));  // |a_p|
    // an orthonormal basis of the tangent space, ±each a direction of the friction impulse: the
    // cone exactly for one tangent, a four-sided pyramid for two. On the contact-point path the
    // tangents t_j of the contact plane (f ↦ Tᵀ f), on the coordinate path the sliding
    // coordinates less the normals; the slip before first when it is more than rounding against
    // the approach speed (a pyramid with an axis along the slip: exact for an impact that slides
    // through, and inside the cone, so never creating energy, for any other)
    std::vector<VectorXd> tangents;
    const double slip = v.norm();
    if (nc > 1 && slip > kAlignedSlip * std::abs(v_minus[i]) / per_unit && slip > 0.0)
      tangents.push_back(v / slip);
    for (Index j = 0; j < nc && Index(tangents.size()) < nc; ++j) {
      VectorXd e = VectorXd::Unit(nc, j);
      if (!fc.kinematics) remove_normals(ws, normals, e);
      for (int pass = 0; pass < 2; ++pass)
        for (const auto& u : tangents) e -= e.dot(u) * u;
      if (e.norm() > 1e-10) tangents.push_back(e / e.norm());
    }
    if (tangents.empty()) continue;
    const Index f = Index(cone_mu_.size());
    cone_mu_.push_back(fc.mu);
    cone_normal_.push_back(per_unit);
    cone_contact_.push_back(i);
    for (const auto& u : tangents) {
      for (const double sign : {1.0, -1.0}) {
        VectorXd d = VectorXd::Zero(n_);
        if (fc.kinematics) {
          add_contact_force(sys, ws, Index(c), sign, u, d);
        } else {
          for (Index r = 0; r < nc; ++r) d[fc.coordinates[std::size_t(r)]] = sign * u[r];
        }
        directions.push_back(std::move(d));
        vt.push_back(sign * u.dot(v));
        direction_cone_.push_back(f);
      }
    }
  }
  if (directions.empty()) return false;
  D_.resize(n_, Index(directions.size()));
  vt_minus_.resize(Index(vt.size()));
  for (std::size_t b = 0; b < directions.size(); ++b) {
    D_.col(Index(b)) = directions[b];
    vt_minus_[Index(b)] = vt[b];
  }
  return true;
}

}  // namespace ukdyn::detail

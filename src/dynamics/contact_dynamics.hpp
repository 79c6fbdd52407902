// SPDX-License-Identifier: BSD-3-Clause
// The dynamics of unilateral contacts at an event (docs/contact.md): which closed contacts push
// (the LCP of the accelerations) and the velocity jump of an impact (the impulsive fundamental
// equation with Newton's restitution, an LCP for simultaneous impacts). Dense, O(n³) per event:
// events are rare, and nothing here runs in a step.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/QR>

#include "ukdyn/core/system.hpp"
#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/dynamics/workspace.hpp"

namespace ukdyn::detail {

// Forces inactive (ws.activity_override 0) the unilateral constraints whose gap at (q, q', t) is
// open (g > 1e-9), so that checks of a state do not count an open gap as a violation; a
// penetrated contact (g < 0) stays and is reported. Returns how many it released. O(contacts).
Index release_open_contacts(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                            const Eigen::Ref<const VectorXd>& qd, double t);

class ContactDynamics {
 public:
  // the unilateral constraints of sys (their indices: contacts())
  explicit ContactDynamics(const System& sys);

  // System::constraint indices of the unilateral constraints, in declaration order
  const std::vector<Index>& contacts() const { return contacts_; }

  // g and g' of the unilateral constraint k at (q, q', t), whether active or not (its
  // violation: phi and dphi/dt along the motion). Cost: one evaluation of its levels.
  void gap(const System& sys, Workspace& ws, Index k, const Eigen::Ref<const VectorXd>& q,
           const Eigen::Ref<const VectorXd>& qd, double t, double& g, double& gd) const;

  // At (q, q', t), for the unilateral constraints `set` (System indices): M and its Cholesky
  // factor, their rows A_c, the bilateral rows A_b (the active constraints that are not
  // unilateral), X = P A_cᵀ (n × k) with P the inverse mass with A_b eliminated, and the
  // Delassus matrix W = A_c P A_cᵀ (k × k). False when M is not positive definite. O(n³).
  // for_impact: the stick constraints of the Coulomb contacts on the set's contacts are left out
  // of A_b (the impact's friction acts there instead: a contact that sticks may slip or leave).
  bool prepare(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
               const Eigen::Ref<const VectorXd>& qd, double t, const std::vector<Index>& set,
               bool for_impact = false);

  // The contacts of the last prepare() that push: the LCP w = (W + F) lambda + (A_c q''_free −
  // b_c), lambda, w >= 0, wᵀlambda = 0, q''_free the acceleration with the bilateral rows only
  // (forward_dynamics with `set` released: it sees the run's forces, drift control and C), F the
  // gap accelerations of the sliding friction of the contacts (column i: A_c P f_i, f_i the
  // friction per unit lambda_i of the Coulomb contacts on contact i that slide: −mu |A_i| v_rel /
  // |v_rel|, or along their slip hint). lambda into lambda() (k). False when the evaluation or the
  // LCP fails, or when the friction makes W + F lose the P-property (a principal minor < 0:
  // Painlevé's paradox, no solution or several), with failure() naming the contacts and mu.
  // O(n k + 2^k k³) with friction (k <= kMinorsUpTo; the diagonal only beyond), O(n k) without.
  bool accelerations(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                     const Eigen::Ref<const VectorXd>& qd, double t);
  // why the last accelerations() failed, when it was Painlevé's paradox (empty otherwise)
  const std::string& failure() const { return failure_; }
  // the contacts failure() names (System indices): Painlevé's, the smallest set whose principal
  // minor is negative; empty when there is no failure or it names none
  const std::vector<Index>& failure_contacts() const { return failure_contacts_; }
  // contacts up to which every principal minor of W + F is checked (2^k minors)
  static constexpr Index kMinorsUpTo = 10;

  // The impact of the contacts of the last prepare() at (q, q'⁻ = qd, t) (qd replaced by q'⁺),
  // v⁻ = their g' (k) and restitutions e (k): the LCP w = W Λ + (1 + e) v⁻ (w = v⁺ + e v⁻),
  // Λ, w >= 0, wᵀΛ = 0, and q'⁺ = q'⁻ + X Λ (A_b q'⁺ = A_b q'⁻: the bilateral constraints
  // keep their velocities). With Coulomb friction (mu > 0) on contacts of the set, the impulse
  // D β along ±their tangents joins it (Anitescu–Potra: Σ β <= mu |A_i| Λ_i, β > 0 only against
  // the tangential velocity after, which vanishes when the contact sticks): q'⁺ = q'⁻ + X Λ +
  // P D β. The normal impulses into lambda(), the friction impulses' magnitudes into
  // friction_impulse(), g'⁺ into v_after(). False when the LCP fails. O(n² (k + d)) for d
  // directions, plus Lemke on k + d + cones variables.
  // Contacts whose constraint follows Poisson's law (restitution_law(), contact_restitution.hpp)
  // with e > 0
  // take two phases: compression (e = 0: the impulse Λ_c that stops the approach), then
  // restitution, the impulse e Λ_c at once and whatever more the LCP from there needs (w = g'⁺
  // >= 0, the cone on the total normal impulse). lambda() is then the whole normal impulse.
  bool impact(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
              Eigen::Ref<VectorXd> qd, double t, const Eigen::Ref<const VectorXd>& v_minus,
              const Eigen::Ref<const VectorXd>& e);

  // After impact() (q'⁻ = qd_minus): holds the contacts `rows` (positions in its set) at rest,
  // the rest of an accumulation of impacts (ContactEvents, "group rest"): their normal rows at
  // g' = 0 and, on those whose Coulomb cone sticks after the impact (every friction direction's
  // |v_t⁺| <= still[j], the contact's speed of rest), the friction directions at v_t = 0. With J
  // those rows and v their velocities, the impulse Λ' of least norm with
  //   J P Jᵀ Λ' = −v  (COD: redundant rows allowed),  q'⁺ += P Jᵀ Λ',
  // the M-orthogonal projection of q'⁺ onto the rows' tangent space (so T only falls on fixed
  // surfaces); the normal shares are added to lambda() (one may pull: the tiny impulse that
  // stops a corner lifting at 1e-6 of its sequence's speed), the friction's to
  // friction_impulse(), and v_after() updated. O(n² (r + d) + (r + d)³), allocates (events only).
  void hold(Eigen::Ref<VectorXd> qd, const Eigen::Ref<const VectorXd>& qd_minus,
            const std::vector<Index>& rows, const VectorXd& still);

  // ½ q'ᵀ M q' with the M of the last prepare()
  double kinetic_energy(const Eigen::Ref<const VectorXd>& qd) const {
    return 0.5 * qd.dot(M_ * qd);
  }
  // T(q'⁺) − T(q'⁻) = ½ (q'⁺ − q'⁻)ᵀ M (q'⁺ + q'⁻), with the M of the last prepare(): from the
  // jump itself, so that coordinates the impact leaves alone add exactly nothing (a controlled
  // run's auxiliary z', whose ½ z'ᵀz' outgrows the plant's T at large forces, cancelled the
  // difference of the two totals: issue #29 item 2's metamorphic suite, masses × 10⁶). O(n²).
  double kinetic_energy_change(const Eigen::Ref<const VectorXd>& qd_plus,
                               const Eigen::Ref<const VectorXd>& qd_minus) const {
    return 0.5 * (qd_plus - qd_minus).dot(M_ * (qd_plus + qd_minus));
  }
  // The work of the last impact's contact impulses on the velocities relative to the contacts'
  // surfaces, with v⁻ = the contacts' g' before (k) and q'⁻, q'⁺ the velocities around it:
  //   W_c = ½ Λᵀ (g'⁻ + g'⁺) + ½ βᵀ (v_t⁻ + v_t⁺),  v_t⁺ = v_t⁻ + Dᵀ (q'⁺ − q'⁻),
  // what the contacts dissipate (<= 0 for an admissible impact: ½ Λ g'⁻ (1 − e) for one
  // frictionless contact). T⁺ − T⁻ = W_c + the impulsive work of moving surfaces (the gaps' and
  // the friction's explicit time dependence) and of rheonomic bilateral constraints (drives):
  // on fixed surfaces without drives the two agree; a ball hit by a rising table gains kinetic
  // energy while its contact dissipates. O(k + n · directions).
  double contact_work(const Eigen::Ref<const VectorXd>& v_minus,
                      const Eigen::Ref<const VectorXd>& qd_plus,
                      const Eigen::Ref<const VectorXd>& qd_minus) const {
    double w = 0.5 * lambda_.dot(v_minus + v_after_);
    if (beta_.size() > 0 && beta_.size() == D_.cols())
      w += 0.5 * beta_.dot(2.0 * vt_minus_ + D_.transpose() * (qd_plus - qd_minus));
    return w;
  }

  const VectorXd& lambda() const { return lambda_; }    // (k) multipliers or impulses
  const VectorXd& slack() const { return w_; }          // (k) w of the LCP
  const VectorXd& v_after() const { return v_after_; }  // (k) g' after an impact
  // (k) |friction impulse| of each contact in the last impact
  const VectorXd& friction_impulse() const { return friction_impulse_; }
  // (k) the contacts' free gap accelerations A_c q''_free − b_c of the last accelerations(): the
  // scale against which a slack w_i is roundoff (a contact left unloaded at a vertex of redundant
  // contacts, w_i = 0 up to it) or a separation
  const VectorXd& free_gap_acceleration() const { return r_; }

 private:
  // P f (f an n-vector of generalized force): the acceleration it causes with the bilateral rows
  // of the last prepare() held. O(n²) per column.
  VectorXd apply_p(const VectorXd& f) const;
  // the gap accelerations of the contacts' sliding friction per unit multiplier (k × k, into F_),
  // and into mu_ each contact's coefficient (0 without sliding friction). False when none slides.
  bool sliding_friction(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                        const Eigen::Ref<const VectorXd>& qd, double t);
  // one impulsive LCP at the contacts of the last prepare(), from qd (qd += X Λ + P D β): the
  // normal rows w = W Λ + A_c P D β + r (r k); with friction (vt: v_rel along D, else empty) the
  // tangents and the cones Σ β <= mu |A_i| (Λ_i + offset_i), scaled so that its blocks do not
  // depend on the units. Λ into lambda_ and w_, β added into beta_. False when the LCP fails
  // (failure() saying why, with friction).
  bool impulse(const System& sys, Eigen::Ref<VectorXd> qd, const VectorXd& r, const VectorXd& vt,
               const VectorXd& offset);
  // true when constraint c is the stick constraint of a Coulomb contact on a contact of the set
  bool stick_of_set(const System& sys, Index c) const;
  // the tangent directions of the set's Coulomb contacts at (q, q', t) for the impact's friction
  // (D_, their cones, v_rel⁻ along them); false when none has friction. Each contact's first
  // tangent is its slip before, v̂_rel⁻, when |v_rel⁻| > kAlignedSlip |g'⁻_i| / N_i (v_minus: the
  // set's normal rows' velocities g'⁻, N_i their normal per unit: the approach speed), so that
  // an impact that slides through takes Coulomb's μ N-impulse against the slip exactly, in any
  // direction of the contact plane (the pyramid's axes, fixed, gave μ N / √2 on the diagonal)
  bool impact_friction(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                       const Eigen::Ref<const VectorXd>& qd, double t,
                       const Eigen::Ref<const VectorXd>& v_minus);
  // The LCP w = Mlcp z + r (its first k variables the contacts' multipliers or impulses, any
  // others the friction's) by lcp (Siconos: Lemke, else the enumeration), into z and w. Where
  // the contacts' forces are indeterminate (redundant rows, W singular: four coplanar corners of
  // a box) and Lemke leaves some unloaded at zero slack — a vertex, the load on two diagonal
  // corners, about which the box then tips — the least-norm split on the contacts that push
  // and those (the fundamental equation's with all of them active; the friction's variables
  // zero) when it solves the LCP; where Siconos finds no solution, the least-norm split of all
  // k contacts pushing when it solves the LCP. False when none does. O(Lemke + k³).
  static bool solve_contacts(ContactLcp& lcp, const MatrixXd& Mlcp, const VectorXd& r, Index k,
                             VectorXd& z, VectorXd& w);
  // The friction impact's LCP (Mlcp, rr of impulse(), k + directions + cones) of redundant
  // contacts where Siconos finds no solution or leaves a vertex (a box landing flat while it
  // slides: its friction on some corners only turns it): the least-norm solution where the
  // contacts `pushing` are closed and each cone slides along its pyramid direction most against
  // v_rel⁻, or along the edge of its two directions against it, or sticks (v_t⁺ = 0) — every
  // cone the same first (the symmetric split), then each mixture (3^cones, up to kMixedCones
  // cones). Into z and w when one solves the LCP (to 1e-9), else false. O(3^cones size³) at
  // most; allocates (events only).
  bool friction_split(const MatrixXd& Mlcp, const VectorXd& rr, const std::vector<Index>& pushing,
                      VectorXd& z, VectorXd& w) const;
  // cones up to which friction_split tries every mixture of sticking and sliding
  static constexpr Index kMixedCones = 6;
  // the slip before an impact, relative to the approach speed, above which a contact's pyramid
  // of friction directions takes it as its first axis (below: rounding, the fixed axes)
  static constexpr double kAlignedSlip = 1e-6;
  // why the friction impact's LCP of the set (its W scaled as solved) was not solved: the
  // contacts, the variables, whether their rows are redundant
  std::string unsolved_impact(const System& sys, const MatrixXd& W) const;
  // "" when every principal minor of Mlcp is >= 0 (to roundoff), else the Painlevé message
  // naming the contacts of the smallest negative minor, which go into `at` (System indices)
  std::string painleve(const System& sys, const MatrixXd& Mlcp, std::vector<Index>& at) const;
  // "" when W and r are finite, else the message naming the set's contacts (a gap row that is
  // not finite at this state: a disk lying flat on its plane is one)
  std::string non_finite(const System& sys, const VectorXd& r) const;

  std::vector<Index> contacts_;
  std::vector<Index> set_;  // the contacts of the last prepare()
  Index n_ = 0, rows_b_ = 0;
  MatrixXd M_, A_, A_c_, A_b_, X_, W_, Y_, F_, D_, PD_;  // PD_ = P D (n × directions)
  MatrixXd M_augmented_;  // M + s NᵀN (n × n) when M is singular (quaternions), by prepare()
  VectorXd b_, b_c_, r_, lambda_, w_, v_after_, mu_, vt_minus_, friction_impulse_;
  VectorXd beta_;  // (directions) the friction impulses of the last impact, both phases
  std::vector<Index> direction_cone_;  // (directions) the cone of each friction direction
  std::vector<Index> cone_contact_;    // (cones) the contact (position in the set) of each cone
  std::vector<double> cone_mu_;        // (cones) its coefficient
  // (cones) the normal force per unit of its contact's impulse: |A_i| (a Cartesian constraint's
  // sliding coordinates), |A_i·w| / |w|² at a contact point (contact_normal_force)
  std::vector<double> cone_normal_;
  Eigen::LLT<MatrixXd> llt_;
  Eigen::CompleteOrthogonalDecomposition<MatrixXd> cod_;  // of G_b = A_b M⁻¹ A_bᵀ
  std::string failure_;
  std::vector<Index> failure_contacts_;  // the contacts failure_ names (failure_contacts())
  ContactLcp lcp_;
  ContactLcp friction_lcp_;  // (the impacts' LCP with friction)
};

}  // namespace ukdyn::detail

// SPDX-License-Identifier: BSD-3-Clause
// The dynamics of unilateral contacts at an event (docs/contact.md): which closed contacts push
// (the LCP of the accelerations) and the velocity jump of an impact (the impulsive fundamental
// equation with Newton's restitution, an LCP for simultaneous impacts). Dense, O(n³) per event:
// events are rare, and nothing here runs in a step.
#pragma once

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
  bool prepare(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
               const Eigen::Ref<const VectorXd>& qd, double t, const std::vector<Index>& set);

  // The contacts of the last prepare() that push: the LCP w = W lambda + (A_c q''_free − b_c),
  // lambda, w >= 0, wᵀlambda = 0, q''_free the acceleration with the bilateral rows only
  // (forward_dynamics with `set` released: it sees the run's forces, drift control and C).
  // lambda into lambda() (k). False when the evaluation or the LCP fails.
  bool accelerations(const System& sys, Workspace& ws, const Eigen::Ref<const VectorXd>& q,
                     const Eigen::Ref<const VectorXd>& qd, double t);

  // The impact of the contacts of the last prepare() at velocities qd (n, replaced by q'⁺),
  // v⁻ = their g' (k) and restitutions e (k): the LCP w = W Λ + (1 + e) v⁻ (w = v⁺ + e v⁻),
  // Λ, w >= 0, wᵀΛ = 0, and q'⁺ = q'⁻ + X Λ (A_b q'⁺ = A_b q'⁻: the bilateral constraints
  // keep their velocities). The impulses into lambda(), g'⁺ into v_after(). False when the LCP
  // fails.
  bool impact(Eigen::Ref<VectorXd> qd, const Eigen::Ref<const VectorXd>& v_minus,
              const Eigen::Ref<const VectorXd>& e);

  // ½ q'ᵀ M q' with the M of the last prepare()
  double kinetic_energy(const Eigen::Ref<const VectorXd>& qd) const {
    return 0.5 * qd.dot(M_ * qd);
  }
  const VectorXd& lambda() const { return lambda_; }    // (k) multipliers or impulses
  const VectorXd& slack() const { return w_; }          // (k) w of the LCP
  const VectorXd& v_after() const { return v_after_; }  // (k) g' after an impact

 private:
  std::vector<Index> contacts_;
  std::vector<Index> set_;  // the contacts of the last prepare()
  Index n_ = 0, rows_b_ = 0;
  MatrixXd M_, A_, A_c_, A_b_, X_, W_;
  VectorXd b_, b_c_, lambda_, w_, v_after_;
  Eigen::LLT<MatrixXd> llt_;
  ContactLcp lcp_;
};

}  // namespace ukdyn::detail

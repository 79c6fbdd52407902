// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts under control (docs/contact.md, "Contacts under control"; not installed).
// The contacts are the plant's rows: the run decides which are closed (impacts, releases, the LCP
// of the accelerations) and the controller's model holds the same ones closed, so that the
// control force is computed with the closed contacts' reactions in it. When the requirements
// cannot be met with the closed contacts held, the contacts that the requirements lift off are
// opened in the model (the plant then releases them: their multiplier under that control pulls),
// and when meeting the requirements would drive a closed contact's gap shut — it would have to
// pull to hold — the control reports it (a run stops there, naming the contact, the requirement
// and the time).
#pragma once

#include <string>
#include <vector>

#include "ukdyn/control/control.hpp"

namespace ukdyn::control_detail {

class ContactModes {
 public:
  // the unilateral constraints of the controller's model (their System indices)
  explicit ContactModes(const Controller& ctrl);

  // true when the model has unilateral constraints
  bool any() const { return !contacts_.empty(); }

  // the controller's model holds the contacts as the run does: run_modes (the run's
  // Workspace::activity_override, K entries, the plant's constraint indices) copied into the
  // model workspace's overrides for each contact. A null run_modes leaves them as they are.
  // O(contacts).
  void mirror(const std::vector<signed char>* run_modes, ControlWorkspace& cws) const;

  // After compute_control gave `s` at (q, q', t) with the mirrored modes: when the requirements
  // are not met and contacts are closed, the contacts whose gap the requirements open
  // (g'' > 0 under the control computed with them open) are opened in the model and the control
  // is recomputed (cws then holds it, and s its status); those the requirements would drive shut
  // are held. Returns false, with `failure` describing it, when a requirement can be met only if
  // a closed contact pulls: met with the contact open, it drives the contact's gap shut
  // (g'' < 0), and not met with it closed. Cost: nothing while the requirements are met; else up
  // to contacts + 2 evaluations of compute_control.
  bool settle(const Controller& ctrl, ControlWorkspace& cws, const Eigen::Ref<const VectorXd>& q,
              const Eigen::Ref<const VectorXd>& qd, double t, ControlStatus& s,
              std::string& failure);

 private:
  // g'' = A_k q'' − b_k of contact i under the control in cws (its row evaluated afresh)
  double gap_acceleration(const Controller& ctrl, ControlWorkspace& cws, std::size_t i,
                          const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                          double t, double& scale);

  std::vector<Index> contacts_;       // (contacts) System indices of the unilateral constraints
  std::vector<signed char> saved_;    // (contacts) the mirrored overrides, restored after a trial
  std::vector<unsigned char> open_;   // (contacts) opened in the trial
  std::vector<unsigned char> pulls_;  // (contacts) driven shut by the requirements
  MatrixXd row_A_;                    // (1 × n) a contact's row
  VectorXd row_b_;                    // (1)
};

}  // namespace ukdyn::control_detail

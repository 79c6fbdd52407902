// SPDX-License-Identifier: BSD-3-Clause
// Unilateral contacts under control (docs/contact.md, "Contacts under control"; not installed).
// The contacts are the plant's rows: the run decides which are closed (impacts, releases, the LCP
// of the accelerations) and the controller's model holds the same ones closed, so that the
// control force is computed with the closed contacts' reactions in it. When the requirements
// cannot be met with the closed contacts held, which of them stay closed is decided jointly with
// the requirements: the linear complementarity problem of the closed contacts in which the
// requirement rows are equalities (the control makes them hold), eliminated through the
// controlled system's closed form,
//
//   w = W̃ λ + r̃,  λ >= 0, w >= 0, wᵀλ = 0,   W̃ = A_c P (I − K A_r P) A_cᵀ,   r̃ = A_c q''₀ − b_c
//
// (P the model's compliance with the contacts open, K the law's generalized inverse of X = A_r P,
// q''₀ the controlled acceleration with the contacts open), solved by Siconos Numerics' Lemke
// (ContactLcp), or by its enumeration where Lemke misses a solution (W̃ need be neither symmetric
// nor positive semi-definite under a weighted or actuated law). The contacts with λ > 0 stay held
// in the model, the others are opened (the plant then releases them: their multiplier under that
// control pulls). When the problem has no solution — the requirements can be met only if a closed
// contact pulls — the control reports it (a run stops there, naming the contacts, the requirement
// and the time).
//
// Glossary: A_c (k × n), b_c (k) the closed contacts' rows; A_r the requirement rows; λ (k) the
// contacts' multipliers (push when > 0); w (k) their gap accelerations g''.
//
// One class, its stages in files of their own: contact_modes.cpp (mirror, settle and the LCP of
// the closed contacts), contact_modes_slip.cpp (the stick/slip trial), contact_modes_held.cpp
// (the held-contact trials), contact_modes_margins.cpp (whether stuck contacts hold: margins and
// several contacts' split), contact_modes_anticipate.cpp (the event's LCP anticipated).
#pragma once

#include <string>
#include <vector>

#include "simulation/split_margin.hpp"
#include "ukdyn/control/control.hpp"
#include "ukdyn/core/units.hpp"
#include "ukdyn/dynamics/contact.hpp"

namespace ukdyn::control_detail {

// a g'' or a relative acceleration within this fraction of its scale is zero (the requirement
// neither lifts nor presses; no direction to slide in)
inline constexpr double kSignificant = 1e-9;
// the LCP's solution is checked to this fraction of its scale (ContactLcp::solve)
inline constexpr double kLcpTolerance = 1e-9;

class ContactModes {
 public:
  // the unilateral constraints of the controller's model (their System indices)
  explicit ContactModes(const Controller& ctrl);

  // true when the model has unilateral constraints or Coulomb contacts: modes that the run
  // switches and the model follows (mirror)
  bool any() const { return !contacts_.empty() || !frictions_.empty(); }

  // the controller's model holds the contacts as the run does: the run's modes (its
  // Workspace::activity_override, K entries, the plant's constraint indices) copied into the
  // model workspace's overrides for each contact; and each Coulomb contact sticks or slides in
  // the model as in the run: its stick constraint's override, its force's nonideal_enabled,
  // slip_hint column and slip_hint_held (the plant's non-ideal indices: the controlled system
  // keeps them). A stuck contact is then a physical constraint of the model, whose control is
  // computed with it held (a rolling sphere pushed at its centre: F = 7/5 m a), not against the
  // sliding law's regularized friction at v_rel ~ 0, whose slope mu N / eps made the controlled
  // run stiff; a requirement that needs it to slide breaks it (slip, below). A null run leaves
  // them as they are. O(contacts + n · frictions).
  void mirror(const Workspace* run, ControlWorkspace& cws) const;
  // the contacts' part of mirror: run_modes (K entries, the run's activity_override) into the
  // model's overrides for each contact (null: nothing). O(contacts).
  void mirror(const std::vector<signed char>* run_modes, ControlWorkspace& cws) const;

  // After compute_control gave `s` at (q, q', t) with the mirrored modes: when the requirements
  // are not met and contacts are closed, the control is recomputed with the contacts open
  // (q''₀); if it meets the requirements, the LCP above decides which closed contacts stay held
  // (λ > 0) and the control is recomputed with those held and the others open (cws then holds
  // it, s its status; the model's overrides are restored to the run's afterwards). Returns false,
  // with `failure` describing it, when the LCP has no solution: a requirement can be met only if
  // a closed contact pulls. When the requirements are not met with the contacts open either, the
  // held control stands. Cost: nothing while the requirements are met; else 2 or 3 evaluations of
  // compute_control, k solves with P and with the law (O(k n² + k² n)) and, when a gap is driven
  // shut, one LCP solve (Lemke, O(k³), or where it misses, the enumeration, O(2^k k³); Siconos
  // allocates its tableau then).
  // Then, when the requirements are still not met, slip() below, and then hold_sliding().
  bool settle(const Controller& ctrl, ControlWorkspace& cws, const Eigen::Ref<const VectorXd>& q,
              const Eigen::Ref<const VectorXd>& qd, double t, ControlStatus& s,
              std::string& failure);

  // A requirement that needs a stuck contact to slide breaks its stick (docs/contact.md,
  // "Contacts under control"). After settle, when the requirements are not met and Coulomb
  // contacts stick in the model: the control is recomputed with them sliding, first without
  // friction (q''₀: the relative acceleration a_rel the requirements impose on each contact),
  // then with the friction mu N against it (slip_hint = −a_rel/|a_rel|), giving F_s — the
  // closed contacts that already slide at rest (|v_rel| <= eps: released by the run, one corner
  // of a box) with them, their friction too turned against a_rel (u22 02). If F_s
  // meets the requirements, the reaction it would need with the contacts stuck is
  // λ + λ_nonideal + Δλ, Δλ = −G_p⁺ A_p M⁻¹ F_s (the stuck model's project_nonideal), split into
  // each contact's normal force N and holding force H as the run's stick margin splits it. When
  // some |H| exceeds mu_static N — and, with several stuck, no split of their holding forces
  // lies inside every cone either (hold_by_split: the run's test, the minimum-norm split being
  // only one of them) — F_s is the control (cws holds it, s = kOk): the plant, which
  // still holds the stick, then sees its holding force beyond mu_static N, and the run releases
  // the contact (at the start, or at a located event) and slides with the friction F_s assumed.
  // Otherwise static friction holds: the held control stands, not met, and stick_note() says
  // why (no allocation: the note is written when asked for). The model's modes are the mirrored
  // ones afterwards. Cost: nothing while the requirements are met or no contact sticks; else 3 or 4
  // evaluations of compute_control and one project_nonideal (O(n² + n m)), and hold_by_split's
  // where several stick and the minimum-norm split fails (it allocates).
  void slip(const Controller& ctrl, ControlWorkspace& cws, const Eigen::Ref<const VectorXd>& q,
            const Eigen::Ref<const VectorXd>& qd, double t, ControlStatus& s);
  // A requirement that the actuators reach only through a held Coulomb contact (docs/contact.md,
  // "Contacts under control"): a wheel driven by its axle torque alone, whose forward motion the
  // axle moves only through the friction under it. With the contact sliding the actuated
  // coordinates do not move that row (X S = 0 there), so the least-squares control is none and
  // the wheel never turns (u21 02). After slip(), when the requirements are still not met, slip()
  // decided nothing (slipped() == 0) and Coulomb contacts slide in the model on closed contacts
  // (mu_static > 0, their friction on or off): the control is recomputed with them held (their
  // stick constraints on, their friction off), F_h. If F_h meets the requirements it is the
  // control — what the actuators do through those contacts (the rolling torque), which the
  // sliding plant answers with its friction mu N — and the held model's reaction under it,
  // λ + λ_nonideal − G_p⁺ A_p M⁻¹ F_h (reaction_under), is split into each contact's N and
  // holding force H (stuck_margins). Where every one of them is at rest (|v_rel| <= eps) and
  // holds (|H| <= mu_static N) the run sticks them: s = kOk. Otherwise the plant slides on under
  // F_h (the run's stick test refuses a stick with |H| > mu_static N): s, and cws's status,
  // residual, met and rows_not_met, are the sliding evaluation's (the requirement not met), and
  // held_note() names the contacts and the forces. If F_h does not meet them either, the sliding
  // control stands. The model's modes are the mirrored ones afterwards (cws then holds the held
  // model's evaluation, as slip() leaves F_s's). Cost: nothing while the requirements are met or
  // no contact slides; else 1 to 3 evaluations of compute_control, one project_nonideal
  // (O(n² + n m)) and the contacts' sliding velocities (hold_by_split's where several slide).
  void hold_sliding(const Controller& ctrl, ControlWorkspace& cws,
                    const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                    double t, ControlStatus& s);
  // whether the last settle() applied F_h to sliding contacts with the requirements not met
  // (hold_sliding); held_note() then says why in words ("" otherwise): the row, the contacts,
  // |H| against mu_static N and N, and the sliding speed where the stick would hold
  bool held_sliding() const { return held_sliding_; }
  std::string held_note(const Controller& ctrl);

  // what the last slip() decided: 1 the control slides stuck contacts (F_s), −1 static friction
  // holds them (the requirements not met), 0 nothing to decide; stick_note() says it in words
  // (the row, the contacts, |H| against mu_static N; "" for 0)
  int slipped() const { return slipped_; }
  // (where several stuck contacts are held by some split, the note's numbers are those of the
  // split of largest margin, computed when the note is first asked for: max_split_margin to its
  // optimum, about 140 Newton steps)
  std::string stick_note(const Controller& ctrl);
  // the run's units (SimulationOptions::units), for the notes' times and forces
  void set_units(const UnitSystem& units) { units_ = units; }

  // The run's LCP of the accelerations at an event (docs/contact.md, "In a run") evaluates its
  // q''_free with every contact released and treats the control in it as a given force. Its
  // contacts would then push against the control that ignores them. In that evaluation — the
  // run's modes open contacts it held at the previous evaluation — the control anticipates the
  // contact forces: with λ the solution of the LCP above over those contacts, the control force
  // becomes F₀ − K A_r P A_cᵀ λ (the control with them open, answering their forces), so that the
  // run's LCP, which sees W = A_c P A_cᵀ and this force, has the same solution λ. Call after
  // settle with the run's modes (null: nothing). Cost O(contacts) when no contact was released;
  // else the LCP above (O(k n² + k³)). Leaves the control unchanged when λ = 0 or there is no
  // solution (the run's LCP then decides alone). The start's LCP counts as such an evaluation
  // for the contacts that touch (g and g' at roundoff) when the run's modes first open them.
  // Where λ_j is free (a requirement row duplicates contact j's: W̃'s row and column zero, r̃_j
  // = 0), the contact takes its multiplier under the control computed with it held
  // (held_reactions): it carries what the uncontrolled constrained system carries.
  // Where the requirements are not met with those contacts open (s == kRequirementsNotMet: a
  // wheel in the air, whose x its axle torque moves only through the friction under it), the
  // control is the one computed with them held instead (probe_held), when that meets them (s
  // becomes kOk): the run's LCP then closes them under it, as it would under none.
  void anticipate(const Controller& ctrl, ControlWorkspace& cws,
                  const std::vector<signed char>* run_modes, const Eigen::Ref<const VectorXd>& q,
                  const Eigen::Ref<const VectorXd>& qd, double t, ControlStatus& s);

  // The multipliers λ of the closed contacts (k, in the order of the model's unilateral
  // constraints that were closed) of the last LCP settle solved, and which contacts they are
  // (System indices). Empty when the last settle solved none.
  const std::vector<Index>& decided_contacts() const { return decided_; }
  Eigen::Ref<const VectorXd> decided_lambda() const { return lambda_.head(Index(decided_.size())); }

 private:
  // the closed contacts' rows A_c, b_c at (q, q', t) into A_c_, b_c_ (closed_ of them)
  void contact_rows(const Controller& ctrl, ControlWorkspace& cws,
                    const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                    double t);
  // W̃ and r̃ of the closed contacts under the control in cws (computed with them open)
  void controlled_delassus(const Controller& ctrl, ControlWorkspace& cws);
  // anticipate's tie-break: the contacts among the k closed_ ones whose λ the LCP leaves free
  // (W̃'s row and column zero, r̃ at roundoff: a requirement row duplicates the contact's) get
  // their multiplier held under the control computed with them held (the uncontrolled
  // reaction, Gauss law) in lambda_; cws holds the control with them open again afterwards.
  // Cost: nothing unless one is free; else two evaluations of compute_control.
  void held_reactions(const Controller& ctrl, ControlWorkspace& cws,
                      const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                      double t, Index k);
  // anticipate's where the requirements are not met with the k = closed_ touching contacts
  // open: the control with them held (closed, and the sticks of their Coulomb contacts at rest,
  // |v_rel| <= eps, on with the friction off; lifted_ lists those) into cws and s = kOk when it
  // meets them; else the control with them open again, s unchanged. Cost: one or two
  // evaluations of compute_control and the contacts' sliding velocities.
  void probe_held(const Controller& ctrl, ControlWorkspace& cws,
                  const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                  double t, ControlStatus& s);
  // the failure text: `names` pull, the requirement `row` missed by `missed` with them held
  std::string pull_message(const Controller& ctrl, double t, Index row, double missed) const;
  // settle's LCP of the unilateral contacts (settle is it, then slip). The Coulomb contacts
  // still stuck under its control must hold (stuck_hold), else the held control stands and
  // slip() decides
  bool settle_contacts(const Controller& ctrl, ControlWorkspace& cws,
                       const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                       double t, ControlStatus& s, std::string& failure);
  // settle_contacts' modes: the stick of each stuck Coulomb contact whose normal the LCP opens
  // (of the k closed_ ones, λ_j = 0) opened too, its friction off (saved in lifted_, which puts
  // them back)
  void open_lifted_sticks(Workspace& model, Index k);
  // whether the Coulomb contacts that stick in the model's modes (into stuck_) hold under the
  // control in cws (its evaluation's modes): their reaction λ + λ_nonideal − G_p⁺ A_p M⁻¹ Qc
  // into lam_, then stuck_margins. Cost: nothing without stuck contacts; else one
  // project_nonideal (O(n² + n m)) and stuck_margins'
  bool stuck_hold(const Controller& ctrl, ControlWorkspace& cws,
                  const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                  double t);
  // the model's multipliers λ + λ_nonideal under the force F (n, not in cws) into lam_, at the
  // model's evaluation: without sliding friction in the model, λ + λ_nonideal − G_p⁺ A_p M⁻¹ F
  // (false: the evaluation untouched); with it, stages 3 and 4 of the model evaluated again with
  // Q + F, the friction mu N of the N under F (true: the model's evaluation is then that one,
  // to be evaluated again). Cost O(n² + n m), or the model's stages 3 and 4
  bool reaction_under(const Controller& ctrl, ControlWorkspace& cws,
                      const Eigen::Ref<const VectorXd>& F, const Eigen::Ref<const VectorXd>& q,
                      const Eigen::Ref<const VectorXd>& qd, double t);
  // whether the stuck_ contacts hold under the multipliers lam_: each margin mu_static N − |H|
  // >= 0 (stick_margin), or, with several stuck, some split of their holding forces inside
  // every cone (hold_by_split). The ones that do not into released_ (empty when they hold); the
  // least margin and its N and |H| into the note's. Cost O(stuck (n + m)), and hold_by_split's
  // where several stick and the minimum-norm split fails (it allocates)
  bool stuck_margins(const Controller& ctrl, ControlWorkspace& cws,
                     const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                     double t);
  // slip's modes of the stuck contacts stuck_: sliding (friction on with the hint in hints_,
  // or off), or the mirrored ones back (saved in held_); and of those sliding at rest, resting_:
  // their friction on with the hint in hints_ (or off), or the mirrored friction and hint back
  void slide_stuck(Workspace& model, bool friction);
  void hold_stuck(Workspace& model) const;
  // contact j's a_rel = P (q''_c − u') (coordinate path) or T q'' + T' q' (contact point) for
  // the control's q'' in cws, into accel_ (its size returned); its scale (the terms' sum) in
  // `scale`. Evaluates the contact's kinematics (sliding_velocity).
  Index relative_acceleration(const Controller& ctrl, ControlWorkspace& cws, std::size_t j,
                              const Eigen::Ref<const VectorXd>& q,
                              const Eigen::Ref<const VectorXd>& qd, double t, double& scale);
  // contact j's mu_static N − |H| with the multipliers lam_ of the stuck model (its rows as the
  // last evaluation assembled them), split as Run::stick_margin splits the reaction; N into
  // normal_force_, |H| into holding_force_
  double stick_margin(const Controller& ctrl, ControlWorkspace& cws, std::size_t j,
                      const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                      double t);

  // slip()'s test of several stuck contacts whose minimum-norm split fails (released_ not
  // empty): the run's, some split of their holding forces inside every cone under F_s
  // (detail::split_space and detail::max_split_margin, its sign only, on lam_, the closed
  // sliding contacts' N kept); where one holds, released_ is cleared and the note's numbers are
  // left to split_note_numbers (note_split_). Cost: an SVD of the active rows, one of the
  // forces' map, and the barrier method's Newton steps (50 to 65); allocates (split_space).
  void hold_by_split(const Controller& ctrl, ControlWorkspace& cws,
                     const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                     double t);
  // the note's numbers of the last hold_by_split that held: those of the contact least held at
  // the split of largest margin (the lower N of a tie), on space_. Cost: max_split_margin to its
  // optimum
  void split_note_numbers();

  // Some Coulomb contacts' stick overrides and friction switches, saved while a trial overrides
  // them and put back after it: settle_contacts' lifted sticks and probe_held's held ones
  // (lifted_), hold_sliding's held contacts (held_sticks_).
  struct SavedSticks {
    std::vector<std::size_t> which;      // (≤ frictions) positions in frictions_ overridden
    std::vector<signed char> modes;      // (frictions) each one's stick override before
    std::vector<unsigned char> enabled;  // (frictions) each one's nonideal_enabled before
    // sized for `count` Coulomb contacts, none overridden (allocates: the constructor's)
    void reserve(std::size_t count);
    // contact f (`c`) overridden: its stick's override and friction switch saved into which,
    // modes and enabled, then the stick set to `stick` and the friction off. O(1)
    void override_stick(Workspace& model, std::size_t f, const FrictionContact& c,
                        signed char stick);
    // every contact in `which` back to its saved override and friction switch. O(which)
    void restore(Workspace& model, const std::vector<FrictionContact>& frictions) const;
  };

  // the model's Coulomb contacts (System::friction_contacts)
  std::vector<FrictionContact> frictions_;
  std::vector<Index> contacts_;      // (contacts) System indices of the unilateral constraints
  std::vector<signed char> saved_;   // (contacts) the mirrored overrides, restored after a trial
  std::vector<signed char> last_;    // (contacts) the run's modes at the previous anticipate()
  std::vector<signed char> first_;   // (contacts) anticipate() sees its run mode 0 first
  std::vector<Index> closed_;        // (≤ contacts) positions in contacts_ of the closed ones
  std::vector<Index> decided_;       // (≤ contacts) System indices of the last LCP's contacts
  MatrixXd row_A_;                   // (1 × n) a contact's row
  VectorXd row_b_;                   // (1)
  MatrixXd A_c_;                     // (contacts × n) the closed contacts' rows
  VectorXd b_c_;                     // (contacts)
  MatrixXd PAt_;                     // (n × contacts) P A_cᵀ, then P (I − K A_r P) A_cᵀ
  MatrixXd W_;                       // (contacts × contacts) W̃
  VectorXd r_;                       // (contacts) r̃
  VectorXd lambda_;                  // (contacts) λ of the last LCP
  VectorXd req_, Kf_, minv_Kf_, u_;  // (m_r), (n), (n), (actuators) the law's response
  VectorXd scratch_n_;               // (n)
  ContactLcp lcp_;                   // Siconos's Lemke (docs/contact.md, "The LCP solver")
  // slip()'s
  std::vector<std::size_t> stuck_;    // (≤ frictions) positions in frictions_ of the stuck ones
  std::vector<signed char> held_;     // (frictions) their mirrored slip_hint_held
  MatrixXd hints_;                    // (slip_hint rows × frictions) their sliding hints
  MatrixXd held_hints_;               // (slip_hint rows × frictions) their mirrored hints
  VectorXd F_s_;                      // (n) the control with them sliding
  VectorXd lam_;                      // (m) the stuck model's multipliers under F_s
  VectorXd accel_, reaction_, part_;  // (max(n, 2)), (n), (n)
  MatrixXd normals_;                  // (rows of a normal constraint × n)
  std::vector<std::size_t> sliding_;  // (≤ frictions) hold_by_split: the closed ones sliding
  // (≤ frictions) slip(): the closed ones sliding at rest (|v_rel| <= eps), whose friction it
  // turns against the relative acceleration too (slide_stuck), and their mirrored
  // nonideal_enabled (frictions; their hints in held_hints_, held_)
  std::vector<std::size_t> resting_;
  std::vector<unsigned char> resting_enabled_;
  // open_lifted_sticks' sticks it opened, or probe_held's it held, and their modes before
  SavedSticks lifted_;
  detail::SplitSpace space_;  // hold_by_split: the split space of stuck_
  VectorXd split_y_;          // (nz) hold_by_split: the split of largest margin
  double normal_force_ = 0.0, holding_force_ = 0.0;  // of the last stick_margin
  int slipped_ = 0;                                  // see slipped()
  // hold_sliding()'s: the contacts it held and their mirrored stick overrides and friction
  // switches, the sliding evaluation's residual, met and rows_not_met (m_r), the largest |v_rel|
  // of the contacts held, and whether it applied F_h with the requirements not met
  SavedSticks held_sticks_;
  VectorXd slide_residual_;
  std::vector<unsigned char> slide_met_;
  Index slide_not_met_ = 0;
  double held_speed_ = 0.0;
  bool held_sliding_ = false;
  bool note_split_ = false;  // the note's numbers are split_note_numbers' (not yet computed)
  // stick_note()'s: the time, the row not met, the least margin mu_static N − |H| and its N
  // and |H|, the contacts released (positions in frictions_)
  double note_t_ = 0.0, note_margin_ = 0.0, note_N_ = 0.0, note_H_ = 0.0;
  Index note_row_ = 0;
  std::vector<std::size_t> released_;
  UnitSystem units_;  // see set_units
};

}  // namespace ukdyn::control_detail

// SPDX-License-Identifier: BSD-3-Clause
// The control at a controlled run's initial state, as the run's first sample evaluates it (not
// installed): what `ukdyn check` reports of a controlled model with contacts (docs/control.md,
// "Requirements that cannot be met"). The run's start decides which unilateral contacts are
// closed (ContactEvents::start: the touching ones at rest that the LCP of the accelerations, the
// control in it, loads) and which Coulomb contacts stick (Run::initial_contact_modes); the
// controller's model mirrors those modes (ContactModes::mirror) and settles them with the
// requirements (ContactModes::settle), as in every evaluation of the run.
#pragma once

#include <functional>
#include <string>

#include "ukdyn/control/control.hpp"

namespace ukdyn::control_detail {

// What the control does at a run's first sample (its initial state, after the start's impacts,
// contact modes and, with project_initial, its projection).
struct ControlAtStart {
  bool evaluated = false;                     // the run reached its first sample
  ControlStatus status = ControlStatus::kOk;  // the control's status there (after settle)
  // a requirement that needs a closed contact to pull (settle's failure: the run stops there
  // with "the controller failed: " and this text); "" when there is none
  std::string pull_failure;
  std::string description;  // describe_control_status() of the control there ("" when ok)
  std::string unactuated;   // explain_unactuated_requirements() of it
  // why static friction holds a contact a requirement needs to slide, or why a requirement met
  // only with a sliding contact held is not met (ContactModes::held_note)
  std::string stick_note;
  // the control there is the one that meets the requirements with a sliding contact held
  // (ContactModes::hold_sliding), which the run applies with it sliding
  bool held = false;
};

// simulate_controlled (control/control.hpp) whose first sample, when `start` is not null, also
// evaluates the control afresh with the run's contact modes into *start (the run is otherwise
// unchanged: the samples, the statistics and their bits are simulate_controlled's).
ControlledTrajectory run_controlled(
    const Controller& ctrl, const System& plant, const Eigen::Ref<const VectorXd>& q0,
    const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& options,
    const std::function<void(const ControlledTrajectory& sample)>& sample_sink,
    ControlAtStart* start);

// The control at the run's first sample: the run of simulate_controlled(ctrl, plant, q0, qd0,
// options) stopped once its first sample is recorded (SimulationOptions::should_stop), nothing
// kept. Throws what simulate_controlled throws (InconsistentInitialState, std::invalid_argument
// for misuse). Cost: the run's start (set_run_scales, the contacts' start, one evaluation of
// the plant) and 2 to 5 evaluations of compute_control.
ControlAtStart control_at_start(const Controller& ctrl, const System& plant,
                                const Eigen::Ref<const VectorXd>& q0,
                                const Eigen::Ref<const VectorXd>& qd0,
                                const SimulationOptions& options);

}  // namespace ukdyn::control_detail

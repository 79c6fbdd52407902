// SPDX-License-Identifier: BSD-3-Clause
// The run's refusal of a model's contacts at its start (Painlevé's paradox at t_start), located in
// the model file: shared by `ukdyn run` (app/run.cpp) and check_model (modelfile/check.cpp), so
// that both print the same FILE:LINE:COLUMN message.
#pragma once

#include "simulation/contact_events.hpp"
#include "ukdyn/modelfile/model.hpp"

namespace ukdyn::detail {

// `e` of a run of `model`, as a ModelError at the entry of the first contact it names: the
// Coulomb friction's entry on that contact (`nonideal:`, where mu is given) when the file gives
// one, else the contact's own (`contacts:`), else the model's start. The message is
// user_message(e) (no C++ function name). Cost O(contacts + frictions).
ModelError locate_contact_start(const Model& model, const ContactStartError& e);

}  // namespace ukdyn::detail

// SPDX-License-Identifier: BSD-3-Clause
/// @file ukdyn.hpp
/// Everything needed to describe a constrained system, evaluate and simulate its motion.
#pragma once

#include "ukdyn/analysis/linearize.hpp"
#include "ukdyn/control/control.hpp"
#include "ukdyn/core/autodiff.hpp"
#include "ukdyn/core/constraint.hpp"
#include "ukdyn/core/nonideal.hpp"
#include "ukdyn/core/status.hpp"
#include "ukdyn/core/system.hpp"
#include "ukdyn/core/types.hpp"
#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/projection.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/gallery/gallery.hpp"
#include "ukdyn/io/trajectory_files.hpp"
#include "ukdyn/linalg/anderson.hpp"
#include "ukdyn/linalg/decomposition.hpp"
#include "ukdyn/linalg/sparse.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/multibody/multibody.hpp"
#include "ukdyn/simulation/ensemble.hpp"
#include "ukdyn/simulation/options.hpp"
#include "ukdyn/simulation/sampling.hpp"
#include "ukdyn/simulation/simulate.hpp"

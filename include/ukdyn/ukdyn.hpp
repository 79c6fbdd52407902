/// @file ukdyn.hpp
/// Everything needed to describe a constrained system, evaluate and simulate its motion.
#pragma once

#include "ukdyn/autodiff.hpp"
#include "ukdyn/constraint.hpp"
#include "ukdyn/control.hpp"
#include "ukdyn/decomposition.hpp"
#include "ukdyn/forward.hpp"
#include "ukdyn/gallery.hpp"
#include "ukdyn/io.hpp"
#include "ukdyn/model.hpp"
#include "ukdyn/multibody.hpp"
#include "ukdyn/nonideal.hpp"
#include "ukdyn/options.hpp"
#include "ukdyn/projection.hpp"
#include "ukdyn/run.hpp"
#include "ukdyn/simulate.hpp"
#include "ukdyn/sparse.hpp"
#include "ukdyn/status.hpp"
#include "ukdyn/system.hpp"
#include "ukdyn/types.hpp"
#include "ukdyn/workspace.hpp"

// SPDX-License-Identifier: BSD-3-Clause
/// @file modelfile/units.hpp
/// UnitSystem, the units a model file declares (`units: {length: mm, mass: g, time: ms}`), is
/// in core/units.hpp: a run's messages label their numbers with it too.
#pragma once

#include "ukdyn/core/units.hpp"

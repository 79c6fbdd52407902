// SPDX-License-Identifier: BSD-3-Clause
// The headers nearly every test source includes, precompiled once for all test programs
// (tests/CMakeLists.txt, UKDYN_PCH): GoogleTest, Eigen's dense modules and ukdyn's public API.
// Each test source still includes what it uses; this file only makes that cheap.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <ukdyn/reference/reference.hpp>
#include <ukdyn/ukdyn.hpp>

// SPDX-License-Identifier: BSD-3-Clause
// The headers nearly every benchmark includes, precompiled once for all benchmark programs
// (bench/CMakeLists.txt, UKDYN_PCH): Google Benchmark, Eigen's dense modules and ukdyn's public
// API. Each benchmark still includes what it uses; this file only makes that cheap (parsing
// them took 3.7 s of each benchmark's compilation, bench/RESULTS.md "Build time").
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include <Eigen/Dense>

#include <ukdyn/reference/reference.hpp>
#include <ukdyn/ukdyn.hpp>

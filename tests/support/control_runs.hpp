// SPDX-License-Identifier: BSD-3-Clause
// What the tracking-control tests share (control/test_control.cpp, _physical.cpp): the tight
// integration their error dynamics are checked at, and measured values in the test report.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::test {

// records a measured value in the test report (--gtest_output=xml)
inline void record(const std::string& name, double value) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3e", value);
  ::testing::Test::RecordProperty(name, buf);
}

// a tight integration (the error dynamics are then checked to 1e-8)
inline SimulationOptions tight(double t_end, double every = 0.05) {
  SimulationOptions o;
  o.t_end = t_end;
  o.output_every = every;
  o.rtol = 1e-11;
  o.atol = 1e-12;
  return o;
}

}  // namespace ukdyn::test

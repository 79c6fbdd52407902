// SPDX-License-Identifier: BSD-3-Clause
// What the singular-mass tests share (dynamics/test_singular_mass.cpp, _bodies.cpp): the status
// of motion that [M; A] leaves undetermined, and a relative comparison of vectors.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <optional>

#include "ukdyn/core/status.hpp"
#include "ukdyn/core/types.hpp"

namespace ukdyn::test {

// Status::kMotionUndetermined arrives with the implementation: until then this test program
// still compiles (the requires-expression on the dependent S is simply false) and the tests
// that need the status fail on "not declared" instead.
template <class S>
constexpr std::optional<S> motion_undetermined_status() {
  if constexpr (requires { S::kMotionUndetermined; }) {
    return S::kMotionUndetermined;
  } else {
    return std::nullopt;
  }
}
inline const std::optional<Status> kMotionUndetermined = motion_undetermined_status<Status>();

// ‖actual − expected‖ within tol · ‖expected‖ (two-sided: EXPECT_NEAR on the norm)
inline void expect_relative(const Eigen::Ref<const VectorXd>& actual,
                            const Eigen::Ref<const VectorXd>& expected, double tol,
                            const char* what) {
  ASSERT_EQ(actual.size(), expected.size()) << what;
  EXPECT_NEAR((actual - expected).norm(), 0.0, tol * std::max(expected.norm(), 1e-300))
      << what << "\n  actual   " << actual.transpose() << "\n  expected " << expected.transpose();
}

}  // namespace ukdyn::test

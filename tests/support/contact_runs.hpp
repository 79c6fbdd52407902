// SPDX-License-Identifier: BSD-3-Clause
// Test support: reading a run with unilateral contacts — its contact events of one kind at one
// constraint, and the sample at a time the run was asked to output.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "ukdyn/dynamics/contact.hpp"
#include "ukdyn/simulation/simulate.hpp"

namespace ukdyn::testing {

// the events of kind `kind` at constraint k
inline std::vector<ContactEvent> events_of(const Trajectory& tr, Index k, ContactEvent::Kind kind) {
  std::vector<ContactEvent> out;
  for (const auto& e : tr.stats.contact_events) {
    if (e.constraint == k && e.kind == kind) out.push_back(e);
  }
  return out;
}

// the sample of tr at time t (failing when there is none)
inline std::size_t sample_at(const Trajectory& tr, double t) {
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    if (std::abs(tr.t[i] - t) <= 1e-12 * std::max(1.0, std::abs(t))) return i;
  }
  ADD_FAILURE() << "no sample at t = " << t;
  return 0;
}

// A ball (mass m) dropped from rest onto a floor with restitution e, reaching it at t0 with speed
// v0 = g t0: the times of the first `count` apexes, t_k + e^(k+1) v0 / g, t_k the k-th impact
inline std::vector<double> bounce_apex_times(double e, double t0, double g, int count) {
  const double v0 = g * t0;
  double tk = t0;
  std::vector<double> apex_t;
  for (int k = 0; k < count; ++k) {
    apex_t.push_back(tk + std::pow(e, k + 1) * v0 / g);
    tk += 2.0 * std::pow(e, k + 1) * v0 / g;
  }
  return apex_t;
}

// The first `count` impacts of that ball against their closed forms: the k-th at
// t_k = t0 + (2 v0 / g) Σ_{j=1..k} e^j with speed e^k v0 before and e^(k+1) v0 after, the impulse
// m (1 + e) e^k v0 and the energy lost ½ m (1 − e²) (e^k v0)²
inline void expect_bounces(const std::vector<ContactEvent>& impacts, double e, double t0, double g,
                           double m, std::size_t count) {
  ASSERT_GE(impacts.size(), count);
  const double v0 = g * t0;
  double tk = t0;
  for (std::size_t k = 0; k < count; ++k) {
    const double ek = std::pow(e, double(k));
    EXPECT_NEAR(impacts[k].t, tk, 1e-9) << "impact " << k;
    EXPECT_NEAR(impacts[k].speed_before, -ek * v0, 1e-8 * v0) << "impact " << k;
    EXPECT_NEAR(impacts[k].speed_after, e * ek * v0, 1e-8 * v0) << "impact " << k;
    EXPECT_NEAR(impacts[k].impulse, m * (1 + e) * ek * v0, 1e-8) << "impact " << k;
    EXPECT_NEAR(impacts[k].energy_change, -0.5 * m * (1 - e * e) * ek * ek * v0 * v0, 1e-8)
        << "impact " << k;
    tk += 2.0 * e * ek * v0 / g;
  }
}

}  // namespace ukdyn::testing

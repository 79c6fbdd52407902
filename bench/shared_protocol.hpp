// SPDX-License-Identifier: BSD-3-Clause
// The timing protocol of bench/data/README.md, shared by the benchmarks that write its
// result records: one warm-up run, then five timed runs of the stepping loop.
#pragma once

#include <algorithm>
#include <chrono>
#include <vector>

#include <Eigen/Core>

#include <ukdyn/simulation/simulate.hpp>

namespace ukdyn::bench {

/// Wall times of the five timed runs (s) and whether every run ended in the same state, bit for
/// bit, as the warm-up.
struct TimedRuns {
  std::vector<double> wall;
  bool deterministic = true;
  /// The median of wall.
  double median() const {
    std::vector<double> v = wall;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  }
};

/// Runs simulate(sys, q0, qd0, opt) six times: a warm-up, then five timed runs.
inline TimedRuns time_runs(const System& sys, const Eigen::Ref<const VectorXd>& q0,
                           const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& opt) {
  TimedRuns r;
  VectorXd q_first;
  for (int run = 0; run < 6; ++run) {
    const auto t0 = std::chrono::steady_clock::now();
    const Trajectory tr = simulate(sys, q0, qd0, opt);
    const auto t1 = std::chrono::steady_clock::now();
    const VectorXd q_end = Eigen::Map<const VectorXd>(tr.q.data() + tr.q.size() - tr.n, tr.n);
    if (run == 0) {
      q_first = q_end;
    } else {
      r.deterministic = r.deterministic && q_end == q_first;
      r.wall.push_back(std::chrono::duration<double>(t1 - t0).count());
    }
  }
  return r;
}

}  // namespace ukdyn::bench

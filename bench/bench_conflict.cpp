// SPDX-License-Identifier: BSD-3-Clause
// Failures reported in proportion to the work (issue #29 item 4): the constraint-conflict
// diagnosis (find_constraint_conflict) on closed chains of N planar rods, the models of
// ../shared/reproducers/2026-11-28/gen_chain.py generated in memory:
//   Diagnosis/N     find_constraint_conflict at the chain's initial state with its tip pinned
//                   twice, 1 mm apart (a conflict it finds; the sparse engine from n = 24 on, as
//                   Engine::kAuto picks)
//   FailingRun/512  the whole run of perf_defects.sh P-D1: RK4 at h = 2e-3, too large for the
//                   512-link chain, fails after a few steps; the time until it reports
// The diagnosis used a dense QR and JacobiSVD of A (O(n³): 39 s of CPU at N = 512); it now uses
// the sparse engine's rank-revealing LDLᵀ, linear in N (the BigO fit of Diagnosis says so).
#include <string>

#include <benchmark/benchmark.h>

#include <ukdyn/dynamics/projection.hpp>
#include <ukdyn/dynamics/workspace.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/simulation/simulate.hpp>

#include "support/closed_chain.hpp"

namespace {

using ukdyn::test::closed_chain;

void Diagnosis(benchmark::State& state) {
  const int n = int(state.range(0));
  const ukdyn::Model m = ukdyn::parse_model(closed_chain(n, 0.0, 1e-3), "chain.yaml");
  ukdyn::Workspace ws(m.system);
  bool found = false;
  for (auto _ : state) {
    const ukdyn::ConstraintConflict c =
        ukdyn::find_constraint_conflict(m.system, ws, m.q0, m.qd0, 0.0, 1e-10);
    found = c.found;
    benchmark::DoNotOptimize(c.residual);
  }
  state.counters["sparse"] = ws.is_sparse() ? 1 : 0;
  state.counters["found"] = found ? 1 : 0;
  state.SetComplexityN(n);
}
BENCHMARK(Diagnosis)
    ->RangeMultiplier(2)
    ->Range(32, 512)
    ->Unit(benchmark::kMillisecond)
    ->Complexity(benchmark::oN);

void FailingRun(benchmark::State& state) {
  const int n = int(state.range(0));
  const ukdyn::Model m = ukdyn::parse_model(closed_chain(n, 0.0), "chain.yaml");
  ukdyn::SimulationOptions o = m.options;
  o.t_end = 1.0;
  long failed = 0;
  for (auto _ : state) {
    const ukdyn::Trajectory tr = ukdyn::simulate(m.system, m.q0, m.qd0, o);
    failed += tr.stats.status != ukdyn::Status::kOk ? 1 : 0;
    state.counters["t_reached"] = tr.stats.t_reached;
  }
  state.counters["failed"] = double(failed) / double(state.iterations());
}
BENCHMARK(FailingRun)->Arg(512)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();

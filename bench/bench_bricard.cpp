// SPDX-License-Identifier: BSD-3-Clause
// The IFToMM A04 Bricard mechanism (examples/models/bricard.yaml, issue #13 item 1): an
// overconstrained spatial loop (5 rigid bodies, 35 coordinates, 35 rows of rank 34, 1 DOF)
// over the benchmark's 10 s, released at rest under gravity.
//
//   Defaults  dopri5, rtol 1e-9, atol 1e-11, projection (stage states off the constraints take
//             the least-squares q'', counted as least_squares)
//   Rk4       the IFToMM protocol's fixed step h = 1e-3
//   Rkf78     rkf78 at the default tolerances
//   Bdf       CVODE BDF at the default tolerances
//
// Each reports the wall time of a whole run (model loaded once, outside the timing) and the
// counters steps, evaluations, least_squares, rel_energy (max |E − E0| / |E0|, E0 = 29.43 J)
// and closure (largest joint position violation after a step or at a sample, m).
#include <algorithm>
#include <cmath>
#include <string>

#include <benchmark/benchmark.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/simulation/simulate.hpp>

namespace {

const ukdyn::Model& model() {
  static const ukdyn::Model m =
      ukdyn::load_model(std::string(UKDYN_EXAMPLES_DIR) + "/bricard.yaml");
  return m;
}

void run(benchmark::State& state, ukdyn::Integrator method) {
  ukdyn::SimulationOptions o = model().options;
  o.integrator = method;
  ukdyn::Trajectory tr;
  for (auto _ : state) {
    tr = ukdyn::simulate(model().system, model().q0, model().qd0, o);
    if (tr.stats.status != ukdyn::Status::kOk) state.SkipWithError(tr.stats.message.c_str());
    benchmark::DoNotOptimize(tr.q.data());
  }
  const ukdyn::RunStatistics& s = tr.stats;
  double dE = 0.0;
  for (double E : tr.energy) dE = std::max(dE, std::abs(E - tr.energy.front()));
  state.counters["steps"] = double(s.steps);
  state.counters["evaluations"] = double(s.evaluations);
  state.counters["least_squares"] = double(s.least_squares);
  state.counters["rel_energy"] = tr.energy.empty() ? -1.0 : dE / std::abs(tr.energy.front());
  state.counters["closure"] = s.max_position_violation;
}

void BM_Bricard_Defaults(benchmark::State& state) { run(state, ukdyn::Integrator::kDopri5); }
void BM_Bricard_Rk4(benchmark::State& state) { run(state, ukdyn::Integrator::kRK4); }
void BM_Bricard_Rkf78(benchmark::State& state) { run(state, ukdyn::Integrator::kRKF78); }
void BM_Bricard_Bdf(benchmark::State& state) { run(state, ukdyn::Integrator::kBDF); }

BENCHMARK(BM_Bricard_Defaults)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Bricard_Rk4)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Bricard_Rkf78)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Bricard_Bdf)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

// SPDX-License-Identifier: BSD-3-Clause
// A contact that stays closed costs what the bilateral constraint it replaces costs (issue #31
// item 6, docs/contact.md, "Equations"): bench/data/closed_contact/ holds two models, each with
// unilateral contacts and as a twin whose rows are bilateral — the ladder of
// examples/models/ladder_leaves_wall.yaml up to t = 0.45 s (both contacts closed; it leaves the
// wall at 0.4597 s) and a frictionless ball (a rigid body) sliding and spinning on the ground —
// run with the files' default settings (dopri5) and with RK4 at h = 1e-4 s, no samples but the
// run's ends. The twins take the same steps and evaluations (tests/simulation/test_contact.cpp,
// `Contact.AClosedContactRunsAsItsBilateralTwinStepForStep`), so their times compare per step.
//
// Counters: steps, evaluations, and the time per step (`per_step`). bench/RESULTS.md has the
// figures beside the instructions of the same runs by callgrind (`ukdyn run`).
#include <array>
#include <string>

#include <benchmark/benchmark.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/simulation/simulate.hpp>

namespace {

// the model files, by the benchmark's first argument
constexpr std::array<const char*, 4> kFiles = {"ladder_unilateral", "ladder_bilateral",
                                               "ball_unilateral", "ball_bilateral"};

// range(0): the file (kFiles); range(1): 0 the file's settings (dopri5), 1 RK4 at h = 1e-4
void BM_ClosedContact(benchmark::State& state) {
  const std::string file = kFiles[std::size_t(state.range(0))];
  ukdyn::Model m =
      ukdyn::load_model(std::string(UKDYN_BENCH_DATA_DIR) + "/closed_contact/" + file + ".yaml");
  if (state.range(1) == 1) {
    m.options.integrator = ukdyn::Integrator::kRK4;
    m.options.step = 1e-4;
  }
  m.options.output_every = 0.0;
  state.SetLabel(file + (state.range(1) == 1 ? "/rk4" : "/default"));
  ukdyn::RunStatistics s;
  for (auto _ : state) {
    const ukdyn::Trajectory tr = ukdyn::simulate(m.system, m.q0, m.qd0, m.options);
    s = tr.stats;
    if (s.status != ukdyn::Status::kOk) state.SkipWithError(s.message.c_str());
    benchmark::DoNotOptimize(tr.q.data());
  }
  state.counters["steps"] = double(s.steps);
  state.counters["evaluations"] = double(s.evaluations);
  state.counters["per_step"] = benchmark::Counter(
      double(s.steps), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_ClosedContact)->ArgsProduct({{0, 1, 2, 3}, {0, 1}})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

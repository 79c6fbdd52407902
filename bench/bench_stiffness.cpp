// SPDX-License-Identifier: BSD-3-Clause
// The default integrator on a stiff phase (issue #12, item 4: "slider_crank_friction_slow.yaml
// on defaults takes at most 3x the time of BDF"). The slider-crank with regularized slider
// friction (eps 1e-6) slides for ~2.1 s and then rests, where the friction law's slope makes the
// problem stiff: plain dopri5 needs ~1.3 M steps for the 2.9 s at rest.
//
//   Defaults   dopri5 with stiff_switch (switches to BDF when Hairer–Wanner's test fires)
//   Bdf        integrator: bdf throughout
//   PlainDopri5  stiff_switch: false, over the first 2.3 s only (the full 5 s takes ~40 s)
//
// Each reports the wall time of a whole run (model loaded once, outside the timing) and the
// counters steps, evaluations, stiff_switches, stiff_switch_time. The two runs alternate in the
// same process when run with --benchmark_repetitions (the machine is shared and noisy).
#include <string>

#include <benchmark/benchmark.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/simulation/simulate.hpp>

namespace {

const ukdyn::Model& model() {
  static const ukdyn::Model m =
      ukdyn::load_model(std::string(UKDYN_TEST_DATA_DIR) + "/slider_crank_friction_slow.yaml");
  return m;
}

void run(benchmark::State& state, ukdyn::Integrator method, bool stiff_switch, double t_end) {
  ukdyn::SimulationOptions o = model().options;
  o.project_initial = model().project_initial;
  o.integrator = method;
  o.stiff_switch = stiff_switch;
  o.t_end = t_end;
  ukdyn::RunStatistics s;
  for (auto _ : state) {
    const ukdyn::ModelRun r = ukdyn::run_model(model(), o);
    s = r.trajectory.stats;
    if (s.status != ukdyn::Status::kOk) state.SkipWithError(s.message.c_str());
    benchmark::DoNotOptimize(r.trajectory.q.data());
  }
  state.counters["steps"] = double(s.steps);
  state.counters["evaluations"] = double(s.evaluations);
  state.counters["stiff_switches"] = double(s.stiff_switches);
  state.counters["stiff_switch_time"] = s.stiff_switches > 0 ? s.stiff_switch_time : -1.0;
  state.counters["stiff_steps"] = double(s.stiff_steps);
}

void BM_SliderCrankSlow_Defaults(benchmark::State& state) {
  run(state, ukdyn::Integrator::kDopri5, true, 5.0);
}
void BM_SliderCrankSlow_Bdf(benchmark::State& state) {
  run(state, ukdyn::Integrator::kBDF, true, 5.0);
}
void BM_SliderCrankSlow_PlainDopri5To2_3s(benchmark::State& state) {
  run(state, ukdyn::Integrator::kDopri5, false, 2.3);
}
void BM_SliderCrankSlow_DefaultsTo2_3s(benchmark::State& state) {
  run(state, ukdyn::Integrator::kDopri5, true, 2.3);
}

BENCHMARK(BM_SliderCrankSlow_Defaults)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SliderCrankSlow_Bdf)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SliderCrankSlow_DefaultsTo2_3s)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SliderCrankSlow_PlainDopri5To2_3s)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();

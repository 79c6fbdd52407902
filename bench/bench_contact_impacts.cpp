// SPDX-License-Identifier: BSD-3-Clause
// A run with k impacts costs O(k) event locations (issue #31 item 6, docs/contact.md): a ball
// dropped from h0 = 1 on a floor with restitution e makes impacts until one approaches at less
// than 1e-6 of the first (the rest criterion, kRestFraction), i.e. k = ceil(ln 1e-6 / ln e)
// impacts; e is chosen for k = 10, 100 and 1000. The model is examples/models/bouncing_ball.yaml
// with that e and no samples between the run's ends. The run ends a little after the accumulation
// point t_inf = t0 (1 + e) / (1 - e) (t0 = sqrt(2 h0 / g)), with dopri5 at rtol 1e-10.
//
// Counters: impacts (located impact events), events (all located contact events: impacts and
// the rest), and per impact the accepted steps and the evaluations of the fundamental equation
// (bisections included); time per run. O(k) shows as per-impact figures that stay flat as k
// grows tenfold. bench/RESULTS.md has the figures.
#include <cmath>
#include <string>

#include <benchmark/benchmark.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/simulation/simulate.hpp>

namespace {

void BM_BouncingBall_Impacts(benchmark::State& state) {
  const double k = double(state.range(0));
  // e^k = 1e-6 at the k-th impact's approach speed, nudged so that k impacts come before it
  const double e = std::pow(1e-6, 1.0 / (k - 0.5));
  // the example's ball (h0 = 1, g = 9.81) with this e; the bench's own integration (dopri5 at
  // rtol 1e-10, atol 1e-12, as the example's today) and no samples but the run's ends
  ukdyn::Model m =
      ukdyn::load_model(std::string(UKDYN_EXAMPLES_DIR) + "/bouncing_ball.yaml", {{"e", e}});
  m.options.integrator = ukdyn::Integrator::kDopri5;
  m.options.rtol = 1e-10;
  m.options.atol = 1e-12;
  m.options.output_every = 0.0;
  const double t0 = std::sqrt(2.0 / 9.81);
  m.options.t_end = 1.01 * t0 * (1.0 + e) / (1.0 - e);
  ukdyn::RunStatistics s;
  for (auto _ : state) {
    const ukdyn::Trajectory tr = ukdyn::simulate(m.system, m.q0, m.qd0, m.options);
    s = tr.stats;
    if (s.status != ukdyn::Status::kOk) state.SkipWithError(s.message.c_str());
    benchmark::DoNotOptimize(tr.q.data());
  }
  long impacts = 0;
  for (const ukdyn::ContactEvent& ev : s.contact_events)
    impacts += ev.kind == ukdyn::ContactEvent::Kind::kImpact ? 1 : 0;
  const double per = impacts > 0 ? 1.0 / double(impacts) : 0.0;
  state.counters["e"] = e;
  state.counters["impacts"] = double(impacts);
  state.counters["events"] = double(s.contact_events.size());
  state.counters["steps_per_impact"] = double(s.steps) * per;
  state.counters["evals_per_impact"] = double(s.evaluations) * per;
}
BENCHMARK(BM_BouncingBall_Impacts)->Arg(10)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

// SPDX-License-Identifier: BSD-3-Clause
// Ensembles (issue #17): samples per second of run_ensemble against the number of threads, for a
// short run (the pendulum, 1 s) and a long one (the double four-bar, 10 s), and what a sample
// that changes parameters pays for reading the model again (parse_model). Wall time and the
// process's CPU time are both reported (UseRealTime, MeasureProcessCPUTime): on a shared machine
// CPU / wall tells the parallel work done from the waiting for cores, and the counter
// quiet_samples_per_s removes the time the worker threads waited for a core (schedstat), an
// estimate of the rate on a machine without other load. Figures: bench/RESULTS.md.
#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include <sys/syscall.h>
#include <unistd.h>

#include <benchmark/benchmark.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/simulation/ensemble.hpp>

namespace {

// a thread's time on a core and waiting for one, in seconds (/proc/thread-self/schedstat)
struct Schedstat {
  double on_cpu = 0.0, waiting = 0.0;
};
Schedstat schedstat() {
  std::ifstream in("/proc/thread-self/schedstat");
  double run_ns = 0.0, wait_ns = 0.0;
  in >> run_ns >> wait_ns;
  return {run_ns * 1e-9, wait_ns * 1e-9};
}

std::string read_text(const std::string& name) {
  std::ifstream in(std::string(UKDYN_EXAMPLES_DIR) + "/" + name);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// `count` samples of `file` with t_end, each setting `name` (a parameter: read again; or an
// initial value: the model shared)
struct Batch {
  ukdyn::EnsembleModel model;
  std::vector<ukdyn::EnsembleSample> samples;
};
Batch batch(const char* file, double t_end, const char* name, double from, double step, int count) {
  Batch b;
  b.model.text = read_text(file);
  b.model.file = file;
  b.model.settings["t_end"] = t_end;
  const ukdyn::Model base = ukdyn::parse_model(b.model.text, b.model.file);
  b.samples.resize(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    const double v = from + step * i;
    if (base.parameters.count(name)) {
      b.samples[std::size_t(i)].parameters[name] = v;
    } else {
      b.samples[std::size_t(i)].initial[name] = v;
    }
  }
  return b;
}

// the batch on state.range(0) threads
void run(benchmark::State& state, const char* file, double t_end, const char* name, double from,
         double step, int count) {
  const Batch b = batch(file, t_end, name, from, step, count);
  const ukdyn::EnsembleModel& model = b.model;
  const std::vector<ukdyn::EnsembleSample>& samples = b.samples;
  ukdyn::EnsembleOptions options;
  options.threads = unsigned(state.range(0));
  // each worker thread's time waiting for a core (the kernel's schedstat), read after each of
  // its samples: the load of the other processes on the machine
  std::mutex mutex;
  std::map<long, Schedstat> seen;
  options.progress = [&](const ukdyn::EnsembleProgress&) {
    const Schedstat now = schedstat();
    const std::lock_guard<std::mutex> lock(mutex);
    seen[long(syscall(SYS_gettid))] = now;
  };
  double quiet = 0.0;  // Σ over iterations of the wall time less the least waiting of a thread
  for (auto _ : state) {
    seen.clear();
    const Schedstat start = schedstat();  // the calling thread (threads = 1 runs on it)
    const auto t0 = std::chrono::steady_clock::now();
    const ukdyn::EnsembleResult r = ukdyn::run_ensemble(model, samples, options);
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (r.failed() != 0) state.SkipWithError(r.samples[0].message.c_str());
    benchmark::DoNotOptimize(r.samples.data());
    double least_wait = wall;
    const long self = long(syscall(SYS_gettid));
    for (const auto& [tid, st] : seen) {
      least_wait = std::min(least_wait, tid == self ? st.waiting - start.waiting : st.waiting);
    }
    quiet += wall - least_wait;
  }
  state.SetItemsProcessed(state.iterations() * count);  // items/s = samples/s
  // the samples per second the run would reach without the time its threads waited for a core
  // (an estimate for a machine without other load: wall time − the least runqueue wait of a
  // worker thread)
  state.counters["quiet_samples_per_s"] = double(state.iterations() * count) / quiet;
}

// the pendulum, 1 s, over L (the model read again for each sample)
void BM_EnsemblePendulumParameters(benchmark::State& state) {
  run(state, "pendulum.yaml", 1.0, "L", 0.5, 0.05, 32);
}
// the same over the initial velocity (one model shared)
void BM_EnsemblePendulumInitial(benchmark::State& state) {
  run(state, "pendulum.yaml", 1.0, "y_dot", 0.0, -0.01, 32);
}
// the double four-bar, 10 s, over v0 (read again for each sample)
void BM_EnsembleFourBar(benchmark::State& state) {
  run(state, "double_four_bar.yaml", 10.0, "v0", 1.0, 0.05, 4);
}
// The parallel efficiency t1 / (2 t2) measured in pairs: each iteration runs the batch on one
// thread, then on two, so that both see the same machine (on a shared VM one thread's rate
// drifts by 1.8x within a minute with the other guests' load; a pair of batches tens of
// milliseconds apart sees the same). Counters: efficiency (total t1 / (2 total t2)) and
// median_efficiency (the median over the iterations' pairs).
void paired(benchmark::State& state, const char* file, double t_end, const char* name, double from,
            double step, int count) {
  const Batch b = batch(file, t_end, name, from, step, count);
  auto seconds = [&](unsigned threads) {
    ukdyn::EnsembleOptions options;
    options.threads = threads;
    const auto t0 = std::chrono::steady_clock::now();
    const ukdyn::EnsembleResult r = ukdyn::run_ensemble(b.model, b.samples, options);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (r.failed() != 0) state.SkipWithError(r.samples[0].message.c_str());
    benchmark::DoNotOptimize(r.samples.data());
    return s;
  };
  double one = 0.0, two = 0.0;
  std::vector<double> ratios;
  for (auto _ : state) {
    const double t1 = seconds(1), t2 = seconds(2);
    one += t1;
    two += t2;
    ratios.push_back(t1 / (2.0 * t2));
  }
  std::sort(ratios.begin(), ratios.end());
  state.counters["efficiency"] = one / (2.0 * two);
  state.counters["median_efficiency"] = ratios[ratios.size() / 2];
  state.counters["samples_per_s_1"] = double(state.iterations() * count) / one;
  state.counters["samples_per_s_2"] = double(state.iterations() * count) / two;
}
void BM_PairedPendulumInitial(benchmark::State& state) {
  paired(state, "pendulum.yaml", 1.0, "y_dot", 0.0, -0.01, int(state.range(0)));
}
void BM_PairedPendulumParameters(benchmark::State& state) {
  paired(state, "pendulum.yaml", 1.0, "L", 0.5, 0.05 / 32, int(state.range(0)));
}
void BM_PairedFourBar(benchmark::State& state) {
  paired(state, "double_four_bar.yaml", 10.0, "v0", 1.0, 0.05, 4);
}

// reading the pendulum's model file once: what a sample that changes parameters adds
void BM_ParsePendulum(benchmark::State& state) {
  const std::string text = read_text("pendulum.yaml");
  for (auto _ : state) {
    const ukdyn::Model m = ukdyn::parse_model(text, "pendulum.yaml", {{"L", 1.5}});
    benchmark::DoNotOptimize(m.q0.data());
  }
}
void BM_ParseFourBar(benchmark::State& state) {
  const std::string text = read_text("double_four_bar.yaml");
  for (auto _ : state) {
    const ukdyn::Model m = ukdyn::parse_model(text, "double_four_bar.yaml", {{"v0", 1.5}});
    benchmark::DoNotOptimize(m.q0.data());
  }
}

}  // namespace

BENCHMARK(BM_EnsemblePendulumParameters)
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->MeasureProcessCPUTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EnsemblePendulumInitial)
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->MeasureProcessCPUTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EnsembleFourBar)
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->MeasureProcessCPUTime()
    ->Unit(benchmark::kMillisecond);
// (the batch's size: 32 samples as above, and 256, a sweep's size, where the fixed cost of a
// batch — reading the model once, starting the threads — weighs less)
BENCHMARK(BM_PairedPendulumInitial)
    ->Arg(32)
    ->Arg(256)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PairedPendulumParameters)
    ->Arg(32)
    ->Arg(256)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PairedFourBar)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ParsePendulum)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ParseFourBar)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();

// SPDX-License-Identifier: BSD-3-Clause
// Memory of long runs (issue #14, item 3): the peak resident set of a run of N samples, its
// samples kept in memory (a Trajectory) or streamed (SimulationOptions::sample_sink; and as
// `ukdyn run` does, run_model's chunks appended to a CSV by CsvWriter); and a controlled model
// (control_duffing.yaml) kept or streamed the same way. Each run is made in a
// child process (fork) so that each figure is that run's own peak: the parent reads the child's
// ru_maxrss with wait4. Counters: samples, peak_rss_MB (the child's peak), bytes_per_sample
// (peak above the 10³-sample run of the same mode, per sample). Figures in bench/RESULTS.md.
#include <benchmark/benchmark.h>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <limits>
#include <string>

#include <ukdyn/gallery/gallery.hpp>
#include <ukdyn/io/trajectory_files.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/simulation/simulate.hpp>

namespace {

enum Mode { kInMemory = 0, kSink = 1, kCsv = 2, kControlledInMemory = 3, kControlledCsv = 4 };

// the pendulum (Cartesian, 2 coordinates, 1 constraint) sampled every 0.01 s: samples − 1
// intervals
int child(Mode mode, long samples) {
  const double t_end = 0.01 * double(samples - 1);
  if (mode == kControlledInMemory || mode == kControlledCsv) {
    // the Duffing oscillator under its tracking controller (1 coordinate, 1 requirement row):
    // the plant's columns and the control's (error, force, power, work, effort)
    ukdyn::Model model =
        ukdyn::load_model(std::string(UKDYN_EXAMPLES_DIR) + "/control_duffing.yaml");
    ukdyn::SimulationOptions o = model.options;
    o.t_end = t_end;
    o.output_every = 0.01;
    o.energy_balance_tolerance = std::numeric_limits<double>::infinity();
    if (mode == kControlledInMemory) {
      const ukdyn::ModelRun run = ukdyn::run_model(model, o);
      return run.trajectory.samples() == samples ? 0 : 1;
    }
    ukdyn::CsvWriter csv("/dev/null");
    const ukdyn::ModelRun run = ukdyn::run_model(model, o, [&](const ukdyn::ModelRun& chunk) {
      csv.append(chunk.trajectory, chunk.extra_columns);
    });
    csv.commit();
    return run.trajectory.stats.samples == samples && csv.rows() == samples ? 0 : 1;
  }
  if (mode == kCsv) {
    ukdyn::Model model = ukdyn::load_model(std::string(UKDYN_EXAMPLES_DIR) + "/pendulum.yaml");
    ukdyn::SimulationOptions o = model.options;
    o.t_end = t_end;
    o.output_every = 0.01;
    ukdyn::CsvWriter csv("/dev/null");
    const ukdyn::ModelRun run = ukdyn::run_model(model, o, [&](const ukdyn::ModelRun& chunk) {
      csv.append(chunk.trajectory, chunk.extra_columns);
    });
    csv.commit();
    return run.trajectory.stats.samples == samples && csv.rows() == samples ? 0 : 1;
  }
  const ukdyn::gallery::Example ex = ukdyn::gallery::pendulum();
  ukdyn::SimulationOptions o;
  o.t_end = t_end;
  long received = 0;
  o.energy_balance_tolerance = std::numeric_limits<double>::infinity();  // (a 10⁴ s run)
  if (mode == kSink) o.sample_sink = [&](const ukdyn::Trajectory&) { ++received; };
  const ukdyn::Trajectory tr = ukdyn::simulate(ex.system, ex.q0, ex.qd0, o);
  const long got = mode == kSink ? received : long(tr.samples());
  return got == samples && tr.stats.status == ukdyn::Status::kOk ? 0 : 1;
}

// peak RSS (MB) of a child process running child(mode, samples); negative when it failed
double peak_rss_mb(Mode mode, long samples) {
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(child(mode, samples));
  int status = 0;
  rusage usage{};
  if (::wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    return -1.0;
  }
  return double(usage.ru_maxrss) / 1024.0;  // (ru_maxrss is in kB on Linux)
}

void BM_PeakRss(benchmark::State& state) {
  const Mode mode = Mode(state.range(0));
  const long samples = long(state.range(1));
  double peak = 0.0, base = 0.0;
  for (auto _ : state) {
    peak = peak_rss_mb(mode, samples);
    state.PauseTiming();
    base = peak_rss_mb(mode, 1000);
    state.ResumeTiming();
  }
  if (peak < 0.0 || base < 0.0) state.SkipWithError("the run failed");
  static const char* const kLabels[] = {"in memory", "sample_sink", "csv stream",
                                        "controlled, in memory", "controlled, csv stream"};
  state.SetLabel(kLabels[mode]);
  state.counters["samples"] = double(samples);
  state.counters["peak_rss_MB"] = peak;
  state.counters["bytes_per_sample"] = (peak - base) * 1024.0 * 1024.0 / double(samples - 1000);
}

BENCHMARK(BM_PeakRss)
    ->ArgsProduct({{kInMemory, kSink, kCsv, kControlledInMemory, kControlledCsv},
                   {100000, 1000000}})
    ->ArgNames({"mode", "samples"})
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();

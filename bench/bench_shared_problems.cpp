// SPDX-License-Identifier: BSD-3-Clause
// ukdyn on the shared benchmark problems P1 (double pendulum) and P2 (crank-rocker four-bar) of
// bench/data/README.md: RK4 at h = 1e-3 for T = 10 s with the default drift control
// (projection), in the natural coordinates of gallery/gallery.hpp.
//
//   bench_shared_problems [google-benchmark flags]   timing by Google Benchmark; the counters
//                                                    carry the accuracy figures of a separate run
//   bench_shared_problems --json=PATH                the README's protocol (one warm-up, five timed
//                                                    runs, median; a separate run sampled at every
//                                                    step) written as a JSON array of records
//
// Counters: ms_per_sim_s (wall milliseconds per simulated second), max_violation and
// final_violation (loop closure in metres, gallery::closure_violation; 0 for P1), max_phi (largest
// constraint violation of any link, metres), coord_final and coord_error (reported coordinate at T
// and its difference from the reference, rad), rel_drift_max (energy, relative to E(0)), steps.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "shared_protocol.hpp"

#include <ukdyn/gallery/gallery.hpp>
#include <ukdyn/simulation/simulate.hpp>

namespace {

using ukdyn::Index;
using ukdyn::VectorXd;

constexpr double kStep = 1e-3;

// RK4 at h = 1e-3 over the problem's T, default drift control; samples every `every` s
ukdyn::SimulationOptions options(double T, double every) {
  ukdyn::SimulationOptions opt;
  opt.t_end = T;
  opt.integrator = ukdyn::Integrator::kRK4;
  opt.step = kStep;
  opt.output_every = every;
  return opt;
}

// the accuracy figures of one run sampled at every step
struct Accuracy {
  double max_violation = 0, final_violation = 0;  // loop closure (m)
  double max_phi = 0;                             // largest constraint violation (m)
  double E0 = 0, E_final = 0, rel_drift_final = 0, rel_drift_max = 0;
  double coord_t1 = 0, coord_final = 0, coord_error = 0, reference = 0;
  long steps = 0, evaluations = 0, projections = 0;
  std::string error;  // "" when the run finished
};

Accuracy measure_accuracy(const std::string& name) {
  const ukdyn::gallery::Example ex = ukdyn::gallery::make(name);
  const auto info = ukdyn::gallery::shared_problem(name);
  const ukdyn::Trajectory tr = ukdyn::simulate(ex.system, ex.q0, ex.qd0, options(info.T, kStep));
  Accuracy a;
  const Index n = tr.n, N = tr.samples();
  a.E0 = tr.energy.front();
  a.E_final = tr.energy.back();
  for (Index i = 0; i < N; ++i) {
    const Eigen::Map<const VectorXd> q(tr.q.data() + i * n, n);
    const double gap = ukdyn::gallery::closure_violation(name, q);
    a.max_violation = std::max(a.max_violation, gap);
    if (i == N - 1) a.final_violation = gap;
    a.rel_drift_max =
        std::max(a.rel_drift_max, std::abs(tr.energy[std::size_t(i)] - a.E0) / std::abs(a.E0));
    if (std::abs(tr.t[std::size_t(i)] - 1.0) < 0.5 * kStep) {
      a.coord_t1 = ukdyn::gallery::reported_coordinate(name, VectorXd(q));
    }
  }
  a.rel_drift_final = (a.E_final - a.E0) / std::abs(a.E0);
  a.coord_final = ukdyn::gallery::reported_coordinate(
      name, Eigen::Map<const VectorXd>(tr.q.data() + (N - 1) * n, n));
  a.reference = info.reference_coordinate;
  a.coord_error = a.coord_final - a.reference;
  a.max_phi = tr.stats.max_position_violation;
  a.steps = tr.stats.steps;
  a.evaluations = tr.stats.evaluations;
  a.projections = tr.stats.projections;
  if (tr.stats.status != ukdyn::Status::kOk || std::abs(tr.t.back() - info.T) > 1e-9) {
    a.error = tr.stats.message.empty() ? "run stopped at t = " + std::to_string(tr.t.back())
                                       : tr.stats.message;
  }
  return a;
}

// ---------------------------------------------------------------------------------------------
// Google Benchmark: the timed loop is one whole run with samples at t = 0 and T only

void BM_SharedProblem(benchmark::State& state, const std::string& name) {
  const ukdyn::gallery::Example ex = ukdyn::gallery::make(name);
  const double T = ukdyn::gallery::shared_problem(name).T;
  const ukdyn::SimulationOptions opt = options(T, 0.0);
  double wall = 0.0;  // seconds spent in simulate(), summed over the iterations
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    ukdyn::Trajectory tr = ukdyn::simulate(ex.system, ex.q0, ex.qd0, opt);
    benchmark::DoNotOptimize(tr.q.data());
    benchmark::ClobberMemory();
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  // wall milliseconds per simulated second (each iteration simulates T seconds)
  state.counters["ms_per_sim_s"] = 1e3 * wall / (double(state.iterations()) * T);
  const Accuracy a = measure_accuracy(name);
  state.counters["max_violation"] = a.max_violation;
  state.counters["final_violation"] = a.final_violation;
  state.counters["max_phi"] = a.max_phi;
  state.counters["coord_final"] = a.coord_final;
  state.counters["coord_error"] = a.coord_error;
  state.counters["rel_drift_max"] = a.rel_drift_max;
  state.counters["steps"] = double(a.steps);
  if (!a.error.empty()) state.SkipWithError(a.error.c_str());
}

BENCHMARK_CAPTURE(BM_SharedProblem, P1, std::string("shared_P1"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);
BENCHMARK_CAPTURE(BM_SharedProblem, P2, std::string("shared_P2"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

// ---------------------------------------------------------------------------------------------
// --json=PATH: the record format of bench/data/README.md

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream os;
  os << std::setprecision(17) << v;
  return os.str();
}

std::string str(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += ' ';
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string record(const std::string& name) {
  const ukdyn::gallery::Example ex = ukdyn::gallery::make(name);
  const auto info = ukdyn::gallery::shared_problem(name);
  const ukdyn::SimulationOptions opt = options(info.T, 0.0);

  // one warm-up run, then five timed runs of the stepping loop; median wall time
  const ukdyn::bench::TimedRuns timed = ukdyn::bench::time_runs(ex.system, ex.q0, ex.qd0, opt);
  const std::vector<double>& wall = timed.wall;
  const bool deterministic = timed.deterministic;
  const double median = timed.median();
  const Accuracy a = measure_accuracy(name);

  const auto& so = opt;
  std::ostringstream os;
  os << "{\"engine\": \"ukdyn\", \"config\": "
     << str("natural coordinates, fundamental equation (Cholesky + COD), projection drift control")
     << ", \"problem\": " << str(info.id) << ", \"integrator\": \"rk4\", \"h\": " << num(kStep)
     << ", \"T\": " << num(info.T) << ", \"nq\": " << ex.system.coordinate_count()
     << ", \"n_closure_eqs\": " << ex.system.constraint_rows() << ", \"wall_runs\": [";
  for (std::size_t i = 0; i < wall.size(); ++i) os << (i ? ", " : "") << num(wall[i]);
  os << "], \"wall_per_sim_s\": " << num(median / info.T)
     << ", \"max_violation\": " << num(a.max_violation)
     << ", \"final_violation\": " << num(a.final_violation) << ", \"E0\": " << num(a.E0)
     << ", \"E_final\": " << num(a.E_final) << ", \"rel_drift_final\": " << num(a.rel_drift_final)
     << ", \"rel_drift_max\": " << num(a.rel_drift_max)
     << ", \"coord_name\": " << str(info.coord_name) << ", \"coord_t1\": " << num(a.coord_t1)
     << ", \"coord_final\": " << num(a.coord_final) << ", \"steps\": " << a.steps
     << ", \"deterministic\": " << (deterministic ? "true" : "false") << ", \"extra\": {"
     << "\"coord_reference\": " << num(a.reference) << ", \"coord_error\": " << num(a.coord_error)
     << ", \"max_constraint_violation\": " << num(a.max_phi) << ", \"constraint_rows_are\": "
     << str(info.id == "P1" ? "link lengths (no loop closure)"
                            : "link lengths; the loop is closed by the shared point C")
     << ", \"violation_measure\": "
     << str("distance between coupler tip and rocker tip with every link placed from its "
            "proximal point at its exact length (0 for P1)")
     << ", \"evaluations\": " << a.evaluations << ", \"projections\": " << a.projections
     << ", \"wall_per_sim_s_min\": " << num(*std::min_element(wall.begin(), wall.end()) / info.T)
     << "}, \"settings\": {"
     << "\"drift\": \"projection\", \"projection_tolerance\": " << num(so.projection.tolerance)
     << ", \"projection_max_iterations\": " << so.projection.max_iterations
     << ", \"rank_threshold\": " << num(so.solver.rank_threshold)
     << ", \"samples_timed_runs\": \"t = 0 and T only\", \"samples_accuracy_run\": \"every step\""
     << "}, \"error\": " << (a.error.empty() ? "null" : str(a.error)) << "}";
  return os.str();
}

}  // namespace

int main(int argc, char** argv) {
  // --json=PATH: write the records and exit; anything else goes to Google Benchmark
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--json=", 7) == 0) {
      const std::string path = argv[i] + 7;
      std::ofstream out(path);
      if (!out) {
        std::cerr << "bench_shared_problems: cannot write '" << path << "'\n";
        return 1;
      }
      out << "[\n";
      bool first = true;
      for (const char* name : {"shared_P1", "shared_P2"}) {
        const std::string r = record(name);
        std::cout << r << "\n";
        out << (first ? "" : ",\n") << r;
        first = false;
      }
      out << "\n]\n";
      return 0;
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

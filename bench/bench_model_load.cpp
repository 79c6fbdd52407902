// SPDX-License-Identifier: BSD-3-Clause
// Loading large models (issue #14, item 7): parse_model() + check_model() of generated models,
// the time `ukdyn check` spends before anything runs. The models are those of
// gen_scaling.py of the bad-input defect report (not in the repository), generated in memory:
//   Uncoupled/N        N oscillators, T = ½ Σ q̇_i², V = Σ ½ q_i²
//   Constrained/N      N oscillators with N/2 holonomic constraints q_{2k} − q_{2k+1} = 0
//   DistinctTerms/N    one coordinate, V = Σ_{i=1}^{N} sin(x + i)/N (N distinct terms)
//   Chain/N            a chain of N planar bodies on revolute joints, under gravity
//   ManyCoordinates/N  N free coordinates, T = ½ Σ q̇_i² only, as the reproducer
//                      many_coordinates.sh writes them (issue #29: 10⁵ took 66 s); load only
//   ManyForces/N       the same with a `forces:` entry per coordinate, F_i = −q_i (issue #29:
//                      5·10⁴ entries took 70 s, O(N²)); load only
//   MovingMasses/N     T = ½ Σ (1 + q_i²) q̇_i²: a total derivative per coordinate (each compared
//                      the whole chain of coordinates, O(N²)); load only. M depends on q, so
//                      the reader checks it dense: that check (O(N³), modelfile/reader.cpp)
//                      dominates from 10³ coordinates on, not the expressions
// Each reports the time per load (+ check) and, over the sizes, the scaling (BigO fit).
#include <string>

#include <benchmark/benchmark.h>

#include <ukdyn/modelfile/model.hpp>

namespace {

std::string uncoupled(int n, int constraints) {
  std::string names, T, V, C;
  for (int i = 0; i < n; ++i) {
    const std::string q = "q" + std::to_string(i);
    names += (i ? ", " : "") + q;
    T += (i ? "+" : "") + q + "_dot^2";
    V += (i ? "+" : "") + ("0.5*" + q + "^2");
  }
  for (int k = 0; k < constraints; ++k) {
    C += "  - {name: c" + std::to_string(k) + ", holonomic: q" + std::to_string(2 * k) + " - q" +
         std::to_string(2 * k + 1) + "}\n";
  }
  return "coordinates: [" + names + "]\nkinetic_energy: 0.5*(" + T + ")\npotential_energy: " + V +
         "\n" + (constraints ? "constraints:\n" + C : "") +
         "initial: {q: {q0: 0}}\nsimulate: {t_end: 0.1}\n";
}

std::string distinct_terms(int n) {
  std::string V;
  for (int i = 1; i <= n; ++i)
    V += (i > 1 ? "+" : "") + ("sin(x+" + std::to_string(i) + ")/" + std::to_string(n));
  return "coordinates: [x]\nkinetic_energy: 0.5*x_dot^2\npotential_energy: " + V + "\n";
}

std::string chain(int n) {
  std::string b = "bodies:\n", j = "joints:\n";
  for (int i = 0; i < n; ++i) {
    b += "  - {name: l" + std::to_string(i) + ", type: planar, mass: 1, inertia: 0.1, position: [" +
         std::to_string(i + 0.5) + ", 0]}\n";
    j += i == 0
             ? "  - {name: p0, type: revolute, parent: ground, child: l0, child_point: [-0.5, 0]}\n"
             : "  - {name: p" + std::to_string(i) + ", type: revolute, parent: l" +
                   std::to_string(i - 1) + ", child: l" + std::to_string(i) +
                   ", parent_point: [0.5, 0], child_point: [-0.5, 0]}\n";
  }
  return b + j + "forces:\n  - {type: gravity, g: [0, -9.81]}\nsimulate: {t_end: 0.01}\n";
}

void load_and_check(benchmark::State& state, const std::string& text) {
  for (auto _ : state) {
    const ukdyn::Model m = ukdyn::parse_model(text, "generated.yaml");
    const ukdyn::CheckReport r = ukdyn::check_model(m);
    benchmark::DoNotOptimize(r.rank);
  }
  state.SetComplexityN(state.range(0));
  state.counters["bytes"] = double(text.size());
}

// n free coordinates, T = ½ Σ q̇_i² (or ½ Σ (1 + q_i²) q̇_i² with `moving`), and with `forces`
// an entry F_i = −q_i per coordinate
std::string free_coordinates(int n, bool forces = false, bool moving = false) {
  std::string names, T, F;
  for (int i = 0; i < n; ++i) {
    const std::string q = "q" + std::to_string(i);
    names += (i ? ", " : "") + q;
    T += (i ? "+" : "") + (moving ? "(1+" + q + "^2)*" : std::string()) + q + "_dot^2";
    F += (i ? ", " : "") + ("-" + q);
  }
  return "coordinates: [" + names + "]\nkinetic_energy: 0.5*(" + T + ")\n" +
         (forces ? "forces: [" + F + "]\n" : "") +
         "simulate: {t_end: 0.01}\noutput: {every: 0.01}\n";
}

void load_only(benchmark::State& state, const std::string& text) {
  for (auto _ : state) {
    const ukdyn::Model m = ukdyn::parse_model(text, "generated.yaml");
    benchmark::DoNotOptimize(m.system.coordinate_count());
  }
  state.SetComplexityN(state.range(0));
  state.counters["bytes"] = double(text.size());
}

void ManyCoordinates(benchmark::State& state) {
  load_only(state, free_coordinates(int(state.range(0))));
}
void ManyForces(benchmark::State& state) {
  load_only(state, free_coordinates(int(state.range(0)), true));
}
void MovingMasses(benchmark::State& state) {
  load_only(state, free_coordinates(int(state.range(0)), false, true));
}

void Uncoupled(benchmark::State& state) {
  load_and_check(state, uncoupled(int(state.range(0)), 0));
}
void Constrained(benchmark::State& state) {
  load_and_check(state, uncoupled(int(state.range(0)), int(state.range(0)) / 2));
}
void DistinctTerms(benchmark::State& state) {
  load_and_check(state, distinct_terms(int(state.range(0))));
}
void Chain(benchmark::State& state) { load_and_check(state, chain(int(state.range(0)))); }

BENCHMARK(Uncoupled)
    ->Arg(100)
    ->Arg(1000)
    ->Arg(10000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(1)
    ->Complexity();
BENCHMARK(Constrained)
    ->Arg(100)
    ->Arg(300)
    ->Arg(1000)
    ->Arg(10000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Complexity();
BENCHMARK(DistinctTerms)
    ->Arg(10000)
    ->Arg(100000)
    ->Arg(400000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Complexity();
BENCHMARK(ManyCoordinates)
    ->Arg(10000)
    ->Arg(30000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Complexity();
BENCHMARK(ManyForces)
    ->Arg(10000)
    ->Arg(20000)
    ->Arg(50000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Complexity();
BENCHMARK(MovingMasses)
    ->Arg(500)
    ->Arg(1000)
    ->Arg(2000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Complexity();
BENCHMARK(Chain)
    ->Arg(100)
    ->Arg(1000)
    ->Arg(3334)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Complexity();

}  // namespace

BENCHMARK_MAIN();

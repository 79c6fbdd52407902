// SPDX-License-Identifier: BSD-3-Clause
// Nanoseconds per evaluation of the fundamental equation: the default algorithm, the textbook
// formula and a dense KKT solve with LDLT, on random full-rank and rank-deficient problems.
//
// "core" benchmarks give every algorithm the same inputs (M, Q, A, b) and time everything it
// needs to produce q'' and the multipliers, including factorizing M. "pipeline" times the whole
// forward_dynamics call (callables for M, Q and A, b; non-finite checks; residuals).
// Counters: allocs_per_eval (after the workspace exists); err = ‖q'' − q''_ref‖ / ‖q''_ref‖ and
// err_lambda = ‖λ − λ_ref‖ / ‖λ_ref‖ against the textbook formula (λ_ref = (B Bᵀ)⁺ e, the
// minimum-norm multipliers). Problems: full rank (deficient = 0), random rank-deficient A = U V
// (deficient = 1), and a full-rank A with a third of its rows duplicated exactly
// (deficient = 2), as redundant joints produce.
#include <benchmark/benchmark.h>

#include <ukdyn/reference/reference.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/alloc_counter.hpp"
#include "support/random_problem.hpp"

namespace {

using namespace ukdyn;

// the rank used for the rank-deficient variant of an m-row problem
Index deficient_rank(Index m) { return std::max<Index>(1, m - std::max<Index>(1, m / 3)); }

testing::RandomProblem problem(const benchmark::State& state) {
  const Index n = state.range(0), m = state.range(1), kind = state.range(2);
  if (kind != 2) {
    const Index r = kind == 1 ? deficient_rank(m) : m;
    return testing::random_problem(n, m, r, 1234u + unsigned(n), false);
  }
  // rows m − d … m−1 repeat rows 0 … d−1 exactly
  const Index d = m - deficient_rank(m);
  auto p = testing::random_problem(n, m - d, m - d, 1234u + unsigned(n), false);
  MatrixXd A(m, n);
  VectorXd b(m);
  A << p.A, p.A.topRows(d);
  b << p.b, p.b.head(d);
  p.A = A;
  p.b = b;
  p.rank = m - d;
  return p;
}

// q'' and λ by the textbook formula, the reference for the error counters
std::pair<VectorXd, VectorXd> textbook(const testing::RandomProblem& p) {
  const Index n = p.M.rows(), m = p.A.rows();
  TextbookDecomposition t(n, m);
  t.compute_mass(p.M).compute_constraints(p.A);
  VectorXd a(n), dq(n), Qc(n), lambda(m);
  t.solve_mass(p.Q, a);
  t.solve_ideal(p.b - p.A * a, dq, Qc, lambda);
  return {a + dq, lambda};
}

// Times eval(): one warm-up call, allocations counted over ten calls, then the timed loop;
// reports allocs_per_eval and the errors of qdd and lambda (which eval() fills) against the
// textbook formula.
template <class F>
void measure(benchmark::State& state, const testing::RandomProblem& p, F&& eval,
             const Eigen::Ref<const VectorXd>& qdd, const Eigen::Ref<const VectorXd>& lambda) {
  eval();
  testing::start_counting_allocations();
  for (int i = 0; i < 10; ++i) eval();
  const double allocs = double(testing::stop_counting_allocations()) / 10.0;
  for (auto _ : state) {
    eval();
    benchmark::DoNotOptimize(qdd.data());
    benchmark::ClobberMemory();
  }
  state.counters["allocs_per_eval"] = allocs;
  const auto [qdd_ref, lambda_ref] = textbook(p);
  state.counters["err"] = (qdd - qdd_ref).norm() / qdd_ref.norm();
  state.counters["err_lambda"] = (lambda - lambda_ref).norm() / lambda_ref.norm();
  const char* labels[] = {"full-rank", "rank-deficient", "duplicated-rows"};
  state.SetLabel(labels[state.range(2)]);
}

// default and textbook share the stages: M = L Lᵀ (or M^{±1/2}); a = M⁻¹ Q; e = b − A a;
// decomposition of the constraints; q'' = a + (ideal part)
template <class Decomposition>
void BM_Decomposition(benchmark::State& state) {
  const auto p = problem(state);
  const Index n = p.M.rows(), m = p.A.rows();
  Decomposition d(n, m);
  VectorXd a(n), e(m), dq(n), Qc(n), lambda(m), qdd(n);
  measure(
      state, p,
      [&] {
        d.compute_mass(p.M);
        d.solve_mass(p.Q, a);
        e = p.b;
        e.noalias() -= p.A * a;
        d.compute_constraints(p.A);
        d.solve_ideal(e, dq, Qc, lambda);
        qdd = a + dq;
      },
      qdd, lambda);
}

void BM_Default(benchmark::State& state) { BM_Decomposition<FundamentalDecomposition>(state); }
void BM_Textbook(benchmark::State& state) { BM_Decomposition<TextbookDecomposition>(state); }

void BM_KKT(benchmark::State& state) {
  const auto p = problem(state);
  const Index n = p.M.rows(), m = p.A.rows();
  KktSolver kkt(n, m);
  VectorXd qdd(n), lambda(m);
  measure(
      state, p, [&] { kkt.solve(p.M, p.Q, p.A, p.b, qdd, lambda); }, qdd, lambda);
}

// the whole forward_dynamics call; M through a callable so that it is factorized every time
void BM_Pipeline(benchmark::State& state, bool residuals) {
  const auto p = problem(state);
  const Index n = p.M.rows();
  SystemBuilder builder(n);
  builder
      .mass_matrix([M = p.M](const Eigen::Ref<const VectorXd>&, double, Eigen::Ref<MatrixXd> out) {
        out = M;
      })
      .forces([Q = p.Q](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                        double, Eigen::Ref<VectorXd> out) { out = Q; })
      .add(acceleration_constraint(
          "A", p.A.rows(),
          [A = p.A, b = p.b](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&,
                             double, Eigen::Ref<MatrixXd> Ao, Eigen::Ref<VectorXd> bo) {
            Ao = A;
            bo = b;
          }));
  const System sys = builder.build();
  Workspace ws(sys, SolverOptions{.compute_residuals = residuals});
  const VectorXd z = VectorXd::Zero(n);
  measure(
      state, p, [&] { forward_dynamics(sys, ws, z, z, 0.0); }, ws.qdd, ws.lambda);
  if (ws.status != Status::kOk) state.SkipWithError(describe_status(sys, ws).c_str());
}

void sizes(benchmark::internal::Benchmark* b) {
  for (int deficient : {0, 1, 2}) {
    for (auto [n, m] : {std::pair{6, 3}, {12, 6}, {30, 20}, {60, 40}, {120, 80}}) {
      b->Args({n, m, deficient});
    }
  }
  b->ArgNames({"n", "m", "deficient"});
}

BENCHMARK(BM_Default)->Apply(sizes);
BENCHMARK(BM_KKT)->Apply(sizes);
BENCHMARK(BM_Textbook)->Apply(sizes);
BENCHMARK_CAPTURE(BM_Pipeline, with_residuals, true)->Apply(sizes);
BENCHMARK_CAPTURE(BM_Pipeline, no_residuals, false)->Apply(sizes);

}  // namespace

BENCHMARK_MAIN();

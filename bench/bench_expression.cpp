// SPDX-License-Identifier: BSD-3-Clause
// Nanoseconds per evaluation of a compiled expression tape against the same formulas written by
// hand in C++, on a realistic model: the double pendulum in its two angles, with M and Q derived
// symbolically from T and V through Lagrange's equations (as a model file does), bob positions
// and velocities, energies and the angular momentum — 20 outputs. Counter: max_diff is the
// largest difference between the tape's and the hand-written outputs.
#include <cmath>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include <ukdyn/modelfile/expression.hpp>

namespace {

using namespace ukdyn::expr;

struct Parameters {
  double m1 = 1.0, m2 = 0.7, l1 = 1.2, l2 = 0.9, g = 9.81;
};

constexpr int kOutputs = 20;

// the model in the expression language; inputs (th1, th2, w1, w2, t)
ukdyn::expr::Program compile_double_pendulum(const Parameters& p) {
  ExpressionSet s({"th1", "th2", "w1", "w2", "t"});
  s.set_constant("m1", p.m1);
  s.set_constant("m2", p.m2);
  s.set_constant("l1", p.l1);
  s.set_constant("l2", p.l2);
  s.set_constant("g", p.g);
  const std::vector<std::pair<std::string, std::string>> chain = {{"th1", "w1"}, {"th2", "w2"}};
  // bob positions and velocities
  const Expr x1 = s.parse("l1*sin(th1)"), y1 = s.parse("-l1*cos(th1)");
  const Expr x2 = s.parse("l1*sin(th1) + l2*sin(th2)"), y2 = s.parse("-l1*cos(th1) - l2*cos(th2)");
  const Expr vx1 = s.total_derivative(x1, "t", chain), vy1 = s.total_derivative(y1, "t", chain);
  const Expr vx2 = s.total_derivative(x2, "t", chain), vy2 = s.total_derivative(y2, "t", chain);
  const Expr T = s.parse(
      "m1/2*(l1*w1)^2 + m2/2*((l1*cos(th1)*w1 + l2*cos(th2)*w2)^2 + "
      "(l1*sin(th1)*w1 + l2*sin(th2)*w2)^2)");
  const Expr V = s.parse("-(m1 + m2)*g*l1*cos(th1) - m2*g*l2*cos(th2)");
  const Expr L = s.subtract(T, V);
  // M_ij = ∂²T/∂q̇_i∂q̇_j;  Q_i = ∂L/∂q_i − D(∂L/∂q̇_i) (without q̈)
  std::vector<Expr> out;
  const char* q[2] = {"th1", "th2"};
  const char* qd[2] = {"w1", "w2"};
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) out.push_back(s.diff(s.diff(T, qd[i]), qd[j]));
  }
  for (int i = 0; i < 2; ++i) {
    out.push_back(s.subtract(s.diff(L, q[i]), s.total_derivative(s.diff(L, qd[i]), "t", chain)));
  }
  for (const Expr e : {x1, y1, x2, y2, vx1, vy1, vx2, vy2}) out.push_back(e);
  out.push_back(T);
  out.push_back(V);
  out.push_back(s.add(T, V));
  out.push_back(L);
  // angular momentum about the pivot, m (x v_y − y v_x) summed over the bobs
  out.push_back(
      s.parse("m1*l1^2*w1 + m2*((l1*sin(th1) + l2*sin(th2))*(l1*sin(th1)*w1 + "
              "l2*sin(th2)*w2) + (l1*cos(th1) + l2*cos(th2))*(l1*cos(th1)*w1 + "
              "l2*cos(th2)*w2))"));
  out.push_back(s.parse("th2 - th1"));
  return s.compile(out);
}

// the 20 outputs written in the expression language with the formulas of hand_written() (M and
// Q in closed form; the derived ones above are GiNaC's expanded forms, with more operations)
ukdyn::expr::Program compile_double_pendulum_closed_form(const Parameters& p) {
  ExpressionSet s({"th1", "th2", "w1", "w2", "t"});
  s.set_constant("m1", p.m1);
  s.set_constant("m2", p.m2);
  s.set_constant("l1", p.l1);
  s.set_constant("l2", p.l2);
  s.set_constant("g", p.g);
  const char* T = "(m1 + m2)/2*l1^2*w1^2 + m2/2*l2^2*w2^2 + m2*l1*l2*w1*w2*cos(th1 - th2)";
  const char* V = "-(m1 + m2)*g*l1*cos(th1) - m2*g*l2*cos(th2)";
  std::vector<Expr> out;
  for (const std::string text :
       {"(m1 + m2)*l1^2", "m2*l1*l2*cos(th1 - th2)", "m2*l1*l2*cos(th1 - th2)", "m2*l2^2",
        "-m2*l1*l2*w2^2*sin(th1 - th2) - (m1 + m2)*g*l1*sin(th1)",
        "m2*l1*l2*w1^2*sin(th1 - th2) - m2*g*l2*sin(th2)", "l1*sin(th1)", "-l1*cos(th1)",
        "l1*sin(th1) + l2*sin(th2)", "-l1*cos(th1) - l2*cos(th2)", "l1*cos(th1)*w1",
        "l1*sin(th1)*w1", "l1*cos(th1)*w1 + l2*cos(th2)*w2", "l1*sin(th1)*w1 + l2*sin(th2)*w2"}) {
    out.push_back(s.parse(text));
  }
  const Expr Te = s.parse(T), Ve = s.parse(V);
  out.push_back(Te);
  out.push_back(Ve);
  out.push_back(s.add(Te, Ve));
  out.push_back(s.subtract(Te, Ve));
  out.push_back(
      s.parse("m1*l1^2*w1 + m2*((l1*sin(th1) + l2*sin(th2))*(l1*sin(th1)*w1 + "
              "l2*sin(th2)*w2) + (l1*cos(th1) + l2*cos(th2))*(l1*cos(th1)*w1 + "
              "l2*cos(th2)*w2))"));
  out.push_back(s.parse("th2 - th1"));
  return s.compile(out);
}

// the same 20 outputs as a careful person writes them
void hand_written(const Parameters& p, const double* in, double* out) {
  const double th1 = in[0], th2 = in[1], w1 = in[2], w2 = in[3];
  const double s1 = std::sin(th1), c1 = std::cos(th1), s2 = std::sin(th2), c2 = std::cos(th2);
  const double s12 = std::sin(th1 - th2), c12 = std::cos(th1 - th2);
  const double m12 = p.m1 + p.m2, k = p.m2 * p.l1 * p.l2;
  // M
  out[0] = m12 * p.l1 * p.l1;
  out[1] = k * c12;
  out[2] = k * c12;
  out[3] = p.m2 * p.l2 * p.l2;
  // Q
  out[4] = -k * w2 * w2 * s12 - m12 * p.g * p.l1 * s1;
  out[5] = k * w1 * w1 * s12 - p.m2 * p.g * p.l2 * s2;
  // positions and velocities
  const double x1 = p.l1 * s1, y1 = -p.l1 * c1, x2 = x1 + p.l2 * s2, y2 = y1 - p.l2 * c2;
  const double vx1 = p.l1 * c1 * w1, vy1 = p.l1 * s1 * w1;
  const double vx2 = vx1 + p.l2 * c2 * w2, vy2 = vy1 + p.l2 * s2 * w2;
  out[6] = x1;
  out[7] = y1;
  out[8] = x2;
  out[9] = y2;
  out[10] = vx1;
  out[11] = vy1;
  out[12] = vx2;
  out[13] = vy2;
  // energies
  const double T =
      0.5 * m12 * p.l1 * p.l1 * w1 * w1 + 0.5 * p.m2 * p.l2 * p.l2 * w2 * w2 + k * w1 * w2 * c12;
  const double V = -m12 * p.g * p.l1 * c1 - p.m2 * p.g * p.l2 * c2;
  out[14] = T;
  out[15] = V;
  out[16] = T + V;
  out[17] = T - V;
  out[18] = p.m1 * p.l1 * p.l1 * w1 + p.m2 * (x2 * vy2 - y2 * vx2);
  out[19] = th2 - th1;
}

template <ukdyn::expr::Program (*make)(const Parameters&)>
void BM_DoublePendulumTape(benchmark::State& state) {
  const Parameters p;
  const Program prog = make(p);
  std::vector<double> scratch(std::size_t(prog.scratch_size())), out(kOutputs), ref(kOutputs);
  double in[5] = {0.3, -0.8, 1.1, -0.4, 0.0};
  for (auto _ : state) {
    benchmark::DoNotOptimize(in);
    prog.evaluate(in, out.data(), scratch.data());
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  hand_written(p, in, ref.data());
  double diff = 0.0;
  for (int k = 0; k < kOutputs; ++k) diff = std::max(diff, std::abs(out[k] - ref[k]));
  state.counters["max_diff"] = diff;
  state.counters["ops"] = double(prog.operations());
  state.counters["outputs"] = double(prog.outputs());
}
// the formulas of hand_written(), interpreted
BENCHMARK(BM_DoublePendulumTape<compile_double_pendulum_closed_form>)
    ->Name("BM_DoublePendulumTape/closed_form");
// M and Q derived by GiNaC from T and V (as a model file does), interpreted
BENCHMARK(BM_DoublePendulumTape<compile_double_pendulum>)->Name("BM_DoublePendulumTape/derived");

void BM_DoublePendulumHandWritten(benchmark::State& state) {
  Parameters p;
  std::vector<double> out(kOutputs);
  double in[5] = {0.3, -0.8, 1.1, -0.4, 0.0};
  for (auto _ : state) {
    benchmark::DoNotOptimize(in);
    benchmark::DoNotOptimize(p);
    hand_written(p, in, out.data());
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_DoublePendulumHandWritten);

// the one-off cost: derivatives with GiNaC and compilation to the tape
void BM_DoublePendulumDeriveAndCompile(benchmark::State& state) {
  const Parameters p;
  for (auto _ : state) benchmark::DoNotOptimize(compile_double_pendulum(p));
}
BENCHMARK(BM_DoublePendulumDeriveAndCompile)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();

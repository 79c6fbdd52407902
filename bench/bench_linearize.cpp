// SPDX-License-Identifier: BSD-3-Clause
// One linearization (issue #32, item 6): the rolling disk upright (5 coordinates, 2
// nonholonomic rows, 8 states) and the heavy symmetric top in Cardan angles spinning upright
// (3 coordinates, 6 states), model files, with a force input; and the Whipple bicycle
// (examples/models/whipple_bicycle.yaml: 8 coordinates, 1 holonomic and 4 nonholonomic rows,
// 10 states of which lean and steer are kept) about its straight run at 5 m/s, with a steer
// torque input (issue #32: under 10 ms). Counters:
//   states        s, the size of A
//   max_A_error   the largest of Ridders' error estimates of A
#include <algorithm>
#include <string>

#include <benchmark/benchmark.h>

#include <ukdyn/analysis/linearize.hpp>
#include <ukdyn/modelfile/model.hpp>

#include "analysis/models.hpp"  // tests/analysis: the Cardan top

namespace {

using ukdyn::VectorXd;

void run(benchmark::State& state, const ukdyn::Model& model, const ukdyn::OperatingPoint& op,
         const std::string& force, const ukdyn::LinearizeOptions& options = {}) {
  const ukdyn::System& sys = model.system;
  const std::vector<ukdyn::LinearInput> inputs = {ukdyn::force_input(sys, force)};
  ukdyn::LinearModel lm;
  for (auto _ : state) {
    lm = ukdyn::linearize(sys, op, inputs, {}, options);
    benchmark::DoNotOptimize(lm.A.data());
  }
  state.counters["states"] = double(lm.A.rows());
  state.counters["max_A_error"] = lm.A_error.maxCoeff();
}

void BM_LinearizeRollingDisk(benchmark::State& state) {
  const ukdyn::Model model =
      ukdyn::load_model(std::string(UKDYN_EXAMPLES_DIR) + "/rolling_disk.yaml");
  const ukdyn::System& sys = model.system;
  ukdyn::OperatingPoint op{VectorXd::Zero(5), VectorXd::Zero(5), 0.0};
  op.qd(sys.coordinate_index("phi")) = 4;
  op.qd(sys.coordinate_index("x")) = 2;  // x' = R phi'
  run(state, model, op, "psi");
}
BENCHMARK(BM_LinearizeRollingDisk)->Unit(benchmark::kMicrosecond);

void BM_LinearizeSleepingTop(benchmark::State& state) {
  const ukdyn::Model model = ukdyn::parse_model(ukdyn::test::kCardanTop);
  ukdyn::OperatingPoint op{VectorXd::Zero(3), VectorXd::Zero(3), 0.0};
  op.qd(2) = 40;
  run(state, model, op, "a");
}
BENCHMARK(BM_LinearizeSleepingTop)->Unit(benchmark::kMicrosecond);

void BM_LinearizeWhippleBicycle(benchmark::State& state) {
  const ukdyn::Model model =
      ukdyn::load_model(std::string(UKDYN_EXAMPLES_DIR) + "/whipple_bicycle.yaml");
  const ukdyn::System& sys = model.system;
  const double v = 5;
  ukdyn::OperatingPoint op{VectorXd::Zero(8), VectorXd::Zero(8), 0.0};
  op.qd(sys.coordinate_index("x")) = v;
  op.qd(sys.coordinate_index("theta_R")) = v / model.parameters.at("rR");
  op.qd(sys.coordinate_index("theta_F")) = v / model.parameters.at("rF");
  ukdyn::LinearizeOptions o;
  o.independent_positions = {"x", "y", "psi", "phi", "delta", "theta_R", "theta_F"};
  o.independent_velocities = {"phi", "delta", "theta_R"};
  o.states = {"phi", "delta", "phi_dot", "delta_dot"};
  run(state, model, op, "delta", o);
}
BENCHMARK(BM_LinearizeWhippleBicycle)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

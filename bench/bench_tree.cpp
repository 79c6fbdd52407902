// SPDX-License-Identifier: BSD-3-Clause
// One evaluation of M(q) and Q(q, q') of a 7-DOF arm as a kinematic tree (issue #30 item 4),
// beside MuJoCo's mj_forward on the same URDF (when built with MuJoCo 2.x).
//
//   bench_tree                       Google Benchmark: wall time per evaluation
//   bench_tree --count N             N evaluations of each, for callgrind's instruction counts:
//     valgrind --tool=callgrind --toggle-collect='run_tree_mq*' bench_tree --count 10000
//     (and 'run_tree_forward*', 'run_mujoco_forward*'); instructions per call = Ir / N
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include <benchmark/benchmark.h>

#include <ukdyn/dynamics/forward.hpp>
#include <ukdyn/dynamics/workspace.hpp>
#include <ukdyn/multibody/tree.hpp>

#ifdef UKDYN_BENCH_MUJOCO
#include <mujoco/mujoco.h>
#endif

namespace {

using ukdyn::MatrixXd;
using ukdyn::VectorXd;

const std::string kPanda = std::string(UKDYN_TEST_DATA_DIR) + "/panda_arm.urdf";

struct Arm {
  ukdyn::System sys = ukdyn::tree::make_system(ukdyn::tree::load_urdf(kPanda));
  std::unique_ptr<ukdyn::CallableScratch> scratch = sys.make_scratch();
  ukdyn::Workspace ws{sys};
  VectorXd q{7}, qd{7}, Q{7};
  MatrixXd M{7, 7};
  Arm() {
    q << 0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6;
    qd << 0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3;
  }
};

// one M + Q evaluation of the tree's system (CRBA, then RNEA, through the System's callables)
__attribute__((noinline)) void run_tree_mq(Arm& a) {
  a.sys.mass_matrix(a.q, 0.0, a.scratch.get(), a.M);
  a.sys.forces(a.q, a.qd, 0.0, a.scratch.get(), a.Q);
}

// one unconstrained forward-dynamics evaluation (M, Q, Cholesky, a = M⁻¹ Q)
__attribute__((noinline)) void run_tree_forward(Arm& a) {
  ukdyn::forward_dynamics(a.sys, a.ws, a.q, a.qd, 0.0);
}

void BM_TreeMassAndForces(benchmark::State& state) {
  Arm a;
  for (auto _ : state) {
    run_tree_mq(a);
    benchmark::DoNotOptimize(a.Q.data());
  }
}
BENCHMARK(BM_TreeMassAndForces);

void BM_TreeForwardDynamics(benchmark::State& state) {
  Arm a;
  for (auto _ : state) {
    run_tree_forward(a);
    benchmark::DoNotOptimize(a.ws.qdd.data());
  }
}
BENCHMARK(BM_TreeForwardDynamics);

#ifdef UKDYN_BENCH_MUJOCO
struct MjArm {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  MjArm() {
    char error[1000] = "";
    m = mj_loadXML(kPanda.c_str(), nullptr, error, int(sizeof error));
    if (!m) {
      std::fprintf(stderr, "MuJoCo: %s\n", error);
      std::exit(1);
    }
    d = mj_makeData(m);
    const double q[7] = {0.3, -0.5, 0.8, -1.9, 0.4, 1.7, -0.6};
    const double qd[7] = {0.5, -1.0, 0.7, 0.2, -0.9, 1.1, 0.3};
    std::memcpy(d->qpos, q, sizeof q);
    std::memcpy(d->qvel, qd, sizeof qd);
  }
  ~MjArm() {
    mj_deleteData(d);
    mj_deleteModel(m);
  }
};

// MuJoCo's whole forward pass: kinematics, CRBA, factorization, RNE bias, qacc
__attribute__((noinline)) void run_mujoco_forward(MjArm& a) { mj_forward(a.m, a.d); }

void BM_MuJoCoForward(benchmark::State& state) {
  MjArm a;
  for (auto _ : state) {
    run_mujoco_forward(a);
    benchmark::DoNotOptimize(a.d->qacc);
  }
}
BENCHMARK(BM_MuJoCoForward);
#endif

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::strcmp(argv[1], "--count") == 0) {
    const long n = std::atol(argv[2]);
    Arm a;
    for (long i = 0; i < n; ++i) run_tree_mq(a);
    for (long i = 0; i < n; ++i) run_tree_forward(a);
#ifdef UKDYN_BENCH_MUJOCO
    MjArm mj;
    for (long i = 0; i < n; ++i) run_mujoco_forward(mj);
#endif
    std::printf("%ld evaluations each; Q[0] = %.17g\n", n, a.Q[0]);
    return 0;
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

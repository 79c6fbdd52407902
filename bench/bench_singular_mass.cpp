// SPDX-License-Identifier: BSD-3-Clause
// Singular mass matrices (issue #13, item 6): the cost of the singular-M path against the regular
// path on the same mechanism, per evaluation of the fundamental equation (forward_dynamics).
//
//   Pendulum3      the pendulum in (x, y, theta) with M = diag(m, m, 0) (singular path), against
//                  the same coordinates and constraints with the regular M + c Aᵀ A, Q + c Aᵀ b
//                  written by hand (c = m; the same motion)
//   Chain/N        N rigid bodies (quaternions) hanging in a chain of spherical joints under
//                  gravity: the singular 4 × 4 quaternion blocks (how multibody/multibody.hpp
//                  builds them now), against the fictitious-inertia blocks with J0 = mean(J) (how
//                  it built them before, tests/support/fictitious_inertia.hpp). N = 3 runs the
//                  dense engine (21 coordinates), N = 16 and 64 the sparse one.
//
// The acceptance bound of the issue: singular / regular <= 1.3 on each pair; for the quaternion
// chains, "not slower than today": singular / fictitious <= 1.00.
//
// Instruction counts (reproducible where wall times are not): `bench_singular_mass --evaluate
// CASE N` runs N evaluations of one case (chain3, chain16, chain64, pendulum3; suffix "_before"
// for the fictitious-inertia or hand-regularized system) on one workspace, after one evaluation
// that detects the singular M; under `valgrind --tool=callgrind
// --toggle-collect='ukdyn::forward_dynamics*'` the difference of the counts for two N, divided
// by the difference of the N, is the cost of one evaluation (bench/RESULTS.md).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include <benchmark/benchmark.h>

#include <ukdyn/core/autodiff.hpp>
#include <ukdyn/dynamics/forward.hpp>
#include <ukdyn/multibody/multibody.hpp>

#include "support/fictitious_inertia.hpp"

namespace {

using namespace ukdyn;

constexpr double kM = 1.0, kL = 1.0, kG = 9.81;

// x = L sin th, y = −L cos th; regular adds c (Aᵀ A, Aᵀ b) of those rows to M and Q
System pendulum3(bool regular) {
  SystemBuilder b(std::vector<std::string>{"x", "y", "th"});
  if (regular) {
    b.mass_matrix([](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> M) {
      const double c = std::cos(q[2]), s = std::sin(q[2]);
      // rows a1 = (1, 0, −L c), a2 = (0, 1, −L s)
      M << kM + kM, 0.0, -kM * kL * c,  //
          0.0, kM + kM, -kM * kL * s,   //
          -kM * kL * c, -kM * kL * s, kM * kL * kL;
    });
    b.forces([](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                Eigen::Ref<VectorXd> Q) {
      const double c = std::cos(q[2]), s = std::sin(q[2]), w2 = qd[2] * qd[2];
      const double b1 = -kL * s * w2, b2 = kL * c * w2;  // x'' = b1 + L c th'', y'' = b2 + L s th''
      Q << kM * b1, -kM * kG + kM * b2, -kM * kL * (c * b1 + s * b2);
    });
  } else {
    MatrixXd M = MatrixXd::Zero(3, 3);
    M(0, 0) = M(1, 1) = kM;
    b.mass_matrix(M);
    b.forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                Eigen::Ref<VectorXd> Q) { Q << 0.0, -kM * kG, 0.0; });
  }
  b.add(holonomic("cx", 1, [](const auto& q, const auto&, auto& phi) {
    using std::sin;
    phi[0] = q[0] - kL * sin(q[2]);
  }));
  b.add(holonomic("cy", 1, [](const auto& q, const auto&, auto& phi) {
    using std::cos;
    phi[0] = q[1] + kL * cos(q[2]);
  }));
  return b.build();
}

void evaluate(benchmark::State& state, const System& sys, const Eigen::Ref<const VectorXd>& q,
              const Eigen::Ref<const VectorXd>& qd) {
  Workspace ws(sys);
  for (auto _ : state) {
    if (forward_dynamics(sys, ws, q, qd, 0.0) != Status::kOk) {
      state.SkipWithError(describe_status(sys, ws).c_str());
      break;
    }
    benchmark::DoNotOptimize(ws.qdd.data());
  }
  state.counters["singular"] = ws.mass_singular ? 1.0 : 0.0;
  state.counters["sparse"] = ws.is_sparse() ? 1.0 : 0.0;
}

void BM_Pendulum3(benchmark::State& state) {
  const bool regular = state.range(0) != 0;
  const System sys = pendulum3(regular);
  VectorXd q(3), qd(3);
  q << kL * std::sin(1.0), -kL * std::cos(1.0), 1.0;
  qd << kL * std::cos(1.0) * 0.5, kL * std::sin(1.0) * 0.5, 0.5;
  evaluate(state, sys, q, qd);
  state.SetLabel(regular ? "regular" : "singular");
}
BENCHMARK(BM_Pendulum3)->Arg(0)->Arg(1);

mb::MultibodyModel chain(int N) {
  mb::Multibody b;
  b.set_gravity({0, 0, -kG});
  mb::BodyId prev = mb::kGround;
  for (int i = 0; i < N; ++i) {
    const Eigen::Quaterniond u(
        Eigen::AngleAxisd(0.2 * (i + 1), Eigen::Vector3d(1, 0.5, 0).normalized()));
    const Eigen::Vector3d r = u * Eigen::Vector3d(0, 0, -0.5) + Eigen::Vector3d(0, 0, -1.0 * i);
    const mb::BodyId id = b.add_rigid_body("b" + std::to_string(i), 1.0, {0.1, 0.1, 0.02}, r, u,
                                           Eigen::Vector3d::Zero(), {0.3, -0.2, 1.0});
    b.add_joint(
        mb::spherical("s" + std::to_string(i), prev,
                      prev == mb::kGround ? Eigen::Vector3d(0, 0, 0) : Eigen::Vector3d(0, 0, -0.5),
                      id, {0, 0, 0.5}));
    prev = id;
  }
  return b.build();
}

void BM_Chain(benchmark::State& state) {
  const int N = int(state.range(0));
  const bool regular = state.range(1) != 0;
  const mb::MultibodyModel m = chain(N);
  if (regular) {
    const System reg = test::with_fictitious_inertia(m.system, (0.1 + 0.1 + 0.02) / 3.0);
    evaluate(state, reg, m.q0, m.qd0);
  } else {
    evaluate(state, m.system, m.q0, m.qd0);
  }
  state.SetLabel(regular ? "fictitious J0 (before)" : "singular (now)");
}
BENCHMARK(BM_Chain)->Args({3, 0})->Args({3, 1})->Args({16, 0})->Args({16, 1})->Args({64, 0})->Args(
    {64, 1});

// --evaluate CASE N: N + 1 evaluations of one case, no timing (for callgrind)
int evaluate_count(const std::string& name, long count) {
  const bool before = name.size() > 7 && name.compare(name.size() - 7, 7, "_before") == 0;
  const std::string base = before ? name.substr(0, name.size() - 7) : name;
  auto run = [count](const System& sys, const Eigen::Ref<const VectorXd>& q,
                     const Eigen::Ref<const VectorXd>& qd) {
    Workspace ws(sys);
    for (long i = 0; i <= count; ++i) {
      if (forward_dynamics(sys, ws, q, qd, 0.0) != Status::kOk) {
        std::fprintf(stderr, "%s\n", describe_status(sys, ws).c_str());
        return 1;
      }
    }
    std::printf("%ld evaluations, singular %d, sparse %d\n", count + 1, int(ws.mass_singular),
                int(ws.is_sparse()));
    return 0;
  };
  if (base == "pendulum3") {
    VectorXd q(3), qd(3);
    q << kL * std::sin(1.0), -kL * std::cos(1.0), 1.0;
    qd << kL * std::cos(1.0) * 0.5, kL * std::sin(1.0) * 0.5, 0.5;
    return run(pendulum3(before), q, qd);
  }
  if (base.rfind("chain", 0) == 0) {
    const mb::MultibodyModel m = chain(std::atoi(base.c_str() + 5));
    if (before)
      return run(test::with_fictitious_inertia(m.system, (0.1 + 0.1 + 0.02) / 3.0), m.q0, m.qd0);
    return run(m.system, m.q0, m.qd0);
  }
  std::fprintf(stderr, "unknown case '%s' (chainN, pendulum3, with or without _before)\n",
               name.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "--evaluate") == 0) {
    return evaluate_count(argv[2], std::atol(argv[3]));
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

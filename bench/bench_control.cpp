// SPDX-License-Identifier: BSD-3-Clause
// Control-force evaluations per second (compute_control, control/control.hpp) for an n-link
// pendulum in absolute joint angles (state-dependent, dense M), n = 3, 7, 30, with
//   - "joints": every joint angle follows a trajectory (m_r = n rows, one requirement), and
//   - "tip":    only the end point follows a path (m_r = 2 rows, redundant actuation),
// under the Gauss law and the weighted law with a state-dependent N. For scale, "model" is one
// forward_dynamics of the pendulum alone (stage 1 of the control pipeline).
#include <cmath>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include <ukdyn/control/control.hpp>
#include <ukdyn/ukdyn.hpp>

namespace {

using ukdyn::Index;
using ukdyn::MatrixXd;
using ukdyn::VectorXd;

// point masses 1 kg on links 1 m: mu_ij = (n − max(i, j)) (kg), M_ij = mu_ij cos(th_i − th_j),
// Q_i = −Σ_j mu_ij sin(th_i − th_j) th_j'² − g mu_ii sin th_i (callables that do not allocate)
ukdyn::System chain(Index n) {
  std::vector<std::string> names;
  for (Index i = 0; i < n; ++i) names.push_back("th" + std::to_string(i + 1));
  MatrixXd mu(n, n);
  for (Index i = 0; i < n; ++i) {
    for (Index j = 0; j < n; ++j) mu(i, j) = double(n - std::max(i, j));
  }
  return ukdyn::SystemBuilder(names)
      .mass_matrix([mu](const Eigen::Ref<const VectorXd>& q, double, Eigen::Ref<MatrixXd> M) {
        const Index coordinate_count = q.size();
        for (Index j = 0; j < coordinate_count; ++j) {
          for (Index i = 0; i < coordinate_count; ++i) M(i, j) = mu(i, j) * std::cos(q[i] - q[j]);
        }
      })
      .forces([mu](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                   double, Eigen::Ref<VectorXd> Q) {
        const Index coordinate_count = q.size();
        for (Index i = 0; i < coordinate_count; ++i) {
          double s = 9.81 * mu(i, i) * std::sin(q[i]);
          for (Index j = 0; j < coordinate_count; ++j)
            s += mu(i, j) * std::sin(q[i] - q[j]) * qd[j] * qd[j];
          Q[i] = -s;
        }
      })
      .build();
}

// every joint angle follows 0.3 sin(t + 0.1 i), one requirement of n rows
ukdyn::Constraint joints(Index n) {
  return ukdyn::holonomic("joints", n, [n](const auto& q, const auto& t, auto& e) {
    using std::sin;
    for (Index i = 0; i < n; ++i) e[i] = q[i] - 0.3 * sin(t + 0.1 * double(i));
  });
}

// the tip follows a small circle below the pivot
ukdyn::Constraint tip(Index n) {
  return ukdyn::holonomic("tip", 2, [n](const auto& q, const auto& t, auto& e) {
    using S = std::decay_t<decltype(t)>;
    using std::cos;
    using std::sin;
    S x(0.0), y(0.0);
    for (Index i = 0; i < n; ++i) {
      x += sin(q[i]);
      y -= cos(q[i]);
    }
    e[0] = x - 0.2 * sin(t);
    e[1] = y + 0.9 * double(n) - 0.2 * cos(t);
  });
}

// N = diag(1 + 0.1 i + 0.5 sin² th_i)
void weight(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>&, double,
            Eigen::Ref<MatrixXd> N) {
  N.setZero();
  for (Index i = 0; i < q.size(); ++i) {
    N(i, i) = 1.0 + 0.1 * double(i) + 0.5 * std::sin(q[i]) * std::sin(q[i]);
  }
}

VectorXd state(Index n, double scale) {
  VectorXd x(n);
  for (Index i = 0; i < n; ++i) x[i] = scale * std::sin(0.7 * double(i) + 0.3);
  return x;
}

void run(benchmark::State& st, const ukdyn::Controller& ctrl) {
  const Index n = ctrl.coordinate_count();
  ukdyn::ControlWorkspace ws(ctrl);
  const VectorXd q = state(n, 0.2), qd = state(n, 0.5);
  double t = 0.0;
  for (auto _ : st) {
    ukdyn::compute_control(ctrl, ws, q, qd, t);
    benchmark::DoNotOptimize(ws.Qc_control.data());
    t += 1e-6;
  }
  if (ws.status != ukdyn::ControlStatus::kOk) {
    st.SkipWithError(ukdyn::describe_control_status(ctrl, ws).c_str());
  }
  st.SetItemsProcessed(st.iterations());
  st.counters["n"] = double(n);
  st.counters["m_r"] = double(ctrl.requirement_rows());
}

void BM_Model(benchmark::State& st) {
  const Index n = st.range(0);
  const ukdyn::System sys = chain(n);
  ukdyn::Workspace ws(sys, ukdyn::SolverOptions{.compute_residuals = false});
  const VectorXd q = state(n, 0.2), qd = state(n, 0.5);
  for (auto _ : st) {
    ukdyn::forward_dynamics(sys, ws, q, qd, 0.0);
    benchmark::DoNotOptimize(ws.qdd.data());
  }
  st.SetItemsProcessed(st.iterations());
}

void BM_GaussJoints(benchmark::State& st) {
  const Index n = st.range(0);
  run(st, ukdyn::ControllerBuilder(chain(n))
              .require(joints(n), ukdyn::ErrorDynamics::second_order(2.0))
              .build());
}

void BM_WeightedJoints(benchmark::State& st) {
  const Index n = st.range(0);
  run(st, ukdyn::ControllerBuilder(chain(n))
              .require(joints(n), ukdyn::ErrorDynamics::second_order(2.0))
              .weighted(weight)
              .build());
}

void BM_GaussTip(benchmark::State& st) {
  const Index n = st.range(0);
  run(st, ukdyn::ControllerBuilder(chain(n))
              .require(tip(n), ukdyn::ErrorDynamics::second_order(2.0))
              .build());
}

void BM_WeightedTip(benchmark::State& st) {
  const Index n = st.range(0);
  run(st, ukdyn::ControllerBuilder(chain(n))
              .require(tip(n), ukdyn::ErrorDynamics::second_order(2.0))
              .weighted(weight)
              .build());
}

}  // namespace

BENCHMARK(BM_Model)->Arg(3)->Arg(7)->Arg(30);
BENCHMARK(BM_GaussJoints)->Arg(3)->Arg(7)->Arg(30);
BENCHMARK(BM_WeightedJoints)->Arg(3)->Arg(7)->Arg(30);
BENCHMARK(BM_GaussTip)->Arg(3)->Arg(7)->Arg(30);
BENCHMARK(BM_WeightedTip)->Arg(3)->Arg(7)->Arg(30);

BENCHMARK_MAIN();

// SPDX-License-Identifier: BSD-3-Clause
// A model read from a file against the same model written by hand in C++ (issue #4: "within 2x").
//
// Three ways to write one system:
//   file  examples/models/NAME.yaml through load_model(): M, Q, A, b, phi, phi' derived
//         symbolically by GiNaC and run on compiled expression tapes;
//   ad    the C++ gallery (gallery/gallery.hpp): M and Q by hand, constraints as generic callables
//         differentiated by Eigen's AutoDiff — what a C++ user of the library writes;
//   hand  everything by hand: M, Q, and each constraint's A, b, phi, phi' derived on paper and
//         coded as a ConstraintModel (the fastest a C++ user can do with the engine).
//
// Each benchmark times the file variant and a C++ variant alternately in the same loop (the
// machine is shared and noisy; alternating cancels drift) and reports the medians:
//   file_ns, cpp_ns   per forward_dynamics evaluation (Eval) or per simulated second (Sim: RK4,
//                     h = 1e-3, projection drift control, 1 s), nanoseconds
//   ratio             file_ns / cpp_ns (the target is ratio <= 2)
//   max_diff          largest |q''| difference between the two (Eval) or |q(T)| difference (Sim)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include <ukdyn/dynamics/forward.hpp>
#include <ukdyn/dynamics/projection.hpp>
#include <ukdyn/gallery/gallery.hpp>
#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/simulation/simulate.hpp>

namespace {

using ukdyn::Index;
using ukdyn::MatrixXd;
using ukdyn::VectorXd;

// ---------------------------------------------------------------------------------------------
// hand-written models

// The distance between two points of a planar linkage, phi = (|p_i − p_j|² − L²) / (2L), with
// p = (q[2k], q[2k+1]) for a moving point k and a fixed point otherwise (index −1 and `fixed`).
//   A_i = (p_i − p_j)ᵀ / L,  A_j = −A_i;  b = −|v_i − v_j|² / L;  phi' = (p_i − p_j)·(v_i − v_j) /
//   L
class Distance final : public ukdyn::ConstraintModel {
 public:
  Distance(Index i, Index j, double fx, double fy, double L)
      : i_(i), j_(j), fx_(fx), fy_(fy), L_(L) {}

  void acceleration_form(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                         double, ukdyn::ConstraintScratch*, Eigen::Ref<MatrixXd> A,
                         Eigen::Ref<VectorXd> b) const override {
    double dx, dy, vx, vy;
    relative(q, qd, dx, dy, vx, vy);
    A.setZero();
    A(0, 2 * i_) = dx / L_;
    A(0, 2 * i_ + 1) = dy / L_;
    if (j_ >= 0) {
      A(0, 2 * j_) = -dx / L_;
      A(0, 2 * j_ + 1) = -dy / L_;
    }
    b[0] = -(vx * vx + vy * vy) / L_;
  }

  void violation(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
                 ukdyn::ConstraintScratch*, Eigen::Ref<VectorXd> position,
                 Eigen::Ref<VectorXd> velocity) const override {
    double dx, dy, vx, vy;
    relative(q, qd, dx, dy, vx, vy);
    position[0] = (dx * dx + dy * dy - L_ * L_) / (2 * L_);
    velocity[0] = (dx * vx + dy * vy) / L_;
  }

 private:
  void relative(const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd,
                double& dx, double& dy, double& vx, double& vy) const {
    dx = q[2 * i_] - (j_ >= 0 ? q[2 * j_] : fx_);
    dy = q[2 * i_ + 1] - (j_ >= 0 ? q[2 * j_ + 1] : fy_);
    vx = qd[2 * i_] - (j_ >= 0 ? qd[2 * j_] : 0.0);
    vy = qd[2 * i_ + 1] - (j_ >= 0 ? qd[2 * j_ + 1] : 0.0);
  }
  Index i_, j_;
  double fx_, fy_, L_;
};

ukdyn::Constraint distance(std::string name, Index i, Index j, double fx, double fy, double L) {
  return {std::move(name), ukdyn::ConstraintKind::kHolonomic, 1,
          std::make_shared<Distance>(i, j, fx, fy, L)};
}

// pendulum: m = 1, L = 1, g = 9.81 (examples/models/pendulum.yaml)
ukdyn::System hand_pendulum() {
  constexpr double m = 1, g = 9.81;
  return ukdyn::SystemBuilder({"x", "y"})
      .mass_matrix(m * MatrixXd::Identity(2, 2))
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q << 0.0, -m * g; })
      .potential_energy([](const Eigen::Ref<const VectorXd>& q, double) { return m * g * q[1]; })
      .add(distance("rod", 0, -1, 0.0, 0.0, 1.0))
      .build();
}

// double four-bar (IFToMM A02): five uniform 1 m, 1 kg rods; cranks from (0,0), (1,0), (2,0) to
// tips 0, 1, 2; couplers tip 0–1 and 1–2. Crank: T = (m/3)|v|²/2; coupler: (m/6)(|v_i|² +
// v_i·v_j + |v_j|²); V = m g Σ (rod centre heights).
ukdyn::System hand_double_four_bar() {
  constexpr double m = 1, L = 1, g = 9.81;
  MatrixXd M = MatrixXd::Zero(6, 6);
  const auto block = [&](Index a, Index b, double v) {
    M(2 * a, 2 * b) += v;
    M(2 * a + 1, 2 * b + 1) += v;
  };
  for (Index k = 0; k < 3; ++k) block(k, k, m / 3);
  for (Index k = 0; k < 2; ++k) {
    block(k, k, m / 3);
    block(k + 1, k + 1, m / 3);
    block(k, k + 1, m / 6);
    block(k + 1, k, m / 6);
  }
  // −dV/dy: crank k: m g/2 on tip k; coupler: m g/2 on each end
  return ukdyn::SystemBuilder({"x1", "y1", "x2", "y2", "x3", "y3"})
      .mass_matrix(M)
      .forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
                 Eigen::Ref<VectorXd> Q) { Q << 0.0, -m * g, 0.0, -1.5 * m * g, 0.0, -m * g; })
      .potential_energy([](const Eigen::Ref<const VectorXd>& q, double) {
        return m * g * (q[1] + 1.5 * q[3] + q[5]);
      })
      .add(distance("crank1", 0, -1, 0.0, 0.0, L))
      .add(distance("crank2", 1, -1, 1.0, 0.0, L))
      .add(distance("crank3", 2, -1, 2.0, 0.0, L))
      .add(distance("coupler1", 1, 0, 0.0, 0.0, L))
      .add(distance("coupler2", 2, 1, 0.0, 0.0, L))
      .build();
}

// ---------------------------------------------------------------------------------------------
// the comparisons

struct Case {
  std::string file;  // examples/models/<file>.yaml
  std::function<ukdyn::System()> cpp;
};

ukdyn::Model load(const std::string& stem) {
  return ukdyn::load_model(std::string(UKDYN_EXAMPLES_DIR) + "/" + stem + ".yaml");
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(v.size() / 2), v.end());
  return v[v.size() / 2];
}

template <class F>
double seconds(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// the initial state of the file's model on its constraints (both variants start from it)
void initial_state(const ukdyn::Model& model, VectorXd& q, VectorXd& qd) {
  q = model.q0;
  qd = model.qd0;
  if (model.project_initial) {
    ukdyn::Workspace ws(model.system);
    ukdyn::project_positions(model.system, ws, q, 0.0);
    ukdyn::project_velocities(model.system, ws, q, qd, 0.0);
  }
}

void BM_Eval(benchmark::State& state, const Case& c) {
  const ukdyn::Model model = load(c.file);
  const ukdyn::System cpp = c.cpp();
  VectorXd q, qd;
  initial_state(model, q, qd);
  ukdyn::Workspace ws_file(model.system), ws_cpp(cpp);
  constexpr int kRepeat = 1000;  // evaluations per timed block
  std::vector<double> t_file, t_cpp;
  for (auto _ : state) {
    t_file.push_back(seconds([&] {
      for (int k = 0; k < kRepeat; ++k) ukdyn::forward_dynamics(model.system, ws_file, q, qd, 0.0);
    }));
    t_cpp.push_back(seconds([&] {
      for (int k = 0; k < kRepeat; ++k) ukdyn::forward_dynamics(cpp, ws_cpp, q, qd, 0.0);
    }));
    benchmark::DoNotOptimize(ws_file.qdd.data());
    benchmark::DoNotOptimize(ws_cpp.qdd.data());
  }
  const double f = 1e9 * median(t_file) / kRepeat, h = 1e9 * median(t_cpp) / kRepeat;
  state.counters["file_ns"] = f;
  state.counters["cpp_ns"] = h;
  state.counters["ratio"] = f / h;
  state.counters["max_diff"] = (ws_file.qdd - ws_cpp.qdd).lpNorm<Eigen::Infinity>();
}

void BM_Sim(benchmark::State& state, const Case& c) {
  const ukdyn::Model model = load(c.file);
  const ukdyn::System cpp = c.cpp();
  VectorXd q, qd;
  initial_state(model, q, qd);
  ukdyn::SimulationOptions opt;
  opt.t_end = 1.0;
  opt.integrator = ukdyn::Integrator::kRK4;
  opt.step = 1e-3;
  opt.output_every = 0.0;
  std::vector<double> t_file, t_cpp;
  ukdyn::Trajectory a, b;
  for (auto _ : state) {
    t_file.push_back(seconds([&] { a = ukdyn::simulate(model.system, q, qd, opt); }));
    t_cpp.push_back(seconds([&] { b = ukdyn::simulate(cpp, q, qd, opt); }));
  }
  const double f = 1e9 * median(t_file) / opt.t_end, h = 1e9 * median(t_cpp) / opt.t_end;
  state.counters["file_ns"] = f;
  state.counters["cpp_ns"] = h;
  state.counters["ratio"] = f / h;
  double diff = 0;
  for (std::size_t i = 0; i < a.q.size() && i < b.q.size(); ++i)
    diff = std::max(diff, std::abs(a.q[a.q.size() - 1 - i] - b.q[b.q.size() - 1 - i]));
  state.counters["max_diff"] = a.q.size() == b.q.size() ? diff : -1.0;
  if (a.stats.status != ukdyn::Status::kOk || b.stats.status != ukdyn::Status::kOk)
    state.SkipWithError("a run failed");
}

const Case kPendulumAd{"pendulum", [] { return ukdyn::gallery::pendulum(1.0, 1.0, 9.81).system; }};
const Case kPendulumHand{"pendulum", hand_pendulum};
const Case kFourBarAd{"double_four_bar", [] { return ukdyn::gallery::double_four_bar().system; }};
const Case kFourBarHand{"double_four_bar", hand_double_four_bar};
const Case kSleighAd{"chaplygin_sleigh",
                     [] { return ukdyn::gallery::make("chaplygin_sleigh").system; }};

}  // namespace

BENCHMARK_CAPTURE(BM_Eval, pendulum_vs_ad, kPendulumAd)->Iterations(200);
BENCHMARK_CAPTURE(BM_Eval, pendulum_vs_hand, kPendulumHand)->Iterations(200);
BENCHMARK_CAPTURE(BM_Eval, double_four_bar_vs_ad, kFourBarAd)->Iterations(100);
BENCHMARK_CAPTURE(BM_Eval, double_four_bar_vs_hand, kFourBarHand)->Iterations(100);
BENCHMARK_CAPTURE(BM_Eval, chaplygin_sleigh_vs_ad, kSleighAd)->Iterations(200);
BENCHMARK_CAPTURE(BM_Sim, pendulum_vs_ad, kPendulumAd)
    ->Iterations(15)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Sim, pendulum_vs_hand, kPendulumHand)
    ->Iterations(15)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Sim, double_four_bar_vs_ad, kFourBarAd)
    ->Iterations(9)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Sim, double_four_bar_vs_hand, kFourBarHand)
    ->Iterations(9)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Sim, chaplygin_sleigh_vs_ad, kSleighAd)
    ->Iterations(15)
    ->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();

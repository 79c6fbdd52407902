// SPDX-License-Identifier: BSD-3-Clause
// One System, many threads (issue #15, item 2): a description is immutable and every buffer an
// evaluation writes is in a Workspace, so one System simulated on several threads at once — one
// workspace each — gives, bitwise, the serial run's trajectory. Systems from C++ (the gallery),
// from model files (constrained, with a non-ideal C, large enough that its compiled constraints
// share the workspace's input vector, a multibody one with a drive) and under control (run_model
// and controlled_system). CI runs this program under ThreadSanitizer too (.ci/run).
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/modelfile/run.hpp>
#include <ukdyn/simulation/ensemble.hpp>
#include <ukdyn/ukdyn.hpp>

namespace ukdyn {
namespace UKDYN_TEST_FILE {

constexpr int kThreads = 4;

// Runs f() once serially, then on kThreads threads at once, and returns every result.
template <class F>
auto serial_then_parallel(F f) {
  using R = decltype(f());
  const R serial = f();
  std::vector<R> parallel(kThreads);
  std::vector<std::thread> threads;
  for (int i = 0; i < kThreads; ++i) {
    threads.emplace_back([&, i] { parallel[std::size_t(i)] = f(); });
  }
  for (auto& t : threads) t.join();
  return std::make_pair(serial, parallel);
}

// Bitwise equality of two runs (== on doubles; both runs are free of NaN when they succeed).
void expect_same_run(const Trajectory& a, const Trajectory& b) {
  EXPECT_EQ(a.stats.status, b.stats.status);
  EXPECT_EQ(a.stats.steps, b.stats.steps);
  EXPECT_EQ(a.t, b.t);
  EXPECT_EQ(a.q, b.q);
  EXPECT_EQ(a.qd, b.qd);
  EXPECT_EQ(a.qdd, b.qdd);
  EXPECT_EQ(a.lambda, b.lambda);
  EXPECT_EQ(a.Qc_nonideal, b.Qc_nonideal);
  EXPECT_EQ(a.potential_energy, b.potential_energy);
  EXPECT_EQ(a.work_nonideal, b.work_nonideal);
}

void check_system(const System& sys, const Eigen::Ref<const VectorXd>& q0,
                  const Eigen::Ref<const VectorXd>& qd0, const SimulationOptions& o,
                  Status expected = Status::kOk) {
  const auto [serial, parallel] = serial_then_parallel([&] { return simulate(sys, q0, qd0, o); });
  ASSERT_EQ(serial.stats.status, expected) << serial.stats.message;
  ASSERT_GT(serial.samples(), 2);
  for (const Trajectory& p : parallel) expect_same_run(serial, p);
}

void check_model(const Model& m, double t_end) {
  SimulationOptions o = m.options;
  o.t_end = t_end;
  const auto [serial, parallel] = serial_then_parallel([&] { return run_model(m, o); });
  ASSERT_EQ(serial.trajectory.stats.status, Status::kOk) << serial.trajectory.stats.message;
  ASSERT_GT(serial.trajectory.samples(), 2);
  for (const ModelRun& p : parallel) {
    expect_same_run(serial.trajectory, p.trajectory);
    EXPECT_EQ(serial.controlled, p.controlled);
    EXPECT_EQ(serial.control.evaluations, p.control.evaluations);
    EXPECT_EQ(serial.control.max_kappa, p.control.max_kappa);
    ASSERT_EQ(serial.extra_columns.size(), p.extra_columns.size());
    for (std::size_t c = 0; c < serial.extra_columns.size(); ++c) {
      EXPECT_EQ(serial.extra_columns[c].values, p.extra_columns[c].values)
          << serial.extra_columns[c].name;
    }
  }
}

TEST(Threads, GallerySystemsRunOnFourThreadsAsSerially) {
  for (const std::string name : {"double_four_bar", "chaplygin_sleigh", "block_on_incline"}) {
    SCOPED_TRACE(name);
    const gallery::Example ex = gallery::make(name);
    SimulationOptions o;
    o.t_end = 0.5;
    o.output_every = 0.05;
    check_system(ex.system, ex.q0, ex.qd0, o);
  }
}

TEST(Threads, OneWorkspacePerThreadEvaluatesAsSerially) {
  // forward dynamics on a shared System, one Workspace per thread, many states each
  const Model m = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/double_pendulum.yaml");
  const System& sys = m.system;
  auto qdd_at = [&] {
    Workspace ws(sys);
    std::vector<double> out;
    for (int k = 0; k < 200; ++k) {
      const VectorXd q = m.q0 + VectorXd::Constant(sys.coordinate_count(), 1e-3 * k);
      const VectorXd qd = m.qd0 + VectorXd::Constant(sys.coordinate_count(), -2e-3 * k);
      EXPECT_EQ(forward_dynamics(sys, ws, q, qd, 0.01 * k), Status::kOk);
      out.insert(out.end(), ws.qdd.data(), ws.qdd.data() + ws.qdd.size());
    }
    return out;
  };
  const auto [serial, parallel] = serial_then_parallel(qdd_at);
  for (const auto& p : parallel) EXPECT_EQ(serial, p);
}

TEST(Threads, ModelFilesRunOnFourThreadsAsSerially) {
  // constrained (multibody, with a drive), Coulomb friction, a user C reading a normal force
  for (const std::string file :
       {"slider_crank.yaml", "double_four_bar.yaml", "four_bar_coulomb.yaml"}) {
    SCOPED_TRACE(file);
    check_model(load_model(std::string(UKDYN_EXAMPLES_DIR) + "/" + file), 0.25);
  }
  const Model c = parse_model(R"(
coordinates: [x, y]
kinetic_energy: 0.5*(x_dot^2 + y_dot^2)
potential_energy: 9.81*y + 0.5*x^2
constraints:
  - {name: floor, holonomic: y}
nonideal:
  - {C: [-0.1*N_floor*x_dot, 0]}
initial: {q: {x: 1, y: 0}, q_dot: {x: 0.5, y: 0}}
)");
  check_model(c, 1.0);
}

TEST(Threads, LargeModelSharingOneInputVectorRunsOnFourThreadsAsSerially) {
  // 520 coordinates: the inputs [q; q'; t] (1041) exceed what a compiled constraint keeps for
  // itself, so its 260 constraints share the workspace's input vector (ModelBuffers)
  const int n = 520;
  std::string coords, T, V, cons, q0;
  for (int i = 0; i < n; ++i) {
    const std::string x = "x" + std::to_string(i);
    coords += (i ? ", " : "") + x;
    T += (i ? " + " : "") + std::string("0.5*") + x + "_dot^2";
    V += (i ? " + " : "") + std::string("0.5*") + std::to_string(1 + i % 7) + "*" + x + "^2";
    q0 += (i ? ", " : "") + x + ": " + std::to_string(0.01 * (i / 2));
  }
  for (int k = 0; k < n / 2; ++k) {
    cons += "  - {name: c" + std::to_string(k) + ", holonomic: x" + std::to_string(2 * k) + " - x" +
            std::to_string(2 * k + 1) + "}\n";
  }
  const Model m = parse_model("coordinates: [" + coords + "]\nkinetic_energy: " + T +
                              "\npotential_energy: " + V + "\nconstraints:\n" + cons +
                              "initial: {q: {" + q0 + "}}\n");
  check_model(m, 0.05);
}

TEST(Threads, ControlledModelsRunOnFourThreadsAsSerially) {
  for (const std::string file : {"control_duffing.yaml", "control_triple_pendulum.yaml"}) {
    SCOPED_TRACE(file);
    const Model m = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/" + file);
    ASSERT_TRUE(m.controller);
    check_model(m, 0.5);
  }
}

TEST(Threads, OneControlledSystemRunsOnFourThreadsAsSerially) {
  // controlled_system: one System whose force evaluates the control — its control workspace is
  // each workspace's own scratch
  const Model m = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/control_duffing.yaml");
  const System sys = controlled_system(*m.controller, m.system);
  SimulationOptions o = m.options;
  o.t_end = 0.5;
  // (the control's work is no work channel of this System: its energy balance is a warning)
  check_system(sys, m.q0, m.qd0, o, Status::kEnergyBalance);
}

TEST(Threads, ContactsRunOnFourThreadsAsSerially) {
  // unilateral contacts (issue #31): impacts and a Zeno rest (bouncing_ball), simultaneous
  // impacts solved by Siconos's LCP (newtons_cradle), a release (ladder_leaves_wall), and
  // Coulomb friction on unilateral contacts with impacts (rocking_block): each run bitwise the
  // same on four threads at once as alone, its contact events included; under ThreadSanitizer in
  // CI
  for (const std::string file : {"bouncing_ball.yaml", "newtons_cradle.yaml",
                                 "ladder_leaves_wall.yaml", "rocking_block.yaml"}) {
    SCOPED_TRACE(file);
    const Model m = load_model(std::string(UKDYN_EXAMPLES_DIR) + "/" + file);
    check_model(m, 1.0);
    const auto [serial, parallel] = serial_then_parallel([&] {
      std::vector<double> events;
      for (const ContactEvent& e : run_model(m).trajectory.stats.contact_events) {
        events.insert(events.end(), {e.t, double(e.constraint), double(int(e.kind)), e.speed_before,
                                     e.speed_after, e.impulse, e.energy_change});
      }
      return events;
    });
    EXPECT_FALSE(serial.empty());  // (each of the four has impacts or a release)
    for (const auto& p : parallel) EXPECT_EQ(serial, p);
  }
}

TEST(Threads, EnsembleOnFourThreadsAsOnOne) {
  // run_ensemble (simulation/ensemble.hpp): samples that read the model again (parameters: their
  // YAML parsed on four threads at once, the rest under the reader's lock) and samples that
  // share it (initial values), on a pool of four threads,
  // bitwise as on one; under ThreadSanitizer in CI (tests/simulation/test_ensemble.cpp has the
  // rest)
  EnsembleModel model;
  model.text = R"(
parameters: {m: 1, L: 1, g: 9.81}
coordinates: [x, y]
kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)
potential_energy: m*g*y
constraints:
  - {name: rod, holonomic: (x^2 + y^2 - L^2)/(2*L)}
initial: {q: {x: L, y: 0}}
simulate: {t_end: 0.3}
output: {every: 0.05, expressions: {r: sqrt(x^2 + y^2)}}
)";
  std::vector<EnsembleSample> samples(8);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (i % 2 == 0) samples[i].parameters["L"] = 0.5 + 0.1 * double(i);
    if (i % 2 == 1) samples[i].initial["y_dot"] = -0.1 * double(i);
  }
  EnsembleOptions o;
  o.at = {0.1, 0.2};
  o.threads = 1;
  const EnsembleResult one = run_ensemble(model, samples, o);
  o.threads = kThreads;
  const EnsembleResult four = run_ensemble(model, samples, o);
  ASSERT_EQ(one.samples.size(), four.samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    ASSERT_TRUE(one.samples[i].ok()) << one.samples[i].message;
    EXPECT_EQ(one.samples[i].values, four.samples[i].values);
    EXPECT_EQ(one.samples[i].stats.steps, four.samples[i].stats.steps);
  }
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

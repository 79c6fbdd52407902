// SPDX-License-Identifier: BSD-3-Clause
// Controlled runs of issue #29, item 1: the derived desired value of a requirement row is exactly
// its target when the kinematics has constant offsets (desired_<row>, docs/model-format.md,
// "Control"), and a controlled run whose motion diverges stops with that cause.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// the index of output `name` (fails the test when missing)
std::size_t output_index(const Model& m, const std::string& name) {
  for (std::size_t i = 0; i < m.output_names.size(); ++i) {
    if (m.output_names[i] == name) return i;
  }
  ADD_FAILURE() << "no output " << name;
  return 0;
}

// the run's column `name` (fails the test when missing)
std::vector<double> column(const ModelRun& run, const std::string& name) {
  for (const auto& c : run.columns()) {
    if (c.name == name) return c.values;
  }
  ADD_FAILURE() << "no column " << name;
  return std::vector<double>(std::size_t(run.trajectory.samples()), 0.0);
}

// The tool point p = (x + 1, y) of tests/data/desired_offset.yaml must follow the circle
// (2 + 0.5 cos t, 0.5 sin t). The requirement's first row holds the constant 1 of the kinematics;
// the point is declared (visual: points: p), so desired_tip_0 is the circle's 2 + 0.5 cos t (the
// earlier rule, the row's terms free of x, gave 1 + 0.5 cos t). Along the run the actual value
// desired + error is the point's coordinate, which the viewer matches to draw the desired path.
TEST(ControlDesired, TargetOfATrackedPointWithAConstantOffset) {
  const Model m = load_model(std::string(UKDYN_TEST_DATA_DIR) + "/desired_offset.yaml");
  const std::size_t d0 = output_index(m, "desired_tip_0"), d1 = output_index(m, "desired_tip_1");
  Trajectory tr;
  tr.n = 2;
  tr.t = {0.7, 2.3};
  tr.q = {0.3, -0.2, 5.0, 7.0};  // (the desired value does not depend on the state)
  tr.qd = {0.1, 0.2, -3.0, 4.0};
  const auto values = evaluate_output_expressions(m, tr);
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    const double t = tr.t[i];
    EXPECT_NEAR(values[d0][i], 2.0 + 0.5 * std::cos(t), 1e-15) << t;
    EXPECT_NEAR(values[d1][i], 0.5 * std::sin(t), 1e-15) << t;
  }
  // the run: desired + error = the point's coordinates at every sample
  const ModelRun r = run_model(m);
  ASSERT_EQ(r.trajectory.stats.status, Status::kOk) << r.trajectory.stats.message;
  const auto d = column(r, "desired_tip_0"), e = column(r, "error.tip.0");
  const auto x = column(r, "x");
  ASSERT_EQ(d.size(), x.size());
  ASSERT_GT(d.size(), 100u);
  for (std::size_t i = 0; i < d.size(); ++i) {
    EXPECT_NEAR(d[i] + e[i], x[i] + 1.0, 1e-13) << r.trajectory.t[i];
  }
  // the error decays (omega = 2: e0 = x0 + 1 − 2.5 = −1 at the start), so late in the run the
  // point is on the circle: x + 1 → 2 + 0.5 cos t
  const std::size_t last = d.size() - 1;
  EXPECT_NEAR(x[last] + 1.0, 2.0 + 0.5 * std::cos(r.trajectory.t[last]), 1e-4);
}

// A requirement written by SymPy merges the kinematics' constant with the target's: the tool
// point's height z + 0.867 (its base above the floor) required at 0.68297 + 0.1 sin t is written
// z + 0.18403 − 0.1 sin t. Declared as an output expression or as a visual point, the kinematics
// gives the target back exactly; undeclared, the row's terms free of the state remain the rule.
TEST(ControlDesired, TargetOfARowWhoseConstantsAreMerged) {
  const std::string head = R"(
coordinates: [x, y, z]
mass_matrix: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
control:
  requirements:
    - {name: tip, holonomic: [x - 0.3*cos(t) - 0.1, z + 0.18403 - 0.1*sin(t)],
       dynamics: {omega: 1, zeta: 1}}
)";
  Trajectory tr;
  tr.n = 3;
  tr.t = {0.9};
  tr.q = {0.3, -0.2, 0.1};
  tr.qd = {0.1, 0.2, 0.3};
  const double t = 0.9;
  for (const std::string& declared :
       {std::string("output: {expressions: {tcp_x: x, tcp_z: z + 867/1000}}"),
        std::string("visual: {points: {tcp: [x, y, z + 0.867]}}")}) {
    const Model m = parse_model(head + declared + "\n");
    const auto values = evaluate_output_expressions(m, tr);
    EXPECT_NEAR(values[output_index(m, "desired_tip_0")][0], 0.3 * std::cos(t) + 0.1, 1e-15)
        << declared;
    EXPECT_NEAR(values[output_index(m, "desired_tip_1")][0], 0.68297 + 0.1 * std::sin(t), 1e-15)
        << declared;
  }
  const Model plain = parse_model(head);
  const auto values = evaluate_output_expressions(plain, tr);
  EXPECT_NEAR(values[output_index(plain, "desired_tip_1")][0], -0.18403 + 0.1 * std::sin(t), 1e-15);
  // an output expression that is the row itself (the error) is not its actual value
  const Model error_declared =
      parse_model(head + "output: {expressions: {e: x - 0.3*cos(t) - 0.1}}\n");
  const auto with_error = evaluate_output_expressions(error_declared, tr);
  EXPECT_NEAR(with_error[output_index(error_declared, "desired_tip_0")][0], 0.3 * std::cos(t) + 0.1,
              1e-15);
}

// The triple pendulum's tip on a circle with its redundancy resolved by the least torque norm
// (N = I, tests/data/triple_tip_leastnorm.yaml): the null-space motion under that law is
// unstable, the joint speeds grow without bound (1.7e9 rad/s), and the run used to end at a
// collapsed step size blaming "forces that jump". It now stops early, at the first steps too
// short for the rest of the 60 s run, naming the divergence: the kinetic energy beyond 1e8 times
// T + |V| at the start (37.2 J), a joint faster than 10⁴ rad/s, after a few 10⁴ steps.
TEST(ControlDivergence, LeastNormRedundancyResolutionThatDivergesStopsWithThatCause) {
  const Model m = load_model(std::string(UKDYN_TEST_DATA_DIR) + "/triple_tip_leastnorm.yaml");
  const ModelRun r = run_model(m);
  const RunStatistics& s = r.trajectory.stats;
  EXPECT_EQ(s.status, Status::kIntegratorFailure);
  EXPECT_NE(s.message.find("the motion grows without bound"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("energy scale (37.2"), std::string::npos) << s.message;
  EXPECT_EQ(s.message.find("forces jump"), std::string::npos) << s.message;
  EXPECT_GT(s.t_reached, 1.0);
  EXPECT_LT(s.t_reached, 10.0);
  EXPECT_LT(s.steps, 200000);
  // the speeds of the last samples have left any scale of the start (at rest, 0.5 m of tip
  // motion per second on the circle)
  const auto b_dot = column(r, "b_dot");
  double fastest = 0.0;
  for (double v : b_dot) fastest = std::max(fastest, std::abs(v));
  EXPECT_GT(fastest, 10.0);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

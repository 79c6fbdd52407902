// SPDX-License-Identifier: BSD-3-Clause
// What a run says about itself (a new user's findings, session 16: /work/u19/repro 02, 04, 07):
// a robust controller whose plant leaves the uncertainty model (its error leaves the
// "guaranteed" bound: the run says when and by how much), requirements that cannot be met (check
// reports them as the run does, naming what forbids them), and a constraint given in
// acceleration form only, whose violation is unknown (NaN, never 0).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "ukdyn/control/control.hpp"
#include "ukdyn/core/format.hpp"
#include "ukdyn/modelfile/model.hpp"
#include "ukdyn/modelfile/run.hpp"
#include "ukdyn/ukdyn.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

const std::vector<double>& column(const ModelRun& r, const std::string& name) {
  for (const CsvColumn& c : r.extra_columns) {
    if (c.name == name) return c.values;
  }
  throw std::runtime_error("no column " + name);
}

// examples/models/control_uncertain_duffing.yaml: the plant's mass m, the controller believing
// 1.2 within 20 %
const char* const kRobustDuffing = R"(
name: robust duffing
parameters: {m: 1, c: 0.3, F: 0.5, w: 1.2}
coordinates: [x]
kinetic_energy: 0.5*m*x_dot^2
forces: [-c*x_dot + x - x^3 + F*cos(w*t)]
control:
  requirements:
    - {name: track, holonomic: x - sin(t), dynamics: {omega: 2, zeta: 1}}
  nominal: {m: 1.2}
  robust: {bound: 0, relative_bound: 0.2, gain_uncertainty: 0.2, boundary_layer: 0.001}
initial: {q: {x: 1}, q_dot: {x: 0}}
simulate: {t_end: 10, integrator: dopri5, rtol: 1e-10, atol: 1e-12}
output: {every: 0.02}
)";

TEST(ControlReports, RobustErrorOutsideItsBoundIsReportedWithTimeAndRatio) {
  // m = 0.4: the plant's acceleration is 3 times the nominal one (mu = 2, far outside 0.2)
  const Model m = parse_model(kRobustDuffing, "<duffing>", {{"m", 0.4}});
  const ModelRun r = run_model(m, m.options);
  ASSERT_EQ(r.trajectory.stats.status, Status::kOk) << r.trajectory.stats.message;
  const auto& e = column(r, "error.track");
  const auto& bound = column(r, "error_bound.track");
  const auto& t = r.trajectory.t;
  // independently of the run's check: the samples outside the bound, the first, the worst ratio
  double first = std::numeric_limits<double>::quiet_NaN(), worst = 0.0, largest = 0.0;
  for (std::size_t j = 0; j < t.size(); ++j) {
    largest = std::max(largest, bound[j]);
    if (std::abs(e[j]) > (1.0 + ControlStatistics::kBoundMargin) * bound[j] + 1e-9 * largest) {
      if (std::isnan(first)) first = t[j];
      worst = std::max(worst, std::abs(e[j]) / bound[j]);
    }
  }
  ASSERT_TRUE(std::isfinite(first));
  // (the reproducer measured 4.66 s and 17.6)
  EXPECT_NEAR(first, 4.66, 0.05);
  EXPECT_NEAR(worst, 17.6, 0.5);
  EXPECT_NEAR(r.control.bound_exceeded_at, first, 1e-12);
  EXPECT_NEAR(r.control.bound_worst_ratio, worst, 1e-9 * worst);
  EXPECT_EQ(r.control.bound_worst_row, "track");
  // a note says it, and the front ends' warning too
  const auto& notes = r.trajectory.stats.notes;
  const bool noted = std::any_of(notes.begin(), notes.end(), [](const std::string& n) {
    return contains(n, "left its guaranteed bound (error_bound.track)") &&
           contains(n, "uncertainty model");
  });
  EXPECT_TRUE(noted);
  const auto warnings = control_warnings(r.control, "s");
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_TRUE(contains(warnings[0], "the error left its guaranteed bound at t = 4.6"))
      << warnings[0];
  EXPECT_TRUE(contains(warnings[0], "relative_bound")) << warnings[0];
}

TEST(ControlReports, RobustErrorInsideItsBoundSaysNothing) {
  // m = 1: the uncertainty model holds (docs/control.md, section 4), the bound too
  const Model m = parse_model(kRobustDuffing, "<duffing>", {});
  const ModelRun r = run_model(m, m.options);
  ASSERT_EQ(r.trajectory.stats.status, Status::kOk) << r.trajectory.stats.message;
  EXPECT_TRUE(std::isnan(r.control.bound_exceeded_at));
  EXPECT_EQ(r.control.bound_worst_ratio, 0.0);
  EXPECT_TRUE(r.trajectory.stats.notes.empty());
  EXPECT_TRUE(control_warnings(r.control, "s").empty());
  // and it is inside by a margin: the largest |e| / bound over the run
  const auto& e = column(r, "error.track");
  const auto& bound = column(r, "error_bound.track");
  double ratio = 0.0;
  for (std::size_t j = 0; j < e.size(); ++j) ratio = std::max(ratio, std::abs(e[j]) / bound[j]);
  EXPECT_GT(ratio, 0.05);
  EXPECT_LT(ratio, 1.0);
}

// a model of app/testdata (the command's and the Python tests' too)
Model testdata(const std::string& name) {
  std::string path = UKDYN_APP_TESTDATA_DIR;
  path += '/';
  path += name;
  return load_model(path);
}

// a particle in the plane (x, y) with `rest` after its kinetic energy (constraints, initial
// state, control)
Model particle(const std::string& rest) {
  return parse_model(
      "name: ctl\nparameters: {m: 1}\ncoordinates: [x, y]\n"
      "kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)\ninitial: {q: {x: 0}, q_dot: {x: 1}}\n" +
      rest);
}

TEST(ControlReports, ContradictingRequirementsAreACheckProblemAndTheRunNamesThem) {
  // x = sin t and x = 2 + sin t
  const Model m = testdata("requirements_contradicting.yaml");
  const CheckReport c = check_model(m);
  ASSERT_EQ(c.problems.size(), 1u);
  EXPECT_TRUE(contains(c.problems[0], "the control cannot meet its requirements at the initial"))
      << c.problems[0];
  EXPECT_TRUE(contains(c.problems[0], "requirement rows 'r1' and 'r2' contradict each other"))
      << c.problems[0];
  // the run meets neither: least squares drives e1 = x − sin t by e1'' + 4 e1' + 4 e1 = 4,
  // e1(0) = e1'(0) = 0 (q(0) = 0, q'(0) = 1): e1 = 1 − (1 + 2t) e^{−2t}
  const ModelRun r = run_model(m, m.options);
  ASSERT_EQ(r.trajectory.stats.status, Status::kOk) << r.trajectory.stats.message;
  EXPECT_EQ(r.control.not_met, r.control.evaluations);
  EXPECT_NEAR(column(r, "error.r1").back(), 1.0 - 3.0 * std::exp(-2.0), 1e-6);
  EXPECT_NEAR(column(r, "error.r2").back(), -1.0 - 3.0 * std::exp(-2.0), 1e-6);
  EXPECT_TRUE(contains(r.control.not_met_message, "'r1' and 'r2' contradict each other"))
      << r.control.not_met_message;
  const auto warnings = control_warnings(r.control, "s");
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_TRUE(contains(warnings[0], "could not meet every requirement")) << warnings[0];
}

TEST(ControlReports, ARequirementThatAPhysicalConstraintFixesNamesTheConstraint) {
  // y = sin t required, y = 0 held by the constraint 'c': every coordinate is actuated, the
  // actuators are not to blame
  const Model m = testdata("requirement_on_constraint.yaml");
  const CheckReport c = check_model(m);
  ASSERT_EQ(c.problems.size(), 1u);
  EXPECT_TRUE(contains(c.problems[0],
                       "requirement row 'r' asks for a motion that the physical "
                       "constraint 'c' fixes"))
      << c.problems[0];
}

TEST(ControlReports, ARequirementOnAnUnactuatedCoordinateSaysSo) {
  const Model m = particle(
      "control: {requirements: [{name: r, holonomic: x - sin(t), dynamics: {omega: 2}}], "
      "actuated: [y]}\n");
  const CheckReport c = check_model(m);
  ASSERT_EQ(c.problems.size(), 1u);
  EXPECT_TRUE(contains(c.problems[0],
                       "requirement row 'r' is not moved by the actuated "
                       "coordinates (y)"))
      << c.problems[0];
  // a model whose requirements can be met: no problem
  const Model fine = particle(
      "control: {requirements: [{name: r, holonomic: x - sin(t), dynamics: {omega: 2}}], "
      "actuated: [x]}\n");
  EXPECT_TRUE(check_model(fine).ok()) << check_model(fine).problems.front();
}

// ---- check evaluates the control as the run's first sample does: with the contacts the run
// closes at the start, and on M_A for a singular M (issue #31: it skipped both)

// the text after `prefix` in `text` ("" when text does not start with it)
std::string after(const std::string& text, const std::string& prefix) {
  return text.rfind(prefix, 0) == 0 ? text.substr(prefix.size()) : std::string();
}

TEST(ControlReports, ARequirementIntoAFloorIsACheckProblemNamingTheContactAsTheRunDoes) {
  // a ball resting on its floor required to go down, y = −t²: y'' = −2 asked, 0 with the floor
  // held (missed by 2), and with it open the gap is driven shut — no pushing force meets it
  const Model m = testdata("requirement_into_floor.yaml");
  const CheckReport c = check_model(m);
  ASSERT_EQ(c.problems.size(), 1u);
  const std::string why = after(c.problems[0], "the control fails at the initial state: ");
  EXPECT_TRUE(contains(why,
                       "at t = 0 s the requirement row 'press' can be met only if the "
                       "contact 'floor' pulls"))
      << c.problems[0];
  EXPECT_TRUE(contains(why, "missed by 2 (")) << why;
  // the run stops there, at its first evaluation, saying the same
  const ModelRun r = run_model(m, m.options);
  EXPECT_EQ(r.trajectory.stats.status, Status::kControlFailed) << r.trajectory.stats.message;
  EXPECT_EQ(r.trajectory.stats.t_reached, 0.0);
  EXPECT_EQ(r.trajectory.stats.message, "the controller failed: " + why);
  // a target below the floor asks the same: y = −0.01 (y'' = −100 · 0.01 = −1 asked)
  const Model below = parse_model(
      "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2 + y_dot^2)\npotential_energy: 9.81*y\n"
      "constraints: [{name: floor, holonomic: y, unilateral: true}]\n"
      "control: {requirements: [{name: under, holonomic: y + 0.01, dynamics: {omega: 10}}]}\n"
      "initial: {q: {x: 0, y: 0}}\nsimulate: {t_end: 1}\n");
  const CheckReport b = check_model(below);
  ASSERT_EQ(b.problems.size(), 1u);
  EXPECT_TRUE(contains(b.problems[0],
                       "the requirement row 'under' can be met only if the "
                       "contact 'floor' pulls"))
      << b.problems[0];
  EXPECT_TRUE(contains(b.problems[0], "missed by 1 (")) << b.problems[0];
}

TEST(ControlReports, ARequirementThatLiftsOffAFloorIsNoCheckProblem) {
  // y = t², x = sin t from y = 0 on the floor, y' = 0, x' = 1: e ≡ 0 for both rows, the floor
  // let go of at the start
  const Model m = testdata("requirement_off_floor.yaml");
  const CheckReport c = check_model(m);
  EXPECT_TRUE(c.ok()) << c.problems.front();
  const ModelRun r = run_model(m, m.options);
  ASSERT_EQ(r.trajectory.stats.status, Status::kOk) << r.trajectory.stats.message;
  EXPECT_EQ(r.control.not_met, 0) << r.control.not_met_message;
  const Trajectory& tr = r.trajectory;
  const std::size_t last = tr.t.size() - 1;
  EXPECT_NEAR(tr.t[last], 1.0, 1e-12);
  EXPECT_NEAR(tr.q[2 * last], std::sin(1.0), 1e-6);
  EXPECT_NEAR(tr.q[2 * last + 1], 1.0, 1e-6);
}

// a rigid ball (m = 2, r = 0.1: its M singular along the quaternion) at height z0, `contact` its
// floor's lines (or none), `require` its requirements
Model rigid_ball(double z0, const std::string& contact, const std::string& require) {
  return parse_model(
      "parameters: {m: 2, g: 9.81, r: 0.1, A: 0.1, w: 3}\nbodies:\n"
      "  - {name: ball, type: rigid, mass: m, inertia: [0.4*m*r^2, 0.4*m*r^2, 0.4*m*r^2],\n"
      "     position: [0, 0, " +
      format_number(z0) + "]}\nforces:\n  - {type: gravity, g: [0, 0, -g]}\n" + contact +
      "control:\n  requirements:\n" + require + "simulate: {t_end: 0.3}\n");
}

TEST(ControlReports, ARigidBodysControlIsCheckedOnItsCompletedMass) {
  const std::string pace =
      "    - {name: pace, holonomic: ball_x - A*(1 - cos(w*t)), dynamics: {omega: 10}}\n";
  // above the floor: x = A (1 − cos 3t) can be met (F_x = m x''); x = 0.5 + … with it cannot
  const Model free = rigid_ball(1.0, "", pace);
  ASSERT_TRUE(check_model(free).mass_singular);
  EXPECT_TRUE(check_model(free).ok()) << check_model(free).problems.front();
  const Model both = rigid_ball(
      1.0, "",
      pace +
          "    - {name: apart, holonomic: ball_x - 0.5 - A*(1 - cos(w*t)), dynamics: {omega: "
          "10}}\n");
  const CheckReport c = check_model(both);
  ASSERT_EQ(c.problems.size(), 1u);
  EXPECT_TRUE(contains(c.problems[0], "the control cannot meet its requirements at the initial"))
      << c.problems[0];
  EXPECT_TRUE(contains(c.problems[0], "requirement rows 'pace' and 'apart' contradict each other"))
      << c.problems[0];
  // on the floor (z = r): paced along it, fine; pressed into it, z = r − t², the floor would pull
  const std::string floor = "contacts:\n  - {name: floor, body: ball, shape: sphere, radius: r}\n";
  const Model on = rigid_ball(0.1, floor, pace);
  EXPECT_TRUE(check_model(on).ok()) << check_model(on).problems.front();
  const Model pressed = rigid_ball(
      0.1, floor, "    - {name: press, holonomic: ball_z - r + t^2, dynamics: {omega: 10}}\n");
  const CheckReport p = check_model(pressed);
  ASSERT_EQ(p.problems.size(), 1u);
  const std::string why = after(p.problems[0], "the control fails at the initial state: ");
  EXPECT_TRUE(contains(why,
                       "at t = 0 s the requirement row 'press' can be met only if the "
                       "contact 'floor' pulls"))
      << p.problems[0];
  EXPECT_TRUE(contains(why, "missed by 2 (")) << why;
  const ModelRun r = run_model(pressed, pressed.options);
  EXPECT_EQ(r.trajectory.stats.status, Status::kControlFailed) << r.trajectory.stats.message;
  EXPECT_EQ(r.trajectory.stats.message, "the controller failed: " + why);
}

TEST(ControlReports, AnAccelerationFormConstraintsViolationIsUnknownNotZero) {
  // a pendulum whose rod x² + y² = 1 is given as A q'' = b only: A = [x, y], b = −(x'² + y'²)
  SystemBuilder b({"x", "y"});
  b.mass_matrix(MatrixXd::Identity(2, 2));
  b.forces([](const Eigen::Ref<const VectorXd>&, const Eigen::Ref<const VectorXd>&, double,
              Eigen::Ref<VectorXd> Q) {
    Q[0] = 0.0;
    Q[1] = -9.81;
  });
  b.potential_energy([](const Eigen::Ref<const VectorXd>& q, double) { return 9.81 * q[1]; });
  b.add(acceleration_constraint(
      "rod", 1,
      [](const Eigen::Ref<const VectorXd>& q, const Eigen::Ref<const VectorXd>& qd, double,
         Eigen::Ref<MatrixXd> A, Eigen::Ref<VectorXd> rhs) {
        A(0, 0) = q[0];
        A(0, 1) = q[1];
        rhs[0] = -qd.squaredNorm();
      }));
  const System sys = b.build();
  SimulationOptions o;
  o.t_end = 20.0;
  o.rtol = 1e-6;
  o.atol = 1e-8;
  const Trajectory tr = simulate(sys, VectorXd::Unit(2, 0), VectorXd::Zero(2), o);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  // the true violation |x² + y² − 1| / 2 drifts away from 0: reporting 0 would be wrong
  const double x = tr.q[tr.q.size() - 2], y = tr.q.back();
  EXPECT_GT(std::abs(x * x + y * y - 1.0) / 2.0, 1e-9);
  EXPECT_LT(std::abs(x * x + y * y - 1.0) / 2.0, 1e-1);
  for (std::size_t j = 0; j < tr.t.size(); ++j) {
    EXPECT_TRUE(std::isnan(tr.position_violation[j]));
    EXPECT_TRUE(std::isnan(tr.velocity_violation[j]));
  }
  EXPECT_TRUE(std::isnan(tr.stats.max_position_violation));
  EXPECT_TRUE(std::isnan(tr.stats.max_velocity_violation));
  ASSERT_EQ(tr.stats.notes.size(), 1u);
  EXPECT_TRUE(contains(tr.stats.notes[0], "the constraint 'rod' given in acceleration form only"))
      << tr.stats.notes[0];
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

// Model files: symbolic derivation against closed forms and against the AD-derived constraints,
// and the errors users meet (file:line:column and a hint).
#include <cmath>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/random_problem.hpp"

namespace ukdyn {
namespace {

using testing::vec;
constexpr double kG = 9.81;

// the error a model text raises, or "" when it loads
std::string error_of(const std::string& text, const std::map<std::string, double>& set = {}) {
  try {
    parse_model(text, "m.yaml", set);
  } catch (const ModelError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(Model, TheIssuesInclineExampleSlidesWithCoulombFriction) {
  const Model m = parse_model(R"(
name: block on a rough incline
parameters: {m: 1, g: 9.81, alpha: 0.5, mu: 0.2}
coordinates: [x, y]
kinetic_energy: 0.5*m*(x_dot^2 + y_dot^2)
potential_energy: m*g*y
constraints:
  - {name: plane, holonomic: y + x*tan(alpha)}
nonideal:
  - {friction: coulomb, constraint: plane, mu: mu}
initial:
  q: {x: 0, y: 0}
  q_dot: {x: 1, y: -0.5463}
  project: true
simulate: {t_end: 2, integrator: dopri5, rtol: 1e-10, atol: 1e-12, drift: projection}
output: {every: 0.01, at: [1, 2], expressions: {s: sqrt(x^2 + y^2)}}
)");
  EXPECT_EQ(m.name, "block on a rough incline");
  EXPECT_TRUE(m.system.mass_is_constant());
  EXPECT_TRUE(m.project_initial);
  EXPECT_EQ(m.options.integrator, Integrator::kDopri5);
  EXPECT_DOUBLE_EQ(m.options.t_end, 2.0);
  EXPECT_DOUBLE_EQ(m.options.rtol, 1e-10);
  ASSERT_EQ(m.output_names.size(), 1u);
  // down-slope acceleration g (sin α − μ cos α) while sliding down (+x)
  const double alpha = 0.5, mu = 0.2;
  Workspace ws(m.system);
  const VectorXd dir = vec({std::cos(alpha), -std::sin(alpha)});
  ASSERT_EQ(forward_dynamics(m.system, ws, VectorXd::Zero(2), 2.0 * dir, 0.0), Status::kOk);
  EXPECT_NEAR(ws.qdd.dot(dir), kG * (std::sin(alpha) - mu * std::cos(alpha)), 1e-12);
  // and it runs, with the output expression s = distance from the origin
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto s = evaluate_output_expressions(m, tr);
  ASSERT_EQ(s.size(), 1u);
  ASSERT_EQ(s[0].size(), std::size_t(tr.samples()));
  for (Index i = 0; i < tr.samples(); i += 37) {
    EXPECT_NEAR(s[0][std::size_t(i)], std::hypot(tr.q[2 * i], tr.q[2 * i + 1]), 1e-14);
  }
}

TEST(Model, LagrangianOfAPendulumInItsAngle) {
  // T = ½ m L² θ'², V = −m g L cos θ: M = m L², Q = −m g L sin θ
  const Model m = parse_model(R"(
parameters: {m: 2, L: 1.5, g: 9.81}
coordinates: [th]
kinetic_energy: 0.5*m*L^2*th_dot^2
potential_energy: -m*g*L*cos(th)
)");
  Workspace ws(m.system);
  ASSERT_EQ(forward_dynamics(m.system, ws, vec({0.7}), vec({1.3}), 0.0), Status::kOk);
  EXPECT_NEAR(ws.M(0, 0), 2 * 1.5 * 1.5, 1e-14);
  EXPECT_NEAR(ws.Q[0], -2 * kG * 1.5 * std::sin(0.7), 1e-13);
  EXPECT_NEAR(m.system.potential_energy(vec({0.7}), 0.0), -2 * kG * 1.5 * std::cos(0.7), 1e-13);
}

TEST(Model, VelocityDependentKineticEnergyGivesCoriolisTerms) {
  // a particle in polar coordinates: T = ½ m (r'² + r² θ'²)
  //   M = diag(m, m r²),  Q = (m r θ'², −2 m r r' θ')
  const Model m = parse_model(R"(
parameters: {m: 3}
coordinates: [r, th]
kinetic_energy: 0.5*m*(r_dot^2 + r^2*th_dot^2)
initial: {q: {r: 1}}
)");
  EXPECT_FALSE(m.system.mass_is_constant());
  Workspace ws(m.system);
  const double r = 1.7, rd = -0.4, thd = 2.1;
  ASSERT_EQ(forward_dynamics(m.system, ws, vec({r, 0.3}), vec({rd, thd}), 0.0), Status::kOk);
  EXPECT_NEAR(ws.M(1, 1), 3 * r * r, 1e-13);
  EXPECT_NEAR(ws.M(0, 1), 0.0, 1e-15);
  EXPECT_NEAR(ws.Q[0], 3 * r * thd * thd, 1e-12);
  EXPECT_NEAR(ws.Q[1], -2 * 3 * r * rd * thd, 1e-12);
}

// symbolic A, b of a model constraint against the AD-derived ones of the same function
void expect_same_constraint_rows(const System& from_file, const System& from_ad,
                                 const Eigen::Ref<const VectorXd>& q,
                                 const Eigen::Ref<const VectorXd>& qd, double t) {
  Workspace w1(from_file), w2(from_ad);
  ASSERT_EQ(assemble_constraints(from_file, w1, q, qd, t), Status::kOk);
  ASSERT_EQ(assemble_constraints(from_ad, w2, q, qd, t), Status::kOk);
  EXPECT_NEAR((w1.A - w2.A).norm(), 0.0, 1e-13);
  EXPECT_NEAR((w1.b - w2.b).norm(), 0.0, 1e-12);
}

TEST(Model, TimeDependentHolonomicConstraintMatchesAutomaticDifferentiation) {
  const Model m = parse_model(R"(
parameters: {W: 1.7}
coordinates: [x, y]
mass_matrix: [[1, 0], [0, 1]]
constraints:
  - {name: wire, holonomic: -x*sin(W*t) + y*cos(W*t)}
)");
  const System ad = SystemBuilder({"x", "y"})
                        .mass_matrix(MatrixXd::Identity(2, 2))
                        .add(holonomic("wire", 1,
                                       [](const auto& q, const auto& t, auto& phi) {
                                         using std::cos;
                                         using std::sin;
                                         phi[0] = -q[0] * sin(1.7 * t) + q[1] * cos(1.7 * t);
                                       }))
                        .build();
  expect_same_constraint_rows(m.system, ad, vec({0.8, 0.3}), vec({-0.2, 1.7}), 0.41);
}

TEST(Model, NonholonomicAndVelocityQuadraticConstraintsMatchAutomaticDifferentiation) {
  const Model m = parse_model(R"(
coordinates: [x, y, th]
mass_matrix: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
constraints:
  - {name: knife, nonholonomic: x_dot*sin(th) - y_dot*cos(th)}
  - {name: cone, nonholonomic: x_dot^2 + y_dot^2 - 0.49*th_dot^2 + t*x}
)");
  const System ad =
      SystemBuilder({"x", "y", "th"})
          .mass_matrix(MatrixXd::Identity(3, 3))
          .add(nonholonomic("knife", 1,
                            [](const auto& q, const auto& qd, const auto&, auto& psi) {
                              using std::cos;
                              using std::sin;
                              psi[0] = qd[0] * sin(q[2]) - qd[1] * cos(q[2]);
                            }))
          .add(nonholonomic("cone", 1,
                            [](const auto& q, const auto& qd, const auto& t, auto& psi) {
                              psi[0] =
                                  qd[0] * qd[0] + qd[1] * qd[1] - 0.49 * qd[2] * qd[2] + t * q[0];
                            }))
          .build();
  expect_same_constraint_rows(m.system, ad, vec({0.3, -1.2, 0.77}), vec({0.6, 0.25, -1.4}), 0.9);
}

TEST(Model, UserCReadsTheNormalForceOfANamedConstraint) {
  // C = (0.25 N_floor, 0) pushes a particle along the floor: x'' = 0.25 g
  const Model m = parse_model(R"(
coordinates: [x, y]
kinetic_energy: 0.5*(x_dot^2 + y_dot^2)
potential_energy: 9.81*y
constraints:
  - {name: floor, holonomic: y}
nonideal:
  - {C: [0.25*N_floor, 0]}
)");
  Workspace ws(m.system);
  ASSERT_EQ(forward_dynamics(m.system, ws, VectorXd::Zero(2), VectorXd::Zero(2), 0.0), Status::kOk);
  EXPECT_NEAR(ws.qdd[0], 0.25 * kG, 1e-13);
  EXPECT_NEAR(ws.qdd[1], 0.0, 1e-13);
}

TEST(Model, ParametersCanBeOverridden) {
  const std::string text =
      "parameters: {k: 2}\ncoordinates: [x]\nmass_matrix: [[1]]\nforces: [-k*x]\n";
  Workspace ws(parse_model(text).system);
  const Model m = parse_model(text, "m.yaml", {{"k", 5.0}});
  Workspace w5(m.system);
  ASSERT_EQ(forward_dynamics(m.system, w5, vec({1.0}), vec({0.0}), 0.0), Status::kOk);
  EXPECT_NEAR(w5.qdd[0], -5.0, 1e-15);
  EXPECT_DOUBLE_EQ(m.parameters.at("k"), 5.0);
}

TEST(ModelErrors, YamlSyntaxHasLineAndColumn) {
  const std::string e = error_of("coordinates: [x, y\nmass_matrix: [[1, 0], [0, 1]]\n");
  EXPECT_TRUE(contains(e, "m.yaml:")) << e;
  EXPECT_TRUE(contains(e, "error: YAML syntax")) << e;
  EXPECT_TRUE(contains(e, "hint:")) << e;
}

TEST(ModelErrors, UnknownNameInAnExpressionPointsAtIt) {
  const std::string e = error_of(
      "coordinates: [x, y]\n"
      "mass_matrix: [[1, 0], [0, 1]]\n"
      "forces: [0, -9.81*mass]\n");
  // line 3; the list item starts at column 13, 'mass' at offset 6 in it
  EXPECT_TRUE(contains(e, "m.yaml:3:19: error: in forces: unknown name 'mass'")) << e;
}

TEST(ModelErrors, UnknownKeysAndKindsAreNamedWithTheChoices) {
  std::string e = error_of("coordinates: [x]\nmass_matrix: [[1]]\nintegrator: rk4\n");
  EXPECT_TRUE(contains(e, "m.yaml:3:1: error: unknown key 'integrator'")) << e;
  EXPECT_TRUE(contains(e, "simulate")) << e;
  e = error_of("coordinates: [x]\nmass_matrix: [[1]]\nsimulate: {integrator: euler}\n");
  EXPECT_TRUE(contains(e, "m.yaml:3:24: error: unknown integrator 'euler' (hint: rk4, rk5, dopri5"))
      << e;
}

TEST(ModelErrors, WrongSizes) {
  std::string e = error_of("coordinates: [x, y]\nmass_matrix: [[1, 0]]\n");
  EXPECT_TRUE(contains(e, "m.yaml:2:14: error: mass_matrix must be a list of 2 rows")) << e;
  e = error_of("coordinates: [x, y]\nmass_matrix: [[1, 0], [0, 1]]\nforces: [0]\n");
  EXPECT_TRUE(contains(e, "forces must have 2 entries")) << e;
}

TEST(ModelErrors, NonIdealForceNamingAMissingCoordinateOrConstraint) {
  const std::string base =
      "coordinates: [x, y]\nmass_matrix: [[1, 0], [0, 1]]\n"
      "constraints:\n  - {name: floor, holonomic: y}\n";
  std::string e = error_of(base + "nonideal:\n  - {friction: viscous, c: 1, coordinates: [z]}\n");
  EXPECT_TRUE(contains(e, "unknown coordinate 'z' (hint: the coordinates are x, y)")) << e;
  EXPECT_TRUE(contains(e, "m.yaml:6:")) << e;
  e = error_of(base + "nonideal:\n  - {friction: coulomb, constraint: flor, mu: 0.1}\n");
  EXPECT_TRUE(contains(e, "no constraint named 'flor' (hint: the constraints are floor)")) << e;
}

TEST(ModelErrors, OutputTimeOutsideTheRunAndUnknownParameterOverride) {
  std::string e = error_of(
      "coordinates: [x]\nmass_matrix: [[1]]\nsimulate: {t_end: 2}\n"
      "output: {at: [1, 3]}\n");
  EXPECT_TRUE(contains(e, "m.yaml:4:18: error: output time 3 is outside the run [0, 2]")) << e;
  e = error_of("parameters: {k: 1}\ncoordinates: [x]\nmass_matrix: [[1]]\n", {{"kk", 2.0}});
  EXPECT_TRUE(contains(e, "the model has no parameter 'kk' (hint: its parameters are k)")) << e;
}

TEST(ModelErrors, HolonomicConstraintMayNotDependOnVelocity) {
  const std::string e = error_of(
      "coordinates: [x]\nmass_matrix: [[1]]\n"
      "constraints:\n  - {name: c, holonomic: x_dot}\n");
  EXPECT_TRUE(contains(e, "is holonomic but depends on the velocity 'x_dot'")) << e;
  EXPECT_TRUE(contains(e, "nonholonomic")) << e;
}

TEST(ModelErrors, MassMatrixNotPositiveDefiniteAtTheInitialState) {
  // M = diag(1, −1): points at the mass_matrix value and names the coordinate
  std::string e = error_of("coordinates: [x, y]\nmass_matrix: [[1, 0], [0, -1]]\n");
  EXPECT_TRUE(contains(e,
                       "m.yaml:2:14: error: the mass matrix is not positive semi-definite at "
                       "the initial state (t = 0) (hint: negative inertia for y: every "
                       "diagonal"))
      << e;
  // polar coordinates at r = 0: T = ½(r'² + r²θ'²) gives no inertia to θ there, and no
  // constraint determines it (a singular M is accepted only then)
  e = error_of(
      "coordinates: [r, th]\nkinetic_energy: 0.5*(r_dot^2 + r^2*th_dot^2)\n"
      "initial: {q: {r: 0}}\n");
  EXPECT_TRUE(contains(e,
                       "m.yaml:2:17: error: the mass matrix is singular at the initial state "
                       "(t = 0) and the constraints do not determine every coordinate"))
      << e;
  EXPECT_TRUE(contains(e, "the coordinates 'th' are not determined")) << e;
  EXPECT_TRUE(contains(e, "no inertia for th: the kinetic energy must involve every velocity"))
      << e;
  // positive diagonal, indefinite: [[1, 2], [2, 1]]
  e = error_of("coordinates: [x, y]\nmass_matrix: [[1, 2], [2, 1]]\n");
  EXPECT_TRUE(contains(e,
                       "not positive semi-definite at the initial state (t = 0) (hint: M must "
                       "be positive semi-definite: check the off-diagonal entries)"))
      << e;
  // not symmetric; not finite (1/x at x = 0)
  e = error_of("coordinates: [x, y]\nmass_matrix: [[1, 2], [0, 1]]\n");
  EXPECT_TRUE(contains(e, "m.yaml:2:14: error: the mass matrix is not symmetric")) << e;
  e = error_of("coordinates: [x]\nmass_matrix: [[1/x]]\n");
  EXPECT_TRUE(contains(e,
                       "m.yaml:2:14: error: the mass matrix is not finite at the initial "
                       "state (t = 0)"))
      << e;
}

TEST(ModelErrors, KineticEnergyNotQuadraticInTheVelocities) {
  const std::string e = error_of("coordinates: [x]\nkinetic_energy: x_dot^4\n");
  EXPECT_TRUE(contains(e,
                       "m.yaml:2:17: error: kinetic_energy is not quadratic in the velocities: "
                       "its mass matrix depends on 'x_dot'"))
      << e;
}

TEST(Model, PiIsBuiltInUnlessTheModelNamesIt) {
  // x'' = -x from x(0) = 1: a run of t_end = 2*pi comes back to x = 1
  const Model m = parse_model(
      "coordinates: [x]\nmass_matrix: [[1]]\nforces: [-x]\ninitial: {q: {x: 1}}\n"
      "simulate: {t_end: 2*pi, rtol: 1e-12, atol: 1e-14}\n");
  EXPECT_NEAR(m.options.t_end, 2 * 3.14159265358979323846, 1e-15);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  EXPECT_NEAR(tr.q.back(), 1.0, 1e-9);
  const Model own = parse_model(
      "parameters: {pi: 3}\ncoordinates: [x]\nmass_matrix: [[1]]\nsimulate: {t_end: pi}\n");
  EXPECT_DOUBLE_EQ(own.options.t_end, 3.0);
}

TEST(ModelErrors, MissingFile) {
  try {
    load_model("/nonexistent/model.yaml");
    FAIL();
  } catch (const ModelError& e) {
    EXPECT_TRUE(contains(e.what(), "/nonexistent/model.yaml: error: cannot read the model file"))
        << e.what();
  }
}

}  // namespace
}  // namespace ukdyn

// SPDX-License-Identifier: BSD-3-Clause
// Model files: symbolic derivation against closed forms and against the AD-derived constraints,
// and the errors users meet (file:line:column and a hint).
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include <ukdyn/modelfile/model.hpp>
#include <ukdyn/ukdyn.hpp>

#include "support/random_problem.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

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

TEST(Model, DerivedParametersAreEvaluatedInOrderAndFollowOverrides) {
  // a rod of mass m and length L pinned at one end: I = m L²/12 about its centre, Ip = I +
  // m (L/2)² = m L²/3 about the pin; T = ½ Ip θ'², V = −m g (L/2) cos θ
  const std::string text = R"(
parameters: {m: 3, L: 2, I: m*L^2/12, Ip: I + m*(L/2)^2, g: 9.81, w: sqrt(m*g*(L/2)/Ip)}
coordinates: [th]
kinetic_energy: 0.5*Ip*th_dot^2
potential_energy: -m*g*(L/2)*cos(th)
)";
  const Model a = parse_model(text);
  EXPECT_NEAR(a.parameters.at("I"), 1.0, 1e-15);
  EXPECT_NEAR(a.parameters.at("Ip"), 4.0, 1e-15);
  EXPECT_NEAR(a.parameters.at("w"), std::sqrt(3 * kG * 1.0 / 4.0), 1e-15);
  Workspace wa(a.system);
  ASSERT_EQ(forward_dynamics(a.system, wa, vec({0.3}), vec({0.0}), 0.0), Status::kOk);
  EXPECT_NEAR(wa.M(0, 0), 4.0, 1e-14);
  // --set m=2 re-evaluates the parameters after it: I = 2/3, Ip = 8/3
  const Model b = parse_model(text, "m.yaml", {{"m", 2.0}});
  EXPECT_NEAR(b.parameters.at("I"), 2.0 / 3.0, 1e-15);
  EXPECT_NEAR(b.parameters.at("Ip"), 8.0 / 3.0, 1e-15);
  Workspace wb(b.system);
  ASSERT_EQ(forward_dynamics(b.system, wb, vec({0.3}), vec({0.0}), 0.0), Status::kOk);
  EXPECT_NEAR(wb.M(0, 0), 8.0 / 3.0, 1e-14);
  EXPECT_NEAR(wb.qdd[0], -2 * kG * 1.0 * std::sin(0.3) / (8.0 / 3.0), 1e-13);
  // an override of a derived parameter wins over its expression, and the later ones follow it
  const Model c = parse_model(text, "m.yaml", {{"I", 5.0}});
  EXPECT_DOUBLE_EQ(c.parameters.at("I"), 5.0);
  EXPECT_NEAR(c.parameters.at("Ip"), 8.0, 1e-15);
  EXPECT_NEAR(c.parameters.at("w"), std::sqrt(3 * kG / 8.0), 1e-15);
  // a value that is not finite is the override's fault, not the parameters' after it
  for (const double bad : {std::nan(""), HUGE_VAL}) {
    try {
      parse_model(text, "m.yaml", {{"m", bad}});
      ADD_FAILURE() << "a non-finite override was accepted";
    } catch (const ModelError& e) {
      EXPECT_NE(std::string(e.what()).find("--set m: the value must be a finite number"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(Model, DerivedParametersInAMultibodyModel) {
  // the bodies' numbers read the derived parameters like the others (a pendulum on a pin)
  const Model m = parse_model(R"(
parameters: {m: 2, L: 1.5, J: m*L^2/12, g: 9.81}
bodies:
  - {name: rod, type: planar, mass: m, inertia: J, position: [L/2, 0], angle: 0}
joints:
  - {name: pin, type: revolute, parent: ground, child: rod, child_point: [-L/2, 0]}
forces:
  - {type: gravity, g: [0, -g]}
)",
                              "m.yaml", {{"L", 3.0}});
  EXPECT_NEAR(m.parameters.at("J"), 2 * 9.0 / 12, 1e-15);
  Workspace ws(m.system);
  ASSERT_EQ(forward_dynamics(m.system, ws, m.q0, m.qd0, 0.0), Status::kOk);
  EXPECT_NEAR(ws.M(2, 2), 1.5, 1e-15);
}

TEST(ModelErrors, DerivedParameterReferringToALaterOrUnknownParameter) {
  std::string e = error_of(
      "parameters: {I: m*L^2/12, m: 1, L: 2}\ncoordinates: [x]\n"
      "mass_matrix: [[I]]\n");
  // 'm' at offset 0 of the value at column 17
  EXPECT_TRUE(contains(e,
                       "m.yaml:1:17: error: in parameter 'I': 'm' is defined after 'I' "
                       "(parameters are evaluated in the order written) (hint: move m above I)"))
      << e;
  e = error_of("parameters:\n  m: 1\n  I: m*Len^2/12\ncoordinates: [x]\nmass_matrix: [[I]]\n");
  EXPECT_TRUE(contains(e, "m.yaml:3:8: error: in parameter 'I': unknown name 'Len'")) << e;
  e = error_of("parameters: {k: 2*k}\ncoordinates: [x]\nmass_matrix: [[k]]\n");
  EXPECT_TRUE(contains(e, "m.yaml:1:19: error: in parameter 'k': 'k' refers to itself")) << e;
  // a coordinate is not known to the parameters
  e = error_of("parameters: {k: 2*x}\ncoordinates: [x]\nmass_matrix: [[k]]\n");
  EXPECT_TRUE(contains(e, "m.yaml:1:19: error: in parameter 'k': unknown name 'x'")) << e;
  // values that are not defined
  e = error_of("parameters: {a: 0, k: 1/a}\ncoordinates: [x]\nmass_matrix: [[k]]\n");
  EXPECT_TRUE(contains(e,
                       "m.yaml:1:24: error: in parameter 'k': cannot evaluate: division by "
                       "zero with the parameters' values"))
      << e;
  e = error_of("parameters: {a: 2, k: sqrt(1 - a)}\ncoordinates: [x]\nmass_matrix: [[k]]\n");
  EXPECT_TRUE(contains(e, "m.yaml:1:23: error: in parameter 'k': cannot evaluate")) << e;
  e = error_of("parameters: {k: [1, 2]}\ncoordinates: [x]\nmass_matrix: [[k]]\n");
  EXPECT_TRUE(contains(e, "m.yaml:1:17: error: parameter 'k' must be a number or an expression"))
      << e;
}

// A slider-crank in (crank angle th, rod angle ph, slider x): r sin th = l sin ph,
// x = r cos th + l cos ph. initial: project: {keep: [th]} holds th and th' as given and solves
// for the rest: the closure solution, not the least M-norm change of every coordinate (which
// turned 8 rad/s into 2.14 in the new-user report).
const char* kSliderCrankKeep = R"(
parameters: {r: 0.3, l: 1, Jc: 0.01, Jr: 0.17, ms: 0.5}
coordinates: [th, ph, x]
kinetic_energy: 0.5*Jc*th_dot^2 + 0.5*Jr*ph_dot^2 + 0.5*ms*x_dot^2
constraints:
  - {name: loop, holonomic: [r*cos(th) + l*cos(ph) - x, r*sin(th) - l*sin(ph)]}
initial:
  q: {th: 0.7, ph: 0, x: 1}
  q_dot: {th: 8, ph: 1, x: -3}
  project: {keep: [th]}
)";

TEST(Model, InitialProjectionKeepsTheNamedCoordinatesAndSolvesForTheOthers) {
  const Model m = parse_model(kSliderCrankKeep);
  const double r = 0.3, l = 1.0, th = 0.7, w = 8.0;
  const double ph = std::asin(r * std::sin(th) / l), x = r * std::cos(th) + l * std::cos(ph);
  const double ph_dot = r * std::cos(th) * w / (l * std::cos(ph));
  const double x_dot = -r * std::sin(th) * w - l * std::sin(ph) * ph_dot;
  EXPECT_EQ(m.q0[0], 0.7);  // exactly as given
  EXPECT_EQ(m.qd0[0], 8.0);
  EXPECT_NEAR(m.q0[1], ph, 1e-14);
  EXPECT_NEAR(m.q0[2], x, 1e-14);
  EXPECT_NEAR(m.qd0[1], ph_dot, 1e-13);
  EXPECT_NEAR(m.qd0[2], x_dot, 1e-13);
  Workspace ws(m.system);
  evaluate_violations(m.system, ws, m.q0, m.qd0, 0.0);
  EXPECT_NEAR(ws.phi.cwiseAbs().maxCoeff(), 0.0, 1e-12);
  EXPECT_NEAR(ws.phi_dot.cwiseAbs().maxCoeff(), 0.0, 1e-12);
  // the run starts from it unchanged
  SimulationOptions o = m.options;
  o.t_end = 1e-3;
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, o);
  EXPECT_EQ(tr.q[0], 0.7);  // sample 0, coordinate th (row-major N × n)
  EXPECT_EQ(tr.qd[0], 8.0);
  // x_dot alone: the crank's angle is then free, its rate not: the velocities keep th' = 8 and
  // x' as solved from it
  std::string text = kSliderCrankKeep;
  text.replace(text.find("keep: [th]"), 10, "keep: [th_dot]");
  const Model v = parse_model(text);
  EXPECT_EQ(v.qd0[0], 8.0);
  Workspace wv(v.system);
  evaluate_violations(v.system, wv, v.q0, v.qd0, 0.0);
  EXPECT_NEAR(wv.phi.cwiseAbs().maxCoeff(), 0.0, 1e-12);
  EXPECT_NEAR(wv.phi_dot.cwiseAbs().maxCoeff(), 0.0, 1e-12);
  EXPECT_GT(std::abs(v.q0[0] - 0.7), 1e-6);  // th moved (least M-norm with ph and x)
}

TEST(Model, InitialProjectionKeepsABodyCoordinateOfAMultibodyModel) {
  // the new-user report's slider-crank, every pose but the crank's written roughly, every
  // velocity but the crank's left 0: keep: [crank_theta] gives the closed-form closure
  const Model m = parse_model(R"(
parameters: {r: 0.3, l: 1, mc: 1, mr: 2, ms: 0.5, th0: 0.3, w0: 8}
bodies:
  - {name: crank, type: planar, mass: mc, inertia: mc*r^2/12, position: [0.1, 0.1], angle: th0,
     angular_velocity: w0}
  - {name: rod, type: planar, mass: mr, inertia: mr*l^2/12, position: [0.8, 0], angle: 0}
  - {name: slider, type: planar, mass: ms, inertia: 0.01, position: [1.3, 0]}
joints:
  - {name: pin, type: revolute, parent: ground, child: crank, child_point: [-r/2, 0]}
  - {name: crank_rod, type: revolute, parent: crank, child: rod, parent_point: [r/2, 0],
     child_point: [-l/2, 0]}
  - {name: rod_slider, type: revolute, parent: rod, child: slider, parent_point: [l/2, 0]}
  - {name: slide, type: prismatic, parent: ground, child: slider}
initial: {project: {keep: [crank.theta]}}
)");
  const double r = 0.3, l = 1.0, th = 0.3, w = 8.0;
  const double root = std::sqrt(l * l - r * r * std::sin(th) * std::sin(th));
  const auto at = [&](const std::string& name) {
    const auto& names = m.system.coordinate_names();
    return Index(std::find(names.begin(), names.end(), name) - names.begin());
  };
  EXPECT_EQ(m.q0[at("crank.theta")], 0.3);
  EXPECT_EQ(m.qd0[at("crank.theta")], 8.0);
  EXPECT_NEAR(m.q0[at("crank.x")], r / 2 * std::cos(th), 1e-14);
  EXPECT_NEAR(m.q0[at("rod.theta")], std::asin(-r * std::sin(th) / l), 1e-14);
  EXPECT_NEAR(m.q0[at("slider.x")], r * std::cos(th) + root, 1e-14);
  EXPECT_NEAR(m.qd0[at("rod.theta")], -r * std::cos(th) * w / root, 1e-13);
  EXPECT_NEAR(m.qd0[at("slider.x")], r * std::sin(th) * (-r * std::cos(th) * w / root - w), 1e-13);
  Workspace ws(m.system);
  evaluate_violations(m.system, ws, m.q0, m.qd0, 0.0);
  EXPECT_NEAR(ws.phi.cwiseAbs().maxCoeff(), 0.0, 1e-12);
  EXPECT_NEAR(ws.phi_dot.cwiseAbs().maxCoeff(), 0.0, 1e-12);
}

TEST(ModelErrors, InitialProjectionKeepingTooMuchOrTheImpossible) {
  std::string text = kSliderCrankKeep;
  // th and x kept: ph alone cannot close the loop's two rows
  text.replace(text.find("keep: [th]"), 10, "keep: [th, x]");
  std::string e = error_of(text);
  EXPECT_TRUE(contains(e,
                       "m.yaml:10:19: error: initial: project: keeping th, x over-determines "
                       "the constraints: the other positions cannot satisfy them (rank 1"))
      << e;
  // a crank longer than the rod cannot close at th = 0.7: Newton does not converge
  e = error_of(kSliderCrankKeep, {{"r", 1.0}, {"l", 0.3}});
  EXPECT_TRUE(contains(e,
                       "m.yaml:10:19: error: initial: project: the Newton iteration for the "
                       "positions did not converge"))
      << e;
  text = kSliderCrankKeep;
  text.replace(text.find("keep: [th]"), 10, "keep: [tht]");
  e = error_of(text);
  EXPECT_TRUE(contains(e, "m.yaml:10:20: error: keep: 'tht' is not a coordinate or a velocity"))
      << e;
  text = kSliderCrankKeep;
  text.replace(text.find("keep: [th]"), 10, "kept: [th]");
  e = error_of(text);
  EXPECT_TRUE(contains(e, "m.yaml:10:13: error: unknown key 'kept' in initial: project")) << e;
  // every coordinate (or every velocity) kept, and the values violate the constraint: an error
  // at keep: (the solve over no free coordinate crashed)
  const std::string line =
      "coordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2 + y_dot^2)\nconstraints:\n"
      "  - {name: line, holonomic: x - y}\n";
  e = error_of(line + "initial: {q: {x: 1, y: 0}, project: {keep: [x, y]}}\n");
  EXPECT_TRUE(contains(e,
                       "m.yaml:5:44: error: initial: project: keeping x, y leaves no coordinate "
                       "free, and the values given violate the constraints' positions rows by 1"))
      << e;
  e = error_of(line +
               "initial: {q: {x: 1, y: 1}, q_dot: {x: 1}, project: {keep: [x_dot, y_dot]}}\n");
  EXPECT_TRUE(contains(e,
                       "keeping x_dot, y_dot leaves no velocity free, and the values given "
                       "violate the constraints' velocities rows by 1"))
      << e;
  // all kept and already consistent: nothing to do
  EXPECT_EQ(
      error_of(line + "initial: {q: {x: 1, y: 1}, q_dot: {x: 2, y: 2}, project: {keep: [x, y]}}\n"),
      "");
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
  // a second Coulomb friction on one constraint, located at it (it was "1:1: error:
  // ukdyn::SystemBuilder::build: constraint 'stick.coulomb.floor' is declared twice")
  e = error_of(base +
               "nonideal:\n  - {friction: coulomb, constraint: floor, mu: 0.3, coordinates: [x]}\n"
               "  - {friction: coulomb, constraint: floor, mu: 0.2, coordinates: [x]}\n");
  EXPECT_TRUE(contains(e,
                       "m.yaml:7:37: error: constraint 'floor' has Coulomb friction already "
                       "(non-ideal force 1)"))
      << e;
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
  // u16 04: a coordinate without inertia that only a unilateral contact determines (open at
  // the start, and free whenever it opens): refused at the start as well, the contact named
  e = error_of(
      "coordinates: [x, y]\nkinetic_energy: 0.5*x_dot^2\ninitial: {q: {y: 1}}\n"
      "constraints:\n  - {name: floor, holonomic: y, unilateral: true}\n");
  EXPECT_TRUE(contains(e,
                       "m.yaml:2:17: error: the mass matrix is singular at the initial state "
                       "(t = 0) and the constraints do not determine every coordinate"))
      << e;
  EXPECT_TRUE(contains(e, "the coordinates 'y' are not determined")) << e;
  EXPECT_TRUE(contains(e, "(a unilateral contact does not: it may open)")) << e;
  // (and nan written bare where a constant is read: not a name of the model)
  e = error_of(
      "coordinates: [x, y]\nmass_matrix: [[1, 0], [0, 1]]\ninitial: {q: {y: 1}}\n"
      "constraints:\n  - {name: floor, holonomic: y, unilateral: true, restitution: nan}\n");
  EXPECT_TRUE(contains(e, "m.yaml:5:64: error: restitution must be a finite number, but is 'nan'"))
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

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// A particle in the V-shaped potential V = F |x| (issue #16 item 6d): the force −F sign(x) is
// derived from abs (0 at x = 0, not 0/0), and with x(0) = A, x'(0) = 0 the motion is parabolic
// arcs, x = A − F t²/(2m) until x = 0 at t1 = sqrt(2 m A / F): period 4 t1. The switch at x = 0
// is not an event: dopri5 meets its tolerance by shrinking the steps around it.
TEST(Model, NonSmoothPotentialGivesTheClosedFormMotion) {
  const Model m = parse_model(R"(
parameters: {m: 1, F: 2, A: 0.5}
coordinates: [x]
kinetic_energy: 0.5*m*x_dot^2
potential_energy: F*abs(x)
initial: {q: {x: A}}
simulate: {t_end: 4*sqrt(2*m*A/F), rtol: 1e-11, atol: 1e-13}
output: {every: 0, at: [sqrt(2*m*A/F), 2*sqrt(2*m*A/F)]}
)");
  const double t1 = std::sqrt(0.5);
  Workspace ws(m.system);
  ASSERT_EQ(forward_dynamics(m.system, ws, vec({0.0}), vec({1.0}), 0.0), Status::kOk);
  EXPECT_EQ(ws.qdd[0], 0.0);  // sign(0) = 0
  ASSERT_EQ(forward_dynamics(m.system, ws, vec({-0.2}), vec({1.0}), 0.0), Status::kOk);
  EXPECT_EQ(ws.qdd[0], 2.0);
  const Trajectory tr = simulate(m.system, m.q0, m.qd0, m.options);
  ASSERT_EQ(tr.stats.status, Status::kOk) << tr.stats.message;
  const auto at = [&](double t) {
    for (std::size_t i = 0; i < tr.t.size(); ++i) {
      if (std::abs(tr.t[i] - t) < 1e-12) return i;
    }
    ADD_FAILURE() << "no sample at " << t;
    return std::size_t(0);
  };
  // x(t1) = 0 with x'(t1) = −F t1 / m; x(2 t1) = −A, x(4 t1) = A; energy F A throughout
  EXPECT_NEAR(tr.q[at(t1)], 0.0, 1e-8);
  EXPECT_NEAR(tr.qd[at(t1)], -2 * t1, 1e-8);
  EXPECT_NEAR(tr.q[at(2 * t1)], -0.5, 1e-8);
  EXPECT_NEAR(tr.q.back(), 0.5, 1e-8);
  EXPECT_NEAR(tr.qd.back(), 0.0, 1e-8);
  EXPECT_NEAR(tr.energy.back(), 1.0, 1e-7);
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn

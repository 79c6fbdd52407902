// SPDX-License-Identifier: BSD-3-Clause
// Inputs the model-reader fuzzer (fuzz/fuzz_model.cpp) found troublesome, and their relatives
// found while fixing them: each must give a clear ModelError, not a crash, a hang, a leak or a
// sanitizer report. A hang fails by the CTest TIMEOUT of 60 s (tests/CMakeLists.txt), not by a
// clock in the test.
#include <gtest/gtest.h>

#include <string>

#include "ukdyn/dynamics/forward.hpp"
#include "ukdyn/dynamics/workspace.hpp"
#include "ukdyn/modelfile/model.hpp"

namespace ukdyn {
namespace UKDYN_TEST_FILE {

// The ModelError `text` raises (failing the test when it loads or throws something else).
ModelError error_of(const std::string& text) {
  try {
    parse_model(text, "f.yaml");
  } catch (const ModelError& e) {
    return e;
  }
  ADD_FAILURE() << "the model loaded:\n" << text;
  return ModelError("", 0, 0, "");
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// A parameter that makes a divisor zero: GiNaC's pole_error escaped from the substitution of the
// parameters' values when compiling (found by the fuzzer, from the double pendulum with L2: 0),
// and GiNaC leaked the product it was building. Now refused where the division is written.
TEST(ModelFuzzRegressions, ParameterValueThatDividesByZero) {
  const ModelError e = error_of(
      "parameters: {L1: 1, L2: 0}\n"
      "coordinates: [x1, y1, x2, y2]\n"
      "kinetic_energy: 0.5*(x1_dot^2 + y1_dot^2 + x2_dot^2 + y2_dot^2)\n"
      "constraints:\n"
      "  - {name: rod1, holonomic: (x1^2 + y1^2 - L1^2)/(2*L1)}\n"
      "  - {name: rod2, holonomic: ((x2 - x1)^2 + (y2 - y1)^2 - L2^2)/(2*L2)}\n");
  EXPECT_EQ(e.line(), 6);
  EXPECT_EQ(e.column(), 29 + 34);  // the '/', 34 characters into the expression at column 29
  EXPECT_TRUE(contains(e.what(),
                       "f.yaml:6:63: error: in constraint 'rod2': cannot evaluate: "
                       "division by zero with the parameters' values"))
      << e.what();
  EXPECT_TRUE(contains(e.hint(), "parameter")) << e.what();
}

// 0^p and log(0) once the parameters have their values (GiNaC throws, and leaks, when it meets
// them in compile's substitution).
TEST(ModelFuzzRegressions, ParameterValueThatMakesAPowerOrALogUndefined) {
  const std::string head = "parameters: {k: 0}\ncoordinates: [x]\nmass_matrix: [[1]]\n";
  ModelError e = error_of(head + "forces: [x + k^-1]\n");
  EXPECT_TRUE(contains(e.what(),
                       "f.yaml:4:15: error: in forces: cannot evaluate: 0^-1 with the "
                       "parameters' values"))
      << e.what();
  e = error_of(head + "forces: [log(k*x)]\n");
  EXPECT_TRUE(contains(e.what(), "f.yaml:4:10: error: in forces: cannot evaluate: ")) << e.what();
  EXPECT_TRUE(contains(e.what(), "log(0)")) << e.what();
  e = error_of(head + "forces: [0^0]\n");
  EXPECT_TRUE(contains(e.what(), "f.yaml:4:11: error: in forces: cannot evaluate: 0^0"))
      << e.what();
}

// Derivatives that divide by a quantity the parameters make zero: sqrt(k x) with k = 0 is 0, but
// its derivative k/(2 sqrt(k x)) is 0/0 (this reached compile's substitution as a pole_error).
TEST(ModelFuzzRegressions, ParameterValueWhereADerivativeIsUndefined) {
  const std::string head =
      "parameters: {k: 0}\ncoordinates: [x, y]\nkinetic_energy: 0.5*(x_dot^2 + y_dot^2)\n";
  ModelError e = error_of(head + "potential_energy: sqrt(k*x)\n");
  EXPECT_EQ(e.line(), 4);
  EXPECT_EQ(e.column(), 19);
  EXPECT_TRUE(contains(e.message(),
                       "cannot differentiate: the base of this power is 0 with the "
                       "parameters' values"))
      << e.what();
  e = error_of(head + "potential_energy: x*(k*y)^1.5\n");
  EXPECT_TRUE(contains(e.what(), "f.yaml:4:26: error: in potential_energy: cannot differentiate"))
      << e.what();
  e = error_of(head + "constraints:\n  - {name: c, holonomic: y + abs(k*x)}\n");
  EXPECT_TRUE(contains(e.what(),
                       "f.yaml:5:30: error: in constraint 'c': cannot differentiate: "
                       "the argument of abs is 0"))
      << e.what();
  e = error_of(head + "potential_energy: asin(1 + k*x)\n");
  EXPECT_TRUE(contains(e.message(), "the argument of asin is 1")) << e.what();
  e = error_of(head + "potential_energy: atan2(k*y, k*x)\n");
  EXPECT_TRUE(contains(e.message(), "both arguments of atan2 are 0")) << e.what();
  // what the parameters leave defined still loads
  EXPECT_NO_THROW(parse_model(head + "potential_energy: sin(k*x) + sqrt(k) + log(1 + k*y) + "
                                     "(k*x)^2 + abs(k)\n"));
}

// A constant the parameters make complex: compile's std::invalid_argument escaped.
TEST(ModelFuzzRegressions, ParameterValueThatMakesAComplexConstant) {
  const ModelError e =
      error_of("parameters: {L: 1}\ncoordinates: [x]\nmass_matrix: [[sqrt(L - 2)]]\n");
  EXPECT_TRUE(contains(e.what(),
                       "f.yaml:3:16: error: in mass_matrix: cannot evaluate: sqrt(-2+L) is "
                       "complex (I)"))
      << e.what();
  EXPECT_FALSE(contains(e.what(), "ukdyn::expr")) << e.what();
}

// Parameter values stod reads but that are not finite: ExpressionSet::set_constant's
// std::invalid_argument escaped.
TEST(ModelFuzzRegressions, ParameterThatIsNotFinite) {
  for (const std::string v : {"nan", "inf", "-Infinity", "1e999"}) {
    const ModelError e =
        error_of("parameters: {m: " + v + "}\ncoordinates: [x]\nmass_matrix: [[m]]\n");
    EXPECT_TRUE(contains(
        e.what(), "f.yaml:1:17: error: parameter 'm' must be a finite number, got '" + v + "'"))
        << e.what();
  }
}

// YAML's non-finite floats (.nan, .inf, -.Inf, …) as a value (repro u14/06 a): they read as "mu:
// unexpected character '.'" with a hint about coordinates; now "not a finite number", located.
// A coefficient of friction far beyond any material's (mu: 1e150) is refused where it is written
// (repro u14/06 b: the run died at t = 0 with a non-finite Q naming no friction).
TEST(ModelFuzzRegressions, NonFiniteYamlFloatsAndAbsurdFrictionAreRefusedWhereWritten) {
  for (const std::string v : {".nan", ".NaN", ".inf", "-.inf", "+.Inf", ".INF"}) {
    const ModelError p =
        error_of("parameters: {m: " + v + "}\ncoordinates: [x]\nmass_matrix: [[m]]\n");
    EXPECT_TRUE(contains(
        p.what(), "f.yaml:1:17: error: parameter 'm' must be a finite number, got '" + v + "'"))
        << p.what();
    const ModelError e = error_of("coordinates: [x]\nmass_matrix: [[" + v + "]]\n");
    const std::string kind =
        v.find_first_of("aA") != std::string::npos ? "not-a-number" : "infinity";
    EXPECT_TRUE(contains(e.what(), "f.yaml:2:16: error: ")) << e.what();
    EXPECT_TRUE(
        contains(e.what(), " must be a finite number, got '" + v + "' (YAML's " + kind + ")"))
        << e.what();
    EXPECT_FALSE(contains(e.what(), "unexpected character")) << e.what();
  }
  // a quoted '.nan' is text: an expression that does not parse
  EXPECT_TRUE(contains(error_of("coordinates: [x]\nmass_matrix: [['.nan']]\n").what(),
                       "unexpected character '.'"));
  const std::string ball = R"(bodies:
  - {name: ball, type: rigid, mass: 1, inertia: [1, 1, 1], position: [0, 0, 0.1]}
forces:
  - {type: gravity, g: [0, 0, -9.81]}
contacts:
  - {name: floor, body: ball, shape: sphere, radius: 0.1}
nonideal:
)";
  const ModelError nan = error_of(ball + "  - {friction: coulomb, constraint: floor, mu: .nan}\n");
  EXPECT_TRUE(contains(nan.what(),
                       "f.yaml:8:48: error: the friction at contact 'floor': mu must "
                       "be a finite number, got '.nan' (YAML's not-a-number)"))
      << nan.what();
  const ModelError huge =
      error_of(ball + "  - {friction: coulomb, constraint: floor, mu: 1e150}\n");
  EXPECT_TRUE(contains(huge.what(),
                       "f.yaml:8:48: error: the friction at contact 'floor': mu must "
                       "be in [0, 1e+06] (a coefficient of friction), got 1e+150"))
      << huge.what();
  EXPECT_NO_THROW(
      parse_model(ball + "  - {friction: coulomb, constraint: floor, mu: 1e6}\n", "f.yaml"));
}

// Parameter names that are a function of the language or an input (a velocity, a constraint's
// N_ or lambda_): set_constant's std::invalid_argument escaped.
TEST(ModelFuzzRegressions, ParameterNamedLikeAFunctionOrAnInput) {
  for (const std::string name : {"sin", "x_dot", "N_rod", "lambda_rod"}) {
    const ModelError e = error_of("parameters: {a: 1, " + name +
                                  ": 2}\ncoordinates: [x]\nmass_matrix: [[1]]\n"
                                  "constraints:\n  - {name: rod, holonomic: x}\n");
    EXPECT_TRUE(contains(e.what(), "f.yaml:1:20: error: parameter '" + name +
                                       "' clashes with a function or an input"))
        << e.what();
    EXPECT_FALSE(e.hint().empty());
  }
}

// Numbers that overflow a double: t_end: 1e400 was read as inf, and a run would never end (now
// the literal itself is refused, as in every expression)
TEST(ModelFuzzRegressions, NumberThatOverflowsADouble) {
  const std::string head = "coordinates: [x]\nmass_matrix: [[1]]\n";
  ModelError e = error_of(head + "simulate: {t_end: 1e400}\n");
  EXPECT_TRUE(contains(e.what(), "f.yaml:3:19: error: in t_end: number '1e400' is too large"))
      << e.what();
  e = error_of(head + "initial:\n  q: {x: -exp(1000)}\n");
  // refused where the overflow is: at exp (issue #14, D12)
  EXPECT_TRUE(contains(e.what(),
                       "f.yaml:4:11: error: in initial q: cannot evaluate: exp(1000) "
                       "overflows a double"))
      << e.what();
}

// Deep nesting: the recursive-descent parser (and GiNaC after it) recursed once per level, and
// enough parentheses overflowed the stack.
TEST(ModelFuzzRegressions, DeeplyNestedExpression) {
  const std::string deep = std::string(20000, '(') + "x" + std::string(20000, ')');
  ModelError e = error_of("coordinates: [x]\nmass_matrix: [[1]]\nforces: [" + deep + "]\n");
  EXPECT_TRUE(contains(e.what(),
                       "f.yaml:3:110: error: in forces: the expression nests more than "
                       "100 deep"))
      << e.what();
  e = error_of("coordinates: [x]\nmass_matrix: [[1]]\nforces: [" + std::string(5000, '-') + "x]\n");
  EXPECT_TRUE(contains(e.message(), "nests more than 100 deep")) << e.what();
  // 100 levels are fine
  EXPECT_NO_THROW(parse_model("coordinates: [x]\nmass_matrix: [[1]]\nforces: [" +
                              std::string(99, '(') + "x" + std::string(99, ')') + "]\n"));
}

// Exact powers too large to compute: GiNaC multiplied 10^(10^9) out digit by digit (minutes and
// gigabytes), including when a power of a power or a numeric factor hides it.
TEST(ModelFuzzRegressions, PowerTooLargeToComputeExactly) {
  const std::string head = "coordinates: [x]\nmass_matrix: [[1]]\n";
  for (const std::string f : {"10^1000000000", "(2*x)^1000000000", "(2^1000)^1000",
                              "sqrt(3)^99999999", "(x/7)^-100000"}) {
    const ModelError e = error_of(head + "forces: [" + f + "]\n");
    EXPECT_EQ(e.line(), 3);
    EXPECT_TRUE(contains(e.message(), "the power makes a number too large to compute exactly"))
        << e.what();
  }
  // large exponents of symbols, and powers of numbers that fit a double, are fine
  EXPECT_NO_THROW(
      parse_model(head + "forces: [x^1000000000 + 2^1000 - 10^-1000 + 1^1000000000]\n"));
  // a power of numbers computed exactly but beyond a double is refused at it (issue #14, D12)
  const ModelError big = error_of(head + "forces: [x + 2^2000]\n");
  EXPECT_TRUE(contains(big.what(),
                       "f.yaml:3:15: error: in forces: cannot evaluate: the power "
                       "2^2000 overflows a double"))
      << big.what();
}

// The same with a parameter for the base: lc^2000…0 looked symbolic to the parser, and compile's
// substitution of lc = 0.3 hung computing 0.3^(2·10^91) exactly (found by the fuzzer, from the
// four-bar's C with lc^2 mutated into lc^2000000…). Exponents a product adds up too.
TEST(ModelFuzzRegressions, PowerTooLargeWithTheParametersValues) {
  const std::string head = "parameters: {lc: 0.3}\ncoordinates: [x]\nmass_matrix: [[1]]\n";
  ModelError e = error_of(head + "forces: [x/lc^2" + std::string(91, '0') + "]\n");
  EXPECT_TRUE(contains(e.what(),
                       "f.yaml:4:14: error: in forces: the power makes a number too "
                       "large to compute exactly (over 4096 bits) with the parameters' "
                       "values"))
      << e.what();
  e = error_of(head + "forces: [lc^1000 * lc^1000]\n");  // lc^2000
  EXPECT_TRUE(contains(e.what(), "f.yaml:4:18: error: in forces: the power makes a number too"))
      << e.what();
  EXPECT_NO_THROW(parse_model(head + "forces: [x^(10^90) + lc^x * lc^(10^90 - x) + lc^1000]\n"));
}

// A number whose exponent overflows a long: strtol returned LONG_MIN, std::abs of it is
// undefined, and the GCC build hung computing 10^(2^63) exactly (the fuzzer's input,
// 0.52222222222222221e-400222…, loaded quickly under clang and hung only in the Release build).
TEST(ModelFuzzRegressions, NumberWithAnExponentBeyondALong) {
  const std::string head = "coordinates: [x]\nmass_matrix: [[1]]\n";
  for (const std::string n : {"0.52222222222222221e-400222222222222222222222222222222222",
                              "1e-9223372036854775808", "1.5E+99999999999999999999", "1e401"}) {
    const ModelError e = error_of(head + "forces: [" + n + "*x]\n");
    EXPECT_TRUE(
        contains(e.what(), "f.yaml:3:10: error: in forces: number '" + n + "' is out of range"))
        << e.what();
  }
  EXPECT_NO_THROW(parse_model(head + "forces: [1e300*x - 1e-400 + 0.5E+0]\n"));
}

// A literal beyond the largest double (issue #16 item 6): it evaluated to inf, and an output
// expression with one passed `ukdyn check`; now an error at the literal, in every expression
TEST(ModelFuzzRegressions, NumberBeyondTheLargestDouble) {
  const std::string head = "coordinates: [x]\nmass_matrix: [[1]]\n";
  ModelError e = error_of(head + "forces: [2*1e400*x]\n");
  EXPECT_TRUE(contains(e.what(),
                       "f.yaml:3:12: error: in forces: number '1e400' is too large: it "
                       "exceeds the largest double (about 1.8e308)"))
      << e.what();
  e = error_of(head + "output: {expressions: {y: x + 2e308}}\n");
  EXPECT_TRUE(contains(e.what(), "f.yaml:3:31: error:")) << e.what();
  EXPECT_TRUE(contains(e.what(), "number '2e308' is too large")) << e.what();
  EXPECT_NO_THROW(parse_model(head + "output: {expressions: {y: x + 1.7e308}}\n"));
}

// More than 20 coordinates (FundamentalDecomposition's blocked path) and no constraint:
// check_model's forward dynamics solved a triangular system with an empty right-hand side, and
// Eigen took a reference to its (null) first element: UndefinedBehaviorSanitizer's
// "reference binding to null pointer".
TEST(ModelFuzzRegressions, ManyCoordinatesWithoutConstraints) {
  std::string names, energy;
  for (int i = 0; i < 25; ++i) {
    const std::string q = "q" + std::to_string(i);
    names += (i ? ", " : "") + q;
    energy += (i ? " + " : "") + q + "_dot^2";
  }
  const Model m =
      parse_model("coordinates: [" + names + "]\nkinetic_energy: 0.5*(" + energy + ")\n");
  const CheckReport r = check_model(m);
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(r.rank, 0);
  EXPECT_EQ(r.degrees_of_freedom, 25);
}

// A constraint's N_c and lambda_c are filled in only when C is evaluated: elsewhere they read
// zero, or what the last evaluation of C left in the thread's buffer.
TEST(ModelFuzzRegressions, ConstraintForcesOutsideC) {
  const std::string head =
      "coordinates: [x, y]\nmass_matrix: [[1, 0], [0, 1]]\n"
      "constraints:\n  - {name: rod, holonomic: x^2 + y^2 - 1}\n";
  ModelError e = error_of(head + "forces: [0, -N_rod]\n");
  EXPECT_TRUE(contains(e.what(), "f.yaml:5:13: error: in forces: 'N_rod' is known only in a C"))
      << e.what();
  e = error_of(head + "output: {expressions: {l: lambda_rod}}\n");
  EXPECT_TRUE(contains(e.message(), "'lambda_rod' is known only in a C")) << e.what();
  EXPECT_NO_THROW(parse_model(head + "nonideal:\n  - C: [-0.1*N_rod*x_dot, lambda_rod*0]\n"));
}

// Names of the expression inputs given twice: a constraint declared twice, or a coordinate
// named like another's velocity, made ExpressionSet's message point at the coordinates.
TEST(ModelFuzzRegressions, NamesGivenTwice) {
  const std::string head = "coordinates: [x]\nmass_matrix: [[1]]\n";
  ModelError e = error_of(head +
                          "constraints:\n  - {name: c, holonomic: x}\n"
                          "  - {name: c, holonomic: 2*x}\n");
  EXPECT_TRUE(contains(e.what(), "f.yaml:5:12: error: constraint 'c' is declared twice"))
      << e.what();
  e = error_of("coordinates: [x, x_dot]\nmass_matrix: [[1, 0], [0, 1]]\n");
  EXPECT_TRUE(contains(e.what(),
                       "f.yaml:1:14: error: a coordinate's name is taken: 'x_dot' is "
                       "already declared"))
      << e.what();
  EXPECT_FALSE(contains(e.what(), "ukdyn::expr")) << e.what();
}

// A constraint named by an empty text or a list: the library's Constraint refused the empty name
// with std::invalid_argument, which escaped the reader (found by CI's fuzzer).
TEST(ModelFuzzRegressions, ConstraintNameThatIsEmptyOrNotAText) {
  const std::string head = "coordinates: [x]\nmass_matrix: [[1]]\nconstraints:\n";
  for (const std::string name : {"\"\"", "[c]", "{a: b}", "~"}) {
    const ModelError e = error_of(head + "  - {name: " + name + ", holonomic: x}\n");
    EXPECT_TRUE(contains(e.what(),
                         "f.yaml:4:12: error: a constraint's name must be a non-empty "
                         "text"))
        << e.what();
  }
}

// A constraint named by a text that is not an identifier ("my pin") has no N_c or lambda_c
// input; a C that read the others' wrote past the end of the input buffer (found by CI's fuzzer:
// heap-buffer-overflow in the C of a non-ideal force). The C must read each constraint's own
// normal force: a pendulum at rest at the bottom, N_rod = m g, and C = [k N_rod, 0, 0] along the
// tangent gives x'' = k g.
TEST(ModelFuzzRegressions, ConstraintNamedByATextThatIsNotAnIdentifier) {
  const Model m = parse_model(
      "parameters: {g: 9.81, k: 0.5}\n"
      "coordinates: [x, y, z]\n"
      "mass_matrix: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n"
      "forces: [0, -g, 0]\n"
      "constraints:\n"
      "  - {name: my pin, holonomic: z}\n"
      "  - {name: \"2nd\", holonomic: z + 0*x}\n"
      "  - {name: rod, holonomic: (x^2 + y^2 - 1)/2}\n"
      "nonideal:\n  - C: [k*N_rod, 0, 0]\n"
      "initial: {q: {x: 0, y: -1, z: 0}}\n",
      "f.yaml");
  Workspace ws(m.system);
  const VectorXd q = (VectorXd(3) << 0.0, -1.0, 0.0).finished();
  ASSERT_EQ(forward_dynamics(m.system, ws, q, VectorXd::Zero(3), 0.0), Status::kOk);
  EXPECT_NEAR(ws.qdd[0], 0.5 * 9.81, 1e-12);
  EXPECT_NEAR(ws.qdd[1], 0.0, 1e-12);
  EXPECT_NEAR(ws.qdd[2], 0.0, 1e-12);
  const ModelError e = error_of(
      "coordinates: [x]\nmass_matrix: [[1]]\n"
      "constraints:\n  - {name: my pin, holonomic: x}\nnonideal:\n  - C: [N_my]\n");
  EXPECT_TRUE(contains(e.what(), "f.yaml:6:9: error: in C")) << e.what();
}

}  // namespace UKDYN_TEST_FILE
}  // namespace ukdyn
